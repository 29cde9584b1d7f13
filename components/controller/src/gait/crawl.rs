//! The crawl gait of the model-based controller: forearms (or hands) and knees, head
//! about 0.4 m (paper 4.2, the crawl form).
//!
//! - The posture is a desired body frame: pelvis at a height set by the thighs'
//!   length (knees under the hips), pitched forward, the spine bent so the back is
//!   level and the head low; every limb's joint targets come from IK between the
//!   desired hip/shoulder and its contact point (knee or hand), so the four stiff PD
//!   limbs hold the body like a table and the contacts carry it.
//! - Each limb has a commanded contact point relative to its nominal one: on the
//!   ground it moves back with the desired body velocity (plus the yaw rate times
//!   its lever), in the air it moves from its lift-off point to half a stride ahead,
//!   lifted over the local height map. Phase offsets and duty factor make the
//!   sequence (a lateral-sequence walk keeps three limbs down).
//! - The plan's next waypoint gives the desired velocity (rate-limited; sideways and
//!   backward at most `max_side_speed` until the body, just down, faces the plan), its
//!   direction the yaw rate; the cycle shortens with speed so strides stay short, and
//!   the duty factor falls from `duty` at rest to `fast_duty` at `max_speed`.
//! - Speed feedback: contacts slip, so the stance limbs sweep back at the desired
//!   velocity plus the integral of what the (low-passed) measured velocity lacks
//!   (`slip_gain`, bounded); a swing limb lands further ahead when the body is faster
//!   than desired (`place_gain`), and the sweep slows while the body pitches onto its
//!   head (`dive_slowdown`).
//! - Terrain: each contact's height comes from the local height map (beyond its
//!   front edge, where the hands land, from the plan's ground with `ground_ahead`);
//!   the desired pelvis height follows the mean ground under the contacts (the
//!   pitch, with `slope_pitch`, the ground's rise); where the map is stepped or bumpy
//!   (stairs, gravel: `rough_step`) the top speed may fall to `rough_speed` (these
//!   three off in the shipped file). A swinging limb clears the plan's ground at its
//!   landing point too (`swing_ahead`), and the head keeps `head_clear` over the
//!   ground under it: the body rises, the stance hands push (`head_push`) (all three
//!   on in the shipped file). Where the body rolls, the low side's limbs reach down
//!   and the high side's draw up (`roll_reach`, on in the shipped file, and
//!   `roll_rate_reach`, off; beyond `roll_reach_from`, on smooth ground only with
//!   `roll_reach_smooth_only`; a swinging limb only draws up).
//! - With `forearms` (on in the built-in `params/crawl.toml`, off in
//!   `params/crawl-hands.toml`) the arms carry the front on the forearms: each arm's
//!   contact is its elbow, the upper arm aimed at it and the forearm laid forward
//!   along the ground (its hand end lifted by `forearm_lift` in the swing), so the
//!   load goes down the upper arm instead of through a bent elbow. A swinging knee
//!   whose landing is higher steps up (`knee_step_up`, on in that file): it clears
//!   the step by its radius and aims its thigh from the pelvis as it is, which
//!   pitches past its target. Lagging its timed plan, the crawl steers along the
//!   plan's path (`pursuit`, on in that file; the path behind the first waypoint is
//!   kept by `plan_trace`).
//! - Getting down and up are joint-space blends over a fixed time from the joint
//!   angles at the switch to the crawl's (or standing) pose, with the residual
//!   wrench holding height rate and attitude.
//! - A bounded residual root wrench (capped by [`ControllerSettings`]) helps with
//!   speed, height and attitude (its torque budget to roll first with `roll_first`
//!   once the body leans past `roll_first_from`, 0.25 rad in the shipped file, or to
//!   yaw last with `yaw_last`, off); it is reported like the biped's.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use plamo_interfaces::CONTROL_DT;
use plamo_physics::humanoid::{BODIES, HEAD_OFFSET, JOINTS, body_index, joint_index};
use plamo_physics::{NUM_BODIES, NUM_JOINTS};
use plamo_scenes::{LOCAL_MAP_SIDE, LOCAL_MAP_SPACING};

use super::map_plane::{MAP_HALF, MapPlane};
use super::params::{parse_toml, read_params};
use super::plan_ground::PlanGround;
use super::plan_trace::PlanTrace;
use super::{com_over_feet, mass_fractions, residual_force, residual_wrench};
use crate::error::{ControllerError, Result};
use crate::math::{low_pass, ramp_past, smoothstep, sub3, wrap_angle};
use crate::observation::{Observation, REACH_FIRST_ROW, REACH_ROWS, WAYPOINT_SPACING};
use crate::policy::{Action, RootWrench};
use crate::settings::{ControllerSettings, GRAVITY};

/// Version of the crawl parameter file format.
pub const CRAWL_PARAMS_VERSION: u32 = 1;

/// The built-in crawl parameter file: on forearms and knees (`forearms` on).
pub const DEFAULT_CRAWL_PARAMS: &str = include_str!("../../params/crawl.toml");

/// The shipped crawl on hands and knees (`params/crawl-hands.toml`), the built-in one
/// until session 17: an alternative to the forearm crawl.
pub const HAND_CRAWL_PARAMS: &str = include_str!("../../params/crawl-hands.toml");

