#!/usr/bin/env python3
"""Granular column scaling (issue 24, items 5 and 6): columns of aspect ratio a = H0/L0 =
0.5, 1, 2, 4, 8 of the Bui et al. (2008) aluminium bars (Mohr-Coulomb phi = 19.8 deg, c = 0,
psi = 0) with L0 = 0.1 m, the numerical settings of cases/collapse_bui2008_quad_mc.json, run to
rest; the normalised runout (L_inf - L0)/L0 and final height at the wall H_inf/L0 against
two published fits for plane (quasi-2D channel) columns; and the steps and wall time of the
three phases of each run (collapse, spreading, settling). Python 3 standard library only.

    cargo build --release
    python3 scripts/column_scaling.py cases            # (re)writes cases/column_scaling_a*.json
    python3 scripts/column_scaling.py run [A ...]      # runs them into out/column_scaling/a<A>
    python3 scripts/column_scaling.py table            # column_scaling.csv + the SVG plot
    python3 scripts/column_scaling.py phases [A ...]   # per-phase steps / wall time

`run` passes --trace-newton to `loam run` and stamps every Newton line the run prints on
stderr with the wall clock (trace.log in the result directory): that gives the wall time of
every step, which monitors.csv (one row per step, simulation time only) does not. `table` and `phases`
only read finished result directories (--root DIR, default out/column_scaling), so they
can be rerun without rerunning the cases.

Fits (normalised runout R = (L_inf - L0)/L0, final height at the wall H_inf/L0):
  Lube, Huppert, Sparks & Freundt 2005, Phys. Rev. E 72, 041301 (quasi-2D channel):
      R = 1.2 a (a <~ 2.3), 1.9 a^(2/3) (a >~ 2.3); H_inf/L0 = a (a <~ 1.15), a^(2/5) beyond.
  Lajeunesse, Monnier & Homsy 2005, Phys. Fluids 17, 103302 (rectangular channel):
      R = 1.8 a (a < 3), 2.3 a^(2/3) (a > 3)  -- coefficients as compiled by Lagree, Staron
      & Popinet 2011 (J. Fluid Mech. 686, Eq. 3.1); see docs/granular_scaling.md for how
      far they could be checked.
  For comparison (same material class as Bui et al. 2008): true-2D aluminium-rod columns,
  arXiv:1512.05180: R = 3.25 a^0.96 (0.65 < a < 1.5), 3.80 a^0.73 (a > 1.5);
  H0/H_inf = 1.42 a^(2/3) (a > 0.65).
"""
import csv
import json
import math
import os
import pathlib
import subprocess
import sys
import time
from xml.sax.saxutils import escape

ROOT = pathlib.Path(__file__).resolve().parent.parent
LOAM = ROOT / "target" / "release" / "loam"
ASPECTS = [0.5, 1.0, 2.0, 4.0, 8.0]
L0 = 0.1  # column width (m)
H_CELL = 0.005  # grid cell (m)
TAU_PIC = 0.02  # PIC relaxation time at h = 5 mm (s), proportional to h
# grid width per aspect ratio (m): the larger of the fits' runouts, times the overshoot of
# the bundled a = 0.5 case over Lube's fit (about 1.7), plus margin (widened for a = 4, 8 after
# the a = 2 run overshot 2.6x)
GRID_WIDTH = {0.5: 0.35, 1.0: 0.6, 2.0: 0.9, 4.0: 1.5, 8.0: 2.5}


def tag(a):
    return f"{a:g}"


def case_path(a, h=H_CELL):
    suffix = "" if h == H_CELL else f"_h{h * 1000:g}"
    return ROOT / "cases" / f"column_scaling_a{tag(a)}{suffix}.json"


# --- published fits --------------------------------------------------------------------


def lube_runout(a):
    """Lube et al. 2005 (PRE 72, 041301), quasi-2D: (L_inf - L0)/L0."""
    return 1.2 * a if a <= 2.3 else 1.9 * a ** (2.0 / 3.0)


def lube_height(a):
    """Lube et al. 2005, quasi-2D: H_inf/L0."""
    return a if a <= 1.15 else a ** 0.4


