#!/usr/bin/env bash
# On the device: bash .carry/gpuround/run.sh   (OUT set by the device tool;
# the folder packed by rounds_pack.sh, which copies this script there as run.sh)
# main = /work/main/build at main's HEAD; new = branch gpuround's build.
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$PWD
t0=$SECONDS
w=/tmp/gr; mkdir -p $w/out; cd $w
for n in main new; do mkdir -p $w/$n; tar -C $w/$n -xJf $here/$n.tar.xz; done
export OMP_WAIT_POLICY=passive
# Every program finds its libraries (the packs hold the same Debian ones).
export LD_LIBRARY_PATH=$w/new/lib
o=$w/out
{ nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader; nproc; date -u; uptime; } > $o/machine.txt
cat $o/machine.txt
# The test programs read the meshes of the tree they were built in.
mkdir -p /work/wt/gpuround && ln -sfn "$root/meshes" /work/wt/gpuround/meshes
M=$w/main/bin N=$w/new/bin
$M/tetiso extract --lattice 12 --threads 0 -o $w/p12.ply >/dev/null
$M/tetiso extract --lattice 100 --threads 0 -o $w/p100.ply >/dev/null
summ() { python3 - "$@" <<'PY'
import json,sys,statistics as st
for f in sys.argv[1:]:
    d=json.load(open(f)); r=d['rounds']; late=[x['seconds'] for x in r[1:]]
    print(f"{f.split('/')[-1]}: rounds {len(r)} total_s {d['total_seconds']:.4f} sum_rounds_ms {1e3*sum(x['seconds'] for x in r):.2f} median_round_ms(rounds 1..) {1e3*st.median(late):.3f} min_round_ms {1e3*min(late):.3f} steps {[x['selection_steps'] for x in r][:6]} tri_out {d['triangles_out']}")
PY
}
echo "== 1. fixed cost: the N = 12 surface (rounds of a few thousand triangles), interleaved"
for i in 1 2 3 4 5; do
  $M/tetiso reduce $w/p12.ply -o $w/m12.ply --device gpu --max-error 0.1136363636 --report $o/tiny_main_$i.json >/dev/null || echo "main tiny FAILED"
  $N/tetiso reduce $w/p12.ply -o $w/n12.ply --device gpu --max-error 0.1136363636 --report $o/tiny_new_$i.json >/dev/null || echo "new tiny FAILED"
  TETISO_GPU_HOST_STEPS=1 $N/tetiso reduce $w/p12.ply -o $w/h12.ply --device gpu --max-error 0.1136363636 --report $o/tiny_newhoststeps_$i.json >/dev/null || echo "new host-steps tiny FAILED"
done
summ $o/tiny_*_5.json $o/tiny_*_3.json
cmp $w/m12.ply $w/n12.ply && cmp $w/m12.ply $w/h12.ply && echo "N=12: main, new, new host-steps cmp-identical"
$N/tetiso reduce $w/p12.ply -o $w/c12.ply --device cpu --threads 4 --max-error 0.1136363636 >/dev/null && cmp $w/c12.ply $w/n12.ply && echo "N=12: new GPU == new CPU"
echo "== 2. primitive calls and host waits (TETISO_GPU_PROFILE)"
for b in main new; do
  B=$w/$b/bin; TETISO_GPU_PROFILE=1 $B/tetiso reduce $w/p12.ply -o $w/x.ply --device gpu --max-error 0.1136363636 2> $o/profile_tiny_$b.txt >/dev/null
  echo -n "$b: "; python3 $here/waits.py $o/profile_tiny_$b.txt 19
done
echo "== 3. N = 100, interleaved [$((SECONDS-t0)) s]"
for i in 1 2 3; do for b in main new; do
  B=$w/$b/bin; $B/tetiso reduce $w/p100.ply -o $w/r100_$b.ply --device gpu --max-error 0.0126262626 --report $o/n100_${b}_$i.json >/dev/null || echo "$b n100 FAILED"
