#!/usr/bin/env python3
"""Co-simulation of the footing FMU (cases/footing_fmu.json) with a spring-mass in Python.

A mass m sits on the strip footing and is pushed down by a spring of stiffness k whose
top is held a distance d lower than its free length (a jack preload), with a damper c:

    m s'' = k (d - s) - R(s) - c s',        R(s) = -soil_force (the soil's resistance)

where s is the settlement (the FMU input) and R the soil reaction the FMU returns after
each communication step (quasi-static Mohr-Coulomb soil). Staggered explicit coupling:
at t_k the master sets s_k, steps the FMU to t_k + h, reads R(s_k) and advances the mass
(semi-implicit Euler). The system is overdamped, so the footing is loaded monotonically.

Checks: the mass comes to rest where the spring force equals the soil reaction
(k (d - s*) = R(s*) within 0.5 %), the footing never unloads, and R(s*) agrees within 1 %
with the force-settlement curve of a plain `loam run` of the same case (20 mm push).

Run alone: .venv/bin/python tests/fmu/footing_spring_mass.py (after cargo build --release
--workspace); tests/fmu/test_fmu.py runs it as one of its checks.
"""

import sys
import tempfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "footing_fmu.json"

K_SPRING = 2.0e7  # N/m per metre of strip
PRELOAD = 0.045  # m: spring compression at s = 0
MASS = 5.5e5  # kg per metre: natural frequency about 10 rad/s with the soil's stiffness
DAMPING = 1.3e7  # N s/m: a little over critical
H = 0.01  # s: communication step
T_END = 3.0  # s


def run(loam, work):
    import subprocess

    fmu_path = Path(work) / "footing.fmu"
    subprocess.run([str(loam), "fmu", str(CASE), "-o", str(fmu_path)], check=True, capture_output=True)
    out = Path(work) / "run_footing"
    subprocess.run([str(loam), "run", str(CASE), "--out", str(out), "--quiet"], check=True, capture_output=True)
    curve = np.genfromtxt(out / "monitors.csv", delimiter=",", names=True)

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmu_path)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="footing",
    )
    fmu.instantiate()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    s, v, t = 0.0, 0.0, 0.0
    history = []
    for _ in range(round(T_END / H)):
        fmu.setFloat64([vr["settlement"]], [s])
        fmu.doStep(t, H)
        t += H
        reaction = -fmu.getFloat64([vr["soil_force"]])[0]
        a = (K_SPRING * (PRELOAD - s) - reaction - DAMPING * v) / MASS
        v += H * a
        s += H * v
        history.append((t, s, v, reaction))
    fmu.terminate()
    fmu.freeInstance()

    h = np.array(history)
    s_end, v_end, r_end = h[-1, 1], h[-1, 2], h[-1, 3]
    spring = K_SPRING * (PRELOAD - s_end)
    balance = abs(spring - r_end) / r_end
    unloading = float(np.max(np.maximum(-np.diff(h[:, 1]), 0.0)))
    r_curve = float(np.interp(s_end, -curve["footing_uy"], -curve["footing_force"]))
    curve_diff = abs(r_end - r_curve) / r_curve
    detail = (
        f"settles at s = {1e3 * s_end:.3f} mm (v = {v_end:.1e} m/s): spring force {spring / 1e3:.2f} kN/m, "
        f"soil reaction {r_end / 1e3:.2f} kN/m (balance {balance:.1e}, tolerance 5e-3); "
        f"loam run's curve at that settlement {r_curve / 1e3:.2f} kN/m (difference {curve_diff:.1e}, tolerance 1e-2)"
    )
    assert 0.005 < s_end < 0.02, f"settlement {s_end} m outside the loam run curve; {detail}"
    assert abs(v_end) < 1e-5, f"not at rest: {detail}"
    assert balance < 5e-3, f"spring force and soil reaction differ: {detail}"
    assert unloading < 1e-9, f"the footing unloaded by {unloading} m: {detail}"
    assert curve_diff < 1e-2, f"co-simulated reaction off the loam run curve: {detail}"
    return detail


if __name__ == "__main__":
    loam = ROOT / "target" / "release" / "loam"
    try:
        print("PASS footing_spring_mass:", run(loam, tempfile.mkdtemp(prefix="loam_footing_")))
        print("1 passed, 0 failed")
    except Exception as e:  # noqa: BLE001
        print("FAIL footing_spring_mass:", e)
        print("0 passed, 1 failed")
        sys.exit(1)
