//! Gait parameters: one [`FormParams`] per locomotion form, loaded from a versioned
//! TOML file (`params/gait.toml`, built in), blended by requested height and speed.

use std::path::{Path, PathBuf};

use crate::error::{ControllerError, Result};

/// Version of the gait parameter file format.
pub const GAIT_PARAMS_VERSION: u32 = 1;

/// The built-in parameter file (MuJoCo's, and the one a caller that names no engine
/// gets).
pub const DEFAULT_GAIT_PARAMS: &str = include_str!("../../params/gait.toml");

/// The built-in parameter file under rapier: `gait.toml` with the crouch and the walk
/// re-tuned on the Table 2 strips in both engines with falls at 3 (its header has the
/// commands). It gains rapier's tours and loses MuJoCo's (RESULTS.md "Gait parameters",
/// session 25), so each engine gets its own.
pub const DEFAULT_RAPIER_GAIT_PARAMS: &str = include_str!("../../params/gait-rapier.toml");

/// A parameter file's TOML as `T`; `origin` names the source in errors.
pub(crate) fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, origin: &Path) -> Result<T> {
    toml::from_str(text).map_err(|source| ControllerError::Toml {
        path: origin.to_path_buf(),
        source,
    })
}

/// A parameter file's text.
pub(crate) fn read_params(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|source| ControllerError::Io {
        path: PathBuf::from(path),
        source,
    })
}

