//! Phase 3: every standing agent's controller turns its state and plan into an
//! action; a fallen agent gets a reset request instead (physics stands it up where it
//! is, and its controller sees a gap in ticks and forgets its gait phase).

use plamo_interfaces::{
    AgentAction, ControllerInput, PHYSICS_STEP, PhysicsInput, PhysicsOutput, PlanMessage,
};
use plamo_physics::reset_request;

use super::{Link, RunError};

/// Fill `input.actions` for the control period starting at `tick`.
pub(crate) fn control(
    controllers: &mut [Box<dyn Link<ControllerInput, AgentAction>>],
    tick: u64,
    world: &PhysicsOutput,
    plans: &[PlanMessage],
    fallen: &[bool],
    input: &mut PhysicsInput,
) -> Result<(), RunError> {
    input.tick = tick;
    input.mode = PHYSICS_STEP;
    input.agent_count = controllers.len() as u32;
    for (k, controller) in controllers.iter_mut().enumerate() {
        if fallen[k] {
            input.actions[k] = reset_request(tick, k as u32);
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
