#!/usr/bin/env bash
# The GPU checks and timings, for a machine with a CUDA GPU but no package
# registry (the lent device machines: Ubuntu 24.04, CUDA 13, Open MPI, no
# muparser, METIS, meshoptimizer or Debian's Google Benchmark). Two steps:
#
#   tools/gpu_check.sh prepare      here (Debian 12, nvcc): build Release for
#                                     sm_90 in build-gpu/ and gather the GPU
#                                     test programs, bench_reduce_gpu, tetiso
#                                     and the shared libraries the device
#                                     lacks into .carry/gpu.tar.xz (carry
#                                     .carry; TETISO_CARRY=DIR packs into DIR
#                                     instead, e.g. the main checkout's
#                                     .carry/NAME from a worktree)
#   tools/gpu_check.sh run OUT [quick]
#                                     there: every gpu-labelled test (the CPU
#                                     reduction suite run on the GPU too, the
#                                     domain pipeline, the extraction, the
#                                     command line with cmp), then
#                                     bench_reduce_gpu; logs and the benchmark's
#                                     JSON under OUT. quick: the tests only.
#   tools/gpu_check.sh bench OUT [COMMIT]
#                                     there: the tests, then what
#                                     results/reduce-gpu/ is made from (see
#                                     bench() below), under OUT
#   tools/gpu_check.sh jobs OUT COMMIT DEADLINE_S N:D...
#                                     there: the jobs of
#                                     results/hardware-comparison/README.md (see
#                                     jobs() below), under OUT; GPU_COUNTS="1 2
#                                     4" (the default) says on how many of the
#                                     machine's GPUs; CHECK=1 also writes
#                                     `tetiso check --strict` of each case's
#                                     surface as OUT/check-nN-dD.json
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pack=${TETISO_CARRY:-$root/.carry}
carry=$pack/gpu
programs=(tetiso test_reduce_gpu test_gpu_pipeline test_extract_gpu bench_reduce_gpu)

