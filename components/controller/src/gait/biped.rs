//! The biped gait of the model-based controller: a SIMBICON-style gait whose parameters ([`GaitParams`]) are blended by the
//! requested head height (crouch-walk <-> walk) and speed (walk <-> run):
//! - the plan's next waypoint (0.5 s ahead, relative to the head) gives the desired
//!   velocity (so position errors are corrected; rate-limited to [`MAX_ACCEL`] so a
//!   start from rest speeds up step by step; where the form asks for it, less of its
//!   sideways part while the heading error is large) and the heading error;
//! - the form's head height follows the plan at a bounded rate ([`MAX_HEIGHT_RATE`]);
//! - the swing foot follows a path from its lift-off point to a SIMBICON foot
//!   placement (ahead of the centre of mass by velocity, velocity error and an
//!   integral of the speed error, further on rough ground and while the pelvis pitches
//!   forward where the form asks for it, sideways by the lateral velocity, stepping
//!   out under a body that turns back and moves fast sideways where the form asks for
//!   it) by two-segment leg IK; the path is followed kd/kp ahead (the lag of a PD
//!   servo behind a moving target) plus the form's `swing_lead` (the leg's inertia
//!   adds to it); the swing is quicker at higher speed (`step_time_per_speed`);
//! - the gait is terrain-aware ([`Ground`]): the ground comes from the local height
//!   map where it reaches and, ahead of it, from the ground under the plan's waypoints;
//!   the sole lands on the highest ground under it; the swing clears the highest
//!   ground it sweeps, higher the more relief it passes (a tread nose, gravel); the
//!   pelvis leans with the slope ahead; the requested head height is the plan's head
//!   point above the ground under it, not under the root;
//! - legs switch at swing-foot touchdown (the swing foot as low as the stance foot,
//!   after half a step; 1.5 steps at most); the leg targets' jump at the switch is
//!   faded out over [`SWITCH_BLEND`];
//! - the stance leg holds the pelvis height above the ground under its sole by IK, and
//!   its hip adds virtual-torso torque from pelvis tilt error realised through the PD
//!   targets (offset = torque / kp) minus the swing hip's torque (SIMBICON); the stance
//!   hip yaw turns the pelvis towards the path; the stance foot's target sits behind
//!   the foot by the desired speed and the speed error (`stance_push`,
//!   `push_err_gain`), so the stance hip propels the body;
//! - a bounded residual root wrench (cap in [`ControllerSettings`]) helps with speed,
//!   height and tilt; it is part of the action and reported by the metrics.

use super::ik::{LegGeometry, leg_ik};
use super::map_plane::{MAP_HALF, MapPlane};
use super::params::GaitParams;
use super::plan_ground::PlanGround;

use plamo_interfaces::CONTROL_DT;
use plamo_physics::humanoid::{BODIES, JOINTS, joint_index};
use plamo_physics::{FEET, HEAD_RADIUS, NUM_BODIES, NUM_JOINTS};
use plamo_scenes::{LOCAL_MAP_SIDE, LOCAL_MAP_SPACING};

use super::{com_offset, mass_fractions, residual_force, residual_wrench};
use crate::math::{clamp_norm, ramp_past, smoothstep, sub3, wrap_angle};
use crate::observation::{Observation, WAYPOINT_SPACING};
use crate::policy::{Action, RootWrench};
use crate::settings::ControllerSettings;

/// Height of the ankle (foot body origin) above the sole \[m\].
const ANKLE_HEIGHT: f64 = 0.07;

/// Joint indices the gait drives, per leg (right, left) and for the upper body.
#[derive(Debug, Clone, Copy)]
struct Joints {
    hip: [[usize; 3]; 2],
    knee: [usize; 2],
    ankle: [[usize; 2]; 2],
    spine: [usize; 3],
    neck_y: usize,
    shoulder: [[usize; 2]; 2],
    elbow: [usize; 2],
}

fn idx(name: &str) -> usize {
    // Names below are the humanoid's own: checked by the unit test `joints_resolve`.
    joint_index(name).unwrap_or_else(|| panic!("humanoid has no joint `{name}`"))
}

impl Joints {
    fn resolve() -> Self {
        let side = ["right", "left"];
        Joints {
            hip: side.map(|s| ["x", "y", "z"].map(|a| idx(&format!("{s}_hip_{a}")))),
            knee: side.map(|s| idx(&format!("{s}_knee"))),
            ankle: side.map(|s| ["y", "x"].map(|a| idx(&format!("{s}_ankle_{a}")))),
            spine: ["x", "y", "z"].map(|a| idx(&format!("spine_{a}"))),
            neck_y: idx("neck_y"),
            shoulder: side.map(|s| ["x", "y"].map(|a| idx(&format!("{s}_shoulder_{a}")))),
            elbow: side.map(|s| idx(&format!("{s}_elbow"))),
        }
    }
}

/// The biped gait (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct BipedGait {
    params: GaitParams,
    settings: ControllerSettings,
    joints: Joints,
    legs: LegGeometry,
    /// Hip anchors in the pelvis frame (right, left) \[m\].
    hip_offset: [[f64; 3]; 2],
    hip_kp: f64,
    /// Body masses over the total mass, for the centre of mass \[-\].
    mass_fraction: [f64; NUM_BODIES],
    /// 0 = right foot in stance, 1 = left.
    stance: usize,
    phase: f64,
    swing_start_rel_stance: [f64; 3],
    started: bool,
    last_wrench: RootWrench,
    /// Leg targets of the previous action \[rad\] (for the cross-fade at a switch).
    last_targets: [f64; NUM_JOINTS],
    /// Target jump at the last leg switch, faded out over [`SWITCH_BLEND`] \[rad\].
    switch_offset: [f64; NUM_JOINTS],
    /// Rate-limited desired velocity, heading frame \[m/s\].
    v_cmd: [f64; 2],
    /// Rate-limited requested head height that selects the form \[m\].
    h_cmd: f64,
    /// Integral of the forward velocity error: the swing foot lands this much
    /// closer (when lagging) \[m\].
    foot_bias: f64,
    /// The swing foot's last target height relative to the root once its path had
    /// ended (the foot pressed down onto the ground it expects), else `None` \[m\].
    landing: Option<f64>,
}

