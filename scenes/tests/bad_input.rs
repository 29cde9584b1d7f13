//! Bad scene files: every error names the file, the field path, the bad value and
//! what is allowed; mutated files never panic.

use plamo_scenes::{SceneError, from_toml_str};
use proptest::prelude::*;

const GOOD: &str = r#"
name = "t"
[terrain]
size = [10.0, 10.0]
[[terrain.tiles]]
area = { min = [4.0, 0.0], max = [6.0, 10.0] }
generator = { kind = "stairs", step_height = 0.1, step_depth = 0.4, symmetric = true }
[[walls]]
center = [5.0, 8.0]
size = [0.4, 3.0]
[[tops]]
center = [2.0, 5.0]
size = [2.0, 2.0]
clearance = 0.7
[[dynamic]]
name = "ball"
shape = { kind = "sphere", radius = 0.2 }
motion = { kind = "linear", from = [1.0, 1.0, 0.2], to = [9.0, 1.0, 0.2], speed = 1.0 }
[[landmarks]]
name = "a"
region = { kind = "circle", center = [1.5, 8.5], radius = 1.0 }
[[landmarks]]
name = "b"
region = { kind = "rect", center = [8.5, 5.0], size = [2.0, 2.0] }
[[landmarks]]
name = "c"
region = { kind = "circle", center = [8.5, 8.5], radius = 0.5 }
"#;

