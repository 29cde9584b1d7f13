//! Subcommands, one file each.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// `println!` for what a command reports on stdout. A reader that goes away
/// (`plamo run ... | head -1`) ends the report, not the command: `println!` panicked
/// there, before a run wrote its output folder and shut its components down.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::cli::say_line(format_args!($($arg)*))
    };
}

mod component;
mod eval;
mod export;
mod fmu;
mod plan;
mod run;
mod scenes;
mod tune;
mod view;

/// PlaMo: plan and move a physics-simulated humanoid through rich 3D scenes.
#[derive(Debug, Parser)]
#[command(name = "plamo", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List, show, validate, render and generate scenes.
    #[command(subcommand)]
    Scenes(scenes::ScenesCommand),
    /// Plan a route on a scene and write the plan (JSON), a map and a profile plot.
    Plan(plan::PlanArgs),
    /// Run planner, controller and physics in lockstep: the humanoid carries out the
    /// instructions; a summary per instruction follows.
    Run(run::RunArgs),
    /// Serve one component of a multi-process run over iceoryx2 (`plamo run
    /// --processes` starts these; with `--attach` you start them yourself).
    Component(component::ComponentArgs),
    /// Tune the model-based gait's parameters by CMA-ES over rollouts.
    Tune(tune::TuneArgs),
    /// Evaluate: the controller (paper Table 2) and the paper's experiments.
    #[command(subcommand)]
    Eval(eval::EvalCommand),
    /// Build the FMI 2.0 co-simulation FMUs.
    #[command(subcommand)]
    Fmu(fmu::FmuCommand),
    /// Write replay.glb (glTF 2.0), motion.bvh and replay.mcap for a recorded run.
    Export(export::ExportArgs),
    /// Write (and open) the HTML replay viewer for recorded runs.
    View(view::ViewArgs),
}

/// Run the parsed command; the exit code says whether it succeeded.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Scenes(cmd) => scenes::run(cmd),
        Command::Plan(args) => plan::run(args),
        Command::Run(args) => run::run(args),
        Command::Component(args) => component::run(args),
        Command::Tune(args) => tune::run(args),
        Command::Eval(cmd) => eval::run(cmd),
        Command::Fmu(cmd) => fmu::run(cmd),
        Command::Export(args) => export::run(args),
        Command::View(args) => view::run(args),
    }
}

/// Writes one line of a command's report to stdout (see `say!`). A closed pipe is
/// not an error; any other write error is told on stderr once per line, and the
/// command goes on with what it was doing.
pub(crate) fn say_line(line: std::fmt::Arguments) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = writeln!(out, "{line}").and_then(|()| out.flush())
        && e.kind() != std::io::ErrorKind::BrokenPipe
    {
        eprintln!("warning: could not write to stdout: {e}");
    }
}
