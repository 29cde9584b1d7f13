//! Phase 1 and the evaluation: read the physics state at tick 4c, decide which
//! humanoids have fallen (for the posture their plan asks for), and feed each agent's
//! per-instruction metrics (r_tau, XY/Z error, falls, residual wrench).
//!
//! Everything here is computed from the interface messages only, so in-process and
//! multi-process runs evaluate identically.

use std::collections::VecDeque;

use plamo_controller::{
    ControllerSettings, FallBody, MetricsAccumulator, MetricsSummary, PathRewardWeights,
    RootWrench, StepSample,
};
use plamo_interfaces::{
    AgentAction, CONTROL_DT, CONTROL_HZ, HumanoidState, PLAN_WAYPOINT_DT, PlanMessage, Tick,
};
use plamo_physics::HEAD;
use plamo_planner::FLAG_FINISHED;
use plamo_scenes::Scene;
use serde::Serialize;

/// Control steps between two plan waypoints (0.5 s at 30 Hz).
const STEPS_PER_WAYPOINT: usize = (PLAN_WAYPOINT_DT * CONTROL_HZ as f64) as usize;

/// One instruction's outcome for one agent.
#[derive(Debug, Clone, Serialize)]
pub struct InstructionReport {
    /// The instruction's index.
    pub index: usize,
    /// Reached its target without falling on the way.
    pub success: bool,
    /// Its target was reached (possibly after falls).
    pub reached: bool,
    /// Simulated time from the instruction becoming current to its target being
    /// reached, or to the end of the run \[s\].
    pub time_s: f64,
    /// Tracking metrics over the instruction (falls, XY/Z error, r_tau, residual).
    pub metrics: MetricsSummary,
}

/// Tracks one agent: its current instruction, its metrics, and the plan's head
/// position for "now" (the plan issued 0.5 s earlier put its first waypoint here).
pub(crate) struct AgentTracker {
    settings: ControllerSettings,
    instructions: Vec<Track>,
    current: usize,
    /// Head targets the plan set for the coming steps: front = now.
    first_waypoints: VecDeque<[f64; 3]>,
    start_head: Option<[f64; 3]>,
    steps: usize,
    done: bool,
    last_xy_error: f64,
    /// The requested head height the fall rule held the head to at the last judged
    /// step \[m\] (it rises at most at `fall_rise_rate`).
    fall_bar: f64,
    /// Whether the humanoid was put back (a fall's reset, or a start with no room to
    /// stand) since the last judged step: the bar then starts from the head of the
    /// pose it was put in.
    reset: bool,
}

struct Track {
    acc: MetricsAccumulator,
    start_t: f64,
    reached_t: Option<f64>,
}

/// Horizontal distance from a low top within which the fall rule allows the head as
/// low as the top's headroom \[m\]: a crawl's body reaches ~1 m behind its head, and
/// the get-down and get-up take 1.5 s each.
const TOP_GRACE: f64 = 2.0;

fn residual(a: &AgentAction) -> Option<RootWrench> {
    let w = a.root_wrench;
    (w != [0.0; 6]).then_some(RootWrench {
        force: [w[0], w[1], w[2]],
        torque: [w[3], w[4], w[5]],
    })
}

fn heading(q: [f64; 4]) -> f64 {
    // Message quaternion (x, y, z, w): yaw of the rotated +X axis.
    let [x, y, z, w] = q;
    let fx = 1.0 - 2.0 * (y * y + z * z);
    let fy = 2.0 * (x * y + w * z);
    fy.atan2(fx)
}

impl AgentTracker {
    pub(crate) fn new(instructions: usize, settings: ControllerSettings) -> Self {
        Self {
            instructions: (0..instructions)
                .map(|_| Track {
                    acc: MetricsAccumulator::new(
                        PathRewardWeights::default(),
                        settings.body_weight(),
                        vec![],
                    ),
                    start_t: 0.0,
                    reached_t: None,
                })
                .collect(),
            settings,
            current: 0,
            first_waypoints: VecDeque::with_capacity(STEPS_PER_WAYPOINT + 1),
            start_head: None,
            steps: 0,
            done: false,
            last_xy_error: 0.0,
            fall_bar: f64::INFINITY,
            reset: false,
        }
    }