/// Crawl gait parameters (`params/crawl.toml`; units there and here).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrawlParams {
    /// File format version ([`CRAWL_PARAMS_VERSION`]).
    pub version: u32,
    /// Requested head height below which the controller crawls \[m\].
    pub crawl_below: f64,
    /// Requested head height above which a crawler stands up again \[m\].
    pub stand_above: f64,
    /// Pelvis pitch, forward positive \[rad\].
    pub pelvis_pitch: f64,
    /// Spine pitch on top of the pelvis' \[rad\].
    pub spine_pitch: f64,
    /// Neck pitch \[rad\].
    pub neck_pitch: f64,
    /// Knee contact ahead of the hip \[m\].
    pub knee_fwd: f64,
    /// Half the distance between the knees \[m\].
    pub knee_width: f64,
    /// Hand contact ahead of the shoulder \[m\].
    pub hand_fwd: f64,
    /// Half the distance between the hands \[m\].
    pub hand_width: f64,
    /// Depth the knee targets are pressed into the ground \[m\].
    pub knee_press: f64,
    /// Depth the hand targets are pressed into the ground \[m\].
    pub hand_press: f64,
    /// Shin pitch above level towards the foot \[rad\].
    pub shin_lift: f64,
    /// Contact height offset per rad of attitude error per m of lever \[-\].
    pub attitude_gain: f64,
    /// Contact height offset per m of pelvis height error \[-\].
    pub height_gain_limbs: f64,
    /// Share of the body weight the hands carry, for the arms' gravity feed-forward
    /// \[-\].
    pub hand_load: f64,
    /// Gait cycle at rest \[s\].
    pub cycle: f64,
    /// Shortest gait cycle \[s\].
    pub min_cycle: f64,
    /// Longest stride of one limb \[m\].
    pub max_stride: f64,
    /// Fraction of the cycle a limb is on the ground at rest \[-\].
    pub duty: f64,
    /// Fraction of the cycle a limb is on the ground at `duty_speed` (linear in
    /// between): a shorter stance leaves the swinging limbs time to reach ahead at
    /// speed \[-\].
    pub fast_duty: f64,
    /// Speed at which the duty factor reaches `fast_duty` \[m/s\]: apart from
    /// `max_speed`, so capping the speed does not change the gait at slower speeds.
    pub duty_speed: f64,
    /// Integral gain of the slip compensation \[1/s\]: the stance limbs sweep back
    /// faster than the desired velocity by the integrated shortfall of the measured
    /// one (contacts slip and the body lags what the limbs' kinematics promise).
    pub slip_gain: f64,
    /// Largest slip compensation \[m/s\].
    pub max_slip: f64,
    /// Share of the gait speed given up per rad of forward pitch beyond
    /// `dive_margin` \[1/rad\]: a body pitching onto its head stops sweeping its limbs
    /// back until the front is up again.
    pub dive_slowdown: f64,
    /// Forward pitch error tolerated at full speed \[rad\].
    pub dive_margin: f64,
    /// Time constant of the low-pass on the measured root velocity \[s\].
    pub vel_filter: f64,
    /// Swing landing point ahead per m/s of (filtered) velocity above the desired one
    /// \[s\] (Raibert-style placement: a limb landing further ahead brakes).
    pub place_gain: f64,
    /// Phase offsets: right knee, left knee, right hand, left hand \[-\].
    pub offsets: [f64; 4],
    /// Swing lift of the knees \[m\].
    pub knee_lift: f64,
    /// Swing lift of the hands \[m\].
    pub hand_lift: f64,
    /// Desired yaw rate per rad of heading error \[1/s\].
    pub yaw_gain: f64,
    /// Largest desired yaw rate \[rad/s\].
    pub max_yaw_rate: f64,
    /// Largest change of the desired velocity \[m/s^2\].
    pub max_accel: f64,
    /// Highest crawl speed \[m/s\].
    pub max_speed: f64,
    /// Highest sideways or backward speed the crawl is asked for after the get-down
    /// until it faces the plan \[m/s\]: where the plan lies to the side or behind (a
    /// crawl leg turning off where a walk leg ended) the body turns towards it
    /// (`yaw_gain`) and crawls forward; stepping sideways at the plan's speed rocked
    /// the body over a hand or knee.
    pub max_side_speed: f64,
    /// Time to get down from standing \[s\].
    pub down_time: f64,
    /// Hands reach ahead per m/s of forward velocity while getting down \[s\].
    pub down_reach: f64,
    /// Speed above which the biped brakes before getting down \[m/s\].
    pub down_speed: f64,
    /// Longest the biped brakes before getting down anyway \[s\].
    pub brake_time: f64,
    /// Time to get up into standing \[s\].
    pub up_time: f64,
    /// Backward speed the residual asks for while sitting back into the squat on the
    /// way up \[m/s\].
    pub sit_back_speed: f64,
    /// Share of a transition's time spent reaching the squat \[-\].
    pub squat_share: f64,
    /// Squat hip pitch \[rad\].
    pub squat_hip: f64,
    /// Squat knee \[rad\].
    pub squat_knee: f64,
    /// Squat ankle pitch \[rad\].
    pub squat_ankle: f64,
    /// Squat spine pitch \[rad\].
    pub squat_spine: f64,
    /// Squat shoulder pitch \[rad\].
    pub squat_shoulder: f64,
    /// Squat elbow \[rad\].
    pub squat_elbow: f64,
    /// Hip pitch of the squat on the way up \[rad\] (deeper than the get-down's, so the
    /// pelvis sits back over the feet before the legs straighten).
    pub up_squat_hip: f64,
    /// Knee of the squat on the way up \[rad\].
    pub up_squat_knee: f64,
    /// Residual force per m/s of velocity error, per kg \[1/s\].
    pub vel_gain: f64,
    /// Residual force per m of pelvis height error, per kg \[1/s^2\].
    pub height_gain: f64,
    /// Residual force per m/s of vertical velocity, per kg \[1/s\].
    pub height_damping: f64,
    /// Residual torque per rad of attitude error \[N m/rad\].
    pub rot_gain: f64,
    /// Residual torque per rad/s of angular velocity \[N m s/rad\].
    pub rot_damping: f64,
    /// Residual yaw torque per rad of heading error \[N m/rad\].
    pub yaw_torque_gain: f64,
    /// Requested head height above which a crawler stands up into a crouch-walk
    /// where the plan stays at least this high for its 10 waypoints (5 s) \[m\]
    /// (above `stand_above`: never; then only `stand_above` stands it up).
    #[serde(default = "never")]
    pub crouch_stand_above: f64,
    /// Height map roughness (largest distance of a sample from the map's best-fit
    /// plane) where the crawl starts to treat the ground as stepped \[m\]: stairs and
    /// gravel, not slopes; at twice this it is fully rough (see `rough_speed`; 4:
    /// never).
    #[serde(default = "never")]
    pub rough_step: f64,
    /// Highest crawl speed on fully rough ground \[m/s\] (not above `max_speed`).
    #[serde(default = "fast")]
    pub rough_speed: f64,
    /// Time constant of the low-pass on the roughness share \[s\]: the speed drops
    /// smoothly, not with every sample the map gains.
    #[serde(default = "rough_filter")]
    pub rough_filter: f64,
    /// Roll first in the residual torque's budget: pitch and yaw share
    /// what the roll torque leaves of `residual_torque_cap`. On stairs the yaw wags and
    /// the pitch errs, and with one norm cap for all three the roll torque was starved
    /// while the body rolled over.
    #[serde(default)]
    pub roll_first: bool,
    /// Roll magnitude where `roll_first` starts to take over \[rad\]: below it the
    /// three torques share the cap as without `roll_first`, at twice it roll comes
    /// first fully, blended linearly between (0: roll first at any roll). On gravel and
    /// stairs the rapier crawl needs its pitch torque while it is level; roll needs the
    /// budget only once the body leans.
    #[serde(default)]
    pub roll_first_from: f64,
    /// Yaw last in the residual torque's budget: roll and pitch share the cap first
    /// and the yaw torque gets what they leave. The yaw wag on stairs (rate damping at
    /// +-2 rad/s) alone asks for more than the cap.
    #[serde(default)]
    pub yaw_last: bool,
    /// Ground beyond the local height map's front edge from the plan: the hands land
    /// ~0.52 m ahead of the pelvis and the map ends 0.35 m ahead, so without this a
    /// hand's target and the body height (the mean ground under the four contacts)
    /// take the map's front row; with it, the ground between the map's edge and the
    /// plan's waypoints ahead (`Observation::waypoint_ground`) is interpolated
    /// linearly, as the biped's feet see it (off: the front row, as before).
    #[serde(default)]
    pub ground_ahead: bool,
    /// Share of the ground's rise, from the knees' nominal contacts to the hands', that
    /// the body pitches up with \[-\] (the slope angle low-passed over
    /// `SLOPE_FILTER`): up stairs and slopes the trunk pitches up and the head keeps
    /// its height above the ground ahead. Downhill the body keeps `pelvis_pitch`:
    /// pitching down with the ground put the head onto the fall rule's bar on the
    /// random tours' slopes (MuJoCo, RESULTS "Crawl", session 11). 0: `pelvis_pitch`
    /// on any ground, as before.
    #[serde(default)]
    pub slope_pitch: f64,
    /// Pelvis pitch under a low top \[rad\] (see `top_below`): the body's back stays
    /// low where a ceiling is near and the crawl may sit higher (a smaller
    /// `pelvis_pitch`) in the open. Unused while `top_below` is 0.
    #[serde(default)]
    pub top_pitch: f64,
    /// Free height under a top within reach of the root (`Observation::headroom`)
    /// below which the body takes `top_pitch` instead of `pelvis_pitch` \[m\], blended
    /// over `TOP_FILTER`. 0: `pelvis_pitch` everywhere, as before.
    #[serde(default)]
    pub top_below: f64,
    /// Least height of the nominal head above the ground under it \[m\] (the head's
    /// centre; the fall rule's bar is 0.2 m, a level crawl's head is ~0.35 m up): the
    /// head is ~0.5 m ahead of the pelvis, beyond the height map, so the ground under
    /// it comes from the plan (`Observation::waypoint_ground`). Where that ground is
    /// higher than the mean under the four contacts (a stair's tread ahead), the
    /// desired pelvis rises until the nominal head clears it by this much. 0: the
    /// contacts' mean alone, as before.
    #[serde(default)]
    pub head_clear: f64,
    /// Hand push per m the measured head is lower than `head_clear` above the ground
    /// under it \[-\]: the stance hands' targets go down by this times the shortfall,
    /// so the arms straighten and lift the front before the head sinks to the fall
    /// rule's bar (session 11's stairs falls: pelvis pitched 0.9-1.3 rad, head
    /// 0.20-0.23 m up). 0: off.
    #[serde(default)]
    pub head_push: f64,
    /// The contacts, the swing and the head read the terrain 0.45-0.85 m ahead of
    /// the root from `Observation::reach_map` (the scene's own heights), and the plan's
    /// ground only beyond it. The paper's height map reaches 0.35 m ahead; the crawl's
    /// elbows and head land 0.45-0.6 m ahead, so a ledge or tread there was the map's
    /// front row (or, with `ground_ahead`, the ground under the plan's waypoints,
    /// metres away where the body lags or has turned off its path). Off: as before.
    /// Measured, off (RESULTS.md "Crawl", session 23): MuJoCo mixed tours seeds
    /// 0-1199 882 -> 868 of 1200, crawl first falls on flat ground 25 -> 35; the
    /// crawl's head held over a ledge it cannot rise above was a third of its falls
    /// on stairs, and seeing the ledge did not lift it.
    #[serde(default)]
    pub reach_map: bool,
    /// A swinging limb clears the plan's ground at its landing point too (beyond the
    /// map, `Observation::waypoint_ground`), not only the map's: a hand landing on a
    /// tread above the map's front row swings over the riser's nose instead of into
    /// it. Where it lands is unchanged (see `ground_ahead`). Off: the map's ground.
    #[serde(default)]
    pub swing_ahead: bool,
    /// Contact height offset per rad of roll per m of lever, on top of
    /// `attitude_gain`'s \[-\]: the limbs on the low side reach down and those on the
    /// high side draw up (at most `MAX_ROLL_REACH` each; a swinging limb only draws
    /// up: reaching down mid-swing took its clearance, and rapier's crawl stalled at
    /// a 0.15 m ledge with a knee or elbow against its face). On flat ground the crawl's
    /// falls were mostly slow roll-overs over an arm (roll growing over 1-2 s, the arms
    /// not folding; RESULTS "Crawl", session 13), which `attitude_gain`'s 0.22 (2.5 cm
    /// at 0.5 rad for a hand) barely answers. 0: off.
    #[serde(default)]
    pub roll_reach: f64,
    /// Contact height offset per rad/s of roll rate per m of lever \[s\] (with
    /// `roll_reach`'s bound): the limbs answer the roll as it starts. 0: off.
    #[serde(default)]
    pub roll_rate_reach: f64,
    /// Roll magnitude below which `roll_reach` does nothing \[rad\]: it answers the
    /// roll beyond this (0: all of it): the level crawl's roll wobbles with its gait
    /// and the ground, and the limbs need not reach after that.
    #[serde(default)]
    pub roll_reach_from: f64,
    /// `roll_reach` and `roll_rate_reach` fade out with the share of rough ground under
    /// the body (`rough_step`; with `rough_speed` left out the speed is not capped):
    /// everywhere, the reach took flat-ground crawl falls down and gravel and stairs
    /// ones up (MuJoCo tours, RESULTS "Crawl", session 13).
    #[serde(default)]
    pub roll_reach_smooth_only: bool,
    /// The arms carry the front on the forearms (elbows and knees), not on the hands:
    /// each arm's contact is its elbow, the upper arm aimed at it and the forearm laid
    /// forward along the ground. A hand-and-knee crawl with the head at ~0.4 m bends
    /// its elbows ~80 degrees under load, and the elbows sag 0.3 rad below their
    /// targets (RESULTS "Crawl", session 14); on the forearms the load goes down the
    /// upper arm. `hand_fwd`, `hand_width`, `hand_press` and `hand_lift` then place
    /// the elbow. Off: hands and knees, as before.
    #[serde(default)]
    pub forearms: bool,
    /// With `forearms`: the stance forearm's pitch below level, hand end down \[rad\]
    /// (the hand presses on the ground).
    #[serde(default)]
    pub forearm_press: f64,
    /// With `forearms`: the swinging forearm's pitch above level, hand end up \[rad\]
    /// (the hand clears a riser ahead).
    #[serde(default)]
    pub forearm_lift: f64,
    /// Rise of a swinging knee's landing ground above its lift-off ground from which
    /// it steps up \[m\]: it clears the step by `knee_lift` with its own radius, and
    /// where its target lies within the thigh's reach of the hip it keeps the target's
    /// height and reaches forward with the whole thigh. The thigh is one segment aimed
    /// at the target, so a target nearer than the thigh (a raised landing) put the knee
    /// below it, into the riser, and the crawl stalled at a ledge with its knees against
    /// the face (RESULTS "Crawl", session 16). 0: off.
    #[serde(default)]
    pub knee_step_up: f64,
    /// Lookahead along the plan's path for a crawl lagging its timed plan \[m\]: it
    /// moves towards the path's point this far beyond the one nearest its head, and
    /// faces the one twice as far, instead of making for the first waypoint (0.5 s
    /// ahead of where the plan is) and facing the second. Lagging ~1 m, the crawl
    /// cut the playground's hedge corner the plan kept 0.5 m clear of, and its
    /// shoulder caught (RESULTS "Crawl", session 17). Within this of the first
    /// waypoint it steers as without. 0: off.
    #[serde(default)]
    pub pursuit: f64,
    /// Heading error above which a crawl already down turns towards its plan before
    /// it moves on \[rad\]: as just after getting down, it only creeps sideways or back
    /// (`max_side_speed`) until it faces the plan within 0.3 rad. Where a crawl leg
    /// starts at a landmark and heads off at 90-180 degrees, the crawl swept its limbs
    /// sideways at the plan's speed while it yawed and rolled over a forearm
    /// (RESULTS "Crawl", session 18). 0: off.
    #[serde(default)]
    pub realign_above: f64,
    /// How far the centre of mass may be ahead of the ankles (heading frame) while
    /// getting up before the residual pushes it back (`up_com_gain`) \[m\]. The get-up
    /// after a crawl that arrived moving straightened its legs with the centre of
    /// mass 0.14 m ahead and the straight body tipped onto its face; one that went
    /// through held it at 0.09-0.12 m (RESULTS "Crawl", session 19).
    #[serde(default)]
    pub up_com_ahead: f64,
    /// Backward speed the get-up's residual asks for per m the centre of mass is
    /// further ahead of the ankles than `up_com_ahead` \[1/s\], on top of
    /// `sit_back_speed`. 0: off.
    #[serde(default)]
    pub up_com_gain: f64,
    /// How far the centre of mass may run ahead of the ankles (heading frame) while
    /// the get-up straightens the legs before the biped takes over to step under it
    /// \[m\] (once the pelvis is `up_handoff_height` up). Out of a squat with the centre
    /// of mass beyond the toes (a crawl facing up a flight of stairs), the
    /// straightening legs pushed it 0.45-0.8 m ahead and the body fell onto its face
    /// (RESULTS "Random 4-landmark scenes", session 47). 4: never.
    #[serde(default = "never")]
    pub up_handoff_ahead: f64,
    /// Lowest pelvis height at which a get-up hands over to the biped as
    /// `up_handoff_ahead` says \[m\] (below it the legs are too bent to step).
    #[serde(default)]
    pub up_handoff_height: f64,
    /// How far the centre of mass may be behind the ankles (heading frame) while
    /// getting down before the residual pushes it forward (`down_com_gain`) \[m\]. On
    /// flat ground the squat holds it within 0.06 m; on a hillside falling away
    /// behind the feet it went 0.27 m back and the body sat onto its back (RESULTS
    /// "Crawl", session 20).
    #[serde(default)]
    pub down_com_behind: f64,
    /// Forward speed the get-down's residual asks for per m the centre of mass is
    /// further behind the ankles than `down_com_behind`, and sideways speed per m it is
    /// outside the ankles' width \[1/s\]. 0: off.
    #[serde(default)]
    pub down_com_gain: f64,
    /// Share of the plan's speed a turning crawl gives up per rad of heading error
    /// \[1/rad\]: it crawls at `1 - turn_slowdown * |error|` of the speed (none below
    /// 0). A turning crawl's limbs sweep sideways with the yaw on top of the forward
    /// sweep, and it rolled over about 1.7 times as often as a straight one (RESULTS
    /// "Crawl", session 21). 0: off.
    #[serde(default)]
    pub turn_slowdown: f64,
    /// How far the get-up straightens the low side's leg and bends the high side's,
    /// per rad of body roll (heading frame) \[rad/rad\]: knee by this, hip and ankle
    /// pitch by half of it the other way, so the foot stays flat. Getting up from a
    /// crawl on a cross slope, the squat let the body roll towards the low side, 0.2-0.3
    /// rad at the start to 0.5-0.9 by the time the legs were straight, and the walk it
    /// handed over to fell sideways (RESULTS "Crawl", session 24). 0: off.
    #[serde(default)]
    pub up_level: f64,
    /// `up_level` for the get-down, into the squat (faded out as the knees go down
    /// to the ground) \[rad/rad\]: squatting on a cross slope, the body rolled
    /// towards the low side as it does getting up, 0.3-0.8 rad before the knees were
    /// down (RESULTS "Crawl", session 24). 0: off; measured, not shipped (MuJoCo
    /// tours, seeds 0-599: 471 of 600 without, 465 at 2.0, 454 at 1.0).
    #[serde(default)]
    pub down_level: f64,
    /// Whether a body found on hands and knees after a reset (a start boxed in by a
    /// low top, a fall's reset under one) with a plan above `crawl_below` starts in
    /// the crawl, which gets up from there as after a crawl leg. The biped gait,
    /// started on a kneeling body under a crouch-walk's 0.8 m plan, straightened one
    /// leg and fell within a second (RESULTS "Crawl", session 24). Off: the biped.
    #[serde(default)]
    pub reset_kneeling_crawls: bool,
    /// Residual torque for roll alone beyond `residual_torque_cap` \[N m\], given as
    /// the body leans past `roll_first_from` (all of it at twice that, blended
    /// linearly between, as `roll_first` takes over). The crawl spends 41-54 N m of the
    /// 60 N m cap holding its chest up and level before a roll starts, and with the
    /// whole cap at 90 N m its first falls in MuJoCo's tours dropped from 67 to 37 of
    /// 600 (RESULTS "Crawl", session 20); this gives the extra only to a roll under
    /// way. It shows in the residual's peak. 0: off.
    #[serde(default)]
    pub roll_torque_extra: f64,
}

/// `rough_speed` of a parameter file without it: no cap.
fn fast() -> f64 {
    5.0
}

/// `rough_filter` of a parameter file without it \[s\].
fn rough_filter() -> f64 {
    0.3
}

/// `crouch_stand_above` of a parameter file without it: never, the crawl as it was.
fn never() -> f64 {
    4.0
}

/// Splits the residual torque's norm `cap` \[N m\] between roll, pitch and yaw
/// (heading frame) by the priorities `roll_first`, `roll_first_from` and `yaw_last`
/// of `p`, at a body roll of `roll` \[rad\]. The result's norm never exceeds `cap`:
/// the blend of two vectors inside the cap's ball stays inside it.
fn share_torque(p: &CrawlParams, cap: f64, roll: f64, torque: [f64; 3]) -> [f64; 3] {
    if !p.roll_first && !p.yaw_last {
        // `residual_wrench` caps the norm, as before these switches.
        return torque;
    }
    // Roll (0), pitch (1), yaw (2) in groups by priority.
    let base: &[&[usize]] = if p.yaw_last {
        &[&[0, 1], &[2]]
    } else {
        &[&[0, 1, 2]]
    };
    let base = by_priority(torque, base, cap);
    if !p.roll_first {
        return base;
    }
    let w = ramp_past(roll.abs(), p.roll_first_from);
    if w == 0.0 {
        return base;
    }
    let first: &[&[usize]] = if p.yaw_last {
        &[&[0], &[1], &[2]]
    } else {
        &[&[0], &[1, 2]]
    };
    let first = by_priority(torque, first, cap);
    [0, 1, 2].map(|i| base[i] + w * (first[i] - base[i]))
}

/// `shared` (the torque as `share_torque` split it) with the roll torque that the cap
/// cut off given back, up to `roll_torque_extra` times the roll's share past
/// `roll_first_from` (as `roll_first` takes over), and the
/// norm cap \[N m\] the result keeps to: `cap` and that extra.
fn extra_roll(
    p: &CrawlParams,
    cap: f64,
    roll: f64,
    torque: [f64; 3],
    shared: [f64; 3],
) -> ([f64; 3], f64) {
    let extra = p.roll_torque_extra * ramp_past(roll.abs(), p.roll_first_from);
    if extra == 0.0 {
        return (shared, cap);
    }
    let mut out = shared;
    out[0] += (torque[0] - shared[0]).clamp(-extra, extra);
    (out, cap + extra)
}

/// `torque` with each group of its components (in order) scaled down to the norm
/// budget the groups before it leave of `cap` \[N m\].
fn by_priority(torque: [f64; 3], groups: &[&[usize]], cap: f64) -> [f64; 3] {
    let mut out = torque;
    let mut budget = cap;
    for group in groups {
        let norm = group.iter().map(|&i| out[i] * out[i]).sum::<f64>().sqrt();
        if norm > budget {
            group.iter().for_each(|&i| out[i] *= budget / norm);
        }
        budget = (budget * budget - group.iter().map(|&i| out[i] * out[i]).sum::<f64>())
            .max(0.0)
            .sqrt();
    }
    out
}

impl Default for CrawlParams {
    fn default() -> Self {
        // The built-in file is tested to parse and validate.
        Self::from_toml(DEFAULT_CRAWL_PARAMS, Path::new("<built-in crawl.toml>"))
            .expect("built-in crawl parameters are valid")
    }
}

impl CrawlParams {
    /// The shipped crawl on hands and knees ([`HAND_CRAWL_PARAMS`]).
    pub fn hands() -> Self {
        // Tested to parse and validate, as the default.
        Self::from_toml(HAND_CRAWL_PARAMS, Path::new("<built-in crawl-hands.toml>"))
            .expect("built-in hand crawl parameters are valid")
    }

