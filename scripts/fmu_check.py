"""The bushing FMU under fmpy, a co-simulation master the FMI community uses.

    fmu_check.py trace FMU TRACE [--x0 MM]
        fmpy's validation of the FMU; the FMU stepped by fmpy one model step
        per communication step on the displacements of `bushing-sim run`'s
        trace.csv (written with trace_every = 1): force and energy must equal
        the trace's bit for bit. Then the rollback: a state saved half-way,
        steps taken, the state restored (and once through its serialised
        bytes), the same steps again: identical outputs.

    fmu_check.py misuse FMU
        Each misuse and the status fmpy sees: calls out of order, a
        communication step that is not a whole number of model steps, a NaN
        input, an FMU whose resource model is missing, malformed or changed.

    fmu_check.py time FMU
        Nanoseconds per model step through fmpy's doStep with a 0.1 s
        communication step (printed, not asserted).

Exit status 1 on any failed check. Used by scripts/fmu.sh.
"""

import csv
import math
import os
import shutil
import sys
import tempfile
import time

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

FMI2_ERROR = 3


def fail(message):
    print(f"FAIL: {message}")
    sys.exit(1)


class Fmu:
    """An extracted FMU and its variables by name."""

    def __init__(self, path, directory=None):
        self.md = read_model_description(path, validate=True)
        self.dir = directory or extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.dt = float(self.md.defaultExperiment.stepSize)

    def slave(self, guid=None):
        s = FMU2Slave(
            guid=guid or self.md.guid,
            unzipDirectory=self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="bushing",
        )
        s.instantiate(loggingOn=True)
        return s

    def started(self, x0=0.0):
        s = self.slave()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setReal([self.vr["x"]], [x0])
        s.exitInitializationMode()
        return s

    def outputs(self, s):
        reals = s.getReal([self.vr["force"], self.vr["tangent"], self.vr["energy"]])
        ints = s.getInteger([self.vr["faults"], self.vr["refused"]])
        return tuple(reals) + tuple(ints)


def same_bits(a, b):
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


def check_trace(path, trace, x0):
    problems = validate_fmu(path)
    if problems:
        fail(f"{path}: fmpy's validation: {problems}")
    fmu = Fmu(path)
    with open(trace, newline="") as f:
        rows = list(csv.DictReader(f))
    s = fmu.started(x0)
    t = 0.0
    outputs = []
    for n, row in enumerate(rows):
        s.setReal([fmu.vr["x"]], [float(row["x_mm"])])
        s.doStep(currentCommunicationPoint=n * fmu.dt, communicationStepSize=fmu.dt)
        force, _, energy, faults, _ = out = fmu.outputs(s)
        outputs.append(out)
        for name, got, want in [
            ("force", force, float(row["force_N"])),
            ("energy", energy, float(row["dissipated_mJ"])),
        ]:
            if not same_bits(got, want):
                fail(f"{path}: step {n + 1}: {name} {got!r}, bushing-sim {want!r}")
        if faults:
            fail(f"{path}: step {n + 1}: faults {faults}")
    print(
        f"{os.path.basename(path)}: fmpy validation passed; {len(rows)} steps, force and "
        f"energy equal to bushing-sim's trace bit for bit"
    )

    # Rollback: from the middle of the run, the same steps twice.
    half = len(rows) // 2
    s.terminate()
    s.freeInstance()
    s = fmu.started(x0)
    for n in range(half):
        s.setReal([fmu.vr["x"]], [float(rows[n]["x_mm"])])
        s.doStep(currentCommunicationPoint=n * fmu.dt, communicationStepSize=fmu.dt)
    state = s.getFMUstate()
    span = range(half, min(len(rows), half + 400))

    def replay():
        got = []
        for n in span:
            s.setReal([fmu.vr["x"]], [float(rows[n]["x_mm"])])
            s.doStep(currentCommunicationPoint=n * fmu.dt, communicationStepSize=fmu.dt)
            got.append(fmu.outputs(s))
        return got

    first = replay()
    if first != outputs[span.start : span.stop]:
        fail(f"{path}: the steps after a saved state differ from the first run")
    s.setFMUstate(state)
    if replay() != first:
        fail(f"{path}: rollback: the outputs after fmi2SetFMUstate differ")
    data = s.serializeFMUstate(state)
    restored = s.deSerializeFMUstate(data)
    s.setFMUstate(restored)
    if replay() != first:
        fail(f"{path}: rollback through serialised bytes: the outputs differ")
    s.freeFMUstate(state)
    s.freeFMUstate(restored)
    s.terminate()
    s.freeInstance()
    print(
        f"{os.path.basename(path)}: rollback at step {half}: {len(span)} steps repeated "
        f"bit for bit (saved state, and its {len(data)} serialised bytes)"
    )


def expect_status(what, call, status=FMI2_ERROR):
    try:
        call()
    except FMICallException as e:
        if e.status != status:
            fail(f"{what}: status {e.status}, expected {status}")
        print(f"misuse: {what}: status {e.status} as expected")
        return
    fail(f"{what}: accepted")


