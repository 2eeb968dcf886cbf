#!/usr/bin/env python3
"""Writes the synthetic data of cases/laws/fit_mc_triaxial.json (issue 29).

Three drained triaxial compression tests (sigma3 = 50, 100, 200 kPa) of a Mohr-Coulomb
material with known parameters are run by `loam law` (the material-point driver); every
4th row of path.csv (41 points to 8 % axial strain) is kept, converted to lab conventions
(axial and volumetric strain in %, compression positive; q in kPa) and given seeded Gaussian
noise with a standard deviation of NOISE times the curve's largest value. The true
parameters and the seed are written in each CSV's header.

    cargo build --release && python3 scripts/make_fit_mc_triaxial.py
"""
import csv
import json
import random
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LOAM = ROOT / "target" / "release" / "loam"
OUT = ROOT / "cases" / "laws"
TRUE = {"law": "mohr_coulomb", "density": 2000.0, "young_modulus": 4.0e7, "poisson_ratio": 0.3,
        "friction_angle": 32.0, "cohesion": 1.5e4, "dilatancy_angle": 4.0}
PRESSURES_KPA = [50, 100, 200]
NOISE = 0.002
SEED = 29
EVERY = 4


def main():
    rng = random.Random(SEED)
    for s3 in PRESSURES_KPA:
        path = {"description": f"synthetic drained triaxial, sigma3 = {s3} kPa", "material": TRUE,
                "path": {"type": "triaxial", "drainage": "drained", "loading": "compression",
                         "confining_pressure": s3 * 1e3, "axial_strain": 0.08, "steps": 160}}
        with tempfile.TemporaryDirectory() as tmp:
            spec = Path(tmp) / "path.json"
            spec.write_text(json.dumps(path))
            subprocess.run([str(LOAM), "law", str(spec), "--out", tmp], check=True, stdout=subprocess.DEVNULL)
            rows = list(csv.DictReader(open(Path(tmp) / "path.csv")))[::EVERY]
        ea = [-100 * float(r["axial_strain"]) for r in rows]
        q = [float(r["q"]) / 1e3 for r in rows]
        ev = [-100 * float(r["volumetric_strain"]) for r in rows]
        sq, sv = NOISE * max(abs(v) for v in q), NOISE * max(abs(v) for v in ev)
        q = [v + rng.gauss(0, sq) for v in q]
        ev = [v + rng.gauss(0, sv) for v in ev]
        with open(OUT / f"fit_mc_triaxial_{s3}kPa.csv", "w") as f:
            f.write(f"# Synthetic drained triaxial compression, sigma3 = {s3} kPa: written by\n"
                    f"# scripts/make_fit_mc_triaxial.py from `loam law` (mohr_coulomb, E = 40 MPa, nu = 0.3,\n"
                    f"# phi = 32 deg, c = 15 kPa, psi = 4 deg; 160 steps to 8 %, every {EVERY}th row) with seeded\n"
                    f"# Gaussian noise (seed {SEED}, standard deviation {100 * NOISE:g} % of each curve's largest value).\n"
                    f"# axial_strain_percent and volumetric_strain_percent: compression positive.\n")
            f.write("axial_strain_percent,q_kPa,volumetric_strain_percent\n")
            for a, b, c in zip(ea, q, ev):
                f.write(f"{a:.4f},{b:.4f},{c:.5f}\n")


if __name__ == "__main__":
    main()
