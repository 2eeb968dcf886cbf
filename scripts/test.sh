#!/usr/bin/env bash
# Loam's whole test suite: Rust unit, validation and CLI tests, then the Python checks
# (VTK files read by meshio, FMUs run by fmpy) in a virtual environment it sets up itself,
# then the distributed path: the `petsc` and `mpi` features' tests (tests/petsc.rs; tests/mpi.rs,
# mpirun -n 1, 2, 4 and 8 against the serial runs), with PETSc and Open MPI installed from the
# system's packages when missing (scripts/install_petsc.sh: root and the network).
#   scripts/test.sh               the default suite (24 minutes on 2 cores from a fresh clone
#                                 on 7 December, builds included: the first 8, the `mpi`
#                                 feature's 2; a fresh machine adds about 2 minutes of packages)
#   LOAM_LONG=1 scripts/test.sh   also the long validation runs: every test marked
#                                 #[ignore = "long ..."] (the Rust tests 58 minutes under
#                                 cargo-nextest on 7 December, the μ(I) Bui refinements the
#                                 longest; three of them fail, README)
#   LOAM_MPI=0 scripts/test.sh    without the distributed path; LOAM_MPI=1 fails where its
#                                 packages cannot be installed (by default the stage is then
#                                 skipped with a message)
#   LOAM_PETSC=1 scripts/test.sh  also the binding crate's own tests (petsc/)
# The Rust part needs no Python: the Rust tests that need the .venv (the meshio reading of VTK
# files, the FMU tutorial's fmpy loop) are #[ignore]d there and run in the Python part, with
# the .venv's interpreter.
set -euo pipefail
cd "$(dirname "$0")/.."

# The Rust tests run under cargo-nextest where the machine has it (a process per test, two at a
# time across all test binaries: the long tests of one binary no longer wait for each other's
# binary to finish; 494-523 s on 7 December against an estimated 650-720 s under `cargo test`,
# from earlier suite logs less that day's test changes), else `cargo test`.
# `rust_tests ARGS...` runs the tests that ARGS select (cargo's target and feature options).
if cargo nextest --version >/dev/null 2>&1; then
  rust_tests() { cargo nextest run --release --no-fail-fast "$@"; }
  # the meshio and FMU-tutorial tests run below with the .venv
  long_tests=(--run-ignored all -E 'not (test(meshio_reads_mesh_and_cloud) | test(tutorial_6_fmu_python))')
else
  rust_tests() { cargo test --release "$@"; }
  long_tests=(-- --include-ignored --skip meshio_reads_mesh_and_cloud --skip tutorial_6_fmu_python)
fi

# `stage TITLE` prints a stage's title with the minutes and seconds since the suite started
stage() { printf '== [%d:%02d] %s\n' $((SECONDS / 60)) $((SECONDS % 60)) "$*"; }

# one (release) build serves the tests, the CLI and the FMU library
stage "Rust: the workspace's tests (release)"
if [ "${LOAM_LONG:-0}" = "1" ]; then
  rust_tests --workspace "${long_tests[@]}"
else
  rust_tests --workspace
fi

stage "Python: virtual environment for meshio/fmpy checks (.venv)"
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r scripts/requirements.txt

stage "Python: VTK output read by meshio"
# target/release/loam is the test build's (the CLI tests need it); the cargo commands below
# reuse that build's artifacts (the same features, Cargo.toml's approx and workspace-hack)
cargo test --release --quiet -p loam --lib \
  output::vtk::tests::meshio_reads_mesh_and_cloud -- --ignored --exact
.venv/bin/python scripts/check_vtk.py

stage "Python: relative links and anchors of README.md and docs/ (standard library)"
python3 scripts/check_links.py

stage "C: fmu/src/ffi.rs types compiled against the FMI 3.0 headers (fmpy's)"
.venv/bin/python scripts/check_fmi_header.py

stage "Python: FMI 3.0 FMUs run by fmpy (loam fmu, tests/fmu)"
cargo build --release --quiet -p loam -p loam-fmu
.venv/bin/python tests/fmu/test_fmu.py

stage "Python: tutorial 6, a case as an FMU in a Python loop (docs/tutorial/fmu_python)"
LOAM_PYTHON="$PWD/.venv/bin/python" cargo test --release --quiet --test tutorials \
  tutorial_6_fmu_python -- --ignored --exact

stage "Python: FMU robustness (reset, 100 instantiations, NaN/inf, bad steps, failing steps)"
.venv/bin/python tests/fmu/test_fmu_robustness.py

# The distributed path last (issue 26, item 7): its build replaces target/release/loam with the
# `mpi` feature's, which the Python checks above must not run.
mpi="${LOAM_MPI:-auto}"
if [ "$mpi" != "0" ]; then
  have_packages() { pkg-config --exists petsc 2>/dev/null && command -v mpirun >/dev/null; }
  if ! have_packages; then
    stage "System packages of the petsc and mpi features (scripts/install_petsc.sh)"
    scripts/install_petsc.sh || true
  fi
  if have_packages; then
    stage "Rust: the petsc and mpi features (tests/petsc.rs; tests/mpi.rs: mpirun -n 1, 2, 4 and 8)"
    rust_tests --features mpi --test mpi --test petsc
    if [ "${LOAM_PETSC:-0}" = "1" ]; then
      cargo test --release --manifest-path petsc/Cargo.toml --target-dir target
    fi
  elif [ "$mpi" = "1" ]; then
    echo "LOAM_MPI=1: PETSc (pkg-config) or mpirun not found after scripts/install_petsc.sh" >&2
    exit 1
  else
    echo "SKIPPED: the petsc and mpi features' tests: PETSc or Open MPI could not be installed" \
      "(scripts/install_petsc.sh needs root and the network); LOAM_MPI=1 makes this an error"
  fi
fi
stage "done"
