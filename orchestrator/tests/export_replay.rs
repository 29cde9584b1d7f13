//! `plamo run --out`, `plamo export` and `plamo view` on a short playground route,
//! through the built binary: the GLB container and its animation read back
//! independently of the exporter (the head recomposed from the glTF node hierarchy
//! lands where the physics put it), byte-identical exports across replays and
//! re-exports, and clear errors. The Khronos validator, the BVH reader and the
//! browser test run in scripts/test-all.sh (they need npm, PyPI and Chromium).

mod support;

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_plamo");
const ROUTE: &str = "Run from the tree to the car, then crawl to the bench";

fn out_dir(name: &str) -> support::OutDir {
    support::out_dir("export", name)
}

/// A 3 s recording; the run itself times out (exit status 1) by design.
fn record(physics: &str, out: &Path) -> Output {
    let o = Command::new(BIN)
        .args(["run", "--scene", "playground", "--quiet", "--seed", "3"])
        .args(["--instructions", ROUTE, "--max-seconds", "3"])
        .args(["--physics", physics, "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(
        out.join("replay.glb").exists() && out.join("motion.bvh").exists(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The two GLB chunks.
fn parse_glb(bytes: &[u8]) -> (Value, Vec<u8>) {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(u32_at(4), 2, "GLB version");
    assert_eq!(u32_at(8), bytes.len(), "GLB length field");
    let jlen = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    assert_eq!(jlen % 4, 0);
    let json: Value = serde_json::from_slice(&bytes[20..20 + jlen]).unwrap();
    let b = 20 + jlen;
    let blen = u32_at(b);
    assert_eq!(&bytes[b + 4..b + 8], b"BIN\0");
    assert_eq!(b + 8 + blen, bytes.len());
    (json, bytes[b + 8..].to_vec())
}

/// Accessor `i` as rows of f32.
fn floats(doc: &Value, bin: &[u8], i: usize) -> Vec<Vec<f32>> {
    let a = &doc["accessors"][i];
    assert_eq!(a["componentType"], 5126);
    let n = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        t => panic!("type {t}"),
    };
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let off = v["byteOffset"].as_u64().unwrap() as usize;
    (0..a["count"].as_u64().unwrap() as usize)
        .map(|r| {
            (0..n)
                .map(|c| {
                    let p = off + 4 * (r * n + c);
                    f32::from_le_bytes(bin[p..p + 4].try_into().unwrap())
                })
                .collect()
        })
        .collect()
}

fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

fn qrot(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let p = qmul(
        qmul(q, [v[0], v[1], v[2], 0.0]),
        [-q[0], -q[1], -q[2], q[3]],
    );
    [p[0], p[1], p[2]]
}

fn to4(v: &[f32]) -> [f64; 4] {
    [v[0], v[1], v[2], v[3]].map(f64::from)
}

fn to3(v: &[f32]) -> [f64; 3] {
    [v[0], v[1], v[2]].map(f64::from)
}

/// Reads the animation back the way a glTF viewer would: each node's sampled local
/// translation and rotation, composed down the node tree from the pelvis to the head,
/// then the head centre (0, 0, 0.08) in the head frame. It must land on the head
/// position the physics recorded in trajectory.csv.
fn check_animation(dir: &Path, tolerance: f64) {
    let (doc, bin) = parse_glb(&std::fs::read(dir.join("replay.glb")).unwrap());
    let nodes = doc["nodes"].as_array().unwrap();
    let find = |name: &str| {
        nodes
            .iter()
            .position(|n| n["name"] == name)
            .unwrap_or_else(|| panic!("no node {name}"))
    };
    for name in [
        "terrain",
        "tunnel",
        "fence-north",
        "tree",
        "green-ball",
        "left_foot",
    ] {
        find(name);
    }
    let anim = &doc["animations"][0];
    let channels = anim["channels"].as_array().unwrap();
    // 15 bodies + 1 moving obstacle, translation and rotation each.
    assert_eq!(channels.len(), 2 * (15 + 1));
    let sampled = |node: usize, path: &str| {
        let c = channels
            .iter()
            .find(|c| c["target"]["node"] == node && c["target"]["path"] == path)
            .unwrap_or_else(|| panic!("no {path} channel on node {node}"));
        let s = &anim["samplers"][c["sampler"].as_u64().unwrap() as usize];
        (
            floats(&doc, &bin, s["input"].as_u64().unwrap() as usize),
            floats(&doc, &bin, s["output"].as_u64().unwrap() as usize),
        )
    };
    let chain = ["pelvis", "torso", "head"].map(find);
    // Parent links: the head is under the torso, the torso under the pelvis.
    for w in chain.windows(2) {
        let kids = nodes[w[0]]["children"].as_array().unwrap();
        assert!(kids.iter().any(|k| *k == w[1]), "node tree");
    }
    let tracks: Vec<_> = chain
        .iter()
        .map(|&n| (sampled(n, "translation"), sampled(n, "rotation")))
        .collect();

    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    let times = &tracks[0].0.0;
    assert_eq!(times.len(), rows.len(), "one keyframe per recorded tick");
    let mut worst = 0.0f64;
    for (i, row) in rows.iter().enumerate() {
        assert!((f64::from(times[i][0]) - row[0] / 120.0).abs() < 1e-4);
        let mut pos = [0.0; 3];
        let mut rot = [0.0, 0.0, 0.0, 1.0];
        for ((_, tr), (_, rq)) in &tracks {
            let o = qrot(rot, to3(&tr[i]));
            pos = [pos[0] + o[0], pos[1] + o[1], pos[2] + o[2]];
            rot = qmul(rot, to4(&rq[i]));
            let n = rq[i].iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!((n - 1.0).abs() < 1e-5, "unit quaternion");
        }
        let h = qrot(rot, [0.0, 0.0, 0.08]);
        let head = [pos[0] + h[0], pos[1] + h[1], pos[2] + h[2]];
        let err = (0..3)
            .map(|k| (head[k] - row[10 + k]).powi(2))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(err);
    }
    assert!(
        worst < tolerance,
        "head from the glTF hierarchy is {worst} m off (allowed {tolerance} m)"
    );
}

fn run_plamo(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// `tolerance`: how far the recorded head may be from the one recomposed from the
/// recorded joint state \[m\].
fn check_backend(physics: &str, tolerance: f64) {
    let a = out_dir(&format!("{physics}-a"));
    let b = out_dir(&format!("{physics}-b"));
    record(physics, &a);
    record(physics, &b);
    check_animation(&a, tolerance);
    for f in [
        "replay.glb",
        "motion.bvh",
        "replay.mcap",
        "trajectory.csv",
        "scene.json",
    ] {
        assert!(
            std::fs::read(a.join(f)).unwrap() == std::fs::read(b.join(f)).unwrap(),
            "{f} differs between two identical runs"
        );
    }
    // Re-exporting the recording writes the same bytes the run wrote.
    let glb = std::fs::read(a.join("replay.glb")).unwrap();
    let bvh = std::fs::read(a.join("motion.bvh")).unwrap();
    let mcap = std::fs::read(a.join("replay.mcap")).unwrap();
    std::fs::remove_file(a.join("replay.glb")).unwrap();
    let o = run_plamo(&["export", a.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(a.join("replay.glb")).unwrap() == glb);
    assert!(std::fs::read(a.join("motion.bvh")).unwrap() == bvh);
    assert!(std::fs::read(a.join("replay.mcap")).unwrap() == mcap);
    assert!(mcap.starts_with(b"\x89MCAP0\r\n") && mcap.ends_with(b"\x89MCAP0\r\n"));
    let text = String::from_utf8(bvh).unwrap();
    assert!(text.starts_with("HIERARCHY\nROOT pelvis\n"));
    let frames: usize = text
        .lines()
        .find_map(|l| l.strip_prefix("Frames: "))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(frames, 3 * 30 + 1);
}

#[test]
fn rapier_run_exports_a_glb_whose_animation_puts_the_head_where_physics_did() {
    // Same joint state, f32 storage: well under a millimetre.
    check_backend("rapier", 0.0005);
}

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_run_exports_a_glb_whose_animation_puts_the_head_where_physics_did() {
    // Body poses are brought to the new joint state after every step (they once
    // lagged it by one 120 Hz step, up to 2.5 cm): the same bound as rapier.
    check_backend("mujoco", 0.0005);
}

#[test]
fn view_writes_one_self_contained_page_or_says_how_to_build_the_bundle() {
    let dir = out_dir("view");
    record("rapier", &dir);
    // A stand-in bundle: this test checks the page assembly; the real bundle is
    // exercised in a browser by scripts/test-all.sh.
    let js = dir.join("fake-viewer.js");
    std::fs::write(&js, "console.log('viewer</script>');").unwrap();
    let page = dir.join("page.html");
    let o = Command::new(BIN)
        .args(["view", dir.to_str().unwrap(), "--write-html"])
        .arg(&page)
        .env("PLAMO_VIEWER_BUNDLE", &js)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("page.html"));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("window.PLAMO_DATA = {\"runs\":["));
    assert!(
        html.contains("console.log('viewer<\\/script>');"),
        "script end escaped"
    );
    // The GLB rides along as base64 ("glTF" = "Z2xURg").
    assert!(html.contains("\"glb\":\"Z2xURg"));
    assert!(html.contains("run from the tree to the car"));
    assert_eq!(html.matches("</script>").count(), 2);
    // The overlay's figures, per recorded frame: at the start the humanoid stands on
    // the plan's first point at standing head height, in its first instruction.
    let start = html.find("window.PLAMO_DATA = ").unwrap() + "window.PLAMO_DATA = ".len();
    let end = start + html[start..].find(";</script>").unwrap();
    let data: Value = serde_json::from_str(&html[start..end].replace("<\\/", "</")).unwrap();
    let agent = &data["runs"][0]["agents"][0];
    for key in ["t", "instruction", "speed", "head_height", "xy_err", "head"] {
        assert_eq!(agent[key].as_array().unwrap().len(), 3 * 30 + 1, "{key}");
    }
    assert_eq!(agent["instruction"][0], 0);
    assert!(
        agent["xy_err"][0].as_f64().unwrap() < 0.05,
        "{}",
        agent["xy_err"][0]
    );
    let h0 = agent["head_height"][0].as_f64().unwrap();
    assert!((h0 - 1.47).abs() < 0.05, "head height {h0}");
    let t = agent["t"].as_array().unwrap();
    assert_eq!(t.last().unwrap().as_f64(), Some(3.0));
    assert_eq!(data["runs"][0]["landmarks"].as_array().unwrap().len(), 6);

    let o = Command::new(BIN)
        .args(["view", dir.to_str().unwrap(), "--write-html"])
        .arg(&page)
        .env("PLAMO_VIEWER_BUNDLE", dir.join("missing.js"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("npm ci") && err.contains("npm run build"),
        "{err}"
    );
}

#[test]
fn export_of_a_directory_that_is_no_recording_names_the_missing_file() {
    let dir = out_dir("empty");
    std::fs::create_dir_all(&dir).unwrap();
    let o = run_plamo(&["export", dir.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("metrics.json") && err.contains("missing"),
        "{err}"
    );
    // A damaged trajectory names the file, line and column.
    let rec = out_dir("damaged");
    record("rapier", &rec);
    let csv = std::fs::read_to_string(rec.join("trajectory.csv")).unwrap();
    let mut lines: Vec<String> = csv.lines().map(str::to_string).collect();
    lines[3] = lines[3].replacen(",0,", ",0,x", 1);
    std::fs::write(rec.join("trajectory.csv"), lines.join("\n")).unwrap();
    let o = run_plamo(&["export", rec.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("trajectory.csv:4:"), "{err}");
}
