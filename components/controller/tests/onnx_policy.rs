//! The ONNX policy: loading, shapes, normalisation, joint mapping, determinism and
//! clear errors, on tiny networks this test writes itself (Gemm + Tanh).

use std::path::{Path, PathBuf};

use plamo_controller::{
    Action, ControllerError, HumanoidSnapshot, NUM_WAYPOINTS, OBSERVATION_VERSION, Observation,
    ObservationLayout, OnnxPolicy, Policy, PolicySidecar, Waypoint,
};
use prost::Message;
use tract_onnx::pb;

const LAYOUT: ObservationLayout = ObservationLayout {
    num_joints: 3,
    num_bodies: 2,
};
const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("onnx_policy_{name}"));
    // Start empty: files left by an earlier run must not change the outcome.
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn value_info(name: &str, dims: &[i64]) -> pb::ValueInfoProto {
    use pb::tensor_shape_proto::{Dimension, dimension::Value};
    pb::ValueInfoProto {
        name: name.into(),
        r#type: Some(pb::TypeProto {
            denotation: String::new(),
            value: Some(pb::type_proto::Value::TensorType(pb::type_proto::Tensor {
                elem_type: pb::tensor_proto::DataType::Float as i32,
                shape: Some(pb::TensorShapeProto {
                    dim: dims
                        .iter()
                        .map(|d| Dimension {
                            denotation: String::new(),
                            value: Some(Value::DimValue(*d)),
                        })
                        .collect(),
                }),
            })),
        }),
        doc_string: String::new(),
    }
}

fn tensor(name: &str, dims: &[i64], data: Vec<f32>) -> pb::TensorProto {
    pb::TensorProto {
        name: name.into(),
        dims: dims.to_vec(),
        data_type: pb::tensor_proto::DataType::Float as i32,
        float_data: data,
        ..Default::default()
    }
}

/// Weights of `y = tanh(x W + b)` with `W: [n_in, n_out]`.
fn weights(n_in: usize, n_out: usize) -> (Vec<f32>, Vec<f32>) {
    let w = (0..n_in * n_out)
        .map(|i| ((i * 37 % 101) as f32 / 101.0 - 0.5) * 0.2)
        .collect();
    let b = (0..n_out).map(|j| 0.1 * j as f32 - 0.1).collect();
    (w, b)
}

/// Writes a Gemm + Tanh network to `path`.
fn write_model(path: &Path, n_in: usize, n_out: usize) {
    let (w, b) = weights(n_in, n_out);
    let node = |op: &str, inputs: &[&str], output: &str| pb::NodeProto {
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.into()],
        name: format!("{op}_0"),
        op_type: op.into(),
        ..Default::default()
    };
    let graph = pb::GraphProto {
        name: "policy".into(),
        node: vec![
            node("Gemm", &["obs", "W", "B"], "pre"),
            node("Tanh", &["pre"], "action"),
        ],
        initializer: vec![
            tensor("W", &[n_in as i64, n_out as i64], w),
            tensor("B", &[n_out as i64], b),
        ],
        input: vec![value_info("obs", &[1, n_in as i64])],
        output: vec![value_info("action", &[1, n_out as i64])],
        ..Default::default()
    };
    let model = pb::ModelProto {
        ir_version: 7,
        opset_import: vec![pb::OperatorSetIdProto {
            domain: String::new(),
            version: 13,
        }],
        producer_name: "plamo-controller test".into(),
        graph: Some(graph),
        ..Default::default()
    };
    std::fs::write(path, model.encode_to_vec()).unwrap();
}

fn sidecar() -> PolicySidecar {
    let n = LAYOUT.len();
    PolicySidecar {
        observation_version: OBSERVATION_VERSION,
        layout: LAYOUT,
        // The network's outputs drive the joints in another order than physics'.
        joint_names: vec!["ankle".into(), "hip".into(), "knee".into()],
        obs_mean: (0..n).map(|i| 0.01 * (i % 7) as f32).collect(),
        obs_std: (0..n).map(|i| 0.5 + 0.1 * (i % 5) as f32).collect(),
        obs_clip: Some(5.0),
        action_scale: vec![1.0, 0.5, 2.0],
        action_offset: vec![0.1, 0.0, -0.2],
    }
}

fn write_sidecar(path: &Path, s: &PolicySidecar) {
    std::fs::write(path, toml::to_string(s).unwrap()).unwrap();
}

fn observation() -> Observation {
    let snap = HumanoidSnapshot {
        root_pos: [1.0, 2.0, 0.92],
        root_quat: [0.96, 0.02, -0.03, 0.28],
        root_lin_vel: [1.1, 0.2, -0.05],
        root_ang_vel: [0.1, -0.2, 0.3],
        head_pos: [1.05, 2.0, 1.45],
        joint_pos: vec![0.3, -0.6, 0.1],
        joint_vel: vec![1.5, -2.0, 0.4],
        body_pos: vec![[1.0, 2.0, 0.92], [1.05, 2.0, 1.45]],
    };
    let plan: Vec<Waypoint> = (1..=NUM_WAYPOINTS)
        .map(|i| Waypoint {
            x: 1.0 + 0.6 * i as f64,
            y: 2.0 + 0.05 * i as f64,
            z: 1.47,
            v: 1.2,
        })
        .collect();
    let map = std::array::from_fn(|i| 0.01 * (i % 9) as f64);
    let mut obs = Observation::new(LAYOUT);
    obs.update_with_map(&snap, &plan, 0.0, &map).unwrap();
    obs
}

