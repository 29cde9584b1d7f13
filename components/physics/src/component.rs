//! The physics world as a [`Component`] over the interface messages: every agent's
//! action in ([`PhysicsInput`]), every agent's state and the obstacles out
//! ([`PhysicsOutput`]). The same `step` runs in-process and behind an IPC server.
//!
//! # Protocol
//! - A step at control tick `c` (a multiple of 4) applies each agent's PD targets and
//!   root wrench, takes [`PHYSICS_STEPS_PER_CONTROL`] steps of 1/120 s, and reports
//!   the world at tick `c + 4`. The input's tick and the step's tick must both equal
//!   the world's current tick, else [`ComponentError::WrongTick`].
//! - An input in mode [`PHYSICS_OBSERVE`] (the default) steps nothing and reports the
//!   world at its current tick: the orchestrator's first read, before tick 0's
//!   control step. Mode [`PHYSICS_STEP`] applies the actions and steps.
//! - An action with command [`ACTION_RESET`] ([`reset_request`]) puts that agent back
//!   at rest before the steps, in the pose its [`ResetPose`] names: pelvis over the
//!   given XY, the given heading, standing ([`RESET_STAND`]) or on hands and knees
//!   ([`RESET_CRAWL`], [`HumanoidPose::crawling_on`]), resting on the terrain (how the
//!   orchestrator recovers a fallen humanoid; it picks a place on the plan clear of
//!   walls and tops). A non-finite or off-terrain place or an unknown form is an
//!   error naming the field. [`ACTION_TRACK`] drives the joints to its PD targets.
//!   Any other command is an error.
//! - `fallen` in each reported state uses the most lenient posture (crawl): the head
//!   is below 0.15 m above the ground or touches the terrain. Posture-aware fall
//!   rules belong to whoever knows the requested posture (the orchestrator).
//! - External obstacles (an FMU host's ball or car) need slots: a world built with
//!   [`PhysicsComponent::with_external_slots`] takes its scene's last `n` dynamic
//!   obstacles as theirs. At each step the input's external obstacle `k` drives slot
//!   `k` (from its position at its constant velocity, [`PhysicsBackend::drive_obstacle`]),
//!   so humanoids collide with it like with any scene obstacle, and it is reported
//!   in the slot's place. More external obstacles than slots is an error.

use plamo_interfaces::{
    ACTION_RESET, ACTION_TRACK, AgentAction, Component, ComponentError, MAX_AGENTS, MAX_BODIES,
    MAX_JOINTS, MAX_OBSTACLES, ObstacleSample, Outcome, PHYSICS_OBSERVE, PHYSICS_STEP,
    PHYSICS_STEPS_PER_CONTROL, PhysicsInput, PhysicsOutput, RESET_CRAWL, RESET_STAND, ResetPose,
    Tick,
};
use plamo_scenes::{ObstacleState, Scene};

use crate::{
    BackendKind, HumanoidPose, NUM_BODIES, NUM_JOINTS, PhysicsBackend, PhysicsError,
    PhysicsSettings, Posture, RootWrench, create_backend, detect_fall,
};

/// A start (or reset) placement of one humanoid: x, y \[m\] and heading \[rad\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// X \[m\].
    pub x: f64,
    /// Y \[m\].
    pub y: f64,
    /// Heading about +Z \[rad\] (0 faces +X).
    pub yaw: f64,
}

/// The physics world behind the component contract (see the module docs).
pub struct PhysicsComponent {
    backend: Box<dyn PhysicsBackend>,
    scene: Scene,
    agents: usize,
    /// Index of the first external obstacle slot in `scene.dynamic`.
    first_slot: usize,
}

/// An action asking physics to put `agent` back at rest in `pose` (see the module
/// docs).
pub fn reset_request(tick: u64, agent: u32, pose: ResetPose) -> AgentAction {
    AgentAction {
        tick,
        agent,
        joint_count: 0,
        command: ACTION_RESET,
        reset: pose,
        ..AgentAction::default()
    }
}

fn failed(e: PhysicsError) -> ComponentError {
    ComponentError::Failed {
        component: PhysicsComponent::NAME,
        reason: e.to_string(),
    }
}

fn to_message_quat(q: [f64; 4]) -> [f64; 4] {
    // Physics stores [w, x, y, z]; messages carry (x, y, z, w).
    [q[1], q[2], q[3], q[0]]
}

