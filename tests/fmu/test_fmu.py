#!/usr/bin/env python3
"""FMI 3.0 FMUs of Loam cases, checked with fmpy (issue 6).

Each check packages a case with `loam fmu`, runs it in fmpy and compares with `loam run`
of the same case:

- fmpy's validate_fmu finds no problem in the model descriptions;
- simulate_fmu on the static and the dynamic cantilever reproduces `loam run`'s monitors
  within 1e-8 at every communication point (also with 5 case steps per communication step);
- an input ramp on the tip load gives the run of a case whose load amplitude is the same
  ramp, held over each communication step (zero-order hold: the value set at t_k acts on
  (t_k, t_k+1]);
- NaN inputs, negative or misplaced steps return fmi3Error, a step that does not converge
  fmi3Discard at the last converged time; the instance stays usable and resets;
- `loam fmu` exits 2 on a bad case and 1 without the shared library;
- the footing co-simulation with a spring-mass (footing_spring_mass.py) settles where the
  spring force equals the soil reaction.

Run: scripts/test.sh (or, after `cargo build --release --workspace`,
`.venv/bin/python tests/fmu/test_fmu.py`). Prints `N passed, M failed` last and exits 1 if
any check failed or none ran.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import traceback
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
LOAM = ROOT / "target" / "release" / "loam"
WORK = Path(tempfile.mkdtemp(prefix="loam_fmu_test_"))
TOL = 1e-8

sys.path.insert(0, str(Path(__file__).resolve().parent))


def loam(*args, check=True):
    p = subprocess.run([str(LOAM), *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise RuntimeError(f"loam {' '.join(map(str, args))} exited {p.returncode}: {p.stderr.strip()}")
    return p


def package(case, name):
    fmu = WORK / f"{name}.fmu"
    loam("fmu", case, "-o", fmu)
    return fmu


def run_cli(case, name):
    out = WORK / f"run_{name}"
    loam("run", case, "--out", out, "--quiet")
    return np.genfromtxt(out / "monitors.csv", delimiter=",", names=True)


def max_difference(fmu_result, cli, names):
    """Largest |FMU - CLI| over the outputs `names` at the communication points."""
    assert len(fmu_result) == len(cli), f"{len(fmu_result)} FMU rows, {len(cli)} CLI rows"
    assert np.max(np.abs(fmu_result["time"] - cli["time"])) < 1e-9, "communication points differ from CLI times"
    return max(float(np.max(np.abs(fmu_result[n] - cli[n]))) for n in names)


def write_case(case, name, edit):
    data = json.loads(Path(case).read_text())
    edit(data)
    path = WORK / f"{name}.json"
    path.write_text(json.dumps(data, indent=1))
    return path


# ---------------------------------------------------------------- checks


def check_validate():
    """fmpy's validate_fmu: schema, variable names, model structure, start values, units."""
    problems = {}
    for case in ["cantilever_fem", "cantilever_fem_dynamic", "cantilever_fmu", "footing_fmu"]:
        p = validate_fmu(str(package(ROOT / "cases" / f"{case}.json", case)))
        if p:
            problems[case] = p
    assert not problems, problems
    return "4 FMUs, no problems"


def check_static_cantilever():
    """Acceptance: loam fmu cases/cantilever_fem.json, simulate_fmu == loam run (tip_uy, ...)."""
    fmu = package(ROOT / "cases" / "cantilever_fem.json", "static")
    r = simulate_fmu(str(fmu), stop_time=1.0)
    cli = run_cli(ROOT / "cases" / "cantilever_fem.json", "static")
    d = max_difference(r, cli, ["tip_uy", "tip_ux", "clamp_reaction_y", "strain_energy"])
    assert d <= TOL, f"max |FMU - CLI| = {d:.3e} > {TOL}"
    return f"tip_uy FMU {r['tip_uy'][-1]:.12f} m, CLI {cli['tip_uy'][-1]:.12f} m; max |difference| {d:.2e} (tolerance {TOL})"


def check_dynamic_cantilever():
    """Dynamic cantilever, 300 steps: every output at every communication point, with one
    and with five case steps per communication step."""
    fmu = package(ROOT / "cases" / "cantilever_fem_dynamic.json", "dynamic")
    cli = run_cli(ROOT / "cases" / "cantilever_fem_dynamic.json", "dynamic")
    names = ["tip_uy", "kinetic_energy", "strain_energy"]
    r = simulate_fmu(str(fmu), stop_time=3.0)
    d1 = max_difference(r, cli, names)
    r5 = simulate_fmu(str(fmu), stop_time=3.0, output_interval=0.05)
    d5 = max_difference(r5, cli[::5], names)
    assert np.ptp(r["tip_uy"]) > 0.5, "the tip should oscillate"
    assert d1 <= TOL and d5 <= TOL, f"max |FMU - CLI| = {d1:.3e} (h = dt), {d5:.3e} (h = 5 dt) > {TOL}"
    return f"301 points: max |difference| {d1:.2e} (h = 0.01 s), {d5:.2e} (h = 0.05 s) (tolerance {TOL})"


