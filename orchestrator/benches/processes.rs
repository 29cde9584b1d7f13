//! Multi-process vs in-process wall time of the same route, measured in one run:
//! the two modes alternate (in-process, multi-process, multi-process without
//! polling, repeated), so a shared machine's load hits them alike, and the ratio is
//! taken per round before the median. Wall time includes spawning the component
//! processes. Every run's digest must match the in-process one.
//!
//! `cargo bench -p plamo --features mujoco --bench processes [-- ROUNDS [MAX_SECONDS]]`

#[path = "../tests/support/mod.rs"]
mod support;

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
    /// Start-up (components built, processes ready), the lockstep loop, and the
    /// shutdown \[s\].
    phases: [f64; 3],
    digest: u64,
    /// Per-call medians and means \[s\]: physics, planners, controllers.
    calls: [(f64, f64); 3],
}

fn median_mean(v: &[f64]) -> (f64, f64) {
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    (median_p99(v).0, mean)
}

fn drive(spec: &RunSpec, links: Links, max_seconds: f64) -> (Lockstep, [(f64, f64); 3]) {
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
        median_mean(&t.physics),
        median_mean(&t.planners),
        median_mean(&t.controllers),
    ];
    (ls, calls)
}

fn in_process(spec: &RunSpec, max_seconds: f64) -> Timing {
    let start = Instant::now();
    let scene = spec.load_scene().expect("scene");
    let links = spec.in_process(&scene).expect("components");
    let up = start.elapsed().as_secs_f64();
    let (ls, calls) = drive(spec, links, max_seconds);
    let wall = start.elapsed().as_secs_f64();
    Timing {
        wall,
        phases: [up, wall - up, 0.0],
        digest: ls.digest().value(),
        calls,
    }
}

fn processes(spec: &RunSpec, max_seconds: f64, settings: IpcSettings, run: &str) -> Timing {
    let exe = Path::new(env!("CARGO_BIN_EXE_plamo"));
    let start = Instant::now();
    let (procs, links) =
        ProcessRun::start(spec, &RunId::new(run).expect("id"), exe, settings, None)
            .expect("component processes");
    let up = start.elapsed().as_secs_f64();
    let (ls, calls) = drive(spec, links, max_seconds);
    let looped = start.elapsed().as_secs_f64();
    let digest = ls.digest().value();
    procs.finish(Some(ls.into_links()));
    let wall = start.elapsed().as_secs_f64();
    Timing {
        wall,
        phases: [up, looped - up, wall - looped],
        digest,
        calls,
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The multi-process variants measured against in-process, by name.
fn variants() -> Vec<(&'static str, IpcSettings)> {
    let default = IpcSettings::default();
    vec![
        ("processes (default)", default),
        (
            "processes, not pinned",
            IpcSettings {
                one_core: false,
                ..default
            },
        ),
        (
            "processes, poll 30 us",
            IpcSettings {
                poll: Duration::from_micros(30),
                ..default
            },
        ),
    ]
}

fn main() {
    // `cargo bench` passes `--bench`; numbers are ours, and `rapier` or `mujoco` picks
    // one backend.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let nums: Vec<f64> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let rounds = nums.first().map_or(5, |&r| r as usize).max(1);
    let max_seconds = nums.get(1).copied().unwrap_or(60.0);
    let mut backends = vec![BackendKind::Rapier];
    if BackendKind::Mujoco.is_available() {
        backends.push(BackendKind::Mujoco);
    }
    backends.retain(|b| {
        !args.iter().any(|a| a == "rapier" || a == "mujoco") || args.contains(&b.to_string())
    });
    let variants = variants();
    println!("route `{ROUTE}` on playground, {max_seconds} s simulated, {rounds} rounds");
    for backend in backends {
        let spec = RunSpec {
            scene: "playground".into(),
            instructions: vec![ROUTE.into()],
            backend,
            seed: 0,
            params: Default::default(),
        };
        let n = variants.len() + 1;
        let mut timings: Vec<Vec<Timing>> = (0..n).map(|_| Vec::new()).collect();
        let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); n];
        for r in 0..rounds {
            let a = in_process(&spec, max_seconds);
            for (i, (_, settings)) in variants.iter().enumerate() {
                let run = support::run_id(&format!("bench{i}"));
                let t = processes(&spec, max_seconds, *settings, &run);
                assert_eq!(t.digest, a.digest, "round {r}: multi-process run differs");
                ratios[i + 1].push(t.wall / a.wall);
                timings[i + 1].push(t);
            }
            ratios[0].push(1.0);
            timings[0].push(a);
        }
        println!(
            "\n{backend}: medians over rounds; start-up / loop / shutdown [s]; per call median (mean) [us]"
        );
        let names = std::iter::once("in-process").chain(variants.iter().map(|v| v.0));
        for (i, name) in names.enumerate() {
            let ts = &timings[i];
            let med =
                |f: &dyn Fn(&Timing) -> f64| median(&mut ts.iter().map(f).collect::<Vec<_>>());
            let call = |k: usize| {
                format!(
                    "{:.0} ({:.0})",
                    med(&|t| t.calls[k].0) * 1e6,
                    med(&|t| t.calls[k].1) * 1e6
                )
            };
            println!(
                "  {name:<22} wall {:.3} s = {:.3} / {:.3} / {:.3}; physics {}, planner {}, controller {}; wall / in-process {:.2}x",
                med(&|t| t.wall),
                med(&|t| t.phases[0]),
                med(&|t| t.phases[1]),
                med(&|t| t.phases[2]),
                call(0),
                call(1),
                call(2),
                median(&mut ratios[i]),
            );
        }
    }
}
