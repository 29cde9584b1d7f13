//! The MuJoCo backend: MuJoCo 3.17.0 through mujoco-rs 7.0.0 (cargo feature
//! `mujoco`), implicitfast integrator at 1/120 s.
//!
//! - `mjcf.rs`: the MJCF written from the humanoid description and the scene.
//! - this file: layout lookups, stepping, state read-back.
//!
//! Everything goes through mujoco-rs's safe API; this module has no `unsafe`.

mod mjcf;

use mujoco_rs::prelude::*;
use plamo_interfaces::Tick;
use plamo_scenes::{ObstacleState, Scene};

pub use mjcf::humanoid_mjcf;

use crate::humanoid::{HEAD, HEAD_OFFSET, JOINT_NAMES, PELVIS};
use crate::obstacles::ObstacleMotions;
use crate::state::sanitize_action;
use crate::{
    BODY_NAMES, BackendKind, HumanoidPose, HumanoidState, NUM_BODIES, NUM_JOINTS, PhysicsBackend,
    PhysicsError, PhysicsSettings, RootWrench, math,
};

/// Where one humanoid lives in MuJoCo's arrays.
struct Layout {
    root_qpos: usize,
    root_dof: usize,
    joint_qpos: [usize; NUM_JOINTS],
    joint_dof: [usize; NUM_JOINTS],
    ctrl: [usize; NUM_JOINTS],
    body: [usize; NUM_BODIES],
}

/// The MuJoCo implementation of [`PhysicsBackend`].
pub struct MujocoBackend {
    data: MjData<Box<MjModel>>,
    settings: PhysicsSettings,
    layouts: Vec<Layout>,
    /// geom id -> (humanoid, body) for humanoid geoms.
    geom_owner: Vec<Option<(usize, usize)>>,
    terrain_geom: usize,
    /// Mocap index of each dynamic obstacle.
    mocap: Vec<usize>,
    states: Vec<HumanoidState>,
    obstacles: Vec<ObstacleState>,
    motions: ObstacleMotions,
    tick: Tick,
    bad_qacc_warnings: i32,
    diverged: Vec<bool>,
}

fn model_error(reason: String) -> PhysicsError {
    PhysicsError::Model {
        backend: BackendKind::Mujoco,
        reason,
    }
}

fn id(model: &MjModel, kind: MjtObjBase, name: &str) -> Result<usize, PhysicsError> {
    model
        .name_to_id(kind, name)
        .ok_or_else(|| model_error(format!("generated model lacks `{name}`")))
}

