//! `replay.glb`: the recorded run as a glTF 2.0 binary.
//!
//! The JSON is built with serde_json and the GLB container packed here: the format
//! needs only accessors, buffer views, meshes, nodes and one animation, and the
//! Khronos validator (run by scripts/test-all.sh) is the contract it is checked
//! against. Everything below the root node stays in the simulation's Z-up metres;
//! the root node turns Z-up into glTF's Y-up, so positions in the file read the same
//! as in trajectory.csv.

use serde_json::{Value, json};

use plamo_physics::humanoid::BODIES;
use plamo_physics::{BODY_NAMES, NUM_BODIES};
use plamo_scenes::{ObstacleShape, Region};

use super::fk::{local_rotations, qnormalize};
use super::mesh::Mesh;
use super::recording::Recording;

const FLOAT: u32 = 5126;
const UINT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// Terrain samples per side at most in the mesh (a 30 m scene at 0.1 m is 301).
const TERRAIN_MAX_SAMPLES: usize = 256;

/// Materials by index in [`MATERIALS`].
#[derive(Clone, Copy)]
enum Mat {
    Terrain = 0,
    Body,
    Left,
    Right,
    Skin,
    Wall,
    Ceiling,
    Obstacle,
    LandmarkArea,
    LandmarkPole,
}

/// (name, linear RGBA, translucent).
const MATERIALS: [(&str, [f64; 4], bool); 10] = [
    ("terrain", [1.0, 1.0, 1.0, 1.0], false),
    ("body", [0.55, 0.58, 0.62, 1.0], false),
    ("left", [0.15, 0.35, 0.80, 1.0], false),
    ("right", [0.80, 0.20, 0.15, 1.0], false),
    ("skin", [0.85, 0.65, 0.50, 1.0], false),
    ("wall", [0.45, 0.42, 0.40, 1.0], false),
    ("ceiling", [0.60, 0.45, 0.30, 0.55], true),
    ("obstacle", [0.20, 0.80, 0.20, 1.0], false),
    ("landmark area", [1.0, 0.55, 0.05, 0.35], true),
    ("landmark pole", [1.0, 0.55, 0.05, 1.0], false),
];

#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    /// Materials in order of first use (the validator flags unused ones).
    materials: Vec<Value>,
    material_index: [Option<usize>; MATERIALS.len()],
}

fn num(x: f32) -> Value {
    json!(f64::from(x))
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn floats<const N: usize>(
        &mut self,
        data: &[[f32; N]],
        kind: &str,
        target: Option<u32>,
        min_max: bool,
    ) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flat_map(|v| v.iter().flat_map(|c| c.to_le_bytes()))
            .collect();
        let view = self.view(&bytes, target);
        let mut a = json!({
            "bufferView": view, "componentType": FLOAT, "count": data.len(), "type": kind,
        });
        if min_max {
            let mut lo = [f32::INFINITY; N];
            let mut hi = [f32::NEG_INFINITY; N];
            for v in data {
                for k in 0..N {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            a["min"] = Value::Array(lo.iter().map(|&x| num(x)).collect());
            a["max"] = Value::Array(hi.iter().map(|&x| num(x)).collect());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view, "componentType": UINT, "count": idx.len(), "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    fn mesh(&mut self, name: &str, m: &Mesh, mat: Mat) -> usize {
        let pos = self.floats(&m.positions, "VEC3", Some(ARRAY_BUFFER), true);
        let nor = self.floats(&m.normals, "VEC3", Some(ARRAY_BUFFER), false);
        let mut attrs = json!({ "POSITION": pos, "NORMAL": nor });
        if !m.colors.is_empty() {
            attrs["COLOR_0"] = json!(self.floats(&m.colors, "VEC3", Some(ARRAY_BUFFER), false));
        }
        let ind = self.indices(&m.indices);
        let material = self.material(mat);
        self.meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": attrs, "indices": ind, "material": material, "mode": 4 }],
        }));
        self.meshes.len() - 1
    }

    fn material(&mut self, mat: Mat) -> usize {
        if let Some(i) = self.material_index[mat as usize] {
            return i;
        }
        let (name, color, translucent) = MATERIALS[mat as usize];
        let mut m = json!({
            "name": name,
            "pbrMetallicRoughness": { "baseColorFactor": color, "metallicFactor": 0.0, "roughnessFactor": 0.85 },
        });
        if translucent {
            m["alphaMode"] = json!("BLEND");
            m["doubleSided"] = json!(true);
        }
        self.materials.push(m);
        self.material_index[mat as usize] = Some(self.materials.len() - 1);
        self.materials.len() - 1
    }

    fn node(&mut self, v: Value) -> usize {
        self.nodes.push(v);
        self.nodes.len() - 1
    }
}

