//! The lockstep scheduler (DESIGN "Lockstep"): one control step at tick 4c is
//!
//! 1. read the physics state at 4c ([`sense`]: falls and metrics),
//! 2. every agent's planner ([`plan`]),
//! 3. every agent's controller ([`control`]),
//! 4. physics, four steps of 1/120 s ([`actuate`]).
//!
//! The components are reached through [`Link`]s, the same way whether they run in
//! this process or in others. Nothing here reads a clock to decide anything: the
//! wall-clock timings it keeps are reported, never used.

mod actuate;
mod control;
mod digest;
mod error;
pub mod external;
mod link;
mod plan;
mod recover;
mod sense;

use std::time::{Duration, Instant};

use plamo_controller::ControllerSettings;
use plamo_interfaces::{
    AgentAction, ControllerInput, MAX_OBSTACLES, ObstacleSample, PHYSICS_STEPS_PER_CONTROL,
    PhysicsInput, PhysicsOutput, PlanMessage, Tick,
};
use plamo_scenes::Scene;

pub use digest::Digest;
pub use error::RunError;
pub use link::{InProcess, Link};
pub(crate) use recover::stands_clear;
pub use sense::InstructionReport;

use sense::AgentTracker;

/// The component instances of one run.
pub struct Links {
    /// The physics world.
    pub physics: Box<dyn Link<PhysicsInput, PhysicsOutput>>,
    /// One planner per agent, in agent order.
    pub planners: Vec<Box<dyn Link<PhysicsOutput, PlanMessage>>>,
    /// One controller per agent, in agent order.
    pub controllers: Vec<Box<dyn Link<ControllerInput, AgentAction>>>,
}

/// Whether the run goes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepStatus {
    /// More to do.
    Running,
    /// Every agent finished every instruction.
    Finished,
    /// The simulated-time limit was reached first.
    TimedOut,
}

/// Wall-clock durations of every call, per component kind \[s\] (reporting only).
#[derive(Debug, Clone, Default)]
pub struct CallTimes {
    /// Physics calls.
    pub physics: Vec<f64>,
    /// Planner calls (all agents of one tick together).
    pub planners: Vec<f64>,
    /// Controller calls (all agents of one tick together).
    pub controllers: Vec<f64>,
    /// Whole control steps.
    pub steps: Vec<f64>,
}

/// The orchestrator's loop over [`Links`].
pub struct Lockstep {
    links: Links,
    scene: Scene,
    world: PhysicsOutput,
    plans: Vec<PlanMessage>,
    input: PhysicsInput,
    fallen: Vec<bool>,
    /// Each agent's falls at one spot, for where its next reset goes.
    recovery: Vec<recover::Recovery>,
    /// The fall rule's verdicts at the last control step.
    fell: Vec<bool>,
    trackers: Vec<AgentTracker>,
    digest: Digest,
    max_tick: u64,
    times: CallTimes,
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

impl Lockstep {
    /// Read the world at tick 0 and get ready. `instruction_counts[k]` is agent k's
    /// number of instructions; the run stops at `max_seconds` of simulated time.
    pub fn start(
        mut links: Links,
        scene: Scene,
        instruction_counts: &[usize],
        controller: &ControllerSettings,
        max_seconds: f64,
    ) -> Result<Self, RunError> {
        let agents = links.planners.len();
        if agents == 0 || links.controllers.len() != agents || instruction_counts.len() != agents {
            return Err(RunError::Setup(format!(
                "{} planners, {} controllers and {} instruction lists: need one of each per agent",
                agents,
                links.controllers.len(),
                instruction_counts.len()
            )));
        }
        let world = links.physics.call(0, &PhysicsInput::default())?;
        if world.tick != 0 || world.agent_count as usize != agents {
            return Err(RunError::Setup(format!(
                "physics reported tick {} with {} agents, expected tick 0 with {agents}",
                world.tick, world.agent_count
            )));
        }
        let mut digest = Digest::default();
        digest.add(&world);
        let per = PHYSICS_STEPS_PER_CONTROL as u64;
        let max_tick =
            ((max_seconds * plamo_interfaces::PHYSICS_HZ as f64).ceil() as u64).div_ceil(per) * per;
        Ok(Self {
            links,
            scene,
            world,
            plans: vec![PlanMessage::default(); agents],
            input: PhysicsInput::default(),
            fallen: vec![false; agents],
            recovery: vec![recover::Recovery::default(); agents],
            fell: vec![false; agents],
            trackers: instruction_counts
                .iter()
                .map(|&n| AgentTracker::new(n, controller.clone()))
                .collect(),
            digest,
            max_tick,
            times: CallTimes::default(),
        })
    }

