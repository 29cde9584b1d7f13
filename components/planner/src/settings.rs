//! Every planner parameter in one place, with its paper symbol, unit and default.

use serde::{Deserialize, Serialize};

use crate::{Locomotion, PlanError};

/// Planner parameters (paper 4.1 and 5.3 "Speed control"). Each field documents its
/// symbol, unit and default; [`PlannerSettings::validate`] checks them all.
///
/// Sign convention for longitudinal acceleration: `a_min` is the most negative
/// acceleration allowed (a deceleration limit), so it is `<= 0`; the paper's
/// a_min = -0.1 m/s^2 means "slow down by at most 0.1 m/s every second".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlannerSettings {
    /// Character radius used as wall clearance by A* and the refiner \[m\]. Default 0.3.
    pub character_radius: f64,
    /// Margin between the head and any ceiling: head <= headroom - margin \[m\].
    /// Also the margin A* adds to the crawl height. Default 0.1.
    pub head_margin: f64,
    /// Margin between a standing head (the centre of its 0.1 m sphere) and a
    /// ceiling (not in the paper) \[m\]. Under a top that leaves less than
    /// `stand_height` + this, a body on its feet crouches at `crouch_height` (where
    /// that stays `head_margin` under the ceiling) or else crawls. The paper's plan
    /// lowers the head to any height, but between a crouch and standing the
    /// controller's blended posture holds its head well above the height asked (a
    /// 0.97 m request stood at 1.2 m against a 1.22 m ceiling's edge for 50 s). In 200
    /// random MuJoCo tours, tours that reached every landmark, falls allowed, rose
    /// 186 -> 198 and collision failures fell 8 -> 2. Success went 90 -> 84, inside the
    /// noise. Crawling wherever a crouch kept less than this margin went
    /// 90 -> 76. Default 0.25.
    pub stoop_margin: f64,
    /// Head height when crawling \[m\]. Default 0.4.
    pub crawl_height: f64,
    /// Head height when crouch-walking \[m\]. Default 0.8.
    pub crouch_height: f64,
    /// Head height standing (walk, run, sprint) \[m\]. Default 1.47.
    pub stand_height: f64,
    /// Top speed crawling \[m/s\]. Default 1.0.
    pub crawl_speed: f64,
    /// Top speed crouch-walking \[m/s\]. Default 2.0.
    pub crouch_speed: f64,
    /// Length of the crawling body behind the head (head to feet: the shins trail
    /// the knees), for the crawl's footprint (not in the paper) \[m\]. Where the
    /// character crawls (a crawl leg, or within this distance of a top that puts the
    /// head below `crawl_switch_height`), A* and the refiner
    /// take a step only in a heading along which this body, `crawl_half_width` wide
    /// on each side, clears every wall: a path through a narrow gap then crosses it
    /// square-on, since at an angle the long body sweeps its hips into the gap's
    /// ends. Default 1.3.
    pub crawl_body_length: f64,
    /// Half the width of the crawling body (shoulders, elbows, knees) \[m\]. Default
    /// 0.25.
    pub crawl_half_width: f64,
    /// Requested head height below which the controller crawls (its `crawl_below`,
    /// not in the paper) \[m\]. Under it the speed cap is at most `crawl_speed` (the
    /// paper's v_max(z) would let a 0.5 m head go 1.25 m/s: a crawl's top speed is
    /// ~1 m/s whatever its head height), and the get-down is planned: see
    /// `form_change_speed`. Default 0.6.
    pub crawl_switch_height: f64,
    /// Requested head height above which a crawler stands up again (the controller's
    /// `stand_above`) \[m\]. Default 1.1.
    pub stand_switch_height: f64,
    /// Speed cap while the character changes form (not in the paper) \[m/s\]: over
    /// `form_change_length` of path from where the head crosses
    /// `crawl_switch_height` going down, from where it crosses `stand_switch_height`
    /// going up, and at the start of a path whose head starts below
    /// `crawl_switch_height` (a crawl leg after a standing one). Getting down or up
    /// takes the body 1.5-2 s nearly on the spot; a plan that runs on at full speed
    /// leaves it metres behind (then re-planned from where it lies). Default 0.3.
    pub form_change_speed: f64,
    /// Path length over which `form_change_speed` holds \[m\]. Default 0.5.
    pub form_change_length: f64,
    /// Path length over which the body takes the corner where one leg ends at its
    /// landmark and the next begins (not in the paper) \[m\]. Each leg's path is
    /// smoothed on its own, so a landmark is a cusp of the route: a tour that turns
    /// back at a landmark asked for a U-turn at full speed. The corner is taken as a
    /// bend of this length, so the legs meet at no more than sqrt(a_lat * length /
    /// angle) (a crawl: `crawl_turn_rate` * length / angle), and at
    /// `form_change_speed` where the form changes there. Default 0.5.
    pub corner_length: f64,
    /// Corner angle at a landmark above which the legs meet at rest (not in the
    /// paper) \[rad\]: a leg that sets off back the way the last one came reverses
    /// the body's velocity at the junction, which `corner_length`'s bend only slows
    /// (a U-turn at sqrt(a_lat * length / pi), 0.4 m/s). The plan's point jumped
    /// behind a body still moving forward, which walked backwards and sideways after
    /// it while it turned, rolled and fell: 14 of the 22 MuJoCo tours (seeds 0-1199)
    /// first lost to a crouch-walk fall on flat ground fell in the first 3 s of a
    /// leg, 9 of them where a crouch-walk leg followed one. Above this angle the
    /// junction speed is 0: the plan stops at the landmark and the next leg starts
    /// from rest. Measured with 2.0 (RESULTS.md, session 23): MuJoCo mixed tours
    /// seeds 0-2399 1721 -> 1783 of 2400 (246 gained, 184 lost; crouch-walk flat
    /// first falls 48 -> 28; 1.6 on seeds 0-1199: as 2.0), rapier seeds 0-159
    /// 96 -> 95; planned tour time +8.3% (the paper's a_min slows the approach). pi:
    /// never (the bend rule alone). Default 2.0 (115 degrees).
    pub turn_back_angle: f64,
    /// How deep inside a landmark's region a leg's path ends, where the region is
    /// that deep (not in the paper) \[m\]: a path that ends on the region's edge
    /// leaves a body that tracks it a few decimetres off standing just outside, never
    /// reaching the landmark; 0 ends it on the edge. Default 0.4.
    pub goal_depth: f64,
    /// Fastest turn of a crawl, heading change per second (not in the paper)
    /// \[rad/s\]: with the head below `crawl_switch_height` the speed is capped at
    /// this over the path's curvature. The lateral limit `a_lat` lets a 0.3 m radius
    /// bend go 0.55 m/s, a turn of 1.8 rad/s that a body a metre long on hands and
    /// knees does not make (it swings its hips wide, into the wall beside a gap).
    /// Default 0.5.
    pub crawl_turn_rate: f64,
    /// Cost of crawling over uneven ground (not in the paper) \[1/m\]: where the
    /// character crawls, each metre of path costs this times the relief under the
    /// body (highest minus lowest terrain within `crawl_half_width` and a cell) on
    /// top of the paper's edge cost. A crawl on hands and knees falls on gravel and
    /// along a step's edge (one side's limbs a step higher than the other's) far
    /// more than on flat ground; with 20 a path along a 0.12 m step's edge costs 3.4
    /// times its length and a flat strip a metre away is taken instead. 0 disables.
    /// Default 20.
    pub crawl_relief_cost: f64,
    /// The same cost where the character walks, runs or crouch-walks (not in the
    /// paper) \[1\]: each metre of a leg that does not crawl costs this times the
    /// relief under it (as `crawl_relief_cost` measures it) on top of its edge cost,
    /// so a route goes around a flight of stairs or a gravel patch where the detour
    /// is short: a preference for smooth ground, as `slope_preference_c` is for
    /// level ground. 0 disables (the paper's planner). Default 0: on the random
    /// tours it changes most routes and loses tours (MuJoCo seeds 0-1999 with
    /// `max_step_height` 0.25: 1669 of 2000 with 0; 1647 with 3, 1642 with 8:
    /// RESULTS.md, session 34).
    pub stand_relief_cost: f64,
    /// Cost of crawling under a low top on a leg that is not a crawl (not in the
    /// paper) \[1\]: on a walk, run or crouch-walk leg, each metre of path in the
    /// crawl zone (under a top that puts the head below `crawl_switch_height`, or
    /// within `crawl_body_length` of one) costs this many metres on top of its edge
    /// cost, so a route goes around a low top where the detour is short. Crawling
    /// there costs the body a get-down and a get-up (1.5-2 s each) and a crawl at a
    /// quarter of a walk's speed, and a standing leg's falls came there. 0 disables
    /// (the paper's planner, which lowers the head under any top on the way).
    /// With 4 (and `stoop_zone_cost` 1) 76 of 200 random MuJoCo tours change route,
    /// their falls 110 -> 73 and planned time -3%; tours that succeed 98 -> 107 on
    /// seeds 0-199 and 101 -> 103 on seeds 200-399, falls 367 -> 309 over the 400
    /// (RESULTS.md, session 10). Default 4.
    pub crawl_zone_cost: f64,
    /// Where a crawl under a low top begins and ends (not in the paper): false, every
    /// path point within `crawl_body_length` of such a top crawls, so a walk that
    /// passes beside one, or ends at a landmark next to one, crawls there too; true,
    /// only points within `crawl_body_length` along the path of one under the top's
    /// edge (within `character_radius`). 41 of the 600 legs of 200 random tours are
    /// walks, runs or crouch-walks that crawled beside a top; with true, MuJoCo tours
    /// 227 -> 247 of 400 succeed (seeds 0-399), falls 279 -> 233, rapier 7 -> 9 of 40.
    /// Default true.
    pub crawl_reach_along_path: bool,
    /// Where a walk, run or crouch-walk leg ends (not in the paper): false, in any
    /// cell of the target (`goal_depth` inside); true, in one whose head room within
    /// `character_radius` lets the leg's body stay off its hands and knees, when the
    /// target has such a cell this leg can reach: a landmark partly under a low top
    /// ended its standing leg crawling, and the next leg started so (random-189: a
    /// run leg crawled its last 2.6 m under a 0.6 m top's edge, the next began so;
    /// both fell). 16 of 600 random tours (seeds 0-599) change route; MuJoCo, one
    /// binary: random-189 fails -> succeeds, none the other way, legs with a fall
    /// 16 -> 16 over the 16; two walk legs arrive 2-5 s sooner (random-13). Mostly the
    /// target lies wholly under the top, or a body length from its edge on a leg that
    /// starts under it: 15 of 19 such legs still crawl there (RESULTS.md). Default
    /// true.
    pub stand_at_goal: bool,
    /// Cost of crouching under a top on a walk, run or sprint leg (not in the
    /// paper) \[1\]: each metre of such a leg within `character_radius` of a top
    /// that leaves no room to stand (below `stand_height` + `stoop_margin`), and a
    /// character radius further out, costs this many metres on top of its edge
    /// cost (`crawl_zone_cost` instead where the top makes it crawl): a crouch
    /// under a top puts two changes of gait into a walk or run. 0 disables.
    /// Default 1.
    pub stoop_zone_cost: f64,
    /// Top speed walking \[m/s\]. Default 2.0.
    pub walk_speed: f64,
    /// Top speed running \[m/s\]. Default 4.0.
    pub run_speed: f64,
    /// Top speed sprinting \[m/s\]. Default 5.0.
    pub sprint_speed: f64,
    /// Longitudinal acceleration limit a_max \[m/s^2\], > 0. Paper: 0.5.
    pub a_max: f64,
    /// Longitudinal deceleration limit a_min \[m/s^2\], < 0 (see the type's doc).
    /// Paper: -0.1.
    pub a_min: f64,
    /// Lateral acceleration limit a_lat: v^2 * kappa <= a_lat \[m/s^2\]. Default 1.0.
    pub a_lat: f64,
    /// Terrain preference c: each edge's length is increased by
    /// length * (e^(c * slope) - 1), slope = |dh| / dxy (paper 5.2) \[1\]. 0 disables it.
    /// Default 1.0.
    pub slope_preference_c: f64,
    /// Height-difference cost: metres of extra cost per metre climbed or descended
    /// \[1\]. Default 0.5.
    pub height_cost: f64,
    /// Steepest traversable slope \[rad\] (paper 4.1: "infeasible slopes"), measured
    /// over half `slope_baseline` before and after each edge: an edge is removed where
    /// the terrain rises or falls faster than this over either, or where the edge
    /// itself is steeper and its height step is above `max_step_height`. Default 0.7
    /// (40 degrees).
    pub max_slope: f64,
    /// A height step that is always traversable (stairs) \[m\]. Default 0.2, the
    /// random scenes' own reachability rule (`plamo_scenes::ReachRules`): their stairs'
    /// risers are 0.08-0.15 m, and a path over a tile's 0.2-0.25 m side is where the
    /// crawl sat until its time ran out and both gaits fell more (0.25 until session
    /// 34; MuJoCo tours seeds 0-1999 1669 -> 1703 of 2000, held out 2000-3499 1232 ->
    /// 1278 of 1500, timeouts 9 -> 0: RESULTS.md).
    pub max_step_height: f64,
    /// Distance kept from a cliff (not in the paper) \[m\]: a height step between
    /// neighbouring terrain samples above `max_step_height`, which no edge crosses.
    /// Cells this close to one are left out as cells near walls are, on both sides,
    /// so a path does not run along a cliff's top or foot, where a foot or a hand
    /// that strays a few centimetres off the path steps over the edge. In random
    /// scenes tiles meet in such cliffs (a slope or stairs tile's side, 0.3-1 m),
    /// and 39 of 114 tours that fell first fell within 0.35 m of a cliff above
    /// 0.16 m (`results/`, forensic replays at 28bee9f). 0 disables. Default 0.45
    /// (0.3 until session 35; MuJoCo tours 0-1999 1742 -> 1773 of 2000, held out
    /// 2000-3499 1301 -> 1327 of 1500, together +231 -174, McNemar p 0.005; session
    /// 34 had measured +39 of 3500 on its own baseline: RESULTS.md).
    pub cliff_clearance: f64,
    /// Length over which `max_slope` is measured, half behind and half ahead (not in
    /// the paper) \[m\]: about a stride, so a stair's riser between its treads and
    /// gravel's bumps average out while a hillside does not. On one grid cell every slope whose rise per cell is
    /// under `max_step_height` would pass as a step: with 0.1 m cells a 65 degree
    /// face did. 0 measures each edge alone (that old rule). Default 0.6.
    pub slope_baseline: f64,
    /// Speed reduction on slopes: v_cap = v / (1 + k * tan(slope along path)) \[1\].
    /// Default 1.0.
    pub slope_speed_gain: f64,
    /// Speed cap where a standing form (walk, run, crouch-walk) crosses stepped
    /// ground (not in the paper) \[m/s\]: where the terrain within
    /// `crawl_half_width` of a path point steps by more than `stand_step_height`
    /// between samples one terrain cell apart (a stair's riser, a gravel bump), the
    /// point's speed is capped at this. The biped falls less on stairs when slower:
    /// 0.31 falls per 20 s run at 1 m/s against 0.69 at 2 m/s (RESULTS.md, walk
    /// stairs sweep). 0 disables. Default 1.0: MuJoCo tours 880 -> 916 of 1000 on
    /// seeds 0-999 and 1319 -> 1358 of 1500 on held-out seeds 2000-3499 (RESULTS.md,
    /// sessions 43-44).
    pub stand_step_speed: f64,
    /// Rise between neighbouring terrain samples that counts as a step for
    /// `stand_step_speed` \[m\]: above what a 30 degree smooth slope rises per
    /// 0.1 m cell (0.058 m). Default 0.08.
    pub stand_step_height: f64,
    /// Planning grid = every `grid_stride`-th terrain sample (1 = the terrain's own
    /// resolution, 0.1 m by default) \[samples\]. Default 1.
    pub grid_stride: usize,
    /// Landmarks of the ALT lower bound for A* (not in the paper; see
    /// `AltLandmarks`): `Planner::new` then runs one Dijkstra over the whole grid
    /// per landmark (about 0.2 s each on 1000 x 1000 cells) and every search after
    /// it expands far fewer cells for the same cheapest path. 0 = off, at most 32.
    /// Worth it on large grids queried many times. Default 0.
    pub alt_landmarks: usize,
    /// Spacing of the refined path \[m\]. Default 0.1.
    pub path_spacing: f64,
    /// Smoothing passes of the refiner (Laplacian, clearance-preserving). Default 40.
    pub smoothing_iterations: usize,
    /// Arc length over which curvature is measured \[m\]. Default 0.3.
    pub curvature_window: f64,
    /// Largest rate of head-height change along the path \[m per m\]. Default 0.5.
    pub head_height_rate: f64,
    /// Dynamic obstacles: look-ahead for predicted collisions \[s\]. Paper: 1.5.
    pub collision_horizon: f64,
    /// Dynamic obstacles: the look-ahead also covers the plan's next this many metres
    /// \[m\] (not in the paper): a crawler at 0.5 m/s needs 5-6 s to get its 1.3 m
    /// body across a ball's way, and entered it with the ball 1.5 s off. Default 3.
    /// 0 = `collision_horizon` alone (the paper).
    pub collision_lookahead: f64,
    /// Time step of the collision sweep \[s\]. Default 0.1.
    pub collision_dt: f64,
    /// Extra distance kept from dynamic obstacles \[m\]. Default 0.2.
    pub obstacle_margin: f64,
    /// Dynamic obstacles: the collision sweep also covers the path behind the plan
    /// point as far as the head lags it, at most this far \[m\] (not in the paper):
    /// a crawl lags its plan by 0.3-2.4 m, and the sweep of the plan alone predicted
    /// the obstacle's crossing where the body was not yet. 0 = the plan point only.
    /// Default 2.0 (`lag_distance`: beyond it the plan is made again from the head).
    pub lag_sweep_max: f64,
    /// Local re-plan: the obstacle is blocked where it is predicted at the conflict and
    /// along where it goes for this long after it \[s\], so that the detour passes
    /// behind a crossing obstacle rather than into its way. Not in the paper (it sets
    /// the obstacle "at its future location"): blocked only there, half the detours
    /// went ahead of the obstacle, which caught up with a humanoid slowed by the turn
    /// (`plamo eval dynamic`: 24% of re-planned runs collided, 0% at 3 s). 0 = the
    /// conflict's position only. Default 3.
    pub obstacle_sweep: f64,
    /// Local re-plan: distance past the conflict where the detour rejoins the old
    /// path \[m\]. Default 2.0.
    pub rejoin_distance: f64,
    /// Local re-plan: margin of the A* window around start, rejoin and obstacle \[m\].
    /// Default 3.0.
    pub replan_window_margin: f64,
    /// Local re-plan: arc length of old path re-timed after the rejoin point \[m\].
    /// Default 20.
    pub replan_speed_horizon: f64,
    /// Waiting for an obstacle to pass (not in the paper): the longest wait tried
    /// where the plan stops short of a predicted conflict instead of detouring \[s\].
    /// 0 = never wait, detour only (the paper). Default 6.
    pub max_wait: f64,
    /// Waiting: the largest deceleration when stopping to wait \[m/s^2\], > 0.
    /// Default 1.0.
    pub wait_deceleration: f64,
    /// Waiting: distance kept from the obstacle by a plan that waits for it, on top
    /// of `obstacle_margin` \[m\]: a humanoid coming to rest overshoots its stop
    /// and steps forward (a walker stopped 0.14 m past it with the passing box's
    /// surface 0.44 m from its root, and its body came within 0.1 m of the box:
    /// `plamo eval dynamic`, scene 16). Default 0.3.
    pub wait_margin: f64,
    /// Waiting: the plan waits rather than detours when it arrives at most this much
    /// later than the detour would \[s\] (either way when the detour is still
    /// predicted to collide: waiting). Default 1.0.
    pub wait_preference: f64,
    /// Full re-plan when the head is farther than this from the path \[m\]. Default 1.0.
    pub drift_distance: f64,
    /// Full re-plan when the head lags the timed plan by more than this \[m\]. Default 2.0.
    pub lag_distance: f64,
    /// A lag re-plan whose head moved less than this since the instruction's
    /// previous lag re-plan starts from the root instead of the head \[m\]: a body
    /// held against a wall's end, its head past the end, was re-planned from the
    /// head onto the same path along the wall every 3 s until the time limit
    /// (random-965). 0: always the head. Default 0: measured at 0.3 m and not
    /// turned on (MuJoCo tours, seeds 0-999 and 4000-4999: 1909 of 2000 against
    /// 1908, +7 -6; every re-plan it changed was a crawl's, which gets unstuck as
    /// often as it rolls over backing up to its root; RESULTS "Random 4-landmark
    /// scenes", session 51).
    pub stuck_distance: f64,
    /// Number of waypoints handed to the controller. Paper: 10.
    pub waypoint_count: usize,
    /// Time between waypoints \[s\]. Paper: 0.5.
    pub waypoint_dt: f64,
    /// Re-plan around dynamic obstacles predicted to hit the plan (paper 4.1); off
    /// only for the re-planning ablation of `plamo eval dynamic`. Default true.
    pub dynamic_replanning: bool,
}

