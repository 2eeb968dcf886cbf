#!/usr/bin/env bash
# System packages of the `petsc` feature (issue 26, docs/distributed.md "Bindings"):
# Debian's PETSc 3.18 (with GAMG, hypre, MUMPS), Open MPI, libclang for bindgen, pkg-config.
# Idempotent: does nothing when every package is installed. Needs root (or sudo).
#   scripts/install_petsc.sh
set -euo pipefail
packages=(libpetsc-real-dev libopenmpi-dev libclang-dev pkg-config)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_petsc: all of ${packages[*]} installed"
  exit 0
fi
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
# a stale package index makes dependencies (libcurl4-openssl-dev of libhdf5-openmpi-dev) look
# uninstallable: refresh it first
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
