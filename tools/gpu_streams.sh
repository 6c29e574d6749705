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
#   tools/gpu_streams.sh batch DEST OUT COMMIT
#                 there: results/reduce-batch/: the GPU tests of the
#                 reduction and the domain pipeline (batched == alone), the
#                 benchmark at N = 1000 in 1000 domains (64 of them, spread)
#                 with batches of B = 1, 4, 16, 64 domains on K = 1 and 4
#                 streams and the CPU on every core, then an nsys trace and
#                 an Nsight Compute sample of the best B on one stream.
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
    for t in test_reduce_gpu test_gpu_pipeline; do
        [ -x "$root/build/validation/$t" ] && cp "$root/build/validation/$t" "$stage/bin/"
    done
    # The importer of the device machines' nsys needs these and finds none there.
    mkdir -p "$stage/dwlib"
    for lib in libdw.so.1 libelf.so.1 libbz2.so.1.0; do
        cp -L "/usr/lib/x86_64-linux-gnu/$lib" "$stage/dwlib/" 2>/dev/null || true
    done
    [ -n "$before" ] && cp "$before" "$stage/bin/bench_gpu_streams.before"
    for p in "$stage"/bin/*; do ldd "$p"; done | awk '{print $3}' | sort -u |
        grep -E 'libmuparser|libpugixml|libmetis|libGKlib|libmpi_cxx' |
        while read -r lib; do cp -L "$lib" "$stage/lib/"; done
    strip "$stage"/bin/*
    cp "$root/tools/gpu_streams.sh" "$root/tools/nsys_concurrency.py" "$stage/"
    tar -C "$stage" -cJf "$dest/gpu_streams.tar.xz" .
    rm -rf "$stage"
    du -sh "$dest/gpu_streams.tar.xz"
}

# The packed programs unpacked into a new folder, named in $work, and the
# environment they run in.
unpack() {
    work=$(mktemp -d)
    tar -C "$work" -xJf "$1/gpu_streams.tar.xz"
    export LD_LIBRARY_PATH=$work/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export OMP_WAIT_POLICY=passive
}

run() {
    local dest=$1 out=$2 commit=$3 work
    unpack "$dest"
    mkdir -p "$out"
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

batch() {
    local dest=$1 out=$2 commit=$3 work
    unpack "$dest"
    mkdir -p "$out/raw"
    local bin=$work/bin args=(--lattice=1000 --domains=1000 --count=64 --pick=spread --streams=1,4 --batches=1,4,16,64)
    local machine
    machine=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader | head -1)
    printf '{"command":"%s","machine":"%s, %s cores","commit":"%s","date":"%s"}\n' \
        "bench_gpu_streams ${args[*]} --json=reduce_batch.json" "$machine" "$(nproc)" "$commit" \
        "$(date -u +%FT%TZ)" >"$out/run.json"
    cat "$out/run.json"
    for t in test_reduce_gpu test_gpu_pipeline; do
        local start=$SECONDS
        if timeout 100 "$bin/$t" --gtest_brief=1 >"$out/raw/$t.log" 2>&1; then echo "$t: passed ($((SECONDS - start)) s)"
        else
            echo "$t: FAILED ($((SECONDS - start)) s)"
            grep -E "Failure|differ|error|FAILED|Expected|Which is" "$out/raw/$t.log" | head -30
        fi
    done
    timeout 170 "$bin/bench_gpu_streams" "${args[@]}" --cpu-threads="$(nproc)" --json="$out/reduce_batch.json" \
        2>&1 | tee "$out/reduce_batch.log"
    echo "bench_gpu_streams: exit ${PIPESTATUS[0]}"
    local best
    best=$(python3 -c "import json,sys; r=[x for x in json.load(open(sys.argv[1]))['rows'] if x['streams']==1]; \
print(max(r, key=lambda x: x['raw_triangles_per_s'])['batch'])" "$out/reduce_batch.json" 2>/dev/null || echo 64)
    echo "profiling B = $best on one stream"
    local nsys
    nsys=$(command -v nsys || ls /opt/nvidia/nsight-compute/*/host/target-linux-x64/nsys 2>/dev/null | head -1)
    if [ -n "$nsys" ]; then
        local rep=/tmp/batch_b$best prof=(--lattice=1000 --domains=1000 --count=64 --streams=1 --batches="$best" --no-cpu)
        timeout 70 "$nsys" profile -t cuda -s none --cpuctxsw=none --gpu-metrics-devices=0 \
            --gpu-metrics-frequency=10000 -o "$rep" -f true "$bin/bench_gpu_streams" "${prof[@]}" \
            >"$out/raw/nsys.log" 2>&1 ||
            timeout 70 "$nsys" profile -t cuda -s none --cpuctxsw=none -o "$rep" -f true \
                "$bin/bench_gpu_streams" "${prof[@]}" >>"$out/raw/nsys.log" 2>&1
        local importer
        importer=$(find / -name QdstrmImporter -type f 2>/dev/null | head -1)
        if [ ! -f "$rep.nsys-rep" ] && [ -n "$importer" ]; then
            LD_LIBRARY_PATH=$work/dwlib:$LD_LIBRARY_PATH timeout 90 "$importer" -i "$rep.qdstrm" >>"$out/raw/nsys.log" 2>&1
        fi
        timeout 60 "$nsys" export --type sqlite -o "$rep.sqlite" -f true "$rep.nsys-rep" >>"$out/raw/nsys.log" 2>&1
        timeout 60 "$nsys" stats -r cuda_gpu_kern_sum,cuda_api_sum -f csv -o "$out/raw/nsys" "$rep.sqlite" \
            >>"$out/raw/nsys.log" 2>&1
        timeout 60 python3 "$work/nsys_concurrency.py" "$rep.sqlite" | tee "$out/raw/nsys_concurrency.txt"
    else
        echo "no nsys on this machine" | tee "$out/raw/nsys.log"
    fi
    if command -v ncu >/dev/null; then
        # The kernels of one batch's rounds, one at a time: their size, occupancy and throughput.
        timeout 60 ncu --launch-skip 3000 --launch-count 150 --section Occupancy --section LaunchStats \
            --section SpeedOfLight --csv "$bin/bench_gpu_streams" --lattice=1000 --domains=1000 --count="$best" \
            --streams=1 --batches="$best" --no-cpu >"$out/raw/ncu_sample.csv" 2>"$out/raw/ncu_sample.log"
        echo "ncu: exit $?"
    fi
    rm -rf "$work"
}

case "${1:-}" in
prepare) shift; prepare "$@" ;;
run) shift; run "$@" ;;
batch) shift; batch "$@" ;;
*) echo "usage: tools/gpu_streams.sh prepare DEST [BEFORE] | run DEST OUT COMMIT | batch DEST OUT COMMIT" >&2; exit 2 ;;
esac
