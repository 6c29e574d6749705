#!/usr/bin/env bash
# results/reduce-gpu/lazy-speculation: the GPU tests, then the N = 100
# surface reduced by base and new (stage seconds, passes per round, cmp with
# each other and the CPU), bench_gpu_streams on the first 32 domains of the
# N = 1000 job one at a time and in a batch, and new's TETISO_GPU_PROFILE of
# the batch. Packs made by tools/reduce-gpu/pack.sh beside this script:
# base_tetiso.tar.xz (tetiso), base_bench.tar.xz (bench_gpu_streams),
# new_all.tar.xz (tetiso, bench_gpu_streams, test_reduce_gpu,
# test_gpu_pipeline). TESTLIST: the tests to run (TESTS=0: none).
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/lazy; mkdir -p $w/base $w/new $w/bb $w/nb; cd $w
tar -C base -xJf $here/base_tetiso.tar.xz; tar -C bb -xJf $here/base_bench.tar.xz
tar -C new -xJf $here/new_all.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $OUT/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
if [ "${TESTS:-1}" = 1 ]; then
  for t in ${TESTLIST:-test_reduce_gpu test_gpu_pipeline}; do s=$SECONDS; timeout 300 $w/new/bin/$t > $OUT/$t.log 2>&1; echo "$t rc=$? $((SECONDS-s)) s: $(grep -E 'PASSED|FAILED' $OUT/$t.log | head -3 | tr '\n' ' ')"; done
fi
$w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply --quiet 2>/dev/null || $w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply
for r in 1 2; do for b in base new; do
  $w/$b/bin/tetiso reduce p100.ply -o r100_$b.ply --device gpu --max-error 0.0126262626 --report $OUT/n100_${b}_$r.json >/dev/null 2>&1
  python3 -c "import json; d=json.load(open('$OUT/n100_${b}_$r.json')); st=d.get('stage_seconds',{}); print('$b $r', 'rounds', len(d['rounds']), 'passes', [x.get('selection_passes') for x in d['rounds']][:12], 'tris', d.get('triangles_out'), 'stages %.3f' % sum(st.values()) if st else d.get('seconds'))"
done; done
cmp r100_base.ply r100_new.ply && echo "same bytes: N=100 base new"
$w/new/bin/tetiso reduce p100.ply -o r100_cpu.ply --max-error 0.0126262626 --threads 0 >/dev/null 2>&1; cmp r100_cpu.ply r100_new.ply && echo "same bytes: N=100 gpu cpu"
for b in bb new; do
  $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=1,32 --no-cpu 2>&1 | grep -E "batch|identical" | sed "s/^/$b /"
done
TETISO_GPU_PROFILE=1 $w/new/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=32 --pick=first --streams=1 --batches=32 --no-cpu > /dev/null 2> $OUT/prof32_new.txt
sed -n '/2\.[0-9]* s in primitives\|[0-9]\.[0-9]* s in primitives/p' $OUT/prof32_new.txt
cd $OUT && tar -czf all.tar.gz *.json *.txt *.log 2>/dev/null; ls
