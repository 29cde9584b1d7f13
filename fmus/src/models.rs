//! The models this binary serves, chosen by GUID in fmi2Instantiate: one shared
//! library can stand behind several FMUs.

use std::sync::OnceLock;

use crate::instance::ModelFactory;
use crate::spec::ModelSpec;
use crate::{humanoid_model, planner_model};

/// The planner-only FMU's description.
pub fn planner_spec() -> &'static ModelSpec {
    static SPEC: OnceLock<ModelSpec> = OnceLock::new();
    SPEC.get_or_init(planner_model::spec)
}

/// Builds the planner-only model.
pub fn planner_factory(
    spec: &ModelSpec,
    ctx: &crate::instance::ModelContext,
    values: &[crate::instance::Value],
) -> Result<Box<dyn crate::instance::Model>, String> {
    planner_model::build(spec, ctx, values)
}

/// The humanoid FMU's description.
pub fn humanoid_spec() -> &'static ModelSpec {
    static SPEC: OnceLock<ModelSpec> = OnceLock::new();
    SPEC.get_or_init(humanoid_model::spec)
}

/// Builds the humanoid model (the whole lockstep run).
pub fn humanoid_factory(
    spec: &ModelSpec,
    ctx: &crate::instance::ModelContext,
    values: &[crate::instance::Value],
) -> Result<Box<dyn crate::instance::Model>, String> {
    humanoid_model::build(spec, ctx, values)
}

/// Every (description, factory) this binary serves.
pub fn all() -> Vec<(&'static ModelSpec, ModelFactory)> {
    vec![
        (planner_spec(), planner_factory as ModelFactory),
        (humanoid_spec(), humanoid_factory as ModelFactory),
    ]
}

/// The model with this GUID.
pub fn by_guid(guid: &str) -> Option<(&'static ModelSpec, ModelFactory)> {
    all().into_iter().find(|(s, _)| s.guid == guid)
}

/// GUIDs this binary accepts.
pub fn guids() -> Vec<&'static str> {
    all().iter().map(|(s, _)| s.guid).collect()
}
