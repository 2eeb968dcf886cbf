#!/usr/bin/env python3
"""FMU robustness with fmpy (issue 16 item 6): the host never crashes, whatever it calls.

The cantilever FMU (cases/cantilever_fmu.json: input tip_force in N, outputs tip_uy and
clamp_reaction_y) is driven through:

- 100 instantiations, each initialised, stepped 5 times and freed, in one process: the
  resident memory (RSS, /proc/self/status) after the last may exceed that after the first
  10 by at most 8 MB (a leaked instance of this case holds several MB);
- reset: after 20 steps, reset and a rerun give the first run's outputs bit for bit; reset
  after a discarded step works too;
- NaN, +inf, -inf inputs: fmi3Error, the input unchanged; a huge finite input (1e300 N) that
  no Newton iteration survives: fmi3Discard at the last converged time, never a crash;
- communication steps negative, zero, NaN, infinite, of more case steps than `limits.steps`
  (1e300 s, 1e5 s), or from a wrong or NaN time: fmi3Error;
- a failing step: fmi3Discard with lastSuccessfulTime and terminateSimulation set; further
  steps are refused with fmi3Error/fmi3Discard until a reset, after which the instance runs
  again;
- calls out of order (doStep before initialisation, after terminate; setFloat64 on an
  output or an unknown value reference; getFloat64 of an unknown one): fmi3Error;
- instantiation with a wrong token or resource path: NULL, no crash; fmi3FreeInstance(NULL)
  is harmless;
- two instances stepped alternately give the results of each alone.

Run: scripts/test.sh (or `.venv/bin/python tests/fmu/test_fmu_robustness.py` after
`cargo build --release --workspace`). Prints `N passed, M failed` last.
"""

import ctypes
import json
import math
import shutil
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi3 import FMU3Slave  # noqa: E402

from test_fmu import ROOT, WORK, expect_status, package, run_checks, write_case  # noqa: E402

CASE = ROOT / "cases" / "cantilever_fmu.json"
DT = 0.01
RSS_BOUND_MB = 8.0


def rss_mb():
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


