#!/usr/bin/env bash
# On the device: dev.sh MODE NAME...   MODE: test (gpu tests of NAME first), bench, prof
# For each NAME: unpack NAME.tar.xz, time the N=100 reduction (3 runs, rounds report),
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# args: NAME:MODES ... (modes: test bench benchfull knob cpu prof meta=COMMIT)
export OMP_WAIT_POLICY=passive
nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader
nproc; date -u
for arg in "$@"; do
  name=${arg%%:*}; d=/tmp/$name; mkdir -p $d; tar -C $d -xJf $here/$name.tar.xz
done
first=${1%%:*}
export LD_LIBRARY_PATH=/tmp/$first/lib
/tmp/$first/bin/tetiso extract --lattice 100 --threads 0 -o /tmp/p100.ply >/dev/null || exit 1
red="reduce /tmp/p100.ply --device gpu --max-error 0.0126262626"
fixed() { python3 - "$1" <<'PY'
import json,sys,statistics as st
d=json.load(open(sys.argv[1])); r=d['rounds']
small=[x['seconds'] for x in r if x['candidates']<5000]
print(f"rounds {len(r)} total_s {d['total_seconds']:.4f} sum_round_s {sum(x['seconds'] for x in r):.4f} fixed_ms(median of {len(small)} rounds <5000 cand) {1e3*st.median(small) if small else float('nan'):.3f} tri_out {d['triangles_out']}")
PY
}
for arg in "$@"; do
  name=${arg%%:*}; modes=${arg#*:}
  b=/tmp/$name/bin; export LD_LIBRARY_PATH=/tmp/$name/lib
  echo "=== $name"
  if [[ $modes == *test* ]]; then
    # test_gpu_pipeline reads the meshes from the worktree it was built in
    [ -d /work/wt/gpu/meshes ] || { mkdir -p /work/wt/gpu; ln -sfn "$(cd $here/../.. && pwd)/meshes" /work/wt/gpu/meshes; }
    for t in test_reduce_gpu test_gpu_pipeline; do
      [ -x $b/$t ] || continue
      s=$SECONDS
      if timeout 300 $b/$t --gtest_brief=1 > /tmp/$name-$t.log 2>&1; then echo "$t: passed ($((SECONDS-s)) s)"
      else echo "$t: FAILED"; grep -E "Failure|differ|error|FAILED|Expected|Which is|CUDA" /tmp/$name-$t.log | head -30; cp /tmp/$name-$t.log $OUT/; fi
    done
  fi
  for i in 1 2 3; do
    $b/tetiso $red -o /tmp/r-$name.ply --report /tmp/$name-rounds$i.json >/dev/null || echo "reduce FAILED"
    echo -n "run $i: "; fixed /tmp/$name-rounds$i.json
  done
  cp /tmp/$name-rounds3.json $OUT/${name}_rounds_n100.json
  [ -f /tmp/r-$first.ply ] && cmp /tmp/r-$first.ply /tmp/r-$name.ply && echo "reduced surface cmp-identical to $first's"
  if [[ $modes == *knob* ]]; then
    for k in 1 2 4; do
      TETISO_GPU_TEST_BLOCKS_PER_SM=$k $b/tetiso $red -o /tmp/k.ply --report /tmp/k.json >/dev/null
      TETISO_GPU_TEST_BLOCKS_PER_SM=$k $b/tetiso $red -o /tmp/k.ply --report /tmp/k.json >/dev/null
      echo -n "blocks/SM $k: "; fixed /tmp/k.json; cmp /tmp/k.ply /tmp/r-$name.ply || echo "knob $k DIFFERS"
    done
  fi
  if [[ $modes == *cpu* ]]; then
    for i in 1 2 3; do
      $b/tetiso reduce /tmp/p100.ply --device cpu --threads 16 --max-error 0.0126262626 -o /tmp/c-$name.ply --report /tmp/c.json >/dev/null
      python3 -c "import json;d=json.load(open('/tmp/c.json'));print('cpu 16 threads total_s %.3f sum_round_s %.3f'%(d['total_seconds'],sum(r['seconds'] for r in d['rounds'])))"
    done
    cmp /tmp/c-$name.ply /tmp/r-$name.ply && echo "$name: GPU surface cmp-identical to CPU (16 threads)"
  fi
  if [[ $modes == *benchfull* ]]; then
    load_before=$(cut -d' ' -f1-3 /proc/loadavg)
    timeout 400 $b/bench_reduce_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
      --benchmark_out_format=json --benchmark_out=$OUT/${name}_bench_reduce_gpu.json > /tmp/$name-bench.log 2>&1 || echo "bench FAILED"
    grep -E "median|byte for byte|DIFFERS" /tmp/$name-bench.log
    commit=${modes##*meta=}
    python3 "$( [ -f $here/bench_meta.py ] && echo $here/bench_meta.py || echo $here/../bench_meta.py )" "$OUT/${name}_meta.json" \
        "bench_cmd=bench_reduce_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_out_format=json --benchmark_out=OUT/bench_reduce_gpu.json" \
        "reduce_cmd=tetiso reduce /tmp/tetiso-p100.ply -o /tmp/tetiso-r100.ply --device gpu --max-error 0.0126262626 --report OUT/rounds_n100.json" \
        "script_cmd=tools/reduce-gpu/dev.sh $commit" "commit=$commit" \
        "source_state=Release build for sm_90 of commit $commit built on Debian 12 (g++ 12, nvcc 13.0) in build/, Release, -DCMAKE_CUDA_ARCHITECTURES=90" \
        "gpu=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader)" \
        "environment=OMP_WAIT_POLICY=passive" "load_before=$load_before" "load_after=$(cut -d' ' -f1-3 /proc/loadavg)" || echo "meta FAILED"
  elif [[ $modes == *bench* ]]; then
    timeout 300 $b/bench_reduce_gpu --benchmark_filter='gpu' --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
      --benchmark_out_format=json --benchmark_out=$OUT/${name}_bench_reduce_gpu.json > /tmp/$name-bench.log 2>&1 || echo "bench FAILED"
    grep -E "median|byte for byte|DIFFERS" /tmp/$name-bench.log
  fi
  if [[ $modes == *timeline* ]]; then
    timeout 300 ncu --csv --print-units base --kernel-name-base demangled ${NCU_TL_FLAGS:-} --metrics gpu__time_duration.sum \
      $b/tetiso $red -o /tmp/x.ply > /tmp/$name-tl.csv 2>/tmp/$name-tl.err || { echo "timeline FAILED"; tail -3 /tmp/$name-tl.err; }
    python3 $here/timeline.py /tmp/$name-tl.csv > $OUT/${name}_timeline.txt 2>&1; tail -8 $OUT/${name}_timeline.txt
  fi
  if [[ $modes == *prof* ]]; then
    TETISO_GPU_PROFILE=1 $b/tetiso $red -o /tmp/x.ply 2> $OUT/${name}_profile_n100.txt >/dev/null
    timeout 200 ncu --kernel-name-base demangled --kernel-name regex:"${NCU_REGEX:-dry_run_all}" --launch-count ${NCU_COUNT:-6} --section WarpStateStats --section LaunchStats --section Occupancy \
      --metrics smsp__thread_inst_executed_per_inst_executed.ratio,l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum,gpu__time_duration.sum,dram__bytes.sum \
      $b/tetiso $red -o /tmp/x.ply > $OUT/${name}_ncu.txt 2>&1 || echo "ncu FAILED"
    grep -E "for_each|thread_inst_executed_per|local_op|Duration|gpu__time|Stall Long|Warp Cycles Per Issued" $OUT/${name}_ncu.txt | head -30
  fi
done
date -u
