#!/usr/bin/env bash
# N = 1000, 1000 domains, --device auto on every GPU and core of the machine
# (results/reduce-gpu/contact-on-gpu/n1000-two-gpus): packs base and new as
# for contact_ab.sh, the folder carried to the device.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/s1; mkdir -p $w/base $w/new; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } | tee $OUT/machine.txt
for b in new base; do T=$w/new/bin/tetiso; [ $b = base ] && T=$w/base/bin/tetiso
  s=$SECONDS
  timeout 130 mpirun --bind-to core -np $(nproc) $T run --lattice 1000 --domains 1000 --device auto --quiet -o /tmp/k$b.vtp --report $OUT/n1000_auto_$b.json >/dev/null 2>$OUT/err_$b.txt
  echo "$b rc=$? wall $((SECONDS-s)) s: $(python3 -c "import json; d=json.load(open('$OUT/n1000_auto_$b.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
done
cmp /tmp/knew.vtp /tmp/kbase.vtp && echo "N=1000/1000 auto: new == base bytes"
