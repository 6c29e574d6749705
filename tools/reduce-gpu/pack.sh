#!/usr/bin/env bash
# pack.sh NAME BUILD_DIR PROGRAM... : stripped binaries + the Debian libs the device lacks -> NAME.tar.xz
set -e
name=$1 build=$2; shift 2
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d); mkdir -p $tmp/bin $tmp/lib
for p in "$@"; do find "$build" -name "$p" -type f -perm -u+x -exec cp {} $tmp/bin/ \; ; done
for p in $tmp/bin/*; do ldd $p; done | awk '{print $3}' | sort -u |
  grep -E 'libmuparser|libmetis|libmeshoptimizer|libbenchmark|libmpi_cxx|libGKlib|libpugixml' |
  while read -r lib; do cp -L "$lib" $tmp/lib/; done
strip $tmp/bin/*
tar -C $tmp -cJf "$here/$name.tar.xz" bin lib
rm -rf $tmp
du -sh "$here/$name.tar.xz"
