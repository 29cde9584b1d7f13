//! `plamo scenes ...`

use clap::Subcommand;
use std::process::ExitCode;

/// Scene subcommands.
#[derive(Debug, Subcommand)]
pub enum ScenesCommand {
    /// List the built-in scenes.
    List,
}

/// Run a scene subcommand.
pub fn run(cmd: ScenesCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        ScenesCommand::List => Ok(ExitCode::SUCCESS),
    }
}
