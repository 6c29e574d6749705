#!/usr/bin/env bash
# results/gpu-streams/: the lattice job's domain tasks on K CUDA Devices of
# one GPU (bench/bench_gpu_streams.cpp), for the lent device machines, which
# have no package registry. Two steps:
#
#   tools/gpu_streams.sh prepare DEST [BEFORE]
#                 here, after `ninja -C build bench_gpu_streams` (build/
#                 configured as the project's builds are): the program, the
#                 shared libraries the device machine lacks and this script
#                 into DEST/gpu_streams.tar.xz; BEFORE, another build of the
#                 program to measure beside it (as bench_gpu_streams.before)
#   tools/gpu_streams.sh run DEST OUT COMMIT
#                 there: the benchmark at N = 1000 in 1000 domains (64 of
#                 them, spread), K = 1, 2, 4, 8, 16 and the CPU on every core;
#                 the BEFORE build at K = 1, 8, 16; then a profile of K = 8
#                 (nsys where the machine has it, Nsight Compute otherwise).
#                 Everything under OUT, with the command, machine, commit and
#                 date in OUT/run.json.
set -uo pipefail
programs=(bench_gpu_streams)

prepare() {
    set -e
    local dest=$1 before=${2:-} root stage
    root=$(cd "$(dirname "$0")/.." && pwd)
    stage=$(mktemp -d)
    mkdir -p "$stage/bin" "$stage/lib" "$dest"
    cp "$root/build/bench/bench_gpu_streams" "$stage/bin/"
    [ -n "$before" ] && cp "$before" "$stage/bin/bench_gpu_streams.before"
    ldd "$stage/bin/bench_gpu_streams" | awk '{print $3}' | grep -E 'libmuparser|libpugixml' |
        while read -r lib; do cp -L "$lib" "$stage/lib/"; done
    strip "$stage"/bin/*
    cp "$root/tools/gpu_streams.sh" "$root/tools/nsys_concurrency.py" "$stage/"
    tar -C "$stage" -cJf "$dest/gpu_streams.tar.xz" .
    rm -rf "$stage"
    du -sh "$dest/gpu_streams.tar.xz"
}

run() {
    local dest=$1 out=$2 commit=$3 work
    work=$(mktemp -d)
    tar -C "$work" -xJf "$dest/gpu_streams.tar.xz"
    mkdir -p "$out"
    export LD_LIBRARY_PATH=$work/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export OMP_WAIT_POLICY=passive
    local bin=$work/bin args=(--lattice=1000 --domains=1000 --count=64 --pick=spread)
    local machine
    machine=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader | head -1)
    printf '{"command":"%s","machine":"%s, %s cores","commit":"%s","date":"%s"}\n' \
        "bench_gpu_streams ${args[*]} --json=gpu_streams.json" "$machine" "$(nproc)" "$commit" \
        "$(date -u +%FT%TZ)" >"$out/run.json"
    cat "$out/run.json"

    timeout 240 "$bin/bench_gpu_streams" "${args[@]}" --cpu-threads="$(nproc)" --json="$out/gpu_streams.json" \
        2>&1 | tee "$out/gpu_streams.log"
    echo "bench_gpu_streams: exit ${PIPESTATUS[0]}"
    if [ -x "$bin/bench_gpu_streams.before" ]; then
        timeout 120 "$bin/bench_gpu_streams.before" "${args[@]}" --streams=1,8,16 --no-cpu \
            --json="$out/gpu_streams_before.json" 2>&1 | tee "$out/gpu_streams_before.log"
        echo "bench_gpu_streams.before: exit ${PIPESTATUS[0]}"
    fi

    # What bounds K = 8: the device's busy time and kernel concurrency over
    # the warm pass, from a trace of every kernel.
    if command -v nsys >/dev/null; then
        local rep=$work/k8
        timeout 150 nsys profile -t cuda -s none --cpuctxsw=none -o "$rep" -f true \
            "$bin/bench_gpu_streams" --lattice=1000 --domains=1000 --count=32 --streams=8 --no-cpu \
            >"$out/nsys_k8.log" 2>&1
        echo "nsys profile: exit $?"
        timeout 90 nsys stats -r cuda_gpu_kern_sum,cuda_api_sum,cuda_gpu_mem_time_sum -f csv -o "$out/nsys_k8" \
            "$rep.nsys-rep" >>"$out/nsys_k8.log" 2>&1
        timeout 60 python3 "$work/nsys_concurrency.py" "$rep.sqlite" | tee "$out/nsys_k8_concurrency.txt"
    else
        echo "no nsys on this machine" | tee "$out/nsys_k8.log"
    fi
    if command -v ncu >/dev/null; then
        # A sample of one warm domain's kernels, one stream (ncu runs
        # kernels one at a time): their occupancy and size.
        timeout 120 ncu --launch-skip 2500 --launch-count 120 --section Occupancy --section LaunchStats \
            --section SpeedOfLight --csv "$bin/bench_gpu_streams" --lattice=1000 --domains=1000 --count=2 \
            --streams=1 --no-cpu >"$out/ncu_sample.csv" 2>"$out/ncu_sample.log"
        echo "ncu: exit $?"
    fi
    rm -rf "$work"
}

case "${1:-}" in
prepare) shift; prepare "$@" ;;
run) shift; run "$@" ;;
*) echo "usage: tools/gpu_streams.sh prepare DEST [BEFORE] | run DEST OUT COMMIT" >&2; exit 2 ;;
esac
