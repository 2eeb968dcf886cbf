#!/usr/bin/env python3
"""Round trip Loam -> Kratos (issue 27): export Loam cases with `loam export kratos`, run Kratos
10.4.4 on the export and store its result beside the case, for tests/kratos_export.rs.

For each case below, tests/data/kratos/roundtrip_<name>/ receives:
  case.json (+ its .msh files)   the Loam case (imported from a Kratos folder, copied from cases/,
                                 or written by hand), with a `displacement` monitor at a grid node
  kratos/                        what `loam export kratos case.json -o kratos` writes
  kratos_10.4.4_<monitor>.json   Kratos' json_output_process result for each displacement monitor
                                 (the grid node's DISPLACEMENT at every step), with a "source" key
Kratos runs in a temporary copy of kratos/ (one thread, its standard MpmAnalysis stage).
usage (repository root, after cargo build --release):
  python3 benches/kratos/roundtrip.py [--loam target/release/loam] [--python /work/.kratos-venv/bin/python]
"""
import argparse, json, os, shutil, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join("tests", "data", "kratos")


def grid_node(folder, node_id):
    """Coordinates of node `node_id` of a Kratos folder's Grid.mdpa."""
    inside = False
    for line in open(os.path.join(folder, "Grid.mdpa")):
        words = line.split("//")[0].split()
        if words[:2] == ["Begin", "Nodes"]:
            inside = True
        elif words[:2] == ["End", "Nodes"]:
            break
        elif inside and words and int(words[0]) == node_id:
            return [float(w) for w in words[1:4]]
    raise KeyError(node_id)


def imported(source, node_id, component, dim):
    """A Kratos test folder imported, with a displacement monitor at its grid node `node_id`."""
    def make(out, loam):
        run([loam, "import", "kratos", source, "-o", os.path.join(out, "case.json")])
        x = grid_node(source, node_id)[:dim]
        add_monitor(os.path.join(out, "case.json"), {"name": "u", "type": "displacement", "point": x, "component": component})
    return make


def copied(case, monitor, edit=None):
    """A bundled case with a displacement monitor added (and `edit` applied to its JSON)."""
    def make(out, loam):
        c = json.load(open(case))
        if edit:
            edit(c)
        json.dump(c, open(os.path.join(out, "case.json"), "w"), indent=2)
        add_monitor(os.path.join(out, "case.json"), monitor)
    return make


def point_load(c, at, force):
    """Gravity replaced by a nodal force on the grid node nearest to `at` (Kratos' POINT_LOAD)."""
    c["description"] = ("Round trip to Kratos (issue 27): cases/cantilever_mpm.json without gravity, loaded by a "
                        "nodal force %s N on the grid node at %s (Kratos: POINT_LOAD on an "
                        "MPMGridPointLoadCondition2D1N). " % (force, at)) + c["description"]
    c.pop("gravity")
    c["regions"]["tip"] = {"nearest": at}
    c["loads"] = [{"type": "nodal_force", "region": "tip", "force": force}]


def kratos_kinematics(c, end_time):
    """A dynamic case shortened to `end_time`, with Kratos' grid kinematics (projected velocity
    and acceleration kept at fixed grid nodes) and its residual criterion."""
    c["description"] = ("Round trip to Kratos (issue 27): shortened to %s s, solver.hold_grid_boundaries false "
                        "(Kratos keeps the projected kinematics of fixed grid nodes), residual criterion. " % end_time) + c["description"]
    c["analysis"]["end_time"] = end_time
    c.setdefault("solver", {}).update({"hold_grid_boundaries": False, "convergence_criterion": "residual"})


def by_hand(out, loam):
    """The case.json already in the folder (written by hand)."""


def add_monitor(path, monitor):
    c = json.load(open(path))
    c["monitors"] = [m for m in c.get("monitors", []) if m["name"] != monitor["name"]] + [monitor]
    json.dump(c, open(path, "w"), indent=2)
    open(path, "a").write("\n")


