#!/usr/bin/env bash
# What the next GPU loan should measure for issue 29, about 4 minutes: the step with several
# threads a sphere (dem.engine.gpu.GpuEngine.lanes; dem/kernels/cuda/step.py lanes_step_kernel)
# against one (the default) on the 100-replica bed batch (4 cycles each; the fastest over 20),
# then the Done-when sizes with the fastest lane count (1e6 spheres, 1e5 screws), and Nsight
# Compute on the lanes kernel. The baseline of the 50x (100 x the 16-thread CPU run of the bed,
# 6.1-7.0 s each) was measured on three loans of the H200 (gpu_h200_batch_queued.json).
# The bed state is carried in: device_in/bed.pkl (gpu_bench.py --bed-state on any machine).
# Usage: bash validation/performance/run_device_lanes.sh [python] [seconds]
set -u
PY=${1:-python3}
BUDGET=${2:-240}
. "$(dirname "$0")/device_common.sh"
{ date +%T; nvidia-smi -L; } 2>&1
"$PY" $B --batch 100 --batch-cycles 20 --batch-variants 128 128x2 128x4 128x8 --variant-cycles 4 \
    --state $S --out "$OUT/lanes_batch.json" 2>&1 | quiet
echo "batch done at ${SECONDS} s"
L=$("$PY" -c "import json; print(json.load(open('$OUT/lanes_batch.json'))['best_full']['lanes'])" \
    2>/dev/null || echo 1)
echo "fastest lanes: $L"
if [ "$(left)" -gt 60 ]; then
    "$PY" $B --gpu --sizes 1e6 --lanes "$L" --out "$OUT/lanes_spheres.json" 2>&1 | quiet \
        | grep -i "sphere-steps\|error" | head -5
fi
if [ "$(left)" -gt 40 ]; then
    "$PY" $B --clumps --device cuda --clump-sizes 1e5 --lanes "$L" \
        --out "$OUT/lanes_screws.json" 2>&1 | quiet | tail -2
fi
echo "sizes done at ${SECONDS} s"
if [ "$(left)" -gt 45 ] && [ "$L" != 1 ]; then
    NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2>/dev/null | head -1)
    timeout $(($(left) - 5)) "$NCU" -k "regex:lanes_step_kernel" --launch-skip 300 \
        --launch-count 1 --section SpeedOfLight --section Occupancy --section LaunchStats \
        --section WarpStateStats --section SchedulerStats \
        "$PY" $B --batch 100 --batch-cycles 1 --batch-variants "128x$L" --variant-cycles 1 \
        --state $S --out "$OUT/ncu_batch.json" >"$OUT/ncu_lanes.txt" 2>&1
    grep -E "Duration|Registers Per|Achieved Occupancy|Active Threads Per Warp" \
        "$OUT/ncu_lanes.txt" | head -8
fi
date +%T
