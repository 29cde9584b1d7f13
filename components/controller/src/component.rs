//! The controller as a [`Component`] over the interface messages: one agent's state
//! and plan in ([`ControllerInput`]), its action out ([`AgentAction`]). The same `step`
//! runs in-process and behind an IPC server.
//!
//! The observation is built from the message and the scene's local height map; the
//! default policy is the [`ModelBasedController`]. Ticks must be control ticks that
//! only move forward; a gap of more than one control step means the episode was
//! interrupted (the orchestrator reset a fallen humanoid instead of asking for an
//! action), so the policy forgets its gait phase.

use plamo_interfaces::{
    ACTION_TRACK, AgentAction, Component, ComponentError, ControllerInput, HumanoidState,
    MAX_JOINTS, Outcome, PHYSICS_STEPS_PER_CONTROL, Tick,
};
use plamo_physics::{NUM_BODIES, NUM_JOINTS};
use plamo_scenes::Scene;

use crate::observation::{HumanoidSnapshot, NUM_WAYPOINTS, Observation, Waypoint};
use crate::policy::{Action, Policy};
use crate::{ControllerError, ControllerSettings, ModelBasedController};

/// One agent's controller behind the component contract (see the module docs).
pub struct ControllerComponent {
    agent: u32,
    scene: Scene,
    policy: Box<dyn Policy + Send>,
    obs: Observation,
    action: Action,
    snapshot: HumanoidSnapshot,
    plan: [Waypoint; NUM_WAYPOINTS],
    last_tick: Option<u64>,
}

/// The message's state as the controller's snapshot (quaternion to `[w, x, y, z]`).
pub fn snapshot_from_message(s: &HumanoidState, out: &mut HumanoidSnapshot) {
    let q = s.root_orientation;
    out.root_pos = s.root_position;
    out.root_quat = [q[3], q[0], q[1], q[2]];
    out.root_lin_vel = s.root_linear_velocity;
    out.root_ang_vel = s.root_angular_velocity;
    out.head_pos = s.head_position;
    out.joint_pos.clear();
    out.joint_pos
        .extend_from_slice(&s.joint_angles[..(s.joint_count as usize).min(MAX_JOINTS)]);
    out.joint_vel.clear();
    out.joint_vel
        .extend_from_slice(&s.joint_velocities[..(s.joint_count as usize).min(MAX_JOINTS)]);
    out.body_pos.clear();
    out.body_pos.extend_from_slice(s.bodies());
}

impl ControllerComponent {
    /// Agent `agent`'s controller on `scene` with the default model-based policy.
    pub fn new(
        agent: u32,
        scene: Scene,
        settings: ControllerSettings,
    ) -> Result<Self, ControllerError> {
        let policy = ModelBasedController::new(settings)?;
        Ok(Self::with_policy(agent, scene, Box::new(policy)))
    }

    /// Agent `agent`'s controller with any policy for the plamo-physics humanoid.
    pub fn with_policy(agent: u32, scene: Scene, policy: Box<dyn Policy + Send>) -> Self {
        let layout = ModelBasedController::LAYOUT;
        Self {
            agent,
            scene,
            policy,
            obs: Observation::new(layout),
            action: Action::zeros(layout.num_joints),
            snapshot: HumanoidSnapshot {
                joint_pos: Vec::with_capacity(NUM_JOINTS),
                joint_vel: Vec::with_capacity(NUM_JOINTS),
                body_pos: Vec::with_capacity(NUM_BODIES),
                ..Default::default()
            },
            plan: [Waypoint::default(); NUM_WAYPOINTS],
            last_tick: None,
        }
    }

    fn invalid(field: &'static str, reason: String) -> ComponentError {
        ComponentError::InvalidInput {
            component: Self::NAME,
            field,
            reason,
        }
    }
}

impl Component for ControllerComponent {
    type Input = ControllerInput;
    type Output = AgentAction;
    const NAME: &'static str = "controller";

