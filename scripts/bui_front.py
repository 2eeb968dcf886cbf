#!/usr/bin/env python3
"""The front of a Bui et al. (2008) collapse's deposit, from the last `.vtu` of runs.

For each output directory (a `loam run` of a Bui case with point output, e.g. `"output":
{"interval": 0}` for the last state only) it prints

- the runout by the deposit's thickness: t(x) = (sum of the current areas of the points whose
  centres lie in a 5 mm bin) / 5 mm, the runout where t falls to 2, 3, 4 and 5 mm (the
  farthest bin at or above the threshold, interpolated linearly to the next bin centre).
  Unlike the `runout` monitor (the connected stretch of point squares whose tops stand 2 mm
  above the base) it does not jump where a sheet at the front is one or two points thick;
- the surface height at the experiment's digitised points from x = 0.38 m on (the highest top
  of the point squares within 0.6 of a square's side of x, as the `surface_height` monitor
  and the surface measure of `tests/mpm_collapse.rs` take it) beside the experiment's.

With several directories (e.g. the same case with gravity perturbed by k·1e-12) it prints the
mean and range of each figure. docs/validation.md (the μ(I) refinement) uses it.

Usage: .venv/bin/python scripts/bui_front.py OUT [OUT ...]
"""
import glob
import os
import sys

import meshio
import numpy as np

BIN = 0.005
THRESHOLDS = [0.002, 0.003, 0.004, 0.005]
SURFACE = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "bui2008", "surface.csv")


def last_points(directory):
    """Positions and current volumes (areas per metre) of the last point output in `directory`."""
    files = sorted(f for f in glob.glob(os.path.join(directory, "*.vtu")) if "grid" not in os.path.basename(f))
    if not files:
        sys.exit(f"bui_front: no .vtu in {directory} (run the case with point output)")
    mesh = meshio.read(files[-1])
    return mesh.points[:, 0], mesh.points[:, 1], mesh.point_data["volume"]


def thickness_runouts(x, volume):
    """The runout where the binned thickness falls to each of THRESHOLDS (m)."""
    edges = np.arange(0.0, x.max() + 2 * BIN, BIN)
    centres = 0.5 * (edges[:-1] + edges[1:])
    thickness = np.bincount(np.digitize(x, edges) - 1, weights=volume, minlength=len(centres))[: len(centres)] / BIN
    runouts = []
    for threshold in THRESHOLDS:
        k = np.nonzero(thickness >= threshold)[0].max()
        runouts.append(centres[k] + (thickness[k] - threshold) / (thickness[k] - thickness[k + 1]) * BIN)
    return runouts


def front_heights(x, y, volume, at):
    """The highest square top covering each abscissa of `at` (m)."""
    size = np.sqrt(volume)
    heights = []
    for xr in at:
        covering = np.abs(x - xr) <= 0.6 * size
        heights.append((y[covering] + 0.5 * size[covering]).max() if covering.any() else 0.0)
    return heights


def main(directories):
    reference = np.loadtxt(SURFACE, delimiter=",", skiprows=1)
    tail = reference[reference[:, 0] >= 0.38]
    rows = []
    for directory in directories:
        x, y, volume = last_points(directory)
        rows.append(thickness_runouts(x, volume) + front_heights(x, y, volume, tail[:, 0]))
        print(f"{directory}: farthest point {x.max():.4f} m")
    rows = np.array(rows)
    labels = [f"runout, thickness >= {1e3 * t:.0f} mm (m)" for t in THRESHOLDS]
    labels += [f"surface at x = {xr:.3f} m (mm), experiment {1e3 * yr:.2f}" for xr, yr in tail]
    scale = [1.0] * len(THRESHOLDS) + [1e3] * len(tail)
    for j, label in enumerate(labels):
        column = rows[:, j] * scale[j]
        spread = f" (range {column.min():.4f}–{column.max():.4f}, {len(column)} runs)" if len(column) > 1 else ""
        print(f"{label}: {column.mean():.4f}{spread}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
