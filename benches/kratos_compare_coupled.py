#!/usr/bin/env python3
"""Benchmark 12 side by side: Kratos' partitioned MPM-FEM co-simulation of `mpm_fem_beam` and
Loam's monolithic coupling on the same discretisation (issue 13, item 8).

Kratos (shared/kratos/cases/mpm_fem_beam, run by its run_cosim.py with --contact-force-fix,
without which Kratos 10.4.4 passes no load from MPM to FEM): FEM 40 x 10 quads on [0, 4],
MPM 40 x 10 cells with 4 points each on [4, 8] and a 40 x 10 grid, one static step, coupled
by Gauss-Seidel iterations with MVQN, residual relative tolerance 1e-4 in both solvers.
Loam: the same meshes, grid and tolerance in one Newton system (the case is
cases/coupled_beam_split.json at h = 0.1 m with Kratos' grid and one load step, written to a
temporary file), converged by Kratos' own test: the residual criterion, relative 1e-4 to the
step's first residual and absolute 1e-9 (ProjectParametersFEM/MPM.json:
`residual_criterion`; Loam's `residual` criterion has the same definition,
fem/src/convergence.rs); `--criterion loam` keeps Loam's default instead (residual and
displacement increment, `and`), which iterates twice more. Both on one thread, each run `--repeat` times; the table gives the best wall
times (solve loop and whole process), Newton solves, coupling iterations and the
deflections.

Usage (from the repository root, after `cargo build --release`):

    python3 -m venv .kratos-venv
    .kratos-venv/bin/pip install KratosMultiphysics==10.4.4 KratosMPMApplication==10.4.4 \\
        KratosLinearSolversApplication==10.4.4 KratosCoSimulationApplication==10.4.4 \\
        KratosMappingApplication==10.4.4 KratosStructuralMechanicsApplication==10.4.4 \\
        KratosConstitutiveLawsApplication==10.4.4
    python3 benches/kratos_compare_coupled.py --repeat 3

Not part of the test suite.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
KRATOS_CASE = os.path.join(ROOT, "..", "shared", "kratos", "cases", "mpm_fem_beam", "run_cosim.py")


def kratos_run(python, workdir):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t = time.perf_counter()
    p = subprocess.run([python, KRATOS_CASE, "--contact-force-fix", "--workdir", workdir],
                       capture_output=True, text=True, env=env, check=True)
    process = time.perf_counter() - t
    summary = json.loads(p.stdout.split("RUN_SUMMARY", 1)[1].strip().splitlines()[0])
    solves = sum(sum(v) for v in summary["newton_iterations_per_solve"].values())
    return {
        "loop": summary["wall_solve_loop_s"],
        "process": process,
        "solves": solves,
        "coupling": sum(summary["coupling_iterations"]),
        "tip": summary["tip_uy_mpm"],
        "interface": summary["fem_interface_node"]["uy"],
    }


# Kratos' convergence test (see the doc string) or Loam's default criterion at Kratos' tolerance
CRITERIA = {
    "kratos": {"convergence_criterion": "residual", "residual_relative_tolerance": 1e-4,
               "residual_absolute_tolerance": 1e-9},
    "loam": {"residual_relative_tolerance": 1e-4, "residual_absolute_tolerance": 1e-9},
}


def loam_case(path, criterion="kratos"):
    with open(os.path.join(ROOT, "cases", "coupled_beam_split.json")) as f:
        c = json.load(f)
    c["domains"][0]["mesh"]["rectangle"]["cells"] = [40, 10]
    c["domains"][1]["grid"] = {"origin": [4.0, 0.0], "size": [4.0, 1.0], "cells": [40, 10], "element": "quad4"}
    c["domains"][1]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = [40, 10]
    c["gravity"] = {"acceleration": [0.0, -9.81]}
    c["analysis"] = {"type": "static", "time_step": 1.0, "end_time": 1.0}
    c["solver"] = dict(CRITERIA[criterion])
    c["output"] = {"vtk": False}
    with open(path, "w") as f:
        json.dump(c, f)


def loam_run(case, out):
    loam = os.path.join(ROOT, "target", "release", "loam")
    t = time.perf_counter()
    p = subprocess.run([loam, "run", case, "--out", out, "--quiet", "--threads", "1"],
                       capture_output=True, text=True, check=True)
    process = time.perf_counter() - t
    with open(os.path.join(out, "summary.json")) as f:
        loop = json.load(f)["wall_time"]["total"]  # the run loop, unrounded
    iterations = int(re.search(r"(\d+) Newton iterations", p.stdout).group(1))
    with open(os.path.join(out, "monitors.csv")) as f:
        last = list(csv.DictReader(f))[-1]
    return {"loop": loop, "process": process, "solves": iterations, "coupling": 1,
            "tip": float(last["tip_uy"]), "interface": float(last["interface_uy"])}


def best(runs):
    b = dict(runs[0])
    b["loop"] = min(r["loop"] for r in runs)
    b["process"] = min(r["process"] for r in runs)
    return b


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--criterion", choices=sorted(CRITERIA), default="kratos",
                    help="Loam's convergence test: Kratos' (default) or Loam's own default")
    ap.add_argument("--kratos-python", default=os.path.join(ROOT, ".kratos-venv", "bin", "python"))
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="loam_kratos_coupled_")
    case = os.path.join(work, "beam.json")
    loam_case(case, args.criterion)
    k = best([kratos_run(args.kratos_python, os.path.join(work, f"kratos_{i}")) for i in range(args.repeat)])
    l = best([loam_run(case, os.path.join(work, f"loam_{i}")) for i in range(args.repeat)])
    print("| code | coupling | Newton solves | solve loop (s) | process (s) | tip uy, points x0 = 7.979 m (m) | interface (4, 0.5) uy (m) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    print(f"| Kratos 10.4.4 (partitioned, Gauss-Seidel + MVQN) | {k['coupling']} iterations | {k['solves']} | "
          f"{k['loop']:.4f} | {k['process']:.3f} | {k['tip']:.4f} | {k['interface']:.4f} |")
    print(f"| Loam (monolithic) | one Newton system | {l['solves']} | {l['loop']:.4f} | {l['process']:.3f} | "
          f"{l['tip']:.4f} | {l['interface']:.4f} |")
    print(f"\nKratos / Loam: solve loop {k['loop'] / l['loop']:.0f}x, whole process {k['process'] / l['process']:.0f}x "
          f"(Timoshenko tip -0.67806 m at x = 8; Loam's criterion: {args.criterion})")


if __name__ == "__main__":
    main()
