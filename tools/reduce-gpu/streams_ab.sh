#!/usr/bin/env bash
# A GPU grant's domains on several streams of its driver, base against new,
# one H200: test_gpu_pipeline and ReduceBatch.* (new); bench_gpu_streams' two
# streams pinned to one core with each way of waiting (TETISO_GPU_WAIT), one
# stream free with two; the N = 1000/1000 job with --device auto (base; new
# with 2, 4, 3 streams) and N = 500/125 (base; new), surfaces compared by cmp.
# base.tar.xz and new.tar.xz (pack.sh) beside this script; run from the
# repository root on the device machine. Writes $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/ln; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt
[ -d /work/wt/meshes ] || { mkdir -p /work/wt; ln -sfn $repo/meshes /work/wt/meshes; }
t0=$SECONDS
timeout 90 new/bin/test_gpu_pipeline --gtest_brief=1 > out/test_gpu_pipeline.log 2>&1; echo "pipeline rc=$? $(grep -E '^\[  (PASSED|FAILED)' out/test_gpu_pipeline.log | tr '\n' ' ')"
timeout 90 new/bin/test_reduce_gpu --gtest_brief=1 --gtest_filter='ReduceBatch.*' > out/test_reduce_gpu.log 2>&1; echo "reduce rc=$? $(grep -E '^\[  (PASSED|FAILED)' out/test_reduce_gpu.log | tr '\n' ' ')"
echo "[$((SECONDS-t0)) s] waits"
B="new/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=128 --pick=first --no-cpu"
for m in spin yield blocking; do TETISO_GPU_WAIT=$m timeout 60 taskset -c 0 $B --streams=2 --batches=32 2> out/wait_core1_$m.txt >/dev/null; echo "one core, $m: $(grep gpu/streams out/wait_core1_$m.txt | cut -c19-100)"; done
for m in spin yield; do TETISO_GPU_WAIT=$m timeout 60 $B --streams=1 --batches=32 2> out/wait_free_$m.txt >/dev/null; echo "free, $m: $(grep gpu/streams out/wait_free_$m.txt | cut -c19-100)"; done
echo "[$((SECONDS-t0)) s] jobs"
job() { local b=$1 name=$2 n=$3 d=$4; shift 4
  timeout 80 mpirun --bind-to core -np $(nproc) $w/$b/bin/tetiso run --lattice $n --domains $d --device auto --quiet -o $w/$name.vtp --report out/$name.json "$@" >/dev/null 2>out/err_$name.txt
  echo "$name rc=$? $(python3 -c "
import json; d=json.load(open('out/$name.json')); t=d['tasks']
dom=[x for x in t if x['kind']=='domain']; g=[x for x in dom if x['device']!='cpu']
print('total %.2f last domain %.2f gpu domains %d gpu busy %.1f' % (d['seconds']['total'], max(x['end'] for x in dom), len(g), sum(x['end']-x['start'] for x in g)))" 2>&1)"; }
job base n1000_base 1000 1000
job new n1000_s2 1000 1000
job new n1000_s4 1000 1000 --gpu-streams 4
job new n1000_s3 1000 1000 --gpu-streams 3
for x in s2 s4 s3; do cmp n1000_base.vtp n1000_$x.vtp && echo "same bytes: N=1000 base, $x"; done
job base n500_base 500 125
job new n500_s2 500 125
cmp n500_base.vtp n500_s2.vtp && echo "same bytes: N=500"
echo "[$((SECONDS-t0)) s] done"
cd out && gzip -f n*.json; tar -czf $OUT/all.tar.gz .
