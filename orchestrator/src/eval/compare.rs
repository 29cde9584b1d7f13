//! Paired comparison of two random-scene sweeps over the same seeds (`plamo eval
//! compare BASE NEW`): a change to the controller, planner or physics is judged by
//! the tours it gains and loses, not by two success rates whose intervals overlap.
//!
//! Every tour is deterministic per seed, so the two sweeps pair tour by tour. Tours
//! that succeed or fail in both say nothing about the change; the test is on the
//! discordant pairs alone (exact McNemar: under no effect a gained tour is as likely
//! as a lost one). Identical digests show how many tours the change left untouched.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, bail};

use super::body_state::BodyState;
use super::random::{CAUSES, FORMS, RandomScenes, table_head};
use super::table::Table;
use super::{Experiment, Meta, read_meta, wilson};
use crate::eval::ground::GroundKind;

/// How many seeds of each of the gained and lost lists the report names.
const LISTED: usize = 20;

/// Tour-by-tour outcome counts of two sweeps on their common seeds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Pairs {
    /// Tours paired (seeds in both sweeps).
    pub n: usize,
    /// Successful in both.
    pub both: usize,
    /// Failed in the base, successful in the new sweep.
    pub gained: usize,
    /// Successful in the base, failed in the new sweep.
    pub lost: usize,
    /// Tours whose trajectory digest is the same in both.
    pub same_digest: usize,
}

impl Pairs {
    /// Successes of the base sweep.
    pub fn base(&self) -> usize {
        self.both + self.lost
    }

    /// Successes of the new sweep.
    pub fn new_successes(&self) -> usize {
        self.both + self.gained
    }

    /// Two-sided exact McNemar p-value: the chance, with gains and losses equally
    /// likely, of a split of the discordant tours at least this uneven.
    pub fn p_value(&self) -> f64 {
        mcnemar_exact(self.gained, self.lost)
    }
}

/// Two-sided exact binomial test of `a` against `b` at p = 1/2 (McNemar's test on
/// the discordant pairs); 1 when there are none.
pub fn mcnemar_exact(a: usize, b: usize) -> f64 {
    let n = a + b;
    if n == 0 {
        return 1.0;
    }
    let k = a.min(b);
    // P(X <= k) for X ~ Bin(n, 1/2), from the log of each term: n reaches thousands.
    let ln_half_n = n as f64 * 0.5f64.ln();
    let mut ln_c = 0.0; // ln C(n, 0)
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_c += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_c + ln_half_n).exp();
    }
    (2.0 * tail).min(1.0)
}

/// One sweep's rows by scene seed.
struct Sweep {
    dir: String,
    meta: Meta,
    runs: Table,
    by_seed: BTreeMap<u64, usize>,
}

impl Sweep {
    fn read(dir: &Path) -> anyhow::Result<Self> {
        let meta = read_meta(dir)?;
        if meta.experiment != RandomScenes::NAME {
            bail!(
                "{}: a `{}` sweep; compare pairs `random` sweeps (tour by tour over their \
                 scene seeds)",
                dir.display(),
                meta.experiment
            );
        }
        if let Some(s) = meta.shard {
            bail!(
                "{}: shard {s} of a sweep; merge the shards first (plamo eval merge)",
                dir.display()
            );
        }
        let p = dir.join("runs.csv");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let runs = Table::parse(&text, &p.display().to_string())?;
        let mut by_seed = BTreeMap::new();
        for r in 0..runs.rows.len() {
            let seed = runs.usize(r, "scene_seed")? as u64;
            if by_seed.insert(seed, r).is_some() {
                bail!("{}: scene seed {seed} appears twice", p.display());
            }
        }
        Ok(Self {
            dir: dir.display().to_string(),
            meta,
            runs,
            by_seed,
        })
    }

    fn success(&self, r: usize) -> anyhow::Result<bool> {
        Ok(self.runs.str(r, "cause")? == "success")
    }

    /// Where the tour of row `r` first fell ("walk@stairs"), if it failed by a fall.
    fn first_fall(&self, r: usize) -> anyhow::Result<Option<String>> {
        if self.runs.str(r, "cause")? != "fall" {
            return Ok(None);
        }
        Ok(self
            .runs
            .str(r, "fall_sites")?
            .split(';')
            .find(|s| !s.is_empty())
            .map(str::to_owned))
    }