    /// Parses and validates parameters; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let p: CrawlParams = parse_toml(text, origin)?;
        p.validate()?;
        Ok(p)
    }

    /// Reads a parameter file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_toml(&read_params(path)?, path)
    }

    /// Checks the version and every field's range.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, reason: String| {
            Err(ControllerError::InvalidSettings { field, reason })
        };
        if self.version != CRAWL_PARAMS_VERSION {
            return bad(
                "version",
                format!(
                    "crawl parameter file version {} (this build reads {CRAWL_PARAMS_VERSION})",
                    self.version
                ),
            );
        }
        let ranges: [(&'static str, f64, f64, f64); 81] = [
            ("top_pitch", self.top_pitch, -0.5, 1.5),
            ("top_below", self.top_below, 0.0, 3.0),
            ("turn_slowdown", self.turn_slowdown, 0.0, 10.0),
            ("up_level", self.up_level, 0.0, 5.0),
            ("roll_torque_extra", self.roll_torque_extra, 0.0, 200.0),
            ("down_level", self.down_level, 0.0, 5.0),
            ("up_com_gain", self.up_com_gain, 0.0, 100.0),
            ("down_com_gain", self.down_com_gain, 0.0, 100.0),
            ("up_com_ahead", self.up_com_ahead, 0.0, 0.5),
            ("up_handoff_ahead", self.up_handoff_ahead, 0.0, 4.0),
            ("up_handoff_height", self.up_handoff_height, 0.0, 1.0),
            ("down_com_behind", self.down_com_behind, 0.0, 0.5),
            ("pursuit", self.pursuit, 0.0, 3.0),
            ("realign_above", self.realign_above, 0.0, PI),
            ("knee_step_up", self.knee_step_up, 0.0, 0.5),
            ("forearm_press", self.forearm_press, -0.5, 0.5),
            ("forearm_lift", self.forearm_lift, 0.0, 1.5),
            ("roll_reach_from", self.roll_reach_from, 0.0, 1.5),
            ("roll_reach", self.roll_reach, 0.0, 10.0),
            ("roll_rate_reach", self.roll_rate_reach, 0.0, 10.0),
            ("head_clear", self.head_clear, 0.0, 1.0),
            ("head_push", self.head_push, 0.0, 10.0),
            ("slope_pitch", self.slope_pitch, 0.0, 1.5),
            ("roll_first_from", self.roll_first_from, 0.0, 1.5),
            ("rough_step", self.rough_step, 0.005, 4.0),
            ("rough_speed", self.rough_speed, 0.0, 5.0),
            ("rough_filter", self.rough_filter, 0.01, 5.0),
            ("crouch_stand_above", self.crouch_stand_above, 0.2, 4.0),
            ("max_side_speed", self.max_side_speed, 0.0, 5.0),
            ("up_squat_hip", self.up_squat_hip, -2.4, 0.6),
            ("up_squat_knee", self.up_squat_knee, 0.0, 2.7),
            ("sit_back_speed", self.sit_back_speed, 0.0, 2.0),
            ("hand_load", self.hand_load, 0.0, 1.0),
            ("attitude_gain", self.attitude_gain, 0.0, 10.0),
            ("height_gain_limbs", self.height_gain_limbs, 0.0, 10.0),
            ("squat_share", self.squat_share, 0.05, 0.95),
            ("squat_hip", self.squat_hip, -2.4, 0.6),
            ("squat_knee", self.squat_knee, 0.0, 2.7),
            ("squat_ankle", self.squat_ankle, -0.9, 0.9),
            ("squat_spine", self.squat_spine, -0.5, 1.2),
            ("squat_shoulder", self.squat_shoulder, -3.0, 1.0),
            ("squat_elbow", self.squat_elbow, -2.6, 0.05),
            ("crawl_below", self.crawl_below, 0.2, 1.2),
            ("stand_above", self.stand_above, 0.2, 1.5),
            ("pelvis_pitch", self.pelvis_pitch, -0.5, 1.5),
            ("spine_pitch", self.spine_pitch, -0.5, 1.2),
            ("neck_pitch", self.neck_pitch, -0.6, 0.9),
            ("knee_fwd", self.knee_fwd, -0.3, 0.3),
            ("knee_width", self.knee_width, 0.0, 0.3),
            ("hand_fwd", self.hand_fwd, -0.3, 0.4),
            ("hand_width", self.hand_width, 0.0, 0.4),
            ("knee_press", self.knee_press, -0.05, 0.05),
            ("hand_press", self.hand_press, -0.05, 0.2),
            ("shin_lift", self.shin_lift, -0.5, 1.2),
            ("cycle", self.cycle, 0.1, 5.0),
            ("min_cycle", self.min_cycle, 0.1, 5.0),
            ("max_stride", self.max_stride, 0.0, 0.6),
            ("duty", self.duty, 0.3, 0.95),
            ("fast_duty", self.fast_duty, 0.3, 0.95),
            ("duty_speed", self.duty_speed, 0.1, 5.0),
            ("slip_gain", self.slip_gain, 0.0, 20.0),
            ("max_slip", self.max_slip, 0.0, 2.0),
            ("dive_slowdown", self.dive_slowdown, 0.0, 20.0),
            ("dive_margin", self.dive_margin, 0.0, 1.0),
            ("vel_filter", self.vel_filter, 0.01, 2.0),
            ("place_gain", self.place_gain, 0.0, 1.0),
            ("knee_lift", self.knee_lift, 0.0, 0.3),
            ("hand_lift", self.hand_lift, 0.0, 0.3),
            ("yaw_gain", self.yaw_gain, 0.0, 10.0),
            ("max_yaw_rate", self.max_yaw_rate, 0.0, 5.0),
            ("max_accel", self.max_accel, 0.01, 20.0),
            ("max_speed", self.max_speed, 0.0, 5.0),
            ("down_time", self.down_time, 0.1, 10.0),
            ("down_reach", self.down_reach, 0.0, 1.0),
            ("down_speed", self.down_speed, 0.0, 10.0),
            ("brake_time", self.brake_time, 0.0, 5.0),
            ("up_time", self.up_time, 0.1, 10.0),
            ("vel_gain", self.vel_gain, 0.0, 50.0),
            ("height_gain", self.height_gain, 0.0, 500.0),
            ("rot_gain", self.rot_gain, 0.0, 5000.0),
            ("yaw_torque_gain", self.yaw_torque_gain, 0.0, 5000.0),
        ];
        for (field, v, lo, hi) in ranges {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return bad(field, format!("{v} is outside [{lo}, {hi}]"));
            }
        }
        for (field, v) in [
            ("height_damping", self.height_damping),
            ("rot_damping", self.rot_damping),
        ] {
            if !(v.is_finite() && (0.0..=1000.0).contains(&v)) {
                return bad(field, format!("{v} is outside [0, 1000]"));
            }
        }
        if self.stand_above <= self.crawl_below {
            return bad(
                "stand_above",
                format!(
                    "{} must exceed crawl_below {} (hysteresis)",
                    self.stand_above, self.crawl_below
                ),
            );
        }
        if self.min_cycle > self.cycle {
            return bad(
                "min_cycle",
                format!("{} must not exceed cycle {}", self.min_cycle, self.cycle),
            );
        }
        if self.offsets.iter().any(|o| !(0.0..1.0).contains(o)) {
            return bad(
                "offsets",
                format!("{:?}: each must be in [0, 1)", self.offsets),
            );
        }
        Ok(())
    }
}

/// Limb order: right knee, left knee, right hand, left hand.
const LIMBS: usize = 4;

/// Radius of the shin capsule at the knee: the knee's height when on the ground \[m\].
const KNEE_RADIUS: f64 = 0.055;

/// Height of the hand sphere's centre above the ground when the hand is down \[m\].
const HAND_RADIUS: f64 = 0.05;

/// Height of the elbow joint above the ground with the forearm down (`forearms`):
/// the hand sphere's radius, the forearm lying level \[m\].
const ELBOW_REST: f64 = 0.05;

/// Ankle pitch target: toes pointed back along the shin as far as the joint goes
/// \[rad\].
const ANKLE_POINT: f64 = 0.9;

/// Joint indices the crawl drives.
#[derive(Debug, Clone, Copy)]
struct Joints {
    hip: [[usize; 3]; 2],
    knee: [usize; 2],
    ankle: [[usize; 2]; 2],
    shoulder: [[usize; 3]; 2],
    elbow: [usize; 2],
    spine_y: usize,
    neck_y: usize,
}

fn idx(name: &str) -> usize {
    // Names below are the humanoid's own: checked by the unit test `geometry_resolves`.
    joint_index(name).unwrap_or_else(|| panic!("humanoid has no joint `{name}`"))
}

fn body(name: &str) -> [f64; 3] {
    BODIES[body_index(name).unwrap_or_else(|| panic!("humanoid has no body `{name}`"))].offset
}

impl Joints {
    fn resolve() -> Self {
        let side = ["right", "left"];
        Joints {
            hip: side.map(|s| ["x", "y", "z"].map(|a| idx(&format!("{s}_hip_{a}")))),
            knee: side.map(|s| idx(&format!("{s}_knee"))),
            ankle: side.map(|s| ["y", "x"].map(|a| idx(&format!("{s}_ankle_{a}")))),
            shoulder: side.map(|s| ["x", "y", "z"].map(|a| idx(&format!("{s}_shoulder_{a}")))),
            elbow: side.map(|s| idx(&format!("{s}_elbow"))),
            spine_y: idx("spine_y"),
            neck_y: idx("neck_y"),
        }
    }
}

/// Body dimensions the crawl's kinematics need (from the humanoid description).
#[derive(Debug, Clone, Copy)]
struct Geometry {
    /// Hip anchors in the pelvis frame (right, left) \[m\].
    hip: [[f64; 3]; 2],
    /// Spine joint in the pelvis frame \[m\].
    spine: [f64; 3],
    /// Shoulder anchors in the torso frame (right, left) \[m\].
    shoulder: [[f64; 3]; 2],
    /// Neck joint in the torso frame \[m\].
    neck: [f64; 3],
    thigh: f64,
    upper_arm: f64,
    /// Elbow to the hand sphere's centre \[m\].
    forearm: f64,
}

impl Geometry {
    fn resolve() -> Self {
        Geometry {
            hip: [body("right_thigh"), body("left_thigh")],
            spine: body("torso"),
            shoulder: [body("right_upper_arm"), body("left_upper_arm")],
            neck: body("head"),
            thigh: -body("right_shin")[2],
            upper_arm: -body("right_lower_arm")[2],
            forearm: -body("right_hand")[2] + HAND_RADIUS,
        }
    }
}

/// Rotation about Y by `a` applied to `v` (positive turns +Z towards +X).
fn rot_y(a: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = a.sin_cos();
    [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Smallest lever of the X hinge \[m\]: a limb pointing along its parent's X axis
/// is a gimbal lock of the X-then-Y hinges, where the exact X angle jumps; below this
/// lever the X hinge gives up some of the sideways reach instead.
const GIMBAL_LEVER: f64 = 0.15;

/// Hinge angles X, Y (and the bend of a second segment) that put the end of a limb
/// hanging along -Z at `p` (parent frame, from the limb's anchor). `bend` is +1 for a
/// knee-like joint (positive flexion), -1 for an elbow; `l2 = 0` aims one segment.
/// `up` picks the solution with the limb pointing up in the parent frame (hip/shoulder
/// Y beyond 90 degrees: an arm reaching down from a torso pitched past level); the
/// caller picks it once per posture so the solution does not flip between steps.
fn limb_ik(l1: f64, l2: f64, bend: f64, up: bool, p: [f64; 3]) -> [f64; 3] {
    let qx = if up {
        (-p[1]).atan2(p[2].max(GIMBAL_LEVER))
    } else {
        p[1].atan2((-p[2]).max(GIMBAL_LEVER))
    };
    let (s, c) = qx.sin_cos();
    // Undo the X hinge: the limb then lies (nearly) in the X-Z plane.
    let z = -s * p[1] + c * p[2];
    let x = p[0];
    let phi = (-x).atan2(-z);
    if l2 == 0.0 {
        return [qx, phi, 0.0];
    }
    let d = (x * x + z * z)
        .sqrt()
        .clamp((l1 - l2).abs() + 0.05, (l1 + l2) * 0.999);
    let cos_bend = (l1 * l1 + l2 * l2 - d * d) / (2.0 * l1 * l2);
    let bend_angle = PI - cos_bend.clamp(-1.0, 1.0).acos();
    let cos_beta = (l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d);
    let beta = cos_beta.clamp(-1.0, 1.0).acos();
    [qx, phi - bend * beta, bend * bend_angle]
}

/// Terrain under the crawl's contacts, relative to the ground under the root (see
/// `ground_ahead`).
struct Ground<'a> {
    map: &'a [f64],
    /// The plan's ground beyond the map ([`PlanGround::NONE`] without `ground_ahead`).
    plan: PlanGround,
    /// The plan's ground beyond the map for the head, with or without `ground_ahead`.
    beyond: PlanGround,
    /// The rows ahead of the map with `reach_map` (`Observation::reach_map`).
    reach: Option<&'a [f64]>,
}

impl<'a> Ground<'a> {
    /// The height map of `obs`, with `ahead` the plan's waypoints straight ahead of
    /// its front row, and with `reach` the terrain ahead of the map's front row from
    /// `Observation::reach_map` (to 0.85 m), the plan's ground only beyond it
    /// (`reach_map`).
    fn new(obs: &'a Observation, ahead: bool, reach: bool) -> Self {
        let (reach, edge) = if reach {
            let front = REACH_FIRST_ROW + (REACH_ROWS - 1) as f64;
            (Some(&obs.reach_map[..]), front * LOCAL_MAP_SPACING)
        } else {
            (None, MAP_HALF)
        };
        let beyond = PlanGround::from_edge(obs, true, edge);
        Ground {
            map: &obs.height_map,
            plan: if ahead { beyond } else { PlanGround::NONE },
            beyond,
            reach,
        }
    }

    /// Height at a heading-frame point (x forward, y left of the root) \[m\]:
    /// bilinear in the map, clamped to its extent; ahead of its front row
    /// interpolated to the waypoints' ground, beyond the last the last one's.
    fn at(&self, x: f64, y: f64) -> f64 {
        self.plan.extend(x, self.map_at(x, y))
    }

    /// Height at a heading-frame point \[m\] as [`Ground::at`] with `ground_ahead`,
    /// with or without it (under the head, `head_clear`; a swing's landing point,
    /// `swing_ahead`).
    fn with_plan(&self, x: f64, y: f64) -> f64 {
        self.beyond.extend(x, self.map_at(x, y))
    }

    /// Bilinear in the map (and the rows ahead of it with `reach_map`), clamped to
    /// its extent \[m\].
    fn map_at(&self, x: f64, y: f64) -> f64 {
        let half = (LOCAL_MAP_SIDE as f64 - 1.0) / 2.0;
        let last = (LOCAL_MAP_SIDE - 1) as f64;
        let rows = LOCAL_MAP_SIDE + self.reach.map_or(0, |r| r.len() / LOCAL_MAP_SIDE);
        let last_row = (rows - 1) as f64;
        let r = (x / LOCAL_MAP_SPACING + half).clamp(0.0, last_row);
        let c = (y / LOCAL_MAP_SPACING + half).clamp(0.0, last);
        let (r0, c0) = (r.floor().min(last_row - 1.0), c.floor().min(last - 1.0));
        let (fr, fc) = (r - r0, c - c0);
        let h = |i: f64, j: f64| {
            let (i, j) = (i as usize, j as usize);
            match self.reach {
                Some(ahead) if i >= LOCAL_MAP_SIDE => {
                    ahead[(i - LOCAL_MAP_SIDE) * LOCAL_MAP_SIDE + j]
                }
                _ => self.map[i * LOCAL_MAP_SIDE + j],
            }
        };
        (1.0 - fr) * ((1.0 - fc) * h(r0, c0) + fc * h(r0, c0 + 1.0))
            + fr * ((1.0 - fc) * h(r0 + 1.0, c0) + fc * h(r0 + 1.0, c0 + 1.0))
    }
}

/// What the crawl is doing.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// Blending from the joint angles at the switch into the crawl pose.
    Down { t: f64, pitch0: f64, height0: f64 },
    /// Crawling.
    Crawl,
    /// Blending from the crawl into standing.
    Up { t: f64, pitch0: f64, height0: f64 },
}

