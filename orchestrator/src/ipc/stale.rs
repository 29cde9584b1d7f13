//! What crashed runs left behind, whatever their run id. Every file a run creates is
//! named `plamo_<run id>_...` (see [`run_config`]), so the files under /dev/shm and
//! the iceoryx2 root tell which runs exist; a run none of whose nodes is alive is
//! stale, and removing its dead nodes' resources and its management segment deletes
//! its files.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, SystemTime};

use iceoryx2::prelude::*;
use plamo_interfaces::RunId;

use super::liveness::end_run;
use super::setup::{FILE_PREFIX, run_config, runtime_root};

/// Where iceoryx2 keeps a run's files: POSIX shared memory and its root directory.
/// iceoryx2's default root too: runs of plamo versions that kept their files there
/// may have crashed.
fn roots() -> Vec<PathBuf> {
    let default = Config::default().global.root_path().to_string();
    let mut roots = vec![PathBuf::from("/dev/shm"), PathBuf::from(default)];
    let ours = PathBuf::from(runtime_root());
    if !roots.iter().any(|r| ours.starts_with(r)) {
        roots.push(ours);
    }
    roots
}

/// Every plamo file on disk, by run id.
fn files_by_run() -> BTreeMap<String, Vec<PathBuf>> {
    let mut runs: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    let mut dirs = roots();
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                dirs.push(path);
                continue;
            }
            let name = e.file_name().to_string_lossy().into_owned();
            if let Some((run, _)) = name
                .strip_prefix(FILE_PREFIX)
                .and_then(|rest| rest.split_once('_'))
            {
                runs.entry(run.to_owned()).or_default().push(path);
            }
        }
    }
    runs
}

/// The files run `run` has on disk now (shared memory, iceoryx2 root).
pub fn run_files(run: &RunId) -> Vec<PathBuf> {
    files_by_run().remove(run.as_str()).unwrap_or_default()
}

/// A crashed run whose files were removed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StaleRun {
    /// Its run id.
    pub run: String,
    /// How many files it had left.
    pub files: usize,
}

/// Remove the files of every run none of whose processes is alive. A run with no
/// node at all whose newest file is younger than `grace` is left alone: it may be
/// starting up (its first node not created yet).
pub fn clean_stale_runs(grace: Duration) -> Vec<StaleRun> {
    let mut cleaned = Vec::new();
    for (run, files) in files_by_run() {
        let Ok(id) = RunId::new(&run) else { continue };
        let Ok(cfg) = run_config(&id) else { continue };
        let (mut nodes, mut live) = (0usize, 0usize);
        let _ = Node::<ipc::Service>::list(&cfg, |state| {
            nodes += 1;
            if !matches!(state, NodeState::Dead(_)) {
                live += 1;
            }
            CallbackProgression::Continue
        });
        if live > 0 {
            continue;
        }
        if nodes == 0 {
            let newest = files
                .iter()
                .filter_map(|f| f.metadata().and_then(|m| m.modified()).ok())
                .max();
            let young = newest
                .and_then(|t| SystemTime::now().duration_since(t).ok())
                .is_none_or(|age| age < grace);
            if young {
                continue;
            }
        }
        if end_run(&cfg).is_ok() {
            // Whatever iceoryx2 no longer knows about (a half-created service of a
            // process killed mid-setup) goes too: nobody of this run is alive.
            for f in run_files(&id) {
                let _ = std::fs::remove_file(f);
            }
            cleaned.push(StaleRun {
                run,
                files: files.len(),
            });
        }
    }
    cleaned
}