/// Parameters of one locomotion form (see `params/gait.toml` for units).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FormParams {
    /// Nominal head height of the form \[m\].
    pub head_height: f64,
    /// Nominal speed \[m/s\].
    pub speed: f64,
    /// Swing duration \[s\].
    pub step_time: f64,
    /// Swing-foot clearance \[m\].
    pub swing_height: f64,
    /// Pelvis origin height above ground \[m\].
    pub pelvis_height: f64,
    /// Pelvis pitch target, + forward \[rad\].
    pub trunk_pitch: f64,
    /// Extra pelvis pitch per m/s \[rad s/m\].
    pub lean_per_speed: f64,
    /// Spine pitch target \[rad\].
    pub spine_pitch: f64,
    /// Foot placement ahead of the root per m/s \[s\].
    pub foot_fwd_gain: f64,
    /// Foot placement per m/s of velocity error \[s\].
    pub foot_err_gain: f64,
    /// Half distance between the feet \[m\].
    pub foot_width: f64,
    /// Lateral placement per m/s of sideways velocity \[s\].
    pub foot_lat_gain: f64,
    /// Virtual torso stiffness \[N m/rad\].
    pub torso_kp: f64,
    /// Virtual torso damping \[N m s/rad\].
    pub torso_kd: f64,
    /// Stance hip yaw per rad of heading error \[-\].
    pub yaw_gain: f64,
    /// Arm swing amplitude \[rad\].
    pub arm_swing: f64,
    /// Stance-foot target moved back by this many seconds of desired velocity, so the
    /// stance hip pushes the pelvis forward \[s\].
    pub stance_push: f64,
    /// Fraction of the swing hip's torque the stance hip cancels (SIMBICON) \[-\].
    pub swing_comp: f64,
    /// Integral gain of forward speed error on foot placement (feet land closer while
    /// the walker lags) \[1/s\]. Absent in older files: 0.
    #[serde(default)]
    pub speed_ki: f64,
    /// Swing duration shortened per m/s of commanded speed above the form's `speed`
    /// (lengthened below it): faster walking takes quicker, not only longer, steps,
    /// which keeps the touchdown collision loss down \[s^2/m\]. Absent in older
    /// files: 0.
    #[serde(default)]
    pub step_time_per_speed: f64,
    /// Stance-foot target moved back by this many seconds of forward speed error
    /// (desired - actual, >= 0): the stance hip pushes harder while the walker lags,
    /// so the body, not the residual, catches up with the plan \[s\]. Absent in older
    /// files: 0.
    #[serde(default)]
    pub push_err_gain: f64,
    /// Extra time the swing foot follows its path ahead, beyond the servo's kd/kp: the
    /// leg's inertia makes it lag further, and a late foot lands short \[s\]. Absent
    /// in older files: 0.
    #[serde(default)]
    pub swing_lead: f64,
    /// Extra foot placement ahead of the centre of mass per m/s where the ground under
    /// the body is stepped or bumpy (stairs, gravel: the local height map's largest
    /// distance from its best-fit plane: none below 0.03 m, all of it from 0.06 m)
    /// \[s\]. A run that places its feet closer keeps
    /// up with 4 m/s on even ground but trips more on gravel; this gives the rough
    /// ground its longer steps back. Absent in older files: 0.
    #[serde(default)]
    pub rough_fwd_gain: f64,
    /// Swing foot placed further ahead per rad of forward pelvis pitch beyond the
    /// target \[m/rad\]: a body pitching forward in flight needs its next foot out in
    /// front. Absent in older files: 0.
    #[serde(default)]
    pub pitch_fwd_gain: f64,
    /// Extra sideways foot placement per m/s of sideways speed beyond 0.3 m/s while
    /// the heading error is large (none below `turn_from`, all of it from 0.6 rad
    /// above it) \[s\]:
    /// the swing foot on the side the body moves towards steps out under it (a capture
    /// step: at 1 m/s sideways a 0.7 m pelvis needs its foot ~0.27 m out,
    /// `foot_lat_gain` alone puts it 0.03-0.2 m), and the other one lands no further
    /// across than the pelvis (crossed legs collide). Where a leg starts by turning
    /// back, the plan leads off sideways and the body falls over its side at 1-1.4 m/s.
    /// (The same step at any heading, measured at 0.3 s: 200 MuJoCo tours 98 -> 93.)
    /// Absent in older files: 0 (off).
    #[serde(default)]
    pub side_step_gain: f64,
    /// Share of the plan's sideways velocity (pelvis heading frame) left out of the
    /// desired velocity while the heading error is large (none below `turn_from`, all
    /// of this share from 0.6 rad above it) \[-\]: a body turning back steps round
    /// instead of being pushed sideways by the residual. Absent in older files: 0 (off).
    #[serde(default)]
    pub turn_lat_share: f64,
    /// Heading error from which `turn_lat_share` and `side_step_gain` start to act
    /// \[rad\]: paths bend below it; a stumble on gravel or stairs can yaw the pelvis
    /// past it too. Absent in older files: 0.6 rad.
    #[serde(default = "default_turn_from")]
    pub turn_from: f64,
    /// Residual torque beyond `residual_torque_cap` for a body rolling or pitching back
    /// past `[residual] tilt_from` \[N m\]: all of it at twice that tilt, blended
    /// linearly between; a forward pitch is left to the steps. Per form because its
    /// effect is (RESULTS "Random 4-landmark scenes", session 30): at 60 N m in the walk
    /// and the run alone MuJoCo's tours gained nothing beyond noise, in all three forms
    /// ~2-4 points, the crouch-walk's. 60 in every form of both built-in files. Absent
    /// in older files: 0 (off).
    #[serde(default)]
    pub tilt_torque_extra: f64,
}

fn default_turn_from() -> f64 {
    0.6
}

