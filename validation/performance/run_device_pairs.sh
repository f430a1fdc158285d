#!/usr/bin/env bash
# The pair kernel (one thread a pair slot, then one thread a sphere gathering; dem/kernels/cuda/
# forces.py) on one lent GPU in about 3 minutes, each stage skipped once the budget is spent:
# the 100-replica bed batch (threads per block 128 and 256 over 4 cycles, the faster over 20),
# one replica alone, the Done-when sizes (1e6 spheres, 1e5 screws) and Nsight Compute on both
# kernels. The 16-thread CPU bed (the baseline, x100) was measured on earlier loans of the kind.
# It ran (2026-11-27) with experiments/gpu_pair_kernel.patch applied to the tree; that kernel lost
# and was dropped (gpu_h200_kernel_experiments.json): on main this script times the current one.
# Usage: bash validation/performance/run_device_pairs.sh [python] [seconds]
set -u
PY=${1:-python3}
BUDGET=${2:-180}
. "$(dirname "$0")/device_common.sh"
{ date +%T; nvidia-smi -L; } 2>&1
"$PY" $B --batch 100 --batch-cycles 20 --batch-variants 128 256 --variant-cycles 4 \
    --state $S --out "$OUT/pairs_batch.json" 2>&1 | quiet
echo "batch done at ${SECONDS} s"
if [ "$(left)" -gt 60 ]; then
    "$PY" $B --gpu --sizes 1e6 --out "$OUT/pairs_spheres.json" 2>&1 | quiet \
        | grep -i "sphere-steps\|error" | head -5
fi
if [ "$(left)" -gt 40 ]; then
    "$PY" $B --clumps --device cuda --clump-sizes 1e5 --out "$OUT/pairs_screws.json" 2>&1 \
        | quiet | tail -2
fi
echo "sizes done at ${SECONDS} s"
if [ "$(left)" -gt 45 ]; then
    NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2>/dev/null | head -1)
    timeout $(($(left) - 5)) "$NCU" -k "regex:step_kernel|pair_kernel" --launch-skip 600 \
        --launch-count 2 --section SpeedOfLight --section Occupancy --section LaunchStats \
        --section WarpStateStats --section SchedulerStats \
        "$PY" $B --batch 100 --batch-cycles 1 --state $S --out "$OUT/ncu_batch.json" \
        >"$OUT/ncu_pairs.txt" 2>&1
    grep -E "^  [a-z_]+kernel|Duration|Registers Per|Achieved Occupancy|Active Threads Per Warp" \
        "$OUT/ncu_pairs.txt" | cut -c1-90 | head -12
fi
date +%T
