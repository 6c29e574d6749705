#!/usr/bin/env bash
# The job's last seams on the GPUs' drivers, base against seams (and chain:
# seams with the shorter chain of results/reduce-gpu/chain-end), one H200,
# --gpu-streams 4 for all: the N = 1000/1000 job with --device auto twice
# each interleaved, N = 500/125 once each and chain's N = 500 on the CPU
# (its surface differs from base's: another tree); per job the total, the
# last domain task's end and the seams that ran on a driver's GPU; cmp.
# base.tar.xz, seams.tar.xz, chain.tar.xz (pack.sh: tetiso) beside this
# script; run from the repository root on the device machine (any count of
# GPUs: mpirun takes every core). BUILDS="base chain" and CPU=0 run fewer.
# Writes $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/sg; mkdir -p $w/out; cd $w
builds=${BUILDS:-base seams chain}
for b in $builds; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/base/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt
t0=$SECONDS
job() { local b=$1 name=$2 n=$3 d=$4 dev=$5
  timeout 100 mpirun --bind-to core -np $(nproc) $w/$b/bin/tetiso run --lattice $n --domains $d --device $dev --gpu-streams 4 --quiet -o $w/$name.vtp --report out/$name.json >/dev/null 2>out/err_$name.txt
  echo "$name rc=$? $(python3 -c "
import json
d=json.load(open('out/$name.json')); t=d['tasks']
dom=[x for x in t if x['kind']=='domain']; last=max(x['end'] for x in dom)
gs=[x for x in t if x['kind']=='seam' and x['device']!='cpu' and x['rank']!=0]
big=sorted([x for x in t if x['kind']=='seam' and x['end']>last], key=lambda x: -x['triangles_in'])[:3]
print('total %.2f last domain %.2f tail %.2f seams on drivers %d; largest after: %s' % (d['seconds']['total'], last, d['seconds']['job']-last, len(gs),
  ', '.join('%dk %s r%d %d thr %.2f s' % (x['triangles_in']//1000, x['device'], x['rank'], x['threads'], x['end']-x['start']) for x in big)))" 2>&1)"; }
for i in 1 2; do for b in $builds; do job $b n1000_${b}_$i 1000 1000 auto; done; done
for b in $builds; do job $b n500_$b 500 125 auto; done
[ "${CPU:-1}" = 1 ] && job chain n500_chain_cpu 500 125 cpu
for b in $builds; do cmp n1000_${b}_1.vtp n1000_${b}_2.vtp && echo "same bytes: $b's two N=1000 runs"; done
[ -f n1000_seams_1.vtp ] && cmp n1000_base_1.vtp n1000_seams_1.vtp && echo "same bytes: N=1000 base, seams"
[ -f n500_seams.vtp ] && cmp n500_base.vtp n500_seams.vtp && echo "same bytes: N=500 base, seams"
[ -f n500_chain_cpu.vtp ] && cmp n500_chain.vtp n500_chain_cpu.vtp && echo "same bytes: N=500 chain auto, cpu"
echo "[$((SECONDS-t0)) s] done"
cd out && gzip -f n*.json; tar -czf $OUT/all.tar.gz .