prepare() {
    set -e
    cmake -S "$root" -B "$root/build-gpu" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
    # Ninja did not always see the CUDA units' headers change (their
    # dependencies were once recorded empty): what travels is rebuilt whole.
    touch "$root"/core/src/*.cu "$root"/core/src/reduce/*.cu
    ninja -C "$root/build-gpu" tetiso test_reduce_gpu test_gpu_pipeline test_extract_gpu bench_reduce_gpu
    rm -rf "$carry"
    mkdir -p "$carry/bin" "$carry/lib"
    for p in "${programs[@]}"; do
        find "$root/build-gpu/" -name "$p" -type f -perm -u+x -exec cp {} "$carry/bin/" \;
    done
    # Debian's libraries that the device has not (or not under this soname).
    for p in "${programs[@]}"; do ldd "$carry/bin/$p"; done | awk '{print $3}' | sort -u |
        grep -E 'libmuparser|libmetis|libmeshoptimizer|libbenchmark|libmpi_cxx|libGKlib|libpugixml' |
        while read -r lib; do cp -L "$lib" "$carry/lib/"; done
    # What travels to the device is limited in size: stripped and packed.
    strip "$carry"/bin/*
    tar -C "$carry" -cJf "$pack/gpu.tar.xz" bin lib
    rm -rf "$carry"
    du -sh "$pack/gpu.tar.xz"
}

run() {
    local out=$1 quick=${2:-}
    mkdir -p "$out"
    if [ ! -d "$carry/bin" ]; then
        mkdir -p "$carry"
        tar -C "$carry" -xJf "$pack/gpu.tar.xz"
    fi
    export LD_LIBRARY_PATH=$carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export OMP_WAIT_POLICY=passive
    local bin=$carry/bin failed=0
    nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader | tee "$out/machine.txt"
    nproc >>"$out/machine.txt"
    for t in test_extract_gpu test_gpu_pipeline test_reduce_gpu; do
        local start=$SECONDS
        if timeout 400 "$bin/$t" --gtest_brief=1 >"$out/$t.log" 2>&1; then
            echo "$t: passed ($((SECONDS - start)) s)"
        else
            echo "$t: FAILED ($((SECONDS - start)) s)"
            grep -E "Failure|differ|error|FAILED|Expected|Which is|CUDA" "$out/$t.log" | head -40
            failed=1
        fi
    done
    local start=$SECONDS
    if timeout 400 "$root/validation/cli/test_gpu_cli.sh" "$bin/tetiso" "$(command -v mpirun)" >"$out/cli.log" 2>&1; then
        echo "test_gpu_cli.sh: passed ($((SECONDS - start)) s)"
    else
        echo "test_gpu_cli.sh: FAILED"
        tail -20 "$out/cli.log"
        failed=1
    fi
    [ -n "$quick" ] && return $failed
    start=$SECONDS
    timeout 500 "$bin/bench_reduce_gpu" --benchmark_repetitions=5 --benchmark_out="$out/bench_reduce_gpu.json" \
        --benchmark_out_format=json >"$out/bench.log" 2>&1 || failed=1
    echo "bench_reduce_gpu: $((SECONDS - start)) s"
    grep -E "median|byte for byte|DIFFERS" "$out/bench.log"
    return $failed
}

# The measurements of results/reduce-gpu/, there: the whole benchmark (the
# GPU, one and every CPU thread, meshoptimizer, the domain task, the device's
# copy bandwidth), the N = 100 reduction's rounds and, apart, its time by
# call site (TETISO_GPU_PROFILE waits for the device around every primitive,
# so its seconds add up to more than the plain run's); then, here, OUT's
# files are copied into results/reduce-gpu/ and tools/render_results.py
# reduce-gpu writes the page.
bench() {
    local out=$1 commit=${2:-unknown}
    run "$out" quick || return 1
    local bin=$carry/bin
    local cmd=(bench_reduce_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
        --benchmark_out_format=json --benchmark_out="$out/bench_reduce_gpu.json")
    local load_before
    load_before=$(cut -d' ' -f1-3 /proc/loadavg)
    timeout 500 "$bin/${cmd[0]}" "${cmd[@]:1}" >"$out/bench.log" 2>&1 || return 1
    "$bin/tetiso" extract --lattice 100 --threads 0 -o /tmp/tetiso-p100.ply >/dev/null
    local reduce=(tetiso reduce /tmp/tetiso-p100.ply -o /tmp/tetiso-r100.ply --device gpu --max-error 0.0126262626
        --report "$out/rounds_n100.json")
    "$bin/${reduce[0]}" "${reduce[@]:1}" >/dev/null
    TETISO_GPU_PROFILE=1 "$bin/tetiso" "${reduce[@]:1:8}" --report /tmp/tetiso-profiled.json 2>"$out/profile_n100.txt" >/dev/null
    python3 "$root/tools/bench_meta.py" "$out/meta.json" \
        "bench_cmd=${cmd[*]}" "reduce_cmd=${reduce[*]}" "script_cmd=tools/gpu_check.sh bench OUT $commit" \
        "commit=$commit" "source_state=Release build for sm_90 of commit $commit, made by tools/gpu_check.sh prepare" \
        "gpu=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader)" \
        "environment=OMP_WAIT_POLICY=passive" "load_before=$load_before" "load_after=$(cut -d' ' -f1-3 /proc/loadavg)"
    grep -E "median|byte for byte|DIFFERS" "$out/bench.log"
}

# What results/hardware-comparison/README.md is made from, there: for each case
# N:D, the job `tetiso run --lattice N --domains D` on every core of the
# machine (one rank per core, rank 0 the controller), once with --device cpu
# and, on the first G GPUs for each G of GPU_COUNTS the machine has, once
# with --device gpu and once with --device auto; each with its report
# (n{N}-d{D}-cpu.json, n{N}-d{D}-{gpu,auto}-g{G}.json) and wall time, every
# surface compared with cmp against the CPU's (n{N}-d{D}-cmp.txt, a line per
# run). Cases run in the order given, and a job that could not end before
# DEADLINE_S seconds from the start (judged by the job before it, scaled by
# the number of nodes, N^3) is skipped, so the lent machine's time limit is
# never hit mid-job. Then, here, tools/collect_results.py hardware OUT takes
# them into results/hardware-comparison/ and renders its page.
jobs() {
    local out=$1 commit=$2 deadline=$3
    shift 3
    mkdir -p "$out"
    if [ ! -d "$carry/bin" ]; then
        mkdir -p "$carry"
        tar -C "$carry" -xJf "$pack/gpu.tar.xz"
    fi
    export LD_LIBRARY_PATH=$carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    local ranks available
    ranks=$(nproc)
    available=$(nvidia-smi -L | grep -c '^GPU')
    local started=$SECONDS last=0 last_n=1 failed=0
    local -a launch=(mpirun --bind-to core -np "$ranks" -x CUDA_VISIBLE_DEVICES)
    python3 "$root/tools/bench_meta.py" "$out/meta.json" \
        "script_cmd=tools/gpu_check.sh jobs OUT $commit $deadline $*" "commit=$commit" \
        "source_state=Release build for sm_90 of commit $commit, made by tools/gpu_check.sh prepare" \
        "gpu=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader | paste -sd';')" \
        "gpu_counts=${GPU_COUNTS:-1 2 4}" "launcher=${launch[*]}" "environment=OMP_WAIT_POLICY=passive" \
        "load_before=$(cut -d' ' -f1-3 /proc/loadavg)"
    for case in "$@"; do
        local n=${case%%:*} d=${case##*:}
        local -a modes=(cpu)
        for g in ${GPU_COUNTS:-1 2 4}; do
            [ "$g" -le "$available" ] && modes+=("gpu-g$g" "auto-g$g")
        done
        rm -f "$out/n$n-d$d-cmp.txt"
        for mode in "${modes[@]}"; do
            local name=n$n-d$d-$mode device=${mode%-g*} visible=""
            [ "$mode" != cpu ] && visible=$(seq -s, 0 $((${mode##*-g} - 1)))
            if [ $((SECONDS - started + last * n * n * n / (last_n * last_n * last_n))) -gt "$deadline" ]; then
                echo "$name: skipped (would pass the deadline)"
                continue
            fi
            local t0=$SECONDS
            CUDA_VISIBLE_DEVICES=$visible timeout $((deadline - (SECONDS - started))) "${launch[@]}" \
                "$carry/bin/tetiso" run --lattice "$n" --domains "$d" --device "$device" --quiet -o "/tmp/$name.vtp" \
                --report "$out/$name.json" >"$out/$name.log" 2>&1 || {
                echo "$name: FAILED"
                tail -5 "$out/$name.log"
                failed=1
                continue
            }
            last=$((SECONDS - t0)) last_n=$n
            echo "$name: ${last} s wall, $(python3 -c "import json, sys; s = json.load(open(sys.argv[1]))['seconds']; print('total %.2f s, job %.2f s' % (s['total'], s['job']))" "$out/$name.json")"
            if [ "$mode" != cpu ] && [ -e "/tmp/n$n-d$d-cpu.vtp" ]; then
                if cmp -s "/tmp/n$n-d$d-cpu.vtp" "/tmp/$name.vtp"; then
                    echo "$mode identical" >>"$out/n$n-d$d-cmp.txt"
                else
                    echo "$mode DIFFER" >>"$out/n$n-d$d-cmp.txt"
                    failed=1
                fi
                rm -f "/tmp/$name.vtp"
            fi
        done
        [ -e "$out/n$n-d$d-cmp.txt" ] && echo "n$n-d$d: against cpu: $(paste -sd' ' "$out/n$n-d$d-cmp.txt")"
        # The surface is the same bytes for any rank count and device: its
        # contract check stands for every run of this case (results/
        # paper-reproduction takes those of N = 500 as check-dD.json).
        if [ -n "${CHECK:-}" ] && [ -e "/tmp/n$n-d$d-cpu.vtp" ]; then
            local status=0
            "$carry/bin/tetiso" check --strict "/tmp/n$n-d$d-cpu.vtp" >"$out/check-n$n-d$d.json" 2>/dev/null || status=$?
            echo "n$n-d$d: check --strict exit $status$( ((status == 0)) && echo ' (clean)')"
        fi
        rm -f "/tmp/n$n-d$d-cpu.vtp"
    done
    return $failed
}

case ${1:-} in
prepare) prepare ;;
jobs) jobs "${2:?usage: gpu_check.sh jobs OUT COMMIT DEADLINE_S N:D...}" "${3:?}" "${4:?}" "${@:5}" ;;
run) run "${2:?usage: gpu_check.sh run OUT [quick]}" "${3:-}" ;;
bench) bench "${2:?usage: gpu_check.sh bench OUT [COMMIT]}" "${3:-}" ;;
*)
    echo "usage: tools/gpu_check.sh prepare | run OUT [quick] | bench OUT [COMMIT] | jobs OUT COMMIT DEADLINE_S N:D..." >&2
    exit 2
    ;;
esac
