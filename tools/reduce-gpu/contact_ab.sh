#!/usr/bin/env bash
# A/B of the contact test on the GPU (results/reduce-gpu/contact-on-gpu): two
# builds packed by pack.sh beside this script, `pack.sh base BUILD tetiso
# bench_gpu_streams` and `pack.sh new BUILD tetiso bench_gpu_streams
# test_exec_gpu`, the folder carried to the device:
#   bash DIR/contact_ab.sh [jobs]     (OUT set by the device tool)
# jobs: also the N = 500/125 job on every core, and bench_gpu_streams of
# both, interleaved.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/s1; mkdir -p $w/base $w/new $w/o; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
o=$w/o; TB=$w/base/bin/tetiso; TN=$w/new/bin/tetiso; t0=$SECONDS
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } | tee $o/machine.txt
[ -x $w/new/bin/test_exec_gpu ] && { timeout 60 $w/new/bin/test_exec_gpu --gtest_brief=1 2>&1 | tail -2; }
$TN extract --lattice 100 --threads 0 -o p100.ply >/dev/null
for i in 1 2 3; do for b in B N; do T=TB; [ $b = N ] && T=TN
  ${!T} reduce p100.ply -o r100$b.ply --device gpu --report $o/n100$b-$i.json >/dev/null || echo FAIL $b
done; done
cmp r100B.ply r100N.ply && echo "N=100 gpu: new == base bytes"
$TN reduce p100.ply -o r100C.ply --device cpu --threads 0 >/dev/null && cmp r100C.ply r100N.ply && echo "N=100: new gpu == new cpu"
python3 - $o <<'PY'
import json,sys,glob
for f in sorted(glob.glob(sys.argv[1]+'/n100*-*.json')):
    d=json.load(open(f)); s=d['stage_seconds']
    print(f.split('/')[-1], 'total %.3f tri_out %d contact %.3f select %.3f' % (d['total_seconds'], d['triangles_out'], s['contact'], s['select']))
PY
for b in B N; do T=TB; [ $b = N ] && T=TN
  TETISO_GPU_PROFILE=1 ${!T} reduce p100.ply -o x.ply --device gpu 2> $o/profile_$b.txt >/dev/null; echo "== profile $b"; head -25 $o/profile_$b.txt
done
if [ "${1:-}" = jobs ]; then
echo "[$((SECONDS-t0)) s] N=500/125 gpu"
for b in B N; do T=TB; [ $b = N ] && T=TN
  timeout 60 mpirun --bind-to core -np $(nproc) ${!T} run --lattice 500 --domains 125 --device gpu --quiet -o /tmp/j$b.vtp --report $o/job500$b.json >/dev/null 2>&1
  python3 -c "import json; d=json.load(open('$o/job500$b.json')); s=d['seconds']; print('job500 $b total %.2f job %.2f' % (s['total'], s['job']))"
done
cmp /tmp/jB.vtp /tmp/jN.vtp && echo "N=500/125: new == base bytes"
echo "[$((SECONDS-t0)) s] streams"
for i in 1 2; do for b in base new; do
  timeout 90 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=1,32 --no-cpu \
    --json=$o/streams_${b}_$i.json > $o/streams_${b}_$i.txt 2>&1
  echo "$b $i: $(grep -E "gpu/" $o/streams_${b}_$i.txt | tr -s ' ' | tr '\n' '|')"
done; done
fi
echo "[$((SECONDS-t0)) s] done"
tar -C $o -czf $OUT/o.tgz .
