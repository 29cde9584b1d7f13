//! `plamo component planner|controller|physics --run ID [--agent K] ...`: serve one
//! component over iceoryx2 for a multi-process run. `plamo run --processes` starts
//! these itself; with `--attach` it prints the commands and waits for someone to
//! start them (another terminal, a debugger, a profiler).

use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use iceoryx2::prelude::*;
use plamo_interfaces::{
    Component, ComponentError, ComponentKind, Outcome, PHYSICS_STEP, PhysicsInput, PhysicsOutput,
    RunId, ServiceNames, Tick,
};
use plamo_physics::PhysicsComponent;

use plamo::ipc::{IpcError, IpcSettings, end_run, remove_stale_resources, run_config, serve};
use plamo::processes::node_name;

use super::run::SpecArgs;

/// Arguments of `plamo component`.
#[derive(Debug, Args)]
pub struct ComponentArgs {
    /// Which component: planner, controller or physics.
    kind: ComponentKind,
    /// The run to join (its services live under this id).
    #[arg(long)]
    run: String,
    /// Agent index (planner and controller).
    #[arg(long, default_value_t = 0)]
    agent: u32,
    /// The run's scene, instructions, backend and seed.
    #[command(flatten)]
    spec: SpecArgs,
    /// Fault injection for reliability tests: `crash@TICK` aborts the process when
    /// asked for TICK, `wrong-tick@TICK` answers TICK with another tick (physics only).
    #[arg(long, hide = true)]
    fault: Option<String>,
}

/// A deliberately broken physics component (reliability tests only).
struct Faulty {
    inner: PhysicsComponent,
    crash_at: Option<u64>,
    wrong_tick_at: Option<u64>,
}

impl Component for Faulty {
    type Input = PhysicsInput;
    type Output = PhysicsOutput;
    const NAME: &'static str = "physics";
    fn step(
        &mut self,
        tick: Tick,
        input: &PhysicsInput,
        output: &mut PhysicsOutput,
    ) -> Result<Outcome, ComponentError> {
        if self.crash_at == Some(tick.0) && input.mode == PHYSICS_STEP {
            std::process::abort();
        }
        let r = self.inner.step(tick, input, output);
        if self.wrong_tick_at == Some(tick.0) && input.mode == PHYSICS_STEP {
            output.tick += 4;
        }
        r
    }
}

fn parse_fault(f: &str) -> anyhow::Result<(&str, u64)> {
    let (what, tick) = f
        .split_once('@')
        .context("--fault expects crash@TICK or wrong-tick@TICK")?;
    Ok((what, tick.parse().context("--fault tick")?))
}

fn serve_one<C>(
    c: &mut C,
    node: &Node<ipc::Service>,
    names: &ServiceNames,
    settings: &IpcSettings,
    identity: &str,
) -> Result<u64, IpcError>
where
    C: Component,
    C::Input: ZeroCopySend + Copy + std::fmt::Debug + Default + 'static,
    C::Output: ZeroCopySend + Copy + std::fmt::Debug + Default + 'static,
{
    serve(c, node, names, settings, identity)
}

/// Run `plamo component`.
pub fn run(args: ComponentArgs) -> anyhow::Result<ExitCode> {
    let run = RunId::new(&args.run).map_err(anyhow::Error::msg)?;
    let spec = args.spec.to_spec()?;
    let scene = spec.load_scene()?;
    let k = args.agent as usize;
    if args.kind != ComponentKind::Physics && k >= spec.agents() {
        anyhow::bail!("--agent {k}: the run has {} agent(s)", spec.agents());
    }
    let cfg = run_config(&run)?;
    let node = NodeBuilder::new()
        .name(
            &NodeName::new(&node_name(args.kind, args.agent))
                .map_err(|e| anyhow::anyhow!("{e:?}"))?,
        )
        .config(&cfg)
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("creating the component's node: {e:?}"))?;
    let names = ServiceNames::new(&run, args.kind, args.agent);
    let identity = spec.identity();
    let settings = &IpcSettings::default();
    let served = match args.kind {
        ComponentKind::Physics => {
            let inner = spec.physics(&scene)?;
            let (mut crash_at, mut wrong_tick_at) = (None, None);
            if let Some(f) = &args.fault {
                match parse_fault(f)? {
                    ("crash", t) => crash_at = Some(t),
                    ("wrong-tick", t) => wrong_tick_at = Some(t),
                    (other, _) => anyhow::bail!("unknown fault `{other}`"),
                }
            }
            serve_one(
                &mut Faulty {
                    inner,
                    crash_at,
                    wrong_tick_at,
                },
                &node,
                &names,
                settings,
                &identity,
            )
        }
        ComponentKind::Planner => serve_one(
            &mut spec.planner(&scene, k)?,
            &node,
            &names,
            settings,
            &identity,
        ),
        ComponentKind::Controller => serve_one(
            &mut spec.controller(&scene, k)?,
            &node,
            &names,
            settings,
            &identity,
        ),
    };
    drop(node);
    match served {
        Ok(_) => {
            // The last one out of a run whose orchestrator did not start it (attached
            // by hand) removes the run's last file.
            let _ = end_run(&cfg);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            // The orchestrator is gone: tidy what it left; the last one out removes
            // the run's last file.
            remove_stale_resources(&cfg);
            let _ = end_run(&cfg);
            Err(anyhow::Error::new(e).context(format!("{} {}", args.kind, args.agent)))
        }
    }
}
