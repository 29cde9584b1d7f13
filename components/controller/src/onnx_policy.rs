//! A learned policy loaded from ONNX with tract (pure Rust).
//!
//! Next to `policy.onnx` sits a sidecar, `policy.toml` (or `policy.json`), that pins
//! what the network was trained with ([`PolicySidecar`]): the observation version and
//! sizes, the joint order of its outputs, observation normalisation and action
//! scaling. The network takes one `f32` input of shape `[1, obs_len]` (the normalised
//! flattened [`Observation`]) and returns `[1, num_joints]`; the PD target of joint j
//! is `action_offset[j] + action_scale[j] * output[j]`.

use std::path::{Path, PathBuf};

use tract_onnx::prelude::{
    Framework, InferenceFact, InferenceModelExt, Tensor, TypedModel, TypedRunnableModel, tvec,
};

use crate::error::{ControllerError, Result, check_finite};
use crate::observation::{OBSERVATION_VERSION, Observation, ObservationLayout};
use crate::policy::{Action, Policy};

/// The sidecar file describing a network's interface.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolicySidecar {
    /// [`OBSERVATION_VERSION`] the network was trained with.
    pub observation_version: u32,
    /// Observation sizes the network was trained with.
    pub layout: ObservationLayout,
    /// Joint names in the network's output order (each must be a physics joint).
    pub joint_names: Vec<String>,
    /// Per-entry observation mean (length = observation length).
    pub obs_mean: Vec<f32>,
    /// Per-entry observation standard deviation, all > 0.
    pub obs_std: Vec<f32>,
    /// Clip of the normalised observation (absolute value), if any.
    #[serde(default)]
    pub obs_clip: Option<f32>,
    /// Per-output action scale \[rad\].
    pub action_scale: Vec<f32>,
    /// Per-output action offset \[rad\].
    pub action_offset: Vec<f32>,
}

impl PolicySidecar {
    /// Reads a sidecar: TOML for `.toml`, JSON for `.json`.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| ControllerError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        if path.extension().is_some_and(|e| e == "json") {
            serde_json::from_str(&text).map_err(|source| ControllerError::Json {
                path: path.to_path_buf(),
                source,
            })
        } else {
            toml::from_str(&text).map_err(|source| ControllerError::Toml {
                path: path.to_path_buf(),
                source,
            })
        }
    }

    /// Checks the sidecar against this controller's observation version, the
    /// humanoid's layout and joint names; returns, for each network output, the
    /// physics joint index it drives.
    pub fn validate(&self, layout: ObservationLayout, joint_names: &[&str]) -> Result<Vec<usize>> {
        if self.observation_version != OBSERVATION_VERSION {
            return Err(ControllerError::VersionMismatch {
                expected: OBSERVATION_VERSION,
                found: self.observation_version,
            });
        }
        let len_check = |what: &'static str, expected: usize, got: usize| {
            if expected == got {
                Ok(())
            } else {
                Err(ControllerError::WrongLength {
                    what,
                    expected,
                    got,
                })
            }
        };
        len_check(
            "sidecar layout.num_joints",
            layout.num_joints,
            self.layout.num_joints,
        )?;
        len_check(
            "sidecar layout.num_bodies",
            layout.num_bodies,
            self.layout.num_bodies,
        )?;
        len_check("humanoid joint names", layout.num_joints, joint_names.len())?;
        let n_obs = layout.len();
        len_check("sidecar obs_mean", n_obs, self.obs_mean.len())?;
        len_check("sidecar obs_std", n_obs, self.obs_std.len())?;
        len_check(
            "sidecar joint_names",
            layout.num_joints,
            self.joint_names.len(),
        )?;
        len_check(
            "sidecar action_scale",
            layout.num_joints,
            self.action_scale.len(),
        )?;
        len_check(
            "sidecar action_offset",
            layout.num_joints,
            self.action_offset.len(),
        )?;
        check_finite("sidecar obs_mean", &self.obs_mean)?;
        check_finite("sidecar action_scale", &self.action_scale)?;
        check_finite("sidecar action_offset", &self.action_offset)?;
        if let Some(i) = self
            .obs_std
            .iter()
            .position(|s| !(s.is_finite() && *s > 0.0))
        {
            return Err(ControllerError::InvalidSettings {
                field: "obs_std",
                reason: format!("entry {i} is {}, must be finite and > 0", self.obs_std[i]),
            });
        }
        let mut map = Vec::with_capacity(self.joint_names.len());
        for name in &self.joint_names {
            let idx = joint_names.iter().position(|j| j == name).ok_or_else(|| {
                ControllerError::JointMismatch {
                    reason: format!("policy joint `{name}` is not a humanoid joint"),
                }
            })?;
            if map.contains(&idx) {
                return Err(ControllerError::JointMismatch {
                    reason: format!("policy joint `{name}` is listed twice"),
                });
            }
            map.push(idx);
        }
        Ok(map)
    }
}