/// Largest change of the desired velocity \[m/s^2\]. The plan's point moves at full
/// speed from the first instant: a slow ramp leaves the walker a distance behind that
/// it then has to catch up (speed^2 / 2a: 1.3 m at 2 m/s with 1.5 m/s^2).
const MAX_ACCEL: f64 = 2.5;

/// Largest forward speed error the stance push responds to \[m/s\].
const PUSH_ERR_MAX: f64 = 1.0;

/// The speed adjustment keeps the swing duration within these factors of the form's
/// `step_time` \[-\].
const STEP_TIME_RANGE: [f64; 2] = [0.5, 1.5];

/// Largest change of the requested head height that selects the form \[m/s\].
const MAX_HEIGHT_RATE: f64 = 0.5;

/// Bound of the integral foot-placement offset \[m\].
const FOOT_BIAS_MAX: f64 = 0.15;

/// Height map roughness (largest distance of a sample from the map's best-fit plane)
/// from which the form's `rough_fwd_gain` starts to act; it acts fully at twice it \[m\].
/// The crawl's `rough_step` default: gravel and treads are above it, a ramp is not.
const ROUGH_STEP: f64 = 0.03;

/// Sideways speed from which the form's `side_step_gain` acts \[m/s\]: a body pushed
/// sideways at a turn-back reaches 1-1.4 m/s.
const SIDE_STEP_FROM: f64 = 0.3;

/// Heading error over which the turn-back switches (`turn_lat_share`,
/// `side_step_gain`) fade in from the form's `turn_from` \[rad\].
const TURN_FADE: f64 = 0.6;

/// Swing-foot clearance above the stance foot's that counts as touchdown \[m\].
const TOUCHDOWN: f64 = 0.02;

/// How close above its path's end target a swing foot has landed \[m\] (the target
/// lies 0.02 m under the ground the gait expects). Stairs strips, 32 runs x 30 s at
/// 0.8-1.2 m/s square and at 30-90 degrees, falls per run summed over the 15 cells:
/// 7.1 without, 3.3-3.9 with 0.05-0.10; flat ground unchanged. MuJoCo random tours
/// (never used to choose it): seeds 4000-4999 909 -> 944 of 1000, 0-999 918 -> 931;
/// crouch-walk first falls on slopes 17 -> 2 over the two.
const ARRIVED: f64 = 0.08;

/// Time over which the target jump at a leg switch is faded out \[s\].
const SWITCH_BLEND: f64 = 0.1;

/// Free height the head's sphere keeps under a top the plan passes beneath \[m\].
const TOP_CLEARANCE: f64 = 0.03;

/// Most the pelvis goes below its form's height to keep the head under a top \[m\].
const TOP_DROP_MAX: f64 = 0.2;

impl BipedGait {
    /// A gait with validated parameters and settings.
    pub(crate) fn new(params: GaitParams, settings: ControllerSettings) -> Self {
        let joints = Joints::resolve();
        let right_thigh = &BODIES[plamo_physics::humanoid::body_index("right_thigh").unwrap_or(9)];
        let left_thigh = &BODIES[plamo_physics::humanoid::body_index("left_thigh").unwrap_or(12)];
        let shin = &BODIES[plamo_physics::humanoid::body_index("right_shin").unwrap_or(10)];
        let foot = &BODIES[FEET[0]];
        let legs = LegGeometry {
            thigh: -shin.offset[2],
            shin: -foot.offset[2],
        };
        Self {
            params,
            settings,
            mass_fraction: mass_fractions(),
            hip_offset: [right_thigh.offset, left_thigh.offset],
            hip_kp: JOINTS[joints.hip[0][1]].kp,
            joints,
            legs,
            stance: 0,
            phase: 0.0,
            swing_start_rel_stance: [0.0; 3],
            started: false,
            last_wrench: RootWrench::default(),
            last_targets: [0.0; NUM_JOINTS],
            switch_offset: [0.0; NUM_JOINTS],
            v_cmd: [0.0; 2],
            foot_bias: 0.0,
            h_cmd: 0.0,
            landing: None,
        }
    }

    /// The parameters in use.
    pub(crate) fn params(&self) -> &GaitParams {
        &self.params
    }

    /// The residual wrench of the last action (world frame).
    pub(crate) fn last_wrench(&self) -> RootWrench {
        self.last_wrench
    }
}

/// Sole of the foot along its length, from the ankle: heel and toe \[m\] (the
/// humanoid's foot box).
const SOLE: [f64; 2] = [-0.065, 0.155];

/// Points along the sole where the ground is sampled, from the ankle \[m\].
const SOLE_SAMPLES: [f64; 5] = [SOLE[0], 0.0, 0.05, 0.10, SOLE[1]];

/// Extra swing clearance per metre of terrain relief the sole passes over (the
/// highest ground it sweeps above the plane of the local slope through the lower of
/// its take-off and landing ground) \[-\].
/// Generous on purpose: a higher knee lift shortens the swinging leg, so it also comes
/// through quicker, and a toe that clears a nose or a gravel bump by a few centimetres
/// still trips when the foot pitches. On flat ground it adds nothing.
const RELIEF_LIFT: f64 = 4.0;

/// Largest swing clearance the relief raises it to \[m\]: above it the swing foot
/// would be pulled towards the pelvis.
const SWING_HEIGHT_MAX: f64 = 0.35;

