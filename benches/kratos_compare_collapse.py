#!/usr/bin/env python3
"""Side-by-side run of the Bui et al. (2008) column collapse (benchmark 8) in Kratos and in
Loam at Kratos' own validation discretisation: structured triangles h = 2 mm on
[0, 0.5] x [0, 0.12] m, 30 000 material points, implicit Newmark steps of dt = 5e-5 s from
the start of the collapse, one thread (and two with --threads 1,2).

Kratos: the Examples case `mpm/validation/granular_flow_2D` (B. Chandra; in this workplace at
shared/kratos/cases/granular_flow_2D, pass another copy with --kratos-case) with its grid
written by benches/kratos/gen_granular_grid.py, run by benches/kratos/run_case.py for
`short` and `steps` steps; seconds per step = the difference of the two solution-loop times
over the difference of steps (excludes set-up and the first steps' extra cost).
Loam: `cases/collapse_bui2008_tri_h2.json` with fixed steps of 5e-5 s (no adaptivity, no
output files), `loam run` for 1 and `steps` steps; seconds per step = the difference of the
wall times over `steps - 1`.

Usage (from the repository root, after `cargo build --release`; the Kratos venv as in
benches/kratos_compare.py):

    python3 benches/kratos_compare_collapse.py --steps 21 --threads 1

Not part of the test suite (Kratos takes about 1 s per step here).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

from kratos_compare import kratos_summary, loam_run_case

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DT = 5e-5


def kratos_loop(python, case_dir, threads, steps):
    """Kratos' solution-loop seconds, steps and Newton iterations for `steps` steps."""
    s = kratos_summary(python, case_dir, threads, steps, DT)
    return s["time_solution_loop_s"], s["steps"], s["nonlinear_iterations_total"]


def loam_run(loam, out_dir, steps, threads):
    """Wall seconds, steps and Newton iterations of `loam run` for `steps` fixed steps."""
    with open(os.path.join(ROOT, "cases", "collapse_bui2008_tri_h2.json")) as f:
        case = json.load(f)
    analysis = case["analysis"]
    for key in ("adaptive", "stop_at_rest"):
        analysis.pop(key, None)
    analysis["time_step"] = DT
    analysis["end_time"] = steps * DT
    case["output"] = {"interval": 0, "vtk": False}
    return loam_run_case(loam, case, out_dir, threads)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=21)
    ap.add_argument("--short", type=int, default=6, help="Kratos' shorter run (steps)")
    ap.add_argument("--threads", default="1")
    ap.add_argument("--venv", default=os.path.join(ROOT, ".kratos-venv"))
    ap.add_argument("--loam", default=os.path.join(ROOT, "target", "release", "loam"))
    ap.add_argument("--kratos-case", default=os.path.join(ROOT, "..", "shared", "kratos", "cases", "granular_flow_2D"))
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "kratos_compare_collapse"))
    a = ap.parse_args()
    python = os.path.join(a.venv, "bin", "python")
    case_dir = os.path.join(a.work, "kratos")
    shutil.rmtree(case_dir, ignore_errors=True)
    shutil.copytree(a.kratos_case, case_dir)
    subprocess.run([sys.executable, os.path.join(HERE, "kratos", "gen_granular_grid.py"),
                    os.path.join(case_dir, "Grid.mdpa")], check=True, capture_output=True)
    print("| threads | Kratos s/step | Loam s/step | Kratos / Loam | Kratos it/step | Loam it/step |")
    print("|---:|---:|---:|---:|---:|---:|")
    for th in [int(v) for v in a.threads.split(",")]:
        k_short, ks, ki_short = kratos_loop(python, case_dir, th, a.short)
        k_long, kl, ki_long = kratos_loop(python, case_dir, th, a.steps)
        kratos = (k_long - k_short) / (kl - ks)
        w1, _, i1 = loam_run(a.loam, os.path.join(a.work, "loam_1_%d" % th), 1, th)
        wn, ln, i_n = loam_run(a.loam, os.path.join(a.work, "loam_%d" % th), a.steps, th)
        loam = (wn - w1) / (ln - 1)
        print("| %d | %.3f | %.4f | %.1f× | %.1f | %.1f |" % (
            th, kratos, loam, kratos / loam, (ki_long - ki_short) / (kl - ks), (i_n - i1) / (ln - 1)), flush=True)


if __name__ == "__main__":
    main()
