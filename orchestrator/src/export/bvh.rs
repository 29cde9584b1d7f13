//! `motion.bvh`: one humanoid's skeleton and joint rotations per frame, in the
//! conventions animation tools expect: Y up, centimetres, degrees.
//!
//! The simulation is Z-up with the humanoid facing +X; the change of basis
//! (x, y, z) -> (x, z, -y) keeps +X forward, makes +Y up and turns a hinge about the
//! body's Y axis into one about -Z and a hinge about Z into one about Y. Every body
//! is a BVH joint with three rotation channels in the order its hinges compose
//! (X, Y, Z in simulation axes, i.e. `Xrotation Zrotation Yrotation` here, negating
//! the Z values); hinge-less or single-hinge bodies keep zero channels so every joint
//! has the same layout. The root adds three position channels and its orientation
//! as the same Euler sequence.

use std::fmt::Write;

use plamo_physics::humanoid::{Axis, BODIES, HEAD_OFFSET, JOINTS};
use plamo_physics::{BODY_NAMES, NUM_BODIES};

use super::fk::qnormalize;
use super::recording::Recording;

/// Simulation metres to BVH centimetres.
const CM: f64 = 100.0;

/// Z-up metres to Y-up centimetres.
fn to_bvh(v: [f64; 3]) -> [f64; 3] {
    // `+ 0.0` turns -0.0 into 0.0 so the text has no "-0.000000".
    [v[0] * CM + 0.0, v[2] * CM + 0.0, -v[1] * CM + 0.0]
}

/// End points of the leaf bodies in their own frame (simulation axes) [m].
fn end_site(body: usize) -> Option<[f64; 3]> {
    match BODY_NAMES[body] {
        "head" => Some([0.0, 0.0, HEAD_OFFSET[2] + 0.10]),
        "right_hand" | "left_hand" => Some([0.0, 0.0, -0.10]),
        "right_foot" | "left_foot" => Some([0.155, 0.0, -0.07]),
        _ => None,
    }
}

/// (a, b, c) with R(q) = Rx(a) Ry(b) Rz(c) in simulation axes.
fn euler_xyz(q: [f64; 4]) -> [f64; 3] {
    let [x, y, z, w] = qnormalize(q);
    let r00 = 1.0 - 2.0 * (y * y + z * z);
    let r01 = 2.0 * (x * y - z * w);
    let r02 = 2.0 * (x * z + y * w);
    let r12 = 2.0 * (y * z - x * w);
    let r22 = 1.0 - 2.0 * (x * x + y * y);
    let b = r02.clamp(-1.0, 1.0).asin();
    [(-r12).atan2(r22), b, (-r01).atan2(r00)]
}

/// The angle equal to `a` modulo a full turn nearest to `prev` [deg], so curves in
/// animation tools do not jump by 360 degrees.
fn unwrap(prev: f64, a: f64) -> f64 {
    a + 360.0 * ((prev - a) / 360.0).round()
}