impl PhysicsComponent {
    /// A world of `kind` for `scene` with one humanoid per placement, each standing
    /// on the terrain. `settings.humanoids` is overridden by the placement count.
    pub fn new(
        kind: BackendKind,
        scene: &Scene,
        settings: &PhysicsSettings,
        placements: &[Placement],
    ) -> Result<Self, PhysicsError> {
        if placements.is_empty() || placements.len() > MAX_AGENTS {
            return Err(PhysicsError::InvalidSettings {
                field: "humanoids",
                reason: format!("must be in 1..={MAX_AGENTS}, got {}", placements.len()),
            });
        }
        let settings = PhysicsSettings {
            humanoids: placements.len(),
            ..settings.clone()
        };
        let mut backend = create_backend(kind, scene, &settings)?;
        for (i, p) in placements.iter().enumerate() {
            backend.reset_humanoid(
                i,
                &HumanoidPose::standing_on(&scene.terrain, p.x, p.y, p.yaw),
            )?;
        }
        Ok(Self {
            backend,
            first_slot: scene.dynamic.len(),
            scene: scene.clone(),
            agents: placements.len(),
        })
    }

    /// The scene's last `n` dynamic obstacles become slots for external obstacles
    /// (see the module docs); how they move until the first step is their scene
    /// motion (e.g. parked out of the way).
    pub fn with_external_slots(mut self, n: usize) -> Result<Self, PhysicsError> {
        let own = self.scene.dynamic.len();
        if n > own {
            return Err(PhysicsError::InvalidScene {
                reason: format!(
                    "{n} external obstacle slots, but scene `{}` has only {own} dynamic obstacles to serve as slots",
                    self.scene.name
                ),
            });
        }
        self.first_slot = own - n;
        Ok(self)
    }

    /// The world's current tick.
    pub fn tick(&self) -> Tick {
        self.backend.tick()
    }

    /// The backend (read-only), e.g. for the rich per-agent state.
    pub fn backend(&self) -> &dyn PhysicsBackend {
        self.backend.as_ref()
    }

    /// Write the world as it is now into `out`.
    pub fn observe(&self, out: &mut PhysicsOutput) -> Result<(), PhysicsError> {
        out.tick = self.backend.tick().0;
        out.agent_count = self.agents as u32;
        for i in 0..self.agents {
            let s = self.backend.humanoid_state(i)?;
            let m = &mut out.agents[i];
            m.root_position = s.root_position;
            m.root_orientation = to_message_quat(s.root_quat);
            m.root_linear_velocity = s.root_linvel;
            m.root_angular_velocity = s.root_angvel;
            m.head_position = s.head;
            m.joint_count = NUM_JOINTS as u32;
            m.body_count = NUM_BODIES as u32;
            m.joint_angles = [0.0; MAX_JOINTS];
            m.joint_velocities = [0.0; MAX_JOINTS];
            m.joint_angles[..NUM_JOINTS].copy_from_slice(&s.joint_pos);
            m.joint_velocities[..NUM_JOINTS].copy_from_slice(&s.joint_vel);
            m.body_positions = [[0.0; 3]; MAX_BODIES];
            m.body_positions[..NUM_BODIES].copy_from_slice(&s.body_pos);
            m.body_contacts = s
                .contact
                .iter()
                .enumerate()
                .fold(0u32, |acc, (b, &c)| acc | ((c as u32) << b));
            let ground = self.scene.height_at(s.head[0], s.head[1]);
            m.fallen = detect_fall(s, Posture::Crawl, ground).is_some() as u32;
        }
        let obstacles = self.backend.obstacles();
        let n = obstacles.len().min(MAX_OBSTACLES);
        for (m, o) in out.obstacles.iter_mut().zip(&obstacles[..n]) {
            *m = ObstacleSample {
                position: o.position,
                velocity: o.velocity,
            };
        }
        out.obstacle_count = n as u32;
        Ok(())
    }

    /// Move the external obstacle slots to the input's samples.
    fn drive_external(&mut self, external: &[ObstacleSample]) -> Result<(), ComponentError> {
        let slots = self.scene.dynamic.len() - self.first_slot;
        if external.len() > slots {
            return Err(ComponentError::InvalidInput {
                component: Self::NAME,
                field: "external_count",
                reason: format!(
                    "{} external obstacles, but this world has {slots} slots for them \
                     (build it with `PhysicsComponent::with_external_slots`)",
                    external.len()
                ),
            });
        }
        for (k, e) in external.iter().enumerate() {
            let state = ObstacleState {
                position: e.position,
                velocity: e.velocity,
            };
            self.backend
                .drive_obstacle(self.first_slot + k, state)
                .map_err(|err| ComponentError::InvalidInput {
                    component: Self::NAME,
                    field: "external_obstacles",
                    reason: format!("external obstacle {k}: {err}"),
                })?;
        }
        Ok(())
    }

