//! Exports of a recorded run (`plamo run --out DIR`) for the tools people watch motion
//! in: `replay.glb` (glTF 2.0 binary: scene, humanoid meshes on a node hierarchy and
//! the animation), `motion.bvh` (skeleton and joint rotations for animation tools),
//! `replay.mcap` (transforms and states for robotics log viewers) and the
//! self-contained HTML replay viewer of `plamo view`.
//!
//! Everything is computed from the files of the recording, never from a live run, so
//! `plamo export DIR` on an old recording writes the same bytes `plamo run --out DIR`
//! wrote; no clock or randomness goes in, so two identical recordings export to
//! byte-identical files.

mod bvh;
mod fk;
mod gltf;
mod mcap;
mod mesh;
mod recording;
mod viewer;

pub use bvh::write_bvh;
pub use fk::{BodyPose, body_poses, local_rotations};
pub use gltf::write_glb;
pub use mcap::write_mcap;
pub use recording::{AgentFrame, AgentTrack, ObstacleFrame, PlannedPoint, Recording};
pub use viewer::{
    BUILD_COMMAND, BUNDLE_PATH, ViewerBundle, viewer_data, viewer_html, write_viewer,
};

use std::path::{Path, PathBuf};

/// What went wrong reading a recording or writing an export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file of the recording is missing.
    #[error(
        "{path}: missing; a recording directory is what `plamo run --out DIR` writes (trajectory.csv, obstacles.csv, plans.json, metrics.json, scene.json)"
    )]
    Missing {
        /// The file.
        path: PathBuf,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A line of a CSV file does not have the expected form.
    #[error("{path}:{line}: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A JSON file does not have the expected form.
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
    /// The scene could not be rebuilt.
    #[error("scene of the recording: {0}")]
    Scene(String),
    /// The recording holds no frames.
    #[error("{0}: no frames recorded")]
    Empty(PathBuf),
}

/// File names of the exports inside the recording directory.
pub const GLB_FILE: &str = "replay.glb";
/// BVH file name.
pub const BVH_FILE: &str = "motion.bvh";
/// MCAP file name.
pub const MCAP_FILE: &str = "replay.mcap";

/// Write `replay.glb`, `motion.bvh` (agent 0's motion) and `replay.mcap` into the
/// recording directory; returns the paths written.
pub fn export_dir(dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let rec = Recording::load(dir)?;
    let glb = dir.join(GLB_FILE);
    write_file(&glb, &write_glb(&rec))?;
    let bvh = dir.join(BVH_FILE);
    write_file(&bvh, write_bvh(&rec, 0).as_bytes())?;
    let mcap = dir.join(MCAP_FILE);
    write_file(&mcap, &write_mcap(&rec))?;
    Ok(vec![glb, bvh, mcap])
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ExportError> {
    std::fs::write(path, bytes).map_err(|source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    })
}