done; done
summ $o/n100_*_3.json
cmp $w/r100_main.ply $w/r100_new.ply && echo "N=100: main and new cmp-identical"
if [ "${BENCH_REDUCE:-0}" = 1 ]; then
echo "== 5. bench_reduce_gpu reduce/gpu [$((SECONDS-t0)) s]"
for b in main new; do
  timeout 60 $w/$b/bin/bench_reduce_gpu --sizes=12,100 --benchmark_filter='reduce/gpu' --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out_format=json --benchmark_out=$o/bench_reduce_gpu_$b.json > $o/bench_reduce_gpu_$b.log 2>&1 || echo "$b bench_reduce_gpu FAILED"
  echo "$b:"; grep -E "median|byte for byte|DIFFERS" $o/bench_reduce_gpu_$b.log
done
fi
echo "== 6. bench_gpu_streams [$((SECONDS-t0)) s]"
for b in main new; do
  timeout 60 $w/$b/bin/bench_gpu_streams --lattice=1000 --domains=1000 --count=64 --pick=first --streams=1 --batches=1,32 --no-cpu --json=$o/streams_$b.json > $o/streams_$b.log 2>&1 || echo "$b streams FAILED"
  echo "$b:"; grep -E "gpu/|byte" $o/streams_$b.log
done
if [ "${NCU:-1}" = 1 ]; then
echo "== 7. kernels per round, N = 12 (ncu, rounds 1-4) [$((SECONDS-t0)) s]"
for b in main new; do
  timeout ${NCU_S:-30} ncu --csv --print-units base --kernel-name-base demangled --metrics gpu__time_duration.sum --launch-count ${NCU_COUNT:-900} \
    $w/$b/bin/tetiso reduce $w/p12.ply -o $w/x.ply --device gpu --max-error 0.1136363636 > $o/ncu_tiny_$b.csv 2>$o/ncu_tiny_$b.err || echo "$b ncu rc=$?"
  python3 - $o/ncu_tiny_$b.csv <<'PY'
import csv,sys
# a round begins with the grouping of corners by vertex (the fans): the first kernel named after the fans' builder
rows=[r for r in csv.DictReader(l for l in open(sys.argv[1]) if l.startswith('"'))]
starts=[]; prev=False
for i,r in enumerate(rows):
    f=('build_fans' in r['Kernel Name'] or 'order_all_fans' in r['Kernel Name']) and 'group_by_key' in r['Kernel Name']
    if f and not prev: starts.append(i)
    prev=f
t=lambda r: float(r['Metric Value'].replace(',',''))
out=[]
for a,b in zip(starts,starts[1:]):
    seg=rows[a:b]; out.append((len(seg), sum(t(r) for r in seg)/1e3))
print(sys.argv[1].split('/')[-1], len(rows), 'kernels profiled; per round (kernels, GPU-busy us, each kernel alone):', [(n, round(u,1)) for n,u in out])
PY
done
fi
echo "== 4. tests (new) [$((SECONDS-t0)) s]"
for t in ${TESTS:-test_exec_gpu test_extract_gpu test_gpu_pipeline test_reduce_gpu}; do
  s=$SECONDS; left=$(( ${LIMIT:-225} - (SECONDS - t0) ))
  [ $left -gt 20 ] || { echo "$t: not run (time)"; continue; }
  if timeout $left $N/$t --gtest_brief=1 > $o/$t.log 2>&1; then echo "$t: passed ($((SECONDS-s)) s) $(grep -E 'PASSED' $o/$t.log)"
  else echo "$t: FAILED rc=$? ($((SECONDS-s)) s)"; grep -E "Failure|differ|error|FAILED|Expected|Which is|CUDA" $o/$t.log | head -20; fi
done
echo "all: $((SECONDS-t0)) s"
tar -C $w -czf $OUT/gr.tar.gz out
cp $o/machine.txt $OUT/