def expect_no_instance(what, fmu, guid=None):
    try:
        fmu.slave(guid)
    except Exception as e:  # fmpy raises a plain Exception when the instance is null
        if "instantiate" not in str(e).lower():
            fail(f"{what}: {e}")
        print(f"misuse: {what}: fmi2Instantiate returned null as expected")
        return
    fail(f"{what}: instantiated")


def check_misuse(path):
    fmu = Fmu(path)
    dt = fmu.dt

    s = fmu.slave()
    expect_status("fmi2DoStep before initialisation", lambda: s.doStep(0.0, dt))
    s.reset()
    s.setupExperiment(startTime=0.0)
    expect_status("fmi2ExitInitializationMode before enter", s.exitInitializationMode)
    s.freeInstance()

    s = fmu.started()
    expect_status("fmi2EnterInitializationMode twice", s.enterInitializationMode)
    s.freeInstance()

    for h in [0.5 * dt, 2.5 * dt, 0.0, -dt]:
        s = fmu.started()
        expect_status(f"fmi2DoStep with h = {h / dt} dt", lambda: s.doStep(0.0, h))
        s.freeInstance()

    s = fmu.started()
    s.doStep(0.0, 4 * dt)
    expect_status("fmi2DoStep at a point already passed", lambda: s.doStep(0.0, dt))
    s.freeInstance()

    s = fmu.started()
    expect_status("fmi2SetReal x = NaN", lambda: s.setReal([fmu.vr["x"]], [float("nan")]))
    # An error is left through a state saved before it.
    s.freeInstance()
    s = fmu.started()
    saved = s.getFMUstate()
    expect_status("fmi2SetReal x = inf", lambda: s.setReal([fmu.vr["x"]], [float("inf")]))
    s.setFMUstate(saved)
    s.doStep(0.0, dt)
    s.freeFMUstate(saved)
    print("misuse: fmi2SetFMUstate after an error: the instance steps again")
    expect_status("fmi2SetReal of an output", lambda: s.setReal([fmu.vr["force"]], [1.0]))
    s.freeInstance()

    s = fmu.started()
    expect_status("fmi2GetDirectionalDerivative (not provided)",
                  lambda: s.getDirectionalDerivative([fmu.vr["force"]], [fmu.vr["x"]], [1.0]))
    s.freeInstance()

    expect_no_instance("another GUID", fmu, "{00000000-0000-0000-0000-000000000000}")
    with tempfile.TemporaryDirectory() as tmp:
        copy = os.path.join(tmp, "fmu")
        shutil.copytree(fmu.dir, copy)
        model = os.path.join(copy, "resources", "model.toml")
        changed = Fmu(path, copy)
        with open(model) as f:
            text = f.read()
        with open(model, "w") as f:
            f.write(text.replace("[backbone]", "[backbone\n"))
        expect_no_instance("a malformed resource model", changed)
        with open(model, "w") as f:
            f.write(text + "\n# edited\n")
        expect_no_instance("a resource model changed after packing", changed)
        os.remove(model)
        expect_no_instance("a missing resource model", changed)


def check_time(path):
    fmu = Fmu(path)
    h = 0.1
    per_call = round(h / fmu.dt)
    calls = 100
    for label, amplitude in [("2 mm, 5 Hz", 2.0), ("0.01 mm, 5 Hz", 0.01)]:
        s = fmu.started()
        x, step = fmu.vr["x"], s.doStep
        start = time.perf_counter()
        for k in range(calls):
            s.setReal([x], [amplitude * math.sin(2 * math.pi * 5 * (k + 0.25) * h)])
            step(k * h, h)
        elapsed = time.perf_counter() - start
        s.freeInstance()
        ns = elapsed / (calls * per_call) * 1e9
        print(
            f"{os.path.basename(path)}: {ns:.1f} ns per model step through fmpy's doStep "
            f"(h = {h} s, {per_call} model steps per call, {calls} calls, input {label} "
            f"held over each call)"
        )
    # One model step per call: the master's overhead alone, for scale.
    s = fmu.started()
    x, step, dt = fmu.vr["x"], s.doStep, fmu.dt
    n = 20_000
    start = time.perf_counter()
    for k in range(n):
        s.setReal([x], [2.0 * math.sin(2 * math.pi * 5 * k * dt)])
        step(k * dt, dt)
    elapsed = time.perf_counter() - start
    s.freeInstance()
    print(
        f"{os.path.basename(path)}: {elapsed / n * 1e9:.0f} ns per call with one model step "
        f"per call (setReal and doStep from Python: fmpy's overhead)"
    )


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "trace":
        x0 = float(sys.argv[5]) if len(sys.argv) >= 6 and sys.argv[4] == "--x0" else 0.0
        check_trace(sys.argv[2], sys.argv[3], x0)
    elif len(sys.argv) == 3 and sys.argv[1] == "misuse":
        check_misuse(sys.argv[2])
    elif len(sys.argv) == 3 and sys.argv[1] == "time":
        check_time(sys.argv[2])
    else:
        print(__doc__)
        sys.exit(2)


if __name__ == "__main__":
    main()
