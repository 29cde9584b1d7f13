//! The planner: instructions -> route of timed trajectories, stepped with the
//! humanoid's state; re-plans on instruction switch, drift, lag and predicted
//! collisions with dynamic obstacles.

use std::sync::Arc;

use plamo_interfaces::Tick;
use plamo_scenes::{ObstacleState, Region, Scene};
use serde::{Deserialize, Serialize};

use crate::alt::AltLandmarks;
use crate::astar::{AStar, CrawlBody, GridPath, Posture, SearchLimits};
use crate::connectivity::Components;
use crate::dynamic::{
    Conflict, External, ExternalObstacle, Prediction, predict_any, predict_conflict_with,
};
use crate::grid::PlanGrid;
use crate::refine::{PathPoint, RefineCtx, annotate, refine};
use crate::speed_oracle::SpeedProblem;
use crate::speed_qp::solve_speed_qp;
use crate::wait::plan_wait;
use crate::{
    Instruction, Locomotion, PlanError, PlannerSettings, Source, Trajectory, UnreachableReason,
    Waypoint, parse_instructions,
};

/// Length of the route's start over which [`Planner::start_heading`] is measured \[m\]:
/// about a body length, so a bend a few metres on does not turn the start, and a
/// route that leaves a landmark round a wall or a hill faces the way it goes rather
/// than the target beyond.
pub const START_HEADING_SPAN: f64 = 1.0;

/// The humanoid's state as the planner reads it each control step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlannerInput {
    /// Head position \[m\].
    pub head: [f64; 3],
    /// Root (pelvis) position \[m\].
    pub root: [f64; 3],
    /// Root linear velocity \[m/s\].
    pub velocity: [f64; 3],
    /// Observed dynamic obstacle states, in scene order; empty = predict from the
    /// scene's motion rules.
    pub obstacles: Vec<ObstacleState>,
}

/// Why the plan was rebuilt this step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReplanReason {
    /// First step, or a new instruction became current.
    NewInstruction,
    /// The head left the path by more than `drift_distance`.
    Drift,
    /// The head lagged the timed plan by more than `lag_distance`.
    Lag,
    /// A dynamic obstacle was predicted to hit the plan (local re-plan).
    Obstacle(Conflict),
    /// A dynamic obstacle was predicted to hit the plan, which now stops short of it
    /// and waits for it to pass.
    Wait(Conflict),
}

/// Outcome of a step (not an error).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PlanStatus {
    /// Following the current instruction.
    #[default]
    Following,
    /// Every instruction's target was reached.
    Finished,
    /// The current target cannot be reached from where the humanoid is; the last
    /// plan is kept.
    Infeasible {
        /// Instruction index.
        index: usize,
        /// Why.
        reason: UnreachableReason,
    },
}

/// Progress through the instructions.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Progress {
    /// Current instruction (0-based); equals the count when finished.
    pub index: usize,
    /// Fraction of the current path covered, by the path point nearest the head.
    pub fraction: f64,
    /// Whether the current instruction's target was reached this step.
    pub reached: bool,
}

/// What the planner hands out each step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlannerOutput {
    /// The tick this output is for.
    pub tick: Tick,
    /// The next `waypoint_count` head waypoints, `waypoint_dt` apart.
    pub waypoints: Vec<Waypoint>,
    /// The whole current trajectory (for plotting and recording).
    pub trajectory: Arc<Trajectory>,
    /// Progress.
    pub progress: Progress,
    /// Outcome.
    pub status: PlanStatus,
    /// Set when the plan was rebuilt this step.
    pub replanned: Option<ReplanReason>,
}

/// The dynamic path planner (paper 4.1).
#[derive(Debug, Clone)]
pub struct Planner {
    scene: Scene,
    settings: PlannerSettings,
    instructions: Vec<Instruction>,
    grid: PlanGrid,
    components: Vec<Components>,
    astar: AStar,
    /// ALT bounds, built at construction when `settings.alt_landmarks > 0`.
    alt: Option<AltLandmarks>,
    /// The host's obstacles (not in the scene) and when they were observed \[s\].
    external: Vec<ExternalObstacle>,
    external_observed: f64,
    route: Vec<Trajectory>,
    // Run state.
    index: usize,
    current: Option<Arc<Trajectory>>,
    last_tick: Option<Tick>,
    finished: bool,
    /// Head (x, y) at the current instruction's last lag re-plan (see
    /// `stuck_distance`).
    lag_head: Option<[f64; 2]>,
}

/// Distance from (x, y) to a region, 0 inside \[m\].
fn region_distance(r: &Region, x: f64, y: f64) -> f64 {
    region_signed_distance(r, x, y).max(0.0)
}