def lajeunesse_runout(a):
    """Lajeunesse et al. 2005 (Phys. Fluids 17, 103302), channel: (L_inf - L0)/L0."""
    return 1.8 * a if a < 3.0 else 2.3 * a ** (2.0 / 3.0)


def rods_runout(a):
    """True-2D aluminium rods (arXiv:1512.05180, 'Failure mechanism of true 2D granular
    flows'; the Bui et al. 2008 material class): (L_inf - L0)/L0 = 3.25 a^0.96 for
    0.65 < a < 1.5, 3.80 a^0.73 for a > 1.5; not given below a = 0.65."""
    if a <= 0.65:
        return None
    return 3.25 * a**0.96 if a < 1.5 else 3.80 * a**0.73


def rods_height(a):
    """The same: H_inf = H0 for a < 0.65, H0/H_inf = 1.42 a^(2/3) beyond; as H_inf/L0."""
    return a if a < 0.65 else a / (1.42 * a ** (2.0 / 3.0))


# --- cases -----------------------------------------------------------------------------


def make_case(a, h=H_CELL):
    H0 = a * L0
    width = GRID_WIDTH[a]
    height = H0 + 4 * h  # a few cells above the column's top
    nx, ny = round(width / h), math.ceil(height / h - 1e-9)
    tau = TAU_PIC * h / H_CELL
    k0 = round(1.0 - math.sin(math.radians(19.8)), 3)
    lo, la = lube_runout(a), lajeunesse_runout(a)
    h_note = "" if h == H_CELL else " (the coarse variant of the h = 5 mm case, the PIC relaxation time scaled with h)"
    description = (
        f"Granular column scaling (issue 24, item 5): a column of aspect ratio a = H0/L0 = {a:g} "
        f"(L0 = {L0:g} m, H0 = {H0:g} m) of the Bui et al. (2008) aluminium bars against a smooth wall "
        f"at x = 0, released under gravity onto the frictional base of the bundled Bui case (slip, "
        f"mu_b = 0.36); Mohr-Coulomb phi = 19.8 deg, c = 0, psi = 0, rho = 2650, E = 840 kPa, nu = 0.3; "
        f"geostatic K0 = 1 - sin(phi) start; quadrilateral grid h = {h * 1000:g} mm{h_note}, 4 points per "
        f"cell, PIC relaxation time {tau:g} s, adaptive implicit steps (their length set by the local time-integration "
        f"error, 2e-6 m, and shortened past 8 Newton iterations), until at rest: the settings of "
        f"cases/collapse_bui2008_quad_mc.json. Fits of the normalised runout (L_inf - L0)/L0 for plane "
        f"(quasi-2D channel) columns: Lube et al. 2005 (Phys. Rev. E 72, 041301) 1.2 a for a <~ 2.3, "
        f"1.9 a^(2/3) beyond: {lo:.2f} here; Lajeunesse et al. 2005 (Phys. Fluids 17, 103302) 1.8 a for "
        f"a < 3, 2.3 a^(2/3) beyond: {la:.2f} here; final height at the wall H_inf/L0 (Lube) a for "
        f"a <~ 1.15, a^(2/5) beyond: {lube_height(a):.2f} here. Rerun: target/release/loam run "
        f"{case_path(a, h).relative_to(ROOT)} --out out/column_scaling/a{tag(a)}{'' if h == H_CELL else f'_h{h * 1000:g}'} "
        f"--quiet, or python3 scripts/column_scaling.py run {tag(a)}{'' if h == H_CELL else ' --h10'}; docs/granular_scaling.md"
    )
    return {
        "description": description,
        "formulation": "plane_strain",
        "materials": {
            "aluminium_bars": {
                "law": "mohr_coulomb",
                "density": 2650.0,
                "young_modulus": 840000.0,
                "poisson_ratio": 0.3,
                "friction_angle": 19.8,
                "cohesion": 0.0,
                "dilatancy_angle": 0.0,
            }
        },
        "domains": [
            {
                "name": "soil",
                "type": "mpm",
                "material": "aluminium_bars",
                "grid": {"origin": [0.0, 0.0], "size": [width, ny * h], "cells": [nx, ny], "element": "quad4"},
                "material_points": {
                    "cells": {
                        "mesh": {
                            "rectangle": {
                                "origin": [0.0, 0.0],
                                "size": [L0, H0],
                                "cells": [round(L0 / h), round(H0 / h)],
                                "element": "quad4",
                            }
                        },
                        "points_per_cell": 4,
                    }
                },
                "initial_stress": {"geostatic": {"surface": H0, "k0": k0}},
                "pic_relaxation_time": tau,
            }
        ],
        "regions": {"wall": {"x": 0.0}, "base": {"y": 0.0}},
        "boundary_conditions": [
            {"name": "wall", "region": "wall", "displacement": [0.0, None]},
            {"name": "base", "region": "base", "slip": {"friction": 0.36}},
        ],
        "gravity": {"acceleration": [0.0, -9.81]},
        "analysis": {
            "type": "dynamic",
            "time_step": 0.002,
            "end_time": 3.0,
            "adaptive": {
                "min_time_step": 1e-05,
                "max_time_step": 0.005,
                "target_iterations": 8,
                "error_tolerance": 2e-06,
            },
            "stop_at_rest": {"kinetic_energy_ratio": 0.001, "duration": 0.05, "min_time": 0.5},
        },
        "solver": {
            "residual_relative_tolerance": 0.0001,
            "residual_absolute_tolerance": 1e-06,
            "displacement_relative_tolerance": 0.0001,
            "max_iterations": 25,
            "line_search": True,
        },
        "output": {"time_interval": 0.05},
        "monitors": [
            {"name": "runout", "type": "runout", "wall": 0.0, "base": 0.0, "threshold": 0.002},
            {"name": "height_at_wall", "type": "surface_height", "x": 0.0},
            {"name": "kinetic_energy", "type": "kinetic_energy"},
            {"name": "runout_5mm", "type": "runout", "wall": 0.0, "base": 0.0, "threshold": 0.005},
        ],
    }