/// Pelvis pitch per unit slope of the ground ahead (rise over run, + up) \[rad\]:
/// leaning into a climb and back on a descent keeps the centre of mass over the feet.
const LEAN_PER_SLOPE: f64 = 0.3;

/// How far ahead the slope that sets the lean is measured \[m\].
const SLOPE_SPAN: f64 = 0.8;

/// The ground the gait sees, heading frame, heights relative to the ground under the
/// root: the local height map (bilinear) where it reaches, ahead of it the ground under
/// the plan's waypoints, interpolated along the heading.
struct Ground<'a> {
    map: &'a [f64],
    plan: PlanGround,
}

impl<'a> Ground<'a> {
    fn new(obs: &'a Observation) -> Self {
        Self {
            map: &obs.height_map,
            plan: PlanGround::new(obs, false),
        }
    }

    /// Bilinear height map value, clamped to the map's extent.
    fn map_at(&self, x: f64, y: f64) -> f64 {
        let last = (LOCAL_MAP_SIDE - 1) as f64;
        let fr = ((x + MAP_HALF) / LOCAL_MAP_SPACING).clamp(0.0, last);
        let fc = ((y + MAP_HALF) / LOCAL_MAP_SPACING).clamp(0.0, last);
        let (r0, c0) = (
            (fr.floor() as usize).min(LOCAL_MAP_SIDE - 2),
            (fc.floor() as usize).min(LOCAL_MAP_SIDE - 2),
        );
        let (tr, tc) = (fr - r0 as f64, fc - c0 as f64);
        let v = |r: usize, c: usize| self.map[r * LOCAL_MAP_SIDE + c];
        let a = v(r0, c0) + (v(r0, c0 + 1) - v(r0, c0)) * tc;
        let b = v(r0 + 1, c0) + (v(r0 + 1, c0 + 1) - v(r0 + 1, c0)) * tc;
        a + (b - a) * tr
    }

    /// Ground height at a heading-frame point.
    fn at(&self, x: f64, y: f64) -> f64 {
        self.plan.extend(x, self.map_at(x, y))
    }

    /// Highest ground under a sole whose ankle is at (x, y): what the foot rests on.
    fn under_sole(&self, x: f64, y: f64) -> f64 {
        SOLE_SAMPLES
            .iter()
            .map(|d| self.at(x + d, y))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Mean ground under a sole whose ankle is at (x, y): the level a stance foot
    /// stands at once it has settled (on a slope the highest point, its toe, would
    /// lift the pelvis and cost residual force).
    fn mean_under_sole(&self, x: f64, y: f64) -> f64 {
        SOLE_SAMPLES.iter().map(|d| self.at(x + d, y)).sum::<f64>() / SOLE_SAMPLES.len() as f64
    }

    /// Least-squares slope (rise over run, forward) of the height map's row means: the
    /// ramp under the feet, with gravel and tread noses averaged out.
    fn map_slope(&self) -> f64 {
        MapPlane::fit(self.map).forward
    }

    /// Share of rough ground under the body, 0-1: the height map's largest distance from
    /// its least-squares plane, from [`ROUGH_STEP`] (0) to twice it (1).
    fn rough_share(&self) -> f64 {
        MapPlane::rough_share(self.map, ROUGH_STEP)
    }

    /// Highest ground a sole sweeps from ankle point `a` to `b` above the plane of
    /// `slope` through the lower of their grounds `ga`, `gb` (0 if none is above).
    fn relief(&self, a: f64, ga: f64, b: f64, gb: f64, y: f64, slope: f64) -> f64 {
        let (xr, gr) = if ga <= gb { (a, ga) } else { (b, gb) };
        let (lo, hi) = (a.min(b) + SOLE[0], a.max(b) + SOLE[1]);
        let n = ((hi - lo) / 0.05).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| {
                let x = lo + (hi - lo) * i as f64 / n as f64;
                self.at(x, y) - gr - slope * (x - xr)
            })
            .fold(0.0, f64::max)
    }