/// Distance from (x, y) to the region's edge \[m\], negative inside.
fn region_signed_distance(r: &Region, x: f64, y: f64) -> f64 {
    match r {
        Region::Circle { center, radius } => {
            ((x - center[0]).powi(2) + (y - center[1]).powi(2)).sqrt() - radius
        }
        Region::Rect { footprint } => footprint.signed_distance(x, y),
    }
}

impl Planner {
    /// Validate the settings, parse the instructions, build the planning grid and plan
    /// the whole route from `start` (x, y) \[m\]. Fails fast when any target is
    /// unreachable.
    pub fn new(
        scene: Scene,
        instructions: &str,
        start: [f64; 2],
        settings: PlannerSettings,
    ) -> Result<Self, PlanError> {
        settings.validate()?;
        let instructions = parse_instructions(instructions, &scene)?;
        let grid = PlanGrid::build(&scene, &settings);
        let alt = (settings.alt_landmarks > 0)
            .then(|| AltLandmarks::build(&grid, settings.alt_landmarks));
        let mut p = Self {
            scene,
            settings,
            instructions,
            grid,
            components: Vec::new(),
            astar: AStar::default(),
            alt,
            external: Vec::new(),
            external_observed: 0.0,
            route: Vec::new(),
            index: 0,
            current: None,
            last_tick: None,
            finished: false,
            lag_head: None,
        };
        p.route = p.plan_route(start)?;
        Ok(p)
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// The settings.
    pub fn settings(&self) -> &PlannerSettings {
        &self.settings
    }
    /// The parsed instructions.
    pub fn instructions(&self) -> &[Instruction] {
        &self.instructions
    }
    /// The route planned at construction, one trajectory per instruction, timed
    /// back to back from t = 0.
    pub fn route(&self) -> &[Trajectory] {
        &self.route
    }
    /// The direction the route sets off in \[rad\]: that of its first
    /// [`START_HEADING_SPAN`] metres, where a body at the start should face. `None`
    /// where the first leg has no length.
    pub fn start_heading(&self) -> Option<f64> {
        self.route.first()?.heading_over(START_HEADING_SPAN)
    }
    /// The planning grid.
    pub fn grid(&self) -> &PlanGrid {
        &self.grid
    }
    /// Replace the host's obstacles that the scene does not know (a car or a ball a
    /// co-simulation host drives), with their states observed at absolute time
    /// `observed` \[s\]; from the next step on they are predicted at constant
    /// velocity and avoided like the scene's. An empty slice removes them. Rejects
    /// non-finite numbers and non-positive sizes, naming the obstacle, and then
    /// keeps the previous set.
    pub fn set_external_obstacles(
        &mut self,
        observed: f64,
        obstacles: &[ExternalObstacle],
    ) -> Result<(), PlanError> {
        if !observed.is_finite() {
            return Err(PlanError::InvalidInput {
                field: "external obstacles",
                reason: format!("observation time must be finite, got {observed}"),
            });
        }
        for (j, o) in obstacles.iter().enumerate() {
            o.check().map_err(|e| PlanError::InvalidInput {
                field: "external obstacles",
                reason: format!("obstacle {j}: {e}"),
            })?;
        }
        self.external.clear();
        self.external.extend_from_slice(obstacles);
        self.external_observed = observed;
        Ok(())
    }

    /// The host's obstacles set by [`Self::set_external_obstacles`].
    pub fn external_obstacles(&self) -> &[ExternalObstacle] {
        &self.external
    }

    fn external(&self) -> External<'_> {
        External {
            obstacles: &self.external,
            observed: self.external_observed,
        }
    }

    /// The trajectory currently followed (after the first step).
    pub fn current(&self) -> Option<&Trajectory> {
        self.current.as_deref()
    }

    /// Plan every instruction in order from `start` (x, y) \[m\].
    pub fn plan_route(&mut self, start: [f64; 2]) -> Result<Vec<Trajectory>, PlanError> {
        let mut out: Vec<Trajectory> = Vec::with_capacity(self.instructions.len());
        let mut t0 = 0.0;
        for i in 0..self.instructions.len() {
            let (from, v0) = match (&self.instructions[i].source, out.last()) {
                (Source::Landmark(name), _) => {
                    let l = self.scene.landmark(name).expect("resolved at parse time");
                    (l.region.center(), out.last().map_or(0.0, end_speed))
                }
                (_, Some(prev)) => {
                    let p = prev.points.last().expect("non-empty trajectory");
                    ([p.x, p.y], end_speed(prev))
                }
                (_, None) => (start, 0.0),
            };
            let tr = self.plan_instruction(i, from, v0, t0, &SearchLimits::default())?;
            t0 = tr.end_time();
            out.push(tr);
        }
        // The legs meet at their landmarks no faster than the corner there allows:
        // re-time each leg between the junction speeds on either side of it.
        let junctions: Vec<f64> = out
            .windows(2)
            .map(|w| junction_speed(&self.settings, &w[0].points, &w[1].points))
            .collect();
        let mut t0 = 0.0;
        for (i, tr) in out.iter_mut().enumerate() {
            let mut pts = std::mem::take(&mut tr.points);
            let v0 = match i {
                0 => pts.first().map_or(0.0, |p| p.v),
                _ => junctions[i - 1],
            };
            let b_end = junctions.get(i).map(|v| v * v);
            set_speeds(&self.settings, &mut pts, v0, b_end)?;
            *tr = Trajectory::new(t0, pts);
            t0 = tr.end_time();
        }
        Ok(out)
    }

