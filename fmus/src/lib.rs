//! PlaMo as FMI 2.0 co-simulation FMUs.
//!
//! One shared library serves every FMU of the project; fmi2Instantiate picks the
//! model by GUID. `plamo.fmu` runs the whole humanoid (planner, controller and
//! physics in the orchestrator's lockstep); `plamo-planner.fmu` wraps the planner alone. The variable table of
//! each model ([`spec::ModelSpec`]) is the single source of its `modelDescription.xml`
//! and of the get/set dispatch, and the library can describe itself
//! ([`plamo_fmu_model_description`]) so the packager writes exactly what the binary
//! implements.
#![warn(missing_docs)]

/// The FMI 2.0 C entry points (public so a test binary can call them in-process
/// under a counting allocator; hosts reach them as C symbols).
#[doc(hidden)]
#[allow(missing_docs)]
pub mod ffi;
pub mod humanoid_model;
pub mod instance;
pub mod models;
mod planner_model;
pub mod resources;
pub mod spec;

use std::ffi::{CString, c_char};
use std::sync::OnceLock;

pub use humanoid_model::GUID as HUMANOID_GUID;
pub use planner_model::GUID as PLANNER_GUID;
pub use resources::resolve_scene;

/// The model description of the FMU at `index` (0 = planner, 1 = humanoid), or null past the end.
/// Not part of FMI: the packager calls it to write `modelDescription.xml`. The text
/// lives as long as the library.
#[unsafe(no_mangle)]
pub extern "C" fn plamo_fmu_model_description(index: u32) -> *const c_char {
    static TEXTS: OnceLock<Vec<CString>> = OnceLock::new();
    let texts = TEXTS.get_or_init(|| {
        models::all()
            .iter()
            .map(|(s, _)| CString::new(s.model_description_xml()).unwrap_or_default())
            .collect()
    });
    texts
        .get(index as usize)
        .map_or(std::ptr::null(), |t| t.as_ptr())
}
