//! `plamo eval random` (paper 5.4, "Randomized scenes": 81% of random 4-landmark
//! scenes fully solved): seeded random scenes (`plamo scenes random --seed N`), each
//! with a random tour through its four landmarks in random locomotion forms (crawl,
//! crouch-walk, walk, run). Success: all four landmarks reached without a fall. The
//! success rate comes with a 95% Wilson interval; failures are put down to one cause:
//! planning (no route at the start, or the planner found the rest infeasible), a
//! component error, a fall, a collision (a wall, ceiling or moving obstacle touched
//! and the tour not finished), else a timeout.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use anyhow::bail;
use plamo_scenes::Scene;
use plotters::style::RGBColor;
use serde::{Deserialize, Serialize};

use super::body_state::{BodyState, DOWN_BELOW, EARLIER, LATER, RISEN_WITHIN};
use super::episode::{EpisodeSpec, TIME_LIMIT_EXTRA, TIME_LIMIT_FACTOR, run_episode, verb};
use super::fall_posture::{FallPosture, PELVIS_UP, ROLLED_FROM, STEP_UNDER_HEAD};
use super::ground::GroundKind;
use super::plot::{Bar, bars};
use super::table::field;
use super::{Experiment, Meta, RunOptions, Table, command_line, mean, wilson};
use crate::seeds::splitmix;
use crate::spec::default_time_limit;

/// The four locomotion forms, as instruction verbs.
pub const FORMS: [&str; 4] = ["crawl", "crouch-walk", "walk", "run"];

/// z of the 95% Wilson interval.
pub const Z95: f64 = 1.96;

/// Failure causes in the order they are assigned.
pub const CAUSES: [&str; 6] = [
    "success",
    "planning",
    "error",
    "fall",
    "collision",
    "timeout",
];

/// The random-scene sweep's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomScenes {
    /// Number of scenes.
    pub scenes: usize,
    /// Seed of the first scene (scene k is random scene seed + k).
    pub seed: u64,
    /// The forms a leg is drawn from, each as likely (default: all of [`FORMS`]).
    /// Fewer forms measure one form over many legs (`--forms crawl`: every leg
    /// crawls); with all four the tours are the paper's.
    #[serde(default = "default_forms")]
    pub forms: Vec<String>,
    /// The scene seeds, when given one by one (`--seeds`) rather than as `scenes`
    /// consecutive seeds from `seed`: the tours a sweep lost, say, run again as a
    /// bench. Empty: `seed`..`seed + scenes`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub seeds: Vec<u64>,
}

fn default_forms() -> Vec<String> {
    FORMS.iter().map(|f| f.to_string()).collect()
}

impl RandomScenes {
    /// Check the parameters: at least one scene, and forms from [`FORMS`], each once
    /// (none given: all four).
    pub fn new(scenes: usize, seed: u64, forms: &[String]) -> anyhow::Result<Self> {
        if scenes == 0 {
            bail!("--scenes 0: need at least one scene");
        }
        for (i, f) in forms.iter().enumerate() {
            if !FORMS.contains(&f.as_str()) {
                bail!(
                    "--forms: unknown form `{f}` (allowed: {})",
                    FORMS.join(", ")
                );
            }
            if forms[..i].contains(f) {
                bail!("--forms: `{f}` given twice");
            }
        }
        let forms = if forms.is_empty() {
            default_forms()
        } else {
            forms.to_vec()
        };
        Ok(Self {
            scenes,
            seed,
            forms,
            seeds: Vec::new(),
        })
    }

    /// The same sweep over the scene seeds `seeds`, each once, in the order given;
    /// `scenes` and `seed` then count them and name the first, as the folder's
    /// eval.json shows them.
    pub fn with_seeds(self, seeds: &[u64]) -> anyhow::Result<Self> {
        let Some(&first) = seeds.first() else {
            bail!("--seeds: need at least one seed");
        };
        if let Some(i) = (1..seeds.len()).find(|&i| seeds[..i].contains(&seeds[i])) {
            bail!("--seeds: seed {} given twice", seeds[i]);
        }
        Ok(Self {
            scenes: seeds.len(),
            seed: first,
            seeds: seeds.to_vec(),
            ..self
        })
    }

    /// Whether the legs are drawn from all four forms (the paper's tours).
    fn draws_all_forms(&self) -> bool {
        self.forms == default_forms()
    }
}

