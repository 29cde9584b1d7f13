//! Reading a recording directory back: the exact f64 text of trajectory.csv and
//! obstacles.csv, the plans, the per-instruction results and the scene.

use std::path::{Path, PathBuf};

use plamo_interfaces::Tick;
use plamo_physics::NUM_JOINTS;
use plamo_scenes::Scene;
use serde::Deserialize;

use super::ExportError;
use crate::record::SCENE_FILE;

/// One agent's state at one control tick.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentFrame {
    /// Physics tick.
    pub tick: u64,
    /// Whether the agent counted as fallen.
    pub fallen: bool,
    /// Pelvis position \[m\].
    pub root: [f64; 3],
    /// Pelvis orientation (x, y, z, w).
    pub quat: [f64; 4],
    /// Head centre \[m\].
    pub head: [f64; 3],
    /// Joint angles in `JOINT_NAMES` order \[rad\].
    pub joints: [f64; NUM_JOINTS],
}

/// One moving obstacle's state at one control tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObstacleFrame {
    /// Physics tick.
    pub tick: u64,
    /// Centre \[m\].
    pub position: [f64; 3],
    /// Velocity \[m/s\].
    pub velocity: [f64; 3],
}

/// One point of a planned route.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedPoint {
    /// Position x, y and planned head height z (ground + head height) \[m\].
    pub pos: [f64; 3],
    /// Planned speed \[m/s\].
    pub v: f64,
    /// Time from the start of its instruction \[s\].
    pub t: f64,
}

/// One agent of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct AgentTrack {
    /// Frames in tick order.
    pub frames: Vec<AgentFrame>,
    /// Instruction texts.
    pub instructions: Vec<String>,
    /// Simulated time at which each instruction became current \[s\]
    /// (`f64::INFINITY` for one never reached).
    pub instruction_starts: Vec<f64>,
    /// The route as first planned, one polyline per instruction.
    pub route: Vec<Vec<PlannedPoint>>,
}

/// A recorded run, read back from its directory.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The directory.
    pub dir: PathBuf,
    /// The scene it ran on.
    pub scene: Scene,
    /// Physics backend name.
    pub physics: String,
    /// Run status ("finished", "timed out").
    pub status: String,
    /// Agents.
    pub agents: Vec<AgentTrack>,
    /// Moving obstacles: frames per obstacle index.
    pub obstacles: Vec<Vec<ObstacleFrame>>,
}

#[derive(Deserialize)]
struct MetricsFile {
    scene: String,
    physics: String,
    status: String,
    agents: Vec<MetricsAgent>,
}

#[derive(Deserialize)]
struct MetricsAgent {
    instructions: Vec<String>,
    results: Vec<MetricsResult>,
}

#[derive(Deserialize)]
struct MetricsResult {
    reached: bool,
    time_s: f64,
}

#[derive(Deserialize)]
struct PlansFile {
    initial: Vec<PlansAgent>,
}

#[derive(Deserialize)]
struct PlansAgent {
    route: Vec<PlansTrajectory>,
}

#[derive(Deserialize)]
struct PlansTrajectory {
    points: Vec<PlansPoint>,
}

#[derive(Deserialize)]
struct PlansPoint {
    x: f64,
    y: f64,
    ground: f64,
    head_height: f64,
    v: f64,
    t: f64,
}

