//! Inputs (initial pose, root wrench) and outputs (humanoid state) of a backend, in
//! world frame, Z up, metres, radians. Quaternions are `[w, x, y, z]`.

use crate::humanoid::{BODIES, JOINTS, Shape};
use crate::{NUM_BODIES, NUM_JOINTS, PhysicsError, humanoid, math};

/// Pelvis pitch of the crawl pose \[rad\] (forward lean; the crawl gait's settled
/// posture, recorded like [`CRAWL_JOINTS`]).
pub const CRAWL_PITCH: f64 = 0.9;

/// Joint angles of the crawl pose \[rad\], [`crate::JOINT_NAMES`] order: the crawl
/// gait's posture on hands and knees (head ~0.4 m, pelvis ~0.46 m), the mean over
/// 18 s of steady MuJoCo crawling on the playground's bench leg (seed 0), made
/// left-right symmetric. A reset into it lands the body where the crawl gait holds
/// it, so the gait carries on instead of getting down again.
pub const CRAWL_JOINTS: [f64; NUM_JOINTS] = [
    0.0, 0.889, 0.0, // spine x, y, z
    0.0, 0.538, 0.0, // neck x, y, z
    0.08, -1.227, 0.0, -1.565, // right shoulder x, y, z, elbow
    -0.08, -1.227, 0.0, -1.565, // left shoulder x, y, z, elbow
    -0.37, -1.52, 0.0, 2.175, 0.904, 0.0, // right hip x, y, z, knee, ankle y, x
    0.37, -1.52, 0.0, 2.175, 0.904, 0.0, // left hip x, y, z, knee, ankle y, x
];

/// Gap between the lowest shape of a pose placed by [`HumanoidPose::resting_on`] and
/// the terrain \[m\]: it drops onto the ground instead of starting in it.
const REST_GAP: f64 = 0.01;

/// Where and how a humanoid starts after `reset`.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanoidPose {
    /// Pelvis origin \[m\].
    pub root_position: [f64; 3],
    /// Heading: rotation about +Z \[rad\] (0 faces +X).
    pub yaw: f64,
    /// Forward lean of the pelvis about its own Y axis, after the heading \[rad\]
    /// (0 upright; the crawl pose leans [`CRAWL_PITCH`]).
    pub pitch: f64,
    /// Joint angles \[rad\] in [`crate::JOINT_NAMES`] order; clamped into the limits.
    pub joints: [f64; NUM_JOINTS],
}

fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [aw, ax, ay, az] = a;
    let [bw, bx, by, bz] = b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

fn quat_axis(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let (s, c) = (0.5 * angle).sin_cos();
    [c, axis[0] * s, axis[1] * s, axis[2] * s]
}

impl HumanoidPose {
    /// Standing in the rest pose with the feet on the ground at `ground_z` under (x, y).
    pub fn standing(x: f64, y: f64, ground_z: f64, yaw: f64) -> Self {
        Self {
            root_position: [x, y, ground_z + humanoid::STANDING_PELVIS_HEIGHT + 0.002],
            yaw,
            pitch: 0.0,
            joints: [0.0; NUM_JOINTS],
        }
    }

    /// On hands and knees ([`CRAWL_JOINTS`], [`CRAWL_PITCH`]) with the pelvis origin
    /// over (x, y), resting on the scene's terrain ([`Self::resting_on`]).
    pub fn crawling_on(terrain: &plamo_scenes::HeightGrid, x: f64, y: f64, yaw: f64) -> Self {
        Self::resting_on(terrain, x, y, yaw, CRAWL_PITCH, CRAWL_JOINTS)
    }

    /// A pose with its pelvis origin over (x, y), lowered until its lowest shape is
    /// [`REST_GAP`] above the terrain under it (every shape's lowest point is checked
    /// against the ground beneath that point, so no limb starts inside a slope or a
    /// step).
    pub fn resting_on(
        terrain: &plamo_scenes::HeightGrid,
        x: f64,
        y: f64,
        yaw: f64,
        pitch: f64,
        joints: [f64; NUM_JOINTS],
    ) -> Self {
        let mut pose = Self {
            root_position: [x, y, 0.0],
            yaw,
            pitch,
            joints,
        };
        let lift = pose
            .lowest_points()
            .iter()
            .map(|p| terrain.height_at(p[0], p[1]) - p[2])
            .fold(f64::NEG_INFINITY, f64::max);
        pose.root_position[2] = lift + REST_GAP;
        pose
    }

