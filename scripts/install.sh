#!/usr/bin/env bash
# Installs what tetiso needs on Debian 12 (as root), then configures and
# builds it in build/. Sourced by main.sh and test.sh; safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config python3 python3-matplotlib
  libmuparser-dev libcli11-dev nlohmann-json3-dev    # core: expressions, CLI, reports
  libxxhash-dev                                      # core: digests of split mesh files
  libpugixml-dev zlib1g-dev                          # core: VTK XML meshes (.vtu, .pvtu)
  libopenmpi-dev openmpi-bin                         # the MPI job
  libgtest-dev libgmock-dev libbenchmark-dev         # tests and benchmarks
  libcgal-dev libeigen3-dev                          # checker's self-intersections; CGAL's simplifier baseline
  libmeshoptimizer-dev                               # reduction baseline
  tetgen libmetis-dev                                # meshes/make_meshes.sh; splitting them into domains
  clang                                              # libFuzzer targets of the readers (tools/fuzz.sh)
  python3-dolfinx python3-gmsh gmsh                  # the worked example (FEniCSx solver) and meshes/solver fixtures
  python3-dev pybind11-dev python3-numpy python3-mpi4py python3-pytest  # import tetiso (python/) and its tests
  paraview python3-paraview                          # the ParaView plugin's test (pvbatch, no display)
)
# Optional baselines, built and tested only where installed (their tests are
# the `reference` label): libvtk9-dev (extraction) and libopenmesh-dev
# (reduction); both pull in a graphics stack that the suite does not need.
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release ${TETISO_CMAKE_ARGS:-}
cmake --build build -j "$(nproc)"