    /// A* with the crawling body's footprint rule for `form` (everywhere on a crawl
    /// leg, else where `limits` says), and without it when it leaves no path (a
    /// start or target wedged against a wall): the footprint shapes a path, it never
    /// makes a reachable target unreachable. Returns the path and the limits it was
    /// found under (the refiner keeps to the same rule).
    fn search_body(
        &mut self,
        start: usize,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
        form: Locomotion,
    ) -> Option<(GridPath, SearchLimits)> {
        let mut limits = limits.clone();
        limits.posture = Posture::of(form);
        if form == Locomotion::Crawl && limits.crawl_body == CrawlBody::Zone {
            limits.crawl_body = CrawlBody::Everywhere;
        }
        loop {
            let found = self.astar.search_with(
                &self.grid,
                start,
                goals,
                min_head,
                &limits,
                self.alt.as_ref(),
            );
            match found {
                Some(p) => return Some((p, limits)),
                None if limits.crawl_body != CrawlBody::Off => limits.crawl_body = CrawlBody::Off,
                None => return None,
            }
        }
    }

    fn min_head(&self, form: Locomotion) -> f32 {
        (self.settings.lowest_head_height(form) + self.settings.head_margin) as f32
    }

    fn components_for(&mut self, min_head: f32) -> &Components {
        if let Some(k) = self.components.iter().position(|c| c.min_head == min_head) {
            return &self.components[k];
        }
        self.components
            .push(Components::build(&self.grid, min_head));
        self.components.last().unwrap()
    }

    fn unreachable(&self, index: usize, reason: UnreachableReason) -> PlanError {
        let ins = &self.instructions[index];
        PlanError::Unreachable {
            index,
            text: ins.text.clone(),
            target: ins.target.clone(),
            reason,
        }
    }

    /// The region of instruction `index`'s target landmark.
    fn target_region(&self, index: usize) -> Region {
        self.scene
            .landmark(&self.instructions[index].target)
            .expect("resolved at parse time")
            .region
    }

