//! `plamo export DIR`: write `replay.glb`, `motion.bvh` and `replay.mcap` for a
//! recorded run (what `plamo run --out DIR` writes itself), e.g. for recordings made
//! before the exporters existed.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

/// Arguments of `plamo export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Recording directory (`plamo run --out DIR`).
    dir: PathBuf,
}

/// Run `plamo export`.
pub fn run(args: ExportArgs) -> anyhow::Result<ExitCode> {
    for p in plamo::export::export_dir(&args.dir)? {
        say!("wrote {}", p.display());
    }
    Ok(ExitCode::SUCCESS)
}
