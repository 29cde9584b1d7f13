//! Phase 3: every standing agent's controller turns its state and plan into an
//! action; a fallen agent gets a reset request instead: physics puts it back at rest
//! on its plan, clear of walls and tops, in the plan's form there (standing, or on
//! hands and knees where the plan crawls or a top is overhead), facing along the plan,
//! and further along the plan after repeated falls at one spot ([`super::recover`]).
//! Its controller then sees a gap in ticks, forgets its gait phase and starts from
//! the pose it finds (a crawl pose crawls on).

use plamo_interfaces::{
    AgentAction, ControllerInput, PHYSICS_STEP, PhysicsInput, PhysicsOutput, PlanMessage,
};
use plamo_physics::reset_request;
use plamo_scenes::Scene;

use super::recover::Recovery;
use super::{Link, RunError};

/// The fallen agents of a control step and what their resets need.
pub(crate) struct Fallen<'a> {
    /// Whether agent k is fallen.
    pub flags: &'a [bool],
    /// The scene the resets must fit into.
    pub scene: &'a Scene,
    /// Each agent's falls at one spot.
    pub recovery: &'a mut [Recovery],
}

/// Fill `input.actions` for the control period starting at `tick`.
pub(crate) fn control(
    controllers: &mut [Box<dyn Link<ControllerInput, AgentAction>>],
    tick: u64,
    world: &PhysicsOutput,
    plans: &[PlanMessage],
    fallen: Fallen<'_>,
    input: &mut PhysicsInput,
) -> Result<(), RunError> {
    input.tick = tick;
    input.mode = PHYSICS_STEP;
    input.agent_count = controllers.len() as u32;
    for (k, controller) in controllers.iter_mut().enumerate() {
        if fallen.flags[k] {
            let pose = fallen.recovery[k].reset_pose(fallen.scene, &world.agents[k], &plans[k]);
            input.actions[k] = reset_request(tick, k as u32, pose);
            continue;
        }
        let msg = ControllerInput {
            tick,
            agent: k as u32,
            reserved: 0,
            state: world.agents[k],
            plan: plans[k],
        };
        let a = controller.call(tick, &msg)?;
        if a.tick != tick || a.agent as usize != k {
            return Err(RunError::WrongTick {
                component: controller.name().to_string(),
                expected: tick,
                got: a.tick,
            });
        }
        input.actions[k] = a;
    }
    Ok(())
}