#[test]
fn loads_normalises_maps_joints_and_is_deterministic() {
    let d = dir("ok");
    let model = d.join("policy.onnx");
    write_model(&model, LAYOUT.len(), LAYOUT.num_joints);
    let sc = sidecar();
    write_sidecar(&d.join("policy.toml"), &sc);
    let mut policy = OnnxPolicy::load(&model, LAYOUT, &JOINTS).unwrap();
    assert_eq!(policy.name(), "onnx");

    let obs = observation();
    let mut a = Action::default();
    policy.act(&obs, &mut a).unwrap();
    assert_eq!(a.pd_targets.len(), 3);
    assert!(a.root_wrench.is_none());

    // The same computation by hand, in f64.
    let x: Vec<f64> = obs
        .flatten()
        .iter()
        .enumerate()
        .map(|(i, v)| ((*v - sc.obs_mean[i]) / sc.obs_std[i]).clamp(-5.0, 5.0) as f64)
        .collect();
    let (w, b) = weights(LAYOUT.len(), 3);
    let physics_index = [2, 0, 1]; // ankle, hip, knee
    for k in 0..3 {
        let pre: f64 = b[k] as f64
            + (0..x.len())
                .map(|i| x[i] * w[i * 3 + k] as f64)
                .sum::<f64>();
        let want = sc.action_offset[k] as f64 + sc.action_scale[k] as f64 * pre.tanh();
        let got = a.pd_targets[physics_index[k]];
        assert!((got - want).abs() < 1e-4, "output {k}: {got} vs {want}");
    }

    // Same input, same output, bit for bit; another instance agrees too.
    let mut b2 = Action::default();
    policy.act(&obs, &mut b2).unwrap();
    let mut other = OnnxPolicy::load(&model, LAYOUT, &JOINTS).unwrap();
    let mut c = Action::default();
    other.act(&obs, &mut c).unwrap();
    for j in 0..3 {
        assert_eq!(a.pd_targets[j].to_bits(), b2.pd_targets[j].to_bits());
        assert_eq!(a.pd_targets[j].to_bits(), c.pd_targets[j].to_bits());
    }
}

#[test]
fn json_sidecar_is_accepted() {
    let d = dir("json");
    let model = d.join("net.onnx");
    write_model(&model, LAYOUT.len(), 3);
    std::fs::write(
        d.join("net.json"),
        serde_json::to_string(&sidecar()).unwrap(),
    )
    .unwrap();
    OnnxPolicy::load(&model, LAYOUT, &JOINTS).unwrap();
}

#[test]
fn mismatches_are_clear_errors() {
    let d = dir("bad");
    let model = d.join("policy.onnx");
    write_model(&model, LAYOUT.len(), 3);
    let load = || OnnxPolicy::load(&model, LAYOUT, &JOINTS);

    let e = load().unwrap_err();
    assert!(matches!(e, ControllerError::SidecarMissing { .. }), "{e}");

    let mut sc = sidecar();
    sc.observation_version = OBSERVATION_VERSION + 1;
    write_sidecar(&d.join("policy.toml"), &sc);
    let e = load().unwrap_err();
    assert!(matches!(e, ControllerError::VersionMismatch { .. }), "{e}");
    assert!(e.to_string().contains("version"));

    let mut sc = sidecar();
    sc.obs_mean.pop();
    write_sidecar(&d.join("policy.toml"), &sc);
    let e = load().unwrap_err();
    assert!(
        matches!(
            e,
            ControllerError::WrongLength {
                what: "sidecar obs_mean",
                ..
            }
        ),
        "{e}"
    );

    let mut sc = sidecar();
    sc.joint_names[0] = "elbow".into();
    write_sidecar(&d.join("policy.toml"), &sc);
    let e = load().unwrap_err();
    assert!(e.to_string().contains("elbow"), "{e}");

    let mut sc = sidecar();
    sc.obs_std[4] = 0.0;
    write_sidecar(&d.join("policy.toml"), &sc);
    assert!(matches!(
        load().unwrap_err(),
        ControllerError::InvalidSettings {
            field: "obs_std",
            ..
        }
    ));

    // A network with 4 outputs for 3 joints.
    write_sidecar(&d.join("policy.toml"), &sidecar());
    write_model(&model, LAYOUT.len(), 4);
    let e = load().unwrap_err();
    assert!(
        matches!(
            e,
            ControllerError::WrongLength {
                what: "network output",
                expected: 3,
                got: 4
            }
        ),
        "{e}"
    );

    // A network expecting a longer observation: tract refuses the input shape.
    write_model(&model, LAYOUT.len() + 5, 3);
    let e = load().unwrap_err();
    assert!(matches!(e, ControllerError::Onnx { .. }), "{e}");

    // Garbage bytes.
    std::fs::write(&model, b"not a model").unwrap();
    assert!(matches!(
        load().unwrap_err(),
        ControllerError::Onnx { stage: "load", .. }
    ));
}