impl MujocoBackend {
    /// Build the world for `scene` (humanoid placement as in the rapier backend).
    pub fn new(scene: &Scene, settings: &PhysicsSettings) -> Result<Self, PhysicsError> {
        settings.validate()?;
        // Terrain checks are shared with rapier's builder.
        crate::rapier::validate_terrain(scene)?;
        let poses: Vec<HumanoidPose> = (0..settings.humanoids)
            .map(|i| crate::rapier::default_pose(scene, i))
            .collect();
        let roots: Vec<[f64; 3]> = poses.iter().map(|p| p.root_position).collect();
        let xml = mjcf::world_mjcf(scene, settings, &roots);
        let mut model = MjModel::from_xml_string(&xml).map_err(|e| model_error(e.to_string()))?;
        // Height field samples, normalised to 0..1 of the range.
        let (_, zmin, range) = mjcf::hfield_frame(scene);
        {
            let hdata = model.hfield_data_mut();
            if hdata.len() != scene.terrain.heights.len() {
                return Err(model_error(format!(
                    "height field has {} samples, scene has {}",
                    hdata.len(),
                    scene.terrain.heights.len()
                )));
            }
            for (d, h) in hdata.iter_mut().zip(&scene.terrain.heights) {
                *d = ((h - zmin) / range) as f32;
            }
        }
        let mut layouts = Vec::with_capacity(settings.humanoids);
        for h in 0..settings.humanoids {
            let p = mjcf::prefix(h);
            let jq = model.jnt_qposadr();
            let jd = model.jnt_dofadr();
            let root = id(&model, MjtObjBase::mjOBJ_JOINT, &format!("{p}root"))?;
            let mut l = Layout {
                root_qpos: jq[root] as usize,
                root_dof: jd[root] as usize,
                joint_qpos: [0; NUM_JOINTS],
                joint_dof: [0; NUM_JOINTS],
                ctrl: [0; NUM_JOINTS],
                body: [0; NUM_BODIES],
            };
            for (ji, name) in JOINT_NAMES.iter().enumerate() {
                let j = id(&model, MjtObjBase::mjOBJ_JOINT, &format!("{p}{name}"))?;
                l.joint_qpos[ji] = jq[j] as usize;
                l.joint_dof[ji] = jd[j] as usize;
                l.ctrl[ji] = id(&model, MjtObjBase::mjOBJ_ACTUATOR, &format!("{p}{name}"))?;
            }
            for (bi, name) in BODY_NAMES.iter().enumerate() {
                l.body[bi] = id(&model, MjtObjBase::mjOBJ_BODY, &format!("{p}{name}"))?;
            }
            layouts.push(l);
        }
        let mut geom_owner = vec![None; model.geom_bodyid().len()];
        for (g, &b) in model.geom_bodyid().iter().enumerate() {
            for (h, l) in layouts.iter().enumerate() {
                if let Some(bi) = l.body.iter().position(|&x| x == b as usize) {
                    geom_owner[g] = Some((h, bi));
                }
            }
        }
        let terrain_geom = id(&model, MjtObjBase::mjOBJ_GEOM, mjcf::TERRAIN)?;
        let mut mocap = Vec::with_capacity(scene.dynamic.len());
        for k in 0..scene.dynamic.len() {
            let b = id(&model, MjtObjBase::mjOBJ_BODY, &format!("obstacle{k}"))?;
            mocap.push(model.body_mocapid()[b] as usize);
        }
        let data = MjData::new(Box::new(model));
        let motions = ObstacleMotions::new(scene);
        let obstacles = motions.states_at(0.0).collect();
        let mut backend = Self {
            data,
            settings: settings.clone(),
            states: vec![HumanoidState::default(); layouts.len()],
            diverged: vec![false; layouts.len()],
            layouts,
            geom_owner,
            terrain_geom,
            mocap,
            obstacles,
            motions,
            tick: Tick(0),
            bad_qacc_warnings: 0,
        };
        for (i, pose) in poses.iter().enumerate() {
            backend.write_pose(i, pose);
        }
        backend.data.forward();
        backend.read_states(false);
        Ok(backend)
    }

    /// Write a humanoid's pose into qpos/qvel/ctrl (no forward pass).
    fn write_pose(&mut self, i: usize, pose: &HumanoidPose) {
        let l = &self.layouts[i];
        let q = pose.root_quat();
        let joints = pose.clamped_joints();
        let qpos = self.data.qpos_mut();
        qpos[l.root_qpos..l.root_qpos + 3].copy_from_slice(&pose.root_position);
        qpos[l.root_qpos + 3..l.root_qpos + 7].copy_from_slice(&q);
        for ji in 0..NUM_JOINTS {
            qpos[l.joint_qpos[ji]] = joints[ji];
        }
        let qvel = self.data.qvel_mut();
        qvel[l.root_dof..l.root_dof + 6].fill(0.0);
        for ji in 0..NUM_JOINTS {
            qvel[l.joint_dof[ji]] = 0.0;
        }
        let warm = self.data.qacc_warmstart_mut();
        warm[l.root_dof..l.root_dof + 6].fill(0.0);
        for ji in 0..NUM_JOINTS {
            warm[l.joint_dof[ji]] = 0.0;
        }
        let ctrl = self.data.ctrl_mut();
        for ji in 0..NUM_JOINTS {
            ctrl[l.ctrl[ji]] = joints[ji];
        }
        let pelvis = l.body[PELVIS];
        self.data.xfrc_applied_mut()[pelvis] = [0.0; 6];
    }

