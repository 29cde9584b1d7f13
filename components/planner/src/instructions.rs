//! Stage 1: templated instructions -> (source, target, locomotion).
//!
//! Grammar (case-insensitive, one or more clauses separated by "then", ",", ";" or
//! "."): `<verb> [crouching] [from [the] <landmark>] to [the] <landmark>`.

use plamo_scenes::Scene;
use serde::{Deserialize, Serialize};

use crate::PlanError;

/// A form of locomotion, with its head height and speed range in
/// [`crate::PlannerSettings`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Locomotion {
    /// On hands and knees: head 0.4 m, up to 1 m/s.
    Crawl,
    /// Crouched walk: head 0.8 m, up to 2 m/s.
    CrouchWalk,
    /// Walk: head 1.47 m, up to 2 m/s.
    Walk,
    /// Run: head 1.47 m, up to 4 m/s.
    Run,
    /// Sprint: head 1.47 m, up to 5 m/s.
    Sprint,
}

/// Where an instruction starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// A named landmark ("from the tree").
    Landmark(String),
    /// The previous instruction's target.
    PreviousTarget,
    /// The character's position (first instruction without "from").
    CurrentPosition,
}

/// One parsed instruction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Instruction {
    /// The clause as written.
    pub text: String,
    /// Where it starts.
    pub source: Source,
    /// Target landmark, as named in the scene.
    pub target: String,
    /// Requested locomotion.
    pub locomotion: Locomotion,
}

/// Verbs accepted as the first word of a clause.
pub const VALID_VERBS: [&str; 8] = [
    "crawl",
    "crouch",
    "crouch-walk",
    "walk",
    "walk crouching",
    "run",
    "jog",
    "sprint",
];

fn clauses(text: &str) -> Vec<String> {
    let lower = text.to_lowercase();
    let mut parts = Vec::new();
    for piece in lower.split([',', ';', '.', '\n']) {
        let mut cur: Vec<&str> = Vec::new();
        for w in piece.split_whitespace() {
            if w == "then" {
                if !cur.is_empty() {
                    parts.push(cur.join(" "));
                }
                cur.clear();
            } else {
                cur.push(w);
            }
        }
        // Drop a dangling "and" left over from "..., and then ...".
        while cur.last() == Some(&"and") {
            cur.pop();
        }
        while cur.first() == Some(&"and") {
            cur.remove(0);
        }
        if !cur.is_empty() {
            parts.push(cur.join(" "));
        }
    }
    parts
}

fn verb_of(words: &[&str]) -> Option<(Locomotion, usize)> {
    let first = *words.first()?;
    let crouching = |w: &&str| matches!(*w, "crouching" | "crouched" | "crouch");
    let form = match first {
        "crawl" | "crawling" => Locomotion::Crawl,
        "crouch" | "crouch-walk" | "crouching" => Locomotion::CrouchWalk,
        "walk" | "walking" => Locomotion::Walk,
        "run" | "running" | "jog" | "jogging" => Locomotion::Run,
        "sprint" | "sprinting" => Locomotion::Sprint,
        _ => return None,
    };
    // "walk crouching", "crouch walk": a second word that modifies the form.
    let mut used = 1;
    let form = match (form, words.get(1)) {
        (Locomotion::Walk, Some(w)) if crouching(w) => {
            used = 2;
            Locomotion::CrouchWalk
        }
        (Locomotion::CrouchWalk, Some(&"walk" | &"walking")) => {
            used = 2;
            Locomotion::CrouchWalk
        }
        (f, _) => f,
    };
    Some((form, used))
}

fn landmark_name<'a>(words: &'a [&'a str]) -> String {
    let w = if words.first() == Some(&"the") {
        &words[1..]
    } else {
        words
    };
    w.join(" ")
}

/// The locomotion of each instruction in `text`, without a scene: the verbs alone
/// (what a table over many scenes' tours needs; [`parse_instructions`] also
/// resolves the landmarks).
pub fn instruction_forms(text: &str) -> Result<Vec<Locomotion>, PlanError> {
    clauses(text)
        .iter()
        .enumerate()
        .map(|(index, clause)| {
            let words: Vec<&str> = clause.split_whitespace().collect();
            clause_verb(index, clause, &words).map(|(l, _)| l)
        })
        .collect()
}

/// The verb of clause `index` (its `words`), or the error that names it and the
/// verbs allowed.
fn clause_verb(
    index: usize,
    clause: &str,
    words: &[&str],
) -> Result<(Locomotion, usize), PlanError> {
    verb_of(words).ok_or_else(|| PlanError::UnknownVerb {
        index,
        text: clause.to_string(),
        verb: words.first().unwrap_or(&"").to_string(),
        valid: VALID_VERBS.iter().map(|s| s.to_string()).collect(),
    })
}

