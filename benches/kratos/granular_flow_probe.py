#!/usr/bin/env python3
"""Kratos 10.4.4 on the granular flow folder (Kratos' Examples `granular_flow_2D`, the Bui
collapse with 30 000 material points) for its first STEPS steps of 5e-5 s: prints one line
`RESULT {json}` with the time, the kinetic energy of the material points (J/m,
sum of MP_MASS |MP_VELOCITY|^2 / 2) and the displacement of the material point nearest the
column's top corner (0.2, 0.1) (tests/kratos_import.rs compares Loam with it).

Run inside a copy of the folder (with its generated Grid.mdpa), with the Kratos venv:
    OMP_NUM_THREADS=1 /work/.kratos-venv/bin/python benches/kratos/granular_flow_probe.py 100
"""
import json
import sys

import KratosMultiphysics as KM
import KratosMultiphysics.MPMApplication as KMPM
try:
    import KratosMultiphysics.LinearSolversApplication  # noqa: F401
except ImportError:
    pass
from KratosMultiphysics.MPMApplication.mpm_analysis import MpmAnalysis

steps = int(sys.argv[1])
params = KM.Parameters(open("ProjectParameters.json").read())
# Kratos steps while t < end_time: end half a step early to take exactly `steps` steps
params["problem_data"]["end_time"].SetDouble((steps - 0.5) * 5e-5)
model = KM.Model()
analysis = MpmAnalysis(model, params)
analysis.Initialize()
mp = model["MPM_Material"]
info = mp.ProcessInfo
elements = list(mp.Elements)
x0 = {e.Id: list(e.CalculateOnIntegrationPoints(KMPM.MP_COORD, info)[0]) for e in elements}
corner = min(elements, key=lambda e: (x0[e.Id][0] - 0.2) ** 2 + (x0[e.Id][1] - 0.1) ** 2).Id
analysis.RunSolutionLoop()
kinetic = 0.0
for e in elements:
    v = e.CalculateOnIntegrationPoints(KMPM.MP_VELOCITY, info)[0]
    m = e.CalculateOnIntegrationPoints(KMPM.MP_MASS, info)[0]
    kinetic += 0.5 * m * (v[0] ** 2 + v[1] ** 2)
xc = mp.GetElement(corner).CalculateOnIntegrationPoints(KMPM.MP_COORD, info)[0]
print("RESULT", json.dumps({
    "steps": steps, "time": info[KM.TIME], "kinetic_energy": kinetic, "material_points": len(elements),
    "corner_initial": x0[corner][:2], "corner_ux": xc[0] - x0[corner][0], "corner_uy": xc[1] - x0[corner][1],
}))
