#!/usr/bin/env python3
"""The indenter of the Hertz contact case (Gmsh MSH 4.1 ASCII, quadrilaterals): the half
(x >= 0) of a cylinder of radius R near its lowest point, cut at x = L and at the height H
above it. Its bottom is the circular arc y = R - sqrt(R^2 - x^2), 0 <= x <= L, with nx cells
along x (evenly in x); each column runs straight up to y = H in ny cells, graded towards the
arc (ratio `grading` between the top and the bottom cell heights), so that the contact zone
is resolved. Cells are counter-clockwise. Also prints the arc's nodes as a polyline (the
case's interface region).

Usage: python3 scripts/hertz_mesh.py R L H nx ny grading OUT.msh
(e.g. python3 scripts/hertz_mesh.py 1.0 0.3 0.3 60 20 8 cases/meshes/hertz_indenter.msh)
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cooks_membrane_meshes import write_msh  # noqa: E402


def indenter(radius, length, height, nx, ny, grading):
    # cell heights in geometric progression, the first (at the arc) `grading` times smaller
    ratio = grading ** (1.0 / max(ny - 1, 1))
    weights = [ratio**j for j in range(ny)]
    fractions = [sum(weights[:j]) / sum(weights) for j in range(ny + 1)]
    nodes = []
    for j in range(ny + 1):
        for i in range(nx + 1):
            x = length * i / nx
            bottom = radius - math.sqrt(radius * radius - x * x)
            nodes.append((x, bottom + (height - bottom) * fractions[j]))
    cells = []
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i
            cells.append((a, a + 1, a + nx + 2, a + nx + 1))
    arc = [list(nodes[i]) for i in range(nx + 1)]
    return nodes, cells, arc


if __name__ == "__main__":
    R, L, H = (float(v) for v in sys.argv[1:4])
    nx, ny, grading, out = int(sys.argv[4]), int(sys.argv[5]), float(sys.argv[6]), sys.argv[7]
    nodes, cells, arc = indenter(R, L, H, nx, ny, grading)
    write_msh(out, nodes, cells, 3)
    print(f"{len(nodes)} nodes, {len(cells)} quadrilaterals; arc polyline:")
    print(json.dumps(arc))
