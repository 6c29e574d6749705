#!/usr/bin/env bash
# Nsight Compute on round 0 of the GPU reduction of the N = 100 paper surface:
# the kernels matching NCU_REGEX (first NCU_COUNT launches), full sections
# (results/reduce-gpu/contact-chunks/ncu_round0_95ad136.txt). The pack
# new.tar.xz (tetiso, made by pack.sh) beside this script; writes
# $OUT/all.tar.gz.
set -u
here=$(cd "$(dirname "$0")" && pwd); w=/tmp/prof; mkdir -p $w/out; cd $w
mkdir -p new; tar -C new -xJf $here/new.tar.xz
export LD_LIBRARY_PATH=$w/new/lib
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader > out/machine.txt; date -u >> out/machine.txt
$w/new/bin/tetiso extract --lattice 100 --threads 0 -o p100.ply >/dev/null 2>&1
NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
timeout 400 $NCU --kernel-name-base demangled --kernel-name "regex:${NCU_REGEX}" --launch-skip 0 --launch-count ${NCU_COUNT:-12} \
  --section LaunchStats --section Occupancy --section SpeedOfLight --section WarpStateStats --section SchedulerStats --section MemoryWorkloadAnalysis --section ComputeWorkloadAnalysis \
  --metrics smsp__thread_inst_executed_per_inst_executed.ratio,l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum,l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum,dram__bytes.sum,lts__t_sector_hit_rate.pct,smsp__average_warp_latency_issue_stalled_long_scoreboard.ratio,smsp__average_warp_latency_issue_stalled_lg_throttle.ratio,smsp__average_warp_latency_issue_stalled_barrier.ratio,smsp__average_warp_latency_issue_stalled_math_pipe_throttle.ratio,smsp__average_warp_latency_issue_stalled_wait.ratio,smsp__average_warp_latency_issue_stalled_short_scoreboard.ratio,smsp__average_warp_latency_issue_stalled_no_instruction.ratio \
  $w/new/bin/tetiso reduce p100.ply -o r.ply --device gpu --max-error 0.0126262626 > out/ncu.txt 2>&1; echo "ncu rc=$?"
grep -E "^  [a-z].*Context|Duration|Registers Per|Achieved Occupancy|Theoretical Occ|thread_inst_executed_per|local_op|dram__bytes|sector_hit|Memory Throughput|Compute \(SM\) Thr|Warp Cycles Per Issued|stalled_[a-z_]*.ratio|Grid Size|Block Size|Eligible Warps|No Eligible" out/ncu.txt | cut -c1-170
cd out && tar -czf $OUT/all.tar.gz .
