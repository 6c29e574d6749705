#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (CTest; labels unit,
# topology, mpi, gpu, reference). GPU tests skip where no device exists.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 1200