    fn read_states(&mut self, with_contacts: bool) {
        let qpos = self.data.qpos();
        let qvel = self.data.qvel();
        let xpos = self.data.xpos();
        let xquat = self.data.xquat();
        for (l, s) in self.layouts.iter().zip(self.states.iter_mut()) {
            s.root_position
                .copy_from_slice(&qpos[l.root_qpos..l.root_qpos + 3]);
            s.root_quat
                .copy_from_slice(&qpos[l.root_qpos + 3..l.root_qpos + 7]);
            s.root_linvel
                .copy_from_slice(&qvel[l.root_dof..l.root_dof + 3]);
            // The free joint's angular velocity is in the body frame.
            s.root_angvel = math::rotate(
                s.root_quat,
                [
                    qvel[l.root_dof + 3],
                    qvel[l.root_dof + 4],
                    qvel[l.root_dof + 5],
                ],
            );
            for ji in 0..NUM_JOINTS {
                s.joint_pos[ji] = qpos[l.joint_qpos[ji]];
                s.joint_vel[ji] = qvel[l.joint_dof[ji]];
            }
            for bi in 0..NUM_BODIES {
                s.body_pos[bi] = xpos[l.body[bi]];
            }
            s.head = math::transform(xpos[l.body[HEAD]], xquat[l.body[HEAD]], HEAD_OFFSET);
            s.contact = [false; NUM_BODIES];
            s.terrain_contact = [false; NUM_BODIES];
        }
        if !with_contacts {
            return;
        }
        for c in self.data.contact() {
            if c.exclude != 0 {
                continue;
            }
            let (g1, g2) = (c.geom[0] as usize, c.geom[1] as usize);
            for (g, other) in [(g1, g2), (g2, g1)] {
                if let Some((h, bi)) = self.geom_owner.get(g).copied().flatten() {
                    self.states[h].contact[bi] = true;
                    if other == self.terrain_geom {
                        self.states[h].terrain_contact[bi] = true;
                    }
                }
            }
        }
    }

    fn bad_qacc_count(&self) -> i32 {
        self.data.warning()[MjtWarning::mjWARN_BADQACC as usize].number
            + self.data.warning()[MjtWarning::mjWARN_BADQPOS as usize].number
            + self.data.warning()[MjtWarning::mjWARN_BADQVEL as usize].number
    }
}