impl Default for PlannerSettings {
    fn default() -> Self {
        Self {
            character_radius: 0.3,
            head_margin: 0.1,
            stoop_margin: 0.25,
            crawl_height: 0.4,
            crouch_height: 0.8,
            stand_height: 1.47,
            crawl_speed: 1.0,
            crouch_speed: 2.0,
            crawl_body_length: 1.3,
            crawl_half_width: 0.25,
            crawl_switch_height: 0.6,
            stand_switch_height: 1.1,
            form_change_speed: 0.3,
            form_change_length: 0.5,
            corner_length: 0.5,
            turn_back_angle: 2.0,
            goal_depth: 0.4,
            crawl_turn_rate: 0.5,
            crawl_relief_cost: 20.0,
            stand_relief_cost: 0.0,
            crawl_zone_cost: 4.0,
            crawl_reach_along_path: true,
            stand_at_goal: true,
            stoop_zone_cost: 1.0,
            walk_speed: 2.0,
            run_speed: 4.0,
            sprint_speed: 5.0,
            a_max: 0.5,
            a_min: -0.1,
            a_lat: 1.0,
            slope_preference_c: 1.0,
            height_cost: 0.5,
            max_slope: 0.7,
            max_step_height: 0.2,
            cliff_clearance: 0.45,
            slope_baseline: 0.6,
            slope_speed_gain: 1.0,
            stand_step_speed: 1.0,
            stand_step_height: 0.08,
            grid_stride: 1,
            alt_landmarks: 0,
            path_spacing: 0.1,
            smoothing_iterations: 40,
            curvature_window: 0.3,
            head_height_rate: 0.5,
            collision_horizon: 1.5,
            collision_lookahead: 3.0,
            collision_dt: 0.1,
            obstacle_margin: 0.2,
            lag_sweep_max: 2.0,
            obstacle_sweep: 3.0,
            rejoin_distance: 2.0,
            replan_window_margin: 3.0,
            replan_speed_horizon: 20.0,
            max_wait: 6.0,
            wait_deceleration: 1.0,
            wait_margin: 0.3,
            wait_preference: 1.0,
            drift_distance: 1.0,
            lag_distance: 2.0,
            stuck_distance: 0.0,
            waypoint_count: 10,
            waypoint_dt: 0.5,
            dynamic_replanning: true,
        }
    }
}