    /// Highest ground a sole sweeps moving from ankle point `a` to `b` (forward).
    fn swept(&self, a: f64, b: f64, y: f64) -> f64 {
        let (lo, hi) = (a.min(b) + SOLE[0], a.max(b) + SOLE[1]);
        let n = ((hi - lo) / 0.05).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| self.at(lo + (hi - lo) * i as f64 / n as f64, y))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// How much of a turn-back a heading error \[rad\] is, 0-1: none below `from` \[rad\]
/// (paths bend), all of it from `from` + [`TURN_FADE`] (the plan leads off sideways or
/// backwards), smooth in between.
fn turn_weight(heading_err: f64, from: f64) -> f64 {
    smoothstep((heading_err.abs() - from) / TURN_FADE)
}

/// The swing foot's sideways target `y` \[m\] (heading frame, from the root) for a body
/// moving sideways at `vy` \[m/s\], swing leg on side `side` (-1 right, +1 left): beyond
/// [`SIDE_STEP_FROM`] the foot on the side of travel steps out `gain` \[s\] per m/s more,
/// the other one lands no further across than the pelvis.
fn side_step(y: f64, vy: f64, side: f64, gain: f64) -> f64 {
    let excess = vy.abs() - SIDE_STEP_FROM;
    if gain <= 0.0 || excess <= 0.0 {
        return y;
    }
    if side == vy.signum() {
        y + side * gain * excess
    } else if side * y < 0.0 {
        0.0
    } else {
        y
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl BipedGait {
    /// PD targets and residual wrench for one control step (layout checked by the
    /// caller).
    pub(crate) fn act(&mut self, obs: &Observation, out: &mut Action) {
        let j = self.joints;
        // Pelvis frame axes in the heading frame.
        let r = obs.root_rotation;
        let fwd = [r[0], r[1], r[2]];
        let left = [r[3], r[4], r[5]];
        let up = [
            fwd[1] * left[2] - fwd[2] * left[1],
            fwd[2] * left[0] - fwd[0] * left[2],
            fwd[0] * left[1] - fwd[1] * left[0],
        ];
        let pitch = (-fwd[2]).clamp(-1.0, 1.0).asin();
        let roll = left[2].clamp(-1.0, 1.0).asin();
        let [wx, wy, wz] = obs.root_ang_vel;
        let [vx, vy, vz] = obs.root_lin_vel;

        // What the plan asks for.
        let wp0 = obs.waypoints[0];
        let wp1 = obs.waypoints[1];
        let speed = obs.waypoint_speeds[0].max(0.0);
        let vmax = 1.15 * speed + 0.2;
        let v_plan = clamp_norm(
            [wp0[0] / WAYPOINT_SPACING, wp0[1] / WAYPOINT_SPACING, 0.0],
            vmax,
        );
        // Rate-limited desired velocity: a start from rest accelerates step by step.
        if !self.started {
            self.v_cmd = [vx, vy];
        }
        let dv_max = MAX_ACCEL * CONTROL_DT;
        for (c, p) in self.v_cmd.iter_mut().zip(v_plan) {
            *c += (p - *c).clamp(-dv_max, dv_max);
        }
        let mut v_des = [self.v_cmd[0], self.v_cmd[1], 0.0];

        let heading_err = if wp1[0].hypot(wp1[1]) > 0.2 {
            wrap_angle(wp1[1].atan2(wp1[0]))
        } else {
            0.0
        };
        let ground = Ground::new(obs);
        let head_above_ground = obs.root_height + obs.head_pos[2];
        // The plan's point lies the requested height above the ground under it, not
        // under the root: on stairs that is a tread or three away.
        let head_des = head_above_ground + wp0[2] - obs.waypoint_ground[0];
        // The form follows the requested height at a bounded rate: dropping into a
        // crouch at once would let the body fall onto bent knees.
        if !self.started {
            self.h_cmd = head_above_ground;
        }
        let dh_max = MAX_HEIGHT_RATE * CONTROL_DT;
        self.h_cmd += (head_des - self.h_cmd).clamp(-dh_max, dh_max);
        let form = self.params.blend(self.h_cmd, speed);
        let turn = turn_weight(heading_err, form.turn_from);
        if form.turn_lat_share > 0.0 {
            v_des[1] *= 1.0 - form.turn_lat_share * turn;
        }
        // Quicker steps as the commanded speed rises (the rate-limited command, so the
        // cadence rises with the speed during a start).
        let step_time = (form.step_time
            - form.step_time_per_speed * (self.v_cmd[0].max(0.0) - form.speed))
            .clamp(
                STEP_TIME_RANGE[0] * form.step_time,
                STEP_TIME_RANGE[1] * form.step_time,
            );
        let slope = (ground.at(SLOPE_SPAN, 0.0) - ground.at(0.0, 0.0)) / SLOPE_SPAN;
        let pitch_des = form.trunk_pitch + form.lean_per_speed * speed + LEAN_PER_SLOPE * slope;
        // + forward of the form's lean.
        let pitch_err = pitch - pitch_des;
        // Under a top the plan passes beneath (its head, over the ground under the root
        // as the headroom is, leaves the head's sphere under it), the pelvis goes down
        // as far as the head rides too high: the crouch holds its head about 0.1 m over
        // the plan's, all of the planner's margin under a 0.9 m top, and bodies stood
        // wedged against such a top's edge until the tour timed out (MuJoCo tours, seeds
        // 0-999 and 4000-4999: collisions 15 -> 6, successes 1875 -> 1886).
        let plan_head = head_above_ground + wp0[2];
        let pelvis_des = if plan_head + HEAD_RADIUS < obs.headroom + TOP_CLEARANCE {
            let fits = obs.headroom - HEAD_RADIUS - TOP_CLEARANCE - obs.head_pos[2];
            form.pelvis_height
                .min(fits)
                .max(form.pelvis_height - TOP_DROP_MAX)
        } else {
            form.pelvis_height
        };
        // Integral speed control: a walker that lags (the engines differ in how far a
        // step carries) places its feet closer until the speed matches.
        self.foot_bias = (self.foot_bias + form.speed_ki * (v_des[0] - vx) * CONTROL_DT)
            .clamp(-FOOT_BIAS_MAX, FOOT_BIAS_MAX);

        // Gait phase and touchdown-triggered leg switch.
        let feet = [obs.body_pos[FEET[0]], obs.body_pos[FEET[1]]];
        let swing = 1 - self.stance;
        let mut switched = false;
        if !self.started {
            self.started = true;
            // First swing: the foot on the side the body drifts towards stays down.
            self.stance = if vy > 0.0 { 1 } else { 0 };
            self.phase = 0.0;
            let sw = 1 - self.stance;
            self.swing_start_rel_stance = sub3(feet[sw], feet[self.stance]);
        } else {
            self.phase += CONTROL_DT;
            // Clearance relative to the stance foot's: the ankle's resting height
            // differs by engine (contact softness) and by how the foot lands.
            let clearance = |f: [f64; 3]| obs.root_height + f[2] - ground.under_sole(f[0], f[1]);
            let rest = clearance(feet[self.stance]).min(ANKLE_HEIGHT + 0.03);
            // A foot at the end of its path that has come down to its target has landed,
            // whatever the map says under it: on a tread's edge the map's bilinear
            // ground reads up to half a riser low, and a swing kept going there loads
            // the foot while the stance leg straightens off the ground.
            let arrived = self.landing.is_some_and(|z| feet[swing][2] < z + ARRIVED);
            let touchdown = self.phase > 0.5 * step_time
                && (clearance(feet[swing]) < rest + TOUCHDOWN || arrived);
            if touchdown || self.phase > 1.5 * step_time {
                self.stance = swing;
                self.phase = 0.0;
                switched = true;
                self.swing_start_rel_stance = sub3(feet[1 - self.stance], feet[self.stance]);
            }
        }
        let stance = self.stance;
        let swing = 1 - stance;
        let side = |leg: usize| if leg == 0 { -1.0 } else { 1.0 };

        // Swing foot target (heading frame, relative to the root).
        // The PD servo lags a moving target by kd/kp: follow the path that far ahead.
        let lead = JOINTS[j.hip[0][1]].kd / self.hip_kp + form.swing_lead;
        let s_lin = ((self.phase + lead) / step_time).min(1.0);
        let s = smoothstep(s_lin);
        // Forward placement is measured from the centre of mass (body origins weighted
        // by body mass): a leaning or crouching trunk carries it ahead of the pelvis.
        let com_x = com_offset(&self.mass_fraction, obs)[0];
        let final_y = side_step(
            side(swing) * form.foot_width
                + form.foot_lat_gain * vy
                + form.foot_err_gain * (vy - v_des[1]),
            vy,
            side(swing),
            form.side_step_gain * turn,
        );
        // Rough ground takes the form's longer steps back (`rough_fwd_gain`); the map
        // is only scanned where the form asks for it.
        let fwd_gain = if form.rough_fwd_gain > 0.0 {
            form.foot_fwd_gain + form.rough_fwd_gain * ground.rough_share()
        } else {
            form.foot_fwd_gain
        };
        let final_xy = [
            com_x + fwd_gain * vx + form.foot_err_gain * (vx - v_des[0]) - self.foot_bias
                + form.pitch_fwd_gain * pitch_err.max(0.0),
            final_y,
        ];
        let start = [
            feet[stance][0] + self.swing_start_rel_stance[0],
            feet[stance][1] + self.swing_start_rel_stance[1],
        ];
        let sx = start[0] + (final_xy[0] - start[0]) * s;
        let sy = start[1] + (final_xy[1] - start[1]) * s;
        // The sole lands on the highest ground under it (the height map's samples are
        // 0.1 m apart, a sole 0.22 m long) and clears what it still has to pass over (a
        // tread nose, a bump) from where it is: the foot lags its path.
        let ground_land = ground.under_sole(final_xy[0], final_xy[1]);
        let foot_x = sx.min(feet[swing][0]);
        let ground_swing = ground.swept(foot_x, final_xy[0], sy).max(ground_land);
        let st = feet[stance];
        let ground_stance = ground.mean_under_sole(st[0], st[1]);
        // Relief above the plane of the local slope: a ramp needs no extra lift, a tread
        // nose or a bump does.
        let relief = ground.relief(
            foot_x,
            ground.under_sole(foot_x, sy).min(ground_stance),
            final_xy[0],
            ground_land,
            sy,
            ground.map_slope(),
        );
        let lift = if s_lin < 1.0 {
            (form.swing_height + RELIEF_LIFT * relief).min(SWING_HEIGHT_MAX.max(form.swing_height))
                * (std::f64::consts::PI * s_lin).sin()
        } else {
            -0.02
        };
        let swing_target = [
            sx,
            sy,
            -obs.root_height + ground_swing + ANKLE_HEIGHT + lift,
        ];
        self.landing = (s_lin >= 1.0).then_some(swing_target[2]);

        // Stance foot target: where it is, with the pelvis at the desired height.
        // The stance hip pushes with the desired speed and, while the walker lags,
        // with the speed error (bounded: a target far behind the foot runs the stance leg
        // out of reach and the pelvis sinks).
        let push_err = (v_des[0] - vx).clamp(0.0, PUSH_ERR_MAX);
        let stance_target = [
            st[0] - form.stance_push * v_des[0] - form.push_err_gain * push_err,
            st[1] - form.stance_push * v_des[1],
            -pelvis_des + ground_stance + ANKLE_HEIGHT,
        ];

        let targets = &mut out.pd_targets;
        targets.clear();
        targets.resize(NUM_JOINTS, 0.0);
        for (leg, target) in [(swing, swing_target), (stance, stance_target)] {
            let o = self.hip_offset[leg];
            let hip = [
                fwd[0] * o[0] + left[0] * o[1] + up[0] * o[2],
                fwd[1] * o[0] + left[1] * o[1] + up[1] * o[2],
                fwd[2] * o[0] + left[2] * o[1] + up[2] * o[2],
            ];
            let rel = sub3(target, hip);
            let p = [dot(rel, fwd), dot(rel, left), dot(rel, up)];
            let [hx_ik, hy_ik, knee] = leg_ik(&self.legs, p);
            let (mut hx, mut hy, mut hz) = (hx_ik, hy_ik, 0.0);
            if leg == stance {
                // Virtual torso control through the stance hip's PD offset, plus the
                // reaction of the swing hip's torque (SIMBICON: the stance hip takes
                // -torso - swing torque).
                let sw_torque = |axis: usize, target: f64| {
                    let ji = j.hip[swing][axis];
                    let jd = &JOINTS[ji];
                    (jd.kp * (target - obs.joint_pos[ji]) - jd.kd * obs.joint_vel[ji])
                        .clamp(-jd.max_torque, jd.max_torque)
                };
                let comp = form.swing_comp;
                hy += (form.torso_kp * pitch_err + form.torso_kd * wy
                    - comp * sw_torque(1, targets[j.hip[swing][1]]))
                    / self.hip_kp;
                hx += (form.torso_kp * roll + form.torso_kd * wx
                    - comp * sw_torque(0, targets[j.hip[swing][0]]))
                    / self.hip_kp;
                hz = (-form.yaw_gain * heading_err).clamp(-0.4, 0.4);
            }
            targets[j.hip[leg][0]] = hx;
            targets[j.hip[leg][1]] = hy;
            targets[j.hip[leg][2]] = hz;
            targets[j.knee[leg]] = knee;
            targets[j.ankle[leg][0]] = -(pitch_des + hy_ik + knee);
            targets[j.ankle[leg][1]] = -hx_ik;
        }
        // Cross-fade the legs' target jump at a switch.
        let legs_joints = [j.hip[0], j.hip[1]]
            .into_iter()
            .flatten()
            .chain(j.knee)
            .chain(j.ankle[0])
            .chain(j.ankle[1]);
        let fade = (1.0 - self.phase / SWITCH_BLEND).max(0.0);
        for ji in legs_joints {
            if switched {
                self.switch_offset[ji] = self.last_targets[ji] - targets[ji];
            }
            targets[ji] += fade * self.switch_offset[ji];
            self.last_targets[ji] = targets[ji];
        }
        // Upper body: spine pitch from the form, head kept level, arms swinging.
        targets[j.spine[1]] = form.spine_pitch;
        targets[j.neck_y] = -(pitch_des + form.spine_pitch) * 0.8;
        let swing_phase = if stance == 0 { 1.0 } else { -1.0 } * (2.0 * s - 1.0);
        for arm in 0..2 {
            targets[j.shoulder[arm][0]] = side(arm) * 0.15;
            targets[j.shoulder[arm][1]] = side(arm) * form.arm_swing * swing_phase;
            targets[j.elbow[arm]] = -0.4;
        }

        // Bounded residual root wrench, heading frame then world.
        let m = self.settings.body_mass;
        let g = &self.params.residual;
        let force = residual_force(
            m,
            g.vel_gain,
            [v_des[0] - vx, v_des[1] - vy],
            g.height_gain,
            pelvis_des - (obs.root_height - ground_stance),
            g.height_damping,
            vz,
        );
        let torque = [
            -(g.rot_gain * roll + g.rot_damping * wx),
            -(g.rot_gain * pitch_err + g.rot_damping * wy),
            g.rot_gain * 0.2 * heading_err - g.rot_damping * wz,
        ];
        // A body tilting past `tilt_from` sideways or backwards gets its form's extra on
        // top of the cap; a forward pitch is left to the steps (foot placement catches
        // it: `pitch_fwd_gain`), which can do nothing for the other two.
        let lean = ramp_past(roll.hypot(pitch_err.min(0.0)), g.tilt_from);
        let cap = self.settings.residual_torque_cap + lean * form.tilt_torque_extra;
        self.last_wrench = residual_wrench(&self.settings, cap, obs.heading, force, torque, out);
    }

    pub(crate) fn reset(&mut self) {
        self.started = false;
        self.phase = 0.0;
        self.switch_offset = [0.0; NUM_JOINTS];
        self.foot_bias = 0.0;
        self.landing = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::map_plane::map_coord;
    use crate::math::norm3;

    #[test]
    fn joints_resolve() {
        let j = Joints::resolve();
        assert_ne!(j.hip[0][1], j.hip[1][1]);
        let c = BipedGait::new(GaitParams::default(), ControllerSettings::default());
        assert!((c.legs.thigh - 0.41).abs() < 0.05 && (c.legs.shin - 0.39).abs() < 0.05);
    }

    #[test]
    fn a_body_tilting_sideways_or_back_gets_its_forms_extra_residual_torque() {
        // The residual torque's norm for a body standing rotated by `rot` (the
        // observation's two pelvis axes) with its head `head` \[m\] above the ground
        // (1.47: walk or run, 0.8: crouch-walk), with a tilt gain that asks for more
        // than any cap; the walk and the run get `upright` \[N m\] of extra, the crouch
        // `crouch`.
        let torque = |upright: f64, crouch: f64, rot: [f64; 6], head: f64| {
            let mut p = GaitParams::default();
            p.residual.rot_gain = 1000.0;
            p.walk.tilt_torque_extra = upright;
            p.run.tilt_torque_extra = upright;
            p.crouch.tilt_torque_extra = crouch;
            p.residual.tilt_from = 0.2;
            let mut gait = BipedGait::new(p, ControllerSettings::default());
            let mut obs = stepped(0.0, 10.0, 0.0);
            obs.root_height = 0.5;
            obs.head_pos = [0.0, 0.0, head - obs.root_height];
            obs.root_rotation = rot;
            gait.act(&obs, &mut Action::default());
            norm3(gait.last_wrench().torque)
        };
        // Left side up by `a`; nose down (forward, the walk's lean is -0.15) by `a`.
        let rolled = |a: f64| [1.0, 0.0, 0.0, 0.0, a.cos(), a.sin()];
        let pitched = |a: f64| [a.cos(), 0.0, -a.sin(), 0.0, 1.0, 0.0];
        let cap = ControllerSettings::default().residual_torque_cap;
        // Past twice `tilt_from`: all of it; between: part of it; below (the tilt
        // counts the pitch's error behind the form's lean too): none, bit for bit.
        assert!((torque(0.0, 0.0, rolled(0.5), 1.47) - cap).abs() < 1e-9);
        assert!((torque(60.0, 0.0, rolled(0.5), 1.47) - (cap + 60.0)).abs() < 1e-9);
        let part = torque(60.0, 0.0, rolled(0.3), 1.47);
        assert!(part > cap + 1.0 && part < cap + 59.0, "{part}");
        let small = rolled(0.05);
        assert_eq!(
            torque(60.0, 0.0, small, 1.47),
            torque(0.0, 0.0, small, 1.47)
        );
        // Pitched back: all of it; pitched forward as far: none (the steps catch it).
        assert!((torque(60.0, 0.0, pitched(-0.8), 1.47) - (cap + 60.0)).abs() < 1e-9);
        assert!((torque(60.0, 0.0, pitched(0.6), 1.47) - cap).abs() < 1e-9);
        // The crouch-walk gets its own form's extra, not the walk's.
        assert!((torque(60.0, 0.0, rolled(0.5), 0.8) - cap).abs() < 1e-9);
        assert!((torque(0.0, 30.0, rolled(0.5), 0.8) - (cap + 30.0)).abs() < 1e-9);
    }

    /// An observation whose map rises by `step` \[m\] from `x0` \[m\] ahead of the root,
    /// and whose first waypoint lies 1.5 m ahead over ground `g_wp`.
    fn stepped(step: f64, x0: f64, g_wp: f64) -> Observation {
        let mut obs = Observation::new(crate::ModelBasedController::LAYOUT);
        let half = (LOCAL_MAP_SIDE as f64 - 1.0) / 2.0;
        for r in 0..LOCAL_MAP_SIDE {
            let x = (r as f64 - half) * LOCAL_MAP_SPACING;
            for c in 0..LOCAL_MAP_SIDE {
                obs.height_map[r * LOCAL_MAP_SIDE + c] = if x >= x0 { step } else { 0.0 };
            }
        }
        obs.head_pos = [0.0, 0.0, 0.6];
        for (i, w) in obs.waypoints.iter_mut().enumerate() {
            *w = [1.5 * (i + 1) as f64, 0.0, 0.0];
        }
        obs.waypoint_ground = [g_wp; crate::observation::NUM_WAYPOINTS];
        obs
    }

    #[test]
    fn ground_ahead_comes_from_the_map_then_the_plan() {
        let obs = stepped(0.12, 0.15, 0.36);
        let g = Ground::new(&obs);
        assert_eq!(g.at(-0.2, 0.0), 0.0);
        assert!((g.at(0.3, 0.1) - 0.12).abs() < 1e-12);
        // Beyond the map (0.35 m) towards the first waypoint (1.5 m, 0.36 m).
        let mid = 0.5 * (MAP_HALF + 1.5);
        assert!((g.at(mid, 0.0) - 0.24).abs() < 1e-9, "{}", g.at(mid, 0.0));
        assert!((g.at(9.0, 0.0) - 0.36).abs() < 1e-12);
        // A sole whose toe reaches the tread rests on it; its mean is lower.
        assert!((g.under_sole(0.0, 0.0) - 0.12).abs() < 1e-12);
        assert!(g.mean_under_sole(0.0, 0.0) < 0.1);
        assert_eq!(g.under_sole(-0.3, 0.0), 0.0);
    }

    #[test]
    fn the_pelvis_goes_down_under_a_top_only_where_the_plan_passes_beneath_it() {
        // The first action's stance knee for a body with its head `head` \[m\] over
        // flat ground, a plan asking for `plan` \[m\] and the lowest top within reach
        // `headroom` \[m\] over the ground.
        let stance_knee = |head: f64, plan: f64, headroom: f64| {
            let mut gait = BipedGait::new(GaitParams::default(), ControllerSettings::default());
            let mut obs = stepped(0.0, 10.0, 0.0);
            obs.root_height = 0.68;
            obs.head_pos = [0.0, 0.0, head - obs.root_height];
            for w in &mut obs.waypoints {
                w[2] = plan - head;
            }
            obs.headroom = headroom;
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            out.pd_targets[gait.joints.knee[gait.stance]]
        };
        let open = f64::INFINITY;
        // A crouch asked for 0.8 m rides at 0.92 m: under a 0.9 m top its sphere
        // (0.1 m) would meet the top, so the stance knee bends further.
        assert!(stance_knee(0.92, 0.8, 0.9) > stance_knee(0.92, 0.8, open) + 0.05);
        // One that already fits under it, and a walk passing beside a low top (the
        // plan's head does not go under it), are left as in the open, bit for bit.
        assert_eq!(stance_knee(0.7, 0.8, 0.9), stance_knee(0.7, 0.8, open));
        assert_eq!(stance_knee(1.47, 1.47, 0.9), stance_knee(1.47, 1.47, open));
    }

    #[test]
    fn a_swing_foot_down_at_its_paths_end_lands_where_the_map_reads_the_ground_low() {
        // The control steps until the legs switch, with the swing foot put `above` \[m\]
        // over its path's end target once the path has ended (0.5 m under the root
        // before), the stance foot resting on the map's flat ground.
        let steps_to_switch = |above: f64| {
            let mut gait = BipedGait::new(GaitParams::default(), ControllerSettings::default());
            let mut obs = stepped(0.0, 10.0, 0.0);
            obs.root_height = 0.85;
            obs.head_pos = [0.0, 0.0, 1.47 - obs.root_height];
            for i in 0..100 {
                let stance = gait.stance;
                let swing_z = gait.landing.map_or(-0.5, |z| z + above);
                obs.body_pos[FEET[stance]] = [0.0, 0.1, -0.85 + ANKLE_HEIGHT];
                obs.body_pos[FEET[1 - stance]] = [0.2, -0.1, swing_z];
                gait.act(&obs, &mut Action::default());
                if i > 0 && gait.stance != stance {
                    return i;
                }
            }
            panic!("no switch in 100 steps");
        };
        // A foot 0.05 m over its target rests 0.03 m over the map's ground, above the
        // clearance that reads as touchdown: the real ground is higher than the map
        // says (a tread's edge), and the foot has landed on it.
        let landed = steps_to_switch(0.05);
        // A foot 0.12 m over its target is still in the air: its swing runs to the
        // step's time limit (1.5 step times, 0.39 s for the walk).
        let in_air = steps_to_switch(0.12);
        let step_time = GaitParams::default().walk.step_time;
        assert_eq!(
            in_air,
            (1.5 * step_time / CONTROL_DT).ceil() as usize,
            "{in_air}"
        );
        assert!(
            landed < in_air && (landed as f64) < step_time / CONTROL_DT,
            "{landed}"
        );
    }

    #[test]
    fn rough_share_sees_steps_and_bumps_but_not_a_ramp() {
        // A ramp (rise 0.2 per metre) is even ground.
        let mut ramp = stepped(0.0, 0.0, 0.0);
        for r in 0..LOCAL_MAP_SIDE {
            for c in 0..LOCAL_MAP_SIDE {
                ramp.height_map[r * LOCAL_MAP_SIDE + c] = 0.2 * map_coord(r);
            }
        }
        assert_eq!(Ground::new(&ramp).rough_share(), 0.0);
        assert_eq!(Ground::new(&stepped(0.0, 0.0, 0.0)).rough_share(), 0.0);
        // A 0.12 m riser across the map (the stairs strip's) is rough ground.
        let riser = Ground::new(&stepped(0.12, 0.05, 0.12)).rough_share();
        assert!(riser > 0.5, "{riser}");
        // A 0.04 m bump on one sample: part way.
        let mut bump = stepped(0.0, 0.0, 0.0);
        bump.height_map[3 * LOCAL_MAP_SIDE + 4] = 0.04;
        let s = Ground::new(&bump).rough_share();
        assert!(s > 0.0 && s < 1.0, "{s}");
    }

    #[test]
    fn side_steps_catch_a_sideways_fall_without_crossing_the_legs() {
        let (right, left) = (-1.0, 1.0);
        // Off, or below the threshold: the target as it was.
        assert_eq!(side_step(0.2, 1.0, left, 0.0), 0.2);
        assert_eq!(side_step(0.1, 0.25, left, 0.3), 0.1);
        // Moving left at 1 m/s: the left foot steps 0.3 s x 0.7 m/s further out.
        assert!((side_step(0.17, 1.0, left, 0.3) - 0.38).abs() < 1e-12);
        // The right foot, whose target lies left of the pelvis, lands under it.
        assert_eq!(side_step(0.05, 1.0, right, 0.3), 0.0);
        assert_eq!(side_step(-0.02, 1.0, right, 0.3), -0.02);
        // Mirrored: moving right.
        assert!((side_step(-0.17, -1.0, right, 0.3) + 0.38).abs() < 1e-12);
        assert_eq!(side_step(-0.05, -1.0, left, 0.3), 0.0);
    }

    /// The residual's sideways force \[N\] after 1 s of a plan that leads off at right
    /// angles to the pelvis at 1 m/s, with `turn_lat_share` set to `share` in every form.
    fn sideways_push(share: f64) -> f64 {
        let mut params = GaitParams::default();
        for form in [&mut params.walk, &mut params.run, &mut params.crouch] {
            form.turn_lat_share = share;
        }
        let mut gait = BipedGait::new(params, ControllerSettings::default());
        let mut obs = stepped(0.0, 0.0, 0.0);
        obs.root_height = 0.87;
        for (i, w) in obs.waypoints.iter_mut().enumerate() {
            *w = [0.0, WAYPOINT_SPACING * (i + 1) as f64, 0.0];
        }
        obs.waypoint_speeds = [1.0; crate::observation::NUM_WAYPOINTS];
        let mut out = Action::default();
        for _ in 0..(1.0 / CONTROL_DT) as usize {
            gait.act(&obs, &mut out);
        }
        gait.last_wrench().force[1]
    }

    #[test]
    fn a_turn_back_is_not_pushed_sideways_where_the_form_says_so() {
        // Off: the residual pushes the body after the plan (0.25 g cap on 69 kg).
        let off = sideways_push(0.0);
        assert!(off > 50.0, "{off}");
        // On: the plan's sideways velocity is left out and nothing pushes sideways.
        let on = sideways_push(1.0);
        assert!(on.abs() < 1.0, "{on}");
        let half = sideways_push(0.5);
        assert!(half > on + 10.0 && half < off - 10.0, "{half}");
    }

    #[test]
    fn the_turn_weight_leaves_bends_alone_and_takes_turn_backs() {
        assert_eq!(turn_weight(0.0, 0.6), 0.0);
        assert_eq!(turn_weight(-0.6, 0.6), 0.0);
        assert!((turn_weight(0.9, 0.6) - 0.5).abs() < 1e-12);
        assert_eq!(turn_weight(1.2, 0.6), 1.0);
        assert_eq!(turn_weight(-3.0, 0.6), 1.0);
        assert_eq!(turn_weight(1.2, 1.2), 0.0);
        assert_eq!(turn_weight(-1.8, 1.2), 1.0);
    }

    #[test]
    fn relief_counts_a_bump_but_not_a_ramp() {
        // A 0.08 m bump (one map row) the sole passes over between level footholds.
        let mut bump = stepped(0.0, 0.0, 0.0);
        for c in 0..LOCAL_MAP_SIDE {
            bump.height_map[4 * LOCAL_MAP_SIDE + c] = 0.08;
        }
        let g = Ground::new(&bump);
        let r = g.relief(-0.3, 0.0, 0.3, 0.0, 0.0, g.map_slope());
        assert!(r > 0.06 && r < 0.08, "{r}");
        // On flat ground nothing, on a ramp nothing either.
        let flat = stepped(0.0, 0.0, 0.0);
        let g = Ground::new(&flat);
        assert_eq!(g.relief(-0.3, 0.0, 0.2, 0.0, 0.0, g.map_slope()), 0.0);
        let mut ramp = stepped(0.0, 0.0, 0.3);
        for r in 0..LOCAL_MAP_SIDE {
            let x = (r as f64 - 3.5) * LOCAL_MAP_SPACING;
            for c in 0..LOCAL_MAP_SIDE {
                ramp.height_map[r * LOCAL_MAP_SIDE + c] = 0.2 * x;
            }
        }
        let g = Ground::new(&ramp);
        assert!((g.map_slope() - 0.2).abs() < 1e-9);
        let r = g.relief(-0.2, -0.04, 0.2, 0.04, 0.0, g.map_slope());
        assert!(r < 1e-9, "{r}");
    }
}
