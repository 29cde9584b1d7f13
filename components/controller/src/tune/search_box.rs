//! What a search moves: each form's built-in box of fields and ranges, the fields a
//! user adds or re-bounds (`plamo tune --search NAME=LO..HI`), and the map between a
//! candidate in the normalised [0, 1] box and a parameter file.
//!
//! Fields are addressed by their names in the parameter file (through serde, so any
//! number field of the form's section can be searched without a list to keep in step
//! with the structs).

use crate::error::{ControllerError, Result};
use crate::gait::{CrawlParams, GaitParams};

use super::{Form, TunedParams};

/// One field of a search box: its name in the form's section of the parameter file
/// (`residual.NAME` for the biped's shared residual gains) and its range, in the
/// field's own unit (see [`crate::FormParams`], [`crate::CrawlParams`],
/// [`crate::ResidualGains`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SearchField {
    /// Field name, e.g. `step_time`, `residual.vel_gain`, `max_speed`.
    pub name: String,
    /// Lower end of the range.
    pub lo: f64,
    /// Upper end of the range.
    pub hi: f64,
}

impl std::str::FromStr for SearchField {
    type Err = ControllerError;
    /// `NAME=LO..HI`, e.g. `max_speed=0.7..1.4`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = |why: &str| ControllerError::InvalidSettings {
            field: "search",
            reason: format!("`{s}`: {why} (expected NAME=LO..HI, e.g. max_speed=0.7..1.4)"),
        };
        let (name, range) = s.split_once('=').ok_or_else(|| bad("no `=`"))?;
        let (lo, hi) = range.split_once("..").ok_or_else(|| bad("no `..`"))?;
        let num = |v: &str| {
            v.trim()
                .parse::<f64>()
                .map_err(|_| bad(&format!("`{}` is not a number", v.trim())))
        };
        let (lo, hi) = (num(lo)?, num(hi)?);
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(bad(&format!(
                "the range must be finite with LO < HI, got {lo}..{hi} (to fix a field, set it \
                 in the --from file instead)"
            )));
        }
        let name = name.trim();
        if name.is_empty() {
            return Err(bad("no field name"));
        }
        Ok(Self {
            name: name.into(),
            lo,
            hi,
        })
    }
}

impl std::fmt::Display for SearchField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}..{}", self.name, self.lo, self.hi)
    }
}

/// Tuned fields with their search box (units of the field, see [`crate::FormParams`] and,
/// for `residual.*`, [`crate::ResidualGains`], which all forms share).
const TUNED: [(&str, f64, f64); 20] = [
    ("step_time", 0.25, 0.55),
    ("swing_height", 0.04, 0.16),
    ("pelvis_height", 0.80, 0.93),
    ("trunk_pitch", -0.15, 0.30),
    ("lean_per_speed", 0.0, 0.15),
    ("foot_fwd_gain", 0.05, 0.40),
    ("foot_err_gain", 0.0, 0.25),
    ("foot_width", 0.05, 0.14),
    ("foot_lat_gain", 0.0, 0.45),
    ("torso_kp", 200.0, 1500.0),
    ("torso_kd", 10.0, 150.0),
    ("stance_push", 0.0, 0.2),
    ("swing_comp", 0.0, 1.0),
    ("speed_ki", 0.0, 0.5),
    ("step_time_per_speed", 0.0, 0.15),
    ("push_err_gain", 0.0, 0.3),
    ("swing_lead", 0.0, 0.15),
    // The residual should only catch what the gait cannot do: its gains are tuned
    // with the gait, so the cost's residual term can push them down.
    ("residual.vel_gain", 0.0, 4.0),
    ("residual.height_gain", 0.0, 60.0),
    ("residual.height_damping", 0.0, 10.0),
];