impl PlannerSettings {
    /// Check every field; the error names the field and what is allowed.
    pub fn validate(&self) -> Result<(), PlanError> {
        let positive = [
            ("character_radius", self.character_radius),
            ("head_margin", self.head_margin),
            ("stoop_margin", self.stoop_margin),
            ("crawl_height", self.crawl_height),
            ("crouch_height", self.crouch_height),
            ("stand_height", self.stand_height),
            ("crawl_speed", self.crawl_speed),
            ("crouch_speed", self.crouch_speed),
            ("crawl_body_length", self.crawl_body_length),
            ("crawl_half_width", self.crawl_half_width),
            ("crawl_switch_height", self.crawl_switch_height),
            ("stand_switch_height", self.stand_switch_height),
            ("form_change_speed", self.form_change_speed),
            ("form_change_length", self.form_change_length),
            ("corner_length", self.corner_length),
            ("turn_back_angle", self.turn_back_angle),
            ("crawl_turn_rate", self.crawl_turn_rate),
            ("walk_speed", self.walk_speed),
            ("run_speed", self.run_speed),
            ("sprint_speed", self.sprint_speed),
            ("a_max", self.a_max),
            ("a_lat", self.a_lat),
            ("max_slope", self.max_slope),
            ("path_spacing", self.path_spacing),
            ("curvature_window", self.curvature_window),
            ("head_height_rate", self.head_height_rate),
            ("collision_horizon", self.collision_horizon),
            ("collision_dt", self.collision_dt),
            ("rejoin_distance", self.rejoin_distance),
            ("replan_window_margin", self.replan_window_margin),
            ("replan_speed_horizon", self.replan_speed_horizon),
            ("drift_distance", self.drift_distance),
            ("lag_distance", self.lag_distance),
            ("waypoint_dt", self.waypoint_dt),
            ("wait_deceleration", self.wait_deceleration),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(PlanError::InvalidSettings {
                    field,
                    reason: format!("must be finite and > 0, got {v}"),
                });
            }
        }
        let non_negative = [
            ("slope_baseline", self.slope_baseline),
            ("slope_preference_c", self.slope_preference_c),
            ("crawl_relief_cost", self.crawl_relief_cost),
            ("stand_relief_cost", self.stand_relief_cost),
            ("crawl_zone_cost", self.crawl_zone_cost),
            ("stoop_zone_cost", self.stoop_zone_cost),
            ("height_cost", self.height_cost),
            ("max_step_height", self.max_step_height),
            ("cliff_clearance", self.cliff_clearance),
            ("slope_speed_gain", self.slope_speed_gain),
            ("stand_step_speed", self.stand_step_speed),
            ("stand_step_height", self.stand_step_height),
            ("obstacle_margin", self.obstacle_margin),
            ("lag_sweep_max", self.lag_sweep_max),
            ("obstacle_sweep", self.obstacle_sweep),
            ("max_wait", self.max_wait),
            ("collision_lookahead", self.collision_lookahead),
            ("wait_margin", self.wait_margin),
            ("wait_preference", self.wait_preference),
            ("goal_depth", self.goal_depth),
            ("stuck_distance", self.stuck_distance),
        ];
        for (field, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PlanError::InvalidSettings {
                    field,
                    reason: format!("must be finite and >= 0, got {v}"),
                });
            }
        }
        if !(self.a_min.is_finite() && self.a_min < 0.0) {
            return Err(PlanError::InvalidSettings {
                field: "a_min",
                reason: format!(
                    "is a deceleration limit and must be finite and < 0 (paper: -0.1), got {}",
                    self.a_min
                ),
            });
        }
        if self.max_slope >= std::f64::consts::FRAC_PI_2 {
            return Err(PlanError::InvalidSettings {
                field: "max_slope",
                reason: format!("must be below pi/2 rad, got {}", self.max_slope),
            });
        }
        if !(self.crawl_height < self.crouch_height && self.crouch_height < self.stand_height) {
            return Err(PlanError::InvalidSettings {
                field: "crouch_height",
                reason: "head heights must satisfy crawl < crouch < stand".into(),
            });
        }
        if self.grid_stride == 0 {
            return Err(PlanError::InvalidSettings {
                field: "grid_stride",
                reason: "must be >= 1".into(),
            });
        }
        if self.alt_landmarks > 32 {
            return Err(PlanError::InvalidSettings {
                field: "alt_landmarks",
                reason: format!("must be 0..=32, got {}", self.alt_landmarks),
            });
        }
        if self.waypoint_count == 0 {
            return Err(PlanError::InvalidSettings {
                field: "waypoint_count",
                reason: "must be >= 1".into(),
            });
        }
        Ok(())
    }

    /// Head height requested by a locomotion form \[m\].
    pub fn head_height(&self, form: Locomotion) -> f64 {
        match form {
            Locomotion::Crawl => self.crawl_height,
            Locomotion::CrouchWalk => self.crouch_height,
            Locomotion::Walk | Locomotion::Run | Locomotion::Sprint => self.stand_height,
        }
    }

    /// Top speed of a locomotion form \[m/s\].
    pub fn top_speed(&self, form: Locomotion) -> f64 {
        match form {
            Locomotion::Crawl => self.crawl_speed,
            Locomotion::CrouchWalk => self.crouch_speed,
            Locomotion::Walk => self.walk_speed,
            Locomotion::Run => self.run_speed,
            Locomotion::Sprint => self.sprint_speed,
        }
    }

    /// The paper's coupling v_max(z): the fastest speed at head height `z` for a form
    /// \[m/s\]. Piecewise linear through (crawl height, crawl speed), (crouch height,
    /// crouch speed), (stand height, the form's top speed), never above the form's top
    /// speed; below the crawl height the crawl speed holds.
    pub fn speed_cap_at_height(&self, form: Locomotion, z: f64) -> f64 {
        let top = self.top_speed(form);
        let pts = [
            (self.crawl_height, self.crawl_speed),
            (self.crouch_height, self.crouch_speed),
            (self.stand_height, top.max(self.crouch_speed)),
        ];
        let v = if z <= pts[0].0 {
            pts[0].1
        } else if z >= pts[2].0 {
            pts[2].1
        } else {
            let k = if z <= pts[1].0 { 0 } else { 1 };
            let (z0, v0) = pts[k];
            let (z1, v1) = pts[k + 1];
            v0 + (v1 - v0) * (z - z0) / (z1 - z0)
        };
        v.min(top)
    }

    /// Lowest head height a form may drop to under a ceiling \[m\]: every form may
    /// go down to crawling (the refiner lowers the head before low tops).
    pub fn lowest_head_height(&self, _form: Locomotion) -> f64 {
        self.crawl_height
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_bad_values_name_the_field() {
        PlannerSettings::default().validate().unwrap();
        let s = PlannerSettings {
            a_min: 0.1,
            ..Default::default()
        };
        match s.validate() {
            Err(PlanError::InvalidSettings { field, .. }) => assert_eq!(field, "a_min"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn speed_is_capped_by_head_height() {
        let s = PlannerSettings::default();
        assert_eq!(s.speed_cap_at_height(Locomotion::Run, 1.47), 4.0);
        assert_eq!(s.speed_cap_at_height(Locomotion::Run, 0.8), 2.0);
        assert_eq!(s.speed_cap_at_height(Locomotion::Run, 0.4), 1.0);
        assert!((s.speed_cap_at_height(Locomotion::Run, 0.6) - 1.5).abs() < 1e-12);
        assert_eq!(s.speed_cap_at_height(Locomotion::Crawl, 1.47), 1.0);
    }
}