fn err(text: &str) -> String {
    match from_toml_str(text, "bad.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_names(msg: &str, parts: &[&str]) {
    assert!(msg.starts_with("bad.toml"), "{msg}");
    for p in parts {
        assert!(msg.contains(p), "{msg:?} lacks {p:?}");
    }
}

#[test]
fn the_good_file_loads() {
    let s = from_toml_str(GOOD, "good.toml").unwrap();
    assert_eq!(s.landmark_names(), vec!["a", "b", "c"]);
    assert!((s.tops[0].z_bottom - 0.7).abs() < 1e-12);
}

#[test]
fn negative_radius_names_its_path_value_and_range() {
    let m = err(&GOOD.replace("radius = 0.5", "radius = -0.5"));
    assert_names(&m, &["landmarks[2].region.radius", "-0.5", "> 0"]);
}

#[test]
fn nan_sizes_are_rejected() {
    let m = err(&GOOD.replace("size = [0.4, 3.0]", "size = [nan, 3.0]"));
    assert_names(&m, &["walls[0].size", "NaN", "> 0"]);
}

#[test]
fn unknown_keys_are_rejected_with_their_path() {
    let m = err(&GOOD.replace("clearance = 0.7", "clearance = 0.7\ncolour = \"red\""));
    assert_names(&m, &["tops[0]", "colour", "clearance"]);
    let m = err(&GOOD.replace("name = \"t\"", "name = \"t\"\nsky = 1"));
    assert_names(&m, &["sky", "terrain"]);
}

#[test]
fn wrong_types_name_the_field() {
    let m = err(&GOOD.replace("size = [10.0, 10.0]", "size = \"big\""));
    assert_names(&m, &["terrain.size", "big"]);
}

#[test]
fn overlapping_landmarks_are_rejected() {
    let m = err(&GOOD.replace(
        "center = [8.5, 8.5], radius = 0.5",
        "center = [8.5, 6.0], radius = 0.5",
    ));
    assert_names(&m, &["landmarks[2].region", "overlap", "landmarks[1]"]);
}

#[test]
fn landmarks_inside_walls_are_rejected() {
    let m = err(&GOOD.replace(
        "center = [8.5, 8.5], radius = 0.5",
        "center = [5.0, 8.0], radius = 0.5",
    ));
    assert_names(&m, &["landmarks[2].region", "walls[0]"]);
}

#[test]
fn obstacles_outside_the_terrain_are_rejected() {
    let m = err(&GOOD.replace("center = [5.0, 8.0]", "center = [12.0, 8.0]"));
    assert_names(&m, &["walls[0]", "inside the terrain", "x 0.00 ..= 10.00"]);
    let m = err(&GOOD.replace("to = [9.0, 1.0, 0.2]", "to = [19.0, 1.0, 0.2]"));
    assert_names(&m, &["dynamic[0].motion.to", "inside the terrain"]);
}

#[test]
fn unreachable_landmarks_are_rejected() {
    let walled = GOOD.replace(
        "[[walls]]\ncenter = [5.0, 8.0]\nsize = [0.4, 3.0]",
        "[[walls]]\ncenter = [7.0, 5.0]\nsize = [0.4, 10.0]",
    );
    let e = from_toml_str(&walled, "bad.toml").unwrap_err();
    assert!(matches!(e, SceneError::Unreachable { to: 1, .. }), "{e}");
    let m = e.to_string();
    assert_names(&m, &["landmarks[1]", "\"b\"", "crawling"]);
}

#[test]
fn too_low_ceilings_make_landmarks_unreachable() {
    // A ceiling over landmark b's only approach... here over b itself.
    let low = GOOD.replace(
        "center = [2.0, 5.0]\nsize = [2.0, 2.0]\nclearance = 0.7",
        "center = [8.5, 5.0]\nsize = [3.0, 9.9]\nclearance = 0.3",
    );
    assert!(matches!(
        from_toml_str(&low, "x").unwrap_err(),
        SceneError::Unreachable { .. }
    ));
}

#[test]
fn bad_generator_parameters_name_the_tile() {
    let m = err(&GOOD.replace("step_height = 0.1", "step_height = 0.9"));
    assert_names(
        &m,
        &["terrain.tiles[0].generator.step_height", "0.9", "<= 0.5"],
    );
    let m = err(&GOOD.replace("kind = \"stairs\"", "kind = \"lava\""));
    assert_names(&m, &["terrain.tiles[0]", "lava"]);
}

#[test]
fn duplicate_landmark_names_are_rejected() {
    let m = err(&GOOD.replace("name = \"c\"", "name = \"A\""));
    assert_names(&m, &["landmarks[2].name", "landmarks[0]"]);
}

#[test]
fn inline_grid_rows_must_agree() {
    let text = "name = \"g\"\n[terrain]\ngrid = { kind = \"inline\", heights = [[0.0, 0.1, 0.2], [0.0, 0.1]] }\n";
    let m = err(text);
    assert_names(&m, &["terrain.grid.heights[1]", "2 values", "3 values"]);
}

#[test]
fn png_height_maps_load_with_their_scale() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (nx, ny) = (11, 6);
    let values: Vec<u16> = (0..nx * ny).map(|k| (k % nx) as u16 * 100).collect();
    plamo_scenes::write_height_png(&dir.join("h.png"), nx, ny, &values).unwrap();
    let toml = "name = \"png\"\n[terrain]\nresolution = 0.5\ngrid = { kind = \"png\", path = \"h.png\", scale = 0.001, offset = -0.1 }\n";
    std::fs::write(dir.join("s.toml"), toml).unwrap();
    let s = plamo_scenes::load(&dir.join("s.toml")).unwrap();
    assert_eq!((s.terrain.nx, s.terrain.ny), (11, 6));
    assert!((s.height_at(5.0, 1.0) - (-0.1 + 0.001 * 1000.0)).abs() < 1e-9);
    assert_eq!(s.terrain.bounds().1, [5.0, 2.5]);
    let missing = toml.replace("h.png", "nope.png");
    std::fs::write(dir.join("m.toml"), missing).unwrap();
    let m = plamo_scenes::load(&dir.join("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        m.contains("terrain.grid.path") && m.contains("nope.png"),
        "{m}"
    );
}

#[test]
fn unknown_extensions_and_names_are_explained() {
    let m = plamo_scenes::load(std::path::Path::new("scene.yaml"))
        .unwrap_err()
        .to_string();
    assert!(m.contains("scene.yaml") && m.contains(".toml"), "{m}");
    let m = plamo_scenes::resolve("nowhere").unwrap_err().to_string();
    assert!(m.contains("nowhere") && m.contains("playground"), "{m}");
    let m = plamo_scenes::resolve("random-x").unwrap_err().to_string();
    assert!(m.contains("random-x") && m.contains("random-<seed>"), "{m}");
}

#[test]
fn random_scenes_resolve_by_their_names() {
    let s = plamo_scenes::resolve("random-7").unwrap();
    let r = plamo_scenes::random_scene(7);
    assert_eq!(s.name, "random-7");
    assert_eq!(s.landmarks.len(), r.landmarks.len());
    assert_eq!(
        s.height_at(3.3, 12.1).to_bits(),
        r.height_at(3.3, 12.1).to_bits()
    );
    let other = plamo_scenes::resolve("random-8").unwrap();
    assert_ne!(other.landmarks[0].region, s.landmarks[0].region);
}

#[derive(Debug, Clone)]
enum Mutation {
    FlipByte(usize, u8),
    DeleteLine(usize),
    SwapNumbers(usize, usize),
    ReplaceNumber(usize, &'static str),
}

fn mutate(text: &str, m: &Mutation) -> String {
    match *m {
        Mutation::FlipByte(at, bits) => {
            let mut b = text.as_bytes().to_vec();
            let k = at % b.len();
            b[k] ^= bits.max(1);
            String::from_utf8_lossy(&b).into_owned()
        }
        Mutation::DeleteLine(at) => {
            let lines: Vec<&str> = text.lines().collect();
            let k = at % lines.len();
            lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| *l)
                .collect::<Vec<_>>()
                .join("\n")
        }
        Mutation::SwapNumbers(a, b) => {
            let nums = numbers(text);
            let (a, b) = (nums[a % nums.len()], nums[b % nums.len()]);
            let (first, second) = if a.0 < b.0 { (a, b) } else { (b, a) };
            if first.0 == second.0 {
                return text.to_string();
            }
            format!(
                "{}{}{}{}{}",
                &text[..first.0],
                &text[second.0..second.1],
                &text[first.1..second.0],
                &text[first.0..first.1],
                &text[second.1..]
            )
        }
        Mutation::ReplaceNumber(a, with) => {
            let nums = numbers(text);
            let (s, e) = nums[a % nums.len()];
            format!("{}{}{}", &text[..s], with, &text[e..])
        }
    }
}

/// Byte ranges of the numbers in the text.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut v = Vec::new();
    let mut k = 0;
    while k < b.len() {
        if b[k].is_ascii_digit() || (b[k] == b'-' && k + 1 < b.len() && b[k + 1].is_ascii_digit()) {
            let s = k;
            k += 1;
            while k < b.len() && (b[k].is_ascii_digit() || b[k] == b'.') {
                k += 1;
            }
            v.push((s, k));
        } else {
            k += 1;
        }
    }
    v
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::FlipByte(a, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapNumbers(a, b)),
        (
            any::<usize>(),
            prop::sample::select(vec![
                "-1", "0", "1e9", "nan", "inf", "-inf", "0.0001", "1e300"
            ])
        )
            .prop_map(|(a, w)| Mutation::ReplaceNumber(a, w)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_never_panic(ms in prop::collection::vec(mutation(), 1..4)) {
        let mut text = GOOD.to_string();
        for m in &ms {
            text = mutate(&text, m);
        }
        // Ok or a typed error, never a panic; an error always names the origin.
        if let Err(e) = from_toml_str(&text, "mutant.toml") {
            prop_assert!(e.to_string().starts_with("mutant.toml"), "{}", e);
        }
    }

    #[test]
    fn mutated_builtins_never_panic(m in mutation(), k in 0usize..7) {
        let name = plamo_scenes::builtin_names()[k];
        let text = mutate(plamo_scenes::builtin_source(name).unwrap(), &m);
        let _ = from_toml_str(&text, "mutant.toml");
    }
}
