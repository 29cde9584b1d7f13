//! The controller's observation (paper 4.2, "State"), versioned and flattened into a
//! fixed-length `f32` vector a learned policy can consume.
//!
//! # Layout, version [`OBSERVATION_VERSION`] = 1
//!
//! Every quantity is expressed in the *heading frame*: origin at the root (pelvis),
//! Z up, +X along the root's heading (the yaw of the pelvis' forward axis), so the
//! observation is invariant to where the humanoid stands and which way it faces.
//! With `J` joints and `B` bodies ([`ObservationLayout`]), the flattened vector is:
//!
//! | offset | length | field | units |
//! |---|---|---|---|
//! | `root_height` | 1 | root Z minus terrain height under the root | m |
//! | `root_rotation` | 6 | first two columns of the root rotation in the heading frame (tangent, normal: continuous 6-D rotation) | - |
//! | `root_lin_vel` | 3 | root linear velocity | m/s |
//! | `root_ang_vel` | 3 | root angular velocity | rad/s |
//! | `joint_pos` | J | joint angles in the physics joint order | rad |
//! | `joint_vel` | J | joint velocities | rad/s |
//! | `body_pos` | 3B | body positions minus the root position | m |
//! | `waypoints` | 30 | next 10 plan points (0.5 s apart, first at t + 0.5 s) minus the head position | m |
//! | `height_map` | 64 | terrain height minus root ground height, 8 x 8 samples 0.1 m apart spanning 0.8 m, row = forward, column = left (see [`plamo_scenes::LocalHeightMap`]) | m |
//!
//! Total length `13 + 2J + 3B + 30 + 64`. The offsets are computed by
//! [`ObservationLayout::offsets`]; a learned policy's sidecar records the version and
//! sizes and is rejected when they differ.

use plamo_scenes::{LOCAL_MAP_SAMPLES, LOCAL_MAP_SIDE, LocalHeightMap, Scene};

use crate::error::{ControllerError, Result, check_finite};
use crate::math::{heading_of, quat_to_mat, to_heading_frame};

/// Version of the observation layout. Bump it whenever a field, its order, frame or
/// units change: learned policies record the version they were trained with.
pub const OBSERVATION_VERSION: u32 = 1;
/// Plan waypoints in the observation (paper 4.2: 5 s ahead, ten samples).
pub const NUM_WAYPOINTS: usize = 10;
/// Time between observed waypoints \[s\] (paper 4.2: one every 0.5 s).
pub const WAYPOINT_SPACING: f64 = 0.5;
/// Rows of [`Observation::reach_map`], the terrain ahead of the height map.
pub const REACH_ROWS: usize = 5;
/// Forward offset of [`Observation::reach_map`]'s first row, in map spacings (the
/// height map's front row is at 3.5).
pub const REACH_FIRST_ROW: f64 = 4.5;
/// Samples in [`Observation::reach_map`].
pub const REACH_SAMPLES: usize = REACH_ROWS * LOCAL_MAP_SIDE;
/// How close a top's footprint comes to the root for [`Observation::headroom`] to
/// count it \[m\]: a crawling body's head and shoulders are 0.4-0.6 m ahead of its
/// root, and the body needs a stride to settle lower before its back reaches the top.
pub const HEADROOM_REACH: f64 = 1.0;

/// The humanoid state the controller reads, world frame (Z up, metres, radians).
///
/// A thin, physics-independent copy of what a backend reports; body and joint order
/// follow the physics model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HumanoidSnapshot {
    /// Root (pelvis) position \[m\].
    pub root_pos: [f64; 3],
    /// Root orientation, unit quaternion `[w, x, y, z]`.
    pub root_quat: [f64; 4],
    /// Root linear velocity, world frame \[m/s\].
    pub root_lin_vel: [f64; 3],
    /// Root angular velocity, world frame \[rad/s\].
    pub root_ang_vel: [f64; 3],
    /// Head position \[m\] (the point the plan's waypoints refer to).
    pub head_pos: [f64; 3],
    /// Joint angles \[rad\], physics joint order.
    pub joint_pos: Vec<f64>,
    /// Joint velocities \[rad/s\], physics joint order.
    pub joint_vel: Vec<f64>,
    /// Body positions \[m\], physics body order.
    pub body_pos: Vec<[f64; 3]>,
}

