"""The plamo FMUs imported by FMPy, a real external FMI 2.0 host.

Usage: python3 fmus/tests/fmpy_host.py DIR   (DIR holds the .fmu files of `plamo fmu build`)
Prints one line per check and a closing 'N passed, M failed' line; exits 1 on failure.
"""
import math
import shutil
import sys
import tempfile
import traceback

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from ctypes import byref
from fmpy.fmi2 import (FMU2Slave, addLoggerProxy, defaultCallbacks, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
from fmpy.validation import validate_fmu

FMU_DIR = sys.argv[1]
PLANNER = f"{FMU_DIR}/plamo-planner.fmu"
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


CHECKS = [check_validate, check_closed_loop_with_string_parameters, check_misuse_is_refused_with_a_message,
          check_unknown_landmark, check_simulate_with_input_file]

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
