//! Files named by string parameters (a scene, parameter files): a relative name is
//! looked up in the unpacked FMU's `resources/` folder first (what `plamo fmu build
//! --resource` ships), then taken as a path.

use std::path::PathBuf;

use plamo::spec::{ControllerParams, ParamFiles, load_physics_settings, load_planner_settings};
use plamo_planner::PlannerSettings;
use plamo_scenes::Scene;

use crate::instance::{ModelContext, Value};
use crate::spec::{ModelSpec, VarType, Variable};

/// The `scene` parameter: a file in the FMU's resources, a built-in name, or a path.
pub fn resolve_scene(name: &str, ctx: &ModelContext) -> Result<Scene, String> {
    if let Some(dir) = &ctx.resources {
        let candidate = dir.join(name);
        if candidate.is_file() {
            return plamo_scenes::load(&candidate).map_err(|e| format!("parameter `scene`: {e}"));
        }
    }
    plamo_scenes::resolve(name).map_err(|e| format!("parameter `scene`: {e}"))
}

/// The value of the String variable `name` (empty when there is none).
pub(crate) fn text(values: &[Value], spec: &ModelSpec, name: &str) -> String {
    match spec.vr(name).map(|vr| &values[vr as usize]) {
        Some(Value::String(s)) => s.to_string_lossy().into_owned(),
        _ => String::new(),
    }
}

/// A parameter file the FMUs take, as a String parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ParamFile {
    /// Planner settings (a TOML table of `PlannerSettings` fields).
    Planner,
    /// Biped gait parameters (the `gait.toml` layout, e.g. from `plamo tune`).
    Gait,
    /// Crawl parameters (the `crawl.toml` layout).
    Crawl,
    /// Physics settings (a TOML table of `PhysicsSettings` fields).
    Physics,
}

impl ParamFile {
    /// The parameter's name in the model description.
    pub(crate) fn parameter(self) -> &'static str {
        match self {
            Self::Planner => "planner_params",
            Self::Gait => "gait_params",
            Self::Crawl => "crawl_params",
            Self::Physics => "physics_params",
        }
    }

    /// The parameter's entry in the variable table (start: empty, the built-in values).
    pub(crate) fn variable(self) -> Variable {
        let what = match self {
            Self::Planner => {
                "planner parameter file: a TOML table of planner settings, the fields it leaves out keep their defaults (as `plamo run --planner-params`)"
            }
            Self::Gait => {
                "biped gait parameter file, the gait.toml layout with every field (as `plamo run --gait-params`, e.g. from `plamo tune`)"
            }
            Self::Crawl => {
                "crawl parameter file, the crawl.toml layout with every field (as `plamo run --crawl-params`)"
            }
            Self::Physics => {
                "physics parameter file: a TOML table of physics settings (friction, solver iterations, contact stiffness), the fields it leaves out keep their defaults (as `plamo run --physics-params`)"
            }
        };
        Variable::parameter(
            self.parameter(),
            VarType::String,
            "",
            format!(
                "{what}; empty: the built-in parameters. A relative path is looked up in the FMU's resources/ first"
            ),
        )
    }

    /// The file this parameter names in `values`, checked to exist (`None`: empty,
    /// the built-in parameters). The error names the parameter.
    fn path(
        self,
        values: &[Value],
        spec: &ModelSpec,
        ctx: &ModelContext,
    ) -> Result<Option<PathBuf>, String> {
        let name = text(values, spec, self.parameter());
        if name.is_empty() {
            return Ok(None);
        }
        let shipped = ctx.resources.as_ref().map(|dir| dir.join(&name));
        if let Some(p) = shipped.filter(|p| p.is_file()) {
            return Ok(Some(p));
        }
        let given = PathBuf::from(&name);
        if given.is_file() {
            return std::path::absolute(&given)
                .map(Some)
                .map_err(|e| format!("parameter `{}` = {name:?}: {e}", self.parameter()));
        }
        let looked = match &ctx.resources {
            Some(dir) => format!(
                "neither in the FMU's resources ({}) nor at that path",
                dir.display()
            ),
            None => "no such file (and the host gave no resources folder)".to_string(),
        };
        Err(format!(
            "parameter `{}` = {name:?}: {looked}; leave it empty for the built-in parameters",
            self.parameter()
        ))
    }
}

/// The parameter files named in `values` (those of `which`; the others built in),
/// each read and checked now, so a typo fails initialisation with the parameter's
/// and the field's name rather than a component later.
pub(crate) fn param_files(
    which: &[ParamFile],
    values: &[Value],
    spec: &ModelSpec,
    ctx: &ModelContext,
) -> Result<ParamFiles, String> {
    let mut files = ParamFiles::default();
    for &kind in which {
        let Some(path) = kind.path(values, spec, ctx)? else {
            continue;
        };
        let named = |e: String| format!("parameter `{}`: {e}", kind.parameter());
        match kind {
            ParamFile::Planner => {
                load_planner_settings(&path).map_err(named)?;
                files.planner = Some(path);
            }
            ParamFile::Gait => {
                ControllerParams::load(Some(&path), None).map_err(named)?;
                files.gait = Some(path);
            }
            ParamFile::Crawl => {
                ControllerParams::load(None, Some(&path)).map_err(named)?;
                files.crawl = Some(path);
            }
            ParamFile::Physics => {
                load_physics_settings(&path).map_err(named)?;
                files.physics = Some(path);
            }
        }
    }
    Ok(files)
}

/// The planner settings of `files` (the built-in ones without a planner file).
pub(crate) fn planner_settings(files: &ParamFiles) -> Result<PlannerSettings, String> {
    files
        .planner
        .as_deref()
        .map_or(Ok(PlannerSettings::default()), |p| {
            load_planner_settings(p).map_err(|e| format!("parameter `planner_params`: {e}"))
        })
}
