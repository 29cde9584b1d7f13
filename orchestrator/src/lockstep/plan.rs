//! Phase 2: every agent's planner reads the world at tick 4c and answers its plan.

use plamo_interfaces::{PhysicsOutput, PlanMessage};

use super::{Link, RunError};

/// Ask each planner for its agent's plan at `tick`; checks tick and agent stamps.
pub(crate) fn plan(
    planners: &mut [Box<dyn Link<PhysicsOutput, PlanMessage>>],
    tick: u64,
    world: &PhysicsOutput,
    plans: &mut [PlanMessage],
) -> Result<(), RunError> {
    for (k, (planner, out)) in planners.iter_mut().zip(plans.iter_mut()).enumerate() {
        let p = planner.call(tick, world)?;
        if p.tick != tick || p.agent as usize != k {
            return Err(RunError::WrongTick {
                component: planner.name().to_string(),
                expected: tick,
                got: p.tick,
            });
        }
        *out = p;
    }
    Ok(())
}
