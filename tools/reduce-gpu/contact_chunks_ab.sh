#!/usr/bin/env bash
# The contact test's entries in chunks, base against new, one H200, lean:
# test_gpu_pipeline and a part of test_reduce_gpu (new), the N = 100
# reduction (cmp base, new, CPU), one batch run and one profile each, the
# N = 1000/1000 and N = 500/125 jobs once each (cmp). Writes $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/cc; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt
[ -d /work/wt/meshes ] || { mkdir -p /work/wt; ln -sfn $repo/meshes /work/wt/meshes; }
t0=$SECONDS
timeout 40 $w/new/bin/test_gpu_pipeline --gtest_brief=1 > out/test_gpu_pipeline.log 2>&1; echo "pipeline rc=$? $(grep -E '^\[  (PASSED|FAILED)' out/test_gpu_pipeline.log | tr '\n' ' ')"
timeout 60 $w/new/bin/test_reduce_gpu --gtest_brief=1 --gtest_filter='ReduceBatch.*:Surfaces/*:Reduce.SurfaceThroughMeshNodesIsCleanedUp:Reduce.ClustersWithinFloatResolutionOfAMeshNodeAreCleanedUp' > out/test_reduce_gpu.log 2>&1; echo "reduce rc=$? $(grep -E '^\[  (PASSED|FAILED)' out/test_reduce_gpu.log | tr '\n' ' ')"
echo "[$((SECONDS-t0)) s]"
$w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply >/dev/null 2>&1
$w/new/bin/tetiso reduce p100.ply -o r100_cpu.ply --max-error 0.0126262626 --threads 0 >/dev/null 2>&1
for b in base new; do $w/$b/bin/tetiso reduce p100.ply -o r100_$b.ply --device gpu --max-error 0.0126262626 --report out/n100_$b.json >/dev/null 2>&1; done
cmp r100_base.ply r100_new.ply && cmp r100_cpu.ply r100_new.ply && echo "same bytes: N=100 base, new, cpu"
for b in base new; do timeout 40 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=32 --no-cpu > out/streams_$b.txt 2>&1; grep -E "gpu/streams" out/streams_$b.txt | cut -c1-120; done
for b in base new; do TETISO_GPU_PROFILE=1 timeout 40 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> out/prof32_$b.txt; done
grep -E "s in primitives" out/prof32_*.txt
echo "[$((SECONDS-t0)) s] jobs"
job() { local name=n$2_d$3_$1 s=$SECONDS
  timeout 60 mpirun --bind-to core -np $(nproc) $w/$1/bin/tetiso run --lattice $2 --domains $3 --device auto --quiet -o $w/$name.vtp --report out/$name.json >/dev/null 2>out/err_$name.txt
  echo "$name rc=$? $(python3 -c "import json; d=json.load(open('out/$name.json')); print('total %.2f' % d['seconds']['total'])" 2>&1)"; }
for b in base new; do job $b 1000 1000; done; cmp n1000_d1000_base.vtp n1000_d1000_new.vtp && echo "same bytes: N=1000"
for b in base new; do job $b 500 125; done; cmp n500_d125_base.vtp n500_d125_new.vtp && echo "same bytes: N=500"
echo "[$((SECONDS-t0)) s] done"
cd out && gzip -f n*_d*.json; tar -czf $OUT/all.tar.gz .
