//! Controller settings: one flat struct, units and defaults side by side, validated.

use crate::error::{ControllerError, Result};

/// Standard gravity \[m/s^2\].
pub const GRAVITY: f64 = 9.81;

/// Settings of the controller component.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControllerSettings {
    /// Humanoid mass \[kg\], used to express residual forces as a fraction of body
    /// weight m*g. Default 69.4 (the MJCF humanoid); set it from the physics model.
    pub body_mass: f64,
    /// Cap on the residual root force, fraction of body weight m*g \[-\]. 0 disables
    /// the force. Default 0.25 (field notes: 0.25 stopped falls in walk).
    pub residual_force_cap: f64,
    /// Cap on the residual root torque \[N m\]. 0 disables the torque. Default 60.
    pub residual_torque_cap: f64,
    /// Head height drift below the requested height that counts as a fall \[m\]
    /// (ProtoMotions' path follower terminates at 0.5 m). Default 0.5.
    pub fall_height_drift: f64,
    /// Head height above the terrain below which the humanoid has fallen whatever
    /// was requested \[m\]. Default 0.2.
    pub fall_min_head_height: f64,
    /// Fastest rise of the height the fall rule holds a head to \[m/s\]: where the
    /// plan asks for a taller form (a crouch-walk's or a crawl's leg ends and a walk
    /// begins) the body needs time to stand up, so the bar rises no faster than the
    /// biped raises its head. Lower requests apply at once. Default 0.5.
    pub fall_rise_rate: f64,
    /// Whether the head's height is judged from the lower of the ground under it and
    /// the body's lowest point while the body is still up (`fall_up_pelvis`,
    /// `fall_up_roll`), as ProtoMotions measures it, rather than always from the
    /// ground under the head (`crate::fall_ground`). Default true (session 35); false
    /// replays older figures.
    pub fall_from_lowest_body: bool,
    /// Least pelvis height above the ground under it for a body still up \[m\].
    /// Default [`crate::fall_ground::UP_PELVIS`] (0.3).
    pub fall_up_pelvis: f64,
    /// Pelvis roll from which a body is no longer up \[rad\]. Default
    /// [`crate::fall_ground::UP_ROLL`] (0.6).
    pub fall_up_roll: f64,
}

impl Default for ControllerSettings {
    fn default() -> Self {
        Self {
            body_mass: 69.4,
            residual_force_cap: 0.25,
            residual_torque_cap: 60.0,
            fall_height_drift: 0.5,
            fall_min_head_height: 0.2,
            fall_rise_rate: 0.5,
            fall_from_lowest_body: true,
            fall_up_pelvis: crate::fall_ground::UP_PELVIS,
            fall_up_roll: crate::fall_ground::UP_ROLL,
        }
    }
}

impl ControllerSettings {
    /// Body weight m*g \[N\].
    pub fn body_weight(&self) -> f64 {
        self.body_mass * GRAVITY
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        let check = |ok: bool, field: &'static str, reason: &str| {
            if ok {
                Ok(())
            } else {
                Err(ControllerError::InvalidSettings {
                    field,
                    reason: reason.to_string(),
                })
            }
        };
        check(
            self.body_mass.is_finite() && self.body_mass > 0.0,
            "body_mass",
            "must be a positive mass in kg",
        )?;
        check(
            (0.0..=2.0).contains(&self.residual_force_cap),
            "residual_force_cap",
            "must be a fraction of body weight in [0, 2]",
        )?;
        check(
            self.residual_torque_cap.is_finite() && self.residual_torque_cap >= 0.0,
            "residual_torque_cap",
            "must be >= 0 N m",
        )?;
        check(
            self.fall_height_drift.is_finite() && self.fall_height_drift > 0.0,
            "fall_height_drift",
            "must be > 0 m",
        )?;
        check(
            self.fall_min_head_height.is_finite() && self.fall_min_head_height >= 0.0,
            "fall_min_head_height",
            "must be >= 0 m",
        )?;
        check(
            self.fall_rise_rate.is_finite() && self.fall_rise_rate > 0.0,
            "fall_rise_rate",
            "must be > 0 m/s",
        )?;
        check(
            self.fall_up_pelvis.is_finite() && self.fall_up_pelvis >= 0.0,
            "fall_up_pelvis",
            "must be >= 0 m",
        )?;
        check(
            self.fall_up_roll.is_finite() && self.fall_up_roll >= 0.0,
            "fall_up_roll",
            "must be >= 0 rad",
        )
    }

    /// Whether a head at `head_above_ground` \[m\] has fallen when the plan asks for
    /// `requested` \[m\].
    pub fn is_fallen(&self, head_above_ground: f64, requested: f64) -> bool {
        head_above_ground < self.fall_min_head_height
            || head_above_ground < requested - self.fall_height_drift
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_bad_values_name_the_field() {
        ControllerSettings::default().validate().unwrap();
        let s = ControllerSettings {
            residual_force_cap: -0.1,
            ..Default::default()
        };
        match s.validate() {
            Err(ControllerError::InvalidSettings { field, .. }) => {
                assert_eq!(field, "residual_force_cap")
            }
            other => panic!("{other:?}"),
        }
        let s: std::result::Result<ControllerSettings, _> = toml::from_str("body_mas = 3.0");
        assert!(s.is_err());
    }

    #[test]
    fn fall_rule() {
        let s = ControllerSettings::default();
        assert!(!s.is_fallen(1.4, 1.47));
        assert!(s.is_fallen(0.9, 1.47));
        assert!(!s.is_fallen(0.35, 0.4));
        assert!(s.is_fallen(0.15, 0.4));
    }
}
