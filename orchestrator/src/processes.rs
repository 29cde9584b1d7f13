//! Multi-process runs: the orchestrator spawns one `plamo component ...` process per
//! component instance, talks to each through an iceoryx2 [`RemoteComponent`], and
//! cleans up whatever happens: a component that dies is noticed within a wait slice
//! (its process exited, or its node is listed dead), the others are told to stop,
//! stragglers are killed, and the run's shared-memory files are removed.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use plamo_interfaces::{ComponentKind, RunId, ServiceNames};

use crate::ipc::{
    CorePin, IpcError, IpcSettings, RemoteComponent, StaleRun, clean_stale_runs, dead_nodes,
    end_run, run_config,
};
use crate::lockstep::{Link, Links, RunError};
use crate::spec::RunSpec;

/// The orchestrator's iceoryx2 node name (components exit when it is gone).
pub const ORCHESTRATOR_NODE: &str = crate::ipc::ORCHESTRATOR_NODE;

/// A run with files but no node yet is younger than this is taken to be starting up,
/// not stale.
const STARTUP_GRACE: Duration = Duration::from_secs(10);

/// How long stopped components get to exit before they are killed.
const EXIT_GRACE: Duration = Duration::from_secs(2);

/// The iceoryx2 node name of a component instance.
pub fn node_name(kind: ComponentKind, agent: u32) -> String {
    match kind {
        ComponentKind::Physics => "plamo-physics".to_string(),
        _ => format!("plamo-{kind}-{agent}"),
    }
}

/// A component instance's name in errors and reports (`physics`, `planner-0`).
fn label(kind: ComponentKind, agent: u32) -> String {
    match kind {
        ComponentKind::Physics => "physics".to_string(),
        _ => format!("{kind}-{agent}"),
    }
}

/// The component processes of one run and the orchestrator's side of their links.
pub struct ProcessRun {
    cfg: Config,
    node: Option<Node<ipc::Service>>,
    children: Vec<(String, Arc<Mutex<Option<Child>>>)>,
    /// The orchestrator thread's core pin, which the spawned components inherit;
    /// held for the run (so drop the run on the thread that started it).
    _pin: CorePin,
    /// Runs that had crashed earlier (any run id) whose files were removed at start.
    pub cleaned: Vec<StaleRun>,
}

type Slot = Arc<Mutex<Option<Child>>>;

fn ipc_setup(what: &str) -> impl FnOnce(IpcError) -> RunError + '_ {
    move |e| RunError::Setup(format!("{what}: {e}"))
}

/// The `plamo component ...` arguments of every component instance of a run, in
/// start order (physics, then each agent's planner and controller).
pub fn component_args(spec: &RunSpec, run: &RunId) -> Vec<(ComponentKind, u32, Vec<String>)> {
    let mut order = vec![(ComponentKind::Physics, 0)];
    for k in 0..spec.agents() as u32 {
        order.push((ComponentKind::Planner, k));
        order.push((ComponentKind::Controller, k));
    }
    order
        .into_iter()
        .map(|(kind, agent)| {
            let mut args = vec![
                "component".to_string(),
                kind.as_str().to_string(),
                "--run".into(),
                run.as_str().to_string(),
                "--agent".into(),
                agent.to_string(),
            ];
            args.extend(spec.to_args());
            (kind, agent, args)
        })
        .collect()
}

/// How the component processes come to be.
#[derive(Debug, Clone, Copy)]
pub enum Launch<'a> {
    /// The orchestrator spawns them from this executable; `physics_fault` is passed
    /// to the physics process as `--fault` (reliability tests only).
    Spawn {
        /// The `plamo` executable.
        exe: &'a Path,
        /// `crash@TICK` or `wrong-tick@TICK`.
        physics_fault: Option<&'a str>,
    },
    /// Someone starts them by hand (`plamo component ...`, see [`component_args`]),
    /// on this machine, within the ready timeout.
    Attach,
}