    /// One control step from the current tick (4c) to 4c + 4. Once the run has
    /// finished or timed out, every further call says so again and changes nothing.
    pub fn step(&mut self) -> Result<StepStatus, RunError> {
        let tick = self.world.tick;
        if tick >= self.max_tick {
            return Ok(StepStatus::TimedOut);
        }
        if self.trackers.iter().all(AgentTracker::done) {
            return Ok(StepStatus::Finished);
        }
        let t0 = Instant::now();
        plan::plan(&mut self.links.planners, tick, &self.world, &mut self.plans)?;
        self.times.planners.push(secs(t0));
        for (k, tracker) in self.trackers.iter_mut().enumerate() {
            let fell = tracker.observe(
                &self.scene,
                Tick(tick),
                &self.world.agents[k],
                &self.plans[k],
                &self.input.actions[k],
            );
            self.fell[k] = fell;
            // A start with no room to stand (a landmark wholly under a low top: the
            // body spawned standing through it) gets the fall reset's placement in
            // the plan's form, without counting a fall.
            let root = self.world.agents[k].root_position;
            let boxed_in = tick == 0 && !stands_clear(&self.scene, root[0], root[1]);
            self.fallen[k] = fell || boxed_in;
            if self.fallen[k] {
                tracker.put_back();
            }
        }
        if self.trackers.iter().all(AgentTracker::done) {
            return Ok(StepStatus::Finished);
        }
        let t1 = Instant::now();
        control::control(
            &mut self.links.controllers,
            tick,
            &self.world,
            &self.plans,
            control::Fallen {
                flags: &self.fallen,
                scene: &self.scene,
                recovery: &mut self.recovery,
            },
            &mut self.input,
        )?;
        self.times.controllers.push(secs(t1));
        if tick == 0 {
            // The start's reset is no fall: a fall near the start is a first one.
            for (r, &fell) in self.recovery.iter_mut().zip(&self.fell) {
                if !fell {
                    *r = recover::Recovery::default();
                }
            }
        }
        let t2 = Instant::now();
        self.world = actuate::actuate(self.links.physics.as_mut(), &self.input)?;
        self.times.physics.push(secs(t2));
        self.times.steps.push(secs(t0));
        self.digest.add(&self.world);
        Ok(StepStatus::Running)
    }

    /// Drive external obstacles (an FMU host's ball or car) from now on: the planners
    /// see these states at the current tick (after the scene's obstacles, in the
    /// slots of [`external::slot_scene`]), physics moves its slots from them at their
    /// velocities through the coming control period (the humanoid collides with them)
    /// and reports them at the next tick. They stay until set again. Refuses
    /// non-finite numbers and more than fit in a world.
    pub fn set_external_obstacles(&mut self, obstacles: &[ObstacleSample]) -> Result<(), RunError> {
        let own = self.scene.dynamic.len().min(MAX_OBSTACLES);
        external::check(own, obstacles)?;
        let n = obstacles.len();
        self.input.external_count = n as u32;
        self.input.external_obstacles[..n].copy_from_slice(obstacles);
        self.world.obstacles[own..own + n].copy_from_slice(obstacles);
        self.world.obstacle_count = (own + n) as u32;
        Ok(())
    }

    /// Agent `k`'s horizontal distance from where its plan wanted its head at the last
    /// control step \[m\] (the XY error of the tracking metrics; 0 before the first
    /// step and after the last instruction).
    pub fn xy_error(&self, k: usize) -> f64 {
        self.trackers
            .get(k)
            .map_or(0.0, AgentTracker::last_xy_error)
    }

    /// The world as physics last reported it.
    pub fn world(&self) -> &PhysicsOutput {
        &self.world
    }
    /// Each agent's plan from the last control step.
    pub fn plans(&self) -> &[PlanMessage] {
        &self.plans
    }
    /// The actions applied during the last control period.
    pub fn input(&self) -> &PhysicsInput {
        &self.input
    }
    /// Which agents were reset at the last control step: found fallen, or at the
    /// first step with no room to stand where they started.
    pub fn fallen(&self) -> &[bool] {
        &self.fallen
    }
    /// Which agents the fall rule found fallen at the last control step, the rule
    /// the run's fall counts use. A recorder writes each world with the verdicts of
    /// the step that judged it; the last world of a run that timed out or finished,
    /// which no step judged, carries the last verdicts over (a fall that would begin
    /// there is not counted by the run's summary, so it is not recorded either).
    pub fn fall_verdicts(&self) -> &[bool] {
        &self.fell
    }
    /// The current tick.
    pub fn tick(&self) -> Tick {
        Tick(self.world.tick)
    }
    /// The fingerprint of every world state so far.
    pub fn digest(&self) -> Digest {
        self.digest
    }
    /// Wall-clock call durations so far.
    pub fn times(&self) -> &CallTimes {
        &self.times
    }
    /// The current instruction of agent `k` (equals its count when done).
    pub fn instruction(&self, k: usize) -> usize {
        self.plans.get(k).map_or(0, |p| p.instruction as usize)
    }
    /// Per-agent, per-instruction outcomes so far.
    pub fn report(&self) -> Vec<Vec<InstructionReport>> {
        let t = self.tick().seconds();
        self.trackers.iter().map(|tr| tr.report(t)).collect()
    }
    /// Agent `k`'s falls over every instruction so far (the per-instruction
    /// reports' sum, without building them).
    pub fn falls(&self, k: usize) -> u32 {
        self.trackers.get(k).map_or(0, AgentTracker::falls)
    }
    /// Give the links back (to shut remote components down).
    pub fn into_links(self) -> Links {
        self.links
    }
}

/// Median and 99th percentile of `v` \[same unit\]; zeros when empty.
pub fn median_p99(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |q: f64| s[((s.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.99))
}

/// Sleep until simulated time `tick` is due on a wall clock started at `start`,
/// `speed` times faster than real time. Returns whether the tick was already late.
pub fn pace(start: Instant, tick: Tick, speed: f64) -> bool {
    let due = Duration::from_secs_f64(tick.seconds() / speed);
    match due.checked_sub(start.elapsed()) {
        Some(wait) => {
            std::thread::sleep(wait);
            false
        }
        None => true,
    }
}
