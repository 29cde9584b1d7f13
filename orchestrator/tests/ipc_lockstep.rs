//! The iceoryx2 transport, exercised with real shared memory between two nodes (one
//! per thread, as between processes): lockstep round trips, tick checks, component
//! errors, and isolation of concurrent runs.

mod support;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;

use iceoryx2::prelude::*;
use plamo::ipc::{IpcError, IpcSettings, RemoteComponent, end_run, run_config, serve};
use plamo_interfaces::{
    Component, ComponentError, ComponentKind, Outcome, RunId, ServiceNames, Tick,
};
use support::run_id;

/// A component whose output depends on its whole input history, so a lost, repeated
/// or reordered message changes the result.
#[derive(Default)]
struct Accumulator {
    sum: u64,
}

impl Component for Accumulator {
    type Input = u64;
    type Output = u64;
    const NAME: &'static str = "accumulator";

    fn step(
        &mut self,
        tick: Tick,
        input: &u64,
        output: &mut u64,
    ) -> Result<Outcome, ComponentError> {
        if *input == 666 {
            return Err(ComponentError::InvalidInput {
                component: Self::NAME,
                field: "value",
                reason: "666 is not allowed".into(),
            });
        }
        self.sum = self.sum.wrapping_mul(31).wrapping_add(*input ^ tick.0);
        *output = self.sum;
        Ok(Outcome::Continue)
    }
}

fn node(cfg: &Config, name: &str) -> Node<ipc::Service> {
    NodeBuilder::new()
        .name(&NodeName::new(name).unwrap())
        .config(cfg)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .unwrap()
}

/// A client, its server thread, the orchestrator's node, and the "server ended" flag.
type Started = (
    RemoteComponent<u64, u64>,
    thread::JoinHandle<Result<u64, IpcError>>,
    Node<ipc::Service>,
    Arc<AtomicBool>,
);

/// What the test server says it was built for.
const IDENTITY: &str = "accumulator for the ipc tests";

/// Start a server thread for `run` and return a connected client and the thread.
fn start(run: &str) -> Started {
    start_as(run, IDENTITY)
}

/// [`start`] with a server announcing `identity`.
fn start_as(run: &str, identity: &'static str) -> Started {
    let run = RunId::new(run).unwrap();
    let cfg = run_config(&run).unwrap();
    let names = ServiceNames::new(&run, ComponentKind::Controller, 0);
    let orch = node(&cfg, "plamo-orchestrator");
    let done = Arc::new(AtomicBool::new(false));
    let done_flag = done.clone();
    let client = RemoteComponent::<u64, u64>::open(
        &orch,
        "accumulator",
        &names,
        IpcSettings::default(),
        Box::new(move || {
            done_flag
                .load(Ordering::SeqCst)
                .then(|| "server thread ended".to_string())
        }),
    )
    .unwrap();
    let server_names = names.clone();
    let server_cfg = cfg.clone();
    let done_server = done.clone();
    let handle = thread::spawn(move || {
        let n = node(&server_cfg, "plamo-controller-0");
        let r = serve(
            &mut Accumulator::default(),
            &n,
            &server_names,
            &IpcSettings::default(),
            identity,
        );
        done_server.store(true, Ordering::SeqCst);
        r
    });
    (client, handle, orch, done)
}

#[test]
fn lockstep_round_trips_match_in_process_steps() {
    let run = run_id("ipc-test-lockstep");
    let (mut client, handle, _orch, _) = start(&run);
    client.wait_ready(IDENTITY).unwrap();
    let mut local = Accumulator::default();
    for tick in (0..400u64).step_by(4) {
        let input = tick * 7 + 3;
        let remote = client.call(tick, &input).unwrap();
        let mut expected = 0;
        local.step(Tick(tick), &input, &mut expected).unwrap();
        assert_eq!(remote, expected, "tick {tick}");
    }
    client.shutdown().unwrap();
    assert_eq!(handle.join().unwrap().unwrap(), 100);
    end(&run, client, _orch);
}