fn read(path: &Path) -> Result<String, ExportError> {
    std::fs::read_to_string(path).map_err(|source| {
        if source.kind() == std::io::ErrorKind::NotFound {
            ExportError::Missing {
                path: path.to_path_buf(),
            }
        } else {
            ExportError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
    })
}

fn json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, ExportError> {
    serde_json::from_str(&read(path)?).map_err(|source| ExportError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// Parses the comma-separated fields of CSV files with a known header.
struct Csv<'a> {
    path: &'a Path,
    line: usize,
}

impl Csv<'_> {
    fn err(&self, message: String) -> ExportError {
        ExportError::Csv {
            path: self.path.to_path_buf(),
            line: self.line,
            message,
        }
    }
    fn f64(&self, field: Option<&str>, name: &str) -> Result<f64, ExportError> {
        let s = field.ok_or_else(|| self.err(format!("missing column `{name}`")))?;
        s.parse()
            .map_err(|_| self.err(format!("`{name}` = `{s}` is not a number")))
    }
    fn u64(&self, field: Option<&str>, name: &str) -> Result<u64, ExportError> {
        let s = field.ok_or_else(|| self.err(format!("missing column `{name}`")))?;
        s.parse().map_err(|_| {
            self.err(format!(
                "`{name}` = `{s}` is not a non-negative whole number"
            ))
        })
    }
}

impl Recording {
    /// Read the recording in `dir`.
    pub fn load(dir: &Path) -> Result<Self, ExportError> {
        let metrics: MetricsFile = json(&dir.join("metrics.json"))?;
        let plans: PlansFile = json(&dir.join("plans.json"))?;
        let scene_path = dir.join(SCENE_FILE);
        let scene: Scene = if scene_path.exists() {
            json(&scene_path)?
        } else {
            // Recordings from before scene.json existed: the scene by its name.
            plamo_scenes::resolve(&metrics.scene).map_err(|e| {
                ExportError::Scene(format!(
                    "{} is missing and `{}` is not a built-in scene: {e}",
                    scene_path.display(),
                    metrics.scene
                ))
            })?
        };

        let mut agents: Vec<AgentTrack> = metrics
            .agents
            .iter()
            .enumerate()
            .map(|(k, a)| {
                let mut starts = Vec::with_capacity(a.results.len());
                let mut t = 0.0;
                for r in &a.results {
                    starts.push(t);
                    t = if r.reached {
                        t + r.time_s
                    } else {
                        f64::INFINITY
                    };
                }
                let route = plans
                    .initial
                    .get(k)
                    .map(|p| {
                        p.route
                            .iter()
                            .map(|tr| {
                                tr.points
                                    .iter()
                                    .map(|q| PlannedPoint {
                                        pos: [q.x, q.y, q.ground + q.head_height],
                                        v: q.v,
                                        t: q.t,
                                    })
                                    .collect()
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                AgentTrack {
                    frames: Vec::new(),
                    instructions: a.instructions.clone(),
                    instruction_starts: starts,
                    route,
                }
            })
            .collect();

        let tpath = dir.join("trajectory.csv");
        let text = read(&tpath)?;
        let mut csv = Csv {
            path: &tpath,
            line: 1,
        };
        for line in text.lines().skip(1) {
            csv.line += 1;
            let mut f = line.split(',');
            let tick = csv.u64(f.next(), "tick")?;
            let agent = csv.u64(f.next(), "agent")? as usize;
            let fallen = match f.next() {
                Some("1" | "true") => true,
                Some("0" | "false") => false,
                other => {
                    return Err(csv.err(format!(
                        "`fallen` = `{}`: expected 0 or 1",
                        other.unwrap_or("")
                    )));
                }
            };
            let mut v = [0.0; 10 + NUM_JOINTS];
            for (i, x) in v.iter_mut().enumerate() {
                *x = csv.f64(f.next(), &format!("column {}", i + 4))?;
            }
            let track = agents.get_mut(agent).ok_or_else(|| {
                csv.err(format!(
                    "agent {agent}, but metrics.json lists {} agent(s)",
                    metrics.agents.len()
                ))
            })?;
            let mut joints = [0.0; NUM_JOINTS];
            joints.copy_from_slice(&v[10..]);
            track.frames.push(AgentFrame {
                tick,
                fallen,
                root: [v[0], v[1], v[2]],
                quat: [v[3], v[4], v[5], v[6]],
                head: [v[7], v[8], v[9]],
                joints,
            });
        }
        if agents.iter().any(|a| a.frames.is_empty()) {
            return Err(ExportError::Empty(tpath));
        }

        let opath = dir.join("obstacles.csv");
        let text = read(&opath)?;
        let mut csv = Csv {
            path: &opath,
            line: 1,
        };
        let mut obstacles: Vec<Vec<ObstacleFrame>> = Vec::new();
        for line in text.lines().skip(1) {
            csv.line += 1;
            let mut f = line.split(',');
            let tick = csv.u64(f.next(), "tick")?;
            let index = csv.u64(f.next(), "index")? as usize;
            let mut v = [0.0; 6];
            for (i, x) in v.iter_mut().enumerate() {
                *x = csv.f64(f.next(), &format!("column {}", i + 3))?;
            }
            if index >= scene.dynamic.len() {
                return Err(csv.err(format!(
                    "obstacle {index}, but the scene has {} moving obstacle(s)",
                    scene.dynamic.len()
                )));
            }
            if obstacles.len() <= index {
                obstacles.resize(index + 1, Vec::new());
            }
            obstacles[index].push(ObstacleFrame {
                tick,
                position: [v[0], v[1], v[2]],
                velocity: [v[3], v[4], v[5]],
            });
        }

        Ok(Self {
            dir: dir.to_path_buf(),
            scene,
            physics: metrics.physics,
            status: metrics.status,
            agents,
            obstacles,
        })
    }

    /// Simulated time of a tick \[s\].
    pub fn time(tick: u64) -> f64 {
        Tick(tick).seconds()
    }
}