impl PhysicsBackend for MujocoBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Mujoco
    }

    fn num_humanoids(&self) -> usize {
        self.layouts.len()
    }

    fn tick(&self) -> Tick {
        self.tick
    }

    fn reset_humanoid(&mut self, index: usize, pose: &HumanoidPose) -> Result<(), PhysicsError> {
        PhysicsError::check_index(index, self.layouts.len())?;
        pose.validate()?;
        self.write_pose(index, pose);
        self.data.forward();
        self.diverged[index] = false;
        self.read_states(false);
        Ok(())
    }

    fn set_action_for(
        &mut self,
        index: usize,
        targets: &[f64],
        root_wrench: Option<RootWrench>,
    ) -> Result<(), PhysicsError> {
        PhysicsError::check_index(index, self.layouts.len())?;
        let (targets, w) = sanitize_action(
            targets,
            root_wrench,
            self.settings.max_root_force,
            self.settings.max_root_torque,
        )?;
        let l = &self.layouts[index];
        let ctrl = self.data.ctrl_mut();
        for ji in 0..NUM_JOINTS {
            ctrl[l.ctrl[ji]] = targets[ji];
        }
        let pelvis = l.body[PELVIS];
        self.data.xfrc_applied_mut()[pelvis] = [
            w.force[0],
            w.force[1],
            w.force[2],
            w.torque[0],
            w.torque[1],
            w.torque[2],
        ];
        Ok(())
    }

    fn step(&mut self) -> Result<(), PhysicsError> {
        if self.diverged.iter().any(|d| *d) {
            return Err(PhysicsError::still_diverged(BackendKind::Mujoco, self.tick));
        }
        let t_next = self.tick.advanced(1).seconds();
        for k in 0..self.mocap.len() {
            let (s, yaw) = self.motions.pose(k, t_next);
            let m = self.mocap[k];
            self.data.mocap_pos_mut()[m] = s.position;
            self.data.mocap_quat_mut()[m] = math::quat_from_yaw(yaw);
            self.obstacles[k] = s;
        }
        self.data.step();
        // mj_step computes body poses before it integrates, so xpos/xquat would lag
        // qpos by one step (up to 2.3 cm of head at walking speed); bring them to the
        // new qpos. This only reads positions: the next mj_step recomputes everything,
        // so the dynamics are unchanged. Contacts stay those found at the step's start.
        self.data.kinematics();
        self.tick = self.tick.advanced(1);
        // MuJoCo resets the data itself on a bad acceleration and only counts a warning.
        let warnings = self.bad_qacc_count();
        let mujoco_reset = warnings != self.bad_qacc_warnings;
        self.bad_qacc_warnings = warnings;
        self.read_states(true);
        let bad = (0..self.layouts.len()).find_map(|i| {
            if mujoco_reset {
                Some((
                    i,
                    "MuJoCo reset the data after a bad acceleration".to_string(),
                ))
            } else {
                self.states[i].unphysical().map(|why| (i, why))
            }
        });
        match bad {
            Some((i, why)) => {
                self.diverged.iter_mut().for_each(|d| *d = true);
                Err(PhysicsError::diverged(
                    BackendKind::Mujoco,
                    self.tick,
                    format!("humanoid {i}: {why}"),
                ))
            }
            None => Ok(()),
        }
    }

    fn humanoid_state(&self, index: usize) -> Result<&HumanoidState, PhysicsError> {
        PhysicsError::check_index(index, self.layouts.len())?;
        Ok(&self.states[index])
    }

    fn obstacles(&self) -> &[ObstacleState] {
        &self.obstacles
    }

    fn drive_obstacle(&mut self, index: usize, state: ObstacleState) -> Result<(), PhysicsError> {
        self.motions.drive(index, state, self.tick.seconds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_scenes::HeightGrid;

    /// Pins the height-field layout (row = grid j, column = grid i) with ray casts.
    #[test]
    fn heightfield_matches_grid() {
        let mut g = HeightGrid::flat([2.0, -1.0], [3.0, 4.0], 0.25, 0.0);
        for jj in 0..g.ny {
            for ii in 0..g.nx {
                let [x, y] = g.position(ii, jj);
                g.heights[jj * g.nx + ii] = 0.3 * x - 0.2 * y + 0.1 * x * y;
            }
        }
        let scene = Scene {
            name: "t".into(),
            description: String::new(),
            terrain: g.clone(),
            walls: vec![],
            dynamic: vec![],
            tops: vec![],
            landmarks: vec![],
        };
        let mut b = MujocoBackend::new(&scene, &PhysicsSettings::default()).unwrap();
        // The humanoid stands at (3, 1); cast away from it.
        for &(x, y) in &[
            (2.0, -1.0),
            (2.3, 2.9),
            (4.9, -0.7),
            (4.5, 2.5),
            (4.0, -0.5),
        ] {
            let (geom, dist) = b
                .data
                .ray(&[x, y, 10.0], &[0.0, 0.0, -1.0], None, true, None, None);
            assert_eq!(geom, Some(b.terrain_geom), "({x},{y}) hits the terrain");
            let z = 10.0 - dist;
            assert!(
                (z - g.height_at(x, y)).abs() < 0.01,
                "({x},{y}): {z} vs {}",
                g.height_at(x, y)
            );
        }
    }
}