/// Keep consecutive quaternions in the same hemisphere so linear interpolation
/// takes the short way.
fn continuous(prev: Option<[f32; 4]>, q: [f64; 4]) -> [f32; 4] {
    let q = qnormalize(q).map(|c| c as f32);
    match prev {
        Some(p) if p.iter().zip(&q).map(|(a, b)| a * b).sum::<f32>() < 0.0 => q.map(|c| -c),
        _ => q,
    }
}

fn disc(center: [f64; 3], radius: f64) -> Mesh {
    const SEG: u32 = 32;
    let mut m = Mesh::default();
    m.positions.push(center.map(|c| c as f32));
    m.normals.push([0.0, 0.0, 1.0]);
    for k in 0..SEG {
        let th = 2.0 * std::f64::consts::PI * f64::from(k) / f64::from(SEG);
        m.positions.push(
            [
                center[0] + radius * th.cos(),
                center[1] + radius * th.sin(),
                center[2],
            ]
            .map(|c| c as f32),
        );
        m.normals.push([0.0, 0.0, 1.0]);
        m.indices.extend([0, 1 + k, 1 + (k + 1) % SEG]);
    }
    m
}

/// Where a landmark's marker stands: above the region's centre, high enough
/// (from [`MARKER_BOTTOM`] up) that it never hides a humanoid standing under it.
pub(crate) fn landmark_marker(region: &Region) -> [f64; 2] {
    region.center()
}

/// Height of the marker's lower end above the terrain \[m\].
pub(crate) const MARKER_BOTTOM: f64 = 2.0;
/// Height of the marker ball's centre above the terrain \[m\].
pub(crate) const MARKER_TOP: f64 = 2.6;

