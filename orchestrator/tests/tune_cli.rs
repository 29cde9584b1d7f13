//! `plamo tune` through the built binary: the crawl writes a crawl parameter file the
//! controller loads (its rollouts under a physics parameter file), and bad
//! combinations are refused by name.

mod support;

use std::process::{Command, Output};

fn plamo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plamo"))
        .arg("tune")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn tuning_the_crawl_writes_a_crawl_file_that_loads() {
    let dir = support::out_dir("tune", "crawl");
    let out = dir.join("crawl.toml");
    // The rollouts' physics from a file; the header records it.
    let physics = dir.join("physics.toml");
    std::fs::write(&physics, "friction = 0.9\n").unwrap();
    let o = plamo(&[
        "--form",
        "crawl",
        "--budget",
        "1",
        "--rollouts",
        "1",
        "--duration",
        "1",
        "--physics",
        "rapier",
        "--physics-params",
        physics.to_str().unwrap(),
        "--fall-cost",
        "5",
        // A field beyond the crawl's built-in box, searched too.
        "--search",
        "max_speed=0.9..1.3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains(" --search max_speed=0.9..1.3 "), "{text}");
    assert!(text.starts_with("# Crawl parameters"), "{text}");
    assert!(
        text.contains("plamo tune --form crawl --budget 1"),
        "{text}"
    );
    assert!(text.contains("--physics-params"), "{text}");
    assert!(text.contains("--fall-cost 5"), "{text}");
    // The run's end replaces any checkpoint with the final file and leaves no part.
    assert!(text.contains("\n# Final cost "), "{text}");
    assert!(!out.with_extension("part").exists());
    plamo_controller::CrawlParams::load(&out).unwrap();
    // Not a terminal: progress comes as one log line per generation.
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(log.contains("generation 1/1: best cost"), "{log}");
}

#[test]
fn bad_tuning_arguments_are_refused_by_name() {
    let dir = support::out_dir("tune", "bad-physics");
    let bad = dir.join("physics.toml");
    std::fs::write(&bad, "frction = 0.5\n").unwrap();
    let bad = bad.to_str().unwrap();
    let cases: [(&[&str], &str); 8] = [
        (&["--form", "hop"], "walk, run, crouch, crawl"),
        (&["--physics-params", bad, "--budget", "1"], "frction"),
        (
            &["--form", "crawl", "--start-like", "walk"],
            "start-like works",
        ),
        (&["--terrains", "ruff", "--budget", "1"], "`ruff`"),
        (
            &["--fall-cost", "-1", "--budget", "1"],
            "--fall-cost must be",
        ),
        // A misspelt field is refused before any rollout, with the fields there are.
        (
            &["--form", "crawl", "--search", "max_sped=0.7..1.4"],
            "its number fields: attitude_gain",
        ),
        (&["--search", "max_speed=0.7..1.4"], "`[walk]` section"),
        (&["--search", "step_time=0.5"], "NAME=LO..HI"),
    ];
    for (args, needle) in cases {
        let o = plamo(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    }
}

#[test]
fn a_search_in_one_engine_starts_from_that_engines_gait() {
    use plamo_controller::GaitParams;
    use plamo_physics::BackendKind;
    // A run search leaves the crouch as it found it: rapier's built-in crouch in rapier
    // alone, MuJoCo's (gait.toml) in MuJoCo alone.
    for (engine, kind) in [
        ("rapier", BackendKind::Rapier),
        ("mujoco", BackendKind::Mujoco),
    ]
    .into_iter()
    .filter(|(_, kind)| kind.is_available())
    {
        let dir = support::out_dir("tune", &format!("start-{engine}"));
        let out = dir.join("gait.toml");
        let o = plamo(&[
            "--form",
            "run",
            "--budget",
            "1",
            "--rollouts",
            "1",
            "--duration",
            "0.5",
            "--physics",
            engine,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let tuned = GaitParams::load(&out).unwrap();
        assert_eq!(tuned.crouch, GaitParams::built_in(kind).crouch, "{engine}");
    }
    assert_ne!(
        GaitParams::built_in(BackendKind::Rapier).crouch,
        GaitParams::built_in(BackendKind::Mujoco).crouch
    );
}

/// A crawl search of `budget` generations in MuJoCo priced by `tours` tours, with
/// `more` arguments, into `out`.
#[cfg(feature = "mujoco")]
fn tune_on_tours(budget: &str, tours: &str, more: &[&str], out: &std::path::Path) -> Output {
    let mut args = vec![
        "--form",
        "crawl",
        "--budget",
        budget,
        "--tours",
        tours,
        "--physics",
        "mujoco",
    ];
    args.extend_from_slice(more);
    args.extend_from_slice(&["--out", out.to_str().unwrap()]);
    plamo(&args)
}

/// A crawl search of `budget` generations in MuJoCo priced by two tours, into `out`.
#[cfg(feature = "mujoco")]
fn tune_on_two_tours(budget: &str, out: &std::path::Path) -> Output {
    tune_on_tours(budget, "2", &[], out)
}

/// `--tours`: candidates priced by whole random tours; the header names the tours, so
/// the command reproduces the file.
#[cfg(feature = "mujoco")]
#[test]
fn tuning_on_tours_writes_a_file_that_names_its_tours() {
    let dir = support::out_dir("tune", "tours");
    let out = dir.join("crawl.toml");
    let o = tune_on_two_tours("0", &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("--physics mujoco --tours 2 --tour-seed 100000 --out"),
        "{text}"
    );
    assert!(text.contains("tours with a fall"), "{text}");
    assert!(!text.contains("--terrains"), "{text}");
    plamo_controller::CrawlParams::load(&out).unwrap();

    // A search says how its result does on the next tours, which it never saw; one
    // that found nothing better than its start has nothing to hold out.
    let o = tune_on_two_tours("1", &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let tuned = plamo_controller::CrawlParams::load(&out).unwrap();
    if tuned == plamo_controller::CrawlParams::default() {
        assert!(!text.contains("Held out"), "{text}");
    } else {
        let line = text
            .lines()
            .find(|l| l.starts_with("# Held out, the next 2 tours (scene seeds "))
            .unwrap_or_else(|| panic!("no held-out line: {text}"));
        assert!(
            line.contains("start cost") && line.contains("this file"),
            "{line}"
        );
        // The search's own tours are seeds 100000.., the held-out ones come after.
        let first: u64 = line
            .split("scene seeds ")
            .nth(1)
            .and_then(|r| r.split("..").next())
            .and_then(|n| n.parse().ok())
            .unwrap();
        assert!(first > 100_000, "{line}");
    }
}

/// `--keep-tracking`: the search on tours also prices flat rollouts against its
/// start; the header says how far the file's are from the start's.
#[cfg(feature = "mujoco")]
#[test]
fn a_search_on_tours_can_keep_the_starts_tracking() {
    let dir = support::out_dir("tune", "keep-tracking");
    let out = dir.join("crawl.toml");
    let o = tune_on_tours("0", "1", &["--keep-tracking", "0.05"], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("--tours 1 --tour-seed 100000 --keep-tracking 0.05"),
        "{text}"
    );
    // The start is the file: its flat XY is the start's.
    let line = text
        .lines()
        .find(|l| l.contains("Flat rollouts' XY"))
        .unwrap_or_else(|| panic!("no tracking in the header: {text}"));
    let xy: Vec<&str> = line
        .split("XY ")
        .skip(2)
        .chain(line.split("(start ").skip(1))
        .map(|r| r.split(' ').next().unwrap())
        .collect();
    assert_eq!(xy.len(), 2, "{line}");
    assert_eq!(xy[0], xy[1], "{line}");
    assert!(xy[0].parse::<f64>().unwrap() > 0.0, "{line}");
}

#[test]
fn keep_tracking_needs_tours_and_a_length() {
    for (args, says) in [
        (
            &["--form", "crawl", "--keep-tracking", "0.05"][..],
            "--tours",
        ),
        (
            &["--form", "crawl", "--tours", "1", "--keep-tracking", "-1"][..],
            ">= 0",
        ),
    ] {
        let o = plamo(args);
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("--keep-tracking") && err.contains(says),
            "{err}"
        );
    }
}

#[test]
fn tours_and_rollout_settings_are_refused_together() {
    for (flag, value) in [
        ("--terrains", "hill"),
        ("--rollouts", "8"),
        ("--duration", "12"),
    ] {
        let o = plamo(&["--form", "crawl", "--tours", "2", flag, value]);
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("--tours") && err.contains(flag) && err.contains("cannot be used"),
            "{err}"
        );
    }
}
