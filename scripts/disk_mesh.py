#!/usr/bin/env python3
"""A disk meshed by quadrilaterals (Gmsh MSH 4.1 ASCII): an O-grid of five blocks.

The centre block is the square [-a, a]^2 (a = R/2) with n x n cells; four blocks of n x m cells
join its edges to the circle of radius R, each node on the straight line from a point of the
square's edge (the same fraction along it) to the point of the arc at the same fraction of its
quarter, evenly in m steps. Nodes are shared between blocks; cells are counter-clockwise.

Usage: python3 scripts/disk_mesh.py R n m CX CY OUT.msh
(e.g. python3 scripts/disk_mesh.py 0.05 4 3 0.3 0.27 cases/meshes/disk_r0.05.msh)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cooks_membrane_meshes import write_msh  # noqa: E402


def disk(radius, n, m, cx, cy):
    a = 0.5 * radius
    nodes, index = [], {}

    def node(x, y):
        key = (round(x * 1e12), round(y * 1e12))
        if key not in index:
            index[key] = len(nodes)
            nodes.append((cx + x, cy + y))
        return index[key]

    cells = []
    # centre block
    grid = [[node(-a + 2 * a * i / n, -a + 2 * a * j / n) for i in range(n + 1)] for j in range(n + 1)]
    for j in range(n):
        for i in range(n):
            cells.append((grid[j][i], grid[j][i + 1], grid[j + 1][i + 1], grid[j + 1][i]))
    # four outer blocks: side k has the square edge from corner c0 to c1 (counter-clockwise)
    corners = [(a, -a), (a, a), (-a, a), (-a, -a)]
    for k in range(4):
        (x0, y0), (x1, y1) = corners[k], corners[(k + 1) % 4]
        t0 = math.atan2(y0, x0)
        rows = []
        for r in range(m + 1):
            row = []
            for i in range(n + 1):
                s = i / n
                qx, qy = x0 + (x1 - x0) * s, y0 + (y1 - y0) * s
                t = t0 + s * math.pi / 2
                px, py = radius * math.cos(t), radius * math.sin(t)
                f = r / m
                row.append(node(qx + (px - qx) * f, qy + (py - qy) * f))
            rows.append(row)
        for r in range(m):
            for i in range(n):
                # inner edge runs counter-clockwise along the square; outward is +r
                cells.append((rows[r][i], rows[r + 1][i], rows[r + 1][i + 1], rows[r][i + 1]))
    return nodes, cells


def area(nodes, cells):
    total = 0.0
    for c in cells:
        p = [nodes[k] for k in c]
        a = 0.5 * sum(p[i][0] * p[(i + 1) % 4][1] - p[(i + 1) % 4][0] * p[i][1] for i in range(4))
        assert a > 0, "a cell is not counter-clockwise"
        total += a
    return total


if __name__ == "__main__":
    R, n, m = float(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    cx, cy, out = float(sys.argv[4]), float(sys.argv[5]), sys.argv[6]
    nodes, cells = disk(R, n, m, cx, cy)
    print(f"{len(nodes)} nodes, {len(cells)} quadrilaterals, area {area(nodes, cells):.6e} (disk {math.pi * R * R:.6e})")
    write_msh(out, nodes, cells, 3)