impl ProcessRun {
    /// Start every component of `spec` as a child process of `exe` under run `run`,
    /// and wait until each has said it is ready. `physics_fault` is passed to the
    /// physics process as `--fault` (reliability tests only).
    pub fn start(
        spec: &RunSpec,
        run: &RunId,
        exe: &Path,
        settings: IpcSettings,
        physics_fault: Option<&str>,
    ) -> Result<(Self, Links), RunError> {
        Self::launch(spec, run, Launch::Spawn { exe, physics_fault }, settings)
    }

    /// Open the run's links, start (or wait for) its component processes, and wait
    /// until each has said it is ready for this very spec.
    pub fn launch(
        spec: &RunSpec,
        run: &RunId,
        launch: Launch<'_>,
        settings: IpcSettings,
    ) -> Result<(Self, Links), RunError> {
        let pin = CorePin::here(settings.one_core);
        let cfg = run_config(run)?;
        // Crashed earlier runs (this id or any other) may have left files behind.
        let cleaned = clean_stale_runs(STARTUP_GRACE);
        let node = NodeBuilder::new()
            .name(&NodeName::new(ORCHESTRATOR_NODE).map_err(|e| RunError::Setup(format!("{e:?}")))?)
            .config(&cfg)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| RunError::Setup(format!("orchestrator node: {e:?}")))?;
        let mut this = Self {
            cfg,
            node: None,
            children: Vec::new(),
            _pin: pin,
            cleaned,
        };
        let result = this.spawn_all(&node, spec, run, launch, settings);
        this.node = Some(node);
        match result {
            Ok(links) => Ok((this, links)),
            Err(e) => {
                this.finish(None);
                Err(e)
            }
        }
    }

    /// A new, empty process slot for component `kind`/`agent`, watched by
    /// [`ProcessRun::finish`].
    fn slot(&mut self, (kind, agent): (ComponentKind, u32)) -> Slot {
        let slot: Slot = Arc::new(Mutex::new(None));
        self.children.push((label(kind, agent), slot.clone()));
        slot
    }

    /// The orchestrator's link to component `kind`/`agent`, whose process (if this
    /// run spawned it) is in `slot`.
    fn open<I, O>(
        &self,
        node: &Node<ipc::Service>,
        run: &RunId,
        (kind, agent): (ComponentKind, u32),
        slot: &Slot,
        settings: IpcSettings,
    ) -> Result<RemoteComponent<I, O>, RunError>
    where
        I: ZeroCopySend + Copy + std::fmt::Debug + Default + 'static,
        O: ZeroCopySend + Copy + std::fmt::Debug + Default + 'static,
    {
        let watched = slot.clone();
        let cfg = self.cfg.clone();
        let node_name = node_name(kind, agent);
        let liveness = Box::new(move || {
            if let Ok(mut guard) = watched.lock()
                && let Some(child) = guard.as_mut()
                && let Ok(Some(status)) = child.try_wait()
            {
                return Some(format!("its process (pid {}) exited: {status}", child.id()));
            }
            dead_nodes(&cfg)
                .iter()
                .any(|n| n.0 == node_name)
                .then(|| format!("its node `{node_name}` is dead"))
        });
        let names = ServiceNames::new(run, kind, agent);
        RemoteComponent::open(node, label(kind, agent), &names, settings, liveness)
            .map_err(ipc_setup("opening a component link"))
    }

    fn spawn_all(
        &mut self,
        node: &Node<ipc::Service>,
        spec: &RunSpec,
        run: &RunId,
        launch: Launch<'_>,
        settings: IpcSettings,
    ) -> Result<Links, RunError> {
        let all_args = component_args(spec, run);
        let spawn = |(kind, agent): (ComponentKind, u32), slot: &Slot| -> Result<(), RunError> {
            let Launch::Spawn { exe, physics_fault } = launch else {
                return Ok(());
            };
            let args = all_args
                .iter()
                .find(|(k, a, _)| *k == kind && *a == agent)
                .map(|(_, _, args)| args.clone())
                .unwrap_or_default();
            let mut cmd = Command::new(exe);
            cmd.args(args)
                .args(
                    physics_fault
                        .filter(|_| kind == ComponentKind::Physics)
                        .map(|f| ["--fault".to_string(), f.to_string()])
                        .into_iter()
                        .flatten(),
                )
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::inherit());
            let child = cmd.spawn().map_err(|e| {
                RunError::Setup(format!(
                    "starting `{} component {kind}`: {e}",
                    exe.display()
                ))
            })?;
            *slot.lock().expect("child slot") = Some(child);
            Ok(())
        };
        // Each link is opened before its process starts, so the process finds the
        // services made (two processes creating one service at once cost the loser a
        // 25 ms back-off in iceoryx2). The planners start first: planning the route is
        // the longest start-up, and it overlaps the other links' set-up.
        let agents = 0..spec.agents() as u32;
        let mut planners = Vec::new();
        for k in agents.clone() {
            let id = (ComponentKind::Planner, k);
            let slot = self.slot(id);
            planners.push(self.open(node, run, id, &slot, settings)?);
            spawn(id, &slot)?;
        }
        let id = (ComponentKind::Physics, 0);
        let slot = self.slot(id);
        let mut physics = self.open(node, run, id, &slot, settings)?;
        spawn(id, &slot)?;
        let mut controllers = Vec::new();
        for k in agents {
            let id = (ComponentKind::Controller, k);
            let slot = self.slot(id);
            controllers.push(self.open(node, run, id, &slot, settings)?);
            spawn(id, &slot)?;
        }
        let identity = spec.identity();
        physics.wait_ready(&identity)?;
        for p in &mut planners {
            p.wait_ready(&identity)?;
        }
        for c in &mut controllers {
            c.wait_ready(&identity)?;
        }
        Ok(Links {
            physics: Box::new(physics),
            planners: planners
                .into_iter()
                .map(|p| Box::new(p) as Box<dyn Link<_, _>>)
                .collect(),
            controllers: controllers
                .into_iter()
                .map(|c| Box::new(c) as Box<dyn Link<_, _>>)
                .collect(),
        })
    }

    /// The run's iceoryx2 configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// Process ids of the component processes, by instance name.
    pub fn pids(&self) -> Vec<(String, u32)> {
        self.children
            .iter()
            .filter_map(|(n, s)| s.lock().ok()?.as_ref().map(|c| (n.clone(), c.id())))
            .collect()
    }

    /// Component nodes of this run that are alive (the orchestrator's excluded).
    fn live_components(&self) -> usize {
        let mut live = 0;
        let _ = Node::<ipc::Service>::list(&self.cfg, |state| {
            if let NodeState::Alive(view) = &state
                && view
                    .details()
                    .as_ref()
                    .is_some_and(|d| d.name().as_str() != ORCHESTRATOR_NODE)
            {
                live += 1;
            }
            CallbackProgression::Continue
        });
        live
    }

    /// Stop every component (politely, then by force), close the links, and remove
    /// the run's files. Returns the instances that had to be killed.
    pub fn finish(mut self, links: Option<Links>) -> Vec<String> {
        if let Some(mut links) = links {
            links.physics.shutdown();
            for p in &mut links.planners {
                p.shutdown();
            }
            for c in &mut links.controllers {
                c.shutdown();
            }
            drop(links);
        }
        let deadline = Instant::now() + EXIT_GRACE;
        let mut killed = Vec::new();
        for (name, slot) in &self.children {
            let Ok(mut guard) = slot.lock() else { continue };
            let Some(child) = guard.as_mut() else {
                continue;
            };
            loop {
                match child.try_wait() {
                    Ok(Some(_)) => break,
                    Ok(None) if Instant::now() < deadline => {
                        std::thread::sleep(Duration::from_millis(1))
                    }
                    _ => {
                        let _ = child.kill();
                        let _ = child.wait();
                        killed.push(name.clone());
                        break;
                    }
                }
            }
        }
        // Components attached by hand are nobody's children: give them the same
        // grace to exit, watching their nodes instead of their processes.
        while Instant::now() < deadline && self.live_components() > 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
        drop(self.node.take());
        // Every node of the run is gone now; the last file can go.
        let _ = end_run(&self.cfg);
        killed
    }
}
