//! Recording a run under `--out DIR`: the trajectory and obstacle states per control
//! tick as CSV with exact (`{:?}`, shortest round-trip) f64 text, so two runs that
//! computed the same bits write byte-identical files; nothing wall-clock goes in them.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use plamo_interfaces::{PhysicsOutput, PlanMessage};
use plamo_physics::{JOINT_NAMES, NUM_JOINTS};

/// File name of the scene a recording ran on (the resolved scene as JSON), so exports
/// and the viewer rebuild the exact terrain and obstacles even for scenes from files.
pub const SCENE_FILE: &str = "scene.json";

/// Write the resolved scene into the recording directory as [`SCENE_FILE`].
pub fn write_scene(dir: &Path, scene: &plamo_scenes::Scene) -> std::io::Result<()> {
    let text = serde_json::to_string(scene).map_err(std::io::Error::other)?;
    std::fs::write(dir.join(SCENE_FILE), text)
}

/// One executed head sample: position and speed, for the map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadSample {
    /// Head x, y \[m\].
    pub xy: [f64; 2],
    /// Root horizontal speed \[m/s\].
    pub speed: f64,
}

/// Writes `trajectory.csv` and `obstacles.csv` and keeps each agent's head path.
pub struct Recorder {
    trajectory: BufWriter<File>,
    obstacles: BufWriter<File>,
    /// Executed head path per agent.
    pub heads: Vec<Vec<HeadSample>>,
    /// Plans rebuilt during the run: (agent, tick, message).
    pub replans: Vec<PlanMessage>,
}

impl Recorder {
    /// Create the files in `dir` for `agents` agents.
    pub fn create(dir: &Path, agents: usize) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut trajectory = BufWriter::new(File::create(dir.join("trajectory.csv"))?);
        let mut obstacles = BufWriter::new(File::create(dir.join("obstacles.csv"))?);
        write!(
            trajectory,
            "tick,agent,fallen,root_x,root_y,root_z,quat_x,quat_y,quat_z,quat_w,head_x,head_y,head_z"
        )?;
        for j in JOINT_NAMES.iter().take(NUM_JOINTS) {
            write!(trajectory, ",{j}")?;
        }
        writeln!(trajectory)?;
        writeln!(obstacles, "tick,index,x,y,z,vx,vy,vz")?;
        Ok(Self {
            trajectory,
            obstacles,
            heads: vec![Vec::new(); agents],
            replans: Vec::new(),
        })
    }

    /// Record the world at its tick; `fallen[k]`: the orchestrator's fall rule found
    /// agent k fallen in it (the rule the run's fall counts use, not the physics
    /// component's own flag).
    pub fn world(&mut self, w: &PhysicsOutput, fallen: &[bool]) -> std::io::Result<()> {
        for k in 0..w.agent_count as usize {
            let s = &w.agents[k];
            let f = fallen.get(k).copied().unwrap_or(false) as u8;
            write!(self.trajectory, "{},{},{f}", w.tick, k)?;
            for v in s
                .root_position
                .iter()
                .chain(&s.root_orientation)
                .chain(&s.head_position)
                .chain(&s.joint_angles[..(s.joint_count as usize).min(NUM_JOINTS)])
            {
                write!(self.trajectory, ",{v:?}")?;
            }
            writeln!(self.trajectory)?;
            if let Some(h) = self.heads.get_mut(k) {
                h.push(HeadSample {
                    xy: [s.head_position[0], s.head_position[1]],
                    speed: s.root_linear_velocity[0].hypot(s.root_linear_velocity[1]),
                });
            }
        }
        for (i, o) in w.obstacles[..w.obstacle_count as usize].iter().enumerate() {
            write!(self.obstacles, "{},{i}", w.tick)?;
            for v in o.position.iter().chain(&o.velocity) {
                write!(self.obstacles, ",{v:?}")?;
            }
            writeln!(self.obstacles)?;
        }
        Ok(())
    }

    /// Keep the plans that were rebuilt at this step.
    pub fn plans(&mut self, plans: &[PlanMessage]) {
        self.replans.extend(
            plans
                .iter()
                .filter(|p| p.flags & plamo_planner::FLAG_REPLANNED != 0),
        );
    }

    /// Flush the files.
    pub fn finish(&mut self) -> std::io::Result<()> {
        self.trajectory.flush()?;
        self.obstacles.flush()
    }
}
