//! PlaMo physics: one humanoid, two backends (rapier and MuJoCo), swappable by one
//! flag.
//!
//! - [`humanoid`]: the humanoid description (bodies, hinge joints, limits, PD gains),
//!   the single source both backends are built from; [`JOINT_NAMES`] is the action
//!   and joint-state order.
//! - [`PhysicsBackend`]: the trait; [`create_backend`] builds either engine from a
//!   [`plamo_scenes::Scene`] and [`PhysicsSettings`].
//! - [`detect_fall`]: fall detection over a [`HumanoidState`].
//!
//! # Cargo feature `mujoco`
//! Off by default, so crates that do not ask for MuJoCo never need the native
//! library. With it, mujoco-rs 7.0.0 links MuJoCo 3.17.0 from
//! `third_party/mujoco/lib` (installed by `scripts/install-mujoco.sh`; the workspace
//! `.cargo/config.toml` sets `MUJOCO_DYNAMIC_LINK_DIR` and an `$ORIGIN`-relative
//! rpath, so `cargo test`/`run`/`bench` need no environment variables). The
//! workspace test command enables it:
//! `scripts/install-mujoco.sh && cargo test --workspace --features plamo-physics/mujoco`.
//! Without it, `create_backend(BackendKind::Mujoco, ..)` returns
//! [`PhysicsError::Unavailable`].
//!
//! # One description, two engines
//! The humanoid is typed Rust data ([`humanoid::BODIES`], [`humanoid::JOINTS`]); the
//! MuJoCo backend writes MJCF from it ([`humanoid_mjcf`] with the feature) and the
//! rapier backend builds a multibody from the same tables, one link per hinge. No
//! MJCF parser is involved on the rapier side (rapier3d-mjcf was not used).
//!
//! ```
//! use plamo_physics::{BackendKind, HumanoidPose, NUM_JOINTS, PhysicsSettings, create_backend};
//! use plamo_scenes::{HeightGrid, Scene};
//!
//! let scene = Scene {
//!     name: "flat".into(),
//!     description: String::new(),
//!     terrain: HeightGrid::flat([-2.0, -2.0], [4.0, 4.0], 0.1, 0.0),
//!     walls: vec![],
//!     dynamic: vec![],
//!     tops: vec![],
//!     landmarks: vec![],
//! };
//! let mut physics = create_backend("rapier".parse()?, &scene, &PhysicsSettings::default())?;
//! physics.reset(&HumanoidPose::standing(0.0, 0.0, 0.0, 0.0))?;
//! physics.set_action(&[0.0; NUM_JOINTS], None)?;
//! physics.step_n(4)?;
//! assert!(physics.state().head[2] > 1.3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

mod backend;
mod component;
mod error;
mod fall;
pub mod humanoid;
mod math;
#[cfg(feature = "mujoco")]
mod mujoco;
mod obstacles;
mod rapier;
mod settings;
mod state;

pub use backend::{BackendKind, PhysicsBackend, create_backend};
pub use component::{PhysicsComponent, Placement, reset_request};
pub use error::{ParseBackendKindError, PhysicsError};
pub use fall::{FallReason, Posture, detect_fall};
pub use humanoid::{
    BODY_NAMES, FEET, HANDS, HEAD, HEAD_OFFSET, HEAD_RADIUS, JOINT_NAMES, NUM_BODIES, NUM_JOINTS,
    PELVIS,
};
#[cfg(feature = "mujoco")]
pub use mujoco::{MujocoBackend, humanoid_mjcf};
pub use rapier::RapierBackend;
pub use settings::PhysicsSettings;
pub use state::{
    HumanoidPose, HumanoidState, MAX_JOINT_SPEED, MAX_ROOT_SPEED, MAX_ROOT_SPIN, RootWrench,
};
