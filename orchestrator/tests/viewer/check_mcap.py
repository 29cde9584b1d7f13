"""Reads replay.mcap of recorded runs with the MCAP project's own Python reader
(PyPI `mcap`, CRCs checked) and checks it against the recording: one /tf message per
recorded tick with every body of every agent, the pelvis transform equal to the
recorded root pose, and one /plamo/agent state per agent and tick whose head is the
recorded head.

usage: python3 check_mcap.py RECORDING_DIR...
"""

import csv
import json
import sys

from mcap.reader import NonSeekingReader

BODIES = 15


def check(d):
    with open(f"{d}/trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    agents = sorted({int(r["agent"]) for r in rows})
    ticks = sorted({int(r["tick"]) for r in rows})
    by_key = {(int(r["tick"]), int(r["agent"])): r for r in rows}
    with open(f"{d}/replay.mcap", "rb") as f:
        reader = NonSeekingReader(f, validate_crcs=True)
        tf, states = [], []
        for schema, channel, message in reader.iter_messages():
            data = json.loads(message.data)
            if channel.topic == "/tf":
                assert schema.name == "foxglove.FrameTransforms", schema.name
                tf.append((message.log_time, data))
            elif channel.topic == "/plamo/agent":
                states.append(data)
    assert len(tf) == len(ticks), f"{d}: {len(tf)} /tf messages for {len(ticks)} ticks"
    assert len(states) == len(rows), f"{d}: {len(states)} states for {len(rows)} rows"
    for (log_time, data), tick in zip(tf, ticks):
        assert abs(log_time - tick / 120 * 1e9) < 1, (log_time, tick)
        frames = {t["child_frame_id"]: t for t in data["transforms"]}
        for k in agents:
            assert sum(1 for c in frames if c.startswith(f"agent{k}/")) == BODIES
            pelvis = frames[f"agent{k}/pelvis"]
            row = by_key[(tick, k)]
            assert pelvis["parent_frame_id"] == "world"
            for axis, col in zip("xyz", ("root_x", "root_y", "root_z")):
                assert pelvis["translation"][axis] == float(row[col]), (tick, axis)
            assert frames[f"agent{k}/head"]["parent_frame_id"] == f"agent{k}/torso"
    for s in states:
        row = by_key[(s["tick"], s["agent"])]
        for axis in "xyz":
            assert s["head"][axis] == float(row[f"head_{axis}"])
        assert s["joints"]["right_knee"] == float(row["right_knee"])
    print(f"{d}/replay.mcap: {len(tf)} /tf messages ({len(agents)} agent(s) x {BODIES} bodies), "
          f"{len(states)} agent states, all equal to trajectory.csv")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for d in sys.argv[1:]:
        check(d)
