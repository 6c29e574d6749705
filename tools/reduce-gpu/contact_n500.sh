#!/usr/bin/env bash
# N = 500, 125 domains on every core of the machine (results/reduce-gpu/
# contact-on-gpu/n500-two-gpus): --device auto with new on two GPUs, base on
# two, new on one; --device cpu with new. Packs as for contact_ab.sh.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/s1; mkdir -p $w/base $w/new; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } | tee $OUT/machine.txt
for v in new:0,1 base:0,1 new:0 new:cpu; do b=${v%%:*} g=${v#*:}; T=$w/new/bin/tetiso; [ $b = base ] && T=$w/base/bin/tetiso
  dev=auto; [ $g = cpu ] && dev=cpu
  s=$SECONDS
  CUDA_VISIBLE_DEVICES=$g timeout 100 mpirun -x CUDA_VISIBLE_DEVICES --bind-to core -np $(nproc) $T run --lattice 500 --domains 125 --device $dev --quiet -o /tmp/m_$b$g.vtp --report $OUT/n500_auto_${b}_gpus${g//,/}.json >/dev/null 2>$OUT/err_$b${g//,/}.txt
  echo "$b gpus=$g rc=$? wall $((SECONDS-s)) s: $(python3 -c "import json; d=json.load(open('$OUT/n500_auto_${b}_gpus${g//,/}.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
done
for f in /tmp/m_base0,1.vtp /tmp/m_new0.vtp /tmp/m_newcpu.vtp; do cmp /tmp/m_new0,1.vtp $f && echo "same bytes: $f"; done