    /// Goal cells of instruction `index`'s target and the reach margin \[m\]: the
    /// passable cells inside the region, or, when there are none (a landmark on an
    /// obstacle), those within the character radius plus two cells of it.
    fn goal_cells(&self, index: usize, min_head: f32) -> (Vec<usize>, f64) {
        let region = self.target_region(index);
        let g = &self.grid;
        let (lo, hi) = region.aabb();
        let margins = [0.0, self.settings.character_radius + 2.0 * g.resolution];
        for m in margins {
            let i0 = (((lo[0] - m - g.origin[0]) / g.resolution).floor().max(0.0)) as usize;
            let j0 = (((lo[1] - m - g.origin[1]) / g.resolution).floor().max(0.0)) as usize;
            let i1 = ((((hi[0] + m - g.origin[0]) / g.resolution).ceil().max(0.0)) as usize)
                .min(g.nx - 1);
            let j1 = ((((hi[1] + m - g.origin[1]) / g.resolution).ceil().max(0.0)) as usize)
                .min(g.ny - 1);
            let mut cells = Vec::new();
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = j * g.nx + i;
                    let [x, y] = g.position(c);
                    if region_distance(&region, x, y) <= m && g.passable(c, min_head) {
                        cells.push(c);
                    }
                }
            }
            if !cells.is_empty() {
                return (cells, m);
            }
        }
        (Vec::new(), 0.0)
    }

    /// The goal cells `goal_depth` inside instruction `index`'s target, or as deep as
    /// any of `cells` lies: a path that ends on the region's edge leaves a body that
    /// tracks it a few decimetres off standing just outside, never reaching it.
    fn deep_cells(&self, index: usize, cells: &[usize]) -> Vec<usize> {
        let region = self.target_region(index);
        let depth = |c: usize| {
            let [x, y] = self.grid.position(c);
            -region_signed_distance(&region, x, y)
        };
        let deepest = cells
            .iter()
            .map(|&c| depth(c))
            .fold(f64::NEG_INFINITY, f64::max);
        let want = self.settings.goal_depth.min(deepest) - 1e-9;
        cells
            .iter()
            .copied()
            .filter(|&c| depth(c) >= want)
            .collect()
    }

    /// The passable cell nearest to (x, y) within 3 m that `limits` allows.
    fn start_cell(
        &self,
        x: f64,
        y: f64,
        min_head: f32,
        limits: &SearchLimits,
    ) -> Result<usize, UnreachableReason> {
        let g = &self.grid;
        let c0 = g.cell_of(x, y).ok_or(UnreachableReason::StartOffGrid)?;
        let ok = |c: usize| {
            let [px, py] = g.position(c);
            g.passable(c, min_head)
                && limits
                    .blocked_discs
                    .iter()
                    .all(|d| (px - d[0]).powi(2) + (py - d[1]).powi(2) > d[2] * d[2])
        };
        if ok(c0) {
            return Ok(c0);
        }
        let r = (3.0 / g.resolution).ceil() as isize;
        let (ci, cj) = ((c0 % g.nx) as isize, (c0 / g.nx) as isize);
        let mut best: Option<(isize, usize)> = None;
        for dj in -r..=r {
            for di in -r..=r {
                let (i, j) = (ci + di, cj + dj);
                if i < 0 || j < 0 || i >= g.nx as isize || j >= g.ny as isize {
                    continue;
                }
                let c = j as usize * g.nx + i as usize;
                let d2 = di * di + dj * dj;
                if d2 <= r * r && ok(c) && best.is_none_or(|(bd, bc)| (d2, c) < (bd, bc)) {
                    best = Some((d2, c));
                }
            }
        }
        best.map(|b| b.1).ok_or(UnreachableReason::StartBlocked)
    }

    /// The cells of `cells` where a leg need not crawl: no top within
    /// `character_radius` and a cell (the refiner's reach, `refine::head_limit`, with
    /// a cell to spare) puts the head below `crawl_switch_height`.
    fn stand_cells(&self, cells: &[usize]) -> Vec<usize> {
        let s = &self.settings;
        let g = &self.grid;
        let crawl_head = (s.crawl_switch_height + s.head_margin) as f32;
        let r = (s.character_radius / g.resolution).ceil() as isize + 1;
        let roomy = |c: usize| {
            let (ci, cj) = ((c % g.nx) as isize, (c / g.nx) as isize);
            (-r..=r).all(|dj| {
                (-r..=r).all(|di| {
                    let (i, j) = (ci + di, cj + dj);
                    di * di + dj * dj > r * r
                        || i < 0
                        || j < 0
                        || i >= g.nx as isize
                        || j >= g.ny as isize
                        || g.headroom[j as usize * g.nx + i as usize] >= crawl_head
                })
            })
        };
        cells.iter().copied().filter(|&c| roomy(c)).collect()
    }

    /// The goal sets a leg of `form` into instruction `index`'s target tries in
    /// turn, from its target cells `cells`, each the deep ones of: with
    /// `stand_at_goal` on a leg that is not a crawl, the cells out of the crawl zone
    /// (where it stands whichever way it comes), then those where it need not crawl
    /// ([`Self::stand_cells`]: coming from the open side it stands); then all.
    fn goal_sets(&self, index: usize, form: Locomotion, cells: &[usize]) -> Vec<Vec<usize>> {
        let mut sets = Vec::new();
        if self.settings.stand_at_goal && form != Locomotion::Crawl && self.grid.has_tops {
            let open: Vec<usize> = cells
                .iter()
                .copied()
                .filter(|&c| !self.grid.crawl_zone[c])
                .collect();
            for set in [open, self.stand_cells(cells)] {
                if !set.is_empty() && set.len() < cells.len() {
                    sets.push(self.deep_cells(index, &set));
                }
            }
        }
        sets.push(self.deep_cells(index, cells));
        sets.dedup();
        sets
    }

    /// Plan instruction `index` from (x, y) with initial speed `v0` \[m/s\], timed from
    /// absolute time `t0` \[s\].
    pub fn plan_instruction(
        &mut self,
        index: usize,
        from: [f64; 2],
        v0: f64,
        t0: f64,
        limits: &SearchLimits,
    ) -> Result<Trajectory, PlanError> {
        let form = self.instructions[index].locomotion;
        let min_head = self.min_head(form);
        let start = self
            .start_cell(from[0], from[1], min_head, limits)
            .map_err(|r| self.unreachable(index, r))?;
        let (goals, _) = self.goal_cells(index, min_head);
        if goals.is_empty() {
            return Err(self.unreachable(index, UnreachableReason::TargetBlocked));
        }
        if !self.components_for(min_head).connected(start, &goals) {
            return Err(self.unreachable(index, UnreachableReason::Disconnected));
        }
        let mut found = None;
        for set in self.goal_sets(index, form, &goals) {
            if !set.is_empty() && self.components_for(min_head).connected(start, &set) {
                found = self.search_body(start, &set, min_head, limits, form);
                if found.is_some() {
                    break;
                }
            }
        }
        let (path, limits) = found
            .or_else(|| self.search_body(start, &goals, min_head, limits, form))
            .ok_or_else(|| self.unreachable(index, UnreachableReason::Disconnected))?;
        let ctx = RefineCtx {
            scene: &self.scene,
            grid: &self.grid,
            settings: &self.settings,
            min_head,
            limits: &limits,
        };
        let mut pts = refine(&ctx, form, &path, Some(from));
        // Towards the next leg's start as the route planned it (none while the route
        // itself is being planned: `plan_route` re-times the legs at the end).
        let b_end = self
            .route
            .get(index + 1)
            .map(|next| junction_speed(&self.settings, &pts, &next.points).powi(2));
        set_speeds(&self.settings, &mut pts, v0, b_end)?;
        Ok(Trajectory::new(t0, pts))
    }

    /// Whether (x, y) is in instruction `index`'s target (with the reach margin used
    /// for landmarks that sit on obstacles).
    pub fn in_target(&self, index: usize, x: f64, y: f64) -> bool {
        let form = self.instructions[index].locomotion;
        let (_, margin) = self.goal_cells(index, self.min_head(form));
        let region = self.target_region(index);
        region_distance(&region, x, y) <= margin + 1e-9
    }

    /// Local re-plan around a predicted conflict: A* in a window from the current
    /// position to a rejoin point on the old path, with the obstacle at its predicted
    /// position blocked; the detour is spliced into the old path and re-timed over
    /// `replan_speed_horizon`. Up to three conflicts are added in turn. When the
    /// detour would end at the target, it ends in the target's cells the obstacles
    /// leave free; an obstacle covering all of them (or the character and all free
    /// cells near it) is an `Unreachable` error naming it.
    pub fn replan_around(
        &mut self,
        old: &Trajectory,
        first: Conflict,
        from: [f64; 2],
        now: f64,
        how: Prediction,
    ) -> Result<Trajectory, PlanError> {
        self.detour(old, first, from, now, how).map(|(tr, _)| tr)
    }

    /// [`Planner::replan_around`], with the conflict the sweep still predicts for the
    /// detour it returns (`None`: clear).
    fn detour(
        &mut self,
        old: &Trajectory,
        first: Conflict,
        from: [f64; 2],
        now: f64,
        how: Prediction,
    ) -> Result<(Trajectory, Option<Conflict>), PlanError> {
        if old.points.is_empty() {
            return Err(PlanError::InvalidInput {
                field: "old",
                reason: "the trajectory to re-plan has no points".into(),
            });
        }
        let s = self.settings.clone();
        let index = self.index.min(self.instructions.len() - 1);
        let form = self.instructions[index].locomotion;
        let min_head = self.min_head(form);
        let v0 = old.sample_at(now).speed;
        let mut discs: Vec<[f64; 3]> = Vec::new();
        let mut conflict = first;
        let mut best = None;
        for _ in 0..3 {
            let o = conflict.obstacle_position;
            let rad = conflict.radius_xy + s.character_radius + s.obstacle_margin;
            discs.push([o[0], o[1], rad]);
            // Along its way after the conflict, one disc per half radius it moves (one
            // coming head-on may cover the character: `start_cell` then steps aside).
            let later = |t: f64| {
                let p = predict_any(&self.scene, self.external(), how, now, conflict.obstacle, t)
                    .position;
                [p[0], p[1]]
            };
            let end = later(conflict.time + s.obstacle_sweep);
            let n = ((end[0] - o[0]).hypot(end[1] - o[1]) / (0.5 * rad)).ceil() as usize;
            for i in 1..=n {
                let p = later(conflict.time + s.obstacle_sweep * i as f64 / n as f64);
                discs.push([p[0], p[1], rad]);
            }
            // Rejoin beyond the last old point near any disc.
            let near = |p: &PathPoint| {
                discs
                    .iter()
                    .any(|d| (p.x - d[0]).powi(2) + (p.y - d[1]).powi(2) <= d[2] * d[2])
            };
            let s_now = old.sample_at(now).s;
            let s_exit = old
                .points
                .iter()
                .filter(|p| p.s >= s_now && near(p))
                .map(|p| p.s)
                .fold(old.sample_at(conflict.time).s, f64::max);
            let last = old.points.len() - 1;
            let rejoin = old
                .points
                .iter()
                .position(|p| p.s > s_exit + s.rejoin_distance && !near(p))
                .unwrap_or(last);
            let rj = old.points[rejoin];
            let g = &self.grid;
            let m = s.replan_window_margin;
            let mut lo = [from[0].min(rj.x), from[1].min(rj.y)];
            let mut hi = [from[0].max(rj.x), from[1].max(rj.y)];
            for d in &discs {
                lo = [lo[0].min(d[0] - d[2]), lo[1].min(d[1] - d[2])];
                hi = [hi[0].max(d[0] + d[2]), hi[1].max(d[1] + d[2])];
            }
            let cell = |v: f64, o: f64, n: usize| {
                (((v - o) / g.resolution).round().max(0.0) as usize).min(n - 1)
            };
            let window = (
                cell(lo[0] - m, g.origin[0], g.nx),
                cell(lo[1] - m, g.origin[1], g.ny),
                cell(hi[0] + m, g.origin[0], g.nx),
                cell(hi[1] + m, g.origin[1], g.ny),
            );
            let limits = SearchLimits {
                blocked_discs: discs.clone(),
                window: Some(window),
                ..SearchLimits::default()
            };
            let start = match self.start_cell(from[0], from[1], min_head, &limits) {
                Ok(c) => c,
                Err(r) => {
                    let free =
                        self.start_cell(from[0], from[1], min_head, &SearchLimits::default());
                    let r = if free.is_ok() {
                        UnreachableReason::StartOccupied {
                            obstacle: conflict.obstacle,
                        }
                    } else {
                        r
                    };
                    return Err(self.unreachable(index, r));
                }
            };
            let goal_sets: Vec<Vec<usize>> = if rejoin == last {
                // The detour ends the instruction: any target cell the discs leave.
                let (cells, _) = self.goal_cells(index, min_head);
                if cells.is_empty() {
                    return Err(self.unreachable(index, UnreachableReason::TargetBlocked));
                }
                let free: Vec<usize> = cells
                    .iter()
                    .copied()
                    .filter(|&c| {
                        let [x, y] = self.grid.position(c);
                        discs
                            .iter()
                            .all(|d| (x - d[0]).powi(2) + (y - d[1]).powi(2) > d[2] * d[2])
                    })
                    .collect();
                if free.is_empty() {
                    let r = UnreachableReason::TargetOccupied {
                        obstacle: conflict.obstacle,
                    };
                    return Err(self.unreachable(index, r));
                }
                self.goal_sets(index, form, &free)
            } else {
                vec![vec![
                    self.start_cell(rj.x, rj.y, min_head, &limits)
                        .map_err(|_| self.unreachable(index, UnreachableReason::TargetBlocked))?,
                ]]
            };
            let found = goal_sets
                .iter()
                .filter(|g| !g.is_empty())
                .find_map(|g| self.search_body(start, g, min_head, &limits, form));
            let Some((path, limits)) = found else {
                break;
            };
            let ctx = RefineCtx {
                scene: &self.scene,
                grid: &self.grid,
                settings: &s,
                min_head,
                limits: &limits,
            };
            let local = refine(&ctx, form, &path, Some(from));
            // Splice: detour, then the old path after the rejoin point.
            let mut xy: Vec<[f64; 2]> = local.iter().map(|p| [p.x, p.y]).collect();
            xy.extend(old.points[rejoin + 1..].iter().map(|p| [p.x, p.y]));
            let mut pts = annotate(&self.scene, &s, form, &xy);
            let s_local = local.last().map_or(0.0, |p| p.s);
            // Re-time the detour plus a horizon; keep the old speeds (limited by the
            // acceleration bound) after that.
            let k_end = pts
                .iter()
                .position(|p| p.s > s_local + s.replan_speed_horizon)
                .unwrap_or(pts.len() - 1);
            let old_b = |k: usize| {
                k.checked_sub(local.len())
                    .and_then(|off| old.points.get(rejoin + 1 + off))
                    .map(|p| p.v * p.v)
            };
            let b_end = if k_end < local.len() {
                None
            } else {
                old_b(k_end)
            };
            set_speeds(&s, &mut pts[..=k_end], v0, b_end)?;
            for k in k_end + 1..pts.len() {
                let ds = pts[k].s - pts[k - 1].s;
                let b = old_b(k)
                    .unwrap_or(f64::INFINITY)
                    .min(pts[k - 1].v.powi(2) + 2.0 * s.a_max * ds);
                pts[k].v = b.max(0.0).sqrt().min(pts[k].v_cap);
            }
            let tr = Trajectory::new(now, pts);
            // The detour starts from the head: no lag.
            let again =
                predict_conflict_with(&tr, &self.scene, self.external(), &s, now, None, how);
            best = Some((tr, again));
            match again {
                Some(c) => conflict = c,
                None => break,
            }
        }
        best.ok_or_else(|| self.unreachable(index, UnreachableReason::Disconnected))
    }

    /// One control step: check progress, re-plan when needed, and return the next
    /// waypoints. Ticks must not go back.
    pub fn plan_step(
        &mut self,
        tick: Tick,
        input: &PlannerInput,
    ) -> Result<PlannerOutput, PlanError> {
        let finite = input
            .head
            .iter()
            .chain(&input.root)
            .chain(&input.velocity)
            .all(|v| v.is_finite());
        if !finite {
            return Err(PlanError::InvalidInput {
                field: "head/root/velocity",
                reason: "must be finite".into(),
            });
        }
        if let Some(k) = input
            .obstacles
            .iter()
            .position(|o| !o.position.iter().chain(&o.velocity).all(|v| v.is_finite()))
        {
            return Err(PlanError::InvalidInput {
                field: "obstacles",
                reason: format!(
                    "observed state of scene obstacle {k} must be finite, got {:?}",
                    input.obstacles[k]
                ),
            });
        }
        if let Some(last) = self.last_tick
            && tick < last
        {
            return Err(PlanError::InvalidInput {
                field: "tick",
                reason: format!("went back from {} to {}", last.0, tick.0),
            });
        }
        self.last_tick = Some(tick);
        let now = tick.seconds();
        let (hx, hy) = (input.head[0], input.head[1]);
        let speed = input.velocity[0].hypot(input.velocity[1]);
        let mut replanned = None;
        let mut status = PlanStatus::Following;
        let mut reached = false;
        if !self.finished && self.in_target(self.index, hx, hy) {
            reached = true;
            self.index += 1;
            self.current = None;
            self.lag_head = None;
            if self.index >= self.instructions.len() {
                self.finished = true;
            }
        }
        if self.finished {
            let tr = self.current.clone().unwrap_or_else(|| {
                Arc::new(Trajectory::new(
                    now,
                    vec![PathPoint {
                        x: hx,
                        y: hy,
                        ground: self.scene.height_at(hx, hy),
                        head_height: input.head[2] - self.scene.height_at(hx, hy),
                        ..Default::default()
                    }],
                ))
            });
            self.current = Some(tr.clone());
            return Ok(self.output(tick, tr, reached, PlanStatus::Finished, None));
        }
        let mut full_reason = None;
        match &self.current {
            None => full_reason = Some(ReplanReason::NewInstruction),
            Some(tr) => {
                if tr
                    .closest_point(hx, hy)
                    .is_some_and(|(_, d)| d > self.settings.drift_distance)
                {
                    full_reason = Some(ReplanReason::Drift);
                } else {
                    let w = tr.sample_at(now);
                    if (w.position[0] - hx).hypot(w.position[1] - hy) > self.settings.lag_distance {
                        full_reason = Some(ReplanReason::Lag);
                    }
                }
            }
        }
        if let Some(reason) = full_reason {
            let mut from = [hx, hy];
            if reason == ReplanReason::Lag {
                // Lagging again where it lagged before: the head is held (against a
                // wall's end, say) and a plan from it would be the same again.
                let stuck = self
                    .lag_head
                    .is_some_and(|[x, y]| (x - hx).hypot(y - hy) < self.settings.stuck_distance);
                if stuck {
                    from = [input.root[0], input.root[1]];
                }
                self.lag_head = Some([hx, hy]);
            }
            match self.plan_instruction(self.index, from, speed, now, &SearchLimits::default()) {
                Ok(tr) => {
                    self.current = Some(Arc::new(tr));
                    replanned = Some(reason);
                }
                Err(PlanError::Unreachable { index, reason, .. }) => {
                    status = PlanStatus::Infeasible { index, reason };
                }
                Err(e) => return Err(e),
            }
        }
        let how = if input.obstacles.is_empty() {
            Prediction::Rules
        } else {
            Prediction::Observed(&input.obstacles)
        };
        if self.settings.dynamic_replanning
            && let Some(tr) = self.current.clone()
            && let Some(conflict) = predict_conflict_with(
                &tr,
                &self.scene,
                self.external(),
                &self.settings,
                now,
                Some([hx, hy]),
                how,
            )
        {
            let head = Some([hx, hy]);
            let wait = plan_wait(
                &tr,
                &conflict,
                &self.scene,
                self.external(),
                &self.settings,
                now,
                head,
                how,
            );
            // A conflict only the look-ahead sees (beyond `collision_horizon`) is
            // waited for, or left until it comes within the horizon: detours that far
            // ahead sent crawlers the long way round (session 49).
            let far = conflict.time > now + self.settings.collision_horizon;
            let detour = (!far).then(|| self.detour(&tr, conflict, [hx, hy], now, how));
            // Wait when the detour arrives little sooner, or is no way out.
            let waits = wait.as_ref().is_some_and(|w| match &detour {
                None | Some(Err(_)) => true,
                Some(Ok((d, still))) => {
                    still.is_some() || w.end_time() <= d.end_time() + self.settings.wait_preference
                }
            });
            match (wait, detour) {
                (Some(w), _) if waits => {
                    self.current = Some(Arc::new(w));
                    replanned = Some(ReplanReason::Wait(conflict));
                }
                (_, Some(Ok((new, _)))) => {
                    self.current = Some(Arc::new(new));
                    replanned = Some(ReplanReason::Obstacle(conflict));
                }
                (_, Some(Err(PlanError::Unreachable { index, reason, .. }))) => {
                    status = PlanStatus::Infeasible { index, reason };
                }
                (_, Some(Err(e))) => return Err(e),
                (_, None) => {}
            }
        }
        let tr = match &self.current {
            Some(t) => t.clone(),
            None => Arc::new(Trajectory::default()),
        };
        Ok(self.output(tick, tr, reached, status, replanned))
    }

    fn output(
        &self,
        tick: Tick,
        tr: Arc<Trajectory>,
        reached: bool,
        status: PlanStatus,
        replanned: Option<ReplanReason>,
    ) -> PlannerOutput {
        let now = tick.seconds();
        let s = &self.settings;
        let waypoints = tr.next_waypoints(now, s.waypoint_count, s.waypoint_dt);
        let fraction = if tr.length() > 0.0 {
            let w = tr.sample_at(now);
            (w.s / tr.length()).clamp(0.0, 1.0)
        } else {
            1.0
        };
        PlannerOutput {
            tick,
            waypoints,
            trajectory: tr,
            progress: Progress {
                index: self.index,
                fraction,
                reached,
            },
            status,
            replanned,
        }
    }
}

