#!/usr/bin/env bash
# Rank 0 and the workers polling MPI without pausing while their sends are in
# flight, base against new, one H200: the N = 1000/1000 job with --device auto
# twice each interleaved (and new with 4 streams twice), N = 500/125 once
# each; per job the total, the last domain task's end, the GPU grants' gaps
# and the CPU workers' median gap between tasks; cmp of the surfaces.
# base.tar.xz, new.tar.xz (pack.sh: tetiso) and job_gaps.py beside this
# script; run from the repository root on the device machine. Writes
# $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/mp; mkdir -p $w/out; cd $w
for b in base new; do mkdir -p $b; tar -C $b -xJf $here/$b.tar.xz; done
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt
t0=$SECONDS
job() { local b=$1 name=$2 n=$3 d=$4; shift 4
  timeout 80 mpirun --bind-to core -np $(nproc) $w/$b/bin/tetiso run --lattice $n --domains $d --device auto --quiet -o $w/$name.vtp --report out/$name.json "$@" >/dev/null 2>out/err_$name.txt
  echo "$name rc=$? $(python3 $here/job_gaps.py out/$name.json 2>&1)"; }
for i in 1 2; do job base n1000_base_$i 1000 1000; job new n1000_new_$i 1000 1000; done
for i in 1 2; do job new n1000_new4_$i 1000 1000 --gpu-streams 4; done
for x in new_1 base_2 new_2 new4_1 new4_2; do cmp n1000_base_1.vtp n1000_$x.vtp && echo "same bytes: N=1000 base_1, $x"; done
job base n500_base 500 125; job new n500_new 500 125
cmp n500_base.vtp n500_new.vtp && echo "same bytes: N=500"
echo "[$((SECONDS-t0)) s] done"
cd out && gzip -f n*.json; tar -czf $OUT/all.tar.gz .
