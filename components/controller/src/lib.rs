//! PlaMo locomotion controller (paper section 4.2): the observation a policy sees,
//! the policy contract, a learned policy loaded from ONNX, and the path-tracking
//! metrics every run reports.
//!
//! Pure computation: no transport, no physics. The orchestrator feeds a
//! [`HumanoidSnapshot`], the plan's next waypoints and the scene into an
//! [`Observation`], asks a [`Policy`] for an [`Action`] (PD targets + optional bounded
//! root wrench), and records a [`StepSample`] into a [`MetricsAccumulator`].
#![warn(missing_docs)]

mod component;
mod error;
pub mod fall_ground;
mod gait;
mod math;
mod metrics;
mod observation;
mod onnx_policy;
mod policy;
mod rollout;
mod settings;
mod tune;

pub use component::{ControllerComponent, snapshot_from_message};
pub use error::{ControllerError, Result};
pub use fall_ground::{FallBody, pelvis_roll};
pub use gait::{
    CRAWL_PARAMS_VERSION, CrawlParams, DEFAULT_CRAWL_PARAMS, DEFAULT_GAIT_PARAMS, FormParams,
    GAIT_PARAMS_VERSION, GaitParams, HAND_CRAWL_PARAMS, LegGeometry, ModelBasedController,
    ResidualGains, leg_fk, leg_ik,
};
pub use metrics::{
    MetricsAccumulator, MetricsSummary, PathRewardWeights, RewardTerms, StepSample, path_reward,
};
pub use observation::{
    HumanoidSnapshot, NUM_WAYPOINTS, OBSERVATION_VERSION, Observation, ObservationLayout,
    ObservationOffsets, WAYPOINT_SPACING, Waypoint,
};
pub use onnx_policy::{OnnxPolicy, PolicySidecar};
pub use policy::{Action, Policy, RootWrench};
pub use rollout::{
    ArcPath, DropPath, HeadPath, RUN_STAGGER, RampedPath, RisingPath, START_ACCEL, STRIP_LENGTH,
    StraightPath, TurnPath, ceiling_scene, control_step, flat_scene, ledge_scene, run_path,
    run_path_with, run_straight, staggered_start, top_scene,
};
pub use settings::{ControllerSettings, GRAVITY};
pub use tune::{
    Cost, Form, Generation, RESIDUAL_COST, Rng, Sample, SearchField, SepCmaEs, TRACKING_COST,
    TrackingGuard, TuneSettings, TunedParams, evaluate, search_box, start_like, terrain_scene,
    to_toml, tune, tune_with,
};