/// The fastest the body may pass from the end of leg `a` into leg `b` \[m/s\]:
/// the corner between their directions taken as a bend of `corner_length`, the
/// form change if one happens there, and both legs' own caps.
pub(crate) fn junction_speed(s: &PlannerSettings, a: &[PathPoint], b: &[PathPoint]) -> f64 {
    let (Some(end), Some(start)) = (a.last(), b.first()) else {
        return 0.0;
    };
    let mut v = end.v_cap.min(start.v_cap);
    // Directions over a corner's length on either side (a shorter leg: all of it).
    let before = a
        .iter()
        .rev()
        .find(|p| end.s - p.s >= s.corner_length)
        .or(a.first())
        .unwrap_or(end);
    let after = b
        .iter()
        .find(|p| p.s - start.s >= s.corner_length)
        .or(b.last())
        .unwrap_or(start);
    let d_in = [end.x - before.x, end.y - before.y];
    let d_out = [after.x - start.x, after.y - start.y];
    let (n_in, n_out) = (d_in[0].hypot(d_in[1]), d_out[0].hypot(d_out[1]));
    if n_in > 1e-6 && n_out > 1e-6 {
        let cos = ((d_in[0] * d_out[0] + d_in[1] * d_out[1]) / (n_in * n_out)).clamp(-1.0, 1.0);
        let angle = cos.acos();
        if angle > s.turn_back_angle {
            return 0.0;
        }
        if angle > 1e-3 {
            let curvature = angle / s.corner_length;
            v = v.min((s.a_lat / curvature).sqrt());
            let crawl = end.head_height.min(start.head_height) < s.crawl_switch_height;
            if crawl {
                v = v.min(s.crawl_turn_rate / curvature);
            }
        }
    }
    let crosses = |h0: f64, h1: f64| {
        (h0 >= s.crawl_switch_height && h1 < s.crawl_switch_height)
            || (h0 <= s.stand_switch_height && h1 > s.stand_switch_height)
    };
    if crosses(end.head_height, start.head_height) {
        v = v.min(s.form_change_speed);
    }
    v
}