class Harness:
    """One unzipped FMU, instantiated as often as asked."""

    def __init__(self, fmu_path):
        self.md = read_model_description(str(fmu_path))
        self.dir = extract(str(fmu_path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []

    def new(self, name="robust", token=None, unzipped=None):
        fmu = FMU3Slave(
            guid=token if token is not None else self.md.guid,
            unzipDirectory=unzipped or self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )

        def log(env, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        fmu.instantiate(logMessage=log)
        return fmu

    def ready(self, name="robust"):
        fmu = self.new(name)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        return fmu

    def outputs(self, fmu):
        return fmu.getFloat64([self.vr["time"], self.vr["tip_uy"], self.vr["clamp_reaction_y"]])


def steps(h, fmu, n, force=5.0e4, t0=0.0):
    """n communication steps of DT from t0 at a tip force; the outputs after each."""
    rows = []
    fmu.setFloat64([h.vr["tip_force"]], [force])
    for k in range(n):
        fmu.doStep(t0 + k * DT, DT)
        rows.append(h.outputs(fmu))
    return rows


def check_instantiations():
    """100 instantiate / initialise / 5 steps / terminate / free cycles in one process:
    RSS after the 100th within RSS_BOUND_MB of that after the 10th."""
    h = Harness(package(CASE, "robust_instances"))
    rss = []
    first = None
    for k in range(100):
        fmu = h.ready(f"instance{k}")
        rows = steps(h, fmu, 5)
        if first is None:
            first = rows
        assert rows == first, f"instance {k} differs from the first"
        fmu.terminate()
        fmu.freeInstance()
        rss.append(rss_mb())
    growth = rss[-1] - rss[9]
    # what a leaked instance would cost: 10 instances kept alive after 5 steps each
    before = rss_mb()
    alive = [h.ready(f"alive{k}") for k in range(10)]
    for fmu in alive:
        steps(h, fmu, 5)
    per_instance = (rss_mb() - before) / 10
    for fmu in alive:
        fmu.terminate()
        fmu.freeInstance()
    assert growth <= RSS_BOUND_MB, f"RSS grew by {growth:.1f} MB from instance 10 to 100"
    return (
        f"RSS {rss[0]:.1f} MB after 1, {rss[9]:.1f} MB after 10, {rss[49]:.1f} MB after 50, "
        f"{rss[-1]:.1f} MB after 100 instantiations (growth 10 -> 100: {growth:+.2f} MB, bound {RSS_BOUND_MB} MB; "
        f"an instance kept alive holds {per_instance:.2f} MB, so 90 leaked ones would add {90 * per_instance:.0f} MB); "
        f"all 100 gave identical outputs"
    )


def check_reset():
    """Reset after 20 steps and after a discarded step: a rerun equals the first run bit for bit."""
    h = Harness(package(CASE, "robust_reset"))
    fmu = h.ready()
    first = steps(h, fmu, 20)
    fmu.reset()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    assert h.outputs(fmu) == [0.0, 0.0, 0.0], h.outputs(fmu)
    again = steps(h, fmu, 20)
    assert again == first, "rerun after reset differs"
    # a step that fails, then reset
    fmu.setFloat64([h.vr["tip_force"]], [1.0e300])
    expect_status(2, fmu.doStep, 20 * DT, DT)
    fmu.reset()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    third = steps(h, fmu, 20)
    assert third == first, "rerun after a discard and reset differs"
    fmu.terminate()
    fmu.freeInstance()
    return f"20 steps, reset, 20 steps: identical (tip_uy {first[-1][1]:.9e} m); also after a discarded step"


def check_non_finite_inputs():
    """NaN, +inf, -inf -> fmi3Error, value unchanged; 1e300 N -> fmi3Discard, no crash."""
    h = Harness(package(CASE, "robust_inputs"))
    fmu = h.ready()
    fmu.setFloat64([h.vr["tip_force"]], [1.0e4])
    for bad in [math.nan, math.inf, -math.inf]:
        expect_status(3, fmu.setFloat64, [h.vr["tip_force"]], [bad])
        assert fmu.getFloat64([h.vr["tip_force"]]) == [1.0e4], "a rejected value must change nothing"
    # a mixed call: the finite value must not be applied either
    expect_status(3, fmu.setFloat64, [h.vr["tip_force"], h.vr["tip_force"]], [2.0e4, math.nan])
    assert fmu.getFloat64([h.vr["tip_force"]]) == [1.0e4]
    fmu.doStep(0.0, DT)
    for huge in [1.0e300, -1.0e300, 1.0e308]:
        fmu.setFloat64([h.vr["tip_force"]], [huge])
        try:
            fmu.doStep(DT, DT)
            raise AssertionError(f"a force of {huge} N converged")
        except FMICallException as e:
            assert e.status == 2, f"status {e.status} for {huge} N"
        t = fmu.getFloat64([h.vr["time"]])[0]
        assert t == DT, f"time {t} after a discarded step"
        fmu.reset()
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.setFloat64([h.vr["tip_force"]], [1.0e4])
        fmu.doStep(0.0, DT)
    fmu.terminate()
    fmu.freeInstance()
    return "NaN, +inf, -inf refused (fmi3Error, value kept); 1e300, -1e300, 1e308 N: fmi3Discard at the last converged time"


def check_bad_steps():
    """Negative, zero, NaN, infinite step sizes and wrong or NaN communication points -> fmi3Error."""
    h = Harness(package(CASE, "robust_steps"))
    fmu = h.ready()
    for t, step in [(0.0, -DT), (0.0, 0.0), (0.0, math.nan), (0.0, math.inf), (0.0, -math.inf),
                    (0.0, 1e300), (0.0, 1e5), (0.5, DT), (math.nan, DT), (-DT, DT), (math.inf, DT),
                    (0.0, 1e-300)]:
        if step == 1e-300:
            # a positive step far below the case's step: accepted (lands on t + h) or refused, never a crash
            try:
                fmu.doStep(t, step)
                fmu.reset()
                fmu.enterInitializationMode()
                fmu.exitInitializationMode()
            except FMICallException as e:
                assert e.status in (2, 3), e.status
            continue
        expect_status(3, fmu.doStep, t, step)
    assert fmu.getFloat64([h.vr["time"]]) == [0.0]
    fmu.doStep(0.0, DT)
    assert fmu.getFloat64([h.vr["time"]]) == [DT]
    fmu.terminate()
    fmu.freeInstance()
    errors = [m for s, c, m in h.messages if s == 3 and "limits.steps" in m]
    assert errors, "a step of 1e300 s names limits.steps"
    return f"12 bad (t, h) pairs refused or handled, e.g. '{errors[0]}'; the instance then steps normally"


def check_failing_step():
    """A step that cannot converge: fmi3Discard, lastSuccessfulTime = last converged time,
    terminateSimulation true; later steps do not crash; reset makes it usable again."""

    def one_iteration(data):
        data["solver"]["max_iterations"] = 1
        data["analysis"]["max_step_cuts"] = 1

    case = write_case(CASE, "robust_failing", one_iteration)
    h = Harness(package(case, "robust_failing"))
    fmu = h.ready()
    fmu.setFloat64([h.vr["tip_force"]], [0.0])
    fmu.doStep(0.0, DT)  # at rest: converges in one iteration
    fmu.setFloat64([h.vr["tip_force"]], [1.0e6])
    # call the C function directly to read lastSuccessfulTime and terminateSimulation
    event, terminate, early = ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool()
    last = ctypes.c_double(-1.0)
    status = fmu.dll.fmi3DoStep(
        fmu.component, ctypes.c_double(DT), ctypes.c_double(DT), ctypes.c_bool(True),
        ctypes.byref(event), ctypes.byref(terminate), ctypes.byref(early), ctypes.byref(last),
    )
    assert status == 2, f"status {status}"
    assert last.value == DT and terminate.value, (last.value, terminate.value)
    for _ in range(3):
        try:
            fmu.doStep(DT, DT)
        except FMICallException as e:
            assert e.status in (2, 3), e.status
    fmu.reset()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, DT)
    fmu.terminate()
    fmu.freeInstance()
    discards = [m for s, c, m in h.messages if s == 2]
    return f"fmi3Discard, lastSuccessfulTime {last.value}, terminateSimulation {terminate.value}: '{discards[0][:90]}...'"


def check_call_order():
    """Calls in the wrong mode or with wrong references -> fmi3Error, never a crash."""
    h = Harness(package(CASE, "robust_order"))
    fmu = h.new()
    expect_status(3, fmu.doStep, 0.0, DT)  # before initialisation
    expect_status(3, fmu.exitInitializationMode)  # not in initialisation mode
    fmu.enterInitializationMode()
    expect_status(3, fmu.enterInitializationMode)  # twice
    fmu.exitInitializationMode()
    expect_status(3, fmu.setFloat64, [h.vr["tip_uy"]], [1.0])  # an output
    expect_status(3, fmu.setFloat64, [999], [1.0])  # no such reference
    expect_status(3, fmu.getFloat64, [999])
    expect_status(3, fmu.getInt32, [h.vr["time"]])  # not provided
    fmu.doStep(0.0, DT)
    fmu.terminate()
    expect_status(3, fmu.doStep, DT, DT)  # after terminate
    expect_status(3, fmu.setFloat64, [h.vr["tip_force"]], [1.0])
    fmu.freeInstance()
    errors = [m for s, c, m in h.messages if s == 3]
    return f"{len(errors)} errors logged, e.g. '{errors[0]}'"


def broken_copy(h, name, damage):
    """A copy of the unzipped FMU with `damage(resources)` applied."""
    target = WORK / name
    shutil.copytree(h.dir, target)
    damage(target / "resources")
    return str(target)


def check_bad_instantiation():
    """A wrong token, missing resources, a corrupt manifest or a bad case give NULL (fmpy
    raises), fmi3FreeInstance(NULL) is harmless."""
    h = Harness(package(CASE, "robust_instantiate"))
    manifest = json.loads((Path(h.dir) / "resources" / "loam_fmu.json").read_text())
    damages = {
        "no_resources": lambda r: shutil.rmtree(r),
        "corrupt_manifest": lambda r: (r / "loam_fmu.json").write_text("{"),
        "bad_case": lambda r: (r / manifest["case"]).write_text('{"description": 1}'),
        "missing_case": lambda r: (r / manifest["case"]).unlink(),
    }
    refused = 0
    attempts = [{"token": "{00000000-0000-0000-0000-000000000000}"}]
    attempts += [{"unzipped": broken_copy(h, f"broken_{k}", d)} for k, d in damages.items()]
    for kwargs in attempts:
        try:
            h.new(**kwargs)
            raise AssertionError(f"instantiated with {kwargs}")
        except Exception as e:  # noqa: BLE001 - fmpy raises a plain Exception on NULL
            if isinstance(e, AssertionError):
                raise
            refused += 1
    lib = ctypes.CDLL(str(next(Path(h.dir, "binaries").rglob("*.so"))))
    lib.fmi3FreeInstance(None)
    lib.fmi3DoStep.restype = ctypes.c_int
    status = lib.fmi3DoStep(None, ctypes.c_double(0.0), ctypes.c_double(DT), ctypes.c_bool(True),
                            None, None, None, None)
    assert status == 3, status
    errors = [m for s, c, m in h.messages if s == 3]
    return f"{refused} instantiations refused (NULL), e.g. '{errors[0][:80]}...'; NULL instance: fmi3Error"


def check_two_instances():
    """Two instances stepped alternately give the outputs of each run alone."""
    h = Harness(package(CASE, "robust_two"))
    a, b = h.ready("a"), h.ready("b")
    a.setFloat64([h.vr["tip_force"]], [5.0e4])
    b.setFloat64([h.vr["tip_force"]], [2.0e4])
    ra, rb = [], []
    for k in range(10):
        a.doStep(k * DT, DT)
        b.doStep(k * DT, DT)
        ra.append(h.outputs(a))
        rb.append(h.outputs(b))
    for f in (a, b):
        f.terminate()
        f.freeInstance()
    alone_a = steps(h, h.ready("a_alone"), 10, force=5.0e4)
    alone_b = steps(h, h.ready("b_alone"), 10, force=2.0e4)
    assert ra == alone_a and rb == alone_b, "interleaved instances differ from each alone"
    return f"interleaved = alone (tip_uy {ra[-1][1]:.6e} and {rb[-1][1]:.6e} m)"


CHECKS = [
    check_instantiations,
    check_reset,
    check_non_finite_inputs,
    check_bad_steps,
    check_failing_step,
    check_call_order,
    check_bad_instantiation,
    check_two_instances,
]


def main():
    return run_checks(CHECKS)


if __name__ == "__main__":
    sys.exit(main())
