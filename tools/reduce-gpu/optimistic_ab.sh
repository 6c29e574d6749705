#!/usr/bin/env bash
# Optimistic placement on one GPU (results/reduce-gpu/optimistic-placement):
# the GPU tests, then base against new, interleaved: the N = 100 reduction
# three times each (cmp with each other and the CPU), bench_gpu_streams in
# batches of 32 twice each (and once each under TETISO_GPU_PROFILE), the
# N = 500/125 job twice each and the N = 1000/1000 job once each with
# --device auto on every core. Packs made by tools/reduce-gpu/pack.sh beside
# this script: base.tar.xz (tetiso, bench_gpu_streams) and new.tar.xz (also
# test_reduce_gpu, test_gpu_pipeline); run from the checkout's root. Writes
# $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/opt; mkdir -p $w/base $w/new $w/out; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
O=$OUT; { nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $O/machine.txt; cat $O/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
t0=$SECONDS
if [ "${TESTS:-1}" = 1 ]; then
  for t in test_reduce_gpu test_gpu_pipeline; do s=$SECONDS; timeout 200 $w/new/bin/$t --gtest_brief=1 > $O/$t.log 2>&1; echo "$t rc=$? $((SECONDS-s)) s: $(grep -E '^\[  (PASSED|FAILED)' $O/$t.log | tr '\n' ' ')"; grep -E "^\[  FAILED" $O/$t.log | head; done
  s=$SECONDS; timeout 150 $repo/validation/cli/test_gpu_cli.sh $w/new/bin/tetiso "$(command -v mpirun)" > $O/test_gpu_cli.log 2>&1
  echo "test_gpu_cli.sh rc=$? $((SECONDS-s)) s: $(tail -1 $O/test_gpu_cli.log)"
fi
$w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply >/dev/null 2>&1
for r in 1 2 3; do for b in base new; do
  $w/$b/bin/tetiso reduce p100.ply -o r100_$b.ply --device gpu --max-error 0.0126262626 --report $w/out/n100_${b}_$r.json >/dev/null 2>&1
  python3 -c "import json; d=json.load(open('$w/out/n100_${b}_$r.json')); st=d['stage_seconds']; print('n100 $b $r', 'rounds', len(d['rounds']), 'tris', d['triangles_out'], 'stages %.4f select %.4f' % (sum(st.values()), st['select']), 'passes', [x.get('selection_passes',1) for x in d['rounds']])"
done; done
cmp r100_base.ply r100_new.ply && echo "same bytes: N=100 base new"
$w/new/bin/tetiso reduce p100.ply -o r100_cpu.ply --max-error 0.0126262626 --threads 0 >/dev/null 2>&1; cmp r100_cpu.ply r100_new.ply && echo "same bytes: N=100 gpu cpu"
echo "[$((SECONDS-t0)) s] streams"
for r in 1 2; do for b in base new; do
  timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=32 --no-cpu > $w/out/streams_${b}_$r.txt 2>&1; grep -E "gpu/|batch|identical|M raw" $w/out/streams_${b}_$r.txt | head -6 | sed "s/^/$b $r /"
done; done
TETISO_GPU_PROFILE=1 timeout 60 $w/new/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $w/out/prof32_new.txt
TETISO_GPU_PROFILE=1 timeout 60 $w/base/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $w/out/prof32_base.txt
grep -E "s in primitives" $w/out/prof32_*.txt
echo "[$((SECONDS-t0)) s] jobs"
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-120} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; t=d['tasks']
dom=[x for x in t if x['kind']=='domain']; last=max(x['end'] for x in dom)
print('total %.2f job %.2f tail %.2f cpu domains %d' % (s['total'], s['job'], s['job']-last, sum(1 for x in dom if x['device']=='cpu')))" 2>&1)"
}
for r in 1 2; do job base 500 125 $r; job new 500 125 $r; done
cmp $w/n500_d125_base_1.vtp $w/n500_d125_new_1.vtp && cmp $w/n500_d125_new_1.vtp $w/n500_d125_new_2.vtp && echo "same bytes: N=500 jobs"
if [ $((SECONDS-t0)) -lt 330 ]; then job base 1000 1000 1; job new 1000 1000 1; cmp $w/n1000_d1000_base_1.vtp $w/n1000_d1000_new_1.vtp && echo "same bytes: N=1000 jobs"; fi
echo "[$((SECONDS-t0)) s] done"
cd $w/out && tar -czf $O/all.tar.gz . ; ls $O