/// The crawl's desired body frame, relative to the desired pelvis, heading frame.
#[derive(Debug, Clone, Copy)]
struct Frame {
    pelvis_pitch: f64,
    torso_pitch: f64,
    hip: [[f64; 3]; 2],
    shoulder: [[f64; 3]; 2],
    /// Pelvis height above the ground under the root \[m\].
    pelvis_height: f64,
    /// Whether the arms point up in the torso frame (see [`limb_ik`]).
    arm_up: bool,
}

/// The crawl gait (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct CrawlGait {
    params: CrawlParams,
    settings: ControllerSettings,
    joints: Joints,
    geo: Geometry,
    mode: Mode,
    /// Joint angles when the current transition began \[rad\].
    from: [f64; NUM_JOINTS],
    /// Gait cycle phase \[-\].
    phase: f64,
    /// Each limb's commanded contact relative to its nominal point (x, y) \[m\].
    offset: [[f64; 2]; LIMBS],
    /// Offset at lift-off \[m\].
    lift_off: [[f64; 2]; LIMBS],
    in_swing: [bool; LIMBS],
    /// Rate-limited desired velocity, heading frame \[m/s\].
    v_cmd: [f64; 2],
    /// Low-passed measured root velocity, heading frame \[m/s\].
    v_filt: [f64; 2],
    /// Slip compensation added to the stance limbs' sweep, heading frame \[m/s\].
    v_slip: [f64; 2],
    /// Whether the crawl is still turning towards the plan after the get-down (see
    /// `max_side_speed`).
    aligning: bool,
    /// Low-passed share of rough ground under the body, 0-1 (see `rough_step`).
    rough: f64,
    /// Low-passed rise of the ground under the contacts \[rad\], 0 downhill (see
    /// `slope_pitch`; stays 0 without it).
    slope: f64,
    /// Low-passed share of `top_pitch` in the body's pitch, 0-1 (see `top_below`);
    /// `None` until the first step after a reset, which takes it as it is.
    under_top: Option<f64>,
    /// The plan's path behind its first waypoint (see `pursuit`).
    trace: PlanTrace,
    /// Body masses over the total mass, for the centre of mass \[-\].
    mass_fraction: [f64; NUM_BODIES],
    last_wrench: RootWrench,
}

/// Time constant of the low-pass on the ground's slope under the body (see
/// `slope_pitch`) \[s\]: a hand crossing a stair's nose changes the slope between
/// knees and hands at once; the trunk follows over a stride.
const SLOPE_FILTER: f64 = 0.3;

/// Time constant of the blend between `pelvis_pitch` and `top_pitch` (see
/// `top_below`) \[s\]: at the crawl's 0.7 m/s the body settles over ~0.2 m, inside
/// `HEADROOM_REACH`'s 1 m before its back reaches the top.
const TOP_FILTER: f64 = 0.3;

/// Largest drop of the hands' targets for a sinking head (`head_push`) \[m\]: the
/// arms are straight a little beyond it.
const MAX_HEAD_PUSH: f64 = 0.1;

/// Largest contact height offset of `roll_reach` and `roll_rate_reach` together, per
/// limb \[m\]: about what a hand or knee can reach beyond its nominal stance.
const MAX_ROLL_REACH: f64 = 0.1;

/// Heading error below which a crawl that has just got down faces its plan \[rad\].
const ALIGNED: f64 = 0.3;

/// Largest heading error the residual yaw torque turns towards while getting down or
/// up \[rad\].
const TRANSITION_YAW_ERR: f64 = 0.2;

/// Largest knee change of `up_level` and `down_level` per leg \[rad\].
const MAX_LEVEL: f64 = 0.6;

/// Standing pose the get-up blends into \[rad\] (hip, knee, ankle pitch).
const STAND: [f64; 3] = [-0.1, 0.2, -0.1];

impl CrawlGait {
    /// A crawl with validated parameters and settings.
    pub(crate) fn new(params: CrawlParams, settings: ControllerSettings) -> Self {
        Self {
            params,
            settings,
            joints: Joints::resolve(),
            geo: Geometry::resolve(),
            mode: Mode::Crawl,
            from: [0.0; NUM_JOINTS],
            phase: 0.0,
            offset: [[0.0; 2]; LIMBS],
            lift_off: [[0.0; 2]; LIMBS],
            in_swing: [false; LIMBS],
            v_cmd: [0.0; 2],
            v_filt: [0.0; 2],
            v_slip: [0.0; 2],
            aligning: false,
            rough: 0.0,
            slope: 0.0,
            under_top: None,
            trace: PlanTrace::default(),
            mass_fraction: mass_fractions(),
            last_wrench: RootWrench::default(),
        }
    }

    pub(crate) fn params(&self) -> &CrawlParams {
        &self.params
    }

    pub(crate) fn last_wrench(&self) -> RootWrench {
        self.last_wrench
    }

    /// Whether the get-up has finished (the biped gait takes over).
    pub(crate) fn stood_up(&self) -> bool {
        matches!(self.mode, Mode::Up { t, .. } if t >= self.params.up_time)
    }

    /// Whether the crawl is down on hands and knees (not in a transition).
    pub(crate) fn settled(&self) -> bool {
        self.mode == Mode::Crawl
    }

    /// Whether the crawl is standing up.
    pub(crate) fn standing_up(&self) -> bool {
        matches!(self.mode, Mode::Up { .. })
    }

    /// Starts getting down from whatever pose `obs` shows.
    pub(crate) fn begin_down(&mut self, obs: &Observation) {
        self.from.copy_from_slice(&obs.joint_pos);
        self.mode = Mode::Down {
            t: 0.0,
            pitch0: Self::pitch(obs),
            height0: obs.root_height,
        };
        self.phase = 0.0;
        self.offset = [[0.0; 2]; LIMBS];
        self.in_swing = [false; LIMBS];
        self.v_cmd = [obs.root_lin_vel[0], obs.root_lin_vel[1]];
        self.v_filt = self.v_cmd;
        self.v_slip = [0.0; 2];
        self.trace.clear();
    }

    /// Starts standing up.
    pub(crate) fn begin_up(&mut self, obs: &Observation) {
        self.from.copy_from_slice(&obs.joint_pos);
        self.mode = Mode::Up {
            t: 0.0,
            pitch0: Self::pitch(obs),
            height0: obs.root_height,
        };
    }

    fn pitch(obs: &Observation) -> f64 {
        (-obs.root_rotation[2]).clamp(-1.0, 1.0).asin()
    }

    /// Height of an arm's contact point (hand centre, or elbow with `forearms`) above
    /// the ground when it is down \[m\].
    fn arm_rest(&self) -> f64 {
        if self.params.forearms {
            ELBOW_REST
        } else {
            HAND_RADIUS
        }
    }

    /// The desired body frame: the level pitch (`base_pitch`), less the share
    /// `slope_pitch` of the ground's rise.
    fn frame(&self, ground: &Ground) -> Frame {
        let p = &self.params;
        self.frame_at(ground, self.base_pitch() - p.slope_pitch * self.slope)
    }

    /// The pelvis pitch on level ground \[rad\]: `pelvis_pitch`, or towards
    /// `top_pitch` under a low top.
    fn base_pitch(&self) -> f64 {
        let p = &self.params;
        let share = self.under_top.unwrap_or(0.0);
        p.pelvis_pitch + share * (p.top_pitch - p.pelvis_pitch)
    }

    /// Forward slope angle of the ground from the knees' nominal contacts to the
    /// hands' \[rad\], uphill positive, for the body at its level pitch.
    fn ground_slope(&self, ground: &Ground) -> f64 {
        let n = self.nominal(&self.frame_at(ground, self.base_pitch()));
        let mid = |a: [f64; 2], b: [f64; 2]| {
            let h = 0.5 * (ground.at(a[0], a[1]) + ground.at(b[0], b[1]));
            (0.5 * (a[0] + b[0]), h)
        };
        let (knees, hands) = (mid(n[0], n[1]), mid(n[2], n[3]));
        (hands.1 - knees.1).atan2(hands.0 - knees.0)
    }

    /// The desired body frame for a pelvis pitch \[rad\].
    fn frame_at(&self, ground: &Ground, pelvis_pitch: f64) -> Frame {
        let p = &self.params;
        let g = &self.geo;
        let torso_pitch = pelvis_pitch + p.spine_pitch;
        let hip = g.hip.map(|h| rot_y(pelvis_pitch, h));
        let spine = rot_y(pelvis_pitch, g.spine);
        let shoulder = g.shoulder.map(|s| add(spine, rot_y(torso_pitch, s)));
        // Knees under the hips: the thigh's length sets the hip height.
        let hip_height = KNEE_RADIUS - p.knee_press
            + (g.thigh * g.thigh - p.knee_fwd * p.knee_fwd)
                .max(0.01)
                .sqrt();
        // Ground under the nominal contacts: on a slope or a step the body follows it.
        let mut under = 0.0;
        for (side, h) in hip.iter().enumerate() {
            under += ground.at(h[0] + p.knee_fwd, h[1]);
            let s = shoulder[side];
            under += ground.at(s[0] + p.hand_fwd, s[1]);
        }
        let mut pelvis_height = under / 4.0 + hip_height - hip[0][2];
        if p.head_clear > 0.0 {
            // Over a tread ahead the head sinks towards it while the contacts' mean
            // still reads the lower ground: the nominal head keeps `head_clear`.
            let neck = add(spine, rot_y(torso_pitch, g.neck));
            let head = add(neck, rot_y(torso_pitch + p.neck_pitch, HEAD_OFFSET));
            let floor = ground.with_plan(head[0], head[1]) + p.head_clear - head[2];
            pelvis_height = pelvis_height.max(floor);
        }
        // The nominal hand seen from the torso decides the arm's IK branch.
        let hand = [
            p.hand_fwd,
            0.0,
            self.arm_rest() - pelvis_height - shoulder[0][2],
        ];
        Frame {
            pelvis_pitch,
            torso_pitch,
            hip,
            shoulder,
            pelvis_height,
            arm_up: rot_y(-torso_pitch, hand)[2] > 0.0,
        }
    }

    /// Nominal contact points (x, y), heading frame relative to the pelvis.
    fn nominal(&self, f: &Frame) -> [[f64; 2]; LIMBS] {
        let p = &self.params;
        let side = |i: usize| if i == 0 { -1.0 } else { 1.0 };
        [
            [f.hip[0][0] + p.knee_fwd, side(0) * p.knee_width],
            [f.hip[1][0] + p.knee_fwd, side(1) * p.knee_width],
            [f.shoulder[0][0] + p.hand_fwd, side(0) * p.hand_width],
            [f.shoulder[1][0] + p.hand_fwd, side(1) * p.hand_width],
        ]
    }

    /// Joint targets with the contacts at `contacts` (heading frame, relative to the
    /// desired pelvis; z absolute relative to the ground under the root).
    fn pose_targets(
        &self,
        f: &Frame,
        contacts: &[[f64; 3]; LIMBS],
        hand_force: [f64; 2],
        arm_swing: [bool; 2],
        step_up: [Option<f64>; 2],
        targets: &mut [f64],
    ) {
        let j = &self.joints;
        let g = &self.geo;
        let p = &self.params;
        for leg in 0..2 {
            let knee = contacts[leg];
            let mut rel = sub3([knee[0], knee[1], knee[2] - f.pelvis_height], f.hip[leg]);
            let mut aim_pitch = f.pelvis_pitch;
            if let Some(pitch) = step_up[leg] {
                // Within the thigh's reach the aimed knee would pass below the target:
                // keep its height, reach forward. The thigh is aimed from the pelvis as
                // it is: the crawl's pelvis pitches ~0.35 rad past its target, and a
                // thigh aimed from the desired pelvis swung the knee into the riser.
                let reach = (g.thigh * g.thigh - rel[1] * rel[1] - rel[2] * rel[2]).max(0.0);
                rel[0] = rel[0].max(reach.sqrt());
                aim_pitch = pitch;
            }
            let q = limb_ik(g.thigh, 0.0, 1.0, false, rot_y(-aim_pitch, rel));
            // Shin back along the ground, its foot end lifted by `shin_lift`.
            let thigh_pitch = f.pelvis_pitch + q[1];
            targets[j.hip[leg][0]] = q[0];
            targets[j.hip[leg][1]] = q[1];
            targets[j.hip[leg][2]] = 0.0;
            targets[j.knee[leg]] = FRAC_PI_2 - p.shin_lift - thigh_pitch;
            targets[j.ankle[leg][0]] = ANKLE_POINT;
            targets[j.ankle[leg][1]] = 0.0;
        }
        for arm in 0..2 {
            let hand = contacts[2 + arm];
            let rel = sub3(
                [hand[0], hand[1], hand[2] - f.pelvis_height],
                f.shoulder[arm],
            );
            let local = rot_y(-f.torso_pitch, rel);
            // Gravity feed-forward: the torque that holds the contact's share of the
            // weight, realised as a PD offset (a bent arm sags by load / kp otherwise).
            let force = rot_y(-f.torso_pitch, [0.0, 0.0, hand_force[arm]]);
            let hold = |joint: usize, r: [f64; 3]| {
                let torque = -(r[2] * force[0] - r[0] * force[2]);
                let jd = &JOINTS[joint];
                torque.clamp(-jd.max_torque, jd.max_torque) / jd.kp
            };
            let sh = j.shoulder[arm][1];
            targets[j.shoulder[arm][2]] = 0.0;
            if p.forearms {
                // The upper arm aimed at the elbow's contact, the forearm laid forward:
                // its pitch in the world is the upper arm's plus the elbow's.
                let mut q = limb_ik(g.upper_arm, 0.0, -1.0, f.arm_up, local);
                // An arm aimed up and forward in the torso frame: the shoulder's
                // range is [-3, 1], not the angle's (-pi, pi].
                if q[1] > 1.0 {
                    q[1] -= 2.0 * PI;
                }
                let forearm = if arm_swing[arm] {
                    p.forearm_lift
                } else {
                    -p.forearm_press
                };
                targets[j.shoulder[arm][0]] = q[0];
                targets[sh] = q[1] + hold(sh, local);
                targets[j.elbow[arm]] = -FRAC_PI_2 - forearm - (f.torso_pitch + q[1]);
            } else {
                let q = limb_ik(g.upper_arm, g.forearm, -1.0, f.arm_up, local);
                let elbow = [-g.upper_arm * q[1].sin(), 0.0, -g.upper_arm * q[1].cos()];
                targets[j.shoulder[arm][0]] = q[0];
                targets[sh] = q[1] + hold(sh, local);
                targets[j.elbow[arm]] = q[2] + hold(j.elbow[arm], sub3(local, elbow));
            }
        }
        targets[j.spine_y] = p.spine_pitch;
        targets[j.neck_y] = p.neck_pitch;
    }

    /// The squat the transitions pass through (`up`: the get-up's).
    fn squat(&self, up: bool) -> [f64; NUM_JOINTS] {
        let (p, j) = (&self.params, &self.joints);
        let mut q = [0.0; NUM_JOINTS];
        for side in 0..2 {
            q[j.hip[side][1]] = if up { p.up_squat_hip } else { p.squat_hip };
            q[j.knee[side]] = if up { p.up_squat_knee } else { p.squat_knee };
            q[j.ankle[side][0]] = p.squat_ankle;
            q[j.shoulder[side][1]] = p.squat_shoulder;
            q[j.elbow[side]] = p.squat_elbow;
        }
        q[j.spine_y] = p.squat_spine;
        q
    }

