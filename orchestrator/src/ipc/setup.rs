//! Per-run configuration and the four ports one side of a component link holds.

use std::fmt::Debug;
use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use plamo_interfaces::RunId;

use super::envelope::{Envelope, EnvelopeKind};
use super::error::{IpcError, setup};

/// Timing of the transport. Waits happen in slices so dead peers are noticed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IpcSettings {
    /// Length of one wait before liveness is checked again \[s\] (default 0.05 s).
    pub slice: Duration,
    /// How long the orchestrator polls for a reply before it blocks on the peer's
    /// wake-up event \[s\]. Polling can only pay with `one_core` off and a core
    /// free for it while a component computes; pinned to one core it holds the core
    /// the component needs (MuJoCo 1.5x with a 30 us poll vs 1.2x blocking, and
    /// unpinned on 2 loaded cores rapier 1.52x vs 1.22x, see BENCHMARKS.md). Default
    /// 0 (always block). Never changes results.
    pub poll: Duration,
    /// Run the orchestrator's thread and the component processes it spawns on one
    /// core, the one the run starts on (see [`CorePin`](super::CorePin)). Default
    /// true. Never changes results.
    pub one_core: bool,
    /// How long a component may take to come up and say it is ready (default 30 s).
    pub ready_timeout: Duration,
    /// How long one step may take before the component is declared hung (default 60 s).
    pub call_timeout: Duration,
}

impl Default for IpcSettings {
    fn default() -> Self {
        Self {
            slice: Duration::from_millis(50),
            poll: Duration::ZERO,
            one_core: true,
            ready_timeout: Duration::from_secs(30),
            call_timeout: Duration::from_secs(60),
        }
    }
}

/// Start of every file name plamo's runs leave under /dev/shm and the iceoryx2 root.
pub const FILE_PREFIX: &str = "plamo_";

/// Where plamo's runs keep iceoryx2's files (node and service descriptions, event
/// sockets) where shared memory exists: iceoryx2 fsyncs every one of them, ~40 per
/// run in the orchestrator alone, and on a disk (its default root, /tmp/iceoryx2)
/// those took 0.2-11 ms each and made most of a multi-process run's start-up; on
/// tmpfs an fsync costs nothing. Elsewhere iceoryx2's default root is kept.
pub const SHM_ROOT: &str = "/dev/shm/plamo-iceoryx2/";

/// The iceoryx2 root of plamo's runs: [`SHM_ROOT`] where /dev/shm exists, else
/// iceoryx2's default.
pub fn runtime_root() -> String {
    if std::path::Path::new("/dev/shm").is_dir() {
        SHM_ROOT.to_owned()
    } else {
        Config::default().global.root_path().to_string()
    }
}

/// An iceoryx2 configuration whose file prefix isolates this run: two runs on one
/// machine never open each other's shared memory. The prefix is `plamo_<run id>_`;
/// `_` cannot occur in a run id, so a file name tells which run it belongs to. Its
/// files live under [`runtime_root`].
pub fn run_config(run: &RunId) -> Result<Config, IpcError> {
    let mut cfg = Config::default();
    let prefix = format!("{FILE_PREFIX}{run}_");
    cfg.global.prefix =
        FileName::new(prefix.as_bytes()).map_err(setup(format!("prefix {prefix}")))?;
    let root = runtime_root();
    cfg.global
        .set_root_path(&Path::new(root.as_bytes()).map_err(setup(format!("root {root}")))?);
    Ok(cfg)
}

/// Nodes a link's services admit: the orchestrator and its component, and room for
/// a component started by hand for the wrong run (refused by the ready handshake)
/// while the right one comes up. Small quotas make the services' shared memory
/// small and quick to create (iceoryx2's defaults are sized for 16-36 ports).
const QUOTA_NODES: usize = 4;

/// One side of a component link: payloads out (`Tx`) and in (`Rx`), and an event
/// each way. The orchestrator sends requests and receives responses; the component
/// the other way round.
pub struct Channels<
    Tx: ZeroCopySend + Copy + Debug + 'static,
    Rx: ZeroCopySend + Copy + Debug + 'static,
> {
    publisher: Publisher<ipc::Service, Envelope<Tx>, ()>,
    subscriber: Subscriber<ipc::Service, Envelope<Rx>, ()>,
    notifier: Notifier<ipc::Service>,
    listener: Listener<ipc::Service>,
}

