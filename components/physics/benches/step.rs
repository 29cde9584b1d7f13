//! Steps per second: one humanoid on a 30 x 30 m rough terrain (gravel bumps, a wall,
//! a ceiling, a moving ball), and eight humanoids in one world. Both backends run in
//! the same process so their ratio comes from one run:
//! `cargo bench -p plamo-physics --features mujoco --bench step`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use plamo_physics::{
    BackendKind, HumanoidPose, NUM_JOINTS, PhysicsBackend, PhysicsSettings, create_backend,
};
use plamo_scenes::{
    DynamicObstacle, Footprint, HeightGrid, Motion, ObstacleShape, Scene, TopObstacle, Wall,
};

fn playground() -> Scene {
    let mut g = HeightGrid::flat([-15.0, -15.0], [30.0, 30.0], 0.1, 0.0);
    for j in 0..g.ny {
        for i in 0..g.nx {
            let [x, y] = g.position(i, j);
            let h = ((x * 12.9898 + y * 78.233).sin() * 43758.5453).fract();
            g.heights[j * g.nx + i] = 0.01 * h + 0.05 * (0.3 * x).sin() * (0.2 * y).cos();
        }
    }
    Scene {
        name: "bench-playground".into(),
        description: "30 x 30 m rough terrain with a wall, a ceiling and a ball".into(),
        terrain: g,
        walls: vec![Wall {
            name: "wall".into(),
            footprint: Footprint::axis_aligned([5.0, 0.0], [0.1, 3.0]),
            z_min: -0.5,
            z_max: 2.0,
        }],
        tops: vec![TopObstacle {
            name: "roof".into(),
            footprint: Footprint::axis_aligned([-5.0, 0.0], [1.0, 2.0]),
            z_bottom: 1.0,
            z_top: 1.3,
        }],
        dynamic: vec![DynamicObstacle {
            name: "ball".into(),
            shape: ObstacleShape::Sphere { radius: 0.3 },
            motion: Motion::Circle {
                center: [0.0, 6.0, 0.4],
                radius: 3.0,
                period: 8.0,
                phase: 0.0,
                clockwise: false,
            },
        }],
        landmarks: vec![],
    }
}

/// Ticks between resets: under pure PD on this terrain the humanoid stays upright
/// (head > 1.43 m) for ~1.3 s and lies on the ground from ~2.1 s, in both engines, so
/// a reset every second keeps every sample on a standing humanoid.
const RESET_EVERY: u64 = 120;

fn world(
    kind: BackendKind,
    scene: &Scene,
    n: usize,
    rapier_iterations: usize,
) -> Box<dyn PhysicsBackend> {
    let settings = PhysicsSettings {
        humanoids: n,
        rapier_solver_iterations: rapier_iterations,
        ..PhysicsSettings::default()
    };
    let mut b = create_backend(kind, scene, &settings).expect("backend");
    reset(b.as_mut(), scene);
    b
}

/// Stand every humanoid up again (cheap: no model rebuild).
fn reset(b: &mut dyn PhysicsBackend, scene: &Scene) {
    for i in 0..b.num_humanoids() {
        let pose = HumanoidPose::standing_on(
            &scene.terrain,
            -2.0 + 1.5 * (i % 4) as f64,
            -2.0 + 2.0 * (i / 4) as f64,
            0.0,
        );
        b.reset_humanoid(i, &pose).expect("reset");
        b.set_action_for(i, &[0.0; NUM_JOINTS], None)
            .expect("action");
    }
}

fn bench(c: &mut Criterion) {
    let scene = playground();
    let kinds: Vec<BackendKind> = BackendKind::ALL
        .into_iter()
        .filter(|k| k.is_available())
        .collect();
    let mut group = c.benchmark_group("physics_step");
    group.throughput(Throughput::Elements(1));
    let default_iterations = PhysicsSettings::default().rapier_solver_iterations;
    let mut cases: Vec<(BackendKind, usize, usize, String)> = Vec::new();
    for &kind in &kinds {
        for n in [1usize, 8] {
            cases.push((kind, n, default_iterations, format!("{kind}/{n}_humanoids")));
        }
    }
    // rapier's solver iterations are its substeps: the cost of the other settings
    // (BENCHMARKS.md "rapier solver settings"), as ratios against the default.
    for iterations in [1, 2, 8] {
        cases.push((
            BackendKind::Rapier,
            1,
            iterations,
            format!("rapier_{iterations}_solver_iterations/1_humanoids"),
        ));
    }
    for (kind, n, iterations, name) in cases {
        let mut b = world(kind, &scene, n, iterations);
        group.bench_function(name, |bencher| {
            bencher.iter(|| {
                if b.step().is_err() || b.tick().0.is_multiple_of(RESET_EVERY) {
                    reset(b.as_mut(), &scene);
                }
            })
        });
        // Every sample measured an upright humanoid.
        assert!(b.state().head[2] > 1.3, "{kind}: fell during the bench");
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
