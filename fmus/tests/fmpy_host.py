"""The plamo FMUs imported by FMPy, a real external FMI 2.0 host.

Usage: python3 fmus/tests/fmpy_host.py DIR   (DIR holds the .fmu files of `plamo fmu build`)
Prints one line per check and a closing 'N passed, M failed' line; exits 1 on failure.
"""
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile
import traceback
import zipfile

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from ctypes import byref
from fmpy.fmi2 import (FMU2Slave, addLoggerProxy, defaultCallbacks, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
from fmpy.validation import validate_fmu

FMU_DIR = sys.argv[1]
PLANNER = f"{FMU_DIR}/plamo-planner.fmu"
HUMANOID = f"{FMU_DIR}/plamo.fmu"
LOGS = []


def logger(component, instance, status, category, message):
    LOGS.append(message.decode() if isinstance(message, bytes) else str(message))


CALLBACKS = fmi2CallbackFunctions()
CALLBACKS.logger = fmi2CallbackLoggerTYPE(logger)
CALLBACKS.allocateMemory = defaultCallbacks.allocateMemory
CALLBACKS.freeMemory = defaultCallbacks.freeMemory
addLoggerProxy(byref(CALLBACKS))


def open_slave(path):
    md = read_model_description(path)
    unzipdir = extract(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="fmpy-test")
    slave.instantiate(callbacks=CALLBACKS, loggingOn=True)
    return slave, vr, unzipdir


def expect_error(what, call, needle):
    """`call` must fail with fmi2Error and the FMU must log a message containing `needle`."""
    LOGS.clear()
    try:
        call()
    except Exception as e:  # FMPy raises FMICallException on fmi2Error
        text = " ".join(LOGS) + " " + str(e)
        assert needle in text, f"{what}: expected a message containing {needle!r}, got {text!r}"
        return
    raise AssertionError(f"{what}: the call succeeded but must fail")


def check_validate():
    problems = validate_fmu(PLANNER)
    assert problems == [], problems


def check_humanoid_validate():
    problems = validate_fmu(HUMANOID)
    assert problems == [], problems


SANDBOX = (4.0, 4.0, 1.5)  # playground landmark: centre x, y and half side [m]


def check_humanoid_simulate_with_a_ball_rolling_across_its_route():
    """`fmpy simulate` with an input CSV: a ball rolls across the default route
    (fountain (4, 14) to sandbox (4, 4)) at y = 9; the humanoid must still arrive."""
    tmp = tempfile.mkdtemp()
    try:
        inputs, result = f"{tmp}/ball.csv", f"{tmp}/result.csv"
        with open(inputs, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["time", "obstacle[1].active", "obstacle[1].x", "obstacle[1].y", "obstacle[1].z",
                        "obstacle[1].vx", "obstacle[1].vy", "obstacle[1].vz"])
            for t in range(0, 21):
                w.writerow([float(t), 1.0, -1.0 + t, 9.0, 0.3, 1.0, 0.0, 0.0])
        outputs = ["head.x", "head.y", "head.z", "speed", "instruction", "progress", "done", "fallen",
                   "xy_error"]
        cmd = [sys.executable, "-m", "fmpy", "simulate", HUMANOID, "--stop-time", "20",
               "--output-interval", "0.1", "--input-file", inputs, "--output-file", result,
               "--start-values", "seed", "2", "--output-variables", *outputs]
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, f"fmpy simulate failed: {run.stdout} {run.stderr}"
        with open(result) as f:
            rows = list(csv.DictReader(f))
        assert len(rows) >= 200, f"{len(rows)} rows: the simulation stopped early"
        assert abs(float(rows[-1]["time"]) - 20.0) < 1e-6, rows[-1]["time"]
        for r in rows:
            assert all(math.isfinite(float(r[k])) for k in ["head.x", "head.y", "head.z", "xy_error"]), r
        done = [r for r in rows if r["done"] in ("1", "True", "true", "1.0")]
        assert done, f"never done; last row {rows[-1]}"
        cx, cy, half = SANDBOX
        x, y = float(done[0]["head.x"]), float(done[0]["head.y"])
        assert abs(x - cx) <= half and abs(y - cy) <= half, \
            f"done at t = {done[0]['time']} s with the head at ({x:.2f}, {y:.2f}), outside the sandbox"
        print(f"       done at t = {float(done[0]['time']):.1f} s, head at ({x:.2f}, {y:.2f}); "
              f"max XY error {max(float(r['xy_error']) for r in rows):.2f} m")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def with_resource(fmu, name, source):
    """A copy of `fmu` that ships `source` as resources/`name`."""
    out = f"{tempfile.mkdtemp()}/{os.path.basename(fmu)}"
    shutil.copy(fmu, out)
    with zipfile.ZipFile(out, "a") as z:
        z.write(source, f"resources/{name}")
    return out


def check_humanoid_string_parameters_and_a_scene_from_resources():
    playground = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "playground.toml")
    fmu = with_resource(HUMANOID, "my-park.toml", playground)
    slave, vr, unzipdir = open_slave(fmu)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["scene"], vr["instructions"], vr["physics"]],
                        ["my-park.toml", "walk from the tree to the fountain", "rapier"])
        slave.exitInitializationMode()
        assert slave.getInteger([vr["instruction_count"]])[0] == 1
        start = slave.getReal([vr["head.x"], vr["head.y"]])
        assert abs(start[0] - 3.5) < 0.5 and abs(start[1] - 26.0) < 0.5, start
        t, dt = 0.0, 0.009999999999999998
        while t < 1.0 - 1e-9:
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
            t += dt
        head = slave.getReal([vr["head.x"], vr["head.y"], vr["head.z"]])
        assert head[2] > 1.2, f"head at {head} after 1 s"
        expect_error("parameter after initialisation",
                     lambda: slave.setString([vr["scene"]], ["slalom"]), "parameters are fixed")
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
        shutil.rmtree(os.path.dirname(fmu), ignore_errors=True)