/// A plan sample: the head should be at (x, y, z) moving at speed `v`.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Waypoint {
    /// World X \[m\].
    pub x: f64,
    /// World Y \[m\].
    pub y: f64,
    /// World Z of the head \[m\].
    pub z: f64,
    /// Requested speed \[m/s\].
    pub v: f64,
}

/// Sizes that fix the observation length: the humanoid's joint and body counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ObservationLayout {
    /// Actuated joints `J` (one angle each).
    pub num_joints: usize,
    /// Bodies `B` whose positions are observed.
    pub num_bodies: usize,
}

/// Offsets of each field in the flattened observation (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObservationOffsets {
    /// Root height (1).
    pub root_height: usize,
    /// Root rotation, 6-D (6).
    pub root_rotation: usize,
    /// Root linear velocity (3).
    pub root_lin_vel: usize,
    /// Root angular velocity (3).
    pub root_ang_vel: usize,
    /// Joint angles (J).
    pub joint_pos: usize,
    /// Joint velocities (J).
    pub joint_vel: usize,
    /// Body positions (3B).
    pub body_pos: usize,
    /// Waypoints (30).
    pub waypoints: usize,
    /// Height map (64).
    pub height_map: usize,
    /// Total length.
    pub len: usize,
}

impl ObservationLayout {
    /// Offsets of every field.
    pub fn offsets(&self) -> ObservationOffsets {
        let root_height = 0;
        let root_rotation = root_height + 1;
        let root_lin_vel = root_rotation + 6;
        let root_ang_vel = root_lin_vel + 3;
        let joint_pos = root_ang_vel + 3;
        let joint_vel = joint_pos + self.num_joints;
        let body_pos = joint_vel + self.num_joints;
        let waypoints = body_pos + 3 * self.num_bodies;
        let height_map = waypoints + 3 * NUM_WAYPOINTS;
        let len = height_map + LOCAL_MAP_SAMPLES;
        ObservationOffsets {
            root_height,
            root_rotation,
            root_lin_vel,
            root_ang_vel,
            joint_pos,
            joint_vel,
            body_pos,
            waypoints,
            height_map,
            len,
        }
    }

    /// Length of the flattened observation.
    pub fn len(&self) -> usize {
        self.offsets().len
    }

