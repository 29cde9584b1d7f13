//! Noticing dead peers and removing what they left behind. A SIGKILLed process is not
//! signalled; its node shows up as dead in the node list, and removing its stale
//! resources deletes its files under /dev/shm and /tmp/iceoryx2.

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

/// Who a node is, from its name (`plamo-orchestrator`, `plamo-physics`,
/// `plamo-planner-0`, ...).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeRole(pub String);

/// Names of the nodes of this run's configuration whose processes died. Their stale
/// resources are removed on the way.
pub fn dead_nodes(cfg: &Config) -> Vec<NodeRole> {
    let mut dead = Vec::new();
    let _ = Node::<ipc::Service>::list(cfg, |state| {
        if let NodeState::Dead(view) = state {
            let name = view
                .details()
                .as_ref()
                .map(|d| d.name().as_str().to_owned())
                .unwrap_or_else(|| "unnamed node".to_owned());
            let _ = view.try_remove_stale_resources();
            dead.push(NodeRole(name));
        }
        CallbackProgression::Continue
    });
    dead
}

/// Remove everything dead nodes of this configuration left behind (a crashed earlier
/// run with the same id). Returns how many dead nodes were cleaned.
pub fn remove_stale_resources(cfg: &Config) -> usize {
    dead_nodes(cfg).len()
}

/// Remove the run's last shared file once every node of the run is gone. iceoryx2
/// keeps a small persistent "global management" segment per file prefix; since our
/// prefix is per run, nobody else will ever open it again.
pub fn end_run(cfg: &Config) -> Result<(), String> {
    let mut alive = 0usize;
    let _ = Node::<ipc::Service>::list(cfg, |state| {
        if matches!(state, NodeState::Alive(_)) {
            alive += 1;
        }
        CallbackProgression::Continue
    });
    if alive > 0 {
        return Err(format!("{alive} node(s) of this run are still alive"));
    }
    remove_stale_resources(cfg);
    // SAFETY: no node of this run is alive (checked above), and the per-run prefix
    // means no other process uses this iceoryx2 domain.
    unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(cfg) }
        .map(|_| ())
        .map_err(|e| format!("removing the management segment: {e:?}"))
}