def check_humanoid_physics_mujoco_runs_or_is_refused():
    """A library built with MuJoCo ships libmujoco inside the FMU and walks with it;
    one built without refuses `physics = mujoco` and says what is allowed."""
    slave, vr, unzipdir = open_slave(HUMANOID)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["physics"]], ["mujoco"])
        LOGS.clear()
        try:
            slave.exitInitializationMode()
        except Exception:
            text = " ".join(LOGS)
            assert "built without the mujoco backend; allowed in this build: rapier" in text, text
            print("       this FMU has no MuJoCo: refused with a message")
            return
        t, dt = 0.0, 0.009999999999999998
        while t < 2.0 - 1e-9:
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
            t += dt
        head = slave.getReal([vr["head.z"], vr["speed"]])
        assert head[0] > 1.2, f"head at z = {head[0]} after 2 s in MuJoCo"
        print(f"       MuJoCo inside the FMU: head at z = {head[0]:.2f} m, speed {head[1]:.2f} m/s after 2 s")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def check_humanoid_misuse_is_refused_with_a_message():
    slave, vr, unzipdir = open_slave(HUMANOID)
    try:
        expect_error("doStep before initialisation", lambda: slave.doStep(0.0, 0.1), "fmi2DoStep is not allowed")
        expect_error("unknown value reference", lambda: slave.getReal([99999]), "unknown value reference 99999")
        expect_error("NaN input", lambda: slave.setReal([vr["obstacle[1].x"]], [math.nan]), "finite numbers only")
        expect_error("infinite input", lambda: slave.setReal([vr["obstacle[3].vy"]], [math.inf]),
                     "finite numbers only")
        expect_error("setting an output", lambda: slave.setReal([vr["head.x"]], [1.0]), "outputs are computed")
        expect_error("wrong type", lambda: slave.getInteger([vr["head.x"]]), "is Real, not Integer")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    for what, name, value, needle in [
        ("bad scene", "scene", "playgrund", "playground"),
        ("bad physics", "physics", "bullet", "allowed in this build: rapier"),
        ("unknown landmark", "instructions", "walk from the moon to the car", "moon"),
    ]:
        slave, vr, unzipdir = open_slave(HUMANOID)
        try:
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.setString([vr[name]], [value])
            expect_error(what, slave.exitInitializationMode, needle)
            # The instance is in the error state now: stepping is refused, not crashed.
            expect_error(f"{what}: doStep after the error", lambda: slave.doStep(0.0, 0.1), "not allowed")
        finally:
            slave.freeInstance()
            shutil.rmtree(unzipdir, ignore_errors=True)
    slave, vr, unzipdir = open_slave(HUMANOID)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setInteger([vr["seed"]], [-1])
        expect_error("negative seed", slave.exitInitializationMode, "must be >= 0")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    slave, vr, unzipdir = open_slave(HUMANOID)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(0.0, 0.05)
        expect_error("a step that does not continue", lambda: slave.doStep(0.2, 0.05), "contiguous")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def check_closed_loop_with_string_parameters():
    slave, vr, unzipdir = open_slave(PLANNER)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["instructions"]], ["walk from the car to the bench then crawl to the swing"])
        assert slave.getString([vr["instructions"]])[0].startswith(b"walk") or \
            slave.getString([vr["instructions"]])[0].startswith("walk")
        head = [25.0, 5.0, 1.47]
        slave.setReal([vr["character.x"], vr["character.y"], vr["character.z"]], head)
        slave.exitInitializationMode()
        t, dt, done, instr = 0.0, 0.009999999999999998, False, 0
        count = [vr["instruction_count"]]
        assert slave.getInteger(count)[0] == 2
        while t < 200.0 and not done:
            wp = slave.getReal([vr["waypoint[1].x"], vr["waypoint[1].y"], vr["waypoint[1].z"]])
            head = [h + (w - h) * dt / 0.5 for h, w in zip(head, wp)]
            slave.setReal([vr["character.x"], vr["character.y"], vr["character.z"]], head)
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
            t += dt
            instr = max(instr, slave.getInteger([vr["instruction"]])[0])
            done = bool(slave.getBoolean([vr["done"]])[0])
        assert done, f"not done at t = {t:.1f} s (instruction {instr})"
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def check_misuse_is_refused_with_a_message():
    slave, vr, unzipdir = open_slave(PLANNER)
    try:
        expect_error("doStep before initialisation", lambda: slave.doStep(0.0, 0.1), "fmi2DoStep is not allowed")
        expect_error("unknown value reference", lambda: slave.getReal([99999]), "unknown value reference 99999")
        expect_error("NaN input", lambda: slave.setReal([vr["character.x"]], [math.nan]), "finite numbers only")
        expect_error("setting an output", lambda: slave.setReal([vr["speed"]], [1.0]), "outputs are computed")
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["scene"]], ["playgrund"])
        expect_error("bad scene parameter", slave.exitInitializationMode, "playground")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def check_unknown_landmark():
    slave, vr, unzipdir = open_slave(PLANNER)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["instructions"]], ["run to the moon"])
        expect_error("unknown landmark", slave.exitInitializationMode, "bench")
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def check_simulate_with_input_file():
    # The host's character walks a straight line from the tree towards the swing.
    times = np.arange(0.0, 10.0, 0.5)
    signals = np.zeros(len(times), dtype=[("time", np.float64), ("character.x", np.float64),
                                          ("character.y", np.float64), ("character.z", np.float64)])
    signals["time"] = times
    signals["character.x"] = 3.5 + 1.0 * times
    signals["character.y"] = 26.0
    signals["character.z"] = 1.47
    result = simulate_fmu(PLANNER, start_time=0.0, stop_time=10.0, output_interval=0.1, input=signals,
                          start_values={"instructions": "walk from the tree to the swing"},
                          output=["waypoint[1].x", "speed", "instruction", "progress"])
    assert len(result) >= 99, len(result)
    assert np.all(np.isfinite(result["waypoint[1].x"]))
    assert result["speed"].max() > 0.5, result["speed"].max()