    /// Never true: the fixed fields alone are 137 values.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// The observation, every field in the heading frame (see the module docs).
///
/// Built in place by [`Observation::update`] so a control step allocates nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    layout: ObservationLayout,
    /// Root height above the terrain under it \[m\].
    pub root_height: f64,
    /// Root rotation in the heading frame: its first two columns (forward and left
    /// axes of the pelvis), 6-D.
    pub root_rotation: [f64; 6],
    /// Root linear velocity, heading frame \[m/s\].
    pub root_lin_vel: [f64; 3],
    /// Root angular velocity, heading frame \[rad/s\].
    pub root_ang_vel: [f64; 3],
    /// Joint angles \[rad\].
    pub joint_pos: Vec<f64>,
    /// Joint velocities \[rad/s\].
    pub joint_vel: Vec<f64>,
    /// Body positions relative to the root, heading frame \[m\].
    pub body_pos: Vec<[f64; 3]>,
    /// Next waypoints relative to the head, heading frame \[m\].
    pub waypoints: [[f64; 3]; NUM_WAYPOINTS],
    /// Requested speeds at the waypoints \[m/s\] (not flattened: implied by spacing;
    /// kept for model-based policies).
    pub waypoint_speeds: [f64; NUM_WAYPOINTS],
    /// Terrain height under each waypoint relative to the ground under the root \[m\]
    /// (not flattened: the plan's points lie the requested head height above it; kept
    /// so model-based policies see the ground beyond the height map, e.g. the treads
    /// of stairs a step ahead). [`Observation::update`] samples the scene;
    /// [`Observation::update_with_map`] has no scene and sets 0 (level ground).
    pub waypoint_ground: [f64; NUM_WAYPOINTS],
    /// Local terrain heights relative to the ground under the root \[m\].
    pub height_map: LocalHeightMap,
    /// The terrain ahead of `height_map`, relative to the ground under the root \[m\]
    /// (not flattened: the paper's map spans 0.8 m, and a crawling body's hands and
    /// head land 0.45-0.6 m ahead of its root, beyond it): [`REACH_ROWS`] more rows
    /// on the map's columns, row `r` at `(REACH_FIRST_ROW + r) * 0.1` m forward
    /// (0.45-0.85 m). [`Observation::update`] samples the scene;
    /// [`Observation::update_with_map`] has no scene and repeats the map's front row
    /// (the ground goes on as at the map's edge).
    pub reach_map: [f64; REACH_SAMPLES],
    /// Lowest free height under the tops (ceilings) whose footprint comes within
    /// [`HEADROOM_REACH`] of the root, over the ground under the root \[m\];
    /// `f64::INFINITY` with none that near (not flattened: the paper's policy reads the
    /// room it has from the plan's head height; kept so a model-based crawl keeps its
    /// back low under a top and can sit higher in the open). [`Observation::update`]
    /// reads the scene; [`Observation::update_with_map`] has no scene and sets open sky.
    pub headroom: f64,
    /// Head position relative to the root, heading frame \[m\] (not flattened: it is
    /// one of `body_pos`; kept so policies need not know the head's body index).
    pub head_pos: [f64; 3],
    /// Root heading in the world \[rad\] (not flattened: the observation is heading
    /// invariant; kept to turn actions back into the world).
    pub heading: f64,
}

impl Observation {
    /// An all-zero observation for `layout`.
    pub fn new(layout: ObservationLayout) -> Self {
        Self {
            layout,
            root_height: 0.0,
            root_rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            root_lin_vel: [0.0; 3],
            root_ang_vel: [0.0; 3],
            joint_pos: vec![0.0; layout.num_joints],
            joint_vel: vec![0.0; layout.num_joints],
            body_pos: vec![[0.0; 3]; layout.num_bodies],
            waypoints: [[0.0; 3]; NUM_WAYPOINTS],
            waypoint_speeds: [0.0; NUM_WAYPOINTS],
            waypoint_ground: [0.0; NUM_WAYPOINTS],
            height_map: [0.0; LOCAL_MAP_SAMPLES],
            reach_map: [0.0; REACH_SAMPLES],
            headroom: f64::INFINITY,
            head_pos: [0.0; 3],
            heading: 0.0,
        }
    }

    /// The layout this observation was built for.
    pub fn layout(&self) -> ObservationLayout {
        self.layout
    }

    /// Rebuilds the observation from a snapshot, the plan and the scene's terrain.
    pub fn update(
        &mut self,
        snapshot: &HumanoidSnapshot,
        waypoints: &[Waypoint],
        scene: &Scene,
    ) -> Result<()> {
        let m = quat_to_mat(snapshot.root_quat);
        let heading = heading_of(&m);
        let [x, y, _] = snapshot.root_pos;
        let ground = scene.height_at(x, y);
        let map = scene.local_height_map(x, y, heading, ground);
        self.update_with_map(snapshot, waypoints, ground, &map)?;
        for (g, w) in self.waypoint_ground.iter_mut().zip(waypoints) {
            *g = scene.height_at(w.x, w.y) - ground;
        }
        scene.local_heights_into(x, y, heading, ground, REACH_FIRST_ROW, &mut self.reach_map);
        self.headroom = scene
            .headroom_near(x, y, HEADROOM_REACH)
            .unwrap_or(f64::INFINITY);
        Ok(())
    }