    /// Each shape's lowest point in the world for this pose (forward kinematics of
    /// [`BODIES`] with the clamped joints; see [`crate::humanoid`] for how hinges
    /// compose).
    pub fn lowest_points(&self) -> Vec<[f64; 3]> {
        let joints = self.clamped_joints();
        let mut frames: Vec<([f64; 3], [f64; 4])> = Vec::with_capacity(NUM_BODIES);
        let mut out = Vec::new();
        for b in &BODIES {
            let (p, mut q) = match b.parent {
                None => (self.root_position, self.root_quat()),
                Some(parent) => {
                    let (pp, pq) = frames[parent];
                    (math::transform(pp, pq, b.offset), pq)
                }
            };
            for &j in b.joints {
                q = quat_mul(q, quat_axis(JOINTS[j].axis.unit(), joints[j]));
            }
            frames.push((p, q));
            for shape in b.shapes {
                let low = match *shape {
                    Shape::Capsule { from, to, radius } => {
                        let (a, c) = (math::transform(p, q, from), math::transform(p, q, to));
                        let e = if a[2] < c[2] { a } else { c };
                        [e[0], e[1], e[2] - radius]
                    }
                    Shape::Sphere { center, radius } => {
                        let c = math::transform(p, q, center);
                        [c[0], c[1], c[2] - radius]
                    }
                    Shape::Box {
                        center,
                        half_extents: h,
                    } => {
                        let corners = (0..8).map(|k| {
                            let sign = |bit: usize| if k & bit == 0 { -1.0 } else { 1.0 };
                            math::transform(
                                p,
                                q,
                                [
                                    center[0] + sign(1) * h[0],
                                    center[1] + sign(2) * h[1],
                                    center[2] + sign(4) * h[2],
                                ],
                            )
                        });
                        corners.min_by(|a, c| a[2].total_cmp(&c[2])).unwrap_or(p)
                    }
                };
                out.push(low);
            }
        }
        out
    }

    /// Standing on the scene's terrain at (x, y): the ground height is the highest
    /// terrain sample under the feet, so no foot starts inside a slope or a step.
    pub fn standing_on(terrain: &plamo_scenes::HeightGrid, x: f64, y: f64, yaw: f64) -> Self {
        // The feet's extent along and across the heading: turned with it, or a body
        // facing anywhere but +X sampled ground beside its feet and started with them
        // inside a slope.
        let heading = math::quat_from_yaw(yaw);
        let mut ground = f64::NEG_INFINITY;
        for along in [-0.1, 0.0, 0.2] {
            for across in [-0.15, 0.0, 0.15] {
                let [dx, dy, _] = math::rotate(heading, [along, across, 0.0]);
                ground = ground.max(terrain.height_at(x + dx, y + dy));
            }
        }
        Self::standing(x, y, ground, yaw)
    }

    /// Check for non-finite values.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check_finite("pose.root_position", &self.root_position)?;
        check_finite("pose.yaw", &[self.yaw])?;
        check_finite("pose.pitch", &[self.pitch])?;
        check_finite("pose.joints", &self.joints)
    }

    /// Root quaternion `[w, x, y, z]`: the heading, then the pitch about the
    /// turned Y axis.
    pub fn root_quat(&self) -> [f64; 4] {
        let yaw = math::quat_from_yaw(self.yaw);
        if self.pitch == 0.0 {
            // Bit-identical to the heading alone, as before poses could lean.
            return yaw;
        }
        quat_mul(yaw, quat_axis([0.0, 1.0, 0.0], self.pitch))
    }

    /// Joint angles clamped into their limits.
    pub fn clamped_joints(&self) -> [f64; NUM_JOINTS] {
        std::array::from_fn(|i| humanoid::clamp_to_range(i, self.joints[i]))
    }
}

/// A residual wrench on the pelvis, world frame, applied at the pelvis centre of
/// mass and held until the next action.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RootWrench {
    /// Force \[N\].
    pub force: [f64; 3],
    /// Torque \[N m\].
    pub torque: [f64; 3],
}

/// The state of one humanoid after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanoidState {
    /// Pelvis origin \[m\].
    pub root_position: [f64; 3],
    /// Pelvis orientation `[w, x, y, z]`.
    pub root_quat: [f64; 4],
    /// Pelvis origin velocity \[m/s\], world frame.
    pub root_linvel: [f64; 3],
    /// Pelvis angular velocity \[rad/s\], world frame.
    pub root_angvel: [f64; 3],
    /// Head centre ([`crate::HEAD_OFFSET`] in the head frame) \[m\].
    pub head: [f64; 3],
    /// Joint angles \[rad\], [`crate::JOINT_NAMES`] order.
    pub joint_pos: [f64; NUM_JOINTS],
    /// Joint velocities \[rad/s\].
    pub joint_vel: [f64; NUM_JOINTS],
    /// Body origins \[m\], [`crate::BODY_NAMES`] order.
    pub body_pos: [[f64; 3]; NUM_BODIES],
    /// Whether each body touches anything (terrain, wall, ceiling, obstacle) during
    /// the last step (all false right after a reset).
    pub contact: [bool; NUM_BODIES],
    /// Whether each body touches the terrain height field.
    pub terrain_contact: [bool; NUM_BODIES],
}