def write_cases(args):
    # the coarse grid only for a = 2 (what h changes)
    for h, aspects in ((H_CELL, ASPECTS), (0.01, [2.0])):
        for a in aspects:
            path = case_path(a, h)
            path.write_text(json.dumps(make_case(a, h), indent=2) + "\n")
            print(path.relative_to(ROOT))


# --- running ---------------------------------------------------------------------------


def result_dir(root, a, h=H_CELL):
    return pathlib.Path(root) / (f"a{tag(a)}" + ("" if h == H_CELL else f"_h{h * 1000:g}"))


def run_case(case, out):
    """Runs `case` into `out` with the Newton trace on, stamping each stderr line with the
    wall time since the start (trace.log: `wall_s<TAB>line`)."""
    out.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    with open(out / "trace.log", "w") as log:
        proc = subprocess.Popen(
            [str(LOAM), "run", str(case), "--out", str(out), "--quiet", "--trace-newton"],
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            bufsize=0,
        )
        # raw reads: a buffered line iterator would stamp the lines up to 8 KB late
        pending = b""
        while True:
            chunk = os.read(proc.stderr.fileno(), 65536)
            if not chunk:
                break
            stamp = f"{time.monotonic() - start:.4f}\t".encode()
            *lines, pending = (pending + chunk).split(b"\n")
            for line in lines:
                log.write((stamp + line + b"\n").decode(errors="replace"))
        if pending:
            log.write(f"{time.monotonic() - start:.4f}\t{pending.decode(errors='replace')}\n")
        rc = proc.wait()
    wall = time.monotonic() - start
    (out / "wall.json").write_text(json.dumps({"wall_time": wall, "exit_code": rc}) + "\n")
    print(f"{case.name}: exit {rc}, {wall:.1f} s -> {out}")
    return rc


def run(args):
    root, args = pop_root(args)
    h = 0.01 if "--h10" in args else H_CELL
    aspects = [float(x) for x in args if not x.startswith("--")] or ASPECTS
    for a in aspects:
        run_case(case_path(a, h), result_dir(root, a, h))


def pop_root(args):
    root = ROOT / "out" / "column_scaling"
    if "--root" in args:
        i = args.index("--root")
        root = pathlib.Path(args[i + 1])
        args = args[:i] + args[i + 2 :]
    return root, args