impl FormParams {
    /// Linear blend `(1 - t) * a + t * b`, `t` clamped to \[0, 1\].
    pub fn lerp(&self, b: &FormParams, t: f64) -> FormParams {
        let t = t.clamp(0.0, 1.0);
        // Exact at the ends, so a form's own parameters come back unchanged.
        let l = |x: f64, y: f64| {
            if t == 1.0 { y } else { x + (y - x) * t }
        };
        FormParams {
            head_height: l(self.head_height, b.head_height),
            speed: l(self.speed, b.speed),
            step_time: l(self.step_time, b.step_time),
            swing_height: l(self.swing_height, b.swing_height),
            pelvis_height: l(self.pelvis_height, b.pelvis_height),
            trunk_pitch: l(self.trunk_pitch, b.trunk_pitch),
            lean_per_speed: l(self.lean_per_speed, b.lean_per_speed),
            spine_pitch: l(self.spine_pitch, b.spine_pitch),
            foot_fwd_gain: l(self.foot_fwd_gain, b.foot_fwd_gain),
            foot_err_gain: l(self.foot_err_gain, b.foot_err_gain),
            foot_width: l(self.foot_width, b.foot_width),
            foot_lat_gain: l(self.foot_lat_gain, b.foot_lat_gain),
            torso_kp: l(self.torso_kp, b.torso_kp),
            torso_kd: l(self.torso_kd, b.torso_kd),
            yaw_gain: l(self.yaw_gain, b.yaw_gain),
            arm_swing: l(self.arm_swing, b.arm_swing),
            stance_push: l(self.stance_push, b.stance_push),
            swing_comp: l(self.swing_comp, b.swing_comp),
            speed_ki: l(self.speed_ki, b.speed_ki),
            step_time_per_speed: l(self.step_time_per_speed, b.step_time_per_speed),
            push_err_gain: l(self.push_err_gain, b.push_err_gain),
            swing_lead: l(self.swing_lead, b.swing_lead),
            rough_fwd_gain: l(self.rough_fwd_gain, b.rough_fwd_gain),
            pitch_fwd_gain: l(self.pitch_fwd_gain, b.pitch_fwd_gain),
            side_step_gain: l(self.side_step_gain, b.side_step_gain),
            turn_lat_share: l(self.turn_lat_share, b.turn_lat_share),
            turn_from: l(self.turn_from, b.turn_from),
            tilt_torque_extra: l(self.tilt_torque_extra, b.tilt_torque_extra),
        }
    }

    fn validate(&self, form: &'static str) -> Result<()> {
        let bad = |field: &'static str, reason: &str| {
            Err(ControllerError::InvalidSettings {
                field,
                reason: format!("[{form}] {reason}"),
            })
        };
        if !(self.step_time > 0.05 && self.step_time < 2.0) {
            return bad("step_time", "must be in (0.05, 2) s");
        }
        if !(self.pelvis_height > 0.2 && self.pelvis_height < 1.0) {
            return bad("pelvis_height", "must be in (0.2, 1.0) m");
        }
        if !(self.head_height > 0.2 && self.head_height < 2.0) {
            return bad("head_height", "must be in (0.2, 2.0) m");
        }
        if !(self.swing_height >= 0.0 && self.swing_height < 0.4) {
            return bad("swing_height", "must be in [0, 0.4) m");
        }
        if !(self.step_time_per_speed >= 0.0 && self.step_time_per_speed < 0.5) {
            return bad("step_time_per_speed", "must be in [0, 0.5) s^2/m");
        }
        if !(self.swing_lead >= 0.0 && self.swing_lead < 0.3) {
            return bad("swing_lead", "must be in [0, 0.3) s");
        }
        if !(self.rough_fwd_gain >= 0.0 && self.rough_fwd_gain < 0.3) {
            return bad("rough_fwd_gain", "must be in [0, 0.3) s");
        }
        if !(self.pitch_fwd_gain >= 0.0 && self.pitch_fwd_gain < 2.0) {
            return bad("pitch_fwd_gain", "must be in [0, 2) m/rad");
        }
        if !(self.side_step_gain >= 0.0 && self.side_step_gain < 1.0) {
            return bad("side_step_gain", "must be in [0, 1) s");
        }
        if !(self.turn_lat_share >= 0.0 && self.turn_lat_share <= 1.0) {
            return bad("turn_lat_share", "must be in [0, 1]");
        }
        if !(self.turn_from >= 0.0 && self.turn_from < 3.0) {
            return bad("turn_from", "must be in [0, 3) rad");
        }
        if !(self.push_err_gain >= 0.0 && self.push_err_gain < 1.0) {
            return bad("push_err_gain", "must be in [0, 1) s");
        }
        if !(self.tilt_torque_extra >= 0.0 && self.tilt_torque_extra <= 200.0) {
            return bad("tilt_torque_extra", "must be in [0, 200] N m");
        }
        Ok(())
    }
}

