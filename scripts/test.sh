#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (CTest; labels unit,
# topology, mpi, gpu (skipped without a CUDA device), reference), then runs it again in a second build with
# AddressSanitizer and UndefinedBehaviorSanitizer, where any report fails the
# test that made it. The optimised build is what users run; the sanitised one
# catches what does not throw (an out-of-bounds read on a damaged file, a
# float cast that overflows) but runs too slowly for timing. Last, each
# reader's fuzz target runs for 20 s (tools/fuzz.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 1200

# The baselines and benchmarks time and compare other libraries' code: they
# are left out here.
cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DTETISO_SANITIZE=address,undefined,float-cast-overflow -DTETISO_BENCH=OFF -DTETISO_REFERENCE=OFF
cmake --build build-sanitize -j "$(nproc)"
ctest --test-dir build-sanitize --output-on-failure -j "$(nproc)" --timeout 1200

# Every fuzz target (each reader, the reduction) for a short fixed time, after replaying the
# inputs that once failed (the recorded campaign is tools/fuzz_campaign.sh).
./tools/fuzz.sh --seconds 20
