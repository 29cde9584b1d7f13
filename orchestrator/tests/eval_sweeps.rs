//! `plamo eval slalom | pyramid | random | dynamic | merge` on tiny sweeps (rapier,
//! a couple of simulated seconds per run): results do not depend on the thread
//! count, shards merge into the very same files as the whole sweep, every output
//! file exists and parses, and bad arguments get clear errors.

mod support;

use std::path::Path;
use std::process::Command;

use plamo::eval::dynamic::Dynamic;
use plamo::eval::pyramid::Pyramid;
use plamo::eval::random::RandomScenes;
use plamo::eval::slalom::{QpConfig, Slalom};
use plamo::eval::{self, ControllerParams, Experiment, RunOptions, Shard, Table};
use plamo_controller::{CrawlParams, GaitParams};
use plamo_physics::{BackendKind, PhysicsSettings};

fn tmp(name: &str) -> support::OutDir {
    support::out_dir("eval", name)
}

fn opts(out: &Path, threads: usize, shard: Shard) -> RunOptions {
    RunOptions {
        physics: BackendKind::Rapier,
        out: out.to_path_buf(),
        shard,
        threads,
        max_seconds: Some(1.0),
        quiet: true,
        planner: None,
        controller: Default::default(),
        physics_settings: None,
    }
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

fn tiny_slalom() -> Slalom {
    Slalom::new(
        2,
        7,
        vec![1.0],
        vec![QpConfig {
            v_max: 2.0,
            a_lat: 2.0,
            a_max: 1.0,
            a_min: -1.0,
        }],
    )
    .unwrap()
}

/// Whole sweep on 1 and on 2 threads, and as 2 shards merged: identical folders.
fn check_sweep<E: Experiment>(e: &E, expect: &[&str]) {
    let one = tmp(&format!("{}-1", E::NAME));
    let two = tmp(&format!("{}-2", E::NAME));
    eval::run(e, &opts(&one, 1, Shard::ALL)).unwrap();
    eval::run(e, &opts(&two, 2, Shard::ALL)).unwrap();
    let a = files(&one);
    assert_eq!(
        a,
        files(&two),
        "{}: results depend on the thread count",
        E::NAME
    );
    let names: Vec<&str> = a.iter().map(|(n, _)| n.as_str()).collect();
    for f in expect {
        assert!(names.contains(f), "{}: {f} missing from {names:?}", E::NAME);
    }
    // Everything parses: the run table has one row per job, the summary is a table.
    let runs = read_runs(&one);
    assert_eq!(runs.rows.len(), e.jobs().unwrap().len());
    let summary = std::fs::read_to_string(one.join("summary.csv")).unwrap();
    assert!(Table::parse(&summary, "summary").unwrap().rows.len() >= 2);
    let meta: eval::Meta =
        serde_json::from_str(&std::fs::read_to_string(one.join("eval.json")).unwrap()).unwrap();
    assert_eq!(meta.experiment, E::NAME);
    for (n, bytes) in &a {
        if n.ends_with(".png") {
            assert!(bytes.starts_with(b"\x89PNG") && bytes.len() > 5000, "{n}");
        }
    }

    let s1 = tmp(&format!("{}-s1", E::NAME));
    let s2 = tmp(&format!("{}-s2", E::NAME));
    let merged = tmp(&format!("{}-m", E::NAME));
    eval::run(e, &opts(&s2, 1, "2/2".parse().unwrap())).unwrap();
    eval::run(e, &opts(&s1, 1, "1/2".parse().unwrap())).unwrap();
    // A missing shard is refused by name.
    let err = eval::merge(&[s1.to_path_buf()], &merged).unwrap_err();
    assert!(err.to_string().contains("shard 2/2 is missing"), "{err}");
    eval::merge(&[s2.to_path_buf(), s1.to_path_buf()], &merged).unwrap();
    assert_eq!(
        a,
        files(&merged),
        "{}: merged shards differ from the whole sweep",
        E::NAME
    );
}

#[test]
fn slalom_is_deterministic_and_merges() {
    check_sweep(
        &tiny_slalom(),
        &[
            "eval.json",
            "runs.csv",
            "summary.csv",
            "slalom.md",
            "slalom_failure.png",
            "slalom_error.png",
            "slalom_paths.png",
        ],
    );
}

#[test]
fn pyramid_random_dynamic_are_deterministic_and_merge() {
    check_sweep(
        &Pyramid::new(1, 0, vec![0.0, 4.0]).unwrap(),
        &["pyramid.md", "pyramid.png", "summary.csv"],
    );
    check_sweep(
        &RandomScenes::new(3, 11, &[]).unwrap(),
        &["random.md", "random.png", "summary.csv"],
    );
    check_sweep(
        &Dynamic::new(1, 3).unwrap(),
        &[
            "dynamic.md",
            "dynamic.png",
            "dynamic_map.png",
            "summary.csv",
        ],
    );
}

/// The random sweep of 3 scenes from seed 11 (rapier, 1 s each), in `tmp(name)`.
fn random_sweep(name: &str) -> support::OutDir {
    let out = tmp(name);
    eval::run(
        &RandomScenes::new(3, 11, &[]).unwrap(),
        &opts(&out, 1, Shard::ALL),
    )
    .unwrap();
    out
}

/// `--seeds` runs the tours it names, in its order, each exactly as in the sweep of
/// consecutive seeds that holds it (a bench of lost tours replays them).
#[test]
fn a_sweep_over_listed_seeds_runs_those_tours_as_the_full_sweep_does() {
    let full = random_sweep("seeds-full");
    let listed = tmp("seeds-listed");
    let bench = RandomScenes::new(50, 0, &[])
        .unwrap()
        .with_seeds(&[13, 11])
        .unwrap();
    eval::run(&bench, &opts(&listed, 1, Shard::ALL)).unwrap();
    let (a, b) = (read_runs(&full), read_runs(&listed));
    assert_eq!(b.rows.len(), 2);
    // Every column but the first, the job's index in its sweep.
    for (rb, ra) in [(0, 2), (1, 0)] {
        assert_eq!(
            b.rows[rb][1..],
            a.rows[ra][1..],
            "seed {}",
            a.str(ra, "scene_seed").unwrap()
        );
    }
    let md = std::fs::read_to_string(listed.join("random.md")).unwrap();
    assert!(md.contains("--seeds 13,11 "), "{md}");
    assert!(md.contains("2 random scenes (seeds 13, 11)"), "{md}");
    for (seeds, needle) in [
        (&[][..], "at least one seed"),
        (&[4, 9, 4][..], "seed 4 given twice"),
    ] {
        let err = RandomScenes::new(1, 0, &[])
            .unwrap()
            .with_seeds(seeds)
            .unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
    }
}

#[test]
fn merge_refuses_shards_of_different_sweeps() {
    let a = tmp("diff-a");
    let b = tmp("diff-b");
    eval::run(&tiny_slalom(), &opts(&a, 1, "1/2".parse().unwrap())).unwrap();
    let other = Slalom::new(1, 7, vec![1.0], vec![]).unwrap();
    eval::run(&other, &opts(&b, 1, "2/2".parse().unwrap())).unwrap();
    let err = eval::merge(&[a.to_path_buf(), b.to_path_buf()], &tmp("diff-m")).unwrap_err();
    assert!(err.to_string().contains("different sweep"), "{err}");
}

fn plamo(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_plamo"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_arguments_are_refused_by_name() {
    let cases: [(&[&str], &str); 9] = [
        (&["eval", "slalom", "--shard", "3/2"], "1 <= i <= n"),
        (&["eval", "slalom", "--qp", "1:2"], "V_MAX:A_LAT:A_MAX"),
        (&["eval", "slalom", "--qp", "2:1:1:0.5"], "A_MIN"),
        (&["eval", "slalom", "--runs", "0"], "--runs 0"),
        (&["eval", "random", "--scenes", "0"], "--scenes 0"),
        (&["eval", "random", "--seeds", "3,3"], "seed 3 given twice"),
        (&["eval", "random", "--seeds", "3", "--seed", "4"], "--seed"),
        (&["eval", "pyramid", "--c=-1"], "terrain preference"),
        (&["eval", "dynamic", "--physics", "bullet"], "bullet"),
    ];
    for (args, needle) in cases {
        let (ok, err) = plamo(args);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    }
    let (ok, err) = plamo(&["eval", "merge", "--out", "/tmp/x", "/nonexistent-shard"]);
    assert!(!ok && err.contains("eval.json"), "{err}");
    let (ok, err) = plamo(&[
        "eval",
        "slalom",
        "--max-seconds=-1",
        "--out",
        "/tmp/plamo-eval-x",
    ]);
    assert!(!ok && err.contains("--max-seconds"), "{err}");
    // Controller parameter files: a value out of range, a gait file given as crawl.
    let dir = tmp("bad-params");
    std::fs::create_dir_all(&dir).unwrap();
    let fast = dir.join("fast-crawl.toml");
    std::fs::write(
        &fast,
        plamo_controller::DEFAULT_CRAWL_PARAMS
            .lines()
            .map(|l| {
                if l.starts_with("max_speed") {
                    "max_speed = 99.0"
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n"),
    )
    .unwrap();
    let gait = dir.join("gait.toml");
    std::fs::write(&gait, plamo_controller::DEFAULT_GAIT_PARAMS).unwrap();
    // The same files for the sweeps and for the Table 2 protocol.
    for eval in ["random", "locomotion"] {
        for (flag, file, needle) in [
            ("--crawl-params", &fast, "max_speed"),
            ("--crawl-params", &gait, "unknown field"),
        ] {
            let (ok, err) = plamo(&["eval", eval, flag, file.to_str().unwrap()]);
            assert!(!ok, "{eval} {flag} {} succeeded", file.display());
            for n in [needle, "crawl parameter file", file.to_str().unwrap()] {
                assert!(err.contains(n), "{eval}: `{n}` not in {err}");
            }
        }
        let (ok, err) = plamo(&["eval", eval, "--physics-params", gait.to_str().unwrap()]);
        assert!(!ok, "{eval} --physics-params {} succeeded", gait.display());
        for n in [
            "physics parameter file",
            "unknown field",
            gait.to_str().unwrap(),
        ] {
            assert!(err.contains(n), "{eval}: `{n}` not in {err}");
        }
    }
}

/// random.md's replay command, run as written, retraces the eval's tour bit for bit,
/// with the built-in parameters, with a `--planner-params` file and with
/// `--gait-params` and `--crawl-params` files, and with a `--physics-params` file.
#[test]
fn a_random_tour_replays_with_plamo_run() {
    // Twice the paper's a_max: the plan speeds up faster from the first step.
    let brisk = plamo_planner::PlannerSettings {
        a_max: 1.0,
        ..Default::default()
    };
    // A slower crawl, and the built-in biped written out as a file.
    let slow_crawl = ControllerParams {
        gait: Some(GaitParams::default()),
        crawl: Some(CrawlParams {
            max_speed: 0.4,
            ..Default::default()
        }),
    };
    // Stiffer contacts than the default 11 Hz.
    let stiff = PhysicsSettings {
        rapier_contact_hz: 30.0,
        ..Default::default()
    };
    let mut digests = Vec::new();
    for (name, planner, controller, physics_settings) in [
        ("replay", None, ControllerParams::default(), None),
        (
            "replay-brisk",
            Some(brisk),
            ControllerParams::default(),
            None,
        ),
        ("replay-slow-crawl", None, slow_crawl, None),
        (
            "replay-stiff",
            None,
            ControllerParams::default(),
            Some(stiff),
        ),
    ] {
        let out = tmp(name);
        // Past the get-down that starts this crawl tour, where the plans differ.
        let o = RunOptions {
            planner,
            controller,
            physics_settings,
            max_seconds: Some(4.0),
            ..opts(&out, 1, Shard::ALL)
        };
        eval::run(&RandomScenes::new(1, 11, &[]).unwrap(), &o).unwrap();
        let runs = read_runs(&out);
        let digest = runs.str(0, "digest").unwrap().to_string();
        let line = replay_line(&out, "random.md", "plamo run --scene random-11 ");
        for (flag, given) in [
            ("--planner-params", o.planner.is_some()),
            ("--gait-params", o.controller.gait.is_some()),
            ("--crawl-params", o.controller.crawl.is_some()),
            ("--physics-params", o.physics_settings.is_some()),
        ] {
            assert_eq!(line.contains(flag), given, "{flag}: {line}");
        }
        let dir = tmp(&format!("{name}-run"));
        assert_replays(&line, None, &dir, &digest);
        digests.push(digest);
    }
    assert_ne!(digests[0], digests[1], "the planner file changed nothing");
    assert_ne!(digests[0], digests[2], "the crawl file changed nothing");
    assert_ne!(digests[0], digests[3], "the physics file changed nothing");
}

/// dynamic.md's replay command, run in the eval's folder as written, retraces the
/// re-planned run bit for bit: the corridor scene and the sweep's planner settings
/// (its walking speed and the `--planner-params` file's fields) come as files.
#[test]
fn a_dynamic_run_replays_with_plamo_run() {
    let out = tmp("dynamic-replay");
    let o = RunOptions {
        planner: Some(plamo_planner::PlannerSettings {
            obstacle_margin: 0.35,
            ..Default::default()
        }),
        max_seconds: Some(3.0),
        ..opts(&out, 1, Shard::ALL)
    };
    eval::run(&Dynamic::new(1, 3).unwrap(), &o).unwrap();
    let runs = read_runs(&out);
    let row = (0..runs.rows.len())
        .find(|&r| runs.flag(r, "replanning").unwrap())
        .unwrap();
    let digest = runs.str(row, "digest").unwrap().to_string();
    let line = replay_line(&out, "dynamic.md", "plamo run --scene crossing-3.toml ");
    let planner = std::fs::read_to_string(out.join("planner-replanning.toml")).unwrap();
    for field in ["walk_speed = 1.5", "obstacle_margin = 0.35"] {
        assert!(planner.contains(field), "{field} not in\n{planner}");
    }
    assert_replays(&line, Some(&out), &out.join("replayed"), &digest);
}

fn read_runs(out: &Path) -> Table {
    Table::parse(
        &std::fs::read_to_string(out.join("runs.csv")).unwrap(),
        "runs",
    )
    .unwrap()
}

/// The line of `out`'s summary `md` that starts with `start` (a replay command).
fn replay_line(out: &Path, md: &str, start: &str) -> String {
    let text = std::fs::read_to_string(out.join(md)).unwrap();
    text.lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no replay command in\n{text}"))
        .to_string()
}

/// Run a summary's replay command as written (in `cwd`, if given), writing to `dir`
/// instead of its `--out`, and check it prints the eval's trajectory `digest`.
fn assert_replays(line: &str, cwd: Option<&Path>, dir: &Path, digest: &str) {
    let run = line
        .replacen("plamo", env!("CARGO_BIN_EXE_plamo"), 1)
        .split(" --out ")
        .next()
        .unwrap()
        .to_string();
    let cd = cwd.map_or(String::new(), |d| format!("cd {} && ", d.display()));
    let cmd = format!("{cd}{run} --quiet --out {}", dir.display());
    let o = Command::new("sh").args(["-c", &cmd]).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!("trajectory digest {digest}")),
        "{cmd}\n{text}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A copy of sweep folder `from` in `to` whose row `row` has outcome `cause`.
fn with_cause(from: &Path, to: &Path, row: usize, cause: &str) {
    std::fs::create_dir_all(to).unwrap();
    for (name, bytes) in files(from) {
        std::fs::write(to.join(name), bytes).unwrap();
    }
    let mut runs = read_runs(from);
    let c = runs.col("cause").unwrap();
    runs.rows[row][c] = cause.into();
    std::fs::write(to.join("runs.csv"), runs.to_csv()).unwrap();
}

#[test]
fn compare_pairs_two_random_sweeps_tour_by_tour() {
    let base = random_sweep("cmp-base");
    let runs = read_runs(&base);
    let seed = |r: usize| runs.str(r, "scene_seed").unwrap().to_string();
    // Runs of 1 s reach no landmark: no tour succeeds. Mark one a success in a copy.
    assert!((0..3).all(|r| runs.str(r, "cause").unwrap() != "success"));
    let won = tmp("cmp-won");
    with_cause(&base, &won, 1, "success");
    let md = eval::compare::compare(&base, &won, None).unwrap();
    assert!(md.contains("3 tours paired"), "{md}");
    assert!(md.contains("Gained 1 ") && md.contains("lost 0,"), "{md}");
    assert!(md.contains(&format!("Gained seeds: {}.", seed(1))), "{md}");
    assert!(
        md.contains("Identical trajectories (digest): 3 of 3"),
        "{md}"
    );
    // The other way round the tour is lost; the exact test of 1 discordant tour is 1.
    let md = eval::compare::compare(&won, &base, None).unwrap();
    assert!(md.contains("Gained 0 ") && md.contains("lost 1,"), "{md}");
    assert!(md.contains("p = 1.000"), "{md}");

    // A tour lost to a fall while the body was getting up on a walk leg: counted by
    // the plan's form and the body's state.
    let fell = tmp("cmp-fell");
    with_cause(&base, &fell, 1, "fall");
    let mut runs = read_runs(&fell);
    let (sites, bodies) = (
        runs.col("fall_sites").unwrap(),
        runs.col("fall_bodies").unwrap(),
    );
    runs.rows[1][sites] = "walk@flat;run@slope".into();
    runs.rows[1][bodies] = "rising;upright".into();
    std::fs::write(fell.join("runs.csv"), runs.to_csv()).unwrap();
    let md = eval::compare::compare(&base, &fell, None).unwrap();
    let after = md
        .split("what the body was doing before the first fall")
        .nth(1)
        .unwrap_or_else(|| panic!("no body-state table in\n{md}"));
    let walk = after.lines().find(|l| l.starts_with("| walk |")).unwrap();
    assert_eq!(
        walk, "| walk | 0 -> 0 | 0 -> 1 | 0 -> 0 | 0 -> 0 | 0 -> 0 |",
        "{md}"
    );

    // The command line writes compare.md.
    let out = tmp("cmp-out");
    let o = Command::new(env!("CARGO_BIN_EXE_plamo"))
        .args(["eval", "compare"])
        .args([base.as_os_str(), won.as_os_str()])
        .arg("--out")
        .arg(out.as_os_str())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(written.contains("Gained 1 "), "{written}");

    // Tours that are not the same tour, other experiments and disjoint seeds: refused
    // by name.
    let crawls = tmp("cmp-crawl");
    let crawl_only = RandomScenes::new(3, 11, &["crawl".to_string()]).unwrap();
    eval::run(&crawl_only, &opts(&crawls, 1, Shard::ALL)).unwrap();
    let err = eval::compare::compare(&base, &crawls, None).unwrap_err();
    assert!(err.to_string().contains("--forms"), "{err}");
    let later = tmp("cmp-later");
    eval::run(
        &RandomScenes::new(2, 40, &[]).unwrap(),
        &opts(&later, 1, Shard::ALL),
    )
    .unwrap();
    let err = eval::compare::compare(&base, &later, None).unwrap_err();
    assert!(err.to_string().contains("share no scene seed"), "{err}");
    let slalom = tmp("cmp-slalom");
    eval::run(&tiny_slalom(), &opts(&slalom, 1, Shard::ALL)).unwrap();
    let err = eval::compare::compare(&base, &slalom, None).unwrap_err();
    assert!(
        err.to_string().contains("compare pairs `random` sweeps"),
        "{err}"
    );
}

/// `plamo eval locomotion` splits each cell's XY-err into its lag along the path and its
/// drift across it: neither part exceeds the whole, and a crawl that starts standing
/// (1.5 s to get down behind a plan already moving) lags its plan on the route.
#[test]
fn the_locomotion_table_splits_xy_error_into_lag_and_drift() {
    let out = tmp("locomotion-split");
    let dir = out.to_str().unwrap();
    let (ok, err) = plamo(&[
        "eval",
        "locomotion",
        "--runs",
        "1",
        "--duration",
        "3",
        "--quiet",
        "--out",
        dir,
    ]);
    assert!(ok, "{err}");
    let md = std::fs::read_to_string(out.join("locomotion.md")).unwrap();
    assert!(md.contains("lag (along the path"), "{md}");
    let cells: Vec<Vec<serde_json::Value>> =
        serde_json::from_str(&std::fs::read_to_string(out.join("locomotion.json")).unwrap())
            .unwrap();
    for (t, row) in cells.iter().enumerate() {
        for (f, c) in row.iter().enumerate() {
            let get = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k} in {c}"));
            let (xy, lag, cross) = (get("xy"), get("lag"), get("cross_track"));
            assert!(
                lag.abs() <= xy + 1e-9 && (0.0..=xy + 1e-9).contains(&cross),
                "terrain {t} form {f}: xy {xy} lag {lag} cross {cross}"
            );
        }
    }
    let crawl_flat = &cells[0][0];
    let lag = crawl_flat["lag"].as_f64().unwrap();
    let cross = crawl_flat["cross_track"].as_f64().unwrap();
    assert!(
        lag > 0.3 && cross < lag,
        "crawl on flat ground: lag {lag}, cross {cross}"
    );
}
