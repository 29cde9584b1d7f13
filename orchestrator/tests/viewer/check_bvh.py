"""Reads motion.bvh of recorded runs with an independent BVH parser (PyPI `bvh`) and
checks it against the recording: one frame per recorded control tick at 30 Hz, the
15-joint skeleton, and standard BVH forward kinematics (offset, then the channels'
rotations in their listed order) putting the head where the physics recorded it
in trajectory.csv (Z-up metres there, Y-up centimetres in the BVH).

usage: python3 check_bvh.py RECORDING_DIR...
"""

import csv
import json
import math
import sys

from bvh import Bvh

BODIES = 15
# Head centre in the head joint's frame, Y-up cm (0.08 m above the neck joint).
HEAD_CENTRE = (0.0, 8.0, 0.0)
# rapier reports the head from the same joint state (exact up to print precision);
# MuJoCo reports body poses from before its last integration step (the head lags
# qpos by one 120 Hz step, up to ~2.5 cm at walking speed).
TOLERANCE_CM = {"rapier": 0.05, "mujoco": 4.0}


def rot(axis, deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return {
        "X": [[1, 0, 0], [0, c, -s], [0, s, c]],
        "Y": [[c, 0, s], [0, 1, 0], [-s, 0, c]],
        "Z": [[c, -s, 0], [s, c, 0], [0, 0, 1]],
    }[axis]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def apply(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def world_head(mocap, frame, chain):
    pos = [0.0, 0.0, 0.0]
    r = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    for name in chain:
        off = apply(r, [float(x) for x in mocap.joint_offset(name)])
        pos = [pos[i] + off[i] for i in range(3)]
        channels = mocap.joint_channels(name)
        values = mocap.frame_joint_channels(frame, name, channels)
        for ch, v in zip(channels, values):
            if ch.endswith("position"):
                pos["XYZ".index(ch[0])] += v
        for ch, v in zip(channels, values):
            if ch.endswith("rotation"):
                r = mul(r, rot(ch[0], v))
    c = apply(r, HEAD_CENTRE)
    return [pos[i] + c[i] for i in range(3)]


def check(d):
    with open(f"{d}/motion.bvh") as f:
        mocap = Bvh(f.read())
    with open(f"{d}/metrics.json") as f:
        physics = json.load(f)["physics"]
    with open(f"{d}/trajectory.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["agent"] == "0"]
    names = mocap.get_joints_names()
    assert len(names) == BODIES, f"{d}: {len(names)} joints, want {BODIES}: {names}"
    assert names[0] == "pelvis", names
    assert mocap.nframes == len(rows), f"{d}: {mocap.nframes} frames for {len(rows)} ticks"
    assert abs(mocap.frame_time - 1 / 30) < 1e-6, mocap.frame_time
    chain = []
    name = "head"
    while name is not None:
        chain.insert(0, name)
        parent = mocap.joint_parent(name)
        name = parent.name if parent is not None else None
    assert chain == ["pelvis", "torso", "head"], chain
    worst = 0.0
    for i, r in enumerate(rows):
        x, y, z = (float(r[k]) for k in ("head_x", "head_y", "head_z"))
        want = [100 * x, 100 * z, -100 * y]
        got = world_head(mocap, i, chain)
        worst = max(worst, math.dist(want, got))
    print(f"{d}/motion.bvh ({physics}): {mocap.nframes} frames at {1 / mocap.frame_time:.0f} Hz, "
          f"{len(names)} joints, head from BVH kinematics within {worst:.3f} cm of the recording")
    assert worst < TOLERANCE_CM[physics], f"{d}: head {worst} cm off"


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for d in sys.argv[1:]:
        check(d)
