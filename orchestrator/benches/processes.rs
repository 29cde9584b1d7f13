//! Multi-process vs in-process wall time of the same route, measured in one run:
//! the two modes alternate (in-process, multi-process, multi-process without
//! polling, repeated), so a shared machine's load hits them alike, and the ratio is
//! taken per round before the median. Wall time includes spawning the component
//! processes. Every run's digest must match the in-process one.
//!
//! `cargo bench -p plamo --features mujoco --bench processes [-- ROUNDS [MAX_SECONDS]]`

use std::path::Path;
use std::time::{Duration, Instant};

use plamo::ipc::IpcSettings;
use plamo::lockstep::{Links, Lockstep, StepStatus, median_p99};
use plamo::processes::ProcessRun;
use plamo::spec::RunSpec;
use plamo_controller::ControllerSettings;
use plamo_interfaces::RunId;
use plamo_physics::BackendKind;

const ROUTE: &str = "Run from the tree to the car, then crawl to the bench";

struct Timing {
    wall: f64,
    digest: u64,
    /// Per-call medians \[s\]: physics, planners, controllers.
    calls: [f64; 3],
}

fn drive(spec: &RunSpec, links: Links, max_seconds: f64) -> (Lockstep, [f64; 3]) {
    let scene = spec.load_scene().expect("scene");
    let counts: Vec<usize> = (0..spec.agents())
        .map(|k| {
            spec.planner(&scene, k)
                .expect("plan")
                .planner()
                .instructions()
                .len()
        })
        .collect();
    let mut ls = Lockstep::start(
        links,
        scene,
        &counts,
        &ControllerSettings::default(),
        max_seconds,
    )
    .expect("start");
    while ls.step().expect("step") == StepStatus::Running {}
    let t = ls.times();
    let calls = [
        median_p99(&t.physics).0,
        median_p99(&t.planners).0,
        median_p99(&t.controllers).0,
    ];
    (ls, calls)
}

fn in_process(spec: &RunSpec, max_seconds: f64) -> Timing {
    let start = Instant::now();
    let scene = spec.load_scene().expect("scene");
    let links = spec.in_process(&scene).expect("components");
    let (ls, calls) = drive(spec, links, max_seconds);
    Timing {
        wall: start.elapsed().as_secs_f64(),
        digest: ls.digest().value(),
        calls,
    }
}

fn processes(spec: &RunSpec, max_seconds: f64, poll: Duration, run: &str) -> Timing {
    let exe = Path::new(env!("CARGO_BIN_EXE_plamo"));
    let settings = IpcSettings {
        poll,
        ..IpcSettings::default()
    };
    let start = Instant::now();
    let (procs, links) =
        ProcessRun::start(spec, &RunId::new(run).expect("id"), exe, settings, None)
            .expect("component processes");
    let (ls, calls) = drive(spec, links, max_seconds);
    let digest = ls.digest().value();
    procs.finish(Some(ls.into_links()));
    Timing {
        wall: start.elapsed().as_secs_f64(),
        digest,
        calls,
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // `cargo bench` passes `--bench`; numbers are ours.
    let nums: Vec<f64> = std::env::args().filter_map(|a| a.parse().ok()).collect();
    let rounds = nums.first().map_or(5, |&r| r as usize).max(1);
    let max_seconds = nums.get(1).copied().unwrap_or(60.0);
    let mut backends = vec![BackendKind::Rapier];
    if BackendKind::Mujoco.is_available() {
        backends.push(BackendKind::Mujoco);
    }
    println!("route `{ROUTE}` on playground, {max_seconds} s simulated, {rounds} rounds");
    for backend in backends {
        let spec = RunSpec {
            scene: "playground".into(),
            instructions: vec![ROUTE.into()],
            backend,
            seed: 0,
        };
        let mut walls = [Vec::new(), Vec::new(), Vec::new()];
        let mut ratios = [Vec::new(), Vec::new()];
        let mut calls = [[0.0; 3]; 3];
        for r in 0..rounds {
            let a = in_process(&spec, max_seconds);
            let b = processes(
                &spec,
                max_seconds,
                IpcSettings::default().poll,
                "bench-poll",
            );
            let c = processes(&spec, max_seconds, Duration::ZERO, "bench-block");
            for t in [&b, &c] {
                assert_eq!(t.digest, a.digest, "round {r}: multi-process run differs");
            }
            for (i, t) in [&a, &b, &c].iter().enumerate() {
                walls[i].push(t.wall);
                calls[i] = t.calls;
            }
            ratios[0].push(b.wall / a.wall);
            ratios[1].push(c.wall / a.wall);
        }
        let names = ["in-process", "processes (poll 0.5 ms)", "processes (block)"];
        println!("\n{backend}:");
        for (i, name) in names.iter().enumerate() {
            let w = median(&mut walls[i]);
            let c = calls[i];
            println!(
                "  {name:<24} wall median {w:.3} s; last round's per-call medians [us]: physics {:.0}, planner {:.0}, controller {:.0}",
                c[0] * 1e6,
                c[1] * 1e6,
                c[2] * 1e6
            );
        }
        println!(
            "  multi / in-process (median of per-round ratios): poll {:.2}x, block {:.2}x",
            median(&mut ratios[0]),
            median(&mut ratios[1])
        );
    }
}