    fn reset_to(&mut self, agent: usize, r: &ResetPose) -> Result<(), ComponentError> {
        let invalid = |field, reason: String| ComponentError::InvalidInput {
            component: Self::NAME,
            field,
            reason: format!("agent {agent}: {reason}"),
        };
        let [x, y] = r.position;
        if !(x.is_finite() && y.is_finite() && r.yaw.is_finite()) {
            return Err(invalid(
                "actions.reset",
                format!("position ({x}, {y}) and yaw {} must be finite", r.yaw),
            ));
        }
        if !self.scene.terrain.contains(x, y) {
            let (lo, hi) = self.scene.terrain.bounds();
            return Err(invalid(
                "actions.reset.position",
                format!(
                    "({x:.3}, {y:.3}) is off the terrain (x {:.2}..{:.2}, y {:.2}..{:.2})",
                    lo[0], hi[0], lo[1], hi[1]
                ),
            ));
        }
        let terrain = &self.scene.terrain;
        let pose = match r.form {
            RESET_STAND => HumanoidPose::standing_on(terrain, x, y, r.yaw),
            RESET_CRAWL => HumanoidPose::crawling_on(terrain, x, y, r.yaw),
            other => {
                return Err(invalid(
                    "actions.reset.form",
                    format!(
                        "form {other}; expected {RESET_STAND} (standing) or {RESET_CRAWL} \
                         (hands and knees)"
                    ),
                ));
            }
        };
        self.backend.reset_humanoid(agent, &pose).map_err(failed)
    }

    fn apply(&mut self, agent: usize, a: &AgentAction) -> Result<(), ComponentError> {
        match a.command {
            ACTION_RESET => return self.reset_to(agent, &a.reset),
            ACTION_TRACK => {}
            other => {
                return Err(ComponentError::InvalidInput {
                    component: Self::NAME,
                    field: "actions.command",
                    reason: format!(
                        "agent {agent}: command {other}; expected {ACTION_TRACK} (track the PD \
                         targets) or {ACTION_RESET} (reset into a pose)"
                    ),
                });
            }
        }
        if a.joint_count as usize != NUM_JOINTS {
            return Err(ComponentError::InvalidInput {
                component: Self::NAME,
                field: "actions.joint_count",
                reason: format!(
                    "agent {agent}: {} joint targets, expected {NUM_JOINTS}",
                    a.joint_count
                ),
            });
        }
        let w = a.root_wrench;
        let wrench = (w != [0.0; 6]).then_some(RootWrench {
            force: [w[0], w[1], w[2]],
            torque: [w[3], w[4], w[5]],
        });
        self.backend
            .set_action_for(agent, &a.pd_targets[..NUM_JOINTS], wrench)
            .map_err(|e| ComponentError::InvalidInput {
                component: Self::NAME,
                field: "actions",
                reason: format!("agent {agent}: {e}"),
            })
    }
}

impl Component for PhysicsComponent {
    type Input = PhysicsInput;
    type Output = PhysicsOutput;
    const NAME: &'static str = "physics";

