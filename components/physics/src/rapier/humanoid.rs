//! The humanoid as a rapier reduced-coordinate multibody, built from
//! [`crate::humanoid::BODIES`].
//!
//! Every hinge is its own link (rapier multibody joints with two free angular axes
//! are unimplemented, and a three-axis joint integrates a rotation vector, not
//! angles): a body with k hinges becomes k-1 massless intermediate links (tiny mass,
//! no collider) followed by the body's own link, so child = parent * offset * R1 *
//! R2 * R3 exactly as in MuJoCo. A body without hinges (the hands) is a fixed link.
//!
//! PD goes through rapier's implicit joint springs and DoF damping, refreshed every
//! step so that the servo torque, damping included, is clamped to `max_torque` as
//! MuJoCo's `forcerange` clamps its position servo (see
//! [`RapierHumanoid::apply_controls`]); armature on every hinge.

use rapier3d::prelude::*;

use super::world::{HUMANOID_GROUP, SCENE_GROUP};
use crate::humanoid::{ARMATURE, BODIES, HEAD, HEAD_OFFSET, JOINT_DAMPING, JOINTS, Shape};
use crate::{HumanoidPose, HumanoidState, NUM_BODIES, NUM_JOINTS, RootWrench, math};

/// Mass of an intermediate hinge link \[kg\] and its principal inertia \[kg m^2\]:
/// small enough not to matter, non-zero so no rigid body is massless.
const LINK_MASS: f32 = 1e-3;
const LINK_INERTIA: f32 = 1e-6;

/// Handles of one humanoid in the world.
pub(crate) struct RapierHumanoid {
    /// Rigid body of each body (its last link), [`crate::BODY_NAMES`] order.
    pub bodies: [RigidBodyHandle; NUM_BODIES],
    /// Every rigid body including intermediate links, in insertion order.
    pub all_bodies: Vec<RigidBodyHandle>,
    /// Multibody link id and DoF index of each joint.
    joint_links: [(usize, usize); NUM_JOINTS],
    /// Collider -> body index.
    pub colliders: Vec<(ColliderHandle, usize)>,
    /// Current PD targets \[rad\].
    pub targets: [f64; NUM_JOINTS],
    /// Current root wrench.
    pub wrench: RootWrench,
    /// [`crate::PhysicsSettings::rapier_root_torque_per_step`].
    torque_per_step: bool,
}

