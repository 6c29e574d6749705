#!/usr/bin/env bash
# The resource manager's rebalancing among GPUs (results/reduce-gpu/
# rebalance) on a machine with two or more GPUs, base against new,
# interleaved: test_gpu_cli.sh with new (tasks on both GPUs, cmp with one
# CPU process); the N = 500/125 and N = 1000/1000 jobs with --device auto on
# every core and every GPU, each build twice (cmp base against new). Packs
# made by tools/reduce-gpu/pack.sh beside this script: base.tar.xz and
# new.tar.xz (tetiso). Run from the checkout's root; writes $OUT/all.tar.gz.
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/reb; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
O=$OUT; { nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > $w/out/machine.txt; cat $w/out/machine.txt
t0=$SECONDS
s=$SECONDS; timeout 200 $repo/validation/cli/test_gpu_cli.sh $w/new/bin/tetiso "$(command -v mpirun)" > $w/out/test_gpu_cli.log 2>&1
echo "test_gpu_cli.sh rc=$? $((SECONDS-s)) s: $(tail -1 $w/out/test_gpu_cli.log)"
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout 100 mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; print('total %.2f job %.2f' % (s['total'], s['job']))" 2>&1)"
}
for r in 1 2; do for b in base new; do job $b 500 125 $r; done; done
cmp $w/n500_d125_base_1.vtp $w/n500_d125_new_1.vtp && echo "same bytes: N=500 base new"
cmp $w/n500_d125_new_1.vtp $w/n500_d125_new_2.vtp && echo "same bytes: N=500 new runs"
for r in 1 2; do for b in base new; do [ $((SECONDS-t0)) -lt 420 ] && job $b 1000 1000 $r; done; done
cmp $w/n1000_d1000_base_1.vtp $w/n1000_d1000_new_1.vtp && echo "same bytes: N=1000 base new"
echo "[$((SECONDS-t0)) s] done"
cd $w/out && tar -czf $O/all.tar.gz . ; ls $O
