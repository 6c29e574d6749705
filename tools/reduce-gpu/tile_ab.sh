#!/usr/bin/env bash
# The dry runs' geometric tests by tiles of threads (results/reduce-gpu/
# legality-tiles) on one GPU: the GPU tests of the first new pack, then base
# against each new pack, interleaved: the N = 100 reduction twice each (cmp
# with each other and the CPU), bench_gpu_streams in batches of 32 twice each,
# the first against the CPU's pieces (and once under TETISO_GPU_PROFILE, base and the first new pack), Nsight
# Compute of the dry runs' second stage in the first rounds of a batch, and
# the N = 500/125 job (and with BIG=1 the N = 1000/1000 job) with --device
# auto on every core, base against the first new pack. Packs made by
# tools/reduce-gpu/pack.sh beside this script (NCU_FOR: the packs profiled,
# by default base and the first new one): base.tar.xz and NAME.tar.xz
# for each NAME of $NEW (tetiso, bench_gpu_streams; the first also
# test_exec_gpu, test_reduce_gpu, test_gpu_pipeline); run from the checkout's root. Writes
# $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/tile; mkdir -p $w/out; cd $w
NEW=${NEW:-t16 t32}; first=${NEW%% *}
for b in base $NEW; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/$first/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
O=$OUT; { nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $O/machine.txt; cat $O/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
t0=$SECONDS
if [ "${TESTS:-1}" = 1 ]; then
  for t in test_exec_gpu test_reduce_gpu test_gpu_pipeline; do s=$SECONDS; timeout 200 $w/$first/bin/$t --gtest_brief=1 > $w/out/$t.log 2>&1; echo "$t rc=$? $((SECONDS-s)) s: $(grep -E '^\[  (PASSED|FAILED)' $w/out/$t.log | tr '\n' ' ')"; grep -E "^\[  FAILED" $w/out/$t.log | head; done
  s=$SECONDS; timeout 150 $repo/validation/cli/test_gpu_cli.sh $w/$first/bin/tetiso "$(command -v mpirun)" > $w/out/test_gpu_cli.log 2>&1
  echo "test_gpu_cli.sh rc=$? $((SECONDS-s)) s: $(tail -1 $w/out/test_gpu_cli.log)"
fi
$w/$first/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply >/dev/null 2>&1
$w/$first/bin/tetiso reduce p100.ply -o r100_cpu.ply --max-error 0.0126262626 --threads 0 >/dev/null 2>&1
for r in 1 2; do for b in base $NEW; do
  $w/$b/bin/tetiso reduce p100.ply -o r100_$b.ply --device gpu --max-error 0.0126262626 --report $w/out/n100_${b}_$r.json >/dev/null 2>&1
  python3 -c "import json; d=json.load(open('$w/out/n100_${b}_$r.json')); st=d['stage_seconds']; print('n100 $b $r', 'rounds', len(d['rounds']), 'tris', d['triangles_out'], 'stages %.4f select %.4f' % (sum(st.values()), st['select']))"
  cmp r100_cpu.ply r100_$b.ply && echo "same bytes: N=100 $b cpu"
done; done
echo "[$((SECONDS-t0)) s] streams"
for r in 1 2; do for b in base $NEW; do
  # The first run also on the cores: every GPU piece against the CPU's.
  cpu=--no-cpu; [ $r = 1 ] && cpu=--cpu-threads=$(nproc)
  timeout 90 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=32 $cpu > $w/out/streams_${b}_$r.txt 2>&1; echo "rc=$?" >> $w/out/streams_${b}_$r.txt; grep -E "gpu/|cpu/|byte for byte|rc=" $w/out/streams_${b}_$r.txt | head -5 | sed "s/^/$b $r /"
done; done
for b in base $first; do
  TETISO_GPU_PROFILE=1 timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $w/out/prof32_$b.txt
done
grep -E "s in primitives" $w/out/prof32_*.txt
echo "[$((SECONDS-t0)) s] ncu"
NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
for b in ${NCU_FOR-base $first}; do
  # base: the second stage is the dry runs' for_each_of_heavy_kernel; new: for_each_of_tiled_kernel.
  k='regex:for_each_of_tiled_kernel|for_each_of_heavy_kernel.*dry_run_all'
  timeout 150 $NCU --clock-control none --kernel-name-base mangled --kernel-name "$k" --launch-skip 0 --launch-count 6 \
    --section LaunchStats --section Occupancy --section SpeedOfLight --section WarpStateStats --section SchedulerStats --section MemoryWorkloadAnalysis --section SourceCounters \
    --metrics smsp__thread_inst_executed_per_inst_executed.ratio,l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum,smsp__pcsamp_warps_issue_stalled_long_scoreboard,smsp__pcsamp_warps_issue_stalled_lg_throttle \
    $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > $w/out/ncu_$b.txt 2>&1; echo "ncu $b rc=$?"
  grep -E "Duration|Registers Per|Achieved Occupancy|Local Memory|thread_inst_executed_per|local_op|Warp Cycles Per Issued|Avg. Active Threads" $w/out/ncu_$b.txt | head -24
done
echo "[$((SECONDS-t0)) s] jobs"
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-120} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
if [ $((SECONDS-t0)) -lt 380 ]; then for b in base $first; do job $b 500 125 1; done
  cmp $w/n500_d125_base_1.vtp $w/n500_d125_${first}_1.vtp && echo "same bytes: N=500 jobs"; fi
if [ "${BIG:-0}" = 1 ] && [ $((SECONDS-t0)) -lt 420 ]; then for b in base $first; do job $b 1000 1000 1; done
  cmp $w/n1000_d1000_base_1.vtp $w/n1000_d1000_${first}_1.vtp && echo "same bytes: N=1000 jobs"; fi
echo "[$((SECONDS-t0)) s] done"
cd $w/out && tar -czf $O/all.tar.gz . ; ls $O