    /// Rebuilds the observation from a snapshot, the plan, the terrain height under
    /// the root \[m\] and a local height map already relative to it.
    pub fn update_with_map(
        &mut self,
        snapshot: &HumanoidSnapshot,
        waypoints: &[Waypoint],
        ground_z: f64,
        height_map: &LocalHeightMap,
    ) -> Result<()> {
        let l = self.layout;
        expect_len("joint_pos", l.num_joints, snapshot.joint_pos.len())?;
        expect_len("joint_vel", l.num_joints, snapshot.joint_vel.len())?;
        expect_len("body_pos", l.num_bodies, snapshot.body_pos.len())?;
        expect_len("waypoints", NUM_WAYPOINTS, waypoints.len())?;
        check_finite("root_pos", &snapshot.root_pos)?;
        check_finite("root_quat", &snapshot.root_quat)?;
        check_finite("joint_pos", &snapshot.joint_pos)?;
        check_finite("joint_vel", &snapshot.joint_vel)?;

        let m = quat_to_mat(snapshot.root_quat);
        let heading = heading_of(&m);
        let root = snapshot.root_pos;
        self.heading = heading;
        self.root_height = root[2] - ground_z;
        let fwd = to_heading_frame(heading, [m[0][0], m[1][0], m[2][0]]);
        let left = to_heading_frame(heading, [m[0][1], m[1][1], m[2][1]]);
        self.root_rotation = [fwd[0], fwd[1], fwd[2], left[0], left[1], left[2]];
        self.root_lin_vel = to_heading_frame(heading, snapshot.root_lin_vel);
        self.root_ang_vel = to_heading_frame(heading, snapshot.root_ang_vel);
        self.joint_pos.copy_from_slice(&snapshot.joint_pos);
        self.joint_vel.copy_from_slice(&snapshot.joint_vel);
        for (dst, p) in self.body_pos.iter_mut().zip(&snapshot.body_pos) {
            *dst = to_heading_frame(heading, sub(*p, root));
        }
        let head = snapshot.head_pos;
        self.head_pos = to_heading_frame(heading, sub(head, root));
        for (i, w) in waypoints.iter().enumerate() {
            self.waypoints[i] = to_heading_frame(heading, sub([w.x, w.y, w.z], head));
            self.waypoint_speeds[i] = w.v;
        }
        self.waypoint_ground = [0.0; NUM_WAYPOINTS];
        self.height_map = *height_map;
        let front = &height_map[(LOCAL_MAP_SIDE - 1) * LOCAL_MAP_SIDE..];
        for row in self.reach_map.chunks_exact_mut(LOCAL_MAP_SIDE) {
            row.copy_from_slice(front);
        }
        self.headroom = f64::INFINITY;
        Ok(())
    }

    /// Writes the flattened observation into `out` (length [`ObservationLayout::len`]).
    pub fn flatten_into(&self, out: &mut [f32]) -> Result<()> {
        let o = self.layout.offsets();
        expect_len("flattened observation", o.len, out.len())?;
        out[o.root_height] = self.root_height as f32;
        put(&mut out[o.root_rotation..], &self.root_rotation);
        put(&mut out[o.root_lin_vel..], &self.root_lin_vel);
        put(&mut out[o.root_ang_vel..], &self.root_ang_vel);
        put(&mut out[o.joint_pos..], &self.joint_pos);
        put(&mut out[o.joint_vel..], &self.joint_vel);
        for (i, p) in self.body_pos.iter().enumerate() {
            put(&mut out[o.body_pos + 3 * i..], p);
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            put(&mut out[o.waypoints + 3 * i..], w);
        }
        put(&mut out[o.height_map..], &self.height_map);
        Ok(())
    }

