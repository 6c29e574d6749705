#!/usr/bin/env bash
# Nsight Compute of the first kernels of drop_contacts (round 0 of the N = 100
# paper surface's reduction) of new.tar.xz (contact_ab.sh), into OUT/ncu.txt.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/s1; mkdir -p $w/new; cd $w
[ -x new/bin/tetiso ] || tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib OMP_WAIT_POLICY=passive
TN=$w/new/bin/tetiso
[ -f p100.ply ] || $TN extract --lattice 100 --threads 0 -o p100.ply >/dev/null
NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu /usr/local/cuda/bin/ncu 2>/dev/null | head -1); echo "ncu=$NCU"
timeout 240 $NCU --clock-control none --kernel-name-base demangled --kernel-name regex:drop_contacts --launch-count 12 \
  --section LaunchStats --section Occupancy --section SpeedOfLight --section WarpStateStats --section SchedulerStats --section MemoryWorkloadAnalysis \
  $TN reduce p100.ply -o x.ply --device gpu > $OUT/ncu.txt 2>&1; echo rc=$?
grep -E "^  [a-z_]+kernel|Duration|Registers Per|Achieved Occupancy|Theoretical Occupancy|Block Limit Reg|Local Memory|Stack Size|Avg. Active Threads|Warp Cycles Per Issued|Grid Size|Block Size|Compute \(SM\) Throughput|Memory Throughput|L1/TEX Hit|L2 Hit|Issued Warp" $OUT/ncu.txt | cut -c1-160 | head -80
