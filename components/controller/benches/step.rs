//! One controller step: observation build (incl. the 8x8 height map query) plus the
//! model-based policy, from a real standing humanoid state (rapier): walking (the biped
//! gait) and asked to crawl (the four-limb gait: getting down, then crawling, as the
//! repeated steps advance its phase), with the built-in crawl on forearms and knees
//! and, as baselines in the same run, the same without `pursuit` and the
//! hand-and-knee crawl.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use plamo_controller::{
    Action, ControllerSettings, CrawlParams, GaitParams, HumanoidSnapshot, ModelBasedController,
    NUM_WAYPOINTS, Observation, Policy, StraightPath, flat_scene,
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
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::default();
    let (forearms, hands) = (CrawlParams::default(), CrawlParams::hands());
    let no_pursuit = CrawlParams {
        pursuit: 0.0,
        ..forearms
    };
    for (name, head_height, speed, crawl) in [
        ("controller_step_model_based", 1.47, 1.0, forearms),
        ("controller_step_model_based_crawl", 0.4, 0.5, forearms),
        ("controller_step_crawl_no_pursuit", 0.4, 0.5, no_pursuit),
        ("controller_step_model_based_crawl_hands", 0.4, 0.5, hands),
    ] {
        let path = StraightPath {
            start: [0.0, 0.0],
            speed,
            head_height,
        };
        let plan: Vec<_> = (1..=NUM_WAYPOINTS)
            .map(|i| path.at(&scene, 0.5 * i as f64))
            .collect();
        let mut policy = ModelBasedController::with_all_params(
            GaitParams::default(),
            crawl,
            ControllerSettings::default(),
        )
        .unwrap();
        c.bench_function(name, |b| {
            b.iter(|| {
                obs.update(black_box(&snap), black_box(&plan), &scene)
                    .unwrap();
                policy.act(&obs, &mut action).unwrap();
                black_box(&action);
            })
        });
    }
    let mut flat = vec![0.0f32; ModelBasedController::LAYOUT.len()];
    c.bench_function("observation_flatten", |b| {
        b.iter(|| obs.flatten_into(black_box(&mut flat)).unwrap())
    });
}

criterion_group!(benches, step);
criterion_main!(benches);
