#!/usr/bin/env python3
"""Side-by-side run of the MPM cantilever (benchmark 1, dynamic) in Kratos and in Loam.

For each size (cells through the thickness n; 28 n^2 material points, 4 per cell) it
generates the Kratos case with benches/kratos/gen_cantilever.py (a copy of
shared/kratos/gen_cantilever.py), runs Kratos' MpmAnalysis through
benches/kratos/run_case.py with OMP_NUM_THREADS = 1 and 2 and KRATOS_END_TIME = steps * dt,
writes the same discretisation as a Loam case (the case JSON of benches/mpm_cantilever.rs)
and runs `loam run --threads T`, then prints seconds per step of both, the ratio
Kratos / Loam, Newton iterations per step and the tip deflection (material point nearest
(L - h/4, H/2)) of both at the end time.

Kratos' time per step is its solution loop over the steps (first step included, set-up
excluded); Loam's is the difference of the wall times of two `loam run` processes (1 step
and `steps` steps) over `steps - 1`, which excludes process start, case building and the
first step (consistent initial acceleration, first pattern). Loam writes no VTK. Both stop
Newton with Kratos' residual criterion (relative 1e-4) and Loam runs with Kratos' grid kinematics
(`solver.hold_grid_boundaries: false`), unless `--criterion loam` (Loam's defaults).

Usage (from the repository root, after `cargo build --release`):

    python3 -m venv .kratos-venv
    .kratos-venv/bin/pip install KratosMultiphysics==10.4.4 KratosMPMApplication==10.4.4 \
        KratosLinearSolversApplication==10.4.4
    python3 benches/kratos_compare.py --n 4,8,16 --steps 10 --threads 1,2

Not part of the test suite. Kratos at n = 64 (114 688 points) takes about 74 s per step.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DT = 0.01


# Kratos' convergence test in benches/kratos/gen_cantilever.py: residual criterion, relative
# 1e-4 to the step's first residual, absolute 1e-9 (Loam's residual criterion has the same
# definition: fem/src/convergence.rs). `--criterion loam` gives Loam's own default instead
# (residual and displacement, 1e-8 relative), one Newton iteration more per step.
CRITERIA = {
    # Kratos' criterion and Kratos' grid kinematics (projected velocity kept at clamped nodes)
    "kratos": {"convergence_criterion": "residual", "residual_relative_tolerance": 1e-4,
               "residual_absolute_tolerance": 1e-9, "hold_grid_boundaries": False},
    "loam": {"residual_relative_tolerance": 1e-8, "residual_absolute_tolerance": 1e-6},
}


def loam_case(n, end, criterion="kratos"):
    h = 1.0 / n
    return {
        "description": "kratos_compare: benchmark 1 with MPM, dynamic, n = %d" % n,
        "formulation": "plane_strain",
        "thickness": 1.0,
        "materials": {"beam": {"law": "neo_hookean", "density": 1000.0, "young_modulus": 9.0e7,
                               "poisson_ratio": 0.0}},
        "domains": [{
            "name": "beam", "type": "mpm", "material": "beam",
            "grid": {"origin": [0.0, -1.5], "size": [8.0, 3.0], "cells": [8 * n, 3 * n], "element": "quad4"},
            "material_points": {"cells": {"mesh": {"rectangle": {
                "origin": [0.0, 0.0], "size": [7.0, 1.0], "cells": [7 * n, n], "element": "quad4"}},
                "points_per_cell": 4}},
        }],
        "regions": {"clamp": {"x": 0.0}},
        "boundary_conditions": [{"region": "clamp", "displacement": [0.0, 0.0]}],
        "gravity": {"acceleration": [0.0, -9.81]},
        "analysis": {"type": "dynamic", "time_step": DT, "end_time": end,
                     "scheme": {"newmark": {"beta": 0.25, "gamma": 0.5}}},
        "solver": dict(CRITERIA[criterion]),
        "monitors": [{"name": "tip_uy", "type": "material_point_displacement", "point": [7.0 - 0.25 * h, 0.5],
                      "component": "y"}],
        "output": {"vtk": False},
    }


def kratos_summary(python, case_dir, threads, steps, dt):
    """Kratos' RUN_SUMMARY (benches/kratos/run_case.py) of `steps` steps of `dt` in `case_dir`."""
    # Kratos advances while t < end_time: end half a step early to take exactly `steps` steps
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), KRATOS_END_TIME=repr((steps - 0.5) * dt))
    out = subprocess.run([python, os.path.join(HERE, "kratos", "run_case.py")], cwd=case_dir, env=env,
                         capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("RUN_SUMMARY "):
            return json.loads(line[len("RUN_SUMMARY "):])
    sys.exit("Kratos failed:\n" + out.stdout[-2000:] + out.stderr[-2000:])


def run_kratos(python, case_dir, threads, steps):
    s = kratos_summary(python, case_dir, threads, steps, DT)
    tip = next((k["value"] for k in s["key_results"] if "MP_DISPLACEMENT_Y" in k["label"]), float("nan"))
    return {"per_step": s["time_per_step_s"], "steps": s["steps"],
            "iters": s["nonlinear_iterations_total"] / max(s["steps"], 1), "tip": tip,
            "points": s["material_points_initial"]}


def loam_run_case(loam, case, out_dir, threads):
    """Wall seconds, steps and Newton iterations of `loam run` on the case dict `case`."""
    os.makedirs(out_dir, exist_ok=True)
    case_path = os.path.join(out_dir, "loam.json")
    with open(case_path, "w") as f:
        json.dump(case, f, indent=1)
    t0 = time.perf_counter()
    out = subprocess.run([loam, "run", case_path, "--out", out_dir, "--threads", str(threads), "--quiet"],
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    m = re.search(r"(\d+) steps, (\d+) Newton iterations", out.stdout)
    if out.returncode != 0 or not m:
        sys.exit("Loam failed:\n" + out.stdout[-2000:] + out.stderr[-2000:])
    return wall, int(m.group(1)), int(m.group(2))


def loam_once(loam, n, steps, out_dir, threads, criterion):
    wall, nsteps, iters = loam_run_case(loam, loam_case(n, steps * DT, criterion), out_dir, threads)
    with open(os.path.join(out_dir, "monitors.csv")) as f:
        rows = list(csv.DictReader(f))
    return wall, nsteps, iters, float(rows[-1]["tip_uy"])


def run_loam(loam, n, case_dir, threads, steps, criterion, repeats):
    """Seconds per step from two runs (1 step and `steps` steps) of `loam run`: the
    difference excludes process start, case building and the first step. The fastest of
    `repeats` pairs (the spread is printed)."""
    per_step = []
    for _ in range(repeats):
        w1, _, i1, _ = loam_once(loam, n, 1, os.path.join(case_dir, "loam_1_%d" % threads), threads, criterion)
        wn, nsteps, iters, tip = loam_once(loam, n, steps, os.path.join(case_dir, "loam_%d" % threads), threads,
                                           criterion)
        per_step.append((wn - w1) / (nsteps - 1))
    if repeats > 1:
        print("  loam s/step over %d repeats: %s" % (repeats, ", ".join("%.5f" % t for t in per_step)),
              file=sys.stderr)
    return {"per_step": min(per_step), "steps": nsteps, "iters": (iters - i1) / (nsteps - 1),
            "tip": tip}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", default="4,8,16", help="cells through the thickness, comma separated (4 -> 448 points)")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--venv", default=os.path.join(ROOT, ".kratos-venv"))
    ap.add_argument("--loam", default=os.path.join(ROOT, "target", "release", "loam"))
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "kratos_compare"))
    ap.add_argument("--no-kratos", action="store_true", help="run Loam only")
    ap.add_argument("--criterion", choices=sorted(CRITERIA), default="kratos",
                    help="Loam's convergence test: Kratos' (default, the same as the Kratos case) or Loam's own")
    ap.add_argument("--repeats", type=int, default=1, help="Loam runs per size (the fastest is reported)")
    ap.add_argument("--kratos-max-n", type=int, default=32, help="skip Kratos above this n (n = 64: 74 s/step)")
    a = ap.parse_args()
    python = os.path.join(a.venv, "bin", "python")
    rows = []
    for n in [int(v) for v in a.n.split(",")]:
        case_dir = os.path.join(a.work, "n%d" % n)
        os.makedirs(case_dir, exist_ok=True)
        subprocess.run([sys.executable, os.path.join(HERE, "kratos", "gen_cantilever.py"), case_dir, "--n", str(n),
                        "--ppc", "4", "--mode", "dynamic", "--dt", repr(DT), "--end", repr(a.steps * DT)],
                       check=True, capture_output=True)
        for th in [int(v) for v in a.threads.split(",")]:
            lo = run_loam(a.loam, n, case_dir, th, a.steps, a.criterion, a.repeats)
            kr = None
            if not a.no_kratos and n <= a.kratos_max_n:
                kr = run_kratos(python, case_dir, th, a.steps)
            rows.append((n, 28 * n * n, th, kr, lo))
            print("n=%d threads=%d: loam %.5f s/step (%.1f it/step, tip %.6f)%s" % (
                n, th, lo["per_step"], lo["iters"], lo["tip"],
                "" if kr is None else "; kratos %.5f s/step (%.1f it/step, tip %.6f)" % (
                    kr["per_step"], kr["iters"], kr["tip"])), file=sys.stderr, flush=True)
    print()
    print("Seconds per step over %d steps (dt = %g s, Newmark); tip deflection at t = %g s; Loam's convergence "
          "test: %s." % (a.steps, DT, a.steps * DT, a.criterion))
    print()
    print("| points | threads | Kratos s/step | Loam s/step | Kratos / Loam | Kratos it/step | Loam it/step "
          "| tip uy Kratos (m) | tip uy Loam (m) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, pts, th, kr, lo in rows:
        if kr is None:
            print("| %d | %d | — | %.5f | — | — | %.1f | — | %.6f |" % (pts, th, lo["per_step"], lo["iters"], lo["tip"]))
        else:
            print("| %d | %d | %.5f | %.5f | %.1f× | %.1f | %.1f | %.6f | %.6f |" % (
                pts, th, kr["per_step"], lo["per_step"], kr["per_step"] / lo["per_step"], kr["iters"],
                lo["iters"], kr["tip"], lo["tip"]))


if __name__ == "__main__":
    main()
