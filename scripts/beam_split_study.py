#!/usr/bin/env python3
"""Benchmark 12's placement and refinement study (issue 31): the cantilever L = 8 m, h = 1 m
under its own weight, split into an FEM and an MPM half at x = 2, 4, 6, on grids
h = 0.2 / 0.1 / 0.05 / 0.025 m (FEM mesh of the same size), FEM | MPM (FEM clamped) and
MPM | FEM (material points clamped), the load in 4 and in 20 static steps; beside them the
MPM-only and the FEM-only beam at each h. Prints the tip deflection against Timoshenko's
-0.67806 m and against the FEM-only beam of the same h.

    scripts/beam_split_study.py [--h 0.2,0.1] [--steps 4] [--basis bspline2] [--loam target/release/loam]

--basis sets the MPM grid's shape functions (linear, gimp, bspline2; default bspline2).

The long test `coupling::beam_split_placement_and_refinement_study` asserts the same runs."""
import argparse, json, os, subprocess, sys, tempfile

E, RHO, G, L, H = 9.0e7, 1000.0, 9.81, 8.0, 1.0


def timoshenko(x):
    """Deflection (m, negative down) of the clamped beam at x under its weight."""
    q = RHO * G * H
    i = H ** 3 / 12.0
    kga = 5.0 / 6.0 * E / 2.0 * H
    return -(q / (24 * E * i) * (x ** 4 - 4 * L * x ** 3 + 6 * L ** 2 * x ** 2) + q / kga * (L * x - x * x / 2))


def rect(x0, x1, h):
    return {"rectangle": {"origin": [x0, 0.0], "size": [x1 - x0, 1.0], "cells": [round((x1 - x0) / h), round(1 / h)], "element": "quad4"}}


def case(kind, h, steps, split=None, basis="bspline2"):
    """kind: 'fem', 'mpm', 'fem_mpm' (FEM clamped) or 'mpm_fem' (MPM clamped)."""
    y0, y1, x_end = -1.2, 1.6, 8.6
    mpm_range = {"mpm": (0.0, 8.0), "fem_mpm": (split, 8.0), "mpm_fem": (0.0, split)}.get(kind)
    fem_range = {"fem": (0.0, 8.0), "fem_mpm": (0.0, split), "mpm_fem": (split, 8.0)}.get(kind)
    domains = []
    if fem_range:
        domains.append({"name": "beam_fem", "type": "fem", "material": "beam", "mesh": rect(*fem_range, h)})
    if mpm_range:
        gx0 = mpm_range[0]
        gx1 = split if kind == "mpm_fem" else x_end
        domains.append({
            "name": "beam_mpm", "type": "mpm", "material": "beam",
            "grid": {"origin": [gx0, y0], "size": [gx1 - gx0, y1 - y0], "cells": [round((gx1 - gx0) / h), round((y1 - y0) / h)], "element": "quad4", "basis": basis},
            "material_points": {"cells": {"mesh": rect(*mpm_range, h), "points_per_cell": 4}},
        })
    tip_on_mpm = kind in ("mpm", "fem_mpm")
    monitors = [
        {"name": "tip_uy", "type": "material_point_displacement" if tip_on_mpm else "displacement", "point": [8.0, 0.5], "component": "y"},
        {"name": "clamp_reaction_y", "type": "reaction", "region": "clamp", "component": "y"},
    ]
    c = {
        "description": f"benchmark 12 study: {kind}, h = {h}, split {split}, {steps} steps",
        "formulation": "plane_strain",
        "materials": {"beam": {"law": "neo_hookean", "density": RHO, "young_modulus": E, "poisson_ratio": 0.0}},
        "domains": domains,
        "regions": {"clamp": {"x": 0.0}},
        "boundary_conditions": [{"name": "clamp", "region": "clamp", "displacement": [0.0, 0.0]}],
        "gravity": {"acceleration": [0.0, -G], "amplitude": [[0.0, 0.0], [1.0, 1.0]]},
        "analysis": {"type": "static", "time_step": 1.0 / steps, "end_time": 1.0},
        "solver": {"residual_relative_tolerance": 1e-8, "residual_absolute_tolerance": 1e-6},
        "output": {"vtk": False},
        "monitors": monitors,
    }
    if split is not None:
        c["regions"]["cut"] = {"segment": {"from": [split, 0.0], "to": [split, 1.0]}}
        c["interfaces"] = [{"name": "cut", "soil": "beam_mpm", "structure": "beam_fem", "region": "cut"}]
    # where the tip monitor measures: the node (8, 0.5), or the point nearest it (2 x 2
    # Gauss positions of the last body cell: x0 = 8 - h/2 + h/(2 sqrt 3))
    x_tip = 8.0 - h / 2 + h / (2 * 3 ** 0.5) if tip_on_mpm else 8.0
    return c, x_tip


def run(loam, c, workdir, name):
    path = os.path.join(workdir, name + ".json")
    with open(path, "w") as f:
        json.dump(c, f)
    out = os.path.join(workdir, name)
    p = subprocess.run([loam, "run", path, "--out", out, "--quiet"], capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
    lines = open(os.path.join(out, "monitors.csv")).read().split()
    header = lines[0].split(",")
    last = lines[-1].split(",")
    summary = json.load(open(os.path.join(out, "summary.json")))
    quality = [g["worst_cell_quality"] for g in summary.get("grid_motion", [])]
    return float(last[header.index("tip_uy")]), quality


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--h", default="0.2,0.1,0.05,0.025")
    ap.add_argument("--steps", default="4,20")
    ap.add_argument("--splits", default="2,4,6")
    ap.add_argument("--basis", default="bspline2")
    ap.add_argument("--loam", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "loam"))
    a = ap.parse_args()
    hs = [float(v) for v in a.h.split(",")]
    steps = [int(v) for v in a.steps.split(",")]
    splits = [float(v) for v in a.splits.split(",")]
    work = tempfile.mkdtemp(prefix="loam_split_")
    print(f"{'case':28s} {'h':>6s} {'steps':>5s} {'tip (m)':>10s} {'vs Timoshenko':>14s} {'vs FEM':>8s} {'quality':>8s}")
    for h in hs:
        for n in steps:
            fem, xt = case("fem", h, n)
            tip_fem, _ = run(a.loam, fem, work, f"fem_{h}_{n}")
            rows = [("FEM only", fem, "fem", None), ("MPM only", None, "mpm", None)]
            rows += [(f"{k.upper().replace('_', ' | ')} x = {s:g}", None, k, s) for s in splits for k in ("fem_mpm", "mpm_fem")]
            for label, _, kind, split in rows:
                c, x_tip = case(kind, h, n, split, a.basis)
                tip, q = (tip_fem, []) if kind == "fem" else run(a.loam, c, work, f"{kind}_{split}_{h}_{n}")
                if tip is None:
                    print(f"{label:28s} {h:6g} {n:5d}  FAILED: {q}")
                    continue
                # against Timoshenko where the monitor measures; against the FEM-only beam
                # (its tip node) at that place too: the tip scaled by Timoshenko's w(8)/w(x)
                ref = timoshenko(x_tip)
                vs_fem = tip * timoshenko(8.0) / ref / tip_fem - 1.0
                print(f"{label:28s} {h:6g} {n:5d} {tip:10.5f} {100 * (tip - ref) / abs(ref):+13.2f}% {100 * vs_fem:+7.2f}% {min(q) if q else 1.0:8.3f}", flush=True)


if __name__ == "__main__":
    main()
