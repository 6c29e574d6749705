#!/usr/bin/env bash
# The resource manager's remainders and extraction's scans (results/
# reduce-gpu/remainders) on one GPU, base against new, interleaved: the GPU
# tests of new (extraction, pipeline, test_gpu_cli.sh); the N = 1000/1000
# job with --device auto on every core twice each and the N = 500/125 job
# once each (cmp base against new); the batch profile of 32 domains
# (TETISO_GPU_PROFILE) and Nsight Compute of extraction's first scans, base
# and new; bench_gpu_streams in batches of 32 and of 64, new. Packs made by
# tools/reduce-gpu/pack.sh beside this script: base.tar.xz, new.tar.xz
# (tetiso, bench_gpu_streams, test_extract_gpu, test_gpu_pipeline). Run from
# the checkout's root; writes $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/rem; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
O=$OUT; { nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $O/machine.txt; cat $O/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
t0=$SECONDS
for t in test_extract_gpu test_gpu_pipeline; do s=$SECONDS; timeout 150 $w/new/bin/$t --gtest_brief=1 > $w/out/$t.log 2>&1; echo "$t rc=$? $((SECONDS-s)) s: $(grep -E '^\[  (PASSED|FAILED)' $w/out/$t.log | tr '\n' ' ')"; grep -E "^\[  FAILED" $w/out/$t.log | head; done
s=$SECONDS; timeout 150 $repo/validation/cli/test_gpu_cli.sh $w/new/bin/tetiso "$(command -v mpirun)" > $w/out/test_gpu_cli.log 2>&1
echo "test_gpu_cli.sh rc=$? $((SECONDS-s)) s: $(tail -1 $w/out/test_gpu_cli.log)"
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-100} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
echo "[$((SECONDS-t0)) s] jobs"
for b in base new; do job $b 1000 1000 1; done
cmp $w/n1000_d1000_base_1.vtp $w/n1000_d1000_new_1.vtp && echo "same bytes: N=1000 jobs"
for b in base new; do job $b 500 125 1; done
cmp $w/n500_d125_base_1.vtp $w/n500_d125_new_1.vtp && echo "same bytes: N=500 jobs"
echo "[$((SECONDS-t0)) s] profiles"
for b in base new; do
  TETISO_GPU_PROFILE=1 timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $w/out/prof32_$b.txt
done
grep -E "s in primitives|marching_tets" $w/out/prof32_*.txt
NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
for b in base new; do
  timeout 100 $NCU --clock-control none --kernel-name regex:DeviceScanKernel --launch-skip 0 --launch-count 2 \
    --section LaunchStats --section Occupancy --section SpeedOfLight --section WarpStateStats --section MemoryWorkloadAnalysis \
    --metrics l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum \
    $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=2 --pick=first --streams=1 --batches=2 --no-cpu > $w/out/ncu_scan_$b.txt 2>&1; echo "ncu $b rc=$?"
  grep -E "Duration|Registers Per|Local Memory|local_op|Memory Throughput|Grid Size|Block Size" $w/out/ncu_scan_$b.txt | head -16
done
echo "[$((SECONDS-t0)) s] streams"
timeout 90 $w/new/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=128 --pick=first --streams=1 --batches=32,64 --no-cpu > $w/out/streams_new.txt 2>&1; echo "rc=$?" >> $w/out/streams_new.txt; grep -E "gpu/|byte for byte|rc=" $w/out/streams_new.txt | head -6
if [ $((SECONDS-t0)) -lt 430 ]; then for b in base new; do job $b 1000 1000 2; done; fi
echo "[$((SECONDS-t0)) s] done"
cd $w/out && tar -czf $O/all.tar.gz . ; ls $O
