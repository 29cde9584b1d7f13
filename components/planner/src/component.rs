//! The planner as a [`Component`] over the interface messages: the world as physics
//! reported it in ([`PhysicsOutput`]; the component knows which agent it plans for),
//! that agent's [`PlanMessage`] out. The same `step` runs in-process and behind an
//! IPC server. In-process callers can also read the rich [`PlannerOutput`] of the
//! last step (whole trajectory, re-plan reason) for recording.

use plamo_interfaces::{
    Component, ComponentError, Outcome, PLAN_WAYPOINTS, PhysicsOutput, PlanMessage, PlanWaypoint,
    Tick,
};
use plamo_scenes::ObstacleState;

use crate::{PlanError, PlanStatus, Planner, PlannerInput, PlannerOutput};

/// [`PlanMessage::flags`] bit: every instruction is done.
pub const FLAG_FINISHED: u32 = 1;
/// [`PlanMessage::flags`] bit: the plan was rebuilt at this tick.
pub const FLAG_REPLANNED: u32 = 2;
/// [`PlanMessage::flags`] bit: the current target is unreachable from here.
pub const FLAG_INFEASIBLE: u32 = 4;

/// One agent's planner behind the component contract.
#[derive(Debug, Clone)]
pub struct PlannerComponent {
    planner: Planner,
    agent: u32,
    input: PlannerInput,
    last: Option<PlannerOutput>,
}

impl PlannerComponent {
    /// Plan for agent `agent` (its index in [`PhysicsOutput::agents`]).
    pub fn new(planner: Planner, agent: u32) -> Self {
        Self {
            planner,
            agent,
            input: PlannerInput::default(),
            last: None,
        }
    }

    /// The wrapped planner (route, instructions, grid).
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The rich output of the last successful step.
    pub fn last_output(&self) -> Option<&PlannerOutput> {
        self.last.as_ref()
    }

    /// The agent this planner plans for.
    pub fn agent(&self) -> u32 {
        self.agent
    }
}

impl Component for PlannerComponent {
    type Input = PhysicsOutput;
    type Output = PlanMessage;
    const NAME: &'static str = "planner";

    fn step(
        &mut self,
        tick: Tick,
        input: &PhysicsOutput,
        output: &mut PlanMessage,
    ) -> Result<Outcome, ComponentError> {
        if input.tick != tick.0 {
            return Err(ComponentError::WrongTick {
                component: Self::NAME,
                expected: tick.0,
                got: input.tick,
            });
        }
        let k = self.agent as usize;
        if k >= input.agent_count as usize {
            return Err(ComponentError::InvalidInput {
                component: Self::NAME,
                field: "agent_count",
                reason: format!(
                    "planner for agent {k}, but the world has {}",
                    input.agent_count
                ),
            });
        }
        let s = &input.agents[k];
        self.input.head = s.head_position;
        self.input.root = s.root_position;
        self.input.velocity = s.root_linear_velocity;
        // Observed obstacles in scene order; external ones are not the planner's.
        let n = (input.obstacle_count as usize)
            .min(self.planner.scene().dynamic.len())
            .min(input.obstacles.len());
        self.input.obstacles.clear();
        self.input
            .obstacles
            .extend(input.obstacles[..n].iter().map(|o| ObstacleState {
                position: o.position,
                velocity: o.velocity,
            }));
        let out = match self.planner.plan_step(tick, &self.input) {
            Ok(out) => out,
            Err(PlanError::InvalidInput { field, reason }) => {
                return Err(ComponentError::InvalidInput {
                    component: Self::NAME,
                    field,
                    reason,
                });
            }
            Err(e) => {
                return Err(ComponentError::Failed {
                    component: Self::NAME,
                    reason: e.to_string(),
                });
            }
        };
        let count = self.planner.instructions().len();
        let current = out.progress.index.min(count.saturating_sub(1));
        let mut flags = 0;
        if out.status == PlanStatus::Finished {
            flags |= FLAG_FINISHED;
        }
        if out.replanned.is_some() {
            flags |= FLAG_REPLANNED;
        }
        if matches!(out.status, PlanStatus::Infeasible { .. }) {
            flags |= FLAG_INFEASIBLE;
        }
        *output = PlanMessage {
            tick: tick.0,
            agent: self.agent,
            instruction: out.progress.index as u32,
            instruction_count: count as u32,
            flags,
            progress: out.progress.fraction,
            form_height: self
                .planner
                .instructions()
                .get(current)
                .map_or(0.0, |i| self.planner.settings().head_height(i.locomotion)),
            waypoints: [PlanWaypoint::default(); PLAN_WAYPOINTS],
        };
        for (dst, w) in output.waypoints.iter_mut().zip(&out.waypoints) {
            *dst = PlanWaypoint {
                position: w.position,
                speed: w.speed,
            };
        }
        // Fewer waypoints than the message holds: repeat the last one (the plan ends).
        if let Some(last) = out.waypoints.len().checked_sub(1) {
            for i in out.waypoints.len()..PLAN_WAYPOINTS {
                output.waypoints[i] = output.waypoints[last];
            }
        }
        let done = out.status == PlanStatus::Finished;
        self.last = Some(out);
        Ok(if done {
            Outcome::Finished
        } else {
            Outcome::Continue
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PlannerSettings;
    use plamo_interfaces::HumanoidState;

    fn world(tick: u64, head: [f64; 3]) -> PhysicsOutput {
        let mut w = PhysicsOutput {
            tick,
            agent_count: 2,
            ..Default::default()
        };
        w.agents[1] = HumanoidState {
            head_position: head,
            root_position: [head[0], head[1], head[2] - 0.5],
            ..Default::default()
        };
        w
    }

    #[test]
    fn plans_for_its_agent_and_checks_ticks() {
        let scene = plamo_scenes::resolve("playground").unwrap();
        let text = "walk from the tree to the car";
        let start = scene.landmark("tree").unwrap().region.center();
        let planner = Planner::new(scene, text, start, PlannerSettings::default()).unwrap();
        let mut c = PlannerComponent::new(planner, 1);
        let mut msg = PlanMessage::default();
        let head = [start[0], start[1], 1.47];
        c.step(Tick(0), &world(0, head), &mut msg).unwrap();
        assert_eq!((msg.tick, msg.agent, msg.instruction_count), (0, 1, 1));
        assert!(msg.flags & FLAG_REPLANNED != 0);
        assert!(msg.form_height > 1.2);
        assert_ne!(msg.waypoints[0].position, msg.waypoints[9].position);
        assert!(c.last_output().is_some());
        assert!(matches!(
            c.step(Tick(4), &world(0, head), &mut msg),
            Err(ComponentError::WrongTick {
                expected: 4,
                got: 0,
                ..
            })
        ));
        let mut one = world(8, head);
        one.agent_count = 1;
        assert!(matches!(
            c.step(Tick(8), &one, &mut msg),
            Err(ComponentError::InvalidInput { .. })
        ));
    }
}
