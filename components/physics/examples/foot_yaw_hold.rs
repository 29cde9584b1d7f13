//! Does a loaded stance foot hold against a yaw torque, or pivot, in each engine?
//!
//! The humanoid holds a crouch (pelvis pitched 0.35 rad, spine 0.9 rad, knees 1.5 rad,
//! head ~0.85 m) on both feet or on the right foot with the left one lifted, on flat
//! ground, a 10 degree slope and +-3 cm gravel (all height fields, in both engines).
//! A root wrench holds the pelvis over its start point (horizontal force) and upright
//! (roll and pitch torque) but leaves it free in height, so the feet carry the weight,
//! and free in yaw, where the test's torque acts:
//!
//! - ramp: the yaw torque grows at 20 N m/s from 0 to 200 N m over 10 s; printed is the
//!   torque at which the stance foot's world yaw has turned 0.01 and 0.05 rad from
//!   where it stood when the ramp began;
//! - hold: a constant yaw torque for 4 s; printed is the stance foot's yaw rate over
//!   the last 3 s \[rad/s\] and how far its centre slid \[m\].
//!
//! Engines: MuJoCo, rapier as shipped, and rapier with its root torques summed over
//! the steps (`rapier_root_torque_per_step` false, the behaviour before it): there
//! even 10 N m spins the body up until it diverges ("spun off").
//!
//! - `contacts`: for rapier, the stance foot's contact points as the solver saw them
//!   after settling and after 0.5 s of 30 N m (foot frame: x forward from the ankle,
//!   the sole at z = -0.07, the box 0.22 x 0.09 m from x = -0.065 to 0.155): are the
//!   corners held?
//! - `free`: without gravity and without the holding wrench, 10 N m of yaw torque for
//!   0.5 s on the floating crouch: the pelvis's yaw rate in each engine.
//!
//! `cargo run --release -p plamo-physics --features mujoco --example foot_yaw_hold [contacts|free]`

use plamo_physics::{
    BackendKind, FEET, HumanoidPose, HumanoidState, NUM_JOINTS, PhysicsBackend, PhysicsSettings,
    RapierBackend, RootWrench, create_backend, humanoid::joint_index,
};
use plamo_scenes::{HeightGrid, Scene};

type Quat = [f64; 4];