    /// The plan's form and what the body was doing before the first fall of row `r`
    /// ("walk:rising"), if it failed by a fall; `None` also for a sweep written before
    /// `fall_bodies` was recorded.
    fn first_body(&self, r: usize) -> anyhow::Result<Option<String>> {
        if !self.has_bodies() {
            return Ok(None);
        }
        let (Some(site), Some(body)) = (
            self.first_fall(r)?,
            self.runs.str(r, "fall_bodies")?.split(';').next(),
        ) else {
            return Ok(None);
        };
        let form = site.split_once('@').map_or(site.as_str(), |(f, _)| f);
        Ok(Some(format!("{form}:{body}")))
    }

    fn has_bodies(&self) -> bool {
        self.runs.header.iter().any(|h| h == "fall_bodies")
    }
}

/// The paired counts of `base` and `new` over their common seeds, with the gained
/// and lost seeds and the common ones. Tours with different instructions under one seed (sweeps of
/// different `--forms`) are an error: they are not the same tour.
/// Seeds of the common tours by how they went (see [`pair`]).
struct Seeds {
    gained: Vec<u64>,
    lost: Vec<u64>,
    common: Vec<u64>,
}

fn pair(base: &Sweep, new: &Sweep) -> anyhow::Result<(Pairs, Seeds)> {
    let mut p = Pairs::default();
    let (mut gained, mut lost, mut common) = (Vec::new(), Vec::new(), Vec::new());
    for (&seed, &rb) in &base.by_seed {
        let Some(&rn) = new.by_seed.get(&seed) else {
            continue;
        };
        let (ib, inew) = (
            base.runs.str(rb, "instructions")?,
            new.runs.str(rn, "instructions")?,
        );
        if ib != inew {
            bail!(
                "scene seed {seed} has different tours: `{ib}` in {} and `{inew}` in {} \
                 (sweeps of different --forms do not pair)",
                base.dir,
                new.dir
            );
        }
        p.n += 1;
        common.push(seed);
        match (base.success(rb)?, new.success(rn)?) {
            (true, true) => p.both += 1,
            (false, true) => {
                p.gained += 1;
                gained.push(seed);
            }
            (true, false) => {
                p.lost += 1;
                lost.push(seed);
            }
            (false, false) => {}
        }
        if base.runs.str(rb, "digest")? == new.runs.str(rn, "digest")? {
            p.same_digest += 1;
        }
    }
    if p.n == 0 {
        bail!(
            "{} and {} share no scene seed (seeds {} and {})",
            base.dir,
            new.dir,
            seed_range(base),
            seed_range(new)
        );
    }
    Ok((
        p,
        Seeds {
            gained,
            lost,
            common,
        },
    ))
}

fn seed_range(s: &Sweep) -> String {
    match (s.by_seed.keys().next(), s.by_seed.keys().next_back()) {
        (Some(a), Some(b)) => format!("{a}-{b}"),
        _ => "none".into(),
    }
}

/// Counts of `key` over the common seeds' rows of `s`.
fn tally(
    s: &Sweep,
    seeds: &[u64],
    key: impl Fn(&Sweep, usize) -> anyhow::Result<Option<String>>,
) -> anyhow::Result<BTreeMap<String, usize>> {
    let mut m = BTreeMap::new();
    for seed in seeds {
        if let Some(k) = key(s, s.by_seed[seed])? {
            *m.entry(k).or_insert(0) += 1;
        }
    }
    Ok(m)
}

fn seed_list(seeds: &[u64]) -> String {
    let mut s: Vec<String> = seeds.iter().take(LISTED).map(u64::to_string).collect();
    if seeds.len() > LISTED {
        s.push(format!("... ({} more)", seeds.len() - LISTED));
    }
    if s.is_empty() {
        "none".into()
    } else {
        s.join(", ")
    }
}