def check_input_ramp():
    """Tip force ramp 0 -> 100 kN over 1 s through the FMU input, against `loam run` of the
    case whose load amplitude is the held ramp A(t_k+1) = u(t_k)."""
    case = ROOT / "cases" / "cantilever_fmu.json"
    fmu = package(case, "ramp")
    signal = np.array([(0.0, 0.0), (1.0, 1.0e5)], dtype=[("time", np.float64), ("tip_force", np.float64)])
    r = simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.01, input=signal)
    h = 0.01

    def held_ramp(data):
        data["loads"][0]["amplitude"] = [[h, 0.0], [1.0, 1.0e5 * (1.0 - h)]]

    cli = run_cli(write_case(case, "ramp_table", held_ramp), "ramp")
    d_uy = max_difference(r, cli, ["tip_uy"])
    d_r = max_difference(r, cli, ["clamp_reaction_y"])
    scale_r = float(np.max(np.abs(cli["clamp_reaction_y"])))
    # without the input the beam stays at rest (start value 0)
    r0 = simulate_fmu(str(fmu), stop_time=0.2)
    assert np.max(np.abs(r0["tip_uy"])) == 0.0, "start value 0 should leave the beam at rest"
    assert abs(r["tip_uy"][-1]) > 1e-3, "the ramp should bend the beam"
    assert d_uy <= TOL and d_r <= TOL * scale_r, f"tip_uy {d_uy:.3e} m, reaction {d_r:.3e} N"
    return (
        f"final tip_uy {r['tip_uy'][-1]:.9f} m; max |difference| tip_uy {d_uy:.2e} m (tolerance {TOL}), "
        f"reaction {d_r:.2e} N of {scale_r:.3e} N (tolerance {TOL:g} relative)"
    )


def instance(fmu_path, messages, name="check"):
    md = read_model_description(str(fmu_path))
    unzipped = extract(str(fmu_path))
    fmu = FMU3Slave(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=name,
    )

    def log(env, status, category, message):
        messages.append((status, category.decode(), message.decode()))

    fmu.instantiate(logMessage=log)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, vr


def expect_status(status, f, *args):
    try:
        f(*args)
    except FMICallException as e:
        assert e.status == status, f"status {e.status}, expected {status}"
        return
    raise AssertionError(f"call returned OK, expected status {status}")


def check_bad_inputs():
    """NaN input, negative step, wrong communication point -> fmi3Error; the instance goes
    on; reset returns to t = 0 with the start values."""
    messages = []
    fmu, vr = instance(package(ROOT / "cases" / "cantilever_fmu.json", "bad"), messages)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    expect_status(3, fmu.setFloat64, [vr["tip_force"]], [math.nan])
    expect_status(3, fmu.setFloat64, [vr["tip_force"]], [math.inf])
    expect_status(3, fmu.setFloat64, [vr["tip_uy"]], [1.0])
    assert fmu.getFloat64([vr["tip_force"]]) == [0.0], "a rejected value must change nothing"
    expect_status(3, fmu.doStep, 0.0, -0.01)
    expect_status(3, fmu.doStep, 0.0, 0.0)
    expect_status(3, fmu.doStep, 0.5, 0.01)
    fmu.setFloat64([vr["tip_force"]], [5.0e4])
    fmu.doStep(0.0, 0.02)
    t, uy = fmu.getFloat64([vr["time"], vr["tip_uy"]])
    assert abs(t - 0.02) < 1e-12 and uy < 0.0, (t, uy)
    fmu.reset()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    assert fmu.getFloat64([vr["time"], vr["tip_uy"], vr["tip_force"]]) == [0.0, 0.0, 0.0]
    fmu.terminate()
    fmu.freeInstance()
    errors = [m for s, c, m in messages if s == 3]
    assert any("must be finite" in m for m in errors), errors
    assert any("communicationStepSize" in m for m in errors), errors
    return f"{len(errors)} error messages, e.g. '{errors[0]}'"


