#!/usr/bin/env bash
# What the next GPU loan should measure for issue 29, about 4 minutes: the step schemes of
# dem/kernels/cuda/ on the 100-replica bed batch (4 cycles each; the fastest over 20): one
# thread a sphere (step_kernel, the default), the compact step (GpuEngine.compact = True,
# compact.py's compact_step_kernel: a block's touching candidates gathered before the contact
# law) and the engine's opt-in trial (compact = None: it times both on its first chunks and keeps
# the faster); several threads a sphere is a patch (experiments/gpu_lanes_step.patch, apply it
# and add 128x2 128x4 to the variants); then the Done-when sizes with the
# fastest (1e6 spheres, 1e5 screws), 1e5 spheres in a trough of triangles (gpu_bench --mesh:
# mesh_step_kernel), and Nsight Compute on the fastest step kernel. warp_model.py counts what
# each scheme should save (warp_model_sphere-bed.json). The baseline of the 50x (100 x the
# 16-thread CPU run of the bed, 6.1-7.0 s each) was measured on three loans of the H200
# (gpu_h200_batch_queued.json). The bed state is carried in: device_in/bed.pkl
# (gpu_bench.py --bed-state on any machine).
# Usage: bash validation/performance/run_device_schemes.sh [python] [seconds]
set -u
PY=${1:-python3}
BUDGET=${2:-240}
. "$(dirname "$0")/device_common.sh"
{ date +%T; nvidia-smi -L; } 2>&1
"$PY" $B --batch 100 --batch-cycles 20 --batch-variants 128 128c 128a \
    --variant-cycles 4 --state $S --out "$OUT/schemes_batch.json" 2>&1 | quiet
echo "batch done at ${SECONDS} s"
read -r M K < <("$PY" -c "import json; b = json.load(open('$OUT/schemes_batch.json'))['best_full']
k = b['step']['kernel']; print('compact' if k == 'compact_step_kernel' else 'plain', k)" \
    2>/dev/null || echo "plain step_kernel")
C="--step $M"
echo "fastest: $M, kernel $K"
if [ "$(left)" -gt 60 ]; then
    "$PY" $B --gpu --sizes 1e6 $C --out "$OUT/schemes_spheres.json" 2>&1 | quiet \
        | grep -i "sphere-steps\|error" | head -5
fi
if [ "$(left)" -gt 40 ]; then
    "$PY" $B --clumps --device cuda --clump-sizes 1e5 $C \
        --out "$OUT/schemes_screws.json" 2>&1 | quiet | tail -2
fi
if [ "$(left)" -gt 50 ]; then  # the trough mesh on the GPU (one thread a sphere): untimed so far
    "$PY" $B --gpu --sizes 1e5 --mesh --out "$OUT/schemes_mesh.json" 2>&1 | quiet \
        | grep -i "sphere-steps\|error" | head -3
fi
echo "sizes done at ${SECONDS} s"
if [ "$(left)" -gt 45 ] && [ "$K" != step_kernel ]; then
    V=128c
    NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2>/dev/null | head -1)
    timeout $(($(left) - 5)) "$NCU" -k "regex:$K" --launch-skip 300 \
        --launch-count 1 --section SpeedOfLight --section Occupancy --section LaunchStats \
        --section WarpStateStats --section SchedulerStats \
        "$PY" $B --batch 100 --batch-cycles 1 --batch-variants "$V" --variant-cycles 1 \
        --state $S --out "$OUT/ncu_batch.json" >"$OUT/ncu_scheme.txt" 2>&1
    grep -E "Duration|Registers Per|Achieved Occupancy|Active Threads Per Warp" \
        "$OUT/ncu_scheme.txt" | head -8
fi
date +%T