impl Default for HumanoidState {
    fn default() -> Self {
        Self {
            root_position: [0.0; 3],
            root_quat: [1.0, 0.0, 0.0, 0.0],
            root_linvel: [0.0; 3],
            root_angvel: [0.0; 3],
            head: [0.0; 3],
            joint_pos: [0.0; NUM_JOINTS],
            joint_vel: [0.0; NUM_JOINTS],
            body_pos: [[0.0; 3]; NUM_BODIES],
            contact: [false; NUM_BODIES],
            terrain_contact: [false; NUM_BODIES],
        }
    }
}

/// Fastest root a humanoid state may have before it counts as a blow-up \[m/s\]
/// (a 100 m fall reaches 44 m/s).
pub const MAX_ROOT_SPEED: f64 = 50.0;

/// Fastest root rotation before a state counts as a blow-up \[rad/s\].
pub const MAX_ROOT_SPIN: f64 = 100.0;

/// Fastest joint before a state counts as a blow-up \[rad/s\] (servo-driven joints
/// stay near 10).
pub const MAX_JOINT_SPEED: f64 = 200.0;

impl HumanoidState {
    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.root_position
            .iter()
            .chain(&self.root_quat)
            .chain(&self.root_linvel)
            .chain(&self.root_angvel)
            .chain(&self.head)
            .chain(&self.joint_pos)
            .chain(&self.joint_vel)
            .chain(self.body_pos.iter().flatten())
            .all(|v| v.is_finite())
    }

    /// Why this state cannot be a humanoid's (a solver blow-up), if it cannot: a
    /// non-finite number, or a root or joint moving faster than any humanoid does
    /// ([`MAX_ROOT_SPEED`], [`MAX_ROOT_SPIN`], [`MAX_JOINT_SPEED`]). A blow-up can
    /// stay finite (rapier has flung a crawling humanoid to 1e12 m), so finiteness
    /// alone is not enough.
    pub fn unphysical(&self) -> Option<String> {
        if !self.is_finite() {
            return Some("non-finite state".into());
        }
        let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let speed = norm(&self.root_linvel);
        if speed > MAX_ROOT_SPEED {
            return Some(format!(
                "root speed {speed:.3e} m/s (a humanoid stays under {MAX_ROOT_SPEED} m/s)"
            ));
        }
        let spin = norm(&self.root_angvel);
        if spin > MAX_ROOT_SPIN {
            return Some(format!(
                "root spin {spin:.3e} rad/s (a humanoid stays under {MAX_ROOT_SPIN} rad/s)"
            ));
        }
        if let Some((j, v)) = self
            .joint_vel
            .iter()
            .enumerate()
            .find(|(_, v)| v.abs() > MAX_JOINT_SPEED)
        {
            return Some(format!(
                "joint `{}` at {v:.3e} rad/s (a humanoid stays under {MAX_JOINT_SPEED} rad/s)",
                crate::JOINT_NAMES[j]
            ));
        }
        None
    }

    /// Heading of the pelvis: yaw of its forward (+X) axis \[rad\].
    pub fn heading(&self) -> f64 {
        let f = math::rotate(self.root_quat, [1.0, 0.0, 0.0]);
        f[1].atan2(f[0])
    }

    /// Every f64 as its bit pattern, for determinism checks.
    pub fn bits(&self) -> Vec<u64> {
        let mut v: Vec<u64> = self
            .root_position
            .iter()
            .chain(&self.root_quat)
            .chain(&self.root_linvel)
            .chain(&self.root_angvel)
            .chain(&self.head)
            .chain(&self.joint_pos)
            .chain(&self.joint_vel)
            .chain(self.body_pos.iter().flatten())
            .map(|x| x.to_bits())
            .collect();
        v.extend(
            self.contact
                .iter()
                .chain(&self.terrain_contact)
                .map(|&b| b as u64),
        );
        v
    }
}

