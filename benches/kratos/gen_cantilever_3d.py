#!/usr/bin/env python3
"""Generate a structured-hexahedron MPM cantilever under self-weight (Kratos 10.4 MPMApplication, 3D).

The 3D counterpart of gen_cantilever.py: beam [0,L]x[0,H]x[0,W], E=9e7, nu=0, rho=1000,
Neo-Hookean (HyperElasticNeoHookean3DLaw), g=9.81 along -y, clamped at x=0 (every grid node on the
plane x=0 fixed). Background grid [0,L+1]x[-1.5,H+0.5]x[-h,W+h] of hexahedra (Element3D8N) of the
body's cell size; body cells (MPMUpdatedLagrangian3D8N) coincide with grid cells; ppc = 1, 8, 27. With --tets every
hexahedron is split into six tetrahedra (Kuhn: one per ordering of the axes; Element3D4N and
MPMUpdatedLagrangian3D4N, ppc = 1 or 4). With nu = 0 the beam bends as the plane-strain one of
gen_cantilever.py.
usage: gen_cantilever_3d.py OUTDIR --n 2 [--L 7] [--W 1] [--ppc 8] [--tets] [--solver amgcl|sparse_lu]
"""
import argparse, itertools, json, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kratos_case  # noqa: E402  (the processes shared with the other generator)

ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--n", type=int, default=2, help="cells through the depth (h = H/n)")
ap.add_argument("--L", type=float, default=7.0)
ap.add_argument("--H", type=float, default=1.0)
ap.add_argument("--W", type=float, default=1.0)
ap.add_argument("--ppc", type=int, default=8)
ap.add_argument("--tets", action="store_true")
ap.add_argument("--solver", default="amgcl")
a = ap.parse_args()
os.makedirs(a.out, exist_ok=True)
h = a.H / a.n
E, nu, rho, g = 9.0e7, 0.0, 1000.0, 9.81


def write_mdpa(fname, x0, y0, z0, nx, ny, nz, elem_name, fixed_x0=False, body=False):
    ids = {}
    lines = ["Begin ModelPartData", "End ModelPartData", "", "Begin Properties 0", "End Properties", "",
             "Begin Nodes"]
    nid = 0
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                nid += 1
                ids[(i, j, k)] = nid
                lines.append("%8d %18.10f %18.10f %18.10f" % (nid, x0 + i * h, y0 + j * h, z0 + k * h))
    lines += ["End Nodes", "", "Begin Elements " + elem_name]
    eid = 0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                if a.tets:
                    cells = []
                    for order in itertools.permutations(range(3)):
                        corner, path = [0, 0, 0], [(i, j, k)]
                        for axis in order:
                            corner[axis] += 1
                            path.append((i + corner[0], j + corner[1], k + corner[2]))
                        # positive volume: odd permutations of the axes are left-handed
                        inversions = sum(1 for p, q in itertools.combinations(order, 2) if p > q)
                        if inversions % 2:
                            path[1], path[2] = path[2], path[1]
                        cells.append([ids[v] for v in path])
                else:
                    cells = [[ids[(i, j, k)], ids[(i + 1, j, k)], ids[(i + 1, j + 1, k)], ids[(i, j + 1, k)],
                              ids[(i, j, k + 1)], ids[(i + 1, j, k + 1)], ids[(i + 1, j + 1, k + 1)],
                              ids[(i, j + 1, k + 1)]]]
                for c in cells:
                    eid += 1
                    lines.append("%8d %4d " % (eid, 0) + " ".join("%8d" % n for n in c))
    lines += ["End Elements", ""]
    part = "Parts_Body" if body else "Parts_Grid"
    lines += ["Begin SubModelPart " + part, "  Begin SubModelPartNodes"]
    lines += ["    %d" % k for k in range(1, nid + 1)]
    lines += ["  End SubModelPartNodes", "  Begin SubModelPartElements"]
    lines += ["    %d" % k for k in range(1, eid + 1)]
    lines += ["  End SubModelPartElements", "End SubModelPart", ""]
    if fixed_x0:
        lines += ["Begin SubModelPart DISPLACEMENT_Support", "  Begin SubModelPartNodes"]
        lines += ["    %d" % ids[(0, j, k)] for k in range(nz + 1) for j in range(ny + 1)]
        lines += ["  End SubModelPartNodes", "End SubModelPart", ""]
    open(fname, "w").write("\n".join(lines))
    return ids, eid


