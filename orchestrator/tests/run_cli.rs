//! `plamo run` end to end, through the built binary: determinism in-process vs
//! multi-process, a SIGKILLed or crashing component, a wrong tick, a killed
//! orchestrator, two concurrent runs, and no shared-memory files left behind.
//! Runs are a few simulated seconds long.

mod support;

use std::path::{Path, PathBuf};

use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};
use support::{recorded_json, run_id};

const BIN: &str = env!("CARGO_BIN_EXE_plamo");
const ROUTE: &str = "Run from the tree to the car, then crawl to the bench";

fn plamo(args: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.arg("run")
        .args(["--scene", "playground", "--quiet"])
        .args(args);
    c
}

fn out_dir(name: &str) -> support::OutDir {
    support::out_dir("run-cli", name)
}

fn run_ok(args: &[&str], out: &Path) -> Output {
    let o = plamo(args)
        .args(["--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("trajectory digest"),
        "{text}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn digest(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("trajectory digest ").map(str::to_string))
        .expect("digest line")
}

/// Files of run `run` left in iceoryx2's shared-memory and runtime directories.
fn leftovers(run: &str) -> Vec<PathBuf> {
    plamo::ipc::run_files(&plamo_interfaces::RunId::new(run).unwrap())
}

/// Pids of the component processes of run `run` (from /proc).
fn component_pids(run: &str) -> Vec<(u32, String)> {
    let mut v = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(cmd) = std::fs::read(e.path().join("cmdline")) else {
            continue;
        };
        let args: Vec<String> = cmd
            .split(|b| *b == 0)
            .map(|a| String::from_utf8_lossy(a).into_owned())
            .collect();
        if args.get(1).is_some_and(|a| a == "component")
            && args.windows(2).any(|w| w[0] == "--run" && w[1] == run)
        {
            v.push((pid, args.get(2).cloned().unwrap_or_default()));
        }
    }
    v
}

fn wait_with_deadline(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    None
}

fn sigkill(pid: u32) {
    assert!(
        Command::new("kill")
            .args(["-9", &pid.to_string()])
            .status()
            .unwrap()
            .success()
    );
}

/// Start a long multi-process run `run` (stdout/stderr as given) and wait until its
/// three component processes exist.
fn long_run_with_components(run: &str, stderr: Stdio) -> Child {
    let orch = plamo(&[
        "--instructions",
        ROUTE,
        "--max-seconds",
        "600",
        "--processes",
        "--run",
        run,
    ])
    .stdout(Stdio::null())
    .stderr(stderr)
    .spawn()
    .unwrap();
    let start = Instant::now();
    while component_pids(run).len() < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "components did not start"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    orch
}

/// Run `args` in-process and as processes (run id `run`); the digests and recorded
/// files must be identical and no file of the run left. Returns the in-process run.
fn same_in_both_modes(args: &[&str], run: &str) -> Output {
    let a = out_dir(&format!("{run}-inproc"));
    let b = out_dir(&format!("{run}-multi"));
    let oa = run_ok(args, &a);
    let mut margs = args.to_vec();
    margs.extend(["--processes", "--run", run]);
    let ob = run_ok(&margs, &b);
    assert_eq!(digest(&oa), digest(&ob));
    for f in ["trajectory.csv", "obstacles.csv", "metrics.json"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs"
        );
    }
    assert!(a.join("run.png").exists() && a.join("plans.json").exists());
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
    oa
}

#[test]
fn in_process_and_multi_process_runs_are_bit_identical() {
    let args = ["--instructions", ROUTE, "--max-seconds", "3", "--seed", "7"];
    let oa = same_in_both_modes(&args, &run_id("cli-test-det"));
    // Another seed changes the start heading, so the trajectory.
    let c = out_dir("seed");
    let oc = run_ok(
        &["--instructions", ROUTE, "--max-seconds", "3", "--seed", "8"],
        &c,
    );
    assert_ne!(digest(&oa), digest(&oc));
}

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_in_process_and_multi_process_runs_are_bit_identical() {
    let args = [
        "--instructions",
        ROUTE,
        "--physics",
        "mujoco",
        "--max-seconds",
        "3",
        "--seed",
        "7",
    ];
    same_in_both_modes(&args, &run_id("cli-test-det-mujoco"));
}