/// `Err(NonFinite)` at the first NaN or infinity in `values`.
pub(crate) fn check_finite(field: &'static str, values: &[f64]) -> Result<(), PhysicsError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(PhysicsError::NonFinite {
            field,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

/// Validate and normalise an action: length and finiteness are errors, targets are
/// clamped into the joint limits and the wrench is scaled into its bounds.
pub(crate) fn sanitize_action(
    targets: &[f64],
    wrench: Option<RootWrench>,
    max_force: f64,
    max_torque: f64,
) -> Result<([f64; NUM_JOINTS], RootWrench), PhysicsError> {
    if targets.len() != NUM_JOINTS {
        return Err(PhysicsError::WrongActionLength {
            expected: NUM_JOINTS,
            got: targets.len(),
        });
    }
    check_finite("targets", targets)?;
    let clamped = std::array::from_fn(|i| humanoid::clamp_to_range(i, targets[i]));
    let w = wrench.unwrap_or_default();
    check_finite("root_wrench.force", &w.force)?;
    check_finite("root_wrench.torque", &w.torque)?;
    Ok((
        clamped,
        RootWrench {
            force: math::clamp_norm(w.force, max_force),
            torque: math::clamp_norm(w.torque, max_torque),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standing_on_reads_the_ground_under_the_feet_as_they_face() {
        // A step 0.3 m up beyond y = 0.17 m: the toes of a body at the origin facing
        // +Y (0.2 m ahead) are over it; facing +X the feet (0.15 m to each side) are
        // not.
        let mut grid = plamo_scenes::HeightGrid::flat([-2.0, -2.0], [4.0, 4.0], 0.05, 0.0);
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                if grid.position(i, j)[1] > 0.17 {
                    grid.heights[j * grid.nx + i] = 0.3;
                }
            }
        }
        let ground = |yaw: f64| {
            HumanoidPose::standing_on(&grid, 0.0, 0.0, yaw).root_position[2]
                - humanoid::STANDING_PELVIS_HEIGHT
                - 0.002
        };
        assert!(ground(0.0).abs() < 1e-9, "facing +X: {}", ground(0.0));
        let up = ground(std::f64::consts::FRAC_PI_2);
        assert!(up > 0.1, "facing +Y the toes are over the step: {up}");
    }

    #[test]
    fn resting_poses_touch_the_ground_with_their_lowest_shapes() {
        let flat = plamo_scenes::HeightGrid::flat([-3.0, -3.0], [6.0, 6.0], 0.1, 0.2);
        // The rest pose resting on flat ground is the standing pose (feet on it).
        let rest = HumanoidPose::resting_on(&flat, 0.5, 0.5, 0.3, 0.0, [0.0; NUM_JOINTS]);
        let stand = HumanoidPose::standing(0.5, 0.5, 0.2, 0.3);
        assert!((rest.root_position[2] - stand.root_position[2]).abs() < 0.01);
        // The crawl pose: pelvis about 0.46 m up, knees and hands on the ground.
        let crawl = HumanoidPose::crawling_on(&flat, 0.0, 0.0, 0.0);
        let pelvis = crawl.root_position[2] - 0.2;
        assert!((0.38..0.55).contains(&pelvis), "pelvis {pelvis}");
        let low = crawl.lowest_points();
        let lowest = low.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
        assert!((lowest - 0.2 - REST_GAP).abs() < 1e-9, "{lowest}");
        let touching: Vec<_> = low.iter().filter(|p| p[2] < 0.2 + 0.06).collect();
        assert!(touching.len() >= 4, "{touching:?}");
        // Hands ahead of the pelvis, knees near under it.
        assert!(low.iter().any(|p| p[0] > 0.4 && p[2] < 0.27), "{low:?}");
        // Leaning forward: the quaternion turns +X downwards.
        let fwd = math::rotate(crawl.root_quat(), [1.0, 0.0, 0.0]);
        assert!(fwd[2] < -0.7, "{fwd:?}");
    }

    #[test]
    fn blow_ups_are_unphysical_even_when_finite() {
        let rest = HumanoidState::default();
        assert_eq!(rest.unphysical(), None);
        let mut flung = rest.clone();
        flung.root_linvel = [-1.07e9, 8.3e8, 4.3e8];
        let why = flung.unphysical().unwrap();
        assert!(why.contains("root speed"), "{why}");
        let mut spun = rest.clone();
        spun.root_angvel = [0.0, 0.0, 150.0];
        assert!(spun.unphysical().unwrap().contains("root spin"));
        let mut joint = rest.clone();
        joint.joint_vel[3] = -4.3e17;
        let why = joint.unphysical().unwrap();
        assert!(why.contains(crate::JOINT_NAMES[3]), "{why}");
        let mut nan = rest;
        nan.head[2] = f64::NAN;
        assert_eq!(nan.unphysical().as_deref(), Some("non-finite state"));
    }
}
