#!/usr/bin/env python3
"""Tutorial 6: a Loam case as an FMU, driven from a Python loop with fmpy.

Packages cantilever_fmu.json (beside this script) with `loam fmu`, then searches for the
tip force that deflects the cantilever's free end by TARGET metres: each iteration sets the
FMU input `tip_force`, advances the FMU by one communication step (one static load step of
the case), reads the output `tip_uy` and updates the force by the secant method.

    python3 find_tip_force.py [OUT_DIR]

`loam` is taken from the environment variable LOAM, else from target/release/ of the
repository, else from the PATH. Writes OUT_DIR/secant.csv (iteration, tip_force_N,
tip_uy_m; default OUT_DIR: out/tutorial_fmu) and prints the force found beside
Timoshenko's. Needs fmpy (pip install fmpy; scripts/test.sh sets up .venv with it).
"""

import csv
import os
import shutil
import subprocess
import sys
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

HERE = Path(__file__).resolve().parent
CASE = HERE / "cantilever_fmu.json"
TARGET = -0.1  # m: the tip deflection sought
TOLERANCE = 1e-6  # m: stop when |tip_uy - TARGET| is below this

# Timoshenko beam, bending + shear: delta = P L^3 / (3 E I) + P L / (kappa G A)
L, H, E, KAPPA = 7.0, 1.0, 9.0e7, 5.0 / 6.0
G = E / 2.0  # nu = 0
COMPLIANCE = L**3 / (3.0 * E * H**3 / 12.0) + L / (KAPPA * G * H)  # m per N
P_TIMOSHENKO = -TARGET / COMPLIANCE


def find_loam():
    if os.environ.get("LOAM"):
        return os.environ["LOAM"]
    built = HERE.parents[2] / "target" / "release" / "loam"
    if built.exists():
        return str(built)
    found = shutil.which("loam")
    if not found:
        sys.exit("loam not found: set LOAM, build with `cargo build --release`, or put loam on the PATH")
    return found


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/tutorial_fmu")
    out.mkdir(parents=True, exist_ok=True)
    fmu_path = out / "cantilever.fmu"
    subprocess.run([find_loam(), "fmu", str(CASE), "-o", str(fmu_path)], check=True)

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmu_path)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="cantilever",
    )
    fmu.instantiate()
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()

    t, h = 0.0, 1.0  # one communication step = one static load step of the case

    def deflection(force):
        nonlocal t
        fmu.setFloat64([vr["tip_force"]], [force])
        fmu.doStep(t, h)
        t += h
        return fmu.getFloat64([vr["tip_uy"]])[0]

    # secant iteration on f(P) = tip_uy(P) - TARGET, starting from two small loads
    rows = []
    p0, p1 = 1000.0, 2000.0
    u0 = deflection(p0)
    rows.append((0, p0, u0))
    u1 = deflection(p1)
    rows.append((1, p1, u1))
    for k in range(2, 20):
        if abs(u1 - TARGET) < TOLERANCE:
            break
        p0, p1 = p1, p1 + (TARGET - u1) * (p1 - p0) / (u1 - u0)
        u0, u1 = u1, deflection(p1)
        rows.append((k, p1, u1))
    fmu.terminate()
    fmu.freeInstance()

    with open(out / "secant.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["iteration", "tip_force_N", "tip_uy_m"])
        w.writerows(rows)
    for k, p, u in rows:
        print(f"iteration {k}: tip_force {p:10.2f} N -> tip_uy {u:.7f} m")
    if abs(rows[-1][2] - TARGET) >= TOLERANCE:
        sys.exit(f"no convergence in {len(rows)} FMU steps")
    print(
        f"tip force for {TARGET} m: {rows[-1][1]:.1f} N; Timoshenko {P_TIMOSHENKO:.1f} N "
        f"({100 * (rows[-1][1] / P_TIMOSHENKO - 1):+.2f} %); wrote {out / 'secant.csv'}"
    )


if __name__ == "__main__":
    main()