/// Crouch-walk search box: a head at 0.8 m needs a low pelvis and a strong lean (the
/// spine carries part of it); the residual gains stay the walk's.
const TUNED_CROUCH: [(&str, f64, f64); 18] = [
    ("step_time", 0.25, 0.6),
    ("swing_height", 0.04, 0.14),
    ("pelvis_height", 0.45, 0.75),
    ("trunk_pitch", 0.0, 0.8),
    ("spine_pitch", 0.0, 1.0),
    ("foot_fwd_gain", 0.05, 0.40),
    ("foot_err_gain", 0.0, 0.25),
    ("foot_width", 0.05, 0.16),
    ("foot_lat_gain", 0.0, 0.45),
    ("torso_kp", 200.0, 1500.0),
    ("torso_kd", 10.0, 150.0),
    ("stance_push", 0.0, 0.2),
    ("swing_comp", 0.0, 1.0),
    ("speed_ki", 0.0, 0.5),
    ("lean_per_speed", 0.0, 0.15),
    ("step_time_per_speed", 0.0, 0.15),
    ("push_err_gain", 0.0, 0.3),
    ("swing_lead", 0.0, 0.15),
];

/// Number of shared residual gains at the end of [`TUNED`]: only the walk search moves
/// them (the run's search would change the walk's residual under it).
const RESIDUAL_FIELDS: usize = 3;

/// Crawl search box: the gait, its feedback and its residual gains, the fields the
/// hand-run evolution strategy behind the shipped `crawl.toml` searched (posture and
/// transitions stay as set by hand: a search on straight paths cannot see the 0.6 m
/// ceiling the posture is made for). Boxes keep `min_cycle` below `cycle`.
const TUNED_CRAWL: [(&str, f64, f64); 19] = [
    ("attitude_gain", 0.0, 1.5),
    ("height_gain_limbs", 0.0, 1.5),
    ("cycle", 0.66, 1.0),
    ("min_cycle", 0.4, 0.66),
    ("max_stride", 0.15, 0.45),
    ("duty", 0.6, 0.9),
    ("fast_duty", 0.5, 0.8),
    ("slip_gain", 0.0, 1.0),
    ("max_slip", 0.0, 0.6),
    ("vel_filter", 0.05, 1.0),
    ("place_gain", 0.0, 0.3),
    ("knee_lift", 0.03, 0.15),
    ("hand_lift", 0.03, 0.15),
    ("yaw_gain", 0.5, 4.0),
    ("max_accel", 0.5, 4.0),
    ("vel_gain", 0.0, 4.0),
    ("rot_gain", 0.0, 300.0),
    ("rot_damping", 0.0, 60.0),
    ("yaw_torque_gain", 0.0, 300.0),
];

/// The search box of a form.
fn tuned(form: Form) -> &'static [(&'static str, f64, f64)] {
    match form {
        Form::Crouch => &TUNED_CROUCH,
        Form::Walk => &TUNED,
        Form::Run => &TUNED[..TUNED.len() - RESIDUAL_FIELDS],
        Form::Crawl => &TUNED_CRAWL,
    }
}

/// The box a search of `form` moves: the form's built-in fields, with each of `extra`
/// re-bounding a field already there or appended after them (in the order given, so
/// a search with no extra fields is the search the built-in files were made with).
/// An extra field must be a number field of the form's section.
pub fn search_box(form: Form, extra: &[SearchField]) -> Result<Vec<SearchField>> {
    let mut fields: Vec<SearchField> = tuned(form)
        .iter()
        .map(|&(name, lo, hi)| SearchField {
            name: name.into(),
            lo,
            hi,
        })
        .collect();
    let mut table = file_table(&TunedParams::default(), form)?;
    for f in extra {
        if slot(&mut table, form, &f.name).is_none() {
            return Err(ControllerError::InvalidSettings {
                field: "search",
                reason: format!(
                    "`{}` is not a number field of the {} ({}); its number fields: {}",
                    f.name,
                    section_name(form),
                    file_name(form),
                    number_fields(&table, form).join(", ")
                ),
            });
        }
        match fields.iter_mut().find(|b| b.name == f.name) {
            Some(b) => *b = f.clone(),
            None => fields.push(f.clone()),
        }
    }
    Ok(fields)
}

/// `base` with the box's fields set from a candidate `x` in the normalised box
/// (clamped into it).
pub(super) fn decode(
    base: &TunedParams,
    form: Form,
    fields: &[SearchField],
    x: &[f64],
) -> Result<TunedParams> {
    let mut table = file_table(base, form)?;
    for (f, v) in fields.iter().zip(x) {
        let value = f.lo + (f.hi - f.lo) * v.clamp(0.0, 1.0);
        *slot(&mut table, form, &f.name).ok_or_else(|| unknown(f))? = toml::Value::Float(value);
    }
    with_file_table(base, form, table)
}