/// The recording as GLB bytes.
pub fn write_glb(rec: &Recording) -> Vec<u8> {
    let scene = &rec.scene;
    let mut b = Builder::default();
    let mut root_children = Vec::new();

    // Terrain.
    let stride = scene
        .terrain
        .nx
        .max(scene.terrain.ny)
        .div_ceil(TERRAIN_MAX_SAMPLES);
    let terrain = Mesh::terrain(&scene.terrain, stride);
    let m = b.mesh("terrain", &terrain, Mat::Terrain);
    root_children.push(b.node(json!({ "name": "terrain", "mesh": m })));

    // Walls and low ceilings.
    for (i, w) in scene.walls.iter().enumerate() {
        let name = if w.name.is_empty() {
            format!("wall {i}")
        } else {
            w.name.clone()
        };
        let m = b.mesh(
            &name,
            &Mesh::prism(&w.footprint, w.z_min, w.z_max),
            Mat::Wall,
        );
        root_children.push(b.node(json!({ "name": name, "mesh": m })));
    }
    for (i, t) in scene.tops.iter().enumerate() {
        let name = if t.name.is_empty() {
            format!("ceiling {i}")
        } else {
            t.name.clone()
        };
        let m = b.mesh(
            &name,
            &Mesh::prism(&t.footprint, t.z_bottom, t.z_top),
            Mat::Ceiling,
        );
        root_children.push(b.node(json!({ "name": name, "mesh": m })));
    }

    // Landmarks: the region on the ground and a floating pin to find it by.
    for l in &scene.landmarks {
        let c = landmark_marker(&l.region);
        let z = scene.terrain.height_at(c[0], c[1]);
        let area = match l.region {
            Region::Circle { center, radius } => {
                let zc = scene.terrain.height_at(center[0], center[1]);
                disc([center[0], center[1], zc + 0.02], radius)
            }
            Region::Rect { footprint } => {
                let zc = scene
                    .terrain
                    .height_at(footprint.center[0], footprint.center[1]);
                Mesh::prism(&footprint, zc, zc + 0.03)
            }
        };
        let am = b.mesh(&format!("{} area", l.name), &area, Mat::LandmarkArea);
        let mut pole = Mesh::capsule(
            [c[0], c[1], z + MARKER_BOTTOM],
            [c[0], c[1], z + MARKER_TOP],
            0.025,
        );
        pole.append(&Mesh::capsule(
            [c[0], c[1], z + MARKER_TOP],
            [c[0], c[1], z + MARKER_TOP],
            0.13,
        ));
        let pm = b.mesh(&format!("{} marker", l.name), &pole, Mat::LandmarkPole);
        let a = b.node(json!({ "name": format!("{} area", l.name), "mesh": am }));
        let p = b.node(json!({ "name": format!("{} marker", l.name), "mesh": pm }));
        root_children.push(b.node(json!({
            "name": l.name, "children": [a, p],
            "extras": { "landmark": l.name },
        })));
    }

    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let mut channel =
        |b: &mut Builder, node: usize, input: usize, t: &[[f32; 3]], r: &[[f32; 4]]| {
            let out_t = b.floats(t, "VEC3", None, false);
            let out_r = b.floats(r, "VEC4", None, false);
            for (path, out) in [("translation", out_t), ("rotation", out_r)] {
                samplers.push(json!({ "input": input, "output": out, "interpolation": "LINEAR" }));
                channels.push(
                json!({ "sampler": samplers.len() - 1, "target": { "node": node, "path": path } }),
            );
            }
        };

    // Moving obstacles, animated from obstacles.csv.
    for (i, o) in scene.dynamic.iter().enumerate() {
        let mesh = match o.shape {
            ObstacleShape::Sphere { radius } => Mesh::capsule([0.0; 3], [0.0; 3], radius),
            ObstacleShape::Box { half_extents } => Mesh::cuboid([0.0; 3], half_extents, 0.0),
        };
        let m = b.mesh(&o.name, &mesh, Mat::Obstacle);
        let frames = rec.obstacles.get(i).map(Vec::as_slice).unwrap_or_default();
        let first = frames.first().map_or([0.0; 3], |f| f.position);
        let node = b.node(json!({ "name": o.name, "mesh": m, "translation": first }));
        root_children.push(node);
        let mut times = Vec::new();
        let mut tr = Vec::new();
        let mut rot = Vec::new();
        let mut yaw = 0.0f64;
        for f in frames {
            let t = Recording::time(f.tick) as f32;
            if times.last().is_some_and(|&[last]: &[f32; 1]| t <= last) {
                continue;
            }
            if f.velocity[0].hypot(f.velocity[1]) > 1e-9 {
                yaw = f.velocity[1].atan2(f.velocity[0]);
            }
            times.push([t]);
            tr.push(f.position.map(|c| c as f32));
            let q = [0.0, 0.0, (0.5 * yaw).sin(), (0.5 * yaw).cos()];
            rot.push(continuous(rot.last().copied(), q));
        }
        if times.len() >= 2 {
            let input = b.floats(&times, "SCALAR", None, true);
            channel(&mut b, node, input, &tr, &rot);
        }
    }

    // The humanoids: one node per body on the body tree, pelvis animated in world
    // coordinates, every other body relative to its parent.
    for (k, agent) in rec.agents.iter().enumerate() {
        let frames: Vec<_> = {
            let mut v: Vec<&super::recording::AgentFrame> = Vec::new();
            for f in &agent.frames {
                if v.last().is_none_or(|l| f.tick > l.tick) {
                    v.push(f);
                }
            }
            v
        };
        let times: Vec<[f32; 1]> = frames
            .iter()
            .map(|f| [Recording::time(f.tick) as f32])
            .collect();
        let mut tr: Vec<Vec<[f32; 3]>> = vec![Vec::new(); NUM_BODIES];
        let mut rot: Vec<Vec<[f32; 4]>> = vec![Vec::new(); NUM_BODIES];
        for f in &frames {
            let local = local_rotations(&f.joints);
            for bi in 0..NUM_BODIES {
                let (t, r) = if bi == 0 {
                    (f.root, f.quat)
                } else {
                    (BODIES[bi].offset, local[bi])
                };
                tr[bi].push(t.map(|c| c as f32));
                let q = continuous(rot[bi].last().copied(), r);
                rot[bi].push(q);
            }
        }
        let mut ids = [0usize; NUM_BODIES];
        for (bi, body) in BODIES.iter().enumerate() {
            let mut mesh = Mesh::default();
            for s in body.shapes {
                mesh.append(&Mesh::shape(s));
            }
            let mat = if bi == plamo_physics::HEAD {
                Mat::Skin
            } else if body.name.starts_with("left_") {
                Mat::Left
            } else if body.name.starts_with("right_") {
                Mat::Right
            } else {
                Mat::Body
            };
            let m = b.mesh(&format!("agent {k} {}", body.name), &mesh, mat);
            ids[bi] = b.node(json!({
                "name": BODY_NAMES[bi],
                "mesh": m,
                "translation": tr[bi][0],
                "rotation": rot[bi][0],
            }));
        }
        for (bi, body) in BODIES.iter().enumerate() {
            if let Some(p) = body.parent {
                let child = ids[bi];
                let parent = &mut b.nodes[ids[p]];
                if parent.get("children").is_none() {
                    parent["children"] = json!([]);
                }
                if let Some(c) = parent["children"].as_array_mut() {
                    c.push(json!(child));
                }
            }
        }
        root_children.push(b.node(json!({
            "name": format!("agent {k}"),
            "children": [ids[0]],
            "extras": { "agent": k, "instructions": agent.instructions },
        })));
        if times.len() >= 2 {
            let input = b.floats(&times, "SCALAR", None, true);
            for bi in 0..NUM_BODIES {
                channel(&mut b, ids[bi], input, &tr[bi], &rot[bi]);
            }
        }
    }

    let h = std::f64::consts::FRAC_1_SQRT_2;
    let root = b.node(json!({
        "name": "plamo (Z-up)",
        "rotation": [-h, 0.0, 0.0, h],
        "children": root_children,
    }));

    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    let mut doc = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("plamo ", env!("CARGO_PKG_VERSION")),
            "extras": { "scene": scene.name, "physics": rec.physics, "status": rec.status },
        },
        "scene": 0,
        "scenes": [{ "name": scene.name, "nodes": [root] }],
        "nodes": b.nodes,
        "meshes": b.meshes,
        "materials": b.materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{ "byteLength": b.bin.len() }],
    });
    if !channels.is_empty() {
        doc["animations"] =
            json!([{ "name": "replay", "samplers": samplers, "channels": channels }]);
    }
    pack_glb(&serde_json::to_vec(&doc).unwrap_or_default(), &b.bin)
}

/// The GLB container: 12-byte header, a JSON chunk padded with spaces and a binary
/// chunk padded with zeros, both to 4 bytes.
fn pack_glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut bb = bin.to_vec();
    while !bb.len().is_multiple_of(4) {
        bb.push(0);
    }
    let total = 12 + 8 + j.len() + if bb.is_empty() { 0 } else { 8 + bb.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !bb.is_empty() {
        out.extend_from_slice(&(bb.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bb);
    }
    out
}