def check_non_convergence():
    """A step that cannot converge (one Newton iteration allowed, no cuts) -> fmi3Discard at
    the last converged time, and a logged reason."""

    def one_iteration(data):
        data["solver"]["max_iterations"] = 1
        data["analysis"]["max_step_cuts"] = 1

    case = write_case(ROOT / "cases" / "cantilever_fmu.json", "diverging", one_iteration)
    messages = []
    fmu, vr = instance(package(case, "diverging"), messages)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.setFloat64([vr["tip_force"]], [1.0e6])
    expect_status(2, fmu.doStep, 0.0, 0.01)
    assert fmu.getFloat64([vr["time"]]) == [0.0]
    fmu.freeInstance()
    discards = [m for s, c, m in messages if s == 2]
    assert discards and "did not converge" in discards[0], messages
    return discards[0][:110] + "..."


def check_cli_errors():
    """`loam fmu` on a bad case exits 2 naming the JSON path; without the library exits 1."""

    def bad_target(data):
        data["fmu"]["inputs"][0]["drives"] = {"load": "nope"}

    bad = write_case(ROOT / "cases" / "cantilever_fmu.json", "bad_target", bad_target)
    p = loam("fmu", bad, "-o", WORK / "x.fmu", check=False)
    assert p.returncode == 2 and "fmu.inputs[0].drives.load" in p.stderr, (p.returncode, p.stderr)
    q = loam("fmu", ROOT / "cases" / "cantilever_fem.json", "-o", WORK / "y.fmu", "--library", WORK / "no.so", check=False)
    assert q.returncode == 1 and "not found" in q.stderr, (q.returncode, q.stderr)
    return f"exit 2: {p.stderr.strip()} | exit 1: {q.stderr.strip()[:60]}..."


def check_footing_spring_mass():
    """Footing FMU + Python spring-mass: equilibrium where spring force = soil reaction."""
    import footing_spring_mass

    return footing_spring_mass.run(LOAM, WORK)


def check_coupled_rubber_plate():
    """Issue 13: the coupled soil-structure case (Bui column onto the rubber plate, MPM soil
    and FEM plate in one Newton system) as an FMU: with fixed steps of 1 ms to 0.15 s (past
    the impact at about 0.11 s) the FMU's outputs equal `loam run`'s at every communication
    point (5 ms); with the gravity_factor input at 0 nothing moves."""
    def fixed_steps(data):
        data["analysis"].pop("adaptive")
        data["analysis"].pop("stop_at_rest")
        data["analysis"]["time_step"] = 0.001
        data["analysis"]["end_time"] = 0.15
        data["output"] = {"vtk": False}

    case = write_case(ROOT / "cases" / "coupled_collapse_rubber.json", "coupled_rubber", fixed_steps)
    fmu = package(case, "coupled_rubber")
    problems = validate_fmu(str(fmu))
    assert not problems, problems
    names = ["obstacle_force_x", "obstacle_top_ux", "clamp_reaction_x"]
    r = simulate_fmu(str(fmu), stop_time=0.15, output_interval=0.005)
    cli = run_cli(case, "coupled_rubber")
    d = max_difference(r, cli[::5], names)
    peak = float(np.max(r["obstacle_force_x"]))
    assert peak > 10.0, f"the soil reaches the plate (peak force {peak} N)"
    assert d <= TOL * max(1.0, peak), f"max |FMU - CLI| = {d:.3e}"
    still = simulate_fmu(str(fmu), stop_time=0.02, output_interval=0.005, start_values={"gravity_factor": 0.0})
    moved = max(float(np.max(np.abs(still[n]))) for n in names)
    assert moved < 1e-9, f"weightless soil moves the plate: {moved}"
    return (f"31 points: max |FMU - CLI| {d:.2e}; peak force on the plate {peak:.1f} N/m, "
            f"top ux {1e3 * float(r['obstacle_top_ux'][-1]):.3f} mm at 0.15 s; gravity_factor 0: |outputs| < {moved:.1e}")


CHECKS = [
    check_validate,
    check_static_cantilever,
    check_dynamic_cantilever,
    check_input_ramp,
    check_bad_inputs,
    check_non_convergence,
    check_cli_errors,
    check_footing_spring_mass,
    check_coupled_rubber_plate,
]


def run_checks(checks):
    """Runs each check (a function returning a detail line or raising), prints PASS/FAIL
    lines and the count; exit status 0 only if all passed."""
    if not LOAM.exists():
        print(f"error: {LOAM} not found: run `cargo build --release --workspace` first")
        return 1
    passed = failed = 0
    for check in checks:
        try:
            detail = check()
            passed += 1
            print(f"PASS {check.__name__}: {detail}", flush=True)
        except Exception as e:  # noqa: BLE001 - every failure is reported, then counted
            failed += 1
            print(f"FAIL {check.__name__}: {e}", flush=True)
            traceback.print_exc()
    print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 and passed > 0 else 1


def main():
    return run_checks(CHECKS)


if __name__ == "__main__":
    sys.exit(main())