    /// The humanoid is being put back into a pose (its head height is judged at the
    /// next step): a crawl pose under a top on a standing plan gets the time a crawler
    /// needs to stand up, as where the plan asks for a taller form. Without it, the
    /// fall rule judged the pose fallen the step after it was placed.
    pub(crate) fn put_back(&mut self) {
        self.reset = true;
    }

    /// Falls over every instruction so far (as the report counts them).
    pub(crate) fn falls(&self) -> u32 {
        self.instructions.iter().map(|t| t.acc.falls()).sum()
    }

    /// Whether the agent finished every instruction.
    pub(crate) fn done(&self) -> bool {
        self.done
    }

    /// The head's horizontal distance from its target at the last recorded step \[m\].
    pub(crate) fn last_xy_error(&self) -> f64 {
        self.last_xy_error
    }

    /// Whether the humanoid has fallen for the posture `plan` asks for.
    #[cfg(test)]
    pub(crate) fn is_fallen(&self, scene: &Scene, s: &HumanoidState, plan: &PlanMessage) -> bool {
        let (fallen, _) = self.judge(scene, s, plan);
        fallen
    }

    /// The fall verdict, and the requested height it held the head to.
    fn judge(&self, scene: &Scene, s: &HumanoidState, plan: &PlanMessage) -> (bool, f64) {
        let h = s.head_position;
        let above = h[2] - self.settings.fall_ground(scene, &FallBody::of_message(s));
        let fall_bar = if self.reset {
            self.fall_bar.min(above)
        } else {
            self.fall_bar
        };
        // The plan lowers the head below its form's height under low tops (a run leg
        // crawls through a gap): a head that follows it has not fallen.
        let w = plan.waypoints[0].position;
        // Nor has a humanoid near a low top whose plan's height moved on faster than a
        // body can get down or up (the plan also runs ahead of a slow crawl): the
        // headroom of tops within `TOP_GRACE` of the root caps the height, so the fall
        // rule does not stand a crawler up inside a top.
        let r = s.root_position;
        let headroom = scene
            .headroom_near(r[0], r[1], TOP_GRACE)
            .unwrap_or(f64::INFINITY);
        // A taller form is asked for at once where a leg ends; the body stands up at
        // a bounded rate, and so does the bar.
        let requested = plan
            .form_height
            .min(w[2] - scene.height_at(w[0], w[1]))
            .min(headroom)
            .min(fall_bar + self.settings.fall_rise_rate * CONTROL_DT);
        (
            self.settings.is_fallen(above, requested) || !above.is_finite(),
            requested,
        )
    }

    /// Record the step at `tick` with this tick's plan and the action applied during
    /// the previous control period. Returns whether the humanoid is fallen.
    pub(crate) fn observe(
        &mut self,
        scene: &Scene,
        tick: Tick,
        s: &HumanoidState,
        plan: &PlanMessage,
        last_action: &AgentAction,
    ) -> bool {
        let t = tick.seconds();
        let (fallen, bar) = self.judge(scene, s, plan);
        self.fall_bar = bar;
        self.reset = false;
        if self.done {
            return fallen;
        }
        let head = s.head_position;
        let start = *self.start_head.get_or_insert(head);
        // Instruction switches: the planner moved on because the target was reached.
        let reached_up_to = (plan.instruction as usize).min(self.instructions.len());
        while self.current < reached_up_to {
            self.instructions[self.current].reached_t = Some(t);
            self.current += 1;
            if let Some(next) = self.instructions.get_mut(self.current) {
                next.start_t = t;
            }
        }
        if plan.flags & FLAG_FINISHED != 0 || self.current >= self.instructions.len() {
            self.done = true;
            return fallen;
        }
        let w0 = plan.waypoints[0].position;
        self.first_waypoints.push_back(w0);
        let target = if self.steps < STEPS_PER_WAYPOINT {
            // Before the first plan's first waypoint is due: along the line to it.
            let first = self.first_waypoints[0];
            let f = self.steps as f64 / STEPS_PER_WAYPOINT as f64;
            std::array::from_fn(|i| start[i] + (first[i] - start[i]) * f)
        } else {
            self.first_waypoints.pop_front().unwrap_or(w0)
        };
        self.steps += 1;
        self.last_xy_error = ((target[0] - head[0]).powi(2) + (target[1] - head[1]).powi(2)).sqrt();
        let yaw = heading(s.root_orientation);
        let max_other = s
            .bodies()
            .iter()
            .enumerate()
            .filter(|(b, _)| *b != HEAD)
            .map(|(_, p)| p[2])
            .fold(f64::NEG_INFINITY, f64::max);
        let sample = StepSample {
            t,
            head,
            target,
            head_dir: [yaw.cos(), yaw.sin(), 0.0],
            path_dir: [w0[0] - target[0], w0[1] - target[1], 0.0],
            max_other_body_z: max_other,
            fallen,
            residual: residual(last_action),
        };
        self.instructions[self.current].acc.push(&sample);
        fallen
    }