/// The tour of random scene `scene_seed`: its landmarks in a random order, each leg in
/// a form drawn from `forms` ("Crawl from the tree to the car, then run to the bench,
/// ..."). With [`FORMS`] the tour is the paper's; the draws do not depend on the forms
/// other than through their number.
pub fn tour<S: AsRef<str>>(scene: &Scene, scene_seed: u64, forms: &[S]) -> anyhow::Result<String> {
    if forms.is_empty() {
        bail!("a tour needs at least one form");
    }
    let mut names: Vec<&str> = scene.landmarks.iter().map(|l| l.name.as_str()).collect();
    if names.len() < 2 {
        bail!(
            "scene `{}` has {} landmarks, a tour needs 2",
            scene.name,
            names.len()
        );
    }
    let mut st = scene_seed ^ 0x746f_7572; // "tour": a stream apart from the scene's
    for i in (1..names.len()).rev() {
        let k = (splitmix(&mut st) % (i as u64 + 1)) as usize;
        names.swap(i, k);
    }
    let mut form = || forms[(splitmix(&mut st) % forms.len() as u64) as usize].as_ref();
    let mut text = format!("{} from the {} to the {}", form(), names[0], names[1]);
    for n in &names[2..] {
        text.push_str(&format!(", then {} to the {n}", form()));
    }
    let mut c = text.chars();
    Ok(c.next()
        .map_or(String::new(), |f| f.to_uppercase().chain(c).collect()))
}

/// How to watch one tour again: `plamo run` on the scene by its name, with the tour's
/// instructions, seed and time limit, gives the same trajectory as the eval's run.
fn replay_note(runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
    let Some(r) =
        (0..runs.rows.len()).find(|&r| runs.str(r, "cause").is_ok_and(|c| c != "success"))
    else {
        return Ok(String::new());
    };
    let seed = runs.str(r, "scene_seed")?;
    let limit = match meta.max_seconds {
        Some(m) => m,
        None => default_time_limit(runs.f64(r, "planned_time")?),
    };
    let params = meta.param_flags(out);
    Ok(format!(
        "\n\nEvery tour replays exactly, with its trajectory, plots and replay files, as \
         `plamo run --scene random-<scene_seed> --instructions \"<instructions>\" --physics \
         {physics} --seed <scene_seed> --max-seconds <limit> --out <folder>` (its trajectory \
         digest is runs.csv's `digest`), where the time limit is {TIME_LIMIT_FACTOR} x the planned time + {TIME_LIMIT_EXTRA} s unless \
         `--max-seconds` was given. The first tour that failed ({cause}):\n\n\
         ```\nplamo run --scene random-{seed} --instructions \"{text}\" --physics {physics} \
         --seed {seed} --max-seconds {limit}{params} --out random-{seed}\n```\n",
        physics = meta.physics,
        cause = runs.str(r, "cause")?,
        text = runs.str(r, "instructions")?,
    ))
}

/// Row `r`'s `;`-separated list in column `col` (`fall_sites`, `fall_postures`).
fn fall_list<'a>(runs: &'a Table, r: usize, col: &str) -> anyhow::Result<Vec<&'a str>> {
    Ok(runs
        .str(r, col)?
        .split(';')
        .filter(|s| !s.is_empty())
        .collect())
}