bx, by, bz = round(a.L / h), round(a.H / h), round(a.W / h)
nodes = "3D4N" if a.tets else "3D8N"
write_mdpa(os.path.join(a.out, "Body.mdpa"), 0.0, 0.0, 0.0, bx, by, bz, "MPMUpdatedLagrangian" + nodes, body=True)
gy0, gy1 = -1.5, a.H + 0.5
gx, gy, gz = round((a.L + 1.0) / h), round((gy1 - gy0) / h), bz + 2
ids, ge = write_mdpa(os.path.join(a.out, "Grid.mdpa"), 0.0, gy0, -h, gx, gy, gz, "Element" + nodes, fixed_x0=True)

mat = {"properties": [{"model_part_name": "Initial_MPM_Material.Parts_Body", "properties_id": 1,
       "Material": {"constitutive_law": {"name": "HyperElasticNeoHookean3DLaw"},
                    "Variables": {"MATERIAL_POINTS_PER_ELEMENT": a.ppc, "DENSITY": rho,
                                  "YOUNG_MODULUS": E, "POISSON_RATIO": nu}, "Tables": {}}}]}
json.dump(mat, open(os.path.join(a.out, "materials.json"), "w"), indent=4)

solver = {"solver_type": "Static", "model_part_name": "MPM_Material", "domain_size": 3,
          "echo_level": 0, "analysis_type": "non_linear",
          "model_import_settings": {"input_type": "mdpa", "input_filename": "Body"},
          "material_import_settings": {"materials_filename": "materials.json"},
          "time_stepping": {"time_step": 1.1},
          "convergence_criterion": "residual_criterion",
          "displacement_relative_tolerance": 1e-4, "displacement_absolute_tolerance": 1e-9,
          "residual_relative_tolerance": 1e-4, "residual_absolute_tolerance": 1e-9, "max_iteration": 20,
          "problem_domain_sub_model_part_list": ["Parts_Body", "Parts_Grid"],
          "processes_sub_model_part_list": ["DISPLACEMENT_Support"],
          "grid_model_import_settings": {"input_type": "mdpa", "input_filename": "Grid"},
          "pressure_dofs": False}
if a.solver == "sparse_lu":
    solver["linear_solver_settings"] = {"solver_type": "LinearSolversApplication.sparse_lu"}
params = kratos_case.project_parameters("cantilever_3d", solver, 1.0, g)
json.dump(params, open(os.path.join(a.out, "ProjectParameters.json"), "w"), indent=4)

# the grid node at the tip, top, mid-width (x = L, y = H, z = W/2) and its displacement
tip = ids[(bx, round((a.H - gy0) / h), 1 + bz // 2)]
I = a.W * a.H ** 3 / 12.0
w_eb = rho * g * a.H * a.W * a.L ** 4 / (8 * E * I)
info = {"source": "generated by benches/kratos/gen_cantilever_3d.py " + " ".join(
            "--%s %s" % (k, v) for k, v in vars(a).items() if k != "out"),
        "euler_bernoulli": {"w_tip": -w_eb},
        "key_results": [{"label": "tip grid node %d DISPLACEMENT_Y" % tip, "type": "node", "node": tip,
                         "variable": "DISPLACEMENT_Y", "reference": -w_eb}],
        "history": []}
json.dump(info, open(os.path.join(a.out, "case_info.json"), "w"), indent=4)
cells = bx * by * bz * (6 if a.tets else 1)
print("generated", a.out, "body cells", cells, "MPs", cells * a.ppc, "grid cells", ge,
      "tip node", tip, "EB w_tip", -w_eb)