    fn step(
        &mut self,
        tick: Tick,
        input: &PhysicsInput,
        output: &mut PhysicsOutput,
    ) -> Result<Outcome, ComponentError> {
        let expected = self.backend.tick().0;
        for got in [tick.0, input.tick] {
            if got != expected {
                return Err(ComponentError::WrongTick {
                    component: Self::NAME,
                    expected,
                    got,
                });
            }
        }
        match input.mode {
            PHYSICS_OBSERVE => {
                self.observe(output).map_err(failed)?;
                return Ok(Outcome::Continue);
            }
            PHYSICS_STEP => {}
            other => {
                return Err(ComponentError::InvalidInput {
                    component: Self::NAME,
                    field: "mode",
                    reason: format!(
                        "{other}; expected {PHYSICS_OBSERVE} (observe) or {PHYSICS_STEP} (step)"
                    ),
                });
            }
        }
        if input.agent_count as usize != self.agents {
            return Err(ComponentError::InvalidInput {
                component: Self::NAME,
                field: "agent_count",
                reason: format!(
                    "{} actions for a world of {} humanoids",
                    input.agent_count, self.agents
                ),
            });
        }
        for (i, a) in input.actions[..self.agents].iter().enumerate() {
            self.apply(i, a)?;
        }
        let external_count = (input.external_count as usize).min(MAX_OBSTACLES);
        self.drive_external(&input.external_obstacles[..external_count])?;
        self.backend
            .step_n(PHYSICS_STEPS_PER_CONTROL as usize)
            .map_err(failed)?;
        self.observe(output).map_err(failed)?;
        Ok(Outcome::Continue)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_scenes::HeightGrid;
    use std::f64::consts::FRAC_PI_2;

    fn flat() -> Scene {
        Scene {
            name: "flat".into(),
            description: String::new(),
            terrain: HeightGrid::flat([-3.0, -3.0], [6.0, 6.0], 0.1, 0.0),
            walls: vec![],
            dynamic: vec![],
            tops: vec![],
            landmarks: vec![],
        }
    }

    fn world(n: usize) -> PhysicsComponent {
        let places: Vec<Placement> = (0..n)
            .map(|i| Placement {
                x: 0.0,
                y: i as f64,
                yaw: 0.0,
            })
            .collect();
        PhysicsComponent::new(
            BackendKind::Rapier,
            &flat(),
            &PhysicsSettings::default(),
            &places,
        )
        .unwrap()
    }

    #[test]
    fn observe_then_step_four_ticks_and_reject_wrong_ticks() {
        let mut p = world(2);
        let mut out = PhysicsOutput::default();
        p.step(Tick(0), &PhysicsInput::default(), &mut out).unwrap();
        assert_eq!((out.tick, out.agent_count), (0, 2));
        assert!(out.agents[1].head_position[2] > 1.3);
        assert_eq!(out.agents[1].root_position[1], 1.0);
        let mut input = PhysicsInput {
            tick: 0,
            agent_count: 2,
            mode: PHYSICS_STEP,
            ..Default::default()
        };
        for (i, a) in input.actions.iter_mut().take(2).enumerate() {
            a.agent = i as u32;
            a.joint_count = NUM_JOINTS as u32;
        }
        // An action nobody filled in (command 0) is refused, not taken as a reset.
        assert!(matches!(
            p.step(Tick(0), &input, &mut out),
            Err(ComponentError::InvalidInput {
                field: "actions.command",
                ..
            })
        ));
        for a in input.actions.iter_mut().take(2) {
            a.command = ACTION_TRACK;
        }
        input.mode = 7;
        assert!(matches!(
            p.step(Tick(0), &input, &mut out),
            Err(ComponentError::InvalidInput { field: "mode", .. })
        ));
        input.mode = PHYSICS_STEP;
        p.step(Tick(0), &input, &mut out).unwrap();
        assert_eq!(out.tick, 4);
        let err = p.step(Tick(0), &input, &mut out).unwrap_err();
        assert_eq!(
            err,
            ComponentError::WrongTick {
                component: "physics",
                expected: 4,
                got: 0
            }
        );
        input.tick = 4;
        input.actions[1].joint_count = 3;
        assert!(matches!(
            p.step(Tick(4), &input, &mut out),
            Err(ComponentError::InvalidInput { .. })
        ));
        let stand = ResetPose {
            position: [0.5, 1.0],
            yaw: 0.0,
            form: RESET_STAND,
            reserved: 0,
        };
        input.actions[1] = reset_request(4, 1, stand);
        p.step(Tick(4), &input, &mut out).unwrap();
        assert_eq!(out.tick, 8);
    }

    #[test]
    fn resets_put_the_humanoid_where_and_how_asked_and_refuse_bad_poses() {
        let mut p = world(1);
        let mut out = PhysicsOutput::default();
        let mut input = PhysicsInput {
            tick: 0,
            agent_count: 1,
            mode: PHYSICS_STEP,
            ..Default::default()
        };
        let crawl = ResetPose {
            position: [1.0, -0.5],
            yaw: FRAC_PI_2,
            form: RESET_CRAWL,
            reserved: 0,
        };
        input.actions[0] = reset_request(0, 0, crawl);
        p.step(Tick(0), &input, &mut out).unwrap();
        let s = out.agents[0];
        // On hands and knees over (1, -0.5), facing +Y: the head low and ahead in +Y.
        assert!(
            (s.root_position[0] - 1.0).abs() < 0.05,
            "{:?}",
            s.root_position
        );
        assert!(
            (s.root_position[1] + 0.5).abs() < 0.05,
            "{:?}",
            s.root_position
        );
        assert!(
            (0.2..0.6).contains(&s.head_position[2]),
            "{:?}",
            s.head_position
        );
        assert!(s.head_position[1] > s.root_position[1] + 0.2);
        let bad = [
            (ResetPose { form: 0, ..crawl }, "actions.reset.form"),
            (
                ResetPose {
                    position: [f64::NAN, 0.0],
                    ..crawl
                },
                "actions.reset",
            ),
            (
                ResetPose {
                    position: [40.0, 0.0],
                    ..crawl
                },
                "actions.reset.position",
            ),
        ];
        for (pose, field) in bad {
            input.tick = out.tick;
            input.actions[0] = reset_request(out.tick, 0, pose);
            let err = p.step(Tick(out.tick), &input, &mut out).unwrap_err();
            match err {
                ComponentError::InvalidInput {
                    field: f, reason, ..
                } => {
                    assert_eq!(f, field, "{reason}");
                }
                other => panic!("{other:?}"),
            }
        }
    }
}
