//! `replay.mcap`: the recorded run for robotics log viewers (Foxglove and other MCAP
//! readers). One `foxglove.FrameTransforms` message per recorded tick on `/tf` (every
//! body relative to its parent body, each pelvis and moving obstacle relative to
//! `world`; Z-up metres as in the simulation) and one JSON state message per agent
//! and tick on `/plamo/agent` (head, fallen, joint angles by name).
//!
//! The file is unchunked and has no summary section, which the MCAP specification
//! allows and readers stream; messages are JSON, schemas JSON Schema. Log times are
//! the simulated time, so the file is the same bytes for the same recording.

use serde_json::{Value, json};

use plamo_physics::humanoid::BODIES;
use plamo_physics::{BODY_NAMES, JOINT_NAMES, NUM_BODIES};

use super::fk::{local_rotations, qnormalize};
use super::recording::Recording;

const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

#[derive(Default)]
struct Writer {
    out: Vec<u8>,
}

impl Writer {
    fn record(&mut self, op: u8, body: &[u8]) {
        self.out.push(op);
        self.out
            .extend_from_slice(&(body.len() as u64).to_le_bytes());
        self.out.extend_from_slice(body);
    }
}

fn string(b: &mut Vec<u8>, s: &str) {
    b.extend_from_slice(&(s.len() as u32).to_le_bytes());
    b.extend_from_slice(s.as_bytes());
}

fn schema(w: &mut Writer, id: u16, name: &str, schema: &Value) {
    let mut b = id.to_le_bytes().to_vec();
    string(&mut b, name);
    string(&mut b, "jsonschema");
    let data = serde_json::to_vec(schema).unwrap_or_default();
    b.extend_from_slice(&(data.len() as u32).to_le_bytes());
    b.extend_from_slice(&data);
    w.record(0x03, &b);
}

fn channel(w: &mut Writer, id: u16, schema_id: u16, topic: &str) {
    let mut b = id.to_le_bytes().to_vec();
    b.extend_from_slice(&schema_id.to_le_bytes());
    string(&mut b, topic);
    string(&mut b, "json");
    b.extend_from_slice(&0u32.to_le_bytes()); // empty metadata map
    w.record(0x04, &b);
}

fn message(w: &mut Writer, channel: u16, sequence: u32, time_ns: u64, data: &Value) {
    let mut b = channel.to_le_bytes().to_vec();
    b.extend_from_slice(&sequence.to_le_bytes());
    b.extend_from_slice(&time_ns.to_le_bytes());
    b.extend_from_slice(&time_ns.to_le_bytes());
    b.extend_from_slice(&serde_json::to_vec(data).unwrap_or_default());
    w.record(0x05, &b);
}