fn end_speed(t: &Trajectory) -> f64 {
    t.points.last().map_or(0.0, |p| p.v)
}

/// Solve the speed QP for annotated points and write `v`: caps from the locomotion,
/// head height and slope (`v_cap`) and the lateral limit v^2 kappa <= a_lat.
pub(crate) fn set_speeds(
    s: &PlannerSettings,
    pts: &mut [PathPoint],
    v0: f64,
    b_end: Option<f64>,
) -> Result<(), PlanError> {
    let n = pts.len();
    if n == 0 {
        return Ok(());
    }
    if n == 1 {
        pts[0].v = v0.min(pts[0].v_cap);
        return Ok(());
    }
    let b_max: Vec<f64> = pts
        .iter()
        .map(|p| {
            let lat = if p.curvature > 1e-9 {
                s.a_lat / p.curvature
            } else {
                f64::INFINITY
            };
            (p.v_cap * p.v_cap).min(lat).max(1e-6)
        })
        .collect();
    let ds: Vec<f64> = pts
        .windows(2)
        .map(|w| (w[1].s - w[0].s).max(1e-6))
        .collect();
    let problem = SpeedProblem {
        ds,
        b_max,
        b_start: Some(v0 * v0),
        b_end,
        accel: s.a_max,
        decel: -s.a_min,
    };
    let b = solve_speed_qp(&problem)?;
    for (p, b) in pts.iter_mut().zip(b) {
        p.v = b.max(0.0).sqrt();
    }
    Ok(())
}
