"""Runs the bundled cantilever and checks that meshio reads its .pvd series and .vtu files
with the expected fields and the tip deflection the monitor reports."""
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
print("1 passed, 0 failed")