    fn step(
        &mut self,
        tick: Tick,
        input: &ControllerInput,
        output: &mut AgentAction,
    ) -> Result<Outcome, ComponentError> {
        if input.tick != tick.0 || input.plan.tick != tick.0 {
            let got = if input.tick != tick.0 {
                input.tick
            } else {
                input.plan.tick
            };
            return Err(ComponentError::WrongTick {
                component: Self::NAME,
                expected: tick.0,
                got,
            });
        }
        if !tick.is_control() || self.last_tick.is_some_and(|t| tick.0 <= t) {
            return Err(ComponentError::WrongTick {
                component: Self::NAME,
                expected: self
                    .last_tick
                    .map_or(0, |t| t + PHYSICS_STEPS_PER_CONTROL as u64),
                got: tick.0,
            });
        }
        if input.agent != self.agent || input.plan.agent != self.agent {
            return Err(Self::invalid(
                "agent",
                format!(
                    "this controller serves agent {}, got state for {} and plan for {}",
                    self.agent, input.agent, input.plan.agent
                ),
            ));
        }
        let interrupted = self
            .last_tick
            .is_some_and(|t| tick.0 > t + PHYSICS_STEPS_PER_CONTROL as u64);
        if interrupted {
            self.policy.reset();
        }
        self.last_tick = Some(tick.0);
        snapshot_from_message(&input.state, &mut self.snapshot);
        for (dst, w) in self.plan.iter_mut().zip(&input.plan.waypoints) {
            *dst = Waypoint {
                x: w.position[0],
                y: w.position[1],
                z: w.position[2],
                v: w.speed,
            };
        }
        let fail = |e: ControllerError| match e {
            ControllerError::WrongLength { what, .. } | ControllerError::NonFinite { what, .. } => {
                Self::invalid(what, e.to_string())
            }
            other => ComponentError::Failed {
                component: Self::NAME,
                reason: other.to_string(),
            },
        };
        self.obs
            .update(&self.snapshot, &self.plan, &self.scene)
            .map_err(fail)?;
        self.policy.act(&self.obs, &mut self.action).map_err(fail)?;
        output.tick = tick.0;
        output.agent = self.agent;
        output.joint_count = self.action.pd_targets.len() as u32;
        output.command = ACTION_TRACK;
        output.pd_targets = [0.0; MAX_JOINTS];
        output.pd_targets[..self.action.pd_targets.len()].copy_from_slice(&self.action.pd_targets);
        output.root_wrench = match self.action.root_wrench {
            Some(w) => [
                w.force[0],
                w.force[1],
                w.force[2],
                w.torque[0],
                w.torque[1],
                w.torque[2],
            ],
            None => [0.0; 6],
        };
        Ok(Outcome::Continue)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flat_scene;
    use plamo_interfaces::{PhysicsInput, PhysicsOutput, PlanMessage, PlanWaypoint};
    use plamo_physics::{BackendKind, PhysicsComponent, PhysicsSettings, Placement};

    #[test]
    fn acts_on_messages_and_rejects_wrong_ticks_and_agents() {
        let scene = flat_scene(10.0);
        let mut physics = PhysicsComponent::new(
            BackendKind::Rapier,
            &scene,
            &PhysicsSettings::default(),
            &[Placement {
                x: 0.0,
                y: 0.0,
                yaw: 0.0,
            }],
        )
        .unwrap();
        let mut world = PhysicsOutput::default();
        physics
            .step(Tick(0), &PhysicsInput::default(), &mut world)
            .unwrap();
        let mut c = ControllerComponent::new(0, scene, ControllerSettings::default()).unwrap();
        let mut plan = PlanMessage::default();
        for (i, w) in plan.waypoints.iter_mut().enumerate() {
            *w = PlanWaypoint {
                position: [0.3 * (i + 1) as f64, 0.0, 1.47],
                speed: 0.6,
            };
        }
        let input = ControllerInput {
            tick: 0,
            agent: 0,
            reserved: 0,
            state: world.agents[0],
            plan,
        };
        let mut action = AgentAction::default();
        c.step(Tick(0), &input, &mut action).unwrap();
        assert_eq!(action.joint_count as usize, NUM_JOINTS);
        assert!(action.pd_targets.iter().all(|v| v.is_finite()));
        // The same tick again, a non-control tick, and a mismatched message tick.
        assert!(matches!(
            c.step(Tick(0), &input, &mut action),
            Err(ComponentError::WrongTick { .. })
        ));
        assert!(matches!(
            c.step(Tick(5), &input, &mut action),
            Err(ComponentError::WrongTick { got: 0, .. })
        ));
        let other = ControllerInput {
            tick: 4,
            agent: 1,
            plan: PlanMessage {
                tick: 4,
                agent: 1,
                ..plan
            },
            ..input
        };
        assert!(matches!(
            c.step(Tick(4), &other, &mut action),
            Err(ComponentError::InvalidInput { field: "agent", .. })
        ));
    }
}