# --- reading results -------------------------------------------------------------------


def read_monitors(d):
    with open(d / "monitors.csv") as f:
        rows = list(csv.reader(f))
    names = rows[0]
    return {n: [float(r[i]) for r in rows[1:]] for i, n in enumerate(names)}


def read_trace(d):
    """[(wall_s, t, dt, it)] from trace.log ('newton t=... dt=... it=...')."""
    out = []
    p = d / "trace.log"
    if not p.exists():
        return out
    for line in open(p):
        wall, _, text = line.partition("\t")
        if not text.startswith("newton "):
            continue
        fields = dict(f.split("=", 1) for f in text.split() if "=" in f)
        out.append((float(wall), float(fields["t"]), float(fields["dt"]), int(fields["it"])))
    return out


def summary(d):
    s = json.loads((d / "summary.json").read_text())
    w = d / "wall.json"
    wall = json.loads(w.read_text())["wall_time"] if w.exists() else s["wall_time"]["total"]
    return s, wall


def runout_drops(L, size=0.0025):
    """How often the 2 mm runout falls back between two steps by more than a point's side
    (`size`; the thin sheet of single points at the front sinking below the threshold),
    and the largest fall (m)."""
    falls = [a - b for a, b in zip(L, L[1:]) if a - b > size]
    return len(falls), max(falls, default=0.0)


def final_points(d):
    """(x, y, volume) of the material points in the last .vtu of `d` (inline base64 binary,
    UInt64 length header, uncompressed, as Loam writes them)."""
    import base64
    import struct
    import xml.etree.ElementTree as ET

    vtus = sorted(d.glob("soil_*.vtu"))
    if not vtus:
        return []
    arrays = {}
    for da in ET.parse(vtus[-1]).getroot().iter("DataArray"):
        if da.get("Name") in ("Points", "volume"):
            raw = base64.b64decode("".join(da.text.split()))
            n = struct.unpack("<Q", raw[:8])[0] // 8
            arrays[da.get("Name")] = struct.unpack(f"<{n}d", raw[8 : 8 + 8 * n])
    pts, vol = arrays["Points"], arrays["volume"]
    return [(pts[3 * i], pts[3 * i + 1], vol[i]) for i in range(len(vol))]


def detached(d, runout):
    """Farthest material (x + half a point's side) in the final output, and the share of the
    points lying beyond the monitored runout (the detached sheet or clumps)."""
    pts = final_points(d)
    if not pts:
        return None, None
    front = max(x + 0.5 * math.sqrt(v) for x, _, v in pts)
    beyond = sum(1 for x, _, _ in pts if x > runout) / len(pts)
    return front, beyond


def deposit_top(d):
    """Highest point of the final deposit (y + half a point's side, m). The monitor
    `height_at_wall` takes only the points whose centres lie within 0.6 of their side of
    x = 0; in the tall columns the yielded points above the dead wedge end with centres
    1.6-2 mm (and higher up 4-6 mm) from the wall, just outside it, so it reports the
    wedge's top instead."""
    pts = final_points(d)
    return max((y + 0.5 * math.sqrt(v) for _, y, v in pts), default=None)