/// Where `base` lies in the normalised box (values outside clamped into it).
pub(super) fn encode(base: &TunedParams, form: Form, fields: &[SearchField]) -> Result<Vec<f64>> {
    let mut table = file_table(base, form)?;
    fields
        .iter()
        .map(|f| {
            let v = slot(&mut table, form, &f.name)
                .and_then(|v| v.as_float())
                .ok_or_else(|| unknown(f))?;
            Ok(((v - f.lo) / (f.hi - f.lo)).clamp(0.0, 1.0))
        })
        .collect()
}

/// `base` with the searched parameters of `form` (residual gains aside) copied from
/// the section of `like`: a search for the run can start from the tuned walk, whose
/// gait at run speeds falls less than an untuned run section. The biped's forms
/// only: the crawl shares no fields with them.
pub fn start_like(base: &TunedParams, form: Form, like: Form) -> Result<TunedParams> {
    let (Some(to), Some(from)) = (biped_section(form), biped_section(like)) else {
        return Err(ControllerError::InvalidSettings {
            field: "start_like",
            reason: format!(
                "{form:?} cannot start like {like:?}: the crawl has its own parameters \
                 (start-like works between walk, run and crouch)"
            ),
        });
    };
    let mut table = file_table(base, form)?;
    for &(name, _, _) in tuned(form) {
        if name.starts_with("residual.") {
            continue;
        }
        let v = table[from][name].clone();
        table[to][name] = v;
    }
    with_file_table(base, form, table)
}

fn unknown(f: &SearchField) -> ControllerError {
    ControllerError::InvalidSettings {
        field: "search",
        reason: format!("`{}` is not a number field", f.name),
    }
}

/// The biped form's section in `gait.toml`; `None` for the crawl.
fn biped_section(form: Form) -> Option<&'static str> {
    match form {
        Form::Walk => Some("walk"),
        Form::Run => Some("run"),
        Form::Crouch => Some("crouch"),
        Form::Crawl => None,
    }
}

fn section_name(form: Form) -> String {
    match biped_section(form) {
        Some(s) => format!("`[{s}]` section and `residual.*` gains"),
        None => "crawl's parameters".into(),
    }
}

fn file_name(form: Form) -> &'static str {
    match form {
        Form::Crawl => "crawl.toml",
        _ => "gait.toml",
    }
}

/// The parameter file `form`'s search changes, as a TOML table.
fn file_table(p: &TunedParams, form: Form) -> Result<toml::Table> {
    let table = match form {
        Form::Crawl => toml::Table::try_from(p.crawl),
        _ => toml::Table::try_from(p.gait),
    };
    table.map_err(|e| ControllerError::InvalidSettings {
        field: "params",
        reason: e.to_string(),
    })
}

/// `base` with `form`'s file replaced by `table`.
fn with_file_table(base: &TunedParams, form: Form, table: toml::Table) -> Result<TunedParams> {
    let bad = |e: toml::de::Error| ControllerError::InvalidSettings {
        field: "params",
        reason: e.to_string(),
    };
    let mut p = *base;
    match form {
        Form::Crawl => p.crawl = table.try_into::<CrawlParams>().map_err(bad)?,
        _ => p.gait = table.try_into::<GaitParams>().map_err(bad)?,
    }
    Ok(p)
}

/// The number field `name` of `form` in its file's table; `None` if there is none.
fn slot<'a>(table: &'a mut toml::Table, form: Form, name: &str) -> Option<&'a mut toml::Value> {
    let (section, key) = match (biped_section(form), name.strip_prefix("residual.")) {
        (Some(_), Some(gain)) => (Some("residual"), gain),
        (Some(s), None) => (Some(s), name),
        (None, _) => (None, name),
    };
    let table = match section {
        Some(s) => table.get_mut(s)?.as_table_mut()?,
        None => table,
    };
    table.get_mut(key).filter(|v| v.is_float())
}

