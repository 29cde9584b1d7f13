//! One controller step: observation build (incl. the 8x8 height map query) plus the
//! model-based policy, from a real standing humanoid state (rapier).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use plamo_controller::{
    Action, ControllerSettings, HumanoidSnapshot, ModelBasedController, NUM_WAYPOINTS, Observation,
    Policy, StraightPath, flat_scene,
};
use plamo_physics::{BackendKind, HumanoidPose, PhysicsSettings, create_backend};

fn step(c: &mut Criterion) {
    let scene = flat_scene(20.0);
    let mut physics =
        create_backend(BackendKind::Rapier, &scene, &PhysicsSettings::default()).unwrap();
    physics
        .reset(&HumanoidPose::standing(0.0, 0.0, 0.0, 0.0))
        .unwrap();
    physics.step_n(8).unwrap();
    let snap = HumanoidSnapshot::from(physics.state());
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: 1.0,
        head_height: 1.47,
    };
    let plan: Vec<_> = (1..=NUM_WAYPOINTS)
        .map(|i| path.at(&scene, 0.5 * i as f64))
        .collect();
    let mut policy = ModelBasedController::new(ControllerSettings::default()).unwrap();
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::default();
    c.bench_function("controller_step_model_based", |b| {
        b.iter(|| {
            obs.update(black_box(&snap), black_box(&plan), &scene)
                .unwrap();
            policy.act(&obs, &mut action).unwrap();
            black_box(&action);
        })
    });
    let mut flat = vec![0.0f32; ModelBasedController::LAYOUT.len()];
    c.bench_function("observation_flatten", |b| {
        b.iter(|| obs.flatten_into(black_box(&mut flat)).unwrap())
    });
}

criterion_group!(benches, step);
criterion_main!(benches);
