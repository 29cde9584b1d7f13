//! The static and kinematic parts of the rapier world: terrain, walls, ceilings and
//! dynamic obstacles.
//!
//! # Height field (rapier is Y-up and centred)
//! parry's height field lies in its local XZ plane with heights along +Y, centred on
//! its origin, with `heights[(row, col)]` at `z = (-1/2 + row/(nrows-1)) * scale.z`,
//! `x = (-1/2 + col/(ncols-1)) * scale.x`. We keep the world Z-up and rotate the
//! collider by +90 deg about X, which maps local (x, y, z) to world (x, -z, y): local
//! heights become world Z and local +Z becomes world -Y. So row `r` holds the grid's
//! row `j = ny - 1 - r`, and the collider sits at the grid's XY centre at z = 0.
//! `tests::heightfield_matches_grid` pins this with ray casts.

use plamo_scenes::{ObstacleShape, Scene};
use rapier3d::parry::utils::Array2;
use rapier3d::prelude::*;

use crate::obstacles::{ObstacleMotions, obstacle_pose};
use crate::{PhysicsError, PhysicsSettings};

/// Collision group of humanoid colliders.
pub(crate) const HUMANOID_GROUP: Group = Group::GROUP_1;
/// Collision group of the scene (terrain, walls, ceilings, obstacles).
pub(crate) const SCENE_GROUP: Group = Group::GROUP_2;

pub(crate) fn scene_groups() -> InteractionGroups {
    InteractionGroups::new(SCENE_GROUP, HUMANOID_GROUP, InteractionTestMode::And)
}

/// Handles of the scene's colliders and kinematic bodies.
pub(crate) struct SceneHandles {
    /// The terrain height field.
    pub terrain: ColliderHandle,
    /// One kinematic body per dynamic obstacle, in `scene.dynamic` order.
    pub obstacles: Vec<RigidBodyHandle>,
}

pub(crate) fn pose_from_yaw(p: [f64; 3], yaw: f64) -> Pose {
    Pose::from_parts(
        Vector::new(p[0] as f32, p[1] as f32, p[2] as f32),
        Rotation::from_rotation_z(yaw as f32),
    )
}

/// Check the terrain grid: at least 2x2 finite samples, positive resolution.
pub(crate) fn validate_terrain(scene: &Scene) -> Result<(), PhysicsError> {
    let g = &scene.terrain;
    if g.nx < 2
        || g.ny < 2
        || g.heights.len() != g.nx * g.ny
        || g.resolution.is_nan()
        || g.resolution <= 0.0
    {
        return Err(PhysicsError::InvalidScene {
            reason: format!(
                "terrain must be at least 2x2 samples with nx*ny heights and resolution > 0 (nx {}, ny {}, {} heights, resolution {})",
                g.nx,
                g.ny,
                g.heights.len(),
                g.resolution
            ),
        });
    }
    if let Some(i) = g.heights.iter().position(|h| !h.is_finite()) {
        return Err(PhysicsError::InvalidScene {
            reason: format!("terrain height {i} is not finite"),
        });
    }
    Ok(())
}

/// The terrain collider (see the module docs for the frame conversion).
pub(crate) fn terrain_collider(
    scene: &Scene,
    settings: &PhysicsSettings,
) -> Result<Collider, PhysicsError> {
    validate_terrain(scene)?;
    let g = &scene.terrain;
    let (nrows, ncols) = (g.ny, g.nx);
    let mut data = vec![0.0f32; nrows * ncols];
    for r in 0..nrows {
        let j = g.ny - 1 - r;
        for c in 0..ncols {
            // Column-major: flat index r + c * nrows.
            data[r + c * nrows] = g.heights[j * g.nx + c] as f32;
        }
    }
    let sx = (g.nx - 1) as f64 * g.resolution;
    let sy = (g.ny - 1) as f64 * g.resolution;
    let center = [g.origin[0] + 0.5 * sx, g.origin[1] + 0.5 * sy, 0.0];
    let _ = settings.terrain_base; // a height field has no thickness in rapier
    let flags = if settings.rapier_fix_internal_edges {
        HeightFieldFlags::FIX_INTERNAL_EDGES
    } else {
        HeightFieldFlags::empty()
    };
    Ok(ColliderBuilder::heightfield_with_flags(
        Array2::new(nrows, ncols, data),
        Vector::new(sx as f32, 1.0, sy as f32),
        flags,
    )
    .position(Pose::from_parts(
        Vector::new(center[0] as f32, center[1] as f32, 0.0),
        Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2),
    ))
    .friction(settings.friction as f32)
    .collision_groups(scene_groups())
    .build())
}

fn fixed_box(
    center: [f64; 2],
    half: [f64; 2],
    yaw: f64,
    z0: f64,
    z1: f64,
    settings: &PhysicsSettings,
) -> Collider {
    let hz = 0.5 * (z1 - z0).max(1e-3);
    ColliderBuilder::cuboid(half[0] as f32, half[1] as f32, hz as f32)
        .position(pose_from_yaw([center[0], center[1], 0.5 * (z0 + z1)], yaw))
        .friction(settings.friction as f32)
        .collision_groups(scene_groups())
        .build()
}

