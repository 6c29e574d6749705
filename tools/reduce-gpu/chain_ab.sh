#!/usr/bin/env bash
# The job's tail, base against new, interleaved: N = 1000/1000 and
# N = 500/125 with --device auto on every GPU and core of the node, two runs
# each; new's N = 500 on the CPU once; cmp of the surfaces
# (results/reduce-gpu/chain-end). Packs base.tar.xz and new.tar.xz (tetiso,
# made by pack.sh) beside this script; writes $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/ab; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt; cat out/machine.txt
job() { # build device lattice domains run
  local name=n$3_d$4_$1_$2_$5 s=$SECONDS
  timeout ${LIMIT:-120} mpirun --bind-to core -np $(nproc) $w/$1/bin/tetiso run --lattice $3 --domains $4 --device $2 --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
for r in 1 2; do for b in base new; do job $b auto 1000 1000 $r; job $b auto 500 125 $r; done; done
job new cpu 500 125 1
for b in base new; do cmp n1000_d1000_${b}_auto_1.vtp n1000_d1000_${b}_auto_2.vtp && echo "same bytes: $b N=1000 runs"; done
cmp n500_d125_new_auto_1.vtp n500_d125_new_cpu_1.vtp && cmp n500_d125_new_auto_2.vtp n500_d125_new_cpu_1.vtp && echo "same bytes: new N=500 auto runs and cpu"
md5sum *.vtp | tee out/md5.txt
cd out && gzip -f *.json; tar -czf $OUT/all.tar.gz .
