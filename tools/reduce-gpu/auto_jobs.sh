#!/usr/bin/env bash
# The N = 1000/1000 and N = 500/125 jobs with --device auto on every GPU and
# core of the node (two runs each), and N = 500/125 on the CPU once; cmp of
# the surfaces (results/reduce-gpu/edge-order/two-gpus, four-gpus). The pack
# new.tar.xz (tetiso, made by pack.sh) beside this script; run from the
# checkout's root on the device; writes $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/jobs; mkdir -p $w/out; cd $w
mkdir -p new; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt; cat out/machine.txt
job() { # device lattice domains run [extra]
  local name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-120} mpirun --bind-to core -np $(nproc) $w/new/bin/tetiso run --lattice $2 --domains $3 --device $1 ${5:-} --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
for r in 1 2; do job auto 1000 1000 $r; job auto 500 125 $r; done
job cpu 500 125 1
cmp n1000_d1000_auto_1.vtp n1000_d1000_auto_2.vtp && echo "same bytes: N=1000 runs"
cmp n500_d125_auto_1.vtp n500_d125_cpu_1.vtp && cmp n500_d125_auto_2.vtp n500_d125_cpu_1.vtp && echo "same bytes: N=500 auto runs and cpu"
md5sum *.vtp | tee out/md5.txt
cd out && gzip -f *.json; tar -czf $OUT/all.tar.gz .