fn qmul(a: Quat, b: Quat) -> Quat {
    let [aw, ax, ay, az] = a;
    let [bw, bx, by, bz] = b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

fn qaxis(axis: usize, angle: f64) -> Quat {
    let (s, c) = (0.5 * angle).sin_cos();
    let mut q = [c, 0.0, 0.0, 0.0];
    q[1 + axis] = s;
    q
}

fn rotate(q: Quat, v: [f64; 3]) -> [f64; 3] {
    let p = qmul(
        qmul(q, [0.0, v[0], v[1], v[2]]),
        [q[0], -q[1], -q[2], -q[3]],
    );
    [p[1], p[2], p[3]]
}

/// Heading of a frame: the angle of its local X axis in the world XY plane.
fn heading(q: Quat) -> f64 {
    let x = rotate(q, [1.0, 0.0, 0.0]);
    x[1].atan2(x[0])
}

/// Rotation vector of a unit quaternion (axis times angle).
fn log(q: Quat) -> [f64; 3] {
    let q = if q[0] < 0.0 { q.map(|c| -c) } else { q };
    let s = (q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if s < 1e-12 {
        return [0.0; 3];
    }
    let angle = 2.0 * s.atan2(q[0]);
    [q[1] / s * angle, q[2] / s * angle, q[3] / s * angle]
}

/// World orientation of a foot from the root and the leg's hinges (hip X, Y, Z,
/// knee Y, ankle Y, X), composed as `crate::humanoid` documents.
fn foot_quat(s: &HumanoidState, side: &str) -> Quat {
    let j = |n: &str| s.joint_pos[joint_index(&format!("{side}_{n}")).expect("joint")];
    let mut q = s.root_quat;
    for (axis, n) in [
        (0, "hip_x"),
        (1, "hip_y"),
        (2, "hip_z"),
        (1, "knee"),
        (1, "ankle_y"),
        (0, "ankle_x"),
    ] {
        q = qmul(q, qaxis(axis, j(n)));
    }
    q
}

/// The foot box's centre in the world (its centre is 4.5 cm ahead of and 3.5 cm
/// below the ankle).
fn foot_centre(s: &HumanoidState, body: usize, side: &str) -> [f64; 3] {
    let c = rotate(foot_quat(s, side), [0.045, 0.0, -0.035]);
    let a = s.body_pos[body];
    [a[0] + c[0], a[1] + c[1], a[2] + c[2]]
}

fn scene(name: &str, f: impl Fn(f64, f64) -> f64) -> Scene {
    let mut g = HeightGrid::flat([-3.0, -3.0], [6.0, 6.0], 0.1, 0.0);
    for jj in 0..g.ny {
        for ii in 0..g.nx {
            let [x, y] = g.position(ii, jj);
            g.heights[jj * g.nx + ii] = f(x, y);
        }
    }
    Scene {
        name: name.into(),
        description: String::new(),
        terrain: g,
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![],
    }
}

/// The three grounds: name, scene, the foot's pitch on it \[rad\] (toes up on the slope).
fn grounds() -> Vec<(&'static str, Scene, f64)> {
    let slope = 10f64.to_radians();
    vec![
        ("flat", scene("flat", |_, _| 0.0), 0.0),
        ("slope", scene("slope", move |x, _| x * slope.tan()), -slope),
        (
            "gravel",
            scene("gravel", |x, y| {
                let h = ((x * 12.9898 + y * 78.233).sin() * 43758.5453).fract();
                0.03 * (2.0 * h.abs() - 1.0)
            }),
            0.0,
        ),
    ]
}

const PITCH: f64 = 0.35;

/// Gains of the root torque holding the pelvis upright \[N m/rad\], \[N m s/rad\].
const KR: f64 = 600.0;
const KW: f64 = 20.0;

/// The crouch's joint angles; `one_foot` lifts the left foot ~15 cm.
fn crouch(foot_pitch: f64, one_foot: bool) -> [f64; NUM_JOINTS] {
    let a = 0.75;
    let mut q = [0.0; NUM_JOINTS];
    let mut set = |n: &str, v: f64| q[joint_index(n).expect("joint")] = v;
    set("spine_y", 0.9);
    for side in ["right", "left"] {
        let (hip, knee) = if one_foot && side == "left" {
            (-(a + PITCH) - 0.5, 2.0 * a + 0.6)
        } else {
            (-(a + PITCH), 2.0 * a)
        };
        set(&format!("{side}_hip_y"), hip);
        set(&format!("{side}_knee"), knee);
        // The sole parallel to the ground: the leg's pitches sum to the foot's.
        set(&format!("{side}_ankle_y"), foot_pitch - PITCH - hip - knee);
    }
    q
}

/// An engine as the example runs it.
#[derive(Clone, Copy)]
struct Engine {
    name: &'static str,
    kind: BackendKind,
    /// [`PhysicsSettings::rapier_root_torque_per_step`].
    per_step: bool,
}

const ENGINES: [Engine; 3] = [
    Engine {
        name: "mujoco",
        kind: BackendKind::Mujoco,
        per_step: true,
    },
    Engine {
        name: "rapier",
        kind: BackendKind::Rapier,
        per_step: true,
    },
    Engine {
        name: "rapier summed",
        kind: BackendKind::Rapier,
        per_step: false,
    },
];

struct Run {
    /// MuJoCo through `create_backend`, or rapier built directly so that its contacts
    /// can be read (what `create_backend` does for rapier).
    backend: Option<Box<dyn PhysicsBackend>>,
    rapier: Option<RapierBackend>,
    targets: [f64; NUM_JOINTS],
    home: [f64; 2],
    tilt: Quat,
    /// Whether the pelvis is held over its start point and upright.
    held: bool,
}

impl Run {
    /// `free`: without gravity, 1 m up, not held.
    fn new(engine: Engine, ground: &Scene, joints: [f64; NUM_JOINTS], free: bool) -> Self {
        let settings = PhysicsSettings {
            gravity: if free { 0.0 } else { 9.81 },
            rapier_root_torque_per_step: engine.per_step,
            ..PhysicsSettings::default()
        };
        let mut pose = HumanoidPose::resting_on(&ground.terrain, 0.0, 0.0, 0.0, PITCH, joints);
        if free {
            pose.root_position[2] += 1.0;
        }
        let (backend, rapier) = match engine.kind {
            BackendKind::Rapier => {
                let mut r = RapierBackend::new(ground, &settings).expect("rapier");
                r.reset(&pose).expect("reset");
                (None, Some(r))
            }
            BackendKind::Mujoco => {
                let mut b = create_backend(engine.kind, ground, &settings).expect("backend");
                b.reset(&pose).expect("reset");
                (Some(b), None)
            }
        };
        Run {
            backend,
            rapier,
            targets: pose.clamped_joints(),
            home: [pose.root_position[0], pose.root_position[1]],
            tilt: qaxis(1, PITCH),
            held: !free,
        }
    }

    fn physics(&mut self) -> &mut dyn PhysicsBackend {
        match (&mut self.rapier, &mut self.backend) {
            (Some(r), _) => r,
            (None, Some(b)) => b.as_mut(),
            (None, None) => unreachable!("a run has one backend"),
        }
    }

    /// One step with a yaw torque `tau` \[N m\] on the pelvis, which is otherwise held
    /// over its start point and upright; `None` once the engine diverged.
    fn step(&mut self, tau: f64) -> Option<HumanoidState> {
        let s = self.physics().state().clone();
        let p = s.root_position;
        let v = s.root_linvel;
        let w = s.root_angvel;
        // Upright at the pelvis's own heading: the error has no yaw component.
        let target = qmul(qaxis(2, heading(s.root_quat)), self.tilt);
        let inv = [
            s.root_quat[0],
            -s.root_quat[1],
            -s.root_quat[2],
            -s.root_quat[3],
        ];
        let e = log(qmul(target, inv));
        let hold = if self.held { 1.0 } else { 0.0 };
        let wrench = RootWrench {
            force: [
                hold * (2000.0 * (self.home[0] - p[0]) - 400.0 * v[0]),
                hold * (2000.0 * (self.home[1] - p[1]) - 400.0 * v[1]),
                0.0,
            ],
            torque: [
                hold * (KR * e[0] - KW * w[0]),
                hold * (KR * e[1] - KW * w[1]),
                tau,
            ],
        };
        let targets = self.targets;
        let b = self.physics();
        b.set_action(&targets, Some(wrench)).expect("action");
        b.step().ok()?;
        Some(b.state().clone())
    }

    /// Settle for [`SETTLE`] steps without torque.
    fn settle(&mut self) -> Option<HumanoidState> {
        let mut s = None;
        for _ in 0..SETTLE {
            s = Some(self.step(0.0)?);
        }
        s
    }
}

const HZ: f64 = 120.0;
const SETTLE: usize = 240;

fn stance_foot(s: &HumanoidState) -> (f64, [f64; 3]) {
    (
        heading(foot_quat(s, "right")),
        foot_centre(s, FEET[0], "right"),
    )
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

/// Torques \[N m\] at which the stance foot has turned 0.01 and 0.05 rad on the ramp
/// (NaN: not within 200 N m); `None` where the engine diverged first.
fn ramp(engine: Engine, ground: &Scene, joints: [f64; NUM_JOINTS]) -> Option<(f64, f64)> {
    let mut run = Run::new(engine, ground, joints, false);
    let (yaw0, _) = stance_foot(&run.settle()?);
    let mut small = f64::NAN;
    for k in 0..(10.0 * HZ) as usize {
        let tau = 20.0 * k as f64 / HZ;
        let turned = wrap(stance_foot(&run.step(tau)?).0 - yaw0).abs();
        if small.is_nan() && turned > 0.01 {
            small = tau;
        }
        if turned > 0.05 {
            return Some((small, tau));
        }
    }
    Some((small, f64::NAN))
}

/// The stance foot's yaw rate over the last 3 s of 4 s at torque `tau` \[rad/s\], and
/// how far its centre moved \[m\]; `None` where the engine diverged.
fn hold(engine: Engine, ground: &Scene, joints: [f64; NUM_JOINTS], tau: f64) -> Option<(f64, f64)> {
    let mut run = Run::new(engine, ground, joints, false);
    let mut s = run.settle()?;
    let (mut prev, c0) = stance_foot(&s);
    let (mut turned, mut after_1s) = (0.0, 0.0);
    for k in 0..(4.0 * HZ) as usize {
        s = run.step(tau)?;
        let y = stance_foot(&s).0;
        turned += wrap(y - prev);
        prev = y;
        if k + 1 == HZ as usize {
            after_1s = turned;
        }
    }
    let (_, c1) = stance_foot(&s);
    let slid = ((c1[0] - c0[0]).powi(2) + (c1[1] - c0[1]).powi(2)).sqrt();
    Some(((turned - after_1s) / 3.0, slid))
}

fn print_contacts(name: &str, ground: &Scene, joints: [f64; NUM_JOINTS]) {
    let mut run = Run::new(ENGINES[1], ground, joints, false);
    for k in 0..SETTLE + 60 {
        let tau = if k < SETTLE { 0.0 } else { 30.0 };
        run.step(tau).expect("rapier steps");
        if k + 1 == SETTLE || k + 1 == SETTLE + 60 {
            let r = run.rapier.as_ref().expect("rapier");
            let (points, raw) = r.body_contacts(0, FEET[0]).expect("contacts");
            println!(
                "{name}, {tau} N m: right foot, {raw} narrow-phase manifolds, {} solver points",
                points.len()
            );
            for p in points {
                println!(
                    "  manifold {} at ({:+.3}, {:+.3}, {:+.3}) dist {:+.4} normal impulse {:.3} friction impulse {:.3} normal ({:+.2}, {:+.2}, {:+.2})",
                    p.manifold,
                    p.local[0],
                    p.local[1],
                    p.local[2],
                    p.dist,
                    p.impulse,
                    p.tangent_impulse,
                    p.normal[0],
                    p.normal[1],
                    p.normal[2]
                );
            }
        }
    }
}

/// Yaw rate of the floating crouch under 10 N m, every 0.1 s for 0.5 s.
fn print_free() {
    let (_, ground, _) = grounds().remove(0);
    for engine in ENGINES {
        let mut run = Run::new(engine, &ground, crouch(0.0, false), true);
        let rates: Vec<String> = (1..=60)
            .filter_map(|k| {
                let s = run.step(10.0);
                (k % 12 == 0)
                    .then(|| s.map_or("diverged".into(), |s| format!("{:.2}", s.root_angvel[2])))
            })
            .collect();
        println!(
            "{:13}: pelvis yaw rate after 0.1..0.5 s of 10 N m [rad/s]: {}",
            engine.name,
            rates.join(" ")
        );
    }
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_default();
    if !BackendKind::Mujoco.is_available() {
        eprintln!("needs --features mujoco");
        std::process::exit(2);
    }
    if mode == "free" {
        print_free();
        return;
    }
    for (name, ground, foot_pitch) in grounds() {
        for (stance, one) in [("both feet", false), ("right foot", true)] {
            let joints = crouch(foot_pitch, one);
            if mode == "contacts" {
                print_contacts(&format!("{name}, {stance}"), &ground, joints);
                continue;
            }
            for engine in ENGINES {
                let turns = match ramp(engine, &ground, joints) {
                    Some((small, large)) => {
                        format!("turns 0.01 rad at {small:5.1} N m, 0.05 at {large:5.1}")
                    }
                    None => "spun off on the ramp".to_string(),
                };
                let holds: Vec<String> = [10.0, 20.0, 40.0, 80.0]
                    .iter()
                    .map(|&tau| match hold(engine, &ground, joints, tau) {
                        Some((rate, slid)) => format!("{tau:.0}: {rate:+.3} rad/s {slid:.3} m"),
                        None => format!("{tau:.0}: spun off"),
                    })
                    .collect();
                println!(
                    "{name:6} {stance:10} {:13}: {turns}; hold {}",
                    engine.name,
                    holds.join(", ")
                );
            }
        }
    }
}