/// Insert terrain, walls, ceilings and obstacles (at t = 0) into the world.
pub(crate) fn build_scene(
    world: &mut PhysicsWorld,
    scene: &Scene,
    settings: &PhysicsSettings,
) -> Result<SceneHandles, PhysicsError> {
    let terrain = world.insert_collider(terrain_collider(scene, settings)?, None);
    for w in &scene.walls {
        let f = &w.footprint;
        world.insert_collider(
            fixed_box(f.center, f.half_extents, f.yaw, w.z_min, w.z_max, settings),
            None,
        );
    }
    for t in &scene.tops {
        let f = &t.footprint;
        world.insert_collider(
            fixed_box(
                f.center,
                f.half_extents,
                f.yaw,
                t.z_bottom,
                t.z_top,
                settings,
            ),
            None,
        );
    }
    let mut obstacles = Vec::with_capacity(scene.dynamic.len());
    for ob in &scene.dynamic {
        let (s, yaw) = obstacle_pose(ob, 0.0);
        let collider = match ob.shape {
            ObstacleShape::Sphere { radius } => ColliderBuilder::ball(radius as f32),
            ObstacleShape::Box { half_extents: h } => {
                ColliderBuilder::cuboid(h[0] as f32, h[1] as f32, h[2] as f32)
            }
        }
        .friction(settings.friction as f32)
        .collision_groups(scene_groups());
        let body =
            RigidBodyBuilder::kinematic_position_based().pose(pose_from_yaw(s.position, yaw));
        let (handle, _) = world.insert(body, collider);
        obstacles.push(handle);
    }
    Ok(SceneHandles { terrain, obstacles })
}

/// Set every obstacle's kinematic target to its pose at time `t` (the end of the
/// coming step), so rapier gives it the matching velocity and it pushes what it hits.
/// A target more than [`TELEPORT`] away (a host placing its obstacle) is reached
/// without velocity: swept at that speed it would fling whatever it crossed.
pub(crate) fn drive_obstacles(
    world: &mut PhysicsWorld,
    motions: &ObstacleMotions,
    handles: &SceneHandles,
    t: f64,
) {
    for (k, &h) in handles.obstacles.iter().enumerate() {
        let (s, yaw) = motions.pose(k, t);
        let pose = pose_from_yaw(s.position, yaw);
        let body = &mut world.bodies[h];
        if (body.translation() - pose.translation).length() > TELEPORT {
            body.set_position(pose, true);
        }
        body.set_next_kinematic_position(pose);
    }
}

/// Largest obstacle displacement in one step that is swept with velocity \[m\].
const TELEPORT: Real = 1.0;

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_scenes::HeightGrid;
    use rapier3d::parry::query::Ray;

    /// A scene of terrain alone.
    fn bare(terrain: HeightGrid) -> Scene {
        Scene {
            name: "t".into(),
            description: String::new(),
            terrain,
            walls: vec![],
            dynamic: vec![],
            tops: vec![],
            landmarks: vec![],
        }
    }

    #[test]
    fn heightfield_matches_grid() {
        // An asymmetric surface: h = 0.3 x - 0.2 y + 0.1 x y on [2, 5] x [-1, 3].
        let mut g = HeightGrid::flat([2.0, -1.0], [3.0, 4.0], 0.25, 0.0);
        for jj in 0..g.ny {
            for ii in 0..g.nx {
                let [x, y] = g.position(ii, jj);
                g.heights[jj * g.nx + ii] = 0.3 * x - 0.2 * y + 0.1 * x * y;
            }
        }
        let scene = bare(g.clone());
        let c = terrain_collider(&scene, &PhysicsSettings::default()).unwrap();
        for &(x, y) in &[(2.0, -1.0), (2.3, 2.9), (4.9, -0.7), (3.5, 1.0), (4.0, 2.5)] {
            let ray = Ray::new(
                Vector::new(x as f32, y as f32, 10.0),
                Vector::new(0.0, 0.0, -1.0),
            );
            let toi = c
                .shape()
                .cast_ray(c.position(), &ray, 100.0, true)
                .expect("ray hits terrain");
            let z = 10.0 - toi as f64;
            // Exact at samples; bilinear vs triangles differ by the twist term inside cells.
            assert!(
                (z - g.height_at(x, y)).abs() < 0.01,
                "({x},{y}): {z} vs {}",
                g.height_at(x, y)
            );
        }
    }

    #[test]
    fn internal_edge_fixing_follows_the_setting() {
        let scene = bare(HeightGrid::flat([0.0, 0.0], [2.0, 2.0], 0.5, 0.0));
        let flags = |fix: bool| {
            let settings = PhysicsSettings {
                rapier_fix_internal_edges: fix,
                ..Default::default()
            };
            let c = terrain_collider(&scene, &settings).unwrap();
            c.shape().as_heightfield().expect("a height field").flags()
        };
        assert!(flags(true).contains(HeightFieldFlags::FIX_INTERNAL_EDGES));
        assert!(!flags(false).contains(HeightFieldFlags::FIX_INTERNAL_EDGES));
    }
}
