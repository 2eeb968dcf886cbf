#!/usr/bin/env python3
"""Kratos' own MPM test cases run side by side in Kratos and in Loam (`loam run DIR`).

For every case folder of tests/data/kratos (Kratos' MPMApplication test cases, and the 3D
cantilevers written by benches/kratos/gen_cantilever_3d.py) it runs Kratos' MpmAnalysis through
benches/kratos/run_case.py (OMP_NUM_THREADS = T) in a copy of the folder, and `loam run DIR
--threads T` on the unchanged folder (imported on the fly, no VTK), then prints per case: steps,
Kratos' solution loop per step, Loam's step loop per step (summary.json `wall_time.total`, which
excludes the import and case building, minus `wall_time.output`: the imported case writes VTK
files, these Kratos cases write none), their ratio, and both processes' wall-clock time
(interpreter start, import, set-up and Loam's VTK output included).

These cases are small (one static step for most), so the per-step figures are dominated by
the fixed costs of a step: pattern, first factorisation, point search.

Usage (from the repository root, after `cargo build --release` and the Kratos venv of
/work/shared/kratos/README.md in .kratos-venv or KRATOS_PYTHON):

    python3 benches/kratos_compare_cases.py [--threads 1] [--cases a,b]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DATA = os.path.join(ROOT, "tests", "data", "kratos")


def kratos_python():
    for p in (os.environ.get("KRATOS_PYTHON"), os.path.join(ROOT, ".kratos-venv", "bin", "python"),
              "/work/.kratos-venv/bin/python"):
        if p and os.path.exists(p):
            return p
    sys.exit("no Kratos venv: see /work/shared/kratos/README.md (or set KRATOS_PYTHON)")


def run_kratos(case, threads, work):
    d = os.path.join(work, "kratos_" + case)
    shutil.copytree(os.path.join(DATA, case), d)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    t0 = time.perf_counter()
    out = subprocess.run([kratos_python(), os.path.join(HERE, "kratos", "run_case.py")], cwd=d, env=env,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    line = next((l for l in out.stdout.splitlines() if l.startswith("RUN_SUMMARY")), None)
    if line is None:
        sys.exit("Kratos failed on %s:\n%s" % (case, out.stderr[-2000:]))
    s = json.loads(line[len("RUN_SUMMARY "):])
    return s["steps"], s["time_solution_loop_s"], wall


def run_loam(case, threads, work):
    out = os.path.join(work, "loam_" + case)
    t0 = time.perf_counter()
    r = subprocess.run([os.path.join(ROOT, "target", "release", "loam"), "run", os.path.join(DATA, case), "--out", out,
                        "--quiet", "--threads", str(threads)], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit("Loam failed on %s:\n%s" % (case, r.stderr))
    s = json.load(open(os.path.join(out, "summary.json")))
    return s["steps"], s["wall_time"]["total"] - s["wall_time"]["output"], wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--cases", default="")
    a = ap.parse_args()
    cases = a.cases.split(",") if a.cases else sorted(
        c for c in os.listdir(DATA) if os.path.isdir(os.path.join(DATA, c)))
    print("| Kratos case | steps | Kratos s/step | Loam s/step | Kratos / Loam | Kratos process s | Loam process s |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for c in cases:
            ks, kt, kw = run_kratos(c, a.threads, work)
            ls, lt, lw = run_loam(c, a.threads, work)
            if ks != ls:
                print("note: %s: Kratos %d steps, Loam %d" % (c, ks, ls), file=sys.stderr)
            print("| `%s` | %d | %.4f | %.4f | %.1f× | %.2f | %.2f |" % (
                c, ls, kt / ks, lt / ls, (kt / ks) / (lt / ls), kw, lw), flush=True)


if __name__ == "__main__":
    main()