/// A learned policy: an ONNX network plus its sidecar.
#[derive(Debug)]
pub struct OnnxPolicy {
    path: PathBuf,
    plan: TypedRunnableModel<TypedModel>,
    sidecar: PolicySidecar,
    output_to_joint: Vec<usize>,
    input: Vec<f32>,
}

impl OnnxPolicy {
    /// The sidecar paths tried for `model`, in order.
    pub fn sidecar_candidates(model: &Path) -> [PathBuf; 2] {
        [model.with_extension("toml"), model.with_extension("json")]
    }

    /// Loads `model` and its sidecar, checks them against `layout` and the humanoid's
    /// `joint_names` (physics order), and runs the network once to check its output
    /// shape.
    pub fn load(model: &Path, layout: ObservationLayout, joint_names: &[&str]) -> Result<Self> {
        let tried = Self::sidecar_candidates(model);
        let sidecar_path = tried.iter().find(|p| p.is_file()).cloned().ok_or_else(|| {
            ControllerError::SidecarMissing {
                model: model.to_path_buf(),
                tried: tried.to_vec(),
            }
        })?;
        let sidecar = PolicySidecar::read(&sidecar_path)?;
        let output_to_joint = sidecar.validate(layout, joint_names)?;
        let n_obs = layout.len();
        let onnx_err = |stage: &'static str| {
            let path = model.to_path_buf();
            move |e: tract_onnx::prelude::TractError| ControllerError::Onnx {
                path,
                stage,
                source: e.into(),
            }
        };
        let plan = tract_onnx::onnx()
            .model_for_path(model)
            .map_err(onnx_err("load"))?
            .with_input_fact(
                0,
                InferenceFact::dt_shape(f32::datum_type(), tvec![1usize, n_obs]),
            )
            .map_err(onnx_err("input shape"))?
            .into_optimized()
            .map_err(onnx_err("optimise"))?
            .into_runnable()
            .map_err(onnx_err("plan"))?;
        let policy = Self {
            path: model.to_path_buf(),
            plan,
            sidecar,
            output_to_joint,
            input: vec![0.0; n_obs],
        };
        let out = policy.run_network()?;
        if out.len() != layout.num_joints {
            return Err(ControllerError::WrongLength {
                what: "network output",
                expected: layout.num_joints,
                got: out.len(),
            });
        }
        Ok(policy)
    }

    /// The sidecar the policy was loaded with.
    pub fn sidecar(&self) -> &PolicySidecar {
        &self.sidecar
    }

    /// Runs the network on `self.input` (already normalised).
    fn run_network(&self) -> Result<Vec<f32>> {
        let err = |stage: &'static str, path: &Path| {
            let path = path.to_path_buf();
            move |e: tract_onnx::prelude::TractError| ControllerError::Onnx {
                path,
                stage,
                source: e.into(),
            }
        };
        let input = Tensor::from_shape(&[1, self.input.len()], &self.input)
            .map_err(err("input tensor", &self.path))?;
        let out = self
            .plan
            .run(tvec!(input.into()))
            .map_err(err("run", &self.path))?;
        let view = out[0]
            .as_slice::<f32>()
            .map_err(err("read output", &self.path))?;
        Ok(view.to_vec())
    }
}

use tract_onnx::prelude::Datum;

impl Policy for OnnxPolicy {
    fn act(&mut self, obs: &Observation, out: &mut Action) -> Result<()> {
        let layout = obs.layout();
        if layout != self.sidecar.layout {
            return Err(ControllerError::WrongLength {
                what: "observation (layout differs from the policy's)",
                expected: self.sidecar.layout.len(),
                got: layout.len(),
            });
        }
        obs.flatten_into(&mut self.input)?;
        let s = &self.sidecar;
        for ((x, m), sd) in self.input.iter_mut().zip(&s.obs_mean).zip(&s.obs_std) {
            let mut v = (*x - m) / sd;
            if let Some(c) = s.obs_clip {
                v = v.clamp(-c, c);
            }
            *x = v;
        }
        let y = self.run_network()?;
        check_finite("network output", &y)?;
        out.pd_targets.resize(layout.num_joints, 0.0);
        for (k, &j) in self.output_to_joint.iter().enumerate() {
            out.pd_targets[j] = f64::from(s.action_offset[k] + s.action_scale[k] * y[k]);
        }
        out.root_wrench = None;
        Ok(())
    }

    fn name(&self) -> &str {
        "onnx"
    }
}
