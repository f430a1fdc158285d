#!/usr/bin/env bash
# The step kernel's single contact loop (dem/kernels/cuda/forces.py: one call site of the contact
# law for pairs and walls) against the three loops it replaced, on one lent GPU, about 5 minutes:
# the 100-replica bed batch (launch variants, 4 cycles; the fastest over 20 cycles), the same
# batch with the old kernel (device_in/old: this tree with the old forces.py), the Done-when
# sizes again (1e6 spheres, 1e5 screws), the 16-thread CPU bed (the sequential baseline, x100)
# and Nsight Compute on the new step kernel. Writes $OUT (or device_out).
# It ran (2026-11-27) with experiments/gpu_single_contact_loop.patch applied; that kernel lost
# and was dropped (gpu_h200_kernel_experiments.json): on main this script times the current one.
# Usage: bash validation/performance/run_device_divergence.sh [python]
set -u
PY=${1:-python3}
. "$(dirname "$0")/device_common.sh"
export NUMBA_NUM_THREADS=16
{ date +%T; nproc; uptime; nvidia-smi -L; } 2>&1
"$PY" $B --batch 100 --batch-cycles 20 --batch-variants 128 64 32 128:128 --variant-cycles 4 \
    --state $S --out "$OUT/new_batch.json" 2>&1 | quiet
echo "new kernel batch done at $(date +%T)"
"$PY" device_in/old/$B --batch 100 --batch-cycles 20 --state $S --out "$OUT/old_batch.json" 2>&1 | quiet
echo "old kernel batch done at $(date +%T)"
"$PY" $B --gpu --sizes 1e6 --out "$OUT/new_spheres.json" 2>&1 | quiet | grep -i "sphere-steps\|error" | head -5
"$PY" $B --clumps --device cuda --clump-sizes 1e5 --out "$OUT/new_screws.json" 2>&1 | quiet | tail -2
echo "sizes done at $(date +%T)"
"$PY" $B --bed --device cpu --threads 16 --cycles 1 --state $S --out "$OUT/cpu_warm.json" >/dev/null 2>&1
for i in 1 2; do
    "$PY" $B --bed --device cpu --threads 16 --state $S --out "$OUT/cpu_bed_$i.json" 2>&1 | tail -1
    "$PY" -c "import json; print('cpu bed wall', json.load(open('$OUT/cpu_bed_$i.json'))['wall_s'])"
done
echo "cpu done at $(date +%T)"
NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2>/dev/null | head -1)
timeout 120 "$NCU" -k regex:step_kernel --launch-skip 300 --launch-count 1 --section SpeedOfLight \
    --section Occupancy --section LaunchStats --section WarpStateStats --section SchedulerStats \
    "$PY" $B --batch 100 --batch-cycles 1 --state $S --out "$OUT/ncu_batch.json" >"$OUT/ncu.txt" 2>&1
grep -E "Duration|Registers Per|Achieved Occupancy|Active Threads Per Warp|Warp Cycles Per Issued" \
    "$OUT/ncu.txt" | head -8
uptime
date +%T