CASES = {
    "cantilever_selfweight_2D_quad": imported(os.path.join(DATA, "cantilever_selfweight_2D_quad"), 93, "y", 2),
    "cantilever_lineload_2D_quad": imported(os.path.join(DATA, "cantilever_lineload_2D_quad"), 881, "y", 2),
    "cantilever_selfweight_3D_hexa": imported(os.path.join(DATA, "cantilever_selfweight_3D_hexa"), 338, "y", 3),
    "cantilever_mpm": copied(os.path.join("cases", "cantilever_mpm.json"),
                             {"name": "tip_node_uy", "type": "displacement", "point": [7.0, 1.0], "component": "y"}),
    "cantilever_point_load": copied(os.path.join("cases", "cantilever_mpm.json"),
                                    {"name": "tip_node_uy", "type": "displacement", "point": [7.0, 1.0], "component": "y"},
                                    lambda c: point_load(c, [7.0, 1.0], [0.0, -5.0e4])),
    "cantilever_mpm_dynamic": copied(os.path.join("cases", "cantilever_mpm_dynamic.json"),
                                     {"name": "node_uy", "type": "displacement", "point": [6.0, 0.5], "component": "y"},
                                     lambda c: kratos_kinematics(c, 0.2)),
    "mohr_coulomb": by_hand,
}


def run(cmd, cwd=None, env=None):
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("failed: %s\n%s%s" % (" ".join(cmd), r.stdout[-2000:], r.stderr[-2000:]))
    return r.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--loam", default=os.path.join(ROOT, "target", "release", "loam"))
    ap.add_argument("--python", default="/work/.kratos-venv/bin/python")
    ap.add_argument("cases", nargs="*", default=list(CASES))
    a = ap.parse_args()
    os.chdir(ROOT)
    printed = run([a.python, "-c", "import KratosMultiphysics as K; print('VERSION', K.KratosGlobals.Kernel.Version())"])
    version = [l.split()[1] for l in printed.splitlines() if l.startswith("VERSION")][0].replace('"', "").split("-")[0]
    for name in a.cases:
        out = os.path.join(DATA, "roundtrip_" + name)
        os.makedirs(out, exist_ok=True)
        CASES[name](out, a.loam)
        kratos = os.path.join(out, "kratos")
        shutil.rmtree(kratos, ignore_errors=True)
        run([a.loam, "export", "kratos", os.path.join(out, "case.json"), "-o", kratos])
        monitors = [m["name"] for m in json.load(open(os.path.join(out, "case.json")))["monitors"]
                    if m["type"] == "displacement"]
        with tempfile.TemporaryDirectory() as tmp:
            work = os.path.join(tmp, "kratos")
            shutil.copytree(kratos, work)
            env = dict(os.environ, OMP_NUM_THREADS="1")
            summary = run([a.python, os.path.join(ROOT, "benches", "kratos", "run_case.py")], cwd=work, env=env)
            line = [l for l in summary.splitlines() if l.startswith("RUN_SUMMARY")][0]
            s = json.loads(line[len("RUN_SUMMARY "):])
            for m in monitors:
                r = json.load(open(os.path.join(work, m + ".json")))
                r["source"] = ("Kratos %s (one thread) on %s/kratos, written by `loam export kratos` "
                               "(benches/kratos/roundtrip.py): %d steps, %d Newton iterations"
                               % (version, out, s["steps"], s["nonlinear_iterations_total"]))
                json.dump(r, open(os.path.join(out, "kratos_10.4.4_%s.json" % m), "w"), indent=1)
                open(os.path.join(out, "kratos_10.4.4_%s.json" % m), "a").write("\n")
                node = [k for k in r if k.startswith("NODE_")][0]
                print(name, m, node, {k: v[-1] for k, v in r[node].items()})


if __name__ == "__main__":
    main()
