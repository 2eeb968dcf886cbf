"""Runs the bundled cantilever and checks that meshio reads its .pvd series and .vtu files
with the expected fields and the tip deflection the monitor reports; then the hydrostatic
column's background grid (output.grid) with its nodal fields and the points' total mass."""
import csv
import pathlib
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import meshio

root = pathlib.Path(__file__).resolve().parent.parent
with tempfile.TemporaryDirectory() as tmp:
    out = pathlib.Path(tmp) / "cantilever"
    subprocess.run([root / "target/release/loam", "run", root / "cases/cantilever_fem.json", "--out", out, "--quiet"], check=True)
    series = ET.parse(out / "beam.pvd").getroot().findall(".//DataSet")
    assert len(series) == 2, f"expected 2 steps in beam.pvd, got {len(series)}"
    mesh = meshio.read(out / series[-1].get("file"))
    for name in ("displacement", "velocity", "acceleration"):
        assert name in mesh.point_data, f"point field {name} missing"
    for name in ("cauchy_stress", "green_lagrange_strain", "von_mises_stress"):
        assert name in mesh.cell_data, f"cell field {name} missing"
    rows = list(csv.DictReader(open(out / "monitors.csv")))
    tip = float(rows[-1]["tip_uy"])
    pts = mesh.points
    k = min(range(len(pts)), key=lambda i: (pts[i][0] - 7.0) ** 2 + (pts[i][1] - 0.5) ** 2)
    vtk_tip = mesh.point_data["displacement"][k][1]
    print(f"meshio: {len(pts)} points, {sum(len(c.data) for c in mesh.cells)} cells; tip u_y in VTK {vtk_tip:.10f} m, monitor {tip:.10f} m")
    assert abs(vtk_tip - tip) < 1e-12

    # output.grid: the MPM background grid of the hydrostatic column as its own series
    out = pathlib.Path(tmp) / "column"
    subprocess.run([root / "target/release/loam", "run", root / "cases/hydrostatic_column_mpm.json", "--out", out, "--quiet"], check=True)
    series = ET.parse(out / "column_grid.pvd").getroot().findall(".//DataSet")
    assert len(series) == 2, f"expected 2 steps in column_grid.pvd, got {len(series)}"
    grid = meshio.read(out / series[-1].get("file"))
    for name in ("mass", "displacement_increment", "velocity", "acceleration", "active"):
        assert name in grid.point_data, f"grid point field {name} missing"
    assert len(grid.points) == 21 * 13 and sum(len(c.data) for c in grid.cells) == 20 * 12
    mass = grid.point_data["mass"].sum()
    active = int(grid.point_data["active"].sum())
    print(f"meshio: grid {len(grid.points)} nodes, {active} active; nodal mass {mass:.12f} kg (points: rho W H = 36 kg)")
    assert abs(mass - 1800 * 0.2 * 0.1) < 1e-9 and active == 21 * 11
print("2 passed, 0 failed")
