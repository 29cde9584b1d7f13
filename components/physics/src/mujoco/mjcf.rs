//! MJCF generation: the humanoid from [`crate::humanoid`] plus the scene.
//!
//! - Height field: an `hfield` asset with `nrow = ny`, `ncol = nx`; MuJoCo puts
//!   sample (row r, col c) at x = -size0 + 2 size0 c/(ncol-1), y = -size1 + 2 size1
//!   r/(nrow-1), which is exactly `heights[j * nx + i]` with r = j, c = i. The geom
//!   sits at the grid's XY centre at the lowest height; the data (0..1) is written
//!   into `hfield_data` after compiling, scaled by the height range (`size2`).
//! - Collision filtering: humanoid geoms have contype 1 / conaffinity 2, scene geoms
//!   contype 2 / conaffinity 1, so humanoids touch the scene but not themselves or
//!   each other (as in the rapier backend).
//! - PD: one `position` actuator per hinge with `kp`, `kv` (= kd) and `forcerange`
//!   = ±max_torque; `ctrl` is the target angle, the same angle rapier's spring uses.

use std::fmt::Write;

use plamo_scenes::{ObstacleShape, Scene};

use crate::PhysicsSettings;
use crate::humanoid::{ARMATURE, BODIES, DENSITY, JOINT_DAMPING, JOINTS, Shape};
use crate::obstacles::obstacle_pose;

/// Prefix of humanoid `i`'s names ("h0_pelvis", "h0_spine_x", ...).
pub(crate) fn prefix(i: usize) -> String {
    format!("h{i}_")
}

/// Name of the terrain geom.
pub(crate) const TERRAIN: &str = "terrain";

fn v(p: [f64; 3]) -> String {
    format!("{} {} {}", p[0], p[1], p[2])
}

fn write_shape(out: &mut String, s: &Shape) {
    let cls = "contype=\"1\" conaffinity=\"2\"";
    match *s {
        Shape::Capsule { from, to, radius } => {
            let _ = writeln!(
                out,
                "<geom type=\"capsule\" fromto=\"{} {}\" size=\"{radius}\" {cls}/>",
                v(from),
                v(to)
            );
        }
        Shape::Sphere { center, radius } => {
            let _ = writeln!(
                out,
                "<geom type=\"sphere\" pos=\"{}\" size=\"{radius}\" {cls}/>",
                v(center)
            );
        }
        Shape::Box {
            center,
            half_extents,
        } => {
            let _ = writeln!(
                out,
                "<geom type=\"box\" pos=\"{}\" size=\"{}\" {cls}/>",
                v(center),
                v(half_extents)
            );
        }
    }
}

fn write_body(out: &mut String, h: usize, b: usize, root_pos: [f64; 3]) {
    let desc = &BODIES[b];
    let p = prefix(h);
    let pos = if desc.parent.is_none() {
        root_pos
    } else {
        desc.offset
    };
    let _ = writeln!(out, "<body name=\"{p}{}\" pos=\"{}\">", desc.name, v(pos));
    if desc.parent.is_none() {
        let _ = writeln!(out, "<freejoint name=\"{p}root\"/>");
    }
    for &ji in desc.joints {
        let jd = &JOINTS[ji];
        let _ = writeln!(
            out,
            "<joint name=\"{p}{}\" type=\"hinge\" axis=\"{}\" range=\"{} {}\"/>",
            jd.name,
            v(jd.axis.unit()),
            jd.range[0],
            jd.range[1]
        );
    }
    for s in desc.shapes {
        write_shape(out, s);
    }
    for child in (0..BODIES.len()).filter(|&c| BODIES[c].parent == Some(b)) {
        write_body(out, h, child, root_pos);
    }
    out.push_str("</body>\n");
}