/// Gains of the bounded residual root wrench.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResidualGains {
    /// Horizontal force per kg per m/s of velocity error \[1/s\].
    pub vel_gain: f64,
    /// Vertical force per kg per m of pelvis height error \[1/s^2\].
    pub height_gain: f64,
    /// Vertical force per kg per m/s of vertical velocity \[1/s\].
    pub height_damping: f64,
    /// Torque per rad of pelvis tilt \[N m/rad\].
    pub rot_gain: f64,
    /// Torque per rad/s of pelvis tilt rate \[N m s/rad\].
    pub rot_damping: f64,
    /// Tilt where the forms' `tilt_torque_extra` starts \[rad\]: roll and the pitch's
    /// error behind the form's lean together (their root sum square).
    #[serde(default = "tilt_from")]
    pub tilt_from: f64,
}

/// `tilt_from` of a parameter file without it \[rad\].
fn tilt_from() -> f64 {
    0.2
}

impl ResidualGains {
    /// Every gain finite and not negative; the tilt extra's start bounded.
    fn validate(&self) -> Result<()> {
        let fields = [
            ("vel_gain", self.vel_gain, f64::INFINITY),
            ("height_gain", self.height_gain, f64::INFINITY),
            ("height_damping", self.height_damping, f64::INFINITY),
            ("rot_gain", self.rot_gain, f64::INFINITY),
            ("rot_damping", self.rot_damping, f64::INFINITY),
            ("tilt_from", self.tilt_from, 1.5),
        ];
        for (field, v, hi) in fields {
            if !(v.is_finite() && (0.0..=hi).contains(&v)) {
                let allowed = if hi.is_infinite() {
                    "a finite number >= 0".to_string()
                } else {
                    format!("in [0, {hi}]")
                };
                return Err(ControllerError::InvalidSettings {
                    field,
                    reason: format!("[residual] must be {allowed}, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// The whole parameter file.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitParams {
    /// File format version ([`GAIT_PARAMS_VERSION`]).
    pub version: u32,
    /// Walking.
    pub walk: FormParams,
    /// Running.
    pub run: FormParams,
    /// Crouch-walking.
    pub crouch: FormParams,
    /// Residual wrench gains.
    pub residual: ResidualGains,
}

impl Default for GaitParams {
    fn default() -> Self {
        // The built-in file is tested to parse and validate.
        Self::from_toml(DEFAULT_GAIT_PARAMS, Path::new("<built-in gait.toml>"))
            .expect("built-in gait parameters are valid")
    }
}

impl GaitParams {
    /// The built-in parameters for a physics engine: `gait-rapier.toml` under rapier,
    /// `gait.toml` (the [`Default`]) under MuJoCo.
    pub fn built_in(backend: plamo_physics::BackendKind) -> Self {
        match backend {
            plamo_physics::BackendKind::Rapier => Self::from_toml(
                DEFAULT_RAPIER_GAIT_PARAMS,
                Path::new("<built-in gait-rapier.toml>"),
            )
            .expect("built-in gait parameters are valid"),
            plamo_physics::BackendKind::Mujoco => Self::default(),
        }
    }

    /// Parses and validates parameters; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let p: GaitParams = parse_toml(text, origin)?;
        p.validate()?;
        Ok(p)
    }

    /// Reads a parameter file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_toml(&read_params(path)?, path)
    }

    /// Checks the version and every form's ranges.
    pub fn validate(&self) -> Result<()> {
        if self.version != GAIT_PARAMS_VERSION {
            return Err(ControllerError::InvalidSettings {
                field: "version",
                reason: format!(
                    "gait parameter file version {} (this build reads {GAIT_PARAMS_VERSION})",
                    self.version
                ),
            });
        }
        self.walk.validate("walk")?;
        self.run.validate("run")?;
        self.crouch.validate("crouch")?;
        self.residual.validate()
    }

    /// The form for a requested head height above ground \[m\] and speed \[m/s\]:
    /// crouch and walk blended by height, then walk and run blended by speed.
    pub fn blend(&self, head_height: f64, speed: f64) -> FormParams {
        let upright = self.walk.lerp(
            &self.run,
            (speed - self.walk.speed) / (self.run.speed - self.walk.speed),
        );
        let t = (head_height - self.crouch.head_height)
            / (self.walk.head_height - self.crouch.head_height);
        self.crouch.lerp(&upright, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_engine_has_its_own_built_in_file() {
        use plamo_physics::BackendKind;
        let (rapier, mujoco) = (
            GaitParams::built_in(BackendKind::Rapier),
            GaitParams::built_in(BackendKind::Mujoco),
        );
        rapier.validate().unwrap();
        assert_eq!(mujoco, GaitParams::default());
        assert_ne!(rapier.crouch, mujoco.crouch);
        // The rapier file re-tuned the crouch and the walk; the run is MuJoCo's.
        assert_eq!(rapier.run, mujoco.run);
    }

    #[test]
    fn built_in_parameters_parse_and_blend() {
        let p = GaitParams::default();
        let w = p.blend(1.47, 1.0);
        assert_eq!(w, p.walk);
        assert_eq!(p.blend(1.47, 5.0), p.run);
        assert_eq!(p.blend(0.5, 0.5), p.crouch);
        let mid = p.blend(1.47, 0.5 * (p.walk.speed + p.run.speed));
        let (a, b) = (p.walk.step_time, p.run.step_time);
        assert!(mid.step_time > a.min(b) && mid.step_time < a.max(b));
    }

    #[test]
    fn bad_files_name_the_problem() {
        let e = GaitParams::from_toml(
            &DEFAULT_GAIT_PARAMS.replace("version = 1", "version = 9"),
            Path::new("x.toml"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("version 9"), "{e}");
        // One field out of range at a time: the message names it (or its section).
        type Spoil = fn(&mut GaitParams);
        let spoiled: [(Spoil, &str); 9] = [
            (|p| p.walk.step_time = 0.0, "[walk]"),
            (|p| p.residual.rot_gain = -1.0, "rot_gain"),
            (|p| p.residual.tilt_from = 2.0, "tilt_from"),
            (|p| p.run.rough_fwd_gain = -0.01, "rough_fwd_gain"),
            (|p| p.run.pitch_fwd_gain = -0.5, "pitch_fwd_gain"),
            (|p| p.crouch.side_step_gain = -0.1, "side_step_gain"),
            (|p| p.walk.turn_lat_share = 1.5, "turn_lat_share"),
            (|p| p.run.turn_from = -0.1, "turn_from"),
            (|p| p.walk.tilt_torque_extra = f64::NAN, "tilt_torque_extra"),
        ];
        for (spoil, field) in spoiled {
            let mut bad = GaitParams::default();
            spoil(&mut bad);
            let e = GaitParams::from_toml(&toml::to_string(&bad).unwrap(), Path::new("x.toml"))
                .unwrap_err();
            assert!(e.to_string().contains(field), "{field}: {e}");
        }
        // Files without the turn-back fields keep the old gait.
        let old: String = DEFAULT_GAIT_PARAMS
            .lines()
            .filter(|l| !l.starts_with("turn_"))
            .map(|l| format!("{l}\n"))
            .collect();
        let p = GaitParams::from_toml(&old, Path::new("old.toml")).unwrap();
        assert_eq!((p.crouch.turn_from, p.crouch.turn_lat_share), (0.6, 0.0));
        let e =
            GaitParams::from_toml("version = 1\n[walk]\nfoo = 1", Path::new("y.toml")).unwrap_err();
        assert!(e.to_string().contains("y.toml"), "{e}");
    }
}