    /// Joint targets `from` -> squat -> `to` at time share `u` in [0, 1].
    fn through_squat(
        &self,
        up: bool,
        from: &[f64; NUM_JOINTS],
        to: &[f64; NUM_JOINTS],
        u: f64,
        out: &mut [f64],
    ) {
        let squat = self.squat(up);
        let (into, s) = self.squat_phase(u);
        let (a, b) = if into { (from, &squat) } else { (&squat, to) };
        for (i, o) in out.iter_mut().enumerate() {
            *o = a[i] + s * (b[i] - a[i]);
        }
    }

    /// Where a transition is at time share `u` in [0, 1]: whether it is still going
    /// into the squat (the first `squat_share`), and its eased progress through that
    /// half \[-\].
    fn squat_phase(&self, u: f64) -> (bool, f64) {
        let share = self.params.squat_share;
        if u < share {
            (true, smoothstep(u / share))
        } else {
            (false, smoothstep((u - share) / (1.0 - share)))
        }
    }

    /// Straightens the low side's leg and bends the high side's by `gain` times the
    /// body's `roll` (> 0: right side low) in the knee, half of it the other way in
    /// hip and ankle pitch (`up_level`, `down_level`).
    fn level_legs(&self, gain: f64, roll: f64, targets: &mut [f64]) {
        if gain == 0.0 {
            return;
        }
        let j = &self.joints;
        for (leg, side) in [(0, -1.0), (1, 1.0)] {
            let knee = targets[j.knee[leg]];
            let e = (-side * gain * roll).clamp(-MAX_LEVEL, MAX_LEVEL).min(knee);
            targets[j.knee[leg]] = knee - e;
            targets[j.hip[leg][1]] += 0.5 * e;
            targets[j.ankle[leg][0]] += 0.5 * e;
        }
    }

    /// Contact heights on the ground (pressed in), for (x, y) points.
    fn grounded(&self, ground: &Ground, xy: &[[f64; 2]; LIMBS]) -> [[f64; 3]; LIMBS] {
        let p = &self.params;
        std::array::from_fn(|i| {
            let [x, y] = xy[i];
            let rest = if i < 2 {
                KNEE_RADIUS - p.knee_press
            } else {
                self.arm_rest() - p.hand_press
            };
            [x, y, ground.at(x, y) + rest]
        })
    }

    /// PD targets and residual wrench for one control step (layout checked by the
    /// caller).
    pub(crate) fn act(&mut self, obs: &Observation, out: &mut Action) {
        let p = self.params;
        let r = obs.root_rotation;
        let pitch = Self::pitch(obs);
        let roll = r[5].clamp(-1.0, 1.0).asin();
        let [wx, wy, wz] = obs.root_ang_vel;
        let [vx, vy, vz] = obs.root_lin_vel;

        // What the plan asks for.
        let wp0 = obs.waypoints[0];
        let wp1 = obs.waypoints[1];
        let share = MapPlane::rough_share(&obs.height_map, p.rough_step);
        self.rough = low_pass(self.rough, share, CONTROL_DT, p.rough_filter);
        let top = p.max_speed + self.rough * (p.rough_speed.min(p.max_speed) - p.max_speed);
        let vmax = (1.15 * obs.waypoint_speeds[0].max(0.0) + 0.2).min(top);
        let mut v_plan = [wp0[0] / WAYPOINT_SPACING, wp0[1] / WAYPOINT_SPACING];
        let n = v_plan[0].hypot(v_plan[1]);
        if n > vmax {
            v_plan = v_plan.map(|v| v * vmax / n);
        }
        self.trace.record(obs);
        let mut face = [wp1[0], wp1[1]];
        if p.pursuit > 0.0
            && let Some(along) = self.trace.pursuit(obs, p.pursuit)
        {
            // The plan's speed, along the path.
            let to = along.toward;
            let (speed, d) = (v_plan[0].hypot(v_plan[1]), to[0].hypot(to[1]));
            if d > 1e-6 {
                v_plan = to.map(|v| v * speed / d);
            }
            face = along.face;
        }
        let heading_err = if face[0].hypot(face[1]) > 0.2 {
            wrap_angle(face[1].atan2(face[0]))
        } else {
            0.0
        };
        // Just down, only creep sideways or back until facing the plan: the yaw rate
        // turns the body, and a crawl stepping sideways at speed rolls over a hand or
        // knee. Once aligned the plan's sideways speed counts again (under a ceiling
        // that yaws the body by its back, stepping back to the plan keeps it up).
        if self.aligning && heading_err.abs() < ALIGNED {
            self.aligning = false;
        }
        if p.realign_above > 0.0 && heading_err.abs() > p.realign_above && self.settled() {
            self.aligning = true;
        }
        if p.turn_slowdown > 0.0 {
            let keep = (1.0 - p.turn_slowdown * heading_err.abs()).max(0.0);
            v_plan = v_plan.map(|v| v * keep);
        }
        if self.aligning {
            v_plan[0] = v_plan[0].max(-p.max_side_speed);
            v_plan[1] = v_plan[1].clamp(-p.max_side_speed, p.max_side_speed);
        }
        let ground = Ground::new(obs, p.ground_ahead, p.reach_map);
        if p.top_below > 0.0 {
            let target = if obs.headroom < p.top_below { 1.0 } else { 0.0 };
            let share = self
                .under_top
                .map_or(target, |s| low_pass(s, target, CONTROL_DT, TOP_FILTER));
            self.under_top = Some(share);
        }
        if p.slope_pitch > 0.0 {
            let rise = self.ground_slope(&ground).max(0.0);
            self.slope = low_pass(self.slope, rise, CONTROL_DT, SLOPE_FILTER);
        }
        let f = self.frame(&ground);
        let nominal = self.nominal(&f);

        let targets = &mut out.pd_targets;
        targets.clear();
        targets.resize(NUM_JOINTS, 0.0);
        let (v_des, pitch_des, height_des, yaw_rate) = match self.mode {
            Mode::Down { t, pitch0, height0 } => {
                let s = smoothstep(t / p.down_time);
                let mut crawl = [0.0; NUM_JOINTS];
                // Hands reach further ahead the faster the body still moves, so the
                // arms brake it instead of the body rolling over them onto its head.
                let mut reach = nominal;
                for hand in &mut reach[2..] {
                    hand[0] += p.down_reach * vx.max(0.0);
                }
                let contacts = self.grounded(&ground, &reach);
                self.pose_targets(&f, &contacts, [0.0; 2], [false; 2], [None; 2], &mut crawl);
                self.through_squat(false, &self.from, &crawl, t / p.down_time, targets);
                // Into the squat only: kneeling, the crawl's own roll feedback takes over.
                let fade = match self.squat_phase(t / p.down_time) {
                    (true, _) => 1.0,
                    (false, out) => 1.0 - out,
                };
                self.level_legs(fade * p.down_level, roll, targets);
                let t = t + CONTROL_DT;
                self.mode = if t >= p.down_time {
                    // The crawl starts from rest (its desired velocity ramps up): the
                    // velocity at the switch (a walk's) is long gone, and sweeping the
                    // limbs at it pitched the body onto its head.
                    self.v_cmd = [0.0; 2];
                    self.v_filt = [vx, vy];
                    self.aligning = true;
                    Mode::Crawl
                } else {
                    Mode::Down { t, pitch0, height0 }
                };
                // Squatting on ground that falls away behind or beside the feet, the
                // centre of mass left them and the body sat down the hill onto its
                // back or side: the residual pushes it back over the feet.
                let push = if p.down_com_gain > 0.0 {
                    let (com, band) = com_over_feet(&self.mass_fraction, obs);
                    [
                        p.down_com_gain * (-com[0] - p.down_com_behind).max(0.0),
                        -p.down_com_gain * (com[1] - com[1].clamp(band[0], band[1])),
                    ]
                } else {
                    [0.0; 2]
                };
                (
                    push,
                    pitch0 + s * (f.pelvis_pitch - pitch0),
                    height0 + s * (f.pelvis_height - height0),
                    0.0,
                )
            }
            Mode::Up { t, pitch0, height0 } => {
                let s = smoothstep(t / p.up_time);
                let j = &self.joints;
                let mut stand = [0.0; NUM_JOINTS];
                for leg in 0..2 {
                    stand[j.hip[leg][1]] = STAND[0];
                    stand[j.knee[leg]] = STAND[1];
                    stand[j.ankle[leg][0]] = STAND[2];
                }
                self.through_squat(true, &self.from, &stand, t / p.up_time, targets);
                self.level_legs(p.up_level, roll, targets);
                let (into, out) = self.squat_phase(t / p.up_time);
                let ahead = com_over_feet(&self.mass_fraction, obs).0[0];
                // Straightening legs that tip the body forward hand it to the biped,
                // whose steps can catch it: the get-up is over.
                let tipping =
                    !into && ahead > p.up_handoff_ahead && obs.root_height > p.up_handoff_height;
                self.mode = Mode::Up {
                    t: if tipping { p.up_time } else { t + CONTROL_DT },
                    pitch0,
                    height0,
                };
                let stand_height = plamo_physics::humanoid::STANDING_PELVIS_HEIGHT - 0.02;
                // Sitting back into the squat must let the pelvis sink onto the heels:
                // no lift until the legs straighten.
                let height = if into {
                    obs.root_height.min(height0)
                } else {
                    obs.root_height.min(height0) + out * (stand_height - height0).max(0.0)
                };
                // The hands push the body back over the feet while sitting back. The
                // legs must straighten under the centre of mass: ahead of the ankles,
                // the straightening legs tipped the whole body onto its face.
                let back = if into { -p.sit_back_speed } else { 0.0 }
                    - p.up_com_gain * (ahead - p.up_com_ahead).max(0.0);
                ([back, 0.0], pitch0 * (1.0 - s), height, 0.0)
            }
            Mode::Crawl => {
                let dv = p.max_accel * CONTROL_DT;
                for (c, want) in self.v_cmd.iter_mut().zip(v_plan) {
                    *c += (want - *c).clamp(-dv, dv);
                }
                let yaw_rate = (p.yaw_gain * heading_err).clamp(-p.max_yaw_rate, p.max_yaw_rate);
                for k in 0..2 {
                    self.v_filt[k] =
                        low_pass(self.v_filt[k], [vx, vy][k], CONTROL_DT, p.vel_filter);
                    self.v_slip[k] = (self.v_slip[k]
                        + p.slip_gain * (self.v_cmd[k] - self.v_filt[k]) * CONTROL_DT)
                        .clamp(-p.max_slip, p.max_slip);
                }
                // What the stance limbs sweep back at: the desired velocity plus what
                // slipped, less while the body pitches onto its head.
                let dive = (pitch - f.pelvis_pitch - p.dive_margin).max(0.0);
                let keep = (1.0 - p.dive_slowdown * dive).clamp(0.0, 1.0);
                let v_gait = [
                    keep * (self.v_cmd[0] + self.v_slip[0]),
                    keep * (self.v_cmd[1] + self.v_slip[1]),
                ];
                let speed = v_gait[0].hypot(v_gait[1]);
                let fast = (self.v_cmd[0].hypot(self.v_cmd[1]) / p.duty_speed).min(1.0);
                let duty = p.duty + fast * (p.fast_duty - p.duty);
                let cycle = (p.max_stride / (speed * duty).max(1e-6)).clamp(p.min_cycle, p.cycle);
                self.phase = (self.phase + CONTROL_DT / cycle).fract();
                let stance_time = cycle * duty;
                let mut xy = [[0.0; 2]; LIMBS];
                let mut land_xy = [[0.0; 2]; LIMBS];
                let mut lift = [0.0; LIMBS];
                for i in 0..LIMBS {
                    let local = (self.phase - p.offsets[i]).rem_euclid(1.0);
                    // Contact velocity relative to the body: -(v + w x r).
                    let [nx, ny] = nominal[i];
                    let vel = [v_gait[0] - yaw_rate * ny, v_gait[1] + yaw_rate * nx];
                    if local < duty {
                        self.in_swing[i] = false;
                        for (o, v) in self.offset[i].iter_mut().zip(vel) {
                            *o -= v * CONTROL_DT;
                        }
                    } else {
                        if !self.in_swing[i] {
                            self.in_swing[i] = true;
                            self.lift_off[i] = self.offset[i];
                        }
                        let s_lin = ((local - duty) / (1.0 - duty)).min(1.0);
                        let s = smoothstep(s_lin + CONTROL_DT / (cycle * (1.0 - duty)));
                        for (k, (o, v)) in self.offset[i].iter_mut().zip(vel).enumerate() {
                            let land = 0.5 * v * stance_time
                                + p.place_gain * (self.v_filt[k] - self.v_cmd[k]);
                            let l = self.lift_off[i][k];
                            *o = l + s * (land - l);
                            land_xy[i][k] = nominal[i][k] + land;
                        }
                        let h = if i < 2 { p.knee_lift } else { p.hand_lift };
                        lift[i] = h * (PI * s_lin).sin();
                    }
                    for k in 0..2 {
                        self.offset[i][k] = self.offset[i][k].clamp(-p.max_stride, p.max_stride);
                    }
                    xy[i] = [nx + self.offset[i][0], ny + self.offset[i][1]];
                }
                let mut contacts = self.grounded(&ground, &xy);
                let mut step_up = [None; 2];
                for i in 0..LIMBS {
                    if lift[i] > 0.0 {
                        // Clear the highest ground between lift-off and landing.
                        let [x0, y0] = [
                            nominal[i][0] + self.lift_off[i][0],
                            nominal[i][1] + self.lift_off[i][1],
                        ];
                        let rest = if i < 2 { KNEE_RADIUS } else { self.arm_rest() };
                        let start = ground.at(x0, y0);
                        let land = ground.with_plan(land_xy[i][0], land_xy[i][1]);
                        let mut over = start.max(contacts[i][2] - rest);
                        if p.swing_ahead {
                            over = over.max(land);
                        }
                        if i < 2 && p.knee_step_up > 0.0 && land - start >= p.knee_step_up {
                            step_up[i] = Some(pitch);
                            over += rest;
                        }
                        contacts[i][2] = contacts[i][2].max(over) + lift[i];
                    }
                }
                // Stance limbs straighten what sags: lower a contact target (relative
                // to the body) where the body is low.
                let pitch_err = pitch - f.pelvis_pitch;
                let height_err = f.pelvis_height - obs.root_height;
                for (c, n) in contacts.iter_mut().zip(&nominal) {
                    c[2] += p.attitude_gain * (roll * n[1] - pitch_err * n[0])
                        - p.height_gain_limbs * height_err;
                }
                if p.roll_reach > 0.0 || p.roll_rate_reach > 0.0 {
                    // The low side's limbs reach down, the high side's draw up.
                    let lean = roll.signum() * (roll.abs() - p.roll_reach_from).max(0.0);
                    let smooth = if p.roll_reach_smooth_only {
                        1.0 - self.rough
                    } else {
                        1.0
                    };
                    let per_lever = smooth * (p.roll_reach * lean + p.roll_rate_reach * wx);
                    for ((c, n), l) in contacts.iter_mut().zip(&nominal).zip(&lift) {
                        let reach = (per_lever * n[1]).clamp(-MAX_ROLL_REACH, MAX_ROLL_REACH);
                        c[2] += if *l > 0.0 { reach.max(0.0) } else { reach };
                    }
                }
                if p.head_push > 0.0 {
                    // The measured head sinking towards the ground under it: the
                    // stance hands push the front up.
                    let [hx, hy, hz] = obs.head_pos;
                    let clear = obs.root_height + hz - ground.with_plan(hx, hy);
                    let push = (p.head_push * (p.head_clear - clear)).clamp(0.0, MAX_HEAD_PUSH);
                    for (c, swing) in contacts[2..].iter_mut().zip(&self.in_swing[2..]) {
                        if !swing {
                            c[2] -= push;
                        }
                    }
                }
                let load = 0.5 * p.hand_load * self.settings.body_mass * GRAVITY;
                let hand_force = [2, 3].map(|i| if self.in_swing[i] { 0.0 } else { load });
                let arm_swing = [self.in_swing[2], self.in_swing[3]];
                self.pose_targets(&f, &contacts, hand_force, arm_swing, step_up, targets);
                (self.v_cmd, f.pelvis_pitch, f.pelvis_height, yaw_rate)
            }
        };

        // Bounded residual root wrench, heading frame then world. Getting down or up,
        // the feet stay planted: a yaw torque towards a plan far off the body's heading
        // (after a reset) only twists the body over them, so only small errors count.
        let yaw_err = if self.mode == Mode::Crawl {
            heading_err
        } else {
            heading_err.clamp(-TRANSITION_YAW_ERR, TRANSITION_YAW_ERR)
        };
        let m = self.settings.body_mass;
        let force = residual_force(
            m,
            p.vel_gain,
            [v_des[0] - vx, v_des[1] - vy],
            p.height_gain,
            height_des - obs.root_height,
            p.height_damping,
            vz,
        );
        let torque = [
            -(p.rot_gain * roll + p.rot_damping * wx),
            -(p.rot_gain * (pitch - pitch_des) + p.rot_damping * wy),
            p.yaw_torque_gain * yaw_err + p.rot_damping * (yaw_rate - wz),
        ];
        let cap = self.settings.residual_torque_cap;
        let shared = share_torque(&p, cap, roll, torque);
        let (torque, cap) = extra_roll(&p, cap, roll, torque, shared);
        self.last_wrench = residual_wrench(&self.settings, cap, obs.heading, force, torque, out);
    }