def table(args):
    root, args = pop_root(args)
    rows = []
    for h in (H_CELL, 0.01):
        for a in ASPECTS:
            d = result_dir(root, a, h)
            if not (d / "summary.json").exists():
                continue
            s, wall = summary(d)
            if not s.get("end"):
                print(f"{d}: still running, left out")
                continue
            drops, big = runout_drops(read_monitors(d)["runout"])
            front, beyond = detached(d, s["monitors"]["runout"])
            top = deposit_top(d)
            m = s["monitors"]
            L, H = m["runout"], m["height_at_wall"]
            L5 = m.get("runout_5mm")
            R = (L - L0) / L0
            lo, la = lube_runout(a), lajeunesse_runout(a)
            rows.append(
                {
                    "a": a,
                    "h_mm": h * 1000,
                    "H0_m": a * L0,
                    "runout_m": L,
                    "runout_norm": R,
                    "runout_5mm_m": L5,
                    "runout_5mm_norm": None if L5 is None else (L5 - L0) / L0,
                    "H_inf_over_L0": top / L0 if top is not None else None,
                    "H_at_wall_monitor_over_L0": H / L0,
                    "steps": s["steps"],
                    "newton_iterations": s["newton"]["iterations"],
                    "wall_time_s": wall,
                    "end_time_s": s["end"]["time"] if s.get("end") else None,
                    "end_reason": s["end"]["reason"] if s.get("end") else s["status"],
                    "lube_runout_norm": lo,
                    "lajeunesse_runout_norm": la,
                    "lube_H_inf_over_L0": lube_height(a),
                    "rods_runout_norm": rods_runout(a),
                    "rods_H_inf_over_L0": rods_height(a),
                    "inside_band": min(lo, la) <= R <= max(lo, la),
                    "farthest_point_m": front,
                    "points_beyond_runout": beyond,
                    "runout_drops": drops,
                    "largest_drop_m": big,
                }
            )
    out = ROOT / "column_scaling.csv"
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.5g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(out.relative_to(ROOT))
    for r in rows:
        print(
            f"a={r['a']:g} h={r['h_mm']:g}mm L={r['runout_m']:.4f} R={r['runout_norm']:.3f} "
            f"(Lube {r['lube_runout_norm']:.2f}, Lajeunesse {r['lajeunesse_runout_norm']:.2f}, inside {r['inside_band']}) "
            f"R5={r['runout_5mm_norm'] if r['runout_5mm_norm'] is None else round(r['runout_5mm_norm'], 3)} "
            f"H/L0={r['H_inf_over_L0']:.3f} (monitor {r['H_at_wall_monitor_over_L0']:.3f}; Lube {r['lube_H_inf_over_L0']:.2f}, rods {r['rods_H_inf_over_L0']:.2f}) steps={r['steps']} wall={r['wall_time_s']:.0f}s "
            f"drops={r['runout_drops']} (largest {r['largest_drop_m'] * 1000:.1f} mm) "
            f"farthest point {r['farthest_point_m']:.3f} m, {r['points_beyond_runout']:.2%} of the points beyond the runout"
        )
    svg(rows, ROOT / "docs" / "img" / "granular" / "column_scaling.svg")


# --- plot ------------------------------------------------------------------------------


