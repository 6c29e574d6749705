#!/usr/bin/env bash
# The CPU's prior and the last seams on a GPU (results/reduce-gpu/job-tail):
# the GPU tests of the job's pipeline and command line, then the base and new
# builds interleaved on every core of the machine, N = 500 with 125 domains
# twice each and N = 1000 with 1000 domains once each, --device auto; every
# surface compared with cmp. Packs made by tools/reduce-gpu/pack.sh as
# base.tar.xz (tetiso) and new.tar.xz (tetiso, test_gpu_pipeline) beside
# this script. Writes to $OUT, its reports in one archive (jobs.tar.gz).
set -u
repo=$(pwd); here=$(cd "$(dirname "$0")" && pwd); w=/tmp/tail; mkdir -p $w/base $w/new $w/out; cd $w
tar -C base -xJf $here/base.tar.xz; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } | tee $OUT/machine.txt
[ -e /work/main/meshes ] || { mkdir -p /work/main && ln -sfn $repo/meshes /work/main/meshes; }
if [ "${TESTS:-1}" = 1 ]; then
  s=$SECONDS; timeout 200 $w/new/bin/test_gpu_pipeline > $OUT/test_gpu_pipeline.log 2>&1
  echo "test_gpu_pipeline rc=$? $((SECONDS-s)) s: $(grep -E '^\[  (PASSED|FAILED)' $OUT/test_gpu_pipeline.log | tr '\n' ' ')"
  s=$SECONDS; timeout 300 $repo/validation/cli/test_gpu_cli.sh $w/new/bin/tetiso "$(command -v mpirun)" > $OUT/test_gpu_cli.log 2>&1
  echo "test_gpu_cli.sh rc=$? $((SECONDS-s)) s: $(tail -1 $OUT/test_gpu_cli.log)"
fi
job() { # build lattice domains run
  local T=$w/$1/bin/tetiso name=n$2_d$3_$1_$4 s=$SECONDS
  timeout ${LIMIT:-200} mpirun --bind-to core -np $(nproc) $T run --lattice $2 --domains $3 --device auto --quiet \
    -o $w/$name.vtp --report $w/out/$name.json >/dev/null 2>$w/out/err_$name.txt
  echo "$name rc=$? wall $((SECONDS-s)) s: $(python3 -c "
import json; d=json.load(open('$w/out/$name.json')); s=d['seconds']; t=d['tasks']
dom=[x for x in t if x['kind']=='domain']; last=max(x['end'] for x in dom)
print('total %.2f job %.2f last domain %.2f tail %.2f cpu domains %d' % (s['total'], s['job'], last, s['job']-last, sum(1 for x in dom if x['device']=='cpu')))" 2>&1)"
}
for r in 1 2; do job base 500 125 $r; job new 500 125 $r; done
[ "${BIG:-1}" = 1 ] && { job new 1000 1000 1; job base 1000 1000 1; }
for f in $w/n*_new_*.vtp; do b=${f/_new_/_base_}; [ -f $b ] && cmp $f $b && echo "same bytes: $(basename $f) $(basename $b)"; done
tar -C $w/out -czf $OUT/jobs.tar.gz .