#[test]
fn two_agents_with_their_own_instructions_run_in_both_modes() {
    let run = run_id("cli-test-two");
    let a = out_dir("two-in");
    let b = out_dir("two-multi");
    let args = [
        "--agents",
        "2",
        "--instructions",
        ROUTE,
        "--instructions",
        "walk from the car to the bench",
        "--max-seconds",
        "2",
    ];
    let oa = run_ok(&args, &a);
    let mut margs = args.to_vec();
    margs.extend(["--processes", "--run", &run]);
    let ob = run_ok(&margs, &b);
    assert_eq!(digest(&oa), digest(&ob));
    let traj = std::fs::read_to_string(a.join("trajectory.csv")).unwrap();
    assert!(
        traj.lines().any(|l| l.starts_with("0,1,")),
        "agent 1 recorded"
    );
    let text = String::from_utf8_lossy(&oa.stdout);
    assert!(text.contains("agent 1"), "{text}");
    assert_eq!(leftovers(&run), Vec::<PathBuf>::new());
}

#[test]
fn a_sigkilled_component_stops_the_run_and_leaves_no_files() {
    let run = &run_id("cli-test-kill");
    let mut orch = long_run_with_components(run, Stdio::piped());
    let (physics, _) = component_pids(run)
        .into_iter()
        .find(|(_, k)| k == "physics")
        .expect("physics process");
    // Let the run go on for a while.
    std::thread::sleep(Duration::from_millis(1500));
    let killed_at = Instant::now();
    sigkill(physics);
    let status =
        wait_with_deadline(&mut orch, Duration::from_secs(30)).expect("orchestrator hangs");
    let took = killed_at.elapsed();
    let mut err = String::new();
    std::io::Read::read_to_string(orch.stderr.as_mut().unwrap(), &mut err).unwrap();
    eprintln!("orchestrator exited {took:?} after the kill: {err}");
    assert!(!status.success());
    assert!(err.contains("physics") && err.contains("died"), "{err}");
    assert!(err.contains("tick"), "{err}");
    assert_eq!(component_pids(run), vec![], "components left running");
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

/// A 2 s multi-process run of the route (run id `run`) writing into `out`, with
/// `extra` arguments.
fn short_multi_process_run(run: &str, out: &Path, extra: &[&str]) -> Command {
    let mut c = plamo(&[
        "--instructions",
        ROUTE,
        "--max-seconds",
        "2",
        "--processes",
        "--run",
        run,
        "--out",
        out.to_str().unwrap(),
    ]);
    c.args(extra);
    c
}

#[test]
fn a_reader_that_goes_away_still_gets_the_output_folder_written() {
    // `plamo run ... | head -1`, with the reader gone before the summary: the run
    // must still write its folder and stop its components, without a panic.
    let run = &run_id("cli-test-closed-stdout");
    let out = out_dir("closed-stdout");
    let mut orch = short_multi_process_run(run, &out, &[])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(orch.stdout.take());
    let status =
        wait_with_deadline(&mut orch, Duration::from_secs(120)).expect("orchestrator hangs");
    let mut err = String::new();
    std::io::Read::read_to_string(orch.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(!err.contains("panicked"), "{err}");
    // Timed out after 2 s: the route is not done, which is a failure, not a crash.
    assert_eq!(status.code(), Some(1), "{err}");
    for f in ["trajectory.csv", "metrics.json", "replay.glb"] {
        assert!(out.join(f).exists(), "{f} not written; stderr: {err}");
    }
    assert_eq!(component_pids(run), vec![], "components left running");
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

/// A 3 s multi-process run whose physics process has `fault`; it must fail. Returns
/// its stderr.
fn failing_run_with_fault(run: &str, fault: &str) -> String {
    let o = plamo(&[
        "--instructions",
        ROUTE,
        "--max-seconds",
        "3",
        "--processes",
        "--run",
        run,
        "--inject-fault",
        fault,
    ])
    .output()
    .unwrap();
    assert!(!o.status.success());
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_crashing_component_is_named_with_its_tick() {
    let run = &run_id("cli-test-crash");
    let err = failing_run_with_fault(run, "crash@40");
    assert!(
        err.contains("physics died") && err.contains("tick 40"),
        "{err}"
    );
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

#[test]
fn a_wrong_tick_is_an_error() {
    let run = &run_id("cli-test-tick");
    let err = failing_run_with_fault(run, "wrong-tick@8");
    assert!(
        err.contains("physics: expected a message for tick 12, got tick 16"),
        "{err}"
    );
    assert_eq!(component_pids(run), vec![]);
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

#[test]
fn components_exit_when_the_orchestrator_is_killed() {
    let run = &run_id("cli-test-orphan");
    let mut orch = long_run_with_components(run, Stdio::null());
    std::thread::sleep(Duration::from_millis(500));
    sigkill(orch.id());
    orch.wait().unwrap();
    let killed = Instant::now();
    while !component_pids(run).is_empty() {
        assert!(
            killed.elapsed() < Duration::from_secs(30),
            "components still running: {:?}",
            component_pids(run)
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // A new run with the same id cleans whatever the killed orchestrator left.
    let o = run_ok(
        &[
            "--instructions",
            ROUTE,
            "--max-seconds",
            "1",
            "--processes",
            "--run",
            run,
        ],
        &out_dir("orphan-after"),
    );
    assert!(!digest(&o).is_empty());
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

#[test]
fn concurrent_runs_are_isolated() {
    let spawn = |run: &str, seed: &str, out: &Path| {
        short_multi_process_run(run, out, &["--seed", seed])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (run_a, run_b) = (run_id("cli-test-conc-a"), run_id("cli-test-conc-b"));
    let (da, db) = (out_dir("conc-a"), out_dir("conc-b"));
    let a = spawn(&run_a, "1", &da);
    let b = spawn(&run_b, "2", &db);
    let oa = a.wait_with_output().unwrap();
    let ob = b.wait_with_output().unwrap();
    let ra = run_ok(
        &["--instructions", ROUTE, "--max-seconds", "2", "--seed", "1"],
        &out_dir("conc-ra"),
    );
    let rb = run_ok(
        &["--instructions", ROUTE, "--max-seconds", "2", "--seed", "2"],
        &out_dir("conc-rb"),
    );
    assert_eq!(digest(&oa), digest(&ra));
    assert_eq!(digest(&ob), digest(&rb));
    assert_ne!(digest(&oa), digest(&ob));
    assert_eq!(leftovers(&run_a), Vec::<PathBuf>::new());
    assert_eq!(leftovers(&run_b), Vec::<PathBuf>::new());
}

#[cfg(not(feature = "mujoco"))]
#[test]
fn mujoco_without_the_feature_names_the_feature() {
    let o = plamo(&["--instructions", ROUTE, "--physics", "mujoco"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("`mujoco` feature"), "{err}");
}

#[test]
fn the_next_run_removes_what_a_crashed_run_of_another_id_left() {
    let run = &run_id("cli-test-crashed");
    let after = &run_id("cli-test-after-crashed");
    let mut orch = long_run_with_components(run, Stdio::null());
    std::thread::sleep(Duration::from_millis(500));
    // The whole run dies at once (a power cut, `kill -9` of the process group):
    // nobody is left to tidy up.
    let mut pids: Vec<String> = component_pids(run)
        .iter()
        .map(|(p, _)| p.to_string())
        .collect();
    pids.push(orch.id().to_string());
    assert!(
        Command::new("kill")
            .arg("-9")
            .args(&pids)
            .status()
            .unwrap()
            .success()
    );
    orch.wait().unwrap();
    assert!(
        !leftovers(run).is_empty(),
        "the crash left nothing to clean"
    );
    let o = run_ok(
        &[
            "--instructions",
            ROUTE,
            "--max-seconds",
            "1",
            "--processes",
            "--run",
            after,
        ],
        &out_dir("after-crashed"),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("crashed run `{run}`")), "{err}");
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
    assert_eq!(leftovers(after), Vec::<PathBuf>::new());
}

/// Simulated seconds and loop wall seconds from a run's summary.
fn sim_and_loop_seconds(o: &Output) -> (f64, f64) {
    let text = String::from_utf8_lossy(&o.stdout);
    let sim = text
        .split("after ")
        .nth(1)
        .and_then(|r| r.split(" s simulated").next())
        .and_then(|v| v.parse().ok())
        .expect("simulated seconds");
    let lp = text
        .split("loop ")
        .nth(1)
        .and_then(|r| r.split(" s)").next())
        .and_then(|v| v.parse().ok())
        .expect("loop seconds");
    (sim, lp)
}

#[test]
fn realtime_pacing_changes_the_wall_clock_only() {
    let args = [
        "--instructions",
        ROUTE,
        "--max-seconds",
        "1.5",
        "--seed",
        "3",
    ];
    let (a, b) = (out_dir("paced"), out_dir("unpaced"));
    let mut paced = args.to_vec();
    paced.push("--realtime");
    let op = run_ok(&paced, &a);
    let ou = run_ok(&args, &b);
    assert_eq!(digest(&op), digest(&ou));
    for f in ["trajectory.csv", "obstacles.csv", "metrics.json"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs"
        );
    }
    let text = String::from_utf8_lossy(&op.stdout);
    assert!(
        text.contains("real time") && text.contains("late tick(s)"),
        "{text}"
    );
    // Pacing sleeps until each tick is due, so the loop cannot end before the
    // simulated time has passed on the wall clock (a bound, not a timing).
    let (sim, lp) = sim_and_loop_seconds(&op);
    assert!(
        sim >= 1.5 && lp >= sim - 1.0 / 30.0,
        "sim {sim} s, loop {lp} s"
    );
}

/// Start `plamo run --processes --attach` and read the component commands it prints;
/// the rest of its stderr is collected by a thread.
fn attach(run: &str, extra: &[&str]) -> (Child, Vec<String>, std::thread::JoinHandle<String>) {
    use std::io::BufRead;
    let mut orch = plamo(extra)
        .args(["--processes", "--attach", "--run", run])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(orch.stderr.take().unwrap()).lines();
    let mut commands = Vec::new();
    let mut head = String::new();
    while commands.len() < 3 {
        let line = lines.next().expect("orchestrator stderr ended").unwrap();
        head.push_str(&line);
        head.push('\n');
        if line.starts_with("  ") && line.contains(" component ") {
            commands.push(line.trim().to_string());
        }
    }
    assert!(head.contains(&format!("run `{run}`")), "{head}");
    let rest =
        std::thread::spawn(move || lines.map_while(Result::ok).collect::<Vec<_>>().join("\n"));
    (orch, commands, rest)
}

#[test]
fn components_started_by_hand_attach_to_the_run() {
    let run = &run_id("cli-test-attach");
    let args = ["--instructions", ROUTE, "--max-seconds", "1", "--seed", "5"];
    let (orch, commands, rest) = attach(run, &args);
    // Exactly what a user would paste into three terminals.
    let mut comps: Vec<Child> = commands
        .iter()
        .map(|c| {
            Command::new("sh")
                .args(["-c", c])
                .stdout(Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    let out = orch.wait_with_output().unwrap();
    let err = rest.join().unwrap();
    assert!(
        out.status.success() || String::from_utf8_lossy(&out.stdout).contains("digest"),
        "{err}"
    );
    for c in &mut comps {
        let s = wait_with_deadline(c, Duration::from_secs(30)).expect("component hangs");
        assert!(s.success(), "a component failed: {err}");
    }
    let inproc = run_ok(&args, &out_dir("attach-ref"));
    assert_eq!(digest(&out), digest(&inproc));
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

#[test]
fn a_component_started_for_another_run_is_refused() {
    let run = &run_id("cli-test-attach-wrong");
    let (orch, commands, rest) = attach(
        run,
        &[
            "--instructions",
            ROUTE,
            "--max-seconds",
            "1",
            "--attach-timeout",
            "30",
        ],
    );
    let physics = commands
        .iter()
        .find(|c| c.contains(" component physics "))
        .unwrap();
    // The same command with another seed: a different run.
    assert!(physics.contains(" --seed 0 "), "{physics}");
    let wrong = physics.replace(" --seed 0 ", " --seed 6 ");
    let mut comp = Command::new("sh")
        .args(["-c", &wrong])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = orch.wait_with_output().unwrap();
    let err = rest.join().unwrap();
    assert!(!out.status.success());
    assert!(
        err.contains("physics was started for another run") && err.contains("seed 6"),
        "{err}"
    );
    wait_with_deadline(&mut comp, Duration::from_secs(30)).expect("component hangs");
    assert_eq!(leftovers(run), Vec::<PathBuf>::new());
}

/// The number of times the trajectory's `fallen` column goes from 0 to 1.
fn recorded_falls(out: &Path) -> usize {
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let col = lines
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "fallen")
        .expect("a fallen column");
    let flags: Vec<bool> = lines
        .map(|l| l.split(',').nth(col).unwrap() == "1")
        .collect();
    let mut prev = false;
    flags
        .into_iter()
        .filter(|&f| {
            let rose = f && !prev;
            prev = f;
            rose
        })
        .count()
}

/// The falls the run's summary counts (metrics.json).
fn summary_falls(out: &Path) -> usize {
    recorded_json(out, "metrics.json")["agents"][0]["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["metrics"]["falls"].as_u64().unwrap() as usize)
        .sum()
}

#[test]
fn the_summary_reports_the_residual_torque_the_metrics_record() {
    let out = out_dir("torque");
    let o = run_ok(&["--instructions", ROUTE, "--max-seconds", "3"], &out);
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("agent 0 ["))
        .expect("a leg");
    // "... residual 6.3% / 23.0% m g, 11 / 40 N m"
    let (head, _) = line.rsplit_once(" N m").expect("torque in N m");
    let (_, torque) = head.rsplit_once(", ").expect("after the force");
    let (mean, peak) = torque.split_once(" / ").expect("mean / peak");
    let m = &recorded_json(&out, "metrics.json")["agents"][0]["results"][0]["metrics"];
    let recorded = |k: &str| m[k].as_f64().unwrap().round();
    assert_eq!(
        mean.parse::<f64>().unwrap(),
        recorded("residual_torque_mean"),
        "{line}"
    );
    assert_eq!(
        peak.parse::<f64>().unwrap(),
        recorded("residual_torque_peak"),
        "{line}"
    );
    assert!(recorded("residual_torque_peak") > 0.0, "{line}");
}

#[test]
fn the_trajectory_records_the_falls_the_summary_counts() {
    // Running on the stairs and gravel strips at full speed falls now and then (the
    // default `stand_step_speed` slows it there, and then it does not): the column
    // must rise exactly as often as the summary counts falls (it used to be the
    // physics component's own, laxer flag, which missed most of them).
    let params = out_dir("uncapped-params");
    let file = params.join("planner.toml");
    std::fs::write(&file, "stand_step_speed = 0.0\n").unwrap();
    let mut total = 0;
    for scene in ["terrain-stairs", "terrain-rough"] {
        let out = out_dir(scene);
        let o = Command::new(BIN)
            .args(["run", "--scene", scene, "--quiet", "--max-seconds", "12"])
            .args(["--instructions", "run from the start to the goal"])
            .arg("--planner-params")
            .arg(&file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            String::from_utf8_lossy(&o.stdout).contains("trajectory digest"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (recorded, counted) = (recorded_falls(&out), summary_falls(&out));
        assert_eq!(recorded, counted, "{scene}");
        total += counted;
    }
    assert!(total > 0, "no fall to record: pick a harder ground");
    eprintln!("{total} falls recorded and counted");
}

/// The short route run with `flag file`, bit-identical in-process and as processes
/// (`run` names its shared memory), and the same run built in (into `built_in`);
/// the file must change the trajectory. Returns the run with the file.
fn file_drives_the_run(flag: &str, file: &Path, run: &str, built_in: &Path) -> Output {
    let base = ["--instructions", ROUTE, "--max-seconds", "3", "--seed", "7"];
    let mut args = base.to_vec();
    args.extend([flag, file.to_str().unwrap()]);
    let with_file = same_in_both_modes(&args, run);
    let without = run_ok(&base, built_in);
    assert_ne!(
        digest(&with_file),
        digest(&without),
        "{flag}: the file changed nothing"
    );
    with_file
}

/// The standard error of a run refused for `flag path`, which must name the file.
fn refused(flag: &str, path: &Path) -> String {
    let o = plamo(&["--instructions", ROUTE, "--max-seconds", "1"])
        .args([flag, path.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{flag} {} was taken", path.display());
    assert!(err.contains(path.to_str().unwrap()), "{err}");
    err
}

#[test]
fn parameter_files_from_tune_drive_the_controller_in_both_modes() {
    // A gait file like `plamo tune` writes, with a slower run cadence.
    let dir = out_dir("params");
    let mut gait = plamo_controller::GaitParams::default();
    gait.run.step_time += 0.03;
    gait.walk.step_time += 0.03;
    let file = dir.join("gait.toml");
    std::fs::write(&file, plamo_controller::to_toml(&gait, "test").unwrap()).unwrap();
    file_drives_the_run(
        "--gait-params",
        &file,
        &run_id("cli-test-params"),
        &out_dir("params-built-in"),
    );
    // A file that is not there, or not a crawl file, is named.
    for path in [dir.join("missing.toml"), file.clone()] {
        refused("--crawl-params", &path);
    }
}

#[test]
fn a_physics_parameter_file_drives_the_physics_in_both_modes() {
    let dir = out_dir("physics-params");
    let file = dir.join("physics.toml");
    // Stiffer feet and less grip than the defaults (11 Hz, 1.0).
    std::fs::write(&file, "rapier_contact_hz = 30.0\nfriction = 0.8\n").unwrap();
    file_drives_the_run(
        "--physics-params",
        &file,
        &run_id("cli-test-physics-params"),
        &out_dir("physics-params-built-in"),
    );
    // A misspelt field, a value out of range, a file that is not there: each named.
    let typo = dir.join("typo.toml");
    std::fs::write(&typo, "frction = 0.8\n").unwrap();
    let range = dir.join("range.toml");
    std::fs::write(&range, "rapier_solver_iterations = 0\n").unwrap();
    let missing = dir.join("missing.toml");
    for (path, needle) in [
        (&typo, "frction"),
        (&range, "rapier_solver_iterations"),
        (&missing, "missing.toml"),
    ] {
        let err = refused("--physics-params", path);
        for n in [needle, "physics parameter file"] {
            assert!(err.contains(n), "`{n}` not in {err}");
        }
    }
}

/// `plamo plan` writes the plan and its pictures, from the built-in settings or a
/// `--planner-params` file (which shows in the plan), and names a bad file.
#[test]
fn plamo_plan_writes_the_plan_with_a_planner_parameter_file() {
    let plan = |out: &Path, extra: &[&str]| {
        Command::new(BIN)
            .args(["plan", "--scene", "playground", "--instructions", ROUTE])
            .args(["--out", out.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap()
    };
    let top_speed = |out: &Path| {
        let v = recorded_json(out, "plan.json");
        v["route"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|leg| leg["points"].as_array().unwrap().iter())
            .map(|p| p["v"].as_f64().unwrap())
            .fold(0.0, f64::max)
    };
    let dir = out_dir("plan-params");
    let file = dir.join("planner.toml");
    std::fs::write(&file, "run_speed = 1.2\n").unwrap();
    let (built_in, slow) = (dir.join("built-in"), dir.join("slow"));
    for (out, extra) in [
        (&built_in, vec![]),
        (&slow, vec!["--planner-params", file.to_str().unwrap()]),
    ] {
        let o = plan(out, &extra);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for f in ["plan.json", "plan.png", "profile.png"] {
            assert!(out.join(f).is_file(), "{f} not written");
        }
    }
    let (v_built_in, v_slow) = (top_speed(&built_in), top_speed(&slow));
    assert!(
        v_slow <= 1.2 + 1e-9 && v_built_in > 1.5,
        "top speed {v_slow} with run_speed = 1.2, {v_built_in} built in"
    );
    std::fs::write(&file, "run_sped = 1.2\n").unwrap();
    let o = plan(
        &dir.join("bad"),
        &["--planner-params", file.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    for n in ["run_sped", "planner parameter file", file.to_str().unwrap()] {
        assert!(err.contains(n), "`{n}` not in {err}");
    }
}

/// The fastest planned speed in a run's `plans.json` \[m/s\].
fn planned_top_speed(out: &Path) -> f64 {
    recorded_json(out, "plans.json")["initial"][0]["route"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|leg| leg["points"].as_array().unwrap().iter())
        .map(|p| p["v"].as_f64().unwrap())
        .fold(0.0, f64::max)
}

#[test]
fn a_planner_parameter_file_drives_the_planner_in_both_modes() {
    let dir = out_dir("planner-params");
    let file = dir.join("planner.toml");
    // Slower than the run leg plans by default (1.64 m/s: a_min caps it on 13 m).
    std::fs::write(&file, "run_speed = 1.2\n").unwrap();
    let built_in_dir = out_dir("planner-params-built-in");
    file_drives_the_run(
        "--planner-params",
        &file,
        &run_id("cli-test-planner-params"),
        &built_in_dir,
    );
    let slow_dir = out_dir("planner-params-slow");
    let base = ["--instructions", ROUTE, "--max-seconds", "3", "--seed", "7"];
    let mut args = base.to_vec();
    args.extend(["--planner-params", file.to_str().unwrap()]);
    run_ok(&args, &slow_dir);
    let (v_slow, v_default) = (
        planned_top_speed(&slow_dir),
        planned_top_speed(&built_in_dir),
    );
    assert!(
        v_slow <= 1.2 + 1e-9 && v_default > 1.5,
        "{v_slow} {v_default}"
    );
    // A misspelt field and a value out of range are named with the file.
    for (text, names) in [
        ("run_sped = 1.2\n", ["run_sped", "run_speed"]),
        ("run_speed = -1.0\n", ["run_speed", "> 0"]),
    ] {
        std::fs::write(&file, text).unwrap();
        let err = refused("--planner-params", &file);
        for n in names {
            assert!(err.contains(n), "`{n}` not in: {err}");
        }
    }
}

/// Under rapier the built-in gait is `gait-rapier.toml`, not MuJoCo's `gait.toml`: the
/// run with no file equals the run with the rapier file and differs from MuJoCo's.
#[test]
fn rapier_runs_on_its_own_built_in_gait_file() {
    let params = Path::new(env!("CARGO_MANIFEST_DIR")).join("../components/controller/params");
    let base = [
        "--instructions",
        ROUTE,
        "--max-seconds",
        "3",
        "--seed",
        "7",
        "--physics",
        "rapier",
    ];
    let run = |name: &str, file: Option<&str>| {
        let mut args = base.to_vec();
        let path = file.map(|f| params.join(f));
        if let Some(p) = &path {
            args.extend(["--gait-params", p.to_str().unwrap()]);
        }
        digest(&run_ok(&args, &out_dir(name)))
    };
    let built_in = run("gait-built-in-rapier", None);
    assert_eq!(built_in, run("gait-rapier-file", Some("gait-rapier.toml")));
    assert_ne!(built_in, run("gait-mujoco-file", Some("gait.toml")));
}