/// Height-field placement: (centre x, centre y, lowest height, height range).
pub(crate) fn hfield_frame(scene: &Scene) -> ([f64; 2], f64, f64) {
    let g = &scene.terrain;
    let (lo, hi) = g.bounds();
    let (zmin, zmax) = g.height_range();
    (
        [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
        zmin,
        (zmax - zmin).max(1e-4),
    )
}

/// The full MJCF of a world: scene + `settings.humanoids` humanoids standing at
/// `root_positions`.
pub(crate) fn world_mjcf(
    scene: &Scene,
    settings: &PhysicsSettings,
    root_positions: &[[f64; 3]],
) -> String {
    let g = &scene.terrain;
    let (c, zmin, range) = hfield_frame(scene);
    let half = [
        0.5 * (g.nx - 1) as f64 * g.resolution,
        0.5 * (g.ny - 1) as f64 * g.resolution,
    ];
    let f = settings.friction;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<mujoco model=\"plamo-{}\">\n<compiler angle=\"radian\" autolimits=\"true\"/>\n\
         <option timestep=\"{}\" integrator=\"implicitfast\" iterations=\"{}\" gravity=\"0 0 {}\"/>\n\
         <default>\n<joint armature=\"{ARMATURE}\" damping=\"{JOINT_DAMPING}\"/>\n\
         <geom density=\"{DENSITY}\" friction=\"{f} 0.005 0.0001\"/>\n</default>\n\
         <asset>\n<hfield name=\"{TERRAIN}\" nrow=\"{}\" ncol=\"{}\" size=\"{} {} {} {}\"/>\n</asset>\n<worldbody>",
        scene.name.replace(['"', '<', '>', '&'], "_"),
        plamo_interfaces::PHYSICS_DT,
        settings.mujoco_solver_iterations,
        -settings.gravity,
        g.ny,
        g.nx,
        half[0],
        half[1],
        range,
        settings.terrain_base,
    );
    let scene_cls = "contype=\"2\" conaffinity=\"1\"";
    let _ = writeln!(
        out,
        "<geom name=\"{TERRAIN}\" type=\"hfield\" hfield=\"{TERRAIN}\" pos=\"{} {} {zmin}\" {scene_cls}/>",
        c[0], c[1]
    );
    let boxes = scene
        .walls
        .iter()
        .map(|w| (w.footprint, w.z_min, w.z_max))
        .chain(
            scene
                .tops
                .iter()
                .map(|t| (t.footprint, t.z_bottom, t.z_top)),
        );
    for (fp, z0, z1) in boxes {
        let hz = 0.5 * (z1 - z0).max(1e-3);
        let _ = writeln!(
            out,
            "<geom type=\"box\" pos=\"{} {} {}\" euler=\"0 0 {}\" size=\"{} {} {hz}\" {scene_cls}/>",
            fp.center[0],
            fp.center[1],
            0.5 * (z0 + z1),
            fp.yaw,
            fp.half_extents[0],
            fp.half_extents[1]
        );
    }
    for (k, ob) in scene.dynamic.iter().enumerate() {
        let (s, yaw) = obstacle_pose(ob, 0.0);
        let _ = writeln!(
            out,
            "<body name=\"obstacle{k}\" mocap=\"true\" pos=\"{}\" euler=\"0 0 {yaw}\">",
            v(s.position)
        );
        match ob.shape {
            ObstacleShape::Sphere { radius } => {
                let _ = writeln!(out, "<geom type=\"sphere\" size=\"{radius}\" {scene_cls}/>");
            }
            ObstacleShape::Box { half_extents } => {
                let _ = writeln!(
                    out,
                    "<geom type=\"box\" size=\"{}\" {scene_cls}/>",
                    v(half_extents)
                );
            }
        }
        out.push_str("</body>\n");
    }
    for (h, &root) in root_positions.iter().enumerate() {
        write_body(&mut out, h, 0, root);
    }
    out.push_str("</worldbody>\n<actuator>\n");
    for h in 0..root_positions.len() {
        let p = prefix(h);
        for jd in &JOINTS {
            let _ = writeln!(
                out,
                "<position name=\"{p}{n}\" joint=\"{p}{n}\" kp=\"{}\" kv=\"{}\" forcerange=\"{} {}\"/>",
                jd.kp,
                jd.kd,
                -jd.max_torque,
                jd.max_torque,
                n = jd.name
            );
        }
    }
    out.push_str("</actuator>\n</mujoco>\n");
    out
}

/// The humanoid alone on a plane, as MJCF: the description both backends share,
/// for inspection with MuJoCo's tools (`python -m mujoco.viewer --mjcf=...`).
pub fn humanoid_mjcf() -> String {
    let scene = Scene {
        name: "humanoid".into(),
        description: String::new(),
        terrain: plamo_scenes::HeightGrid::flat([-5.0, -5.0], [10.0, 10.0], 1.0, 0.0),
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![],
    };
    world_mjcf(
        &scene,
        &PhysicsSettings::default(),
        &[[0.0, 0.0, crate::humanoid::STANDING_PELVIS_HEIGHT]],
    )
}
