//! Shared by the orchestrator's integration tests and benchmarks.

// Each test binary compiles this module and uses a part of it.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::ops::Deref;
use std::path::Path;

/// An output folder under the system temp dir that is deleted when the test that
/// made it ends, pass or fail: a run writes several MB, and CI machines run the
/// suite again and again. It derefs to the folder's path.
pub struct OutDir(tempfile::TempDir);

/// A fresh, empty output folder whose name starts with `plamo-{tag}-{name}-`.
pub fn out_dir(tag: &str, name: &str) -> OutDir {
    OutDir(
        tempfile::Builder::new()
            .prefix(&format!("plamo-{tag}-{name}-"))
            .tempdir()
            .expect("a temporary folder"),
    )
}

/// A run id of this process's own: two test runs or benchmarks on one machine at
/// once (two clones, two CI jobs) must not open each other's shared memory.
pub fn run_id(name: &str) -> String {
    format!("{name}-{}", std::process::id())
}

/// A JSON file a run recorded into `out`.
pub fn recorded_json(out: &Path, file: &str) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join(file)).unwrap()).unwrap()
}

impl Deref for OutDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for OutDir {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<OsStr> for OutDir {
    fn as_ref(&self) -> &OsStr {
        self.0.path().as_os_str()
    }
}
