//! Obstacles driven from outside the run (an FMU host's ball or car).
//!
//! The planner predicts collisions only for obstacles its scene describes (their
//! shapes), and matches observed states to them by index; physics collides only with
//! bodies its world holds. So the planners and physics of a run with external
//! obstacles get the scene plus one slot per external obstacle ([`slot_scene`]),
//! parked out of the way until driven. Physics moves each slot to its host's sample
//! every control step (`PhysicsComponent::with_external_slots`), so the humanoid
//! collides with it and physics reports it in the slot's place, where
//! [`Lockstep::set_external_obstacles`] also puts it for the planners' current tick.
//!
//! [`Lockstep::set_external_obstacles`]: super::Lockstep::set_external_obstacles

use plamo_interfaces::{MAX_OBSTACLES, ObstacleSample};
use plamo_scenes::{DynamicObstacle, Motion, ObstacleShape, Scene};

use super::{InProcess, Link, Links, RunError};
use crate::spec::RunSpec;

/// Where an inactive external obstacle waits: far below any terrain, so no plan
/// ever meets it \[m\].
pub const PARKED: [f64; 3] = [0.0, 0.0, -1000.0];

/// An external obstacle's state while it is inactive.
pub const PARKED_SAMPLE: ObstacleSample = ObstacleSample {
    position: PARKED,
    velocity: [0.0; 3],
};

/// `scene` plus one parked obstacle slot of each shape, after the scene's own.
pub fn slot_scene(scene: &Scene, shapes: &[ObstacleShape]) -> Result<Scene, RunError> {
    let room = MAX_OBSTACLES.saturating_sub(scene.dynamic.len());
    if shapes.len() > room {
        return Err(RunError::Setup(format!(
            "{} external obstacles, but scene `{}` has {} of its own and a world holds at most {MAX_OBSTACLES}",
            shapes.len(),
            scene.name,
            scene.dynamic.len()
        )));
    }
    let mut s = scene.clone();
    s.dynamic
        .extend(shapes.iter().enumerate().map(|(k, shape)| DynamicObstacle {
            name: format!("external-{k}"),
            shape: *shape,
            motion: Motion::Linear {
                from: PARKED,
                to: PARKED,
                speed: 1.0,
            },
        }));
    Ok(s)
}

/// Every component of `spec` in this process, its planners and physics with one slot
/// per external obstacle of the given shapes (for agent placement and controllers the
/// scene is `scene` itself).
pub fn in_process_with_external(
    spec: &RunSpec,
    scene: &Scene,
    shapes: &[ObstacleShape],
) -> Result<Links, RunError> {
    let with_slots = slot_scene(scene, shapes)?;
    let mut planners: Vec<Box<dyn Link<_, _>>> = Vec::new();
    let mut controllers: Vec<Box<dyn Link<_, _>>> = Vec::new();
    let mut headings = Vec::new();
    for k in 0..spec.agents() {
        let planner = spec.planner_in(scene, &with_slots, k)?;
        headings.push(planner.planner().start_heading());
        planners.push(Box::new(InProcess::new(format!("planner-{k}"), planner)));
        controllers.push(Box::new(InProcess::new(
            format!("controller-{k}"),
            spec.controller(scene, k)?,
        )));
    }
    Ok(Links {
        physics: Box::new(InProcess::new(
            "physics",
            spec.physics_facing(&with_slots, &spec.physics_settings()?, &headings)?
                .with_external_slots(shapes.len())
                .map_err(|e| RunError::Setup(e.to_string()))?,
        )),
        planners,
        controllers,
    })
}

/// Check external obstacle states: finite, and few enough to fit next to the scene's.
pub(crate) fn check(scene_obstacles: usize, obstacles: &[ObstacleSample]) -> Result<(), RunError> {
    if scene_obstacles + obstacles.len() > MAX_OBSTACLES {
        return Err(RunError::Setup(format!(
            "{} external obstacles next to the scene's {scene_obstacles}: a world holds at most {MAX_OBSTACLES}",
            obstacles.len()
        )));
    }
    for (k, o) in obstacles.iter().enumerate() {
        if o.position.iter().chain(&o.velocity).any(|x| !x.is_finite()) {
            return Err(RunError::Setup(format!(
                "external obstacle {k}: position {:?} / velocity {:?}: finite numbers only",
                o.position, o.velocity
            )));
        }
    }
    Ok(())
}