/// Every number field `form`'s search could move, as `--search` names them.
fn number_fields(table: &toml::Table, form: Form) -> Vec<String> {
    let floats = |t: &toml::Table, prefix: &str| -> Vec<String> {
        t.iter()
            .filter(|(_, v)| v.is_float())
            .map(|(k, _)| format!("{prefix}{k}"))
            .collect()
    };
    match biped_section(form) {
        Some(s) => {
            let mut names = floats(table[s].as_table().expect("a gait section"), "");
            names.extend(floats(
                table["residual"].as_table().expect("the residual section"),
                "residual.",
            ));
            names
        }
        None => floats(table, ""),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_search_field_parses_and_bad_ones_say_the_form() {
        let f: SearchField = "max_speed=0.7..1.4".parse().unwrap();
        assert_eq!((f.name.as_str(), f.lo, f.hi), ("max_speed", 0.7, 1.4));
        assert_eq!(f.to_string(), "max_speed=0.7..1.4");
        for bad in [
            "max_speed",
            "max_speed=1",
            "max_speed=a..2",
            "x=2..1",
            "=0..1",
        ] {
            let e = bad.parse::<SearchField>().unwrap_err().to_string();
            assert!(e.contains("NAME=LO..HI"), "{bad}: {e}");
        }
    }

    #[test]
    fn the_built_in_box_round_trips_through_the_file() {
        for form in [Form::Walk, Form::Run, Form::Crouch, Form::Crawl] {
            let base = TunedParams::default();
            let fields = search_box(form, &[]).unwrap();
            assert_eq!(fields.len(), tuned(form).len());
            let x = encode(&base, form, &fields).unwrap();
            // Every built-in value lies inside its box, so decoding it is the start.
            let back = decode(&base, form, &fields, &x).unwrap();
            let again = encode(&back, form, &fields).unwrap();
            for (a, b) in x.iter().zip(&again) {
                assert!((a - b).abs() < 1e-12, "{form:?}: {a} vs {b}");
            }
            // A corner of the box sets every field to its lower end, nothing else.
            let low = decode(&base, form, &fields, &vec![0.0; fields.len()]).unwrap();
            let mut table = file_table(&low, form).unwrap();
            for f in &fields {
                let v = slot(&mut table, form, &f.name).unwrap().as_float().unwrap();
                assert_eq!(v, f.lo, "{form:?} {}", f.name);
            }
        }
    }

    #[test]
    fn an_extra_field_is_added_or_rebounds_one_and_unknown_ones_are_listed() {
        let crawl = search_box(Form::Crawl, &["max_speed=0.7..1.4".parse().unwrap()]).unwrap();
        assert_eq!(crawl.len(), tuned(Form::Crawl).len() + 1);
        assert_eq!(crawl.last().unwrap().name, "max_speed");
        let top = decode(
            &TunedParams::default(),
            Form::Crawl,
            &crawl,
            &vec![1.0; crawl.len()],
        )
        .unwrap();
        assert_eq!(top.crawl.max_speed, 1.4);

        let walk = search_box(Form::Walk, &["step_time=0.3..0.4".parse().unwrap()]).unwrap();
        assert_eq!(walk.len(), tuned(Form::Walk).len());
        assert_eq!((walk[0].lo, walk[0].hi), (0.3, 0.4));
        let rebounded = search_box(Form::Run, &["residual.rot_gain=50..300".parse().unwrap()])
            .unwrap()
            .pop()
            .unwrap();
        assert_eq!(rebounded.name, "residual.rot_gain");

        let e = search_box(Form::Crawl, &["max_sped=0.7..1.4".parse().unwrap()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_sped") && e.contains("max_speed"), "{e}");
        // A flag is not a number, and a biped field is not the crawl's.
        for bad in ["roll_first=0..1", "step_time=0.2..0.5"] {
            let e = search_box(Form::Crawl, &[bad.parse().unwrap()]).unwrap_err();
            assert!(e.to_string().contains("crawl.toml"), "{bad}: {e}");
        }
        let e = search_box(Form::Walk, &["max_speed=0.7..1.4".parse().unwrap()]).unwrap_err();
        assert!(e.to_string().contains("[walk]"), "{e}");
    }
}
