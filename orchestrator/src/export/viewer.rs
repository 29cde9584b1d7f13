//! The self-contained HTML replay viewer: the JavaScript bundle (three.js and the
//! viewer, bundled by esbuild from `orchestrator/viewer/`), the run's `replay.glb`
//! inlined as base64 and the overlay data (plans, head paths, per-frame figures) as
//! JSON, all in one file that needs no network.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use super::gltf::write_glb;
use super::recording::{AgentTrack, Recording};

/// Where the viewer's JavaScript bundle is looked for (`npm run build` in
/// `orchestrator/viewer/` writes it); `PLAMO_VIEWER_BUNDLE` overrides.
pub const BUNDLE_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/viewer/dist/viewer.js");

/// The commands that build the bundle.
pub const BUILD_COMMAND: &str = concat!(
    "npm ci --prefix ",
    env!("CARGO_MANIFEST_DIR"),
    "/viewer && npm run build --prefix ",
    env!("CARGO_MANIFEST_DIR"),
    "/viewer"
);

/// The viewer's JavaScript bundle.
#[derive(Debug, Clone)]
pub struct ViewerBundle {
    /// The JavaScript (an IIFE that reads `window.PLAMO_DATA`).
    pub js: String,
    /// Where it was read from.
    pub path: PathBuf,
}

impl ViewerBundle {
    /// Read the bundle from `PLAMO_VIEWER_BUNDLE` or [`BUNDLE_PATH`]; the error says
    /// which command builds it.
    pub fn load() -> Result<Self, String> {
        let path = std::env::var_os("PLAMO_VIEWER_BUNDLE")
            .map_or_else(|| PathBuf::from(BUNDLE_PATH), PathBuf::from);
        match std::fs::read_to_string(&path) {
            Ok(js) => Ok(Self { js, path }),
            Err(e) => Err(format!(
                "the viewer's JavaScript bundle {} is not there ({e}); build it once with \
                 Node.js >= 18 and npm: `{BUILD_COMMAND}` (or point PLAMO_VIEWER_BUNDLE at a built viewer.js)",
                path.display()
            )),
        }
    }
}

/// Round to millimetres (or milli-units) to keep the page small.
fn r3(x: f64) -> f64 {
    if x.is_finite() {
        (x * 1000.0).round() / 1000.0
    } else {
        0.0
    }
}

fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Per-frame figures of one agent: time, current instruction, speed, head height
/// above the terrain, and the horizontal distance between the head and where the
/// plan put it at that time of the instruction.
fn agent_json(rec: &Recording, a: &AgentTrack) -> Value {
    let terrain = &rec.scene.terrain;
    let n = a.frames.len();
    let mut t = Vec::with_capacity(n);
    let mut instr = Vec::with_capacity(n);
    let mut speed = Vec::with_capacity(n);
    let mut height = Vec::with_capacity(n);
    let mut xy_err = Vec::with_capacity(n);
    let mut plan_speed = Vec::with_capacity(n);
    let mut fallen = Vec::with_capacity(n);
    let mut head = Vec::with_capacity(n);
    for (i, f) in a.frames.iter().enumerate() {
        let time = Recording::time(f.tick);
        t.push(r3(time));
        let k = a
            .instruction_starts
            .iter()
            .rposition(|&s| s <= time)
            .unwrap_or(0);
        instr.push(k);
        // Pelvis horizontal speed by a central difference over the recorded frames.
        let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
        let dt = Recording::time(a.frames[hi].tick) - Recording::time(a.frames[lo].tick);
        let v = if dt > 0.0 {
            let (p, q) = (a.frames[lo].root, a.frames[hi].root);
            (q[0] - p[0]).hypot(q[1] - p[1]) / dt
        } else {
            0.0
        };
        speed.push(r3(v));
        height.push(r3(f.head[2] - terrain.height_at(f.head[0], f.head[1])));
        // Where (and how fast) the plan had the head at this time of the instruction.
        let planned = a.route.get(k).and_then(|route| {
            let local = time - a.instruction_starts[k];
            let j = route.partition_point(|p| p.t <= local);
            match (j, route.len()) {
                (_, 0) => None,
                (0, _) => Some((route[0].pos, route[0].v)),
                (j, len) if j >= len => Some((route[len - 1].pos, route[len - 1].v)),
                (j, _) => {
                    let (p0, p1) = (route[j - 1], route[j]);
                    let w = ((local - p0.t) / (p1.t - p0.t).max(1e-12)).clamp(0.0, 1.0);
                    let lerp = |a: f64, b: f64| a + w * (b - a);
                    Some((
                        [lerp(p0.pos[0], p1.pos[0]), lerp(p0.pos[1], p1.pos[1]), 0.0],
                        lerp(p0.v, p1.v),
                    ))
                }
            }
        });
        let err = planned.map(|(p, _)| (f.head[0] - p[0]).hypot(f.head[1] - p[1]));
        plan_speed.push(planned.map(|(_, v)| r3(v)));
        xy_err.push(err.map(r3));
        fallen.push(f.fallen);
        head.push(f.head.map(r3));
    }
    let plan: Vec<Vec<[f64; 4]>> = a
        .route
        .iter()
        .map(|r| {
            r.iter()
                .map(|p| [r3(p.pos[0]), r3(p.pos[1]), r3(p.pos[2]), r3(p.v)])
                .collect()
        })
        .collect();
    json!({
        "instructions": a.instructions,
        "plan": plan,
        "head": head,
        "t": t,
        "instruction": instr,
        "speed": speed,
        "head_height": height,
        "xy_err": xy_err,
        "plan_speed": plan_speed,
        "fallen": fallen,
    })
}

/// The data the viewer page reads for one recorded run.
pub fn viewer_data(rec: &Recording) -> Value {
    let landmarks: Vec<Value> = rec
        .scene
        .landmarks
        .iter()
        .map(|l| {
            let c = super::gltf::landmark_marker(&l.region);
            json!({ "name": l.name, "pos": [r3(c[0]), r3(c[1]), r3(rec.scene.terrain.height_at(c[0], c[1]))] })
        })
        .collect();
    let (lo, hi) = rec.scene.terrain.bounds();
    json!({
        "name": rec.dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
        "scene": rec.scene.name,
        "physics": rec.physics,
        "status": rec.status,
        "bounds": [lo, hi],
        "landmarks": landmarks,
        "agents": rec.agents.iter().map(|a| agent_json(rec, a)).collect::<Vec<_>>(),
        "glb": base64(&write_glb(rec)),
    })
}

/// The whole HTML page for one or more recorded runs (shown side by side in one
/// scene, each run in its own colour).
pub fn viewer_html(runs: &[Recording], bundle: &ViewerBundle) -> String {
    let data = json!({ "runs": runs.iter().map(viewer_data).collect::<Vec<_>>() });
    // `</` inside a script element would end it early.
    let data = serde_json::to_string(&data)
        .unwrap_or_default()
        .replace("</", "<\\/");
    let js = bundle.js.replace("</script", "<\\/script");
    let title = runs
        .iter()
        .map(|r| format!("{} ({})", r.scene.name, r.physics))
        .collect::<Vec<_>>()
        .join(" vs ");
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>plamo replay: {title}</title>\n</head>\n<body>\n\
         <script>window.PLAMO_DATA = {data};</script>\n<script>{js}</script>\n</body>\n</html>\n"
    )
}

/// Write the viewer page for the recordings in `dirs` to `out`.
pub fn write_viewer(dirs: &[&Path], out: &Path) -> anyhow::Result<()> {
    let bundle = ViewerBundle::load().map_err(anyhow::Error::msg)?;
    let runs = dirs
        .iter()
        .map(|d| Recording::load(d))
        .collect::<Result<Vec<_>, _>>()?;
    std::fs::write(out, viewer_html(&runs, &bundle))
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}
