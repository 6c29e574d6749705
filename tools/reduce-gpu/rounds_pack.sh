#!/usr/bin/env bash
# rounds_pack.sh FOLDER: packs main's GPU programs (/work/main/build, main's
# HEAD) and gpuround's (/work/wt/gpuround/build) into FOLDER/main.tar.xz and
# FOLDER/new.tar.xz, with the Debian libraries the device lacks, and the
# device's script (rounds.sh as run.sh, waits.py). FOLDER: .carry/gpuround of
# the checkout that travels.
set -e
tools=$(cd "$(dirname "$0")" && pwd)
here=${1:?folder to pack into}
mkdir -p "$here"; here=$(cd "$here" && pwd)
pack() { # NAME BUILD PROGRAM...
  local name=$1 build=$2; shift 2
  local tmp; tmp=$(mktemp -d); mkdir -p $tmp/bin $tmp/lib
  for p in "$@"; do find "$build" -path "*/package" -prune -o -name "$p" -type f -perm -u+x -exec cp {} $tmp/bin/ \; ; done
  for p in $tmp/bin/*; do ldd $p; done | awk '{print $3}' | sort -u |
    grep -E 'libmuparser|libmetis|libmeshoptimizer|libbenchmark|libmpi_cxx|libGKlib|libpugixml' |
    while read -r lib; do cp -L "$lib" $tmp/lib/; done
  strip $tmp/bin/*
  tar -C $tmp -cJf "$here/$name.tar.xz" bin lib
  rm -rf $tmp; du -sh "$here/$name.tar.xz"
}
pack main /work/main/build tetiso bench_reduce_gpu bench_gpu_streams
pack new /work/wt/gpuround/build tetiso bench_reduce_gpu bench_gpu_streams test_reduce_gpu test_gpu_pipeline test_extract_gpu test_exec_gpu
cp "$tools/waits.py" "$here/"
cp "$tools/rounds.sh" "$here/run.sh"