fn v3(p: [f64; 3]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

fn shape_collider(shape: &Shape, friction: f64) -> ColliderBuilder {
    let b = match *shape {
        Shape::Capsule { from, to, radius } => {
            ColliderBuilder::capsule_from_endpoints(v3(from), v3(to), radius as f32)
        }
        Shape::Sphere { center, radius } => {
            ColliderBuilder::ball(radius as f32).translation(v3(center))
        }
        Shape::Box {
            center,
            half_extents: h,
        } => ColliderBuilder::cuboid(h[0] as f32, h[1] as f32, h[2] as f32).translation(v3(center)),
    };
    b.density(crate::humanoid::DENSITY as f32)
        .friction(friction as f32)
        .collision_groups(InteractionGroups::new(
            HUMANOID_GROUP,
            SCENE_GROUP,
            InteractionTestMode::And,
        ))
}

fn hinge(axis: crate::humanoid::Axis, offset: [f64; 3], range: [f64; 2]) -> GenericJoint {
    let (free, jaxis) = match axis {
        crate::humanoid::Axis::X => (JointAxesMask::ANG_X, JointAxis::AngX),
        crate::humanoid::Axis::Y => (JointAxesMask::ANG_Y, JointAxis::AngY),
        crate::humanoid::Axis::Z => (JointAxesMask::ANG_Z, JointAxis::AngZ),
    };
    GenericJointBuilder::new(JointAxesMask::LOCKED_FIXED_AXES & !free)
        .local_frame1(Pose::from_translation(v3(offset)))
        .local_frame2(Pose::IDENTITY)
        .limits(jaxis, [range[0] as f32, range[1] as f32])
        .contacts_enabled(false)
        .build()
}

impl RapierHumanoid {
    /// Build the humanoid at `pose` (at rest, targets = pose angles).
    pub fn build(
        world: &mut PhysicsWorld,
        pose: &HumanoidPose,
        friction: f64,
        torque_per_step: bool,
    ) -> RapierHumanoid {
        let q = pose.root_quat();
        let root_pose = Pose::from_parts(
            v3(pose.root_position),
            Rotation::from_xyzw(q[1] as f32, q[2] as f32, q[3] as f32, q[0] as f32),
        );
        let mut bodies = [RigidBodyHandle::invalid(); NUM_BODIES];
        let mut joint_bodies = [RigidBodyHandle::invalid(); NUM_JOINTS];
        let mut all_bodies = Vec::new();
        let mut colliders = Vec::new();
        for (bi, desc) in BODIES.iter().enumerate() {
            let mut parent = desc.parent.map(|p| bodies[p]);
            let mut offset = desc.offset;
            let n = desc.joints.len();
            // Intermediate links for all hinges but the last.
            for (k, &ji) in desc.joints.iter().enumerate() {
                let last = k + 1 == n;
                let mut rb = RigidBodyBuilder::dynamic().pose(root_pose).can_sleep(false);
                if !last {
                    rb = rb.additional_mass_properties(MassProperties::new(
                        Vector::ZERO,
                        LINK_MASS,
                        Vector::splat(LINK_INERTIA),
                    ));
                }
                let h = world.insert_body(rb);
                all_bodies.push(h);
                let jd = &JOINTS[ji];
                world.insert_multibody_joint(
                    parent.expect("only the pelvis has no parent"),
                    h,
                    hinge(jd.axis, offset, jd.range),
                );
                joint_bodies[ji] = h;
                parent = Some(h);
                offset = [0.0; 3];
            }
            let h = if n > 0 {
                *all_bodies.last().expect("just inserted")
            } else {
                let h =
                    world.insert_body(RigidBodyBuilder::dynamic().pose(root_pose).can_sleep(false));
                all_bodies.push(h);
                if let Some(p) = parent {
                    let fixed = GenericJointBuilder::new(JointAxesMask::LOCKED_FIXED_AXES)
                        .local_frame1(Pose::from_translation(v3(offset)))
                        .contacts_enabled(false)
                        .build();
                    world.insert_multibody_joint(p, h, fixed);
                }
                h
            };
            bodies[bi] = h;
            for s in desc.shapes {
                let c = world.insert_collider(shape_collider(s, friction), Some(h));
                colliders.push((c, bi));
            }
        }
        let mut joint_links = [(0, 0); NUM_JOINTS];
        let mb_index = world
            .multibody_joints
            .rigid_body_link(bodies[0])
            .expect("root is a link")
            .multibody;
        for ji in 0..NUM_JOINTS {
            let link = world
                .multibody_joints
                .rigid_body_link(joint_bodies[ji])
                .expect("joint body is a link");
            let mb = world
                .multibody_joints
                .get_multibody(mb_index)
                .expect("multibody");
            let l = mb.link(link.id).expect("link");
            joint_links[ji] = (link.id, l.assembly_id());
        }
        let joints = pose.clamped_joints();
        let mb = world
            .multibody_joints
            .get_multibody_mut(mb_index)
            .expect("multibody");
        let mut disp = vec![0.0f32; mb.ndofs()];
        for ji in 0..NUM_JOINTS {
            let (_, dof) = joint_links[ji];
            disp[dof] = joints[ji] as f32;
            mb.armature_mut()[dof] = ARMATURE as f32;
        }
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&world.bodies, true);
        mb.update_rigid_bodies(&mut world.bodies, true);
        let mut h = RapierHumanoid {
            bodies,
            all_bodies,
            joint_links,
            colliders,
            targets: joints,
            wrench: RootWrench::default(),
            torque_per_step,
        };
        h.apply_controls(world);
        h
    }

    fn multibody_index(&self, world: &PhysicsWorld) -> MultibodyIndex {
        world
            .multibody_joints
            .rigid_body_link(self.bodies[0])
            .expect("root is a link")
            .multibody
    }

    /// Remove every body, collider and joint of this humanoid.
    pub fn remove(&self, world: &mut PhysicsWorld) {
        for &h in self.all_bodies.iter().rev() {
            world.remove_body(h);
        }
        world.remove_body(self.bodies[0]);
    }

    /// Refresh the servo springs (torque-limited PD) and the root wrench.
    ///
    /// MuJoCo's position servo applies `clamp(kp (q* - q) - kd q', +-max_torque)` with
    /// `kd` implicit; rapier's spring is `-kp (q - rest) - kp h q'+` (backward Euler) in
    /// each of the step's n substeps of `h = dt / n`, at the substep's own q, and the DoF
    /// damping is implicit too. Over the step the spring's velocity term averages
    /// `kp c q'` with `c = dt (n + 1) / 2n`. Unsaturated: rest = q*, damping
    /// `kd - kp c + JOINT_DAMPING`, MuJoCo's implicitfast servo at any substep count
    /// (with `kp dt` at every n, the damping fell short of `kd` by `kp dt (n - 1) / 2n`).
    /// Saturated: the spring is made to push exactly `+-max_torque` (its rest sits
    /// `max_torque / kp` away, plus `c q'` to cancel its own velocity term) and only the
    /// passive damping remains, as MuJoCo clamps the servo's damping with its spring.
    /// Clamping only the spring (as before) left `(kd + kp dt) q'` unclamped: a
    /// shoulder reached half MuJoCo's angle after 83 ms of a 2 rad step
    /// (`saturated_joint_step_responses_agree_across_backends`).
    pub fn apply_controls(&mut self, world: &mut PhysicsWorld) {
        // `c` of the doc: the spring's velocity term averaged over rapier's n substeps.
        let n = world.integration_parameters.num_solver_iterations.max(1) as f64;
        let spring_dt = world.integration_parameters.dt as f64 * (n + 1.0) / (2.0 * n);
        let idx = self.multibody_index(world);
        let mb = world
            .multibody_joints
            .get_multibody_mut(idx)
            .expect("multibody");
        let mut vel = [0.0f64; NUM_JOINTS];
        for (ji, v) in vel.iter_mut().enumerate() {
            *v = mb.generalized_velocity()[self.joint_links[ji].1] as f64;
        }
        for (ji, jd) in JOINTS.iter().enumerate() {
            let (link_id, dof) = self.joint_links[ji];
            let axis = 3 + jd.axis.index();
            let v = vel[ji];
            let q = mb.link(link_id).expect("link").joint.coords()[axis] as f64;
            let servo = jd.kp * (self.targets[ji] - q) - jd.kd * v;
            let (rest, damping) = if servo.abs() <= jd.max_torque {
                (
                    self.targets[ji],
                    (jd.kd - jd.kp * spring_dt).max(0.0) + JOINT_DAMPING,
                )
            } else {
                let torque = jd.max_torque.copysign(servo);
                (q + torque / jd.kp + spring_dt * v, JOINT_DAMPING)
            };
            mb.damping_mut()[dof] = damping as f32;
            let link = mb.link_mut(link_id).expect("link");
            link.joint.set_spring(axis, jd.kp as f32, rest as f32);
        }
        let root = &mut world.bodies[self.bodies[0]];
        root.reset_forces(false);
        if self.torque_per_step {
            // `reset_forces` leaves `add_torque`'s torque in place (rapier 0.36).
            root.reset_torques(false);
        }
        root.add_force(v3(self.wrench.force), true);
        root.add_torque(v3(self.wrench.torque), true);
    }

    /// See [`super::RapierBackend::body_contacts`].
    pub fn body_contacts(
        &self,
        world: &PhysicsWorld,
        body: usize,
    ) -> (Vec<super::ContactPoint>, usize) {
        let mut out = Vec::new();
        let mut raw = 0;
        let mut manifold = 0;
        let f3 = |v: Vector| [v.x as f64, v.y as f64, v.z as f64];
        for &(c, bi) in &self.colliders {
            if bi != body {
                continue;
            }
            let col = &world.colliders[c];
            let in_body = col.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
            for pair in world.narrow_phase.contact_pairs_with(c) {
                raw += pair.manifolds().len();
                let first = pair.collider1 == c;
                for m in pair.solver_manifolds() {
                    let n = m.data.normal;
                    let n = if first { n } else { -n };
                    for sc in &m.data.solver_contacts {
                        let Some(pt) = m.points.get(sc.contact_indices()[0] as usize) else {
                            continue;
                        };
                        let p = if first { pt.local_p1 } else { pt.local_p2 };
                        out.push(super::ContactPoint {
                            manifold,
                            local: f3(in_body * p),
                            dist: pt.dist as f64,
                            impulse: pt.data.impulse as f64,
                            tangent_impulse: pt.data.tangent_impulse.norm() as f64,
                            normal: f3(n),
                        });
                    }
                    manifold += 1;
                }
            }
        }
        (out, raw)
    }

    /// Read the state; `terrain` is the terrain collider.
    pub fn read_state(
        &self,
        world: &PhysicsWorld,
        terrain: ColliderHandle,
        out: &mut HumanoidState,
    ) {
        let idx = self.multibody_index(world);
        let mb = world
            .multibody_joints
            .get_multibody(idx)
            .expect("multibody");
        let vel = mb.generalized_velocity();
        for (ji, jd) in JOINTS.iter().enumerate() {
            let (link_id, dof) = self.joint_links[ji];
            let axis = 3 + jd.axis.index();
            out.joint_pos[ji] = mb.link(link_id).expect("link").joint.coords()[axis] as f64;
            out.joint_vel[ji] = vel[dof] as f64;
        }
        let quat = |rb: &RigidBody| {
            let r = rb.position().rotation;
            [r.w as f64, r.x as f64, r.y as f64, r.z as f64]
        };
        let p3 = |v: Vector| [v.x as f64, v.y as f64, v.z as f64];
        let root = &world.bodies[self.bodies[0]];
        out.root_position = p3(root.position().translation);
        out.root_quat = quat(root);
        out.root_linvel = p3(root.linvel());
        out.root_angvel = p3(root.angvel());
        for (bi, &h) in self.bodies.iter().enumerate() {
            out.body_pos[bi] = p3(world.bodies[h].position().translation);
        }
        let head = &world.bodies[self.bodies[HEAD]];
        out.head = math::transform(p3(head.position().translation), quat(head), HEAD_OFFSET);
        out.contact = [false; NUM_BODIES];
        out.terrain_contact = [false; NUM_BODIES];
        for &(c, bi) in &self.colliders {
            for pair in world.narrow_phase.contact_pairs_with(c) {
                // rapier's active contacts include speculative ones up to its prediction
                // distance (2 cm) away; MuJoCo reports touching geoms only. Touching is
                // where the solver pushed (`contact_flags_agree_across_backends`).
                if pair.has_any_active_contact() && pair.total_impulse_magnitude() > 0.0 {
                    out.contact[bi] = true;
                    if pair.collider1 == terrain || pair.collider2 == terrain {
                        out.terrain_contact[bi] = true;
                    }
                }
            }
        }
    }
}