    /// The flattened observation as a new vector.
    pub fn flatten(&self) -> Vec<f32> {
        let mut v = vec![0.0; self.layout.len()];
        // The length is the layout's own: cannot fail.
        let _ = self.flatten_into(&mut v);
        v
    }
}

fn expect_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(ControllerError::WrongLength {
            what,
            expected,
            got,
        })
    }
}

fn put(dst: &mut [f32], src: &[f64]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s as f32;
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snapshot(yaw: f64, at: [f64; 2]) -> HumanoidSnapshot {
        HumanoidSnapshot {
            root_pos: [at[0], at[1], 0.9],
            root_quat: [(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()],
            root_lin_vel: [yaw.cos(), yaw.sin(), 0.0],
            root_ang_vel: [0.0, 0.0, 0.3],
            head_pos: [at[0], at[1], 1.47],
            joint_pos: vec![0.1, -0.2, 0.3],
            joint_vel: vec![1.0, 2.0, 3.0],
            body_pos: vec![[at[0], at[1], 0.9], [at[0], at[1], 1.47]],
        }
    }

    fn plan(yaw: f64, at: [f64; 2]) -> Vec<Waypoint> {
        (1..=NUM_WAYPOINTS)
            .map(|i| {
                let d = 0.5 * i as f64;
                Waypoint {
                    x: at[0] + d * yaw.cos(),
                    y: at[1] + d * yaw.sin(),
                    z: 1.47,
                    v: 1.0,
                }
            })
            .collect()
    }

    const LAYOUT: ObservationLayout = ObservationLayout {
        num_joints: 3,
        num_bodies: 2,
    };

    #[test]
    fn offsets_are_contiguous_and_documented_length() {
        let o = LAYOUT.offsets();
        assert_eq!(o.joint_pos, 13);
        assert_eq!(o.body_pos, 13 + 6);
        assert_eq!(o.waypoints, 13 + 6 + 6);
        assert_eq!(o.len, 13 + 2 * 3 + 3 * 2 + 30 + 64);
    }

    #[test]
    fn observation_is_invariant_to_position_and_heading() {
        let map = [0.0; LOCAL_MAP_SAMPLES];
        let mut a = Observation::new(LAYOUT);
        let mut b = Observation::new(LAYOUT);
        a.update_with_map(
            &snapshot(0.0, [0.0, 0.0]),
            &plan(0.0, [0.0, 0.0]),
            0.0,
            &map,
        )
        .unwrap();
        b.update_with_map(
            &snapshot(2.1, [5.0, -3.0]),
            &plan(2.1, [5.0, -3.0]),
            0.0,
            &map,
        )
        .unwrap();
        let (fa, fb) = (a.flatten(), b.flatten());
        for (i, (x, y)) in fa.iter().zip(&fb).enumerate() {
            assert!((x - y).abs() < 1e-5, "index {i}: {x} vs {y}");
        }
        let o = LAYOUT.offsets();
        // Forward velocity along +X, first waypoint 0.5 m ahead and 0 m up.
        assert!((fa[o.root_lin_vel] - 1.0).abs() < 1e-6);
        assert!((fa[o.waypoints] - 0.5).abs() < 1e-6);
        assert!(fa[o.waypoints + 2].abs() < 1e-6);
        assert!((fa[o.root_height] - 0.9).abs() < 1e-6);
        // Head body is 0.57 m above the root.
        assert!((fa[o.body_pos + 5] - 0.57).abs() < 1e-6);
    }

    #[test]
    fn the_ground_ahead_of_the_map_and_under_the_waypoints_comes_from_the_scene() {
        // Root 0.6 m before a 0.2 m ledge: the height map (to 0.35 m ahead) is all
        // floor, the rows ahead of it reach the ledge, as do the waypoints from 1 m.
        let scene = crate::rollout::ledge_scene(8.0, 0.2);
        let at = [crate::rollout::LEDGE_AT - 0.6, 0.0];
        let s = snapshot(0.0, at);
        let mut obs = Observation::new(LAYOUT);
        obs.update(&s, &plan(0.0, at), &scene).unwrap();
        assert_eq!(obs.waypoint_ground[..2], [0.0, 0.2]);
        assert!(obs.height_map.iter().all(|&h| h == 0.0));
        let row = |o: &Observation, r: usize| {
            o.reach_map[r * LOCAL_MAP_SIDE..][..LOCAL_MAP_SIDE].to_vec()
        };
        // 0.45 m is short of the ledge (0.6 m), 0.65 m on it.
        assert!(row(&obs, 0).iter().all(|&h| h == 0.0), "{:?}", row(&obs, 0));
        assert!(row(&obs, 2).iter().all(|&h| h == 0.2), "{:?}", row(&obs, 2));
        // Turned back, the rows ahead lie over the floor.
        obs.update(&snapshot(std::f64::consts::PI, at), &plan(0.0, at), &scene)
            .unwrap();
        assert!(obs.reach_map.iter().all(|&h| h == 0.0));
        // Without a scene the ground ahead goes on as the map's front row.
        let mut map = [0.0; LOCAL_MAP_SAMPLES];
        map[LOCAL_MAP_SAMPLES - 1] = 0.3;
        obs.update_with_map(&s, &plan(0.0, at), 0.0, &map).unwrap();
        for r in 0..REACH_ROWS {
            assert_eq!(row(&obs, r), &map[LOCAL_MAP_SAMPLES - LOCAL_MAP_SIDE..]);
        }
    }

    #[test]
    fn headroom_counts_the_tops_within_reach_of_the_root() {
        // The bench's 0.6 m top spans x 2.5-4.5 m.
        let scene = crate::rollout::ceiling_scene(8.0);
        let mut obs = Observation::new(LAYOUT);
        let mut at = |x: f64| {
            let p = [x, 0.0];
            obs.update(&snapshot(0.0, p), &plan(0.0, p), &scene)
                .unwrap();
            obs.headroom
        };
        assert_eq!(at(3.5), 0.6);
        assert_eq!(at(2.5 - HEADROOM_REACH + 0.05), 0.6);
        assert_eq!(at(2.5 - HEADROOM_REACH - 0.05), f64::INFINITY);
        assert_eq!(at(4.5 + HEADROOM_REACH + 0.05), f64::INFINITY);
        // Without a scene: open sky.
        let p = [3.5, 0.0];
        obs.update_with_map(
            &snapshot(0.0, p),
            &plan(0.0, p),
            0.0,
            &[0.0; LOCAL_MAP_SAMPLES],
        )
        .unwrap();
        assert_eq!(obs.headroom, f64::INFINITY);
    }

    #[test]
    fn wrong_sizes_and_nan_are_errors() {
        let map = [0.0; LOCAL_MAP_SAMPLES];
        let mut obs = Observation::new(LAYOUT);
        let mut s = snapshot(0.0, [0.0, 0.0]);
        s.joint_pos.pop();
        let e = obs.update_with_map(&s, &plan(0.0, [0.0; 2]), 0.0, &map);
        assert!(matches!(
            e,
            Err(ControllerError::WrongLength {
                what: "joint_pos",
                expected: 3,
                got: 2
            })
        ));
        let e = obs.update_with_map(
            &snapshot(0.0, [0.0; 2]),
            &plan(0.0, [0.0; 2])[..4],
            0.0,
            &map,
        );
        assert!(matches!(
            e,
            Err(ControllerError::WrongLength {
                what: "waypoints",
                ..
            })
        ));
        let mut s = snapshot(0.0, [0.0, 0.0]);
        s.joint_vel[1] = f64::NAN;
        let e = obs.update_with_map(&s, &plan(0.0, [0.0; 2]), 0.0, &map);
        assert!(matches!(
            e,
            Err(ControllerError::NonFinite {
                what: "joint_vel",
                index: 1
            })
        ));
        let mut short = vec![0.0f32; 10];
        assert!(obs.flatten_into(&mut short).is_err());
    }
}
