#!/usr/bin/env bash
# The N = 1000/1000 job with --device auto twice, one pack (new.tar.xz
# beside this script, pack.sh: tetiso; job_gaps.py beside it too): the
# total, the last domain task's end, the gaps between GPU grants and the CPU
# workers' median gap between tasks (results/reduce-gpu/mpi-polling/bounded). Run from the repository root on
# the device machine; writes $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/mv; mkdir -p $w/out; cd $w; tar -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/lib OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader; nproc; date -u; } > out/machine.txt
for i in 1 2; do
timeout 80 mpirun --bind-to core -np $(nproc) $w/bin/tetiso run --lattice 1000 --domains 1000 --device auto --quiet -o $w/s.vtp --report out/n1000_$i.json >/dev/null 2>out/err.txt
echo "rc=$? $(python3 $here/job_gaps.py out/n1000_$i.json)"
done
cd out && gzip -f *.json; tar -czf $OUT/all.tar.gz .