fn stamp(ns: u64) -> Value {
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

fn transform(ns: u64, parent: &str, child: &str, t: [f64; 3], r: [f64; 4]) -> Value {
    json!({
        "timestamp": stamp(ns),
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": { "x": t[0], "y": t[1], "z": t[2] },
        "rotation": { "x": r[0], "y": r[1], "z": r[2], "w": r[3] },
    })
}

fn frame_transforms_schema() -> Value {
    let vec3 = json!({ "type": "object", "properties": {
        "x": { "type": "number" }, "y": { "type": "number" }, "z": { "type": "number" } } });
    let quat = json!({ "type": "object", "properties": {
        "x": { "type": "number" }, "y": { "type": "number" }, "z": { "type": "number" },
        "w": { "type": "number" } } });
    json!({
        "title": "foxglove.FrameTransforms",
        "type": "object",
        "properties": { "transforms": { "type": "array", "items": {
            "type": "object",
            "properties": {
                "timestamp": { "type": "object", "properties": {
                    "sec": { "type": "integer" }, "nsec": { "type": "integer" } } },
                "parent_frame_id": { "type": "string" },
                "child_frame_id": { "type": "string" },
                "translation": vec3,
                "rotation": quat,
            },
        } } },
    })
}

fn agent_schema() -> Value {
    json!({
        "title": "plamo.AgentState",
        "type": "object",
        "properties": {
            "agent": { "type": "integer" },
            "tick": { "type": "integer" },
            "fallen": { "type": "boolean" },
            "head": { "type": "object", "description": "head centre [m], Z up" },
            "joints": { "type": "object", "description": "joint angles [rad] by name" },
        },
    })
}

/// The recording as MCAP bytes.
pub fn write_mcap(rec: &Recording) -> Vec<u8> {
    let mut w = Writer::default();
    w.out.extend_from_slice(MAGIC);
    let mut header = Vec::new();
    string(&mut header, "");
    string(&mut header, concat!("plamo ", env!("CARGO_PKG_VERSION")));
    w.record(0x01, &header);
    schema(
        &mut w,
        1,
        "foxglove.FrameTransforms",
        &frame_transforms_schema(),
    );
    schema(&mut w, 2, "plamo.AgentState", &agent_schema());
    channel(&mut w, 1, 1, "/tf");
    channel(&mut w, 2, 2, "/plamo/agent");

    // All ticks with agent or obstacle frames, in order.
    let mut ticks: Vec<u64> = rec
        .agents
        .iter()
        .flat_map(|a| a.frames.iter().map(|f| f.tick))
        .chain(rec.obstacles.iter().flatten().map(|o| o.tick))
        .collect();
    ticks.sort_unstable();
    ticks.dedup();
    let mut next = vec![0usize; rec.agents.len()];
    let mut next_obstacle = vec![0usize; rec.obstacles.len()];
    let (mut seq_tf, mut seq_agent) = (0u32, 0u32);
    for tick in ticks {
        let ns = (Recording::time(tick) * 1e9).round() as u64;
        let mut transforms = Vec::new();
        let mut states = Vec::new();
        for (k, a) in rec.agents.iter().enumerate() {
            let Some(f) = a.frames.get(next[k]).filter(|f| f.tick == tick) else {
                continue;
            };
            next[k] += 1;
            let frame = |b: usize| format!("agent{k}/{}", BODY_NAMES[b]);
            transforms.push(transform(
                ns,
                "world",
                &frame(0),
                f.root,
                qnormalize(f.quat),
            ));
            let local = local_rotations(&f.joints);
            for b in 1..NUM_BODIES {
                let parent = BODIES[b].parent.unwrap_or(0);
                transforms.push(transform(
                    ns,
                    &frame(parent),
                    &frame(b),
                    BODIES[b].offset,
                    local[b],
                ));
            }
            let joints: serde_json::Map<String, Value> = JOINT_NAMES
                .iter()
                .zip(f.joints)
                .map(|(n, q)| (n.to_string(), json!(q)))
                .collect();
            states.push(json!({
                "agent": k, "tick": tick, "fallen": f.fallen,
                "head": { "x": f.head[0], "y": f.head[1], "z": f.head[2] },
                "joints": joints,
            }));
        }
        for (i, frames) in rec.obstacles.iter().enumerate() {
            let Some(o) = frames.get(next_obstacle[i]).filter(|o| o.tick == tick) else {
                continue;
            };
            next_obstacle[i] += 1;
            let name = rec.scene.dynamic.get(i).map_or("obstacle", |d| &d.name);
            transforms.push(transform(
                ns,
                "world",
                name,
                o.position,
                [0.0, 0.0, 0.0, 1.0],
            ));
        }
        message(&mut w, 1, seq_tf, ns, &json!({ "transforms": transforms }));
        seq_tf += 1;
        for s in &states {
            message(&mut w, 2, seq_agent, ns, s);
            seq_agent += 1;
        }
    }
    // Data end (no CRC computed: 0), footer without a summary section, magic.
    w.record(0x0F, &0u32.to_le_bytes());
    let mut footer = Vec::new();
    footer.extend_from_slice(&0u64.to_le_bytes());
    footer.extend_from_slice(&0u64.to_le_bytes());
    footer.extend_from_slice(&0u32.to_le_bytes());
    w.record(0x02, &footer);
    w.out.extend_from_slice(MAGIC);
    w.out
}