    /// The per-instruction outcomes at simulated time `end_t` \[s\].
    pub(crate) fn report(&self, end_t: f64) -> Vec<InstructionReport> {
        self.instructions
            .iter()
            .enumerate()
            .map(|(index, tr)| {
                let metrics = tr.acc.summary();
                let reached = tr.reached_t.is_some();
                let started = index <= self.current;
                InstructionReport {
                    index,
                    success: reached && metrics.falls == 0,
                    reached,
                    time_s: if started {
                        tr.reached_t.unwrap_or(end_t) - tr.start_t
                    } else {
                        0.0
                    },
                    metrics,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_tops_cap_the_fall_height() {
        let scene = plamo_scenes::builtin("playground").unwrap();
        let tracker = AgentTracker::new(1, ControllerSettings::default());
        let mut plan = PlanMessage {
            form_height: 1.47,
            ..Default::default()
        };
        let mut s = HumanoidState::default();
        // Under the 0.6 m tunnel (x 7-11, y 19.6-21.2), 0.2 m beside it, and in the open
        // by the fountain: a crawler (head 0.35 m) whose plan already rose to standing.
        for ([x, y], under) in [
            ([9.5, 20.4], true),
            ([9.5, 19.4], true),
            ([4.0, 11.0], false),
        ] {
            s.root_position = [x, y, 0.45];
            s.head_position = [x + 0.4, y, 0.35];
            plan.waypoints[0].position = [x + 1.0, y, 1.47];
            assert_eq!(tracker.is_fallen(&scene, &s, &plan), !under, "({x}, {y})");
        }
        // Under the tunnel a head on the ground is still a fall.
        s.root_position = [9.5, 20.4, 0.2];
        s.head_position = [9.9, 20.4, 0.1];
        assert!(tracker.is_fallen(&scene, &s, &plan));
    }

    /// A crawler up on its knees at the foot of a riser whose head is over the tread
    /// above is judged from its knees, not from that tread; lying there, or with the
    /// rule switched off, it is fallen.
    #[test]
    fn a_crawler_with_its_head_over_a_tread_is_judged_from_its_knees() {
        let scene = plamo_scenes::builtin("terrain-stairs").unwrap();
        let y = 0.0;
        let x = (0..600)
            .map(|i| 5.0 + i as f64 * 0.05)
            .find(|&x| scene.height_at(x + 0.5, y) - scene.height_at(x, y) > 0.1)
            .expect("a riser on the stairs strip");
        let (low, high) = (scene.height_at(x, y), scene.height_at(x + 0.5, y));
        let mut plan = PlanMessage {
            form_height: 0.4,
            ..Default::default()
        };
        plan.waypoints[0].position = [x + 1.0, y, high + 0.4];
        let mut s = HumanoidState {
            root_position: [x, y, low + 0.5],
            head_position: [x + 0.5, y, high + 0.18],
            body_count: 2,
            ..Default::default()
        };
        s.body_positions[0] = s.root_position;
        s.body_positions[1] = [x - 0.2, y, low + 0.05];
        let judged = |settings: ControllerSettings, s: &HumanoidState| {
            AgentTracker::new(1, settings).is_fallen(&scene, s, &plan)
        };
        assert!(!judged(ControllerSettings::default(), &s));
        let old = ControllerSettings {
            fall_from_lowest_body: false,
            ..Default::default()
        };
        assert!(judged(old, &s));
        // Down on the riser: the pelvis no higher than the tread it lies against.
        s.root_position[2] = low + 0.15;
        s.body_positions[0] = s.root_position;
        assert!(judged(ControllerSettings::default(), &s));
    }

    /// A body put back on hands and knees (a start under a low top, a reset under one)
    /// on a walking plan: judged from the pose's head, rising at the body's pace, not
    /// fallen the step after it was placed; a body not put back with its head there is.
    #[test]
    fn a_body_put_back_crawling_gets_the_time_to_stand_up() {
        let scene = plamo_scenes::builtin("playground").unwrap();
        let settings = ControllerSettings::default();
        let ([x, y], ground) = ([4.0, 11.0], scene.height_at(4.0, 11.0));
        let mut plan = PlanMessage {
            instruction_count: 2,
            form_height: 1.47,
            ..Default::default()
        };
        plan.waypoints[0].position = [x + 1.0, y, ground + 1.47];
        let mut s = HumanoidState::default();
        let mut judge = |tracker: &mut AgentTracker, head: f64, k: u64| {
            s.root_position = [x, y, ground + 0.45];
            s.head_position = [x + 0.3, y, ground + head];
            plan.tick = k * 4;
            tracker.observe(&scene, Tick(k * 4), &s, &plan, &AgentAction::default())
        };
        // Standing, then put back crawling: the crawl's head rises as it stands up.
        let mut tracker = AgentTracker::new(2, settings.clone());
        assert!(!judge(&mut tracker, 1.47, 0));
        tracker.put_back();
        let up = (1.47 - 0.4) / (settings.fall_rise_rate * CONTROL_DT);
        for i in 1..=up.ceil() as u64 {
            let head = (0.4 + settings.fall_rise_rate * CONTROL_DT * (i - 1) as f64).min(1.47);
            assert!(!judge(&mut tracker, head, i), "standing up, step {i}");
        }
        // Not put back: the same crawl pose on the walking plan is fallen.
        let mut tracker = AgentTracker::new(2, settings);
        assert!(!judge(&mut tracker, 1.47, 0));
        assert!(judge(&mut tracker, 0.4, 1));
    }

    /// A crouch-walk leg ends and a walk begins: the plan asks for 1.47 m at once, the
    /// body rises at the biped's rate and is not fallen on the way; a body that stays
    /// crouched is fallen once the bar has had time to rise (1.3 s to 1.3 m); a crawl asked for after
    /// a walk lowers the bar at once.
    #[test]
    fn the_fall_bar_rises_at_a_bodys_pace() {
        let scene = plamo_scenes::builtin("playground").unwrap();
        let settings = ControllerSettings::default();
        let mut tracker = AgentTracker::new(2, settings.clone());
        let ([x, y], ground) = ([4.0, 11.0], scene.height_at(4.0, 11.0));
        let plan_at = |h: f64, k: u64| {
            let mut p = PlanMessage {
                tick: k * 4,
                instruction_count: 2,
                form_height: h,
                ..Default::default()
            };
            p.waypoints[0].position = [x + 1.0, y, ground + h];
            p
        };
        let mut s = HumanoidState::default();
        let mut judge = |tracker: &mut AgentTracker, head: f64, h: f64, k: u64| {
            s.root_position = [x, y, ground + 0.6];
            s.head_position = [x + 0.2, y, ground + head];
            let a = AgentAction::default();
            tracker.observe(&scene, Tick(k * 4), &s, &plan_at(h, k), &a)
        };
        let mut k = 0;
        for _ in 0..30 {
            assert!(!judge(&mut tracker, 0.8, 0.8, k));
            k += 1;
        }
        // Rising from 0.8 m at 0.5 m/s: never below the bar.
        let rise_steps = ((1.47 - 0.8) / (settings.fall_rise_rate * CONTROL_DT)).ceil() as u64;
        for i in 0..=rise_steps {
            let head = (0.8 + settings.fall_rise_rate * CONTROL_DT * i as f64).min(1.47);
            assert!(!judge(&mut tracker, head, 1.47, k), "rising, step {i}");
            k += 1;
        }
        // Staying crouched under a walk's plan is a fall once the bar has risen.
        let mut tracker = AgentTracker::new(2, settings.clone());
        let verdicts: Vec<bool> = (0..90)
            .map(|i| judge(&mut tracker, 0.8, if i < 30 { 0.8 } else { 1.47 }, i))
            .collect();
        assert!(!verdicts[30], "fallen the moment the walk began");
        assert!(verdicts[89], "a crouched body 2 s into a walk is fallen");
        // A lower request applies at once: a standing head is not fallen, a head at
        // 0.15 m is.
        assert!(!judge(&mut tracker, 1.47, 0.4, 90));
        assert!(judge(&mut tracker, 0.15, 0.4, 91));
    }
}
