//! Phase 4: physics applies every agent's action and takes four 1/120 s steps.

use plamo_interfaces::{PHYSICS_STEPS_PER_CONTROL, PhysicsInput, PhysicsOutput};

use super::{Link, RunError};

/// Step the world from `input.tick` to `input.tick + 4`.
pub(crate) fn actuate(
    physics: &mut dyn Link<PhysicsInput, PhysicsOutput>,
    input: &PhysicsInput,
) -> Result<PhysicsOutput, RunError> {
    let out = physics.call(input.tick, input)?;
    let expected = input.tick + PHYSICS_STEPS_PER_CONTROL as u64;
    if out.tick != expected {
        return Err(RunError::WrongTick {
            component: physics.name().to_string(),
            expected,
            got: out.tick,
        });
    }
    Ok(out)
}