/// Parse one or several instructions against the scene's landmarks.
pub fn parse_instructions(text: &str, scene: &Scene) -> Result<Vec<Instruction>, PlanError> {
    let valid_landmarks = || {
        scene
            .landmark_names()
            .iter()
            .map(|s| s.to_string())
            .collect()
    };
    let mut out = Vec::new();
    for (index, clause) in clauses(text).into_iter().enumerate() {
        let words: Vec<&str> = clause.split_whitespace().collect();
        let (locomotion, used) = clause_verb(index, &clause, &words)?;
        let rest = &words[used..];
        let from = rest.iter().position(|w| *w == "from");
        let to = rest.iter().rposition(|w| *w == "to");
        let Some(to) = to else {
            return Err(PlanError::Malformed {
                index,
                text: clause.clone(),
                reason: "no target (\"to the <landmark>\")",
            });
        };
        let resolve = |name: String| -> Result<String, PlanError> {
            if name.is_empty() {
                return Err(PlanError::Malformed {
                    index,
                    text: clause.clone(),
                    reason: "a landmark name is missing",
                });
            }
            scene
                .landmark(&name)
                .map(|l| l.name.clone())
                .ok_or_else(|| PlanError::UnknownLandmark {
                    index,
                    text: clause.clone(),
                    name,
                    valid: valid_landmarks(),
                })
        };
        let source = match from {
            Some(f) if f < to => Source::Landmark(resolve(landmark_name(&rest[f + 1..to]))?),
            Some(_) => {
                return Err(PlanError::Malformed {
                    index,
                    text: clause.clone(),
                    reason: "\"from\" must come before \"to\"",
                });
            }
            None if index == 0 => Source::CurrentPosition,
            None => Source::PreviousTarget,
        };
        let target = resolve(landmark_name(&rest[to + 1..]))?;
        out.push(Instruction {
            text: clause,
            source,
            target,
            locomotion,
        });
    }
    if out.is_empty() {
        return Err(PlanError::NoInstructions);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::flat_scene;

    #[test]
    fn parses_the_templates() {
        let s = flat_scene();
        let v = parse_instructions("Run from the tree to the car", &s).unwrap();
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].source, Source::Landmark("tree".into()));
        assert_eq!(v[0].target, "car");
        assert_eq!(v[0].locomotion, Locomotion::Run);
        let v = parse_instructions("walk crouching to the bench", &s).unwrap();
        assert_eq!(v[0].locomotion, Locomotion::CrouchWalk);
        assert_eq!(v[0].source, Source::CurrentPosition);
        let v = parse_instructions("sprint to the car", &s).unwrap();
        assert_eq!(v[0].locomotion, Locomotion::Sprint);
        let v = parse_instructions("crawl to the tree then run to the swing", &s).unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].locomotion, Locomotion::Crawl);
        assert_eq!(v[1].source, Source::PreviousTarget);
        assert_eq!(v[1].target, "swing");
        let v = parse_instructions("Run from the tree to the car, then crawl to the bench.", &s)
            .unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[1].locomotion, Locomotion::Crawl);
        assert_eq!(v[1].target, "bench");
    }

    #[test]
    fn the_forms_alone_need_no_scene_and_agree_with_the_full_parse() {
        let text = "Run from the tree to the car; then walk crouching to the bench, then crawl to \
                    the moon";
        assert_eq!(
            instruction_forms(text).unwrap(),
            [Locomotion::Run, Locomotion::CrouchWalk, Locomotion::Crawl]
        );
        let known = "Run from the tree to the car, then crouch walk to the bench";
        let parsed: Vec<Locomotion> = parse_instructions(known, &flat_scene())
            .unwrap()
            .iter()
            .map(|i| i.locomotion)
            .collect();
        assert_eq!(instruction_forms(known).unwrap(), parsed);
        match instruction_forms("walk to the car, then fly to the tree") {
            Err(e @ PlanError::UnknownVerb { index: 1, .. }) => {
                assert!(e.to_string().contains("`fly`"), "{e}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn errors_list_the_valid_choices() {
        let s = flat_scene();
        match parse_instructions("fly to the car", &s) {
            Err(e @ PlanError::UnknownVerb { .. }) => {
                let msg = e.to_string();
                assert!(msg.contains("`fly`") && msg.contains("crawl") && msg.contains("sprint"));
            }
            other => panic!("{other:?}"),
        }
        match parse_instructions("run to the moon", &s) {
            Err(e @ PlanError::UnknownLandmark { .. }) => {
                let msg = e.to_string();
                assert!(msg.contains("`moon`"), "{msg}");
                for l in ["tree", "car", "bench", "swing"] {
                    assert!(msg.contains(l), "{msg}");
                }
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            parse_instructions("run from the tree", &s),
            Err(PlanError::Malformed { .. })
        ));
        assert!(matches!(
            parse_instructions("  ", &s),
            Err(PlanError::NoInstructions)
        ));
    }
}