/// Agent `agent`'s motion as BVH text (an empty agent list gives an empty skeleton).
pub fn write_bvh(rec: &Recording, agent: usize) -> String {
    let mut s = String::from("HIERARCHY\n");
    let children = |p: usize| (0..NUM_BODIES).filter(move |&c| BODIES[c].parent == Some(p));
    fn indent(n: usize) -> String {
        "  ".repeat(n)
    }
    fn body(s: &mut String, b: usize, depth: usize, children: &dyn Fn(usize) -> Vec<usize>) {
        let pad = indent(depth);
        let o = if b == 0 {
            [0.0; 3]
        } else {
            to_bvh(BODIES[b].offset)
        };
        let _ = writeln!(
            s,
            "{pad}{} {}\n{pad}{{\n{pad}  OFFSET {:.6} {:.6} {:.6}",
            if b == 0 { "ROOT" } else { "JOINT" },
            BODY_NAMES[b],
            o[0],
            o[1],
            o[2]
        );
        let _ = writeln!(
            s,
            "{pad}  CHANNELS {}{}",
            if b == 0 {
                "6 Xposition Yposition Zposition "
            } else {
                "3 "
            },
            channel_names(b)
        );
        for c in children(b) {
            body(s, c, depth + 1, children);
        }
        if let Some(e) = end_site(b) {
            let e = to_bvh(e);
            let _ = writeln!(
                s,
                "{pad}  End Site\n{pad}  {{\n{pad}    OFFSET {:.6} {:.6} {:.6}\n{pad}  }}",
                e[0], e[1], e[2]
            );
        }
        let _ = writeln!(s, "{pad}}}");
    }
    body(&mut s, 0, 0, &|p| children(p).collect());

    let frames: Vec<_> = rec
        .agents
        .get(agent)
        .map(|a| a.frames.as_slice())
        .unwrap_or_default()
        .iter()
        .collect();
    let dt = match frames.as_slice() {
        [a, b, ..] => Recording::time(b.tick) - Recording::time(a.tick),
        _ => 1.0 / f64::from(plamo_interfaces::CONTROL_HZ),
    };
    let _ = writeln!(s, "MOTION\nFrames: {}\nFrame Time: {dt:.9}", frames.len());
    let mut prev = [[0.0f64; 3]; NUM_BODIES];
    for f in frames {
        let mut line = String::new();
        let p = to_bvh(f.root);
        let _ = write!(line, "{:.6} {:.6} {:.6}", p[0], p[1], p[2]);
        for b in 0..NUM_BODIES {
            // Simulation-axis angles in composition order, then the change of basis.
            let sim = if b == 0 {
                euler_xyz(f.quat)
            } else {
                let mut v = [0.0; 3];
                for (slot, &j) in BODIES[b].joints.iter().enumerate() {
                    v[slot] = f.joints[j];
                }
                v
            };
            for (slot, ch) in channels(b).iter().enumerate() {
                let sign = if *ch == Axis::Y { -1.0 } else { 1.0 };
                let deg = unwrap(prev[b][slot], sign * sim[slot].to_degrees());
                prev[b][slot] = deg;
                let deg = deg + 0.0;
                let _ = write!(line, " {deg:.6}");
            }
        }
        s.push_str(&line);
        s.push('\n');
    }
    s
}

/// The simulation axes of a body's three rotation channels, in composition order:
/// its hinges' axes, padded with the unused axes.
fn channels(b: usize) -> [Axis; 3] {
    if b == 0 {
        return [Axis::X, Axis::Y, Axis::Z];
    }
    let mut out: Vec<Axis> = BODIES[b].joints.iter().map(|&j| JOINTS[j].axis).collect();
    for a in [Axis::X, Axis::Y, Axis::Z] {
        if !out.contains(&a) {
            out.push(a);
        }
    }
    [out[0], out[1], out[2]]
}

fn channel_names(b: usize) -> String {
    channels(b)
        .iter()
        .map(|a| match a {
            Axis::X => "Xrotation",
            // Simulation Y is BVH -Z, simulation Z is BVH Y.
            Axis::Y => "Zrotation",
            Axis::Z => "Yrotation",
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::fk::{qaxis, qmul};

    #[test]
    fn euler_round_trips() {
        let q = qmul(
            qmul(qaxis([1.0, 0.0, 0.0], 0.3), qaxis([0.0, 1.0, 0.0], -0.7)),
            qaxis([0.0, 0.0, 1.0], 2.5),
        );
        let e = euler_xyz(q);
        assert!((e[0] - 0.3).abs() < 1e-12 && (e[1] + 0.7).abs() < 1e-12);
        assert!((e[2] - 2.5).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn ankle_channels_follow_its_hinge_order() {
        let foot = plamo_physics::FEET[0];
        assert_eq!(channel_names(foot), "Zrotation Xrotation Yrotation");
        assert_eq!(channel_names(1), "Xrotation Zrotation Yrotation");
        assert!((unwrap(179.0, -179.0) - 181.0).abs() < 1e-12);
    }
}