def svg(rows, path):
    """Normalised runout against a, log-log, with both fits (hand-written SVG)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    W, Hh, ml, mr, mt, mb = 560, 420, 70, 20, 20, 60
    ax0, ax1, ay0, ay1 = math.log10(0.3), math.log10(12.0), math.log10(0.3), math.log10(30.0)

    def X(a):
        return ml + (math.log10(a) - ax0) / (ax1 - ax0) * (W - ml - mr)

    def Y(r):
        return Hh - mb - (math.log10(r) - ay0) / (ay1 - ay0) * (Hh - mt - mb)

    e = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{Hh}" font-family="sans-serif" font-size="12">',
        f'<rect width="{W}" height="{Hh}" fill="white"/>',
    ]
    for v in [0.3, 0.5, 1, 2, 3, 5, 10, 20, 30]:
        if v <= 12:
            e.append(f'<line x1="{X(v):.1f}" y1="{mt}" x2="{X(v):.1f}" y2="{Hh - mb}" stroke="#ddd"/>')
            e.append(f'<text x="{X(v):.1f}" y="{Hh - mb + 16}" text-anchor="middle">{v:g}</text>')
        e.append(f'<line x1="{ml}" y1="{Y(v):.1f}" x2="{W - mr}" y2="{Y(v):.1f}" stroke="#ddd"/>')
        e.append(f'<text x="{ml - 6}" y="{Y(v) + 4:.1f}" text-anchor="end">{v:g}</text>')
    e.append(f'<rect x="{ml}" y="{mt}" width="{W - ml - mr}" height="{Hh - mt - mb}" fill="none" stroke="black"/>')
    e.append(f'<text x="{(W + ml - mr) / 2}" y="{Hh - 20}" text-anchor="middle">aspect ratio a = H0/L0</text>')
    e.append(
        f'<text x="18" y="{(Hh - mb + mt) / 2}" text-anchor="middle" transform="rotate(-90 18 {(Hh - mb + mt) / 2})">'
        "(L∞ − L0)/L0</text>"
    )
    for f, colour, label in [
        (lube_runout, "#1f77b4", "Lube et al. 2005 (1.2a; 1.9a^2/3)"),
        (lajeunesse_runout, "#2ca02c", "Lajeunesse et al. 2005 (1.8a; 2.3a^2/3)"),
        (rods_runout, "#7f7f7f", "true-2D aluminium rods"),
    ]:
        pts = []
        n = 200
        for i in range(n + 1):
            a = 10 ** (ax0 + (ax1 - ax0) * i / n)
            if f(a) is not None:
                pts.append(f"{X(a):.1f},{Y(f(a)):.1f}")
        dash = ' stroke-dasharray="5,3"' if f is rods_runout else ""
        e.append(f'<polyline points="{" ".join(pts)}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>')
    markers = {5.0: ("#d62728", "Loam, h = 5 mm"), 10.0: ("#ff7f0e", "Loam, h = 10 mm")}
    for hmm, (colour, _) in markers.items():
        for r in rows:
            if r["h_mm"] == hmm and r["runout_norm"] > 0:
                if hmm == 5.0:
                    e.append(f'<circle cx="{X(r["a"]):.1f}" cy="{Y(r["runout_norm"]):.1f}" r="4.5" fill="{colour}"/>')
                else:
                    e.append(
                        f'<rect x="{X(r["a"]) - 4:.1f}" y="{Y(r["runout_norm"]) - 4:.1f}" width="8" height="8" '
                        f'fill="none" stroke="{colour}" stroke-width="1.5"/>'
                    )
                r5 = r.get("runout_5mm_norm")
                if hmm == 5.0 and r5 and r5 > 0:
                    e.append(
                        f'<circle cx="{X(r["a"]):.1f}" cy="{Y(r5):.1f}" r="4" fill="none" stroke="{colour}" stroke-width="1.2"/>'
                    )
    legend = [
        ("line", "#1f77b4", "Lube et al. 2005: 1.2a (a ≲ 2.3), 1.9a^(2/3)"),
        ("line", "#2ca02c", "Lajeunesse et al. 2005: 1.8a (a < 3), 2.3a^(2/3)"),
        ("dash", "#7f7f7f", "Al rods, true 2D (arXiv:1512.05180): 3.25a^0.96; 3.80a^0.73"),
        ("dot", "#d62728", "Loam h = 5 mm, 2 mm threshold"),
        ("ring", "#d62728", "Loam h = 5 mm, 5 mm threshold"),
    ]
    if any(r["h_mm"] == 10.0 for r in rows):
        legend.append(("square", "#ff7f0e", "Loam h = 10 mm, 2 mm threshold"))
    for i, (kind, colour, text) in enumerate(legend):
        y = mt + 16 + 17 * i
        x = ml + 12
        if kind in ("line", "dash"):
            dash = ' stroke-dasharray="5,3"' if kind == "dash" else ""
            e.append(f'<line x1="{x}" y1="{y - 4}" x2="{x + 20}" y2="{y - 4}" stroke="{colour}" stroke-width="1.5"{dash}/>')
        elif kind == "dot":
            e.append(f'<circle cx="{x + 10}" cy="{y - 4}" r="4.5" fill="{colour}"/>')
        elif kind == "ring":
            e.append(f'<circle cx="{x + 10}" cy="{y - 4}" r="4" fill="none" stroke="{colour}" stroke-width="1.2"/>')
        else:
            e.append(f'<rect x="{x + 6}" y="{y - 8}" width="8" height="8" fill="none" stroke="{colour}" stroke-width="1.5"/>')
        e.append(f'<text x="{x + 28}" y="{y}">{escape(text)}</text>')
    e.append("</svg>")
    path.write_text("\n".join(e) + "\n")
    print(path.relative_to(ROOT))


# --- phases (item 6) -------------------------------------------------------------------


def phases_of(d, front="runout"):
    """Collapse (to the kinetic energy peak), spreading (until the runout `front` stays
    within 1 mm of its final value), settling (the rest): steps, Newton iterations,
    simulated and wall time of each."""
    m = read_monitors(d)
    t, ke, L = m["time"], m["kinetic_energy"], m[front]
    n = len(t)
    i_peak = max(range(n), key=lambda i: ke[i])
    final = L[-1]
    i_spread = n - 1
    while i_spread > 0 and abs(L[i_spread - 1] - final) <= 1e-3:
        i_spread -= 1
    i_spread = max(i_spread, i_peak)
    trace = read_trace(d)
    s, wall_total = summary(d)

    def wall_at(time_s):
        # the last Newton line of a step ending at or before time_s (t is the step's end)
        w = 0.0
        for wall, tt, _, _ in trace:
            if tt <= time_s * (1 + 1e-12):
                w = wall
            else:
                break
        return w

    def iterations(t0, t1):
        # Newton iterations of the attempts whose end time lies in (t0, t1]
        total, last = 0, None
        for _, tt, dt, it in trace:
            if t0 < tt <= t1 * (1 + 1e-12):
                if it == 0 and last is not None:
                    total += last
                last = it
            elif tt > t1 * (1 + 1e-12):
                break
        return total + (last or 0)

    bounds = [(0, i_peak), (i_peak + 1, i_spread), (i_spread + 1, n - 1)]
    names = ["collapse", "spreading", "settling"]
    out = []
    prev_t, prev_wall = 0.0, 0.0
    for name, (i0, i1) in zip(names, bounds):
        steps = max(0, i1 - i0 + 1)
        t_end = t[i1] if steps else prev_t
        w_end = (wall_at(t_end) if name != "settling" else wall_total) if trace else float("nan")
        out.append(
            {
                "phase": name,
                "t_start": prev_t,
                "t_end": t_end,
                "steps": steps,
                "iterations": iterations(prev_t, t_end) if trace else None,
                "wall_s": w_end - prev_wall,
            }
        )
        prev_t, prev_wall = t_end, w_end
    return out, {"final_runout": final, "steps": s["steps"], "wall": wall_total, "peak_t": t[i_peak]}


def phases(args):
    root, args = pop_root(args)
    aspects = [float(x) for x in args if not x.startswith("--")] or [2.0, 8.0]
    for a in aspects:
        d = result_dir(root, a)
        if not (d / "summary.json").exists():
            print(f"a={a:g}: no results in {d}")
            continue
        m = read_monitors(d)
        t, ke = m["time"], m["kinetic_energy"]
        peak = max(ke)
        first = sum(1 for x in t if x <= 0.1)
        last = sum(1 for x in t if x > t[-1] - 0.1)
        t1 = next((x for x, k in zip(t, ke) if x > t[ke.index(peak)] and k < 0.01 * peak), float("nan"))
        print(f"a={a:g}: steps in the first 0.1 s {first}, in the last 0.1 s {last}; "
              f"kinetic energy below 1 % of its peak from t = {t1:.3f} s, run ends at {t[-1]:.3f} s")
        for front in [c for c in ("runout", "runout_5mm") if c in m]:
            ph, info = phases_of(d, front)
            print(f"a={a:g} ({front} within 1 mm of final): {info['steps']} steps, {info['wall']:.1f} s wall, "
                  f"final {front} {info['final_runout']:.4f} m")
            print_phases(ph, info)


def print_phases(ph, info):
    if True:
        for p in ph:
            share = p["steps"] / info["steps"] if info["steps"] else 0
            it = p["iterations"]
            per = f"{it / p['steps']:.1f}" if it is not None and p["steps"] else "-"
            print(
                f"  {p['phase']:9s} t {p['t_start']:.3f}-{p['t_end']:.3f} s: {p['steps']:5d} steps ({share:5.1%}), "
                f"{it} Newton its ({per}/step), {p['wall_s']:.1f} s wall"
            )


def main():
    if len(sys.argv) < 2 or sys.argv[1] not in ("cases", "run", "table", "phases"):
        print(__doc__)
        sys.exit(2)
    {"cases": write_cases, "run": run, "table": table, "phases": phases}[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
