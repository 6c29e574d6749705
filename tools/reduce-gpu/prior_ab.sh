#!/usr/bin/env bash
# The CPU's prior under --device auto (results/reduce-gpu/cpu-prior): base and
# new builds, interleaved, on every core of a one-GPU machine: the N = 500,
# 125-domain job twice each, then the N = 1000, 1000-domain job once each;
# every surface compared with cmp. Packs made by tools/reduce-gpu/pack.sh as
# base.tar.xz and new.tar.xz beside this script. Writes to $OUT.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/prior; mkdir -p $w/base $w/new; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } | tee $OUT/machine.txt
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-250} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o /tmp/$name.vtp --report $OUT/$name.json >/dev/null 2>$OUT/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "import json; d=json.load(open('$OUT/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
for r in 1 2; do job base 500 125 $r; job new 500 125 $r; done
[ "${BIG:-1}" = 1 ] && { job new 1000 1000 1; job base 1000 1000 1; }
for f in /tmp/n*_new_*.vtp; do b=${f/_new_/_base_}; [ -f $b ] && { cmp $f $b && echo "same bytes: $(basename $f) $(basename $b)"; }; done
cmp /tmp/n500_d125_new_1.vtp /tmp/n500_d125_new_2.vtp && echo "same bytes: new runs 1 and 2"
gzip -f $OUT/*.json