def check_humanoid_parameter_files_from_resources():
    """A planner parameter file shipped in resources/ and named by `planner_params`
    slows the walk; one with a typo fails initialisation naming the parameter and
    the field."""
    tmp = tempfile.mkdtemp()
    try:
        slow, typo = f"{tmp}/slow.toml", f"{tmp}/typo.toml"
        with open(slow, "w") as f:
            f.write("walk_speed = 0.6\n")
        with open(typo, "w") as f:
            f.write("walk_sped = 1.2\n")
        fmu = with_resource(HUMANOID, "slow.toml", slow)

        def travelled(files):
            slave, vr, unzipdir = open_slave(fmu)
            try:
                slave.setupExperiment(startTime=0.0)
                slave.enterInitializationMode()
                if files:
                    slave.setString([vr["planner_params"]], [files])
                slave.exitInitializationMode()
                t, dt, path = 0.0, 0.1, []
                while t < 4.0 - 1e-9:
                    slave.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
                    t += dt
                    path.append(slave.getReal([vr["head.x"], vr["head.y"]]))
                slave.terminate()
                return sum(math.dist(a, b) for a, b in zip(path, path[1:]))
            finally:
                slave.freeInstance()
                shutil.rmtree(unzipdir, ignore_errors=True)

        built_in, with_file = travelled(""), travelled("slow.toml")
        assert with_file < 0.85 * built_in, (with_file, built_in)
        print(f"       head travelled {with_file:.2f} m in 4 s with walk_speed = 0.6, {built_in:.2f} m built in")
        slave, vr, unzipdir = open_slave(HUMANOID)
        try:
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.setString([vr["planner_params"]], [typo])
            expect_error("planner file with a typo", slave.exitInitializationMode, "walk_sped")
            assert any("planner_params" in m for m in LOGS), LOGS
        finally:
            slave.freeInstance()
            shutil.rmtree(unzipdir, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


CHECKS = [check_validate, check_closed_loop_with_string_parameters, check_misuse_is_refused_with_a_message,
          check_unknown_landmark, check_simulate_with_input_file, check_humanoid_validate,
          check_humanoid_simulate_with_a_ball_rolling_across_its_route,
          check_humanoid_string_parameters_and_a_scene_from_resources,
          check_humanoid_physics_mujoco_runs_or_is_refused,
          check_humanoid_misuse_is_refused_with_a_message,
          check_humanoid_parameter_files_from_resources]

passed = failed = 0
for check in CHECKS:
    try:
        check()
        print(f"ok     {check.__name__}")
        passed += 1
    except Exception:
        print(f"FAILED {check.__name__}")
        traceback.print_exc()
        failed += 1
print(f"fmpy host: {passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
