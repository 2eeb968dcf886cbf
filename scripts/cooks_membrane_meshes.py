#!/usr/bin/env python3
"""Cook's membrane meshes (Gmsh MSH 4.1 ASCII) for the mixed u–p validation (issue 15).

The membrane is the trapezoid (0, 0), (48, 44), (48, 60), (0, 44), clamped at x = 0 and loaded
on its right edge x = 48. Writes into cases/meshes/:

- cooks_membrane_quad_N.msh, N = 4, 8, 16, 32: the bilinear map of an N x N grid of
  quadrilaterals (the usual refinement sequence of Cook's membrane);
- cooks_membrane_kratos.msh: the triangles of Kratos' own test
  (../shared/kratos/cases/cooks_membrane_UP_incompressible/Body.mdpa, 1 720 nodes, 3 262
  triangles), converted as they are.

Usage: python3 scripts/cooks_membrane_meshes.py [path to Kratos' Body.mdpa]
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "cases", "meshes")
KRATOS = os.path.join(HERE, "..", "..", "shared", "kratos", "cases", "cooks_membrane_UP_incompressible", "Body.mdpa")


def write_msh(path, nodes, cells, gmsh_type):
    """nodes: list of (x, y); cells: list of node-index tuples (0-based, counter-clockwise)."""
    xs = [n[0] for n in nodes]
    ys = [n[1] for n in nodes]
    with open(path, "w") as f:
        f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        f.write("$Entities\n0 0 1 0\n")
        f.write(f"1 {min(xs)} {min(ys)} 0 {max(xs)} {max(ys)} 0 0 0\n$EndEntities\n")
        f.write(f"$Nodes\n1 {len(nodes)} 1 {len(nodes)}\n2 1 0 {len(nodes)}\n")
        for k in range(len(nodes)):
            f.write(f"{k + 1}\n")
        for x, y in nodes:
            f.write(f"{x!r} {y!r} 0\n")
        f.write("$EndNodes\n")
        f.write(f"$Elements\n1 {len(cells)} 1 {len(cells)}\n2 1 {gmsh_type} {len(cells)}\n")
        for k, c in enumerate(cells):
            f.write(f"{k + 1} " + " ".join(str(a + 1) for a in c) + "\n")
        f.write("$EndElements\n")


def structured(n):
    def at(s, t):
        # bilinear map of (s, t) in [0, 1]^2: left edge x = 0 from y = 0 to 44, right edge x = 48
        # from y = 44 to 60
        x = 48.0 * s
        y = (1 - s) * (44.0 * t) + s * (44.0 + 16.0 * t)
        return (x, y)

    nodes = [at(i / n, j / n) for j in range(n + 1) for i in range(n + 1)]
    cells = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            cells.append((a, a + 1, a + n + 2, a + n + 1))
    return nodes, cells


def kratos(path):
    nodes, ids, cells = [], {}, []
    section = None
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "Begin":
            section = w[1]
            continue
        if w[0] == "End":
            section = None
            continue
        if section == "Nodes":
            ids[int(w[0])] = len(nodes)
            nodes.append((float(w[1]), float(w[2])))
        elif section == "Elements":
            a, b, c = (ids[int(v)] for v in w[2:5])
            (ax, ay), (bx, by), (cx, cy) = nodes[a], nodes[b], nodes[c]
            if (bx - ax) * (cy - ay) - (cx - ax) * (by - ay) < 0:
                b, c = c, b
            cells.append((a, b, c))
    return nodes, cells


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    for n in (4, 8, 16, 32):
        nodes, cells = structured(n)
        write_msh(os.path.join(OUT, f"cooks_membrane_quad_{n}.msh"), nodes, cells, 3)
    src = sys.argv[1] if len(sys.argv) > 1 else KRATOS
    nodes, cells = kratos(src)
    write_msh(os.path.join(OUT, "cooks_membrane_kratos.msh"), nodes, cells, 2)
    print(f"wrote {OUT}: quads 4..32, Kratos' mesh ({len(nodes)} nodes, {len(cells)} triangles)")