fn service_name(name: &str) -> Result<ServiceName, IpcError> {
    ServiceName::new(name).map_err(setup(format!("service name {name}")))
}

impl<Tx, Rx> Channels<Tx, Rx>
where
    Tx: ZeroCopySend + Copy + Debug + Default + 'static,
    Rx: ZeroCopySend + Copy + Debug + Default + 'static,
{
    /// Open (or create) the services and this side's ports.
    pub fn open(
        node: &Node<ipc::Service>,
        tx: &str,
        rx: &str,
        tx_event: &str,
        rx_event: &str,
    ) -> Result<Self, IpcError> {
        let tx_service = node
            .service_builder(&service_name(tx)?)
            .publish_subscribe::<Envelope<Tx>>()
            .history_size(0)
            .subscriber_max_buffer_size(4)
            .max_publishers(1)
            .max_subscribers(1)
            .max_nodes(QUOTA_NODES)
            .open_or_create()
            .map_err(setup(format!("service {tx}")))?;
        let rx_service = node
            .service_builder(&service_name(rx)?)
            .publish_subscribe::<Envelope<Rx>>()
            .history_size(0)
            .subscriber_max_buffer_size(4)
            .max_publishers(1)
            .max_subscribers(1)
            .max_nodes(QUOTA_NODES)
            .open_or_create()
            .map_err(setup(format!("service {rx}")))?;
        let tx_ev = node
            .service_builder(&service_name(tx_event)?)
            .event()
            .max_nodes(QUOTA_NODES)
            .max_notifiers(QUOTA_NODES)
            .max_listeners(QUOTA_NODES)
            .event_id_max_value(0)
            .open_or_create()
            .map_err(setup(format!("event {tx_event}")))?;
        let rx_ev = node
            .service_builder(&service_name(rx_event)?)
            .event()
            .max_nodes(QUOTA_NODES)
            .max_notifiers(QUOTA_NODES)
            .max_listeners(QUOTA_NODES)
            .event_id_max_value(0)
            .open_or_create()
            .map_err(setup(format!("event {rx_event}")))?;
        Ok(Self {
            publisher: tx_service
                .publisher_builder()
                .create()
                .map_err(setup(format!("publisher {tx}")))?,
            subscriber: rx_service
                .subscriber_builder()
                .create()
                .map_err(setup(format!("subscriber {rx}")))?,
            notifier: tx_ev
                .notifier_builder()
                .create()
                .map_err(setup(format!("notifier {tx_event}")))?,
            listener: rx_ev
                .listener_builder()
                .create()
                .map_err(setup(format!("listener {rx_event}")))?,
        })
    }

    /// Send a frame and wake the peer.
    pub fn send(&self, frame: Envelope<Tx>) -> Result<(), IpcError> {
        let sample = self.publisher.loan_uninit().map_err(setup("loan"))?;
        sample.write_payload(frame).send().map_err(setup("send"))?;
        self.notifier.notify().map_err(setup("notify"))?;
        Ok(())
    }

    /// Send a frame of `kind` with a default payload.
    pub fn signal(&self, kind: EnvelopeKind, tick: u64) -> Result<(), IpcError> {
        self.send(Envelope::new(kind, tick, Tx::default()))
    }

    /// Take the next waiting frame, if any.
    pub fn try_receive(&self) -> Result<Option<Envelope<Rx>>, IpcError> {
        Ok(self
            .subscriber
            .receive()
            .map_err(setup("receive"))?
            .map(|s| *s))
    }

    /// Poll for the next frame for up to `poll`, without blocking.
    pub fn poll_within(&self, poll: Duration) -> Result<Option<Envelope<Rx>>, IpcError> {
        let start = std::time::Instant::now();
        loop {
            if let Some(frame) = self.try_receive()? {
                return Ok(Some(frame));
            }
            if start.elapsed() >= poll {
                return Ok(None);
            }
            std::hint::spin_loop();
        }
    }

    /// Wait up to `slice` for the peer's wake-up, then take the next frame, if any.
    pub fn receive_within(&self, slice: Duration) -> Result<Option<Envelope<Rx>>, IpcError> {
        if let Some(frame) = self.try_receive()? {
            return Ok(Some(frame));
        }
        self.listener
            .timed_wait(|_| {}, slice)
            .map_err(setup("wait"))?;
        self.try_receive()
    }
}