/// Compares the random sweeps in folders `base` and `new` tour by tour; writes
/// `compare.md` into `out` when given, and returns the markdown. The sweeps may be
/// of different engines (the header names both): a backend swap pairs as well.
pub fn compare(base: &Path, new: &Path, out: Option<&Path>) -> anyhow::Result<String> {
    let (b, n) = (Sweep::read(base)?, Sweep::read(new)?);
    let (
        p,
        Seeds {
            gained,
            lost,
            common,
        },
    ) = pair(&b, &n)?;
    let mut md = String::new();
    let _ = writeln!(md, "# Paired comparison of random-scene sweeps\n");
    let _ = writeln!(
        md,
        "Base: `{}` ({}); new: `{}` ({}). {} tours paired by scene seed (seeds {}-{}); \
         {} only in the base, {} only in the new sweep.\n",
        b.dir,
        b.meta.physics,
        n.dir,
        n.meta.physics,
        p.n,
        common.first().copied().unwrap_or_default(),
        common.last().copied().unwrap_or_default(),
        b.by_seed.len() - p.n,
        n.by_seed.len() - p.n,
    );
    let rate = |k: usize| {
        let (lo, hi) = wilson(k, p.n, super::random::Z95);
        format!(
            "{k} / {} = {:.1}% (95% CI {:.1}-{:.1}%)",
            p.n,
            100.0 * k as f64 / p.n as f64,
            100.0 * lo,
            100.0 * hi
        )
    };
    let _ = writeln!(md, "| | success |\n|---|---|");
    let _ = writeln!(md, "| base | {} |", rate(p.base()));
    let _ = writeln!(md, "| new | {} |\n", rate(p.new_successes()));
    let d = p.gained + p.lost;
    let z = if d > 0 {
        (p.gained as f64 - p.lost as f64) / (d as f64).sqrt()
    } else {
        0.0
    };
    let _ = writeln!(
        md,
        "Gained {} (failed in the base, succeeded in the new), lost {}, succeeded in both \
         {}, failed in both {}. Exact McNemar test on the {d} discordant tours: p = {:.3} \
         (z = {z:+.1}). Identical trajectories (digest): {} of {}.\n",
        p.gained,
        p.lost,
        p.both,
        p.n - p.both - p.gained - p.lost,
        p.p_value(),
        p.same_digest,
        p.n
    );
    let _ = writeln!(md, "Gained seeds: {}.\n", seed_list(&gained));
    let _ = writeln!(md, "Lost seeds: {}.\n", seed_list(&lost));

    let cause = |s: &Sweep, r: usize| Ok(Some(s.runs.str(r, "cause")?.to_owned()));
    let (cb, cn) = (tally(&b, &common, cause)?, tally(&n, &common, cause)?);
    let _ = writeln!(md, "Tours by outcome, base -> new:\n");
    let _ = writeln!(md, "| outcome | base | new |\n|---|---|---|");
    for c in CAUSES {
        let (x, y) = (cb.get(c).copied(), cn.get(c).copied());
        if x.is_some() || y.is_some() {
            let _ = writeln!(md, "| {c} | {} | {} |", x.unwrap_or(0), y.unwrap_or(0));
        }
    }
    let first = |s: &Sweep, r: usize| s.first_fall(r);
    let (fb, fnew) = (tally(&b, &common, first)?, tally(&n, &common, first)?);
    let _ = writeln!(
        md,
        "\nTours lost to a fall, by where the first fall came (form, ground), base -> new:\n"
    );
    let grounds = GroundKind::ALL.map(GroundKind::name);
    base_to_new(&mut md, &grounds, '@', &fb, &fnew);
    if b.has_bodies() && n.has_bodies() {
        let body = |s: &Sweep, r: usize| s.first_body(r);
        let (bb, bn) = (tally(&b, &common, body)?, tally(&n, &common, body)?);
        let _ = writeln!(
            md,
            "\nTours lost to a fall, by what the body was doing before the first fall \
             (`eval::body_state`; the row is the plan's form), base -> new:\n"
        );
        base_to_new(&mut md, &BodyState::ALL.map(BodyState::name), ':', &bb, &bn);
    }
    if let Some(out) = out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let p = out.join("compare.md");
        std::fs::write(&p, &md).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(md)
}

/// A table of tallies keyed `form{sep}column` (rows [`FORMS`], a column per name in
/// `columns`), each cell `base -> new`.
fn base_to_new(
    md: &mut String,
    columns: &[&str],
    sep: char,
    base: &BTreeMap<String, usize>,
    new: &BTreeMap<String, usize>,
) {
    table_head(md, columns.iter().copied());
    for f in FORMS {
        let _ = write!(md, "| {f} |");
        for c in columns {
            let k = format!("{f}{sep}{c}");
            let (x, y) = (
                base.get(&k).copied().unwrap_or(0),
                new.get(&k).copied().unwrap_or(0),
            );
            let _ = write!(md, " {x} -> {y} |");
        }
        md.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mcnemar_matches_the_binomial_tail() {
        // No discordant tours, or an even split: no evidence.
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        assert_eq!(mcnemar_exact(5, 5), 1.0);
        // 0 of 5 one way: 2 * (1/2)^5.
        assert!((mcnemar_exact(5, 0) - 0.0625).abs() < 1e-12);
        assert_eq!(mcnemar_exact(0, 5), mcnemar_exact(5, 0));
        // 1 of 10: 2 * (1 + 10) / 1024.
        assert!((mcnemar_exact(9, 1) - 22.0 / 1024.0).abs() < 1e-12);
        // Thousands of tours stay finite; 126 against 86 is p ~ 0.007.
        let p = mcnemar_exact(126, 86);
        assert!(p > 0.005 && p < 0.01, "{p}");
    }
}
