#!/usr/bin/env bash
# The dry runs in edge order (results/reduce-gpu/edge-order) on one GPU,
# base against new, interleaved: the GPU tests of new (test_reduce_gpu,
# test_gpu_pipeline); the N = 100 reduction (cmp base, new and the CPU);
# bench_gpu_streams in batches of 32, plain (twice each) and profiled
# (TETISO_GPU_PROFILE); the N = 1000/1000 and N = 500/125 jobs with
# --device auto on every core (cmp base against new). Packs made by
# tools/reduce-gpu/pack.sh beside this script: base.tar.xz (tetiso,
# bench_gpu_streams), new.tar.xz (also test_reduce_gpu, test_gpu_pipeline).
# TESTS=0 skips the tests, REPEAT=0 the second N = 1000 runs. Run from the
# checkout's root; writes $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/sp; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
O=$OUT; { nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $w/out/machine.txt; cat $w/out/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
t0=$SECONDS
if [ "${TESTS:-1}" = 1 ]; then
  for t in test_reduce_gpu test_gpu_pipeline; do s=$SECONDS; timeout 200 $w/new/bin/$t --gtest_brief=1 > $w/out/$t.log 2>&1; echo "$t rc=$? $((SECONDS-s)) s: $(grep -E '^\[  (PASSED|FAILED)' $w/out/$t.log | tr '\n' ' ')"; grep -E "^\[  FAILED" $w/out/$t.log | head; done
fi
echo "[$((SECONDS-t0)) s] N = 100"
$w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply >/dev/null 2>&1
$w/new/bin/tetiso reduce p100.ply -o r100_cpu.ply --max-error 0.0126262626 --threads 0 >/dev/null 2>&1
for r in 1 2; do for b in base new; do
  $w/$b/bin/tetiso reduce p100.ply -o r100_$b.ply --device gpu --max-error 0.0126262626 --report $w/out/n100_${b}_$r.json >/dev/null 2>&1
  echo "n100 $b $r: $(python3 -c "import json; d=json.load(open('$w/out/n100_${b}_$r.json')); print('%.4f s, rounds %.4f s' % (d['seconds'], sum(r['seconds'] for r in d['rounds'])))")"
done; done
cmp r100_base.ply r100_new.ply && cmp r100_cpu.ply r100_new.ply && echo "same bytes: N=100 base, new, cpu"
echo "[$((SECONDS-t0)) s] streams"
for r in 1 2; do for b in base new; do
  timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=32 --no-cpu > $w/out/streams_${b}_$r.txt 2>&1
  grep -E "gpu/streams" $w/out/streams_${b}_$r.txt | sed "s/^/$b $r: /" | cut -c1-150
done; done
for b in base new; do
  TETISO_GPU_PROFILE=1 timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $w/out/prof32_$b.txt
done
grep -E "s in primitives" $w/out/prof32_*.txt
echo "[$((SECONDS-t0)) s] jobs"
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-100} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
for b in base new; do job $b 1000 1000 1; done
cmp $w/n1000_d1000_base_1.vtp $w/n1000_d1000_new_1.vtp && echo "same bytes: N=1000 jobs"
for b in base new; do job $b 500 125 1; done
cmp $w/n500_d125_base_1.vtp $w/n500_d125_new_1.vtp && echo "same bytes: N=500 jobs"
if [ "${REPEAT:-1}" = 1 ] && [ $((SECONDS-t0)) -lt 420 ]; then for b in new base; do job $b 1000 1000 2; done; fi
echo "[$((SECONDS-t0)) s] done"
cd $w/out && gzip -f n1000_*.json n500_*.json 2>/dev/null; tar -czf $O/all.tar.gz . ; ls $O
