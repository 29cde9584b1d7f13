//! `plamo fmu build`: package the FMU library into `.fmu` archives.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};
use plamo::fmu_package::{find_library, package_all};

/// FMU subcommands.
#[derive(Debug, Subcommand)]
pub enum FmuCommand {
    /// Write `plamo.fmu` (the whole humanoid) and `plamo-planner.fmu` (the planner
    /// alone), every FMU the library serves, into a folder.
    Build(BuildArgs),
}

/// Arguments of `plamo fmu build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Output folder.
    #[arg(long, default_value = "out/fmu")]
    out: PathBuf,
    /// The FMU shared library (default: libplamo_fmu.so next to this executable).
    #[arg(long)]
    library: Option<PathBuf>,
    /// Files to ship in the FMUs' resources/ folder (scene files named by the `scene`
    /// parameter with a relative path).
    #[arg(long = "resource")]
    resources: Vec<PathBuf>,
}

/// Run an FMU subcommand.
pub fn run(cmd: FmuCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        FmuCommand::Build(args) => {
            let library = match args.library {
                Some(l) => l,
                None => find_library()?,
            };
            for fmu in package_all(&library, &args.out, &args.resources)? {
                say!(
                    "wrote {} ({}, GUID {})",
                    fmu.path.display(),
                    fmu.model_name,
                    fmu.guid
                );
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}