    /// Back to crawling from rest (used when the controller is reset).
    pub(crate) fn reset(&mut self) {
        self.mode = Mode::Crawl;
        self.phase = 0.0;
        self.offset = [[0.0; 2]; LIMBS];
        self.in_swing = [false; LIMBS];
        self.v_cmd = [0.0; 2];
        self.v_filt = [0.0; 2];
        self.v_slip = [0.0; 2];
        self.aligning = false;
        self.rough = 0.0;
        self.slope = 0.0;
        self.under_top = None;
        self.trace.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_physics::FEET;

    /// An observation of the humanoid with its root 0.5 m up (a crawl's), the rest 0.
    fn crawling_obs() -> Observation {
        let mut obs = Observation::new(crate::observation::ObservationLayout {
            num_joints: NUM_JOINTS,
            num_bodies: BODIES.len(),
        });
        obs.root_height = 0.5;
        obs
    }

    /// `crawling_obs` rolled by `roll` \[rad\] (> 0: right side low).
    fn rolled_obs(roll: f64) -> Observation {
        let mut obs = crawling_obs();
        obs.root_rotation = [1.0, 0.0, 0.0, 0.0, roll.cos(), roll.sin()];
        obs
    }

    /// The residual torque (heading frame) of one step rolled `roll` \[rad\] (right
    /// side low) while the yaw wags at 2 rad/s.
    fn wagging_torque(params: CrawlParams, roll: f64) -> [f64; 3] {
        let mut obs = rolled_obs(roll);
        obs.root_ang_vel = [0.0, 0.0, 2.0];
        let mut gait = crawling_gait(params);
        gait.act(&obs, &mut Action::default());
        gait.last_wrench().torque
    }

    /// A crawl gait with `params`, down and crawling (reset from rest).
    fn crawling_gait(params: CrawlParams) -> CrawlGait {
        let mut gait = CrawlGait::new(params, ControllerSettings::default());
        gait.reset();
        gait
    }

    /// Fill `obs`'s height map with `map(x, y)` at each sample (heading frame).
    fn fill_map(obs: &mut Observation, map: &dyn Fn(f64, f64) -> f64) {
        for r in 0..LOCAL_MAP_SIDE {
            for c in 0..LOCAL_MAP_SIDE {
                obs.height_map[r * LOCAL_MAP_SIDE + c] = map(map_coord(r), map_coord(c));
            }
        }
    }
    use crate::gait::map_plane::map_coord;
    use crate::observation::NUM_WAYPOINTS;

    #[test]
    fn built_in_parameters_validate_and_bad_ones_name_the_field() {
        CrawlParams::hands().validate().unwrap();
        let p = CrawlParams::default();
        p.validate().unwrap();
        let bad = CrawlParams { duty: 1.5, ..p };
        match bad.validate() {
            Err(ControllerError::InvalidSettings { field, .. }) => assert_eq!(field, "duty"),
            other => panic!("{other:?}"),
        }
        let bad = CrawlParams {
            stand_above: p.crawl_below,
            ..p
        };
        assert!(bad.validate().is_err());
        let text = DEFAULT_CRAWL_PARAMS.replace("duty", "dutty");
        assert!(CrawlParams::from_toml(&text, Path::new("x")).is_err());
    }

    #[test]
    fn the_forearm_crawl_validates_and_lays_its_forearms_along_the_ground() {
        // No gravity feed-forward, so the shoulder's target is the IK's alone.
        let p = CrawlParams {
            hand_load: 0.0,
            ..CrawlParams::default()
        };
        assert!(p.forearms);
        let mut obs = crawling_obs();
        for i in 0..NUM_WAYPOINTS {
            obs.waypoints[i] = [(i + 1) as f64 * WAYPOINT_SPACING * 0.5, 0.0, 0.0];
            obs.waypoint_speeds[i] = 0.5;
        }
        let mut gait = CrawlGait::new(p, ControllerSettings::default());
        gait.reset();
        let j = Joints::resolve();
        let mut out = Action::default();
        let mut seen = [[false; 2]; 2];
        for _ in 0..(3.0 / CONTROL_DT) as usize {
            gait.act(&obs, &mut out);
            for (arm, seen) in seen.iter_mut().enumerate() {
                // The forearm's pitch in the world: the desired torso's, the
                // shoulder's and the elbow's; -pi/2 lies it forward, level.
                let pitch = p.pelvis_pitch
                    + p.spine_pitch
                    + out.pd_targets[j.shoulder[arm][1]]
                    + out.pd_targets[j.elbow[arm]];
                let swing = gait.in_swing[2 + arm];
                let want = if swing {
                    -FRAC_PI_2 - p.forearm_lift
                } else {
                    -FRAC_PI_2 + p.forearm_press
                };
                assert!((pitch - want).abs() < 1e-9, "arm {arm}: {pitch} vs {want}");
                seen[swing as usize] = true;
            }
        }
        assert_eq!(seen, [[true; 2]; 2], "each arm both in stance and in swing");
        // Off, the same posture's arms reach for their hands: other elbow targets.
        let mut elbows = |p: CrawlParams| {
            let mut gait = CrawlGait::new(p, ControllerSettings::default());
            gait.reset();
            gait.act(&obs, &mut out);
            [0, 1].map(|a| out.pd_targets[j.elbow[a]])
        };
        let (on, off) = (
            elbows(p),
            elbows(CrawlParams {
                forearms: false,
                ..p
            }),
        );
        assert!((on[0] - off[0]).abs() > 0.1, "{on:?} vs {off:?}");
    }

    /// A settled crawl asked for 1 m/s straight ahead over a height map; the speed it
    /// commands after 4 s.
    fn commanded_speed(params: CrawlParams, map: impl Fn(f64, f64) -> f64) -> f64 {
        use crate::observation::NUM_WAYPOINTS;
        let mut obs = crawling_obs();
        for i in 0..NUM_WAYPOINTS {
            obs.waypoints[i] = [(i + 1) as f64 * WAYPOINT_SPACING, 0.0, 0.0];
            obs.waypoint_speeds[i] = 1.0;
        }
        fill_map(&mut obs, &map);
        let mut gait = crawling_gait(params);
        let mut out = Action::default();
        for _ in 0..(4.0 / CONTROL_DT) as usize {
            gait.act(&obs, &mut out);
        }
        gait.v_cmd[0].hypot(gait.v_cmd[1])
    }

    #[test]
    fn a_crawl_already_down_turns_first_where_its_plan_heads_off_with_realign_above() {
        // Crawling ahead at 1 m/s for 3 s, then the plan heads off 135 degrees to the
        // left (a crawl leg starting at a landmark); the speed commanded 1 s later.
        let speed_after_turn = |params: CrawlParams| {
            let mut obs = crawling_obs();
            let mut gait = crawling_gait(params);
            let mut out = Action::default();
            for (seconds, angle) in [(3.0, 0.0_f64), (1.0, 0.75 * PI)] {
                for i in 0..NUM_WAYPOINTS {
                    let d = (i + 1) as f64 * WAYPOINT_SPACING;
                    obs.waypoints[i] = [d * angle.cos(), d * angle.sin(), 0.0];
                    obs.waypoint_speeds[i] = 1.0;
                }
                for _ in 0..(seconds / CONTROL_DT) as usize {
                    gait.act(&obs, &mut out);
                }
            }
            gait.v_cmd[0].hypot(gait.v_cmd[1])
        };
        let p = CrawlParams {
            realign_above: 1.0,
            ..CrawlParams::default()
        };
        let turning = speed_after_turn(p);
        assert!(
            turning <= p.max_side_speed * 2f64.sqrt() + 1e-9,
            "{turning} m/s"
        );
        let off = speed_after_turn(CrawlParams {
            realign_above: 0.0,
            ..p
        });
        assert!(off > 0.5, "without realign_above: {off} m/s");
    }

    #[test]
    fn a_turning_crawl_slows_with_its_heading_error_under_turn_slowdown() {
        // The plan heads off 0.6 rad to the left at 0.6 m/s, under `realign_above`;
        // the speed commanded after 2 s.
        let speed = |turn_slowdown: f64| {
            let mut obs = crawling_obs();
            let angle = 0.6_f64;
            for i in 0..NUM_WAYPOINTS {
                let d = (i + 1) as f64 * WAYPOINT_SPACING * 0.6;
                obs.waypoints[i] = [d * angle.cos(), d * angle.sin(), 0.0];
                obs.waypoint_speeds[i] = 0.6;
            }
            let mut gait = crawling_gait(CrawlParams {
                turn_slowdown,
                realign_above: 1.0,
                pursuit: 0.0,
                ..CrawlParams::default()
            });
            let mut out = Action::default();
            for _ in 0..(2.0 / CONTROL_DT) as usize {
                gait.act(&obs, &mut out);
            }
            gait.v_cmd[0].hypot(gait.v_cmd[1])
        };
        let off = speed(0.0);
        assert!((off - 0.6).abs() < 0.01, "without turn_slowdown: {off} m/s");
        let on = speed(1.0);
        assert!((on - 0.4 * 0.6).abs() < 0.01, "turn_slowdown 1: {on} m/s");
    }

    #[test]
    fn the_get_up_pushes_back_while_the_centre_of_mass_is_ahead_of_the_ankles() {
        // Every body 0.1 m ahead of the root but the feet, 0.15 m behind it: the
        // centre of mass is ~0.24 m ahead of the ankles.
        let obs_with = |ahead: bool| {
            let mut obs = crawling_obs();
            for (b, p) in obs.body_pos.iter_mut().enumerate() {
                *p = match (ahead, FEET.contains(&b)) {
                    (false, _) => [0.0, 0.0, 0.0],
                    (true, true) => [-0.15, 0.0, -0.4],
                    (true, false) => [0.1, 0.0, 0.0],
                };
            }
            obs
        };
        // The residual force forward in the sit-back's first step and in the
        // straightening's first step.
        let push = |params: CrawlParams, ahead: bool| {
            let obs = obs_with(ahead);
            let mut gait = crawling_gait(params);
            gait.begin_up(&obs);
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            let sit = gait.last_wrench().force[0];
            for _ in 0..(params.squat_share * params.up_time / CONTROL_DT).ceil() as usize {
                gait.act(&obs, &mut out);
            }
            [sit, gait.last_wrench().force[0]]
        };
        let off = CrawlParams {
            up_com_ahead: 0.0,
            up_com_gain: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            up_com_ahead: 0.08,
            up_com_gain: 10.0,
            ..off
        };
        let [sit_off, lift_off] = push(off, true);
        let [sit_on, lift_on] = push(on, true);
        assert!(sit_on < sit_off - 50.0, "{sit_on} N against {sit_off} N");
        assert!(
            lift_on < lift_off - 50.0,
            "{lift_on} N against {lift_off} N"
        );
        // Over the ankles: no extra push.
        assert_eq!(push(on, false), push(off, false));
    }

    #[test]
    fn a_get_up_tipping_forward_as_the_legs_straighten_hands_over_to_the_biped() {
        // Control steps of the get-up until it is over, for a body whose centre of mass
        // is `ahead` \[m\] ahead of its ankles (every body there but the feet) and
        // whose pelvis is `height` \[m\] up.
        let steps_to_stand = |ahead: f64, height: f64| {
            let mut obs = crawling_obs();
            for (b, p) in obs.body_pos.iter_mut().enumerate() {
                *p = if FEET.contains(&b) {
                    [0.0, 0.0, -0.4]
                } else {
                    [ahead, 0.0, 0.0]
                };
            }
            obs.root_height = height;
            let params = CrawlParams::default();
            let mut gait = crawling_gait(params);
            gait.begin_up(&obs);
            let mut out = Action::default();
            (1..200)
                .find(|_| {
                    gait.act(&obs, &mut out);
                    gait.stood_up()
                })
                .unwrap()
        };
        let p = CrawlParams::default();
        let squat = (p.squat_share * p.up_time / CONTROL_DT).ceil() as usize;
        let whole = (p.up_time / CONTROL_DT).round() as usize;
        // Far ahead with the pelvis up: over as soon as the legs start to straighten.
        let tipping = steps_to_stand(0.5, 0.6);
        assert!(
            (squat..squat + 3).contains(&tipping),
            "{tipping} (squat {squat})"
        );
        // Over the feet, or with the legs still too bent to step: the whole get-up.
        for (ahead, height) in [(0.1, 0.6), (0.5, 0.4)] {
            let n = steps_to_stand(ahead, height);
            assert!(
                n + 1 >= whole,
                "ahead {ahead}, height {height}: {n} of {whole}"
            );
        }
    }

    /// Knee, hip and ankle pitch targets (right, left) `secs` into the get-up (or,
    /// `down`, the get-down) of a body rolled `roll` (> 0: right side low).
    fn transition_legs(params: CrawlParams, roll: f64, down: bool, secs: f64) -> [[f64; 3]; 2] {
        let obs = rolled_obs(roll);
        let mut gait = crawling_gait(params);
        if down {
            gait.begin_down(&obs);
        } else {
            gait.begin_up(&obs);
        }
        let mut out = Action::default();
        for _ in 0..(secs / CONTROL_DT) as usize {
            gait.act(&obs, &mut out);
        }
        let (j, q) = (&gait.joints, &out.pd_targets);
        [0, 1].map(|leg| [q[j.knee[leg]], q[j.hip[leg][1]], q[j.ankle[leg][0]]])
    }

    #[test]
    fn the_get_down_straightens_the_low_sides_leg_into_the_squat_under_down_level() {
        let off = CrawlParams {
            down_level: 0.0,
            up_level: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            down_level: 1.0,
            ..off
        };
        // Into the squat (0.5 s of the 1.5 s get-down): the right (low) knee 0.2 rad
        // straighter than without, the left 0.2 rad more bent.
        let [right, left] = transition_legs(on, 0.2, true, 0.5);
        let [right_off, left_off] = transition_legs(off, 0.2, true, 0.5);
        assert!(
            (right[0] - (right_off[0] - 0.2)).abs() < 1e-9,
            "{right:?} / {right_off:?}"
        );
        assert!(
            (left[0] - (left_off[0] + 0.2)).abs() < 1e-9,
            "{left:?} / {left_off:?}"
        );
        // Kneeling at the end: nearly faded out (0.2 rad into the squat).
        let end = off.down_time - CONTROL_DT;
        let knee = |p| transition_legs(p, 0.2, true, end)[0][0];
        assert!(
            (knee(on) - knee(off)).abs() < 0.02,
            "{} / {}",
            knee(on),
            knee(off)
        );
        // The get-up does not read it.
        assert_eq!(
            transition_legs(on, 0.2, false, 1.0),
            transition_legs(off, 0.2, false, 1.0)
        );
    }

    #[test]
    fn the_get_up_straightens_the_low_sides_leg_under_up_level() {
        let legs = |params: CrawlParams, roll: f64| transition_legs(params, roll, false, 1.0);
        let off = CrawlParams {
            up_level: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            up_level: 1.0,
            ..off
        };
        let [right, left] = legs(on, 0.2);
        let [right_off, left_off] = legs(off, 0.2);
        assert_eq!(right_off, left_off, "off: the legs move alike");
        // The right knee straightens by 0.2 rad, the left bends by 0.2; hip and ankle
        // take half of it the other way, so the foot keeps its pitch.
        for (k, (a, b)) in [(right, right_off), (left, left_off)]
            .into_iter()
            .enumerate()
        {
            let e = if k == 0 { 0.2 } else { -0.2 };
            assert!((a[0] - (b[0] - e)).abs() < 1e-9, "knee {a:?} against {b:?}");
            assert!(
                (a[1] - (b[1] + 0.5 * e)).abs() < 1e-9,
                "hip {a:?} against {b:?}"
            );
            assert!(
                (a[2] - (b[2] + 0.5 * e)).abs() < 1e-9,
                "ankle {a:?} against {b:?}"
            );
        }
        // Rolled left: the other way round.
        let [right_l, left_l] = legs(on, -0.2);
        assert!(right_l[0] > left_l[0], "{right_l:?} against {left_l:?}");
    }

    #[test]
    fn the_get_down_pushes_the_centre_of_mass_back_over_the_feet() {
        // Every body `com` off the root but the feet, at the root: the centre of mass
        // is ~0.9 `com` off the ankles' midpoint.
        let obs_with = |com: [f64; 2]| {
            let mut obs = crawling_obs();
            for (b, p) in obs.body_pos.iter_mut().enumerate() {
                let foot_y = if b == FEET[0] { -0.1 } else { 0.1 };
                *p = if FEET.contains(&b) {
                    [0.0, foot_y, -0.9]
                } else {
                    [com[0], com[1], 0.0]
                };
            }
            obs
        };
        // The residual force (forward, left) in the get-down's first step.
        let push = |params: CrawlParams, com: [f64; 2]| {
            let obs = obs_with(com);
            let mut gait = crawling_gait(params);
            gait.begin_down(&obs);
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            let f = gait.last_wrench().force;
            [f[0], f[1]]
        };
        let off = CrawlParams {
            down_com_behind: 0.0,
            down_com_gain: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            down_com_behind: 0.08,
            down_com_gain: 10.0,
            ..off
        };
        // 0.25 m behind the ankles: pushed forward.
        let [fwd_off, _] = push(off, [-0.25, 0.0]);
        let [fwd_on, _] = push(on, [-0.25, 0.0]);
        assert!(fwd_on > fwd_off + 50.0, "{fwd_on} N against {fwd_off} N");
        // 0.25 m left of the ankles (0.1 m each side): pushed right.
        let [_, left_off] = push(off, [0.0, 0.25]);
        let [_, left_on] = push(on, [0.0, 0.25]);
        assert!(
            left_on < left_off - 50.0,
            "{left_on} N against {left_off} N"
        );
        // Over the feet, or within `down_com_behind` of the ankles: no push.
        assert_eq!(push(on, [0.0, 0.05]), push(off, [0.0, 0.05]));
        assert_eq!(push(on, [-0.05, 0.0]), push(off, [-0.05, 0.0]));
    }

    #[test]
    fn rough_speed_slows_the_crawl_on_stairs_not_on_slopes() {
        let old = CrawlParams {
            rough_step: 4.0,
            ..CrawlParams::hands()
        };
        let rough = CrawlParams {
            rough_step: 0.03,
            rough_speed: 0.3,
            ..old
        };
        // The random scenes' steepest stairs, 0.15 m x 0.31 m; a 20 degree side slope.
        let stairs = |x: f64, _y: f64| 0.15 * (x / 0.31).floor();
        let slope = |_x: f64, y: f64| 0.36 * y;
        let full = rough.max_speed;
        assert!((commanded_speed(rough, |_, _| 0.0) - full).abs() < 1e-9);
        assert!((commanded_speed(rough, slope) - full).abs() < 1e-9);
        let on_stairs = commanded_speed(rough, stairs);
        assert!(
            on_stairs <= rough.rough_speed + 0.05 && on_stairs < full - 0.2,
            "{on_stairs} m/s on stairs (rough_speed {})",
            rough.rough_speed
        );
        assert!((commanded_speed(old, stairs) - full).abs() < 1e-9);
    }

    #[test]
    fn roll_comes_first_in_the_residual_torque() {
        let roll_torque = |params: CrawlParams| wagging_torque(params, 0.4)[0];
        let cap = ControllerSettings::default().residual_torque_cap;
        let old = CrawlParams {
            roll_first: false,
            yaw_last: false,
            ..CrawlParams::hands()
        };
        let first = roll_torque(CrawlParams {
            roll_first: true,
            roll_first_from: 0.0,
            ..old
        });
        assert!((first + cap).abs() < 1e-9, "{first}");
        let shared = roll_torque(old);
        assert!(shared > -0.7 * cap, "{shared}");
    }

    #[test]
    fn a_roll_under_way_gets_the_extra_roll_torque() {
        let torque = wagging_torque;
        let cap = ControllerSettings::default().residual_torque_cap;
        // A stiff roll gain, so that the roll torque asks for more than any budget.
        let off = CrawlParams {
            roll_first: true,
            roll_first_from: 0.2,
            rot_gain: 1000.0,
            roll_torque_extra: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            roll_torque_extra: 60.0,
            ..off
        };
        // Past twice `roll_first_from`: all of the extra, to roll alone.
        let (a, b) = (torque(off, 0.5), torque(on, 0.5));
        assert!((a[0] + cap).abs() < 1e-9, "{a:?}");
        assert!((b[0] + cap + 60.0).abs() < 1e-9, "{b:?}");
        assert_eq!((a[1], a[2]), (b[1], b[2]));
        // Halfway into the roll's priority: half of it.
        let (a, b) = (torque(off, 0.3), torque(on, 0.3));
        assert!((b[0] - (a[0] - 30.0)).abs() < 1e-9, "{a:?} {b:?}");
        assert_eq!((a[1], a[2]), (b[1], b[2]));
        // Below `roll_first_from`: none, bit for bit.
        assert_eq!(torque(off, 0.1), torque(on, 0.1));
    }

    #[test]
    fn the_low_sides_arm_reaches_down_with_roll_reach() {
        // Elbow targets (right, left) of a crawl rolled `roll` (right side low) at a
        // roll rate `rate`.
        let elbows = |params: CrawlParams, roll: f64, rate: f64| {
            let mut obs = rolled_obs(roll);
            obs.root_ang_vel = [rate, 0.0, 0.0];
            let mut gait = crawling_gait(params);
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            ["right_elbow", "left_elbow"].map(|n| out.pd_targets[idx(n)])
        };
        let off = CrawlParams {
            roll_reach: 0.0,
            roll_rate_reach: 0.0,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            roll_reach: 1.0,
            roll_rate_reach: 0.2,
            ..off
        };
        for (roll, rate) in [(0.3, 0.0), (0.0, 1.5)] {
            let [r0, l0] = elbows(off, roll, rate);
            let [r1, l1] = elbows(on, roll, rate);
            // The right arm straightens, the left one bends.
            assert!(
                r1.abs() < r0.abs() - 0.02,
                "{roll} {rate}: right {r0} -> {r1}"
            );
            assert!(
                l1.abs() > l0.abs() + 0.02,
                "{roll} {rate}: left {l0} -> {l1}"
            );
        }
        // Level and still, the switch changes nothing.
        assert_eq!(elbows(off, 0.0, 0.0), elbows(on, 0.0, 0.0));
        // From 0.2 rad: a slight lean is left to `attitude_gain`, a larger one is not.
        let from = CrawlParams {
            roll_rate_reach: 0.0,
            roll_reach_from: 0.2,
            ..on
        };
        assert_eq!(elbows(off, 0.15, 0.0), elbows(from, 0.15, 0.0));
        let ([r0, _], [r1, _]) = (elbows(off, 0.4, 0.0), elbows(from, 0.4, 0.0));
        assert!(r1.abs() < r0.abs() - 0.02, "right {r0} -> {r1}");
    }

    #[test]
    fn a_swinging_limb_on_the_low_side_keeps_its_clearance_under_roll_reach() {
        // Right arm targets (shoulder pitch, elbow) and whether it swings, one step
        // from `phase`, rolled 0.3 rad right side low (the forearm crawl: its elbow is
        // the contact, placed by the shoulder and elbow together).
        let right_arm = |params: CrawlParams, phase: f64| {
            let obs = rolled_obs(0.3);
            let mut gait = crawling_gait(params);
            gait.phase = phase;
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            let t = ["right_shoulder_y", "right_elbow"].map(|n| out.pd_targets[idx(n)]);
            (t, gait.in_swing[2])
        };
        let off = CrawlParams {
            roll_reach: 0.0,
            roll_rate_reach: 0.0,
            ..CrawlParams::default()
        };
        let on = CrawlParams {
            roll_reach: 1.0,
            ..off
        };
        let (mut swings, mut stances) = (0, 0);
        for k in 0..40 {
            let phase = k as f64 / 40.0;
            let ((t0, swing), (t1, _)) = (right_arm(off, phase), right_arm(on, phase));
            if swing {
                // Reaching down mid-swing lowered the arm into a ledge's face: rapier's
                // crawl stalled or fell at the crawl suite's 0.15 m ledge.
                assert_eq!(t0, t1, "phase {phase}: the swinging arm reached down");
                swings += 1;
            } else if t0 != t1 {
                stances += 1;
            }
        }
        assert!(swings > 0, "no phase with the right arm in swing");
        assert!(
            stances > 10,
            "the right arm reached down in only {stances} stance phases"
        );
    }

    #[test]
    fn roll_reach_leaves_stairs_alone_with_roll_reach_smooth_only() {
        // The right elbow's target after 2 s rolled 0.4 rad (right side low) over a
        // height map.
        let right_elbow = |params: CrawlParams, map: &dyn Fn(f64, f64) -> f64| {
            let mut obs = rolled_obs(0.4);
            fill_map(&mut obs, map);
            let mut gait = crawling_gait(params);
            let mut out = Action::default();
            for _ in 0..(2.0 / CONTROL_DT) as usize {
                gait.phase = 0.0;
                gait.act(&obs, &mut out);
            }
            out.pd_targets[idx("right_elbow")]
        };
        let off = CrawlParams {
            roll_reach: 0.0,
            roll_rate_reach: 0.0,
            roll_reach_from: 0.0,
            roll_reach_smooth_only: false,
            rough_step: 0.03,
            ..CrawlParams::hands()
        };
        let smooth_only = CrawlParams {
            roll_reach: 1.5,
            roll_reach_smooth_only: true,
            ..off
        };
        let everywhere = CrawlParams {
            roll_reach_smooth_only: false,
            ..smooth_only
        };
        // The random scenes' steepest stairs, 0.15 m x 0.31 m.
        let stairs = |x: f64, _y: f64| 0.15 * (x / 0.31).floor();
        let flat = |_x: f64, _y: f64| 0.0;
        let (s0, s1, s2) = (
            right_elbow(off, &stairs),
            right_elbow(smooth_only, &stairs),
            right_elbow(everywhere, &stairs),
        );
        // (The stairs' rough share is a little short of 1.)
        assert!(
            s2.abs() < s0.abs() - 0.05,
            "stairs, everywhere: {s0} -> {s2}"
        );
        assert!(
            (s1 - s0).abs() < 0.25 * (s2 - s0).abs(),
            "stairs: {s0} -> {s1} ({s2} everywhere)"
        );
        let (f0, f1) = (right_elbow(off, &flat), right_elbow(smooth_only, &flat));
        assert!(f1.abs() < f0.abs() - 0.02, "flat: {f0} -> {f1}");
    }

    #[test]
    fn roll_takes_over_the_torque_budget_only_as_the_body_leans() {
        let cap = 60.0;
        // Roll, pitch and yaw each asking for most of the cap.
        let ask = [-50.0, 40.0, 100.0];
        let p = CrawlParams {
            roll_first: true,
            roll_first_from: 0.2,
            ..CrawlParams::hands()
        };
        let norm = |t: [f64; 3]| t.iter().map(|x| x * x).sum::<f64>().sqrt();
        let shared = {
            let n = norm(ask);
            ask.map(|x| x * cap / n)
        };
        let level = share_torque(&p, cap, 0.1, ask);
        assert!(
            level.iter().zip(shared).all(|(a, b)| (a - b).abs() < 1e-9),
            "{level:?}"
        );
        let leaning = share_torque(&p, cap, -0.45, ask);
        assert!((leaning[0] + 50.0).abs() < 1e-9, "{leaning:?}");
        let half = share_torque(&p, cap, 0.3, ask);
        assert!(half[0] < shared[0] - 1.0 && half[0] > -50.0, "{half:?}");
        for roll in [0.0, 0.1, 0.25, 0.3, 0.35, 0.4, 1.0] {
            let t = share_torque(&p, cap, roll, ask);
            assert!(norm(t) <= cap + 1e-9, "{roll}: {t:?}");
        }
    }

    #[test]
    fn yaw_gets_what_roll_and_pitch_leave() {
        let cap = 60.0;
        let ask = [-20.0, 30.0, 100.0];
        let p = CrawlParams {
            roll_first: false,
            yaw_last: true,
            ..CrawlParams::hands()
        };
        let t = share_torque(&p, cap, 0.1, ask);
        assert!(
            (t[0] + 20.0).abs() < 1e-9 && (t[1] - 30.0).abs() < 1e-9,
            "{t:?}"
        );
        let left = (cap * cap - 20.0 * 20.0 - 30.0 * 30.0).sqrt();
        assert!((t[2] - left).abs() < 1e-9, "{t:?}");
        // Off, the yaw's request crowds the others out (the norm cap comes later).
        let off = CrawlParams {
            roll_first: false,
            yaw_last: false,
            ..CrawlParams::hands()
        };
        assert_eq!(share_torque(&off, cap, 0.1, ask), ask);
    }

    #[test]
    fn the_hands_see_the_plans_ground_beyond_the_map() {
        // Flat under the body (the map), a tread 0.15 m up under the plan ahead: the
        // crawl's head 0.6 m ahead of the root, its waypoints from 0.85 m on.
        let mut obs = crawling_obs();
        obs.head_pos = [0.6, 0.0, -0.15];
        for i in 0..NUM_WAYPOINTS {
            obs.waypoints[i] = [0.25 * (i + 1) as f64, 0.0, 0.0];
        }
        obs.waypoint_ground = [0.15; NUM_WAYPOINTS];
        let off = CrawlParams {
            ground_ahead: false,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            ground_ahead: true,
            ..off
        };
        let gait = |p: CrawlParams| CrawlGait::new(p, ControllerSettings::default());
        let (g_off, g_on) = (
            Ground::new(&obs, false, false),
            Ground::new(&obs, true, false),
        );
        // Inside the map both read the map; beyond it only the switch sees the tread.
        assert_eq!(g_on.at(0.2, 0.1), 0.0);
        assert_eq!(g_off.at(0.52, 0.1), 0.0);
        let hand = g_on.at(0.52, 0.1);
        assert!((hand - 0.15 * 0.17 / 0.5).abs() < 1e-9, "{hand}");
        assert!((g_on.at(3.0, 0.0) - 0.15).abs() < 1e-9);
        let (f_off, f_on) = (gait(off).frame(&g_off), gait(on).frame(&g_on));
        assert!(
            f_on.pelvis_height > f_off.pelvis_height + 0.01,
            "{} vs {}",
            f_on.pelvis_height,
            f_off.pelvis_height
        );
        // A plan off to the side has its ground elsewhere: not taken.
        for w in &mut obs.waypoints {
            w[1] = 3.0 * (w[0] + 0.6);
        }
        assert_eq!(Ground::new(&obs, true, false).at(0.52, 0.1), 0.0);
    }

    #[test]
    fn the_body_pitches_up_stairs_only_with_slope_pitch() {
        // The body's desired pelvis pitch after 1.5 s at rest over stairs of 0.15 m x
        // 0.31 m rising (`up`) or falling ahead, the plan's ground beyond the map on
        // the same stairs.
        let pitch = |params: CrawlParams, up: bool| {
            let sign = if up { 1.0 } else { -1.0 };
            let stairs = |x: f64| sign * 0.15 * (x / 0.31).floor();
            let mut obs = crawling_obs();
            obs.head_pos = [0.6, 0.0, -0.15];
            fill_map(&mut obs, &|x, _| stairs(x));
            for i in 0..NUM_WAYPOINTS {
                let x = 0.25 * (i + 1) as f64;
                obs.waypoints[i] = [x, 0.0, 0.0];
                obs.waypoint_ground[i] = stairs(x + 0.6);
            }
            let mut gait = crawling_gait(params);
            let mut out = Action::default();
            for _ in 0..(1.5 / CONTROL_DT) as usize {
                gait.act(&obs, &mut out);
            }
            gait.frame(&Ground::new(&obs, params.ground_ahead, false))
                .pelvis_pitch
        };
        let off = CrawlParams {
            slope_pitch: 0.0,
            ground_ahead: true,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            slope_pitch: 1.0,
            ..off
        };
        let level = off.pelvis_pitch;
        assert_eq!(pitch(off, true), level);
        assert_eq!(pitch(off, false), level);
        // The stairs' mean slope is 0.45 rad; between knees and hands ~0.5 m apart
        // the treads under them decide.
        let up = pitch(on, true);
        assert!(
            up < level - 0.2 && up > level - 0.8,
            "up {up} (level {level})"
        );
        assert_eq!(pitch(on, false), level);
    }

    #[test]
    fn the_body_takes_top_pitch_under_a_low_top_only() {
        let params = CrawlParams {
            pelvis_pitch: 0.5,
            top_pitch: 0.6,
            top_below: 0.75,
            slope_pitch: 0.0,
            ..CrawlParams::default()
        };
        let mut obs = crawling_obs();
        let mut gait = crawling_gait(params);
        let mut out = Action::default();
        let mut run = |gait: &mut CrawlGait, headroom: f64, seconds: f64| {
            obs.headroom = headroom;
            for _ in 0..(seconds / CONTROL_DT).round() as usize {
                gait.act(&obs, &mut out);
            }
            gait.frame(&Ground::new(&obs, params.ground_ahead, params.reach_map))
                .pelvis_pitch
        };
        assert_eq!(run(&mut gait, f64::INFINITY, 1.0), 0.5);
        // A top with room to spare changes nothing.
        assert_eq!(run(&mut gait, 0.9, 1.0), 0.5);
        // A low one: the pitch moves over a few strides, not at once.
        let first = run(&mut gait, 0.6, CONTROL_DT);
        assert!(first > 0.5 && first < 0.53, "{first}");
        assert!((run(&mut gait, 0.6, 3.0) - 0.6).abs() < 1e-3);
        // Out again, back to the open pitch.
        assert!((run(&mut gait, f64::INFINITY, 3.0) - 0.5).abs() < 1e-3);
        // Reset (a fall put back) under the top: the low pitch at once.
        gait.reset();
        assert_eq!(run(&mut gait, 0.6, CONTROL_DT), 0.6);
        // Off (`top_below` 0): `pelvis_pitch` under any top.
        let mut off = crawling_gait(CrawlParams {
            top_below: 0.0,
            ..params
        });
        assert_eq!(run(&mut off, 0.6, 1.0), 0.5);
    }

    #[test]
    fn the_reach_map_shows_a_ledge_the_plan_does_not_cross() {
        // Flat under the body (the map); a 0.2 m ledge from 0.45 m ahead, across the
        // reach map only: the plan runs off to the side over level ground.
        let mut obs = crawling_obs();
        obs.head_pos = [0.55, 0.0, -0.15];
        for i in 0..NUM_WAYPOINTS {
            obs.waypoints[i] = [0.0, 0.25 * (i + 1) as f64, 0.0];
        }
        for (k, h) in obs.reach_map.iter_mut().enumerate() {
            let x = (REACH_FIRST_ROW + (k / LOCAL_MAP_SIDE) as f64) * LOCAL_MAP_SPACING;
            *h = if x >= 0.45 - 1e-9 { 0.2 } else { 0.0 };
        }
        let on = CrawlParams {
            reach_map: true,
            ..CrawlParams::default()
        };
        let off = CrawlParams {
            reach_map: false,
            ..on
        };
        let ground = |p: &CrawlParams| Ground::new(&obs, p.ground_ahead, p.reach_map);
        let (g_off, g_on) = (ground(&off), ground(&on));
        // Inside the map both read it; ahead of it only the reach map has the ledge.
        assert_eq!(g_on.at(0.3, 0.1), g_off.at(0.3, 0.1));
        assert_eq!(g_off.at(0.6, 0.1), 0.0);
        assert!((g_on.at(0.6, 0.1) - 0.2).abs() < 1e-12);
        // Halfway between the map's front row (0.35 m) and the reach map's first.
        assert!(
            (g_on.at(0.4, 0.0) - 0.1).abs() < 1e-9,
            "{}",
            g_on.at(0.4, 0.0)
        );
        // Beyond the reach map's last row (0.85 m) its front row goes on.
        assert!((g_on.at(2.0, 0.0) - 0.2).abs() < 1e-12);
        // The head keeps its clearance over the ledge: the pelvis rises.
        let gait = |p: CrawlParams| CrawlGait::new(p, ControllerSettings::default());
        let (f_off, f_on) = (gait(off).frame(&g_off), gait(on).frame(&g_on));
        assert!(
            f_on.pelvis_height > f_off.pelvis_height + 0.05,
            "{} vs {}",
            f_on.pelvis_height,
            f_off.pelvis_height
        );
    }

    #[test]
    fn the_head_clears_a_tread_ahead_only_with_head_clear() {
        // Flat under the body (the map); the plan's ground beyond it flat (`tread` 0)
        // or a tread 0.2 m up from the map's edge on.
        let height = |params: CrawlParams, tread: f64| {
            let mut obs = crawling_obs();
            obs.head_pos = [0.6, 0.0, -0.15];
            for i in 0..NUM_WAYPOINTS {
                obs.waypoints[i] = [0.25 * i as f64 - 0.2, 0.0, 0.0];
            }
            obs.waypoint_ground = [tread; NUM_WAYPOINTS];
            let gait = CrawlGait::new(params, ControllerSettings::default());
            gait.frame(&Ground::new(&obs, params.ground_ahead, false))
                .pelvis_height
        };
        let off = CrawlParams {
            head_clear: 0.0,
            head_push: 0.0,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            head_clear: 0.3,
            ..off
        };
        let level = height(off, 0.0);
        assert_eq!(height(off, 0.2), level);
        // On level ground the nominal head is higher than 0.3 m: nothing changes.
        assert_eq!(height(on, 0.0), level);
        let up = height(on, 0.2);
        // The tread reaches 0.1 m up under the nominal head (the plan's ground
        // interpolated from the map's edge): the pelvis rises by 0.1 m less the
        // nominal head's 0.05 m of spare clearance.
        assert!(up > level + 0.03 && up < level + 0.08, "{up} vs {level}");
    }

    #[test]
    fn the_hands_push_the_front_up_as_the_head_sinks_with_head_push() {
        // One step from rest, the head `head_z` above level ground: the arms' joint
        // targets with and without the push.
        let arms = |params: CrawlParams, head_z: f64| {
            let mut obs = crawling_obs();
            obs.head_pos = [0.5, 0.0, head_z - obs.root_height];
            for i in 0..NUM_WAYPOINTS {
                obs.waypoints[i] = [0.25 * i as f64, 0.0, 0.0];
            }
            let mut gait = crawling_gait(params);
            let mut out = Action::default();
            gait.act(&obs, &mut out);
            let j = gait.joints;
            [0, 1].map(|a| [out.pd_targets[j.shoulder[a][1]], out.pd_targets[j.elbow[a]]])
        };
        let off = CrawlParams {
            head_clear: 0.3,
            head_push: 0.0,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            head_push: 1.0,
            ..off
        };
        assert_eq!(arms(on, 0.35), arms(off, 0.35));
        assert_eq!(arms(off, 0.22), arms(off, 0.35));
        let (low, high) = (arms(on, 0.22), arms(off, 0.22));
        // The hands reach further down: the elbows straighten.
        for a in 0..2 {
            assert!(
                low[a][1].abs() < high[a][1].abs() - 0.01,
                "{low:?} vs {high:?}"
            );
        }
    }

    /// `obs` with a plan 0.5 m/s straight ahead whose ground beyond the map is
    /// `ground` \[m\].
    fn with_plan_ahead(mut obs: Observation, ground: f64) -> Observation {
        for i in 0..NUM_WAYPOINTS {
            obs.waypoints[i] = [0.25 * (i + 1) as f64, 0.0, 0.0];
        }
        obs.waypoint_speeds = [0.5; NUM_WAYPOINTS];
        obs.waypoint_ground = [ground; NUM_WAYPOINTS];
        obs
    }

    /// A second of crawling with `params` on a fixed `obs`: `read` of each step's
    /// targets.
    fn a_second_of(
        params: CrawlParams,
        obs: &Observation,
        read: impl Fn(&Joints, &[f64]) -> [f64; 2],
    ) -> Vec<[f64; 2]> {
        let mut gait = crawling_gait(params);
        let mut out = Action::default();
        (0..(1.0 / CONTROL_DT) as usize)
            .map(|_| {
                gait.act(obs, &mut out);
                read(&gait.joints, &out.pd_targets)
            })
            .collect()
    }

    #[test]
    fn a_swinging_hand_clears_the_plans_tread_only_with_swing_ahead() {
        // A second of crawling towards a plan 0.5 m/s ahead over a flat map; the plan's
        // ground beyond the map flat or a tread 0.15 m up: the arms' targets per step.
        let arms = |params: CrawlParams, tread: f64| {
            let mut obs = crawling_obs();
            obs.head_pos = [0.6, 0.0, -0.15];
            let obs = with_plan_ahead(obs, tread);
            a_second_of(params, &obs, |j, t| [0, 1].map(|a| t[j.elbow[a]]))
        };
        // The head's clearance would also read the plan's tread: left out here.
        let off = CrawlParams {
            swing_ahead: false,
            ground_ahead: false,
            head_clear: 0.0,
            head_push: 0.0,
            ..CrawlParams::hands()
        };
        let on = CrawlParams {
            swing_ahead: true,
            ..off
        };
        assert_eq!(arms(on, 0.0), arms(off, 0.0));
        assert_eq!(arms(off, 0.15), arms(off, 0.0));
        assert_ne!(arms(on, 0.15), arms(off, 0.15));
    }

    #[test]
    fn a_swinging_knee_steps_up_a_ledge_only_with_knee_step_up() {
        // A second of crawling towards a plan 0.5 m/s ahead, the map flat or with a
        // ledge 0.1 m up from 0.2 m ahead of the root, the pelvis pitched 1 rad (its
        // target is 0.6-0.75): the legs' hip flexion targets per step.
        let hips = |params: CrawlParams, ledge: f64| {
            let mut obs = crawling_obs();
            let (s, c) = 1.0_f64.sin_cos();
            obs.root_rotation = [c, 0.0, -s, 0.0, 1.0, 0.0];
            fill_map(&mut obs, &|x, _| if x >= 0.2 { ledge } else { 0.0 });
            let obs = with_plan_ahead(obs, ledge);
            a_second_of(params, &obs, |j, t| [0, 1].map(|l| t[j.hip[l][1]]))
        };
        let most_flexed =
            |h: &[[f64; 2]]| h.iter().flatten().copied().fold(f64::INFINITY, f64::min);
        let off = CrawlParams::default();
        assert!(off.knee_step_up > 0.0, "the forearm crawl steps up");
        let off = CrawlParams {
            knee_step_up: 0.0,
            ..off
        };
        let on = CrawlParams::default();
        assert_eq!(hips(on, 0.0), hips(off, 0.0));
        let (up, stuck) = (hips(on, 0.1), hips(off, 0.1));
        // Aimed from the pelvis as it is (pitched past its target) and reaching forward,
        // the swinging thigh flexes further than one aimed from the desired pelvis.
        assert!(
            most_flexed(&up) < most_flexed(&stuck) - 0.2,
            "hip flexion {} with the step-up, {} without",
            most_flexed(&up),
            most_flexed(&stuck)
        );
    }

    #[test]
    fn geometry_resolves() {
        let g = Geometry::resolve();
        assert!((g.thigh - 0.41).abs() < 1e-9 && (g.upper_arm - 0.28).abs() < 1e-9);
        let j = Joints::resolve();
        assert_ne!(j.shoulder[0][1], j.shoulder[1][1]);
    }

    #[test]
    fn limb_ik_reaches_targets_up_and_down() {
        let (l1, l2) = (0.28, 0.29);
        for bend in [1.0, -1.0] {
            for p in [[0.1, 0.05, -0.4], [0.4, -0.05, 0.25], [-0.2, 0.1, -0.3]] {
                let [qx, qy, b] = limb_ik(l1, l2, bend, p[2] > 0.0, p);
                // Forward kinematics: Rx(qx) [Ry(qy)(0,0,-l1) + Ry(qy+b)(0,0,-l2)].
                let x = -l1 * qy.sin() - l2 * (qy + b).sin();
                let z = -l1 * qy.cos() - l2 * (qy + b).cos();
                let back = [x, -z * qx.sin(), z * qx.cos()];
                for k in 0..3 {
                    assert!((back[k] - p[k]).abs() < 1e-9, "{p:?} -> {back:?}");
                }
                assert!(bend * b > 0.0);
            }
        }
    }
}