/// A markdown table's head: `| form |` and a column per name, then the rule.
pub(crate) fn table_head<'a>(md: &mut String, names: impl ExactSizeIterator<Item = &'a str>) {
    md.push_str("| form |");
    let n = names.len();
    for name in names {
        md.push_str(&format!(" {name} |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(n));
    md.push('\n');
}

/// Where the tours fell: for each form (rows) and kind of ground (columns), the
/// tours with a fall there, in parentheses their falls (a humanoid that falls again
/// and again at one spot counts once among the tours), and in brackets the tours
/// whose first fall was there.
fn fall_table(runs: &Table) -> anyhow::Result<String> {
    let grounds = GroundKind::ALL;
    // Per form and ground: tours with a fall there, falls, tours whose first fall
    // (the one that failed the tour) was there.
    let mut tours = BTreeMap::<(&str, GroundKind), (usize, usize, usize)>::new();
    // The tour's four forms, and a sprint where merged rows came from elsewhere.
    let known = [FORMS[0], FORMS[1], FORMS[2], FORMS[3], "sprint"];
    for r in 0..runs.rows.len() {
        let mut seen = BTreeSet::new();
        for (k, site) in fall_list(runs, r, "fall_sites")?.into_iter().enumerate() {
            let (form, ground) = site
                .split_once('@')
                .ok_or_else(|| anyhow::anyhow!("row {r}: fall site `{site}` is not form@ground"))?;
            let ground = grounds
                .into_iter()
                .find(|g| g.name() == ground)
                .ok_or_else(|| anyhow::anyhow!("row {r}: unknown ground `{ground}`"))?;
            let form = known.into_iter().find(|f| *f == form).ok_or_else(|| {
                anyhow::anyhow!("row {r}: unknown form `{form}` (expected one of {known:?})")
            })?;
            let e = tours.entry((form, ground)).or_default();
            e.1 += 1;
            if seen.insert((form, ground)) {
                e.0 += 1;
            }
            if k == 0 {
                e.2 += 1;
            }
        }
    }
    let mut md = String::from(
        "Where the tours fell: tours with a fall in that form on that ground, (falls), and \
         [tours whose first fall, the one that failed the tour, was there]; the form is the \
         plan's, the ground is judged from the height map under the root \
         (`eval::ground`).\n\n",
    );
    table_head(&mut md, grounds.iter().map(|g| g.name()));
    let shown = known
        .into_iter()
        .filter(|f| FORMS.contains(f) || tours.keys().any(|(k, _)| k == f));
    for f in shown {
        md.push_str(&format!("| {f} |"));
        for g in grounds {
            let (t, n, first) = tours.get(&(f, g)).copied().unwrap_or_default();
            md.push_str(&format!(" {t} ({n}) [{first}] |"));
        }
        md.push('\n');
    }
    Ok(md)
}

/// The forms a table has rows for: the tours' four, then each other one `seen`
/// (rows merged from a sweep with other forms), once each.
fn row_forms<'a>(seen: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut forms: Vec<String> = FORMS.iter().map(|f| f.to_string()).collect();
    for f in seen {
        if !forms.iter().any(|g| g == f) {
            forms.push(f.to_string());
        }
    }
    forms
}

/// Falls by form (rows, from `fall_sites`) and by a per-fall name in column `col`
/// (one for each fall, in the order of `fall_sites`), one column per value of `all`:
/// falls, and \[tours whose first fall it was\], after the paragraph `intro`. Empty
/// for a folder written before `col` was recorded; `what` names a value in errors
/// ("fall posture").
fn by_form_table<K: Copy + Ord>(
    runs: &Table,
    col: &str,
    what: &str,
    all: &[K],
    name: fn(K) -> &'static str,
    intro: &str,
) -> anyhow::Result<String> {
    if !runs.header.iter().any(|h| h == col) {
        return Ok(String::new());
    }
    // Per form and value: falls, and tours whose first fall was that.
    let mut counts = BTreeMap::<(String, K), (usize, usize)>::new();
    for r in 0..runs.rows.len() {
        let sites = fall_list(runs, r, "fall_sites")?;
        let values = fall_list(runs, r, col)?;
        if sites.len() != values.len() {
            bail!(
                "row {r}: {} fall sites but {} {what}s",
                sites.len(),
                values.len()
            );
        }
        for (k, (site, value)) in sites.iter().zip(&values).enumerate() {
            let form = site.split_once('@').map_or(*site, |(f, _)| f);
            let value = all
                .iter()
                .copied()
                .find(|v| name(*v) == *value)
                .ok_or_else(|| {
                    let known: Vec<&str> = all.iter().map(|v| name(*v)).collect();
                    anyhow::anyhow!("row {r}: unknown {what} `{value}` (one of {known:?})")
                })?;
            let e = counts.entry((form.to_string(), value)).or_default();
            e.0 += 1;
            e.1 += usize::from(k == 0);
        }
    }
    let mut md = format!("{intro}\n\n");
    table_head(&mut md, all.iter().map(|v| name(*v)));
    for f in row_forms(counts.keys().map(|(f, _)| f.as_str())) {
        md.push_str(&format!("| {f} |"));
        for v in all {
            let (n, first) = counts.get(&(f.clone(), *v)).copied().unwrap_or_default();
            md.push_str(&format!(" {n} [{first}] |"));
        }
        md.push('\n');
    }
    // What follows starts its own paragraph.
    md.pop();
    Ok(md)
}

/// Falls by form and the body's posture at the fall (`eval::fall_posture`), from
/// `fall_sites` and `fall_postures`; empty for a folder written before the postures
/// were recorded.
fn posture_table(runs: &Table) -> anyhow::Result<String> {
    let intro = format!(
        "\nHow the body lay when the fall rule judged it fallen: falls, and [tours whose first \
         fall it was]; rolled: pelvis roll past {ROLLED_FROM} rad; head-over-step: pelvis \
         still up ({PELVIS_UP} m or more) and the ground under the head {STEP_UNDER_HEAD} m or \
         more above the ground under the pelvis (a body still up is judged from its lowest \
         point, so such a head came within the rule's bar of it too); forward / backward: \
         the head ahead of / behind the pelvis (`eval::fall_posture`)."
    );
    let (all, name) = (&FallPosture::ALL, FallPosture::name);
    by_form_table(runs, "fall_postures", "fall posture", all, name, &intro)
}

/// Falls by the plan's form and what the body was doing before (`eval::body_state`),
/// from `fall_sites` and `fall_bodies`; empty for a folder written before the column
/// was recorded.
fn body_table(runs: &Table) -> anyhow::Result<String> {
    let intro = format!(
        "\n\nWhat the body was doing before it fell, read from the head's and pelvis's \
         heights over the ground {EARLIER} s before the fall and over the last {LATER} s \
         (down: the head below {DOWN_BELOW} m or the pelvis below {PELVIS_UP} m; up in the \
         last {LATER} s if not down at some time in them): falls, and [tours whose first \
         fall it was]; the row is the plan's form, which a body that lags its plan may not \
         be in. down: down at both reads (crawling, kneeling); rising: down, then up \
         (getting up); risen: up at both, but down within {RISEN_WITHIN} s before (the \
         first steps after a get-up); lowering: up, then down (getting down, or sagging \
         slowly); upright: up all through (`eval::body_state`)."
    );
    let (all, name) = (&BodyState::ALL, BodyState::name);
    by_form_table(runs, "fall_bodies", "body state", all, name, &intro)
}

/// How far into its leg a first fall counts as one of the leg's start \[s\]: a
/// get-down or a get-up takes 1.5-2 s, and a turn on the spot at the landmark about
/// as long.
const LEG_START: f64 = 4.0;

/// When in their leg the tours first fell (`fall_legs`): per form of the leg (rows),
/// the tours whose first fall came in the leg's first [`LEG_START`] s, by the form
/// before it (the tour's first leg starts standing), and those that fell later.
/// Empty for a folder written before the column was recorded.
fn leg_start_table(runs: &Table) -> anyhow::Result<String> {
    if !runs.header.iter().any(|h| h == "fall_legs") {
        return Ok(String::new());
    }
    let before = ["start", FORMS[0], FORMS[1], FORMS[2], FORMS[3]];
    // Per form: tours by the form before (in `before`'s order) and later.
    let mut counts = BTreeMap::<&str, [usize; 6]>::new();
    for r in 0..runs.rows.len() {
        let Some(first) = fall_list(runs, r, "fall_legs")?.into_iter().next() else {
            continue;
        };
        let bad = || anyhow::anyhow!("row {r}: fall leg `{first}` is not n:seconds");
        let (n, t) = first.split_once(':').ok_or_else(bad)?;
        let (n, t): (usize, f64) = (n.parse().map_err(|_| bad())?, t.parse().map_err(|_| bad())?);
        let forms: Vec<&str> = plamo_planner::instruction_forms(runs.str(r, "instructions")?)
            .map_err(|e| anyhow::anyhow!("row {r}: {e}"))?
            .into_iter()
            .map(verb)
            .collect();
        if n == 0 || n > forms.len() {
            bail!(
                "row {r}: fall in instruction {n} of a tour of {} legs",
                forms.len()
            );
        }
        let col = if t >= LEG_START {
            5
        } else if n == 1 {
            0
        } else {
            let prev = forms[n - 2];
            before.iter().position(|f| *f == prev).ok_or_else(|| {
                anyhow::anyhow!("row {r}: unknown form `{prev}` (one of {FORMS:?})")
            })?
        };
        counts.entry(forms[n - 1]).or_default()[col] += 1;
    }
    let mut md = format!(
        "\n\nWhen in its leg each tour first fell: tours whose first fall came in a leg's first \
         {LEG_START} s, by the form of the leg before it (start: the tour's first leg, from \
         standing), and later in a leg; the row is the form of the leg it fell in.\n\n"
    );
    let names: Vec<String> = before
        .iter()
        .map(|f| format!("first {LEG_START} s after {f}"))
        .chain(["later".to_string()])
        .collect();
    table_head(&mut md, names.iter().map(String::as_str));
    for f in row_forms(counts.keys().copied()) {
        let row = counts.get(f.as_str()).copied().unwrap_or_default();
        md.push_str(&format!("| {f} |"));
        for c in row {
            md.push_str(&format!(" {c} |"));
        }
        md.push('\n');
    }
    md.pop();
    Ok(md)
}

const COLUMNS: [&str; 24] = [
    "job",
    "scene_seed",
    "instructions",
    "cause",
    "landmarks_reached",
    "landmarks",
    "falls",
    "dynamic_collisions",
    "wall_contact_steps",
    "infeasible",
    "timed_out",
    "time_s",
    "xy_err",
    "z_err",
    "planned",
    "planned_length",
    "planned_time",
    "replans",
    "fall_sites",
    "fall_postures",
    "fall_bodies",
    "fall_legs",
    "digest",
    "error",
];

impl Experiment for RandomScenes {
    const NAME: &'static str = "random";
    type Job = u64;

    fn columns(&self) -> Vec<&'static str> {
        COLUMNS.to_vec()
    }

    fn jobs(&self) -> anyhow::Result<Vec<Self::Job>> {
        if !self.seeds.is_empty() {
            return Ok(self.seeds.clone());
        }
        Ok((0..self.scenes as u64)
            .map(|k| self.seed.wrapping_add(k))
            .collect())
    }

    fn run_job(
        &self,
        _j: usize,
        job: &Self::Job,
        opts: &RunOptions,
    ) -> anyhow::Result<Vec<String>> {
        let scene_seed = *job;
        let scene = plamo_scenes::random_scene(scene_seed);
        let text = tour(&scene, scene_seed, &self.forms)?;
        let ep = run_episode(&EpisodeSpec {
            scene: &scene,
            instructions: text.clone(),
            backend: opts.physics,
            seed: scene_seed,
            planner: opts.planner(),
            controller: opts.controller,
            physics_settings: opts.physics_settings(),
            max_seconds: opts.max_seconds,
        })?;
        let finished = ep.reached == ep.instructions;
        let collided = ep.dynamic_collisions > 0 || ep.static_contact_steps > 0;
        let cause = if ep.success() {
            "success"
        } else if ep.planning_error.is_some() || (ep.infeasible && !finished) {
            "planning"
        } else if ep.run_error.is_some() {
            "error"
        } else if ep.falls > 0 {
            "fall"
        } else if collided {
            "collision"
        } else {
            "timeout"
        };
        let b = |x: bool| u8::from(x).to_string();
        let landmarks = ep.instructions + 1;
        let reached = if ep.planning_error.is_some() {
            0
        } else {
            ep.reached + 1
        };
        Ok(vec![
            scene_seed.to_string(),
            field(&text),
            cause.into(),
            reached.to_string(),
            landmarks.to_string(),
            ep.falls.to_string(),
            ep.dynamic_collisions.to_string(),
            ep.static_contact_steps.to_string(),
            b(ep.infeasible),
            b(ep.timed_out),
            ep.time_s.to_string(),
            ep.xy_err.to_string(),
            ep.z_err.to_string(),
            b(ep.planning_error.is_none()),
            ep.planned_length.to_string(),
            ep.planned_time.to_string(),
            ep.replans.to_string(),
            ep.fall_sites_field(),
            ep.fall_postures_field(),
            ep.fall_bodies_field(),
            ep.fall_legs_field(),
            format!("{:016x}", ep.digest),
            field(
                ep.planning_error
                    .as_deref()
                    .or(ep.run_error.as_deref())
                    .unwrap_or(""),
            ),
        ])
    }

    fn params(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn summarize(&self, runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
        let n = runs.rows.len();
        let mut counts = [0usize; CAUSES.len()];
        let mut reached = Vec::new();
        let (mut plen, mut ptime, mut xy, mut z) = (vec![], vec![], vec![], vec![]);
        let mut planned = 0;
        let mut all_reached = 0;
        for r in 0..n {
            all_reached +=
                usize::from(runs.usize(r, "landmarks_reached")? == runs.usize(r, "landmarks")?);
            let cause = runs.str(r, "cause")?;
            let k = CAUSES
                .iter()
                .position(|c| *c == cause)
                .ok_or_else(|| anyhow::anyhow!("row {r}: unknown cause `{cause}`"))?;
            counts[k] += 1;
            reached.push(runs.f64(r, "landmarks_reached")?);
            if runs.flag(r, "planned")? {
                planned += 1;
                plen.push(runs.f64(r, "planned_length")?);
                ptime.push(runs.f64(r, "planned_time")?);
                xy.push(runs.f64(r, "xy_err")?);
                z.push(runs.f64(r, "z_err")?);
            }
        }
        let (lo, hi) = wilson(counts[0], n, Z95);
        let rate = counts[0] as f64 / n.max(1) as f64;
        let (mut args, which) = if self.seeds.is_empty() {
            (
                format!(" --scenes {} --seed {}", self.scenes, self.seed),
                format!(
                    "seeds {}..{}",
                    self.seed,
                    self.seed + self.scenes as u64 - 1
                ),
            )
        } else {
            let list: Vec<String> = self.seeds.iter().map(u64::to_string).collect();
            (
                format!(" --seeds {}", list.join(",")),
                format!("seeds {}", list.join(", ")),
            )
        };
        if !self.draws_all_forms() {
            args.push_str(&format!(" --forms {}", self.forms.join(",")));
        }
        let mut md = format!(
            "Command: `{}`\n\n\
             {n} random scenes ({which}), each a tour of its 4 landmarks in random forms \
             ({}). Success = all four landmarks reached without a \
             fall.\n\n\
             **Success: {}/{n} = {:.0}% (95% Wilson interval {:.0}-{:.0}%)**; paper: 81%.\n\n\
             | outcome | runs | share |\n|---|---|---|\n",
            command_line(meta, &args),
            self.forms.join(", "),
            counts[0],
            100.0 * rate,
            100.0 * lo,
            100.0 * hi,
        );
        for (k, c) in CAUSES.iter().enumerate() {
            md.push_str(&format!(
                "| {c} | {} | {:.0}% |\n",
                counts[k],
                100.0 * counts[k] as f64 / n.max(1) as f64
            ));
        }
        md.push_str(&format!(
            "\nPlanner only: a route found at the start in {planned}/{n} scenes, mean planned \
             length {:.1} m, planned time {:.1} s. Executed: all four landmarks reached in \
             {all_reached}/{n} scenes when falls are allowed (a fallen humanoid is reset onto \
             its plan and goes on), mean landmarks reached {:.2} of 4, head XY / Z error \
             {:.2} / {:.2} m.\n\n\
             Causes are assigned in this order: planning (no route at the start, or the \
             planner flagged the rest infeasible), error (a component failed), fall, collision \
             (a wall, ceiling or moving obstacle touched and the tour unfinished), timeout.\n\n\
             ![outcomes](random.png)\n\n{}{}{}{}{}",
            mean(&plen),
            mean(&ptime),
            mean(&reached),
            mean(&xy),
            mean(&z),
            fall_table(runs)?,
            posture_table(runs)?,
            body_table(runs)?,
            leg_start_table(runs)?,
            replay_note(runs, meta, out)?,
        ));
        let mut csv = Table {
            header: ["outcome", "runs", "share", "wilson95_low", "wilson95_high"]
                .map(String::from)
                .to_vec(),
            rows: vec![],
        };
        let colors = [
            RGBColor(30, 150, 60),
            RGBColor(120, 60, 170),
            RGBColor(90, 90, 90),
            RGBColor(210, 50, 40),
            RGBColor(230, 140, 20),
            RGBColor(60, 110, 210),
        ];
        let mut chart = Vec::new();
        for (k, c) in CAUSES.iter().enumerate() {
            let (l, h) = wilson(counts[k], n, Z95);
            let share = counts[k] as f64 / n.max(1) as f64;
            csv.rows.push(vec![
                c.to_string(),
                counts[k].to_string(),
                format!("{share:.4}"),
                format!("{l:.4}"),
                format!("{h:.4}"),
            ]);
            chart.push(Bar {
                label: c.to_string(),
                value: share,
                interval: Some((l, h)),
                color: colors[k],
            });
        }
        std::fs::write(out.join("summary.csv"), csv.to_csv())?;
        bars(
            &out.join("random.png"),
            &format!(
                "Random 4-landmark scenes ({}, n = {n}): outcome shares, 95% Wilson intervals",
                meta.physics
            ),
            "share of scenes",
            &chart,
            1.0,
        )?;
        Ok(md)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell<'a>(md: &'a str, form: &str, ground: GroundKind) -> &'a str {
        let col = GroundKind::ALL.iter().position(|g| *g == ground).unwrap() + 2;
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| {form} |")))
            .unwrap();
        row.split('|').nth(col).unwrap().trim()
    }

    #[test]
    fn tours_draw_their_forms_from_the_forms_asked_for() {
        let scene = plamo_scenes::random_scene(0);
        // All four forms: the paper's tours, the draws as before `--forms` (the
        // tour in results/*/random/runs.csv for scene 0).
        let all = RandomScenes::new(1, 0, &[]).unwrap();
        assert_eq!(all.forms, FORMS);
        assert_eq!(
            tour(&scene, 0, &all.forms).unwrap(),
            "Run from the rock to the kiosk, then walk to the fountain, then crouch-walk to \
             the statue"
        );
        // Crawl only: every leg crawls, through the same landmarks.
        let crawl = RandomScenes::new(1, 0, &["crawl".to_string()]).unwrap();
        assert_eq!(
            tour(&scene, 0, &crawl.forms).unwrap(),
            "Crawl from the rock to the kiosk, then crawl to the fountain, then crawl to the \
             statue"
        );
        // Two forms: only those two.
        let two = ["walk".to_string(), "run".to_string()];
        for seed in 0..20 {
            let scene = plamo_scenes::random_scene(seed);
            let t = tour(&scene, seed, &two).unwrap().to_lowercase();
            assert!(!t.contains("crawl"), "{t}");
        }
    }

    #[test]
    fn unknown_or_repeated_forms_are_refused_naming_the_allowed_ones() {
        let e = RandomScenes::new(1, 0, &["crawll".to_string()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`crawll`") && e.contains("crawl, crouch-walk, walk, run"),
            "{e}"
        );
        let e = RandomScenes::new(1, 0, &["walk".to_string(), "walk".to_string()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("`walk` given twice"), "{e}");
    }

    #[test]
    fn the_fall_table_counts_tours_falls_and_first_falls() {
        let runs = Table {
            header: vec!["job".into(), "fall_sites".into()],
            rows: [
                "crawl@stairs;walk@flat;crawl@stairs",
                "walk@flat;crawl@stairs",
                "",
            ]
            .iter()
            .enumerate()
            .map(|(k, s)| vec![k.to_string(), s.to_string()])
            .collect(),
        };
        let md = fall_table(&runs).unwrap();
        assert_eq!(cell(&md, "crawl", GroundKind::Stairs), "2 (3) [1]", "{md}");
        assert_eq!(cell(&md, "walk", GroundKind::Flat), "2 (2) [1]", "{md}");
        assert_eq!(cell(&md, "run", GroundKind::Slope), "0 (0) [0]", "{md}");
    }

    /// A runs.csv of one tour per entry of `sites` (`fall_sites`), with the per-fall
    /// column `col` holding `values`.
    fn per_fall_runs(col: &str, sites: &[&str], values: &[&str]) -> Table {
        Table {
            header: ["job", "fall_sites", col].map(String::from).to_vec(),
            rows: sites
                .iter()
                .zip(values)
                .enumerate()
                .map(|(k, (s, v))| vec![k.to_string(), s.to_string(), v.to_string()])
                .collect(),
        }
    }

    /// Value column `col` (0 = the first after the form) of the row for `form` in the
    /// markdown table `md`.
    fn column_of_row(md: &str, form: &str, col: usize) -> String {
        md.lines()
            .find(|l| l.starts_with(&format!("| {form} |")))
            .unwrap_or_else(|| panic!("no row {form} in {md}"))
            .split('|')
            .nth(col + 2)
            .unwrap()
            .trim()
            .to_string()
    }

    /// A runs.csv from before the per-fall columns: only `fall_sites`.
    fn before_per_fall_columns() -> Table {
        Table {
            header: vec!["job".into(), "fall_sites".into()],
            rows: vec![vec!["0".into(), "crawl@flat".into()]],
        }
    }

    #[test]
    fn the_posture_table_counts_falls_and_first_falls_and_names_a_bad_posture() {
        let sites = [
            "crawl@stairs;walk@flat;crawl@stairs",
            "crawl@rough;crawl@stairs",
            "",
        ];
        let table = |postures: [&str; 3]| per_fall_runs("fall_postures", &sites, &postures);
        let md = posture_table(&table([
            "head-over-step;backward;rolled",
            "head-over-step;head-over-step",
            "",
        ]))
        .unwrap();
        let at = |form: &str, p: FallPosture| {
            let col = FallPosture::ALL.iter().position(|q| *q == p).unwrap();
            column_of_row(&md, form, col)
        };
        assert_eq!(at("crawl", FallPosture::HeadOverStep), "3 [2]", "{md}");
        assert_eq!(at("crawl", FallPosture::Rolled), "1 [0]", "{md}");
        assert_eq!(at("walk", FallPosture::Backward), "1 [0]", "{md}");
        assert_eq!(at("run", FallPosture::Forward), "0 [0]", "{md}");
        let e = posture_table(&table(["rolled;sideways;rolled", "rolled;rolled", ""]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`sideways`") && e.contains("head-over-step"),
            "{e}"
        );
        let e = posture_table(&table(["rolled", "rolled;rolled", ""]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 fall sites but 1 fall postures"), "{e}");
        // A folder from before the column: no table, no error.
        assert_eq!(posture_table(&before_per_fall_columns()).unwrap(), "");
    }

    #[test]
    fn the_body_table_counts_falls_by_the_plans_form_and_names_a_bad_state() {
        let sites = ["walk@flat;walk@slope;crawl@rough", "walk@stairs"];
        let table = |bodies: [&str; 2]| per_fall_runs("fall_bodies", &sites, &bodies);
        let md = body_table(&table(["down;rising;down", "down"])).unwrap();
        let at = |form: &str, b: BodyState| {
            let col = BodyState::ALL.iter().position(|q| *q == b).unwrap();
            column_of_row(&md, form, col)
        };
        // A walk leg whose body was still down: two tours, both first falls.
        assert_eq!(at("walk", BodyState::Down), "2 [2]", "{md}");
        assert_eq!(at("walk", BodyState::Rising), "1 [0]", "{md}");
        assert_eq!(at("crawl", BodyState::Down), "1 [0]", "{md}");
        assert_eq!(at("run", BodyState::Upright), "0 [0]", "{md}");
        let e = body_table(&table(["down;up;down", "down"]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("unknown body state `up`") && e.contains("risen"),
            "{e}"
        );
        let e = body_table(&table(["down", "down"]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 fall sites but 1 body states"), "{e}");
        assert_eq!(body_table(&before_per_fall_columns()).unwrap(), "");
    }

    #[test]
    fn the_leg_start_table_sorts_first_falls_by_the_form_before_them() {
        let tour = "Crawl from the rock to the kiosk; then walk to the well; then walk to the car";
        let table = |legs: [&str; 4]| Table {
            header: ["job", "instructions", "fall_legs"]
                .map(String::from)
                .to_vec(),
            rows: legs
                .iter()
                .enumerate()
                .map(|(k, l)| vec![k.to_string(), tour.to_string(), l.to_string()])
                .collect(),
        };
        // A walk just up from the crawl, the same walk later, a crawl getting down
        // from standing (and a second fall that does not count), no fall.
        let md = leg_start_table(&table(["2:1.50", "2:9.00", "1:0.40;3:0.50", ""])).unwrap();
        let row = |form: &str| {
            md.lines()
                .find(|l| l.starts_with(&format!("| {form} |")))
                .unwrap_or_else(|| panic!("no row {form} in {md}"))
                .split('|')
                .skip(2)
                .map(|c| c.trim().to_string())
                .filter(|c| !c.is_empty())
                .collect::<Vec<_>>()
        };
        assert_eq!(row("walk"), ["0", "1", "0", "0", "0", "1"], "{md}");
        assert_eq!(row("crawl"), ["1", "0", "0", "0", "0", "0"], "{md}");
        assert_eq!(row("run"), ["0"; 6], "{md}");
        // A third walk just after a walk.
        let md2 = leg_start_table(&table(["3:0.10", "", "", ""])).unwrap();
        assert!(md2.contains("| walk | 0 | 0 | 0 | 1 | 0 | 0 |"), "{md2}");
        // A fall in an instruction the tour does not have, or a garbled field.
        let e = leg_start_table(&table(["4:1.0", "", "", ""]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("instruction 4 of a tour of 3 legs"), "{e}");
        let e = leg_start_table(&table(["2-1.0", "", "", ""]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("`2-1.0` is not n:seconds"), "{e}");
        // A folder from before the column: no table.
        let old = Table {
            header: vec!["job".into(), "instructions".into()],
            rows: vec![vec!["0".into(), tour.into()]],
        };
        assert_eq!(leg_start_table(&old).unwrap(), "");
    }
}
