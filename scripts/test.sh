#!/usr/bin/env bash
# Loam's whole test suite: Rust unit, validation and CLI tests, then the Python checks
# (VTK files read by meshio, FMUs run by fmpy) in a virtual environment it sets up itself.
#   scripts/test.sh               the default suite (12–16 minutes on 2 cores)
#   LOAM_LONG=1 scripts/test.sh   also the long validation runs: every test marked
#                                 #[ignore = "long ..."] (about 25 minutes in all)
#   LOAM_PETSC=1 scripts/test.sh  also the `petsc` feature's tests (needs scripts/install_petsc.sh;
#                                 the feature's build adds 1.5-2.5 minutes)
#   LOAM_MPI=1 scripts/test.sh    also the `mpi` feature's tests: mpirun -n 2 and -n 4 against the
#                                 serial PETSc run (tests/mpi.rs; needs scripts/install_petsc.sh,
#                                 which brings Open MPI; the build adds 3-5 minutes, the tests ~25 s)
# The Rust part needs no Python: the Rust tests that need the .venv (the meshio reading of VTK
# files, the FMU tutorial's fmpy loop) are #[ignore]d there and run in the Python part, with
# the .venv's interpreter.
set -euo pipefail
cd "$(dirname "$0")/.."

# one (release) build serves the tests, the CLI and the FMU library
echo "== Rust: cargo test --release (workspace)"
if [ "${LOAM_LONG:-0}" = "1" ]; then
  # the meshio and FMU-tutorial tests run below with the .venv
  cargo test --release --workspace -- --include-ignored --skip meshio_reads_mesh_and_cloud \
    --skip tutorial_6_fmu_python
else
  cargo test --release --workspace
fi

if [ "${LOAM_PETSC:-0}" = "1" ]; then
  if ! pkg-config --exists petsc 2>/dev/null; then
    echo "LOAM_PETSC=1: PETSc not found by pkg-config; run scripts/install_petsc.sh" >&2
    exit 1
  fi
  echo "== Rust: the petsc feature (PETSc found by pkg-config)"
  cargo test --release --features petsc --test petsc
  cargo test --release --manifest-path petsc/Cargo.toml --target-dir target
fi

if [ "${LOAM_MPI:-0}" = "1" ]; then
  if ! pkg-config --exists petsc 2>/dev/null || ! command -v mpirun >/dev/null; then
    echo "LOAM_MPI=1: PETSc (pkg-config) or mpirun not found; run scripts/install_petsc.sh" >&2
    exit 1
  fi
  echo "== Rust: the mpi feature (mpirun -n 2 and -n 4, oversubscribed where cores are fewer)"
  cargo test --release --features mpi --test mpi
fi

echo "== Python: virtual environment for meshio/fmpy checks (.venv)"
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r scripts/requirements.txt

echo "== Python: VTK output read by meshio"
cargo build --release --quiet
cargo test --release --quiet -p loam --lib \
  output::vtk::tests::meshio_reads_mesh_and_cloud -- --ignored --exact
.venv/bin/python scripts/check_vtk.py

echo "== Python: relative links and anchors of README.md and docs/ (standard library)"
python3 scripts/check_links.py

echo "== C: fmu/src/ffi.rs types compiled against the FMI 3.0 headers (fmpy's)"
.venv/bin/python scripts/check_fmi_header.py

echo "== Python: FMI 3.0 FMUs run by fmpy (loam fmu, tests/fmu)"
cargo build --release --quiet -p loam -p loam-fmu
.venv/bin/python tests/fmu/test_fmu.py

echo "== Python: tutorial 6, a case as an FMU in a Python loop (docs/tutorial/fmu_python)"
LOAM_PYTHON="$PWD/.venv/bin/python" cargo test --release --quiet --test tutorials \
  tutorial_6_fmu_python -- --ignored --exact

echo "== Python: FMU robustness (reset, 100 instantiations, NaN/inf, bad steps, failing steps)"
.venv/bin/python tests/fmu/test_fmu_robustness.py