/// Close the orchestrator side, end the run, and check nothing of it is left on disk.
fn end(run: &str, client: RemoteComponent<u64, u64>, orch: Node<ipc::Service>) {
    drop(client);
    drop(orch);
    let cfg = run_config(&RunId::new(run).unwrap()).unwrap();
    end_run(&cfg).unwrap();
    assert_eq!(files_of(run), Vec::<std::path::PathBuf>::new());
}

/// Files of run `run` left in iceoryx2's shared-memory and runtime directories.
fn files_of(run: &str) -> Vec<std::path::PathBuf> {
    plamo::ipc::run_files(&RunId::new(run).unwrap())
}

#[test]
fn component_errors_come_back_with_their_message() {
    let run = run_id("ipc-test-errors");
    let (mut client, handle, _orch, _) = start(&run);
    client.wait_ready(IDENTITY).unwrap();
    client.call(0, &1).unwrap();
    let err = client.call(4, &666).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, IpcError::Component { tick: 4, .. }), "{text}");
    assert!(
        text.contains("666 is not allowed") && text.contains("accumulator"),
        "{text}"
    );
    // The component keeps serving after reporting an error.
    client.call(8, &2).unwrap();
    client.shutdown().unwrap();
    handle.join().unwrap().unwrap();
    end(&run, client, _orch);
}

#[test]
fn concurrent_runs_with_the_same_service_names_are_isolated() {
    let run_a = run_id("ipc-test-iso-a");
    let run_b = run_id("ipc-test-iso-b");
    let (mut a, ha, oa, _) = start(&run_a);
    let (mut b, hb, ob, _) = start(&run_b);
    a.wait_ready(IDENTITY).unwrap();
    b.wait_ready(IDENTITY).unwrap();
    for tick in (0..80u64).step_by(4) {
        let ra = a.call(tick, &1).unwrap();
        let rb = b.call(tick, &2).unwrap();
        assert_ne!(ra, rb);
    }
    a.shutdown().unwrap();
    b.shutdown().unwrap();
    assert_eq!(ha.join().unwrap().unwrap(), 20);
    assert_eq!(hb.join().unwrap().unwrap(), 20);
    end(&run_a, a, oa);
    end(&run_b, b, ob);
}

#[test]
fn a_dead_peer_is_reported_instead_of_waiting_forever() {
    let run = run_id("ipc-test-dead");
    let (mut client, handle, _orch, _) = start(&run);
    client.wait_ready(IDENTITY).unwrap();
    client.call(0, &1).unwrap();
    client.shutdown().unwrap();
    handle.join().unwrap().unwrap();
    let err = client.call(4, &1).unwrap_err();
    assert!(matches!(err, IpcError::PeerDied { tick: 4, .. }), "{err}");
    assert!(err.to_string().contains("accumulator"));
    end(&run, client, _orch);
}

#[test]
fn a_component_exits_when_its_orchestrator_is_gone() {
    let run = run_id("ipc-test-orphan");
    let (client, handle, orch, _) = start(&run);
    drop(client);
    drop(orch);
    let err = handle.join().unwrap().unwrap_err();
    assert!(matches!(err, IpcError::PeerDied { .. }), "{err}");
    let cfg = run_config(&RunId::new(&run).unwrap()).unwrap();
    end_run(&cfg).unwrap();
    assert_eq!(files_of(&run), Vec::<std::path::PathBuf>::new());
}

#[test]
fn a_component_built_for_another_run_is_refused() {
    let run = run_id("ipc-test-mismatch");
    let (mut client, handle, orch, _) = start_as(&run, "scene pyramid, seed 9");
    let err = client.wait_ready(IDENTITY).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, IpcError::Mismatch { .. }), "{text}");
    assert!(
        text.contains("scene pyramid, seed 9") && text.contains(IDENTITY),
        "{text}"
    );
    client.shutdown().unwrap();
    handle.join().unwrap().unwrap();
    end(&run, client, orch);
}
