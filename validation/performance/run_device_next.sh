#!/usr/bin/env bash
# What issue 29 still needs measured on a lent GPU, about 8 minutes: screws on the GPU (1e4 and
# 1e5, clump-steps/s) and on 16 CPU threads (1e4), the 100 x 1500-sphere batch with the queued
# step launches, and one 16-thread CPU run of the same bed (the sequential baseline, times 100).
# The bed state is carried in: device_in/bed.pkl (gpu_bench.py --bed-state on any machine).
# Usage: bash validation/performance/run_device_next.sh [python]
set -u
PY=${1:-python3}
. "$(dirname "$0")/device_common.sh"
export NUMBA_NUM_THREADS=16
L="$OUT/next.log"
{ nproc; uptime; nvidia-smi -L; } >"$L" 2>&1
"$PY" $B --clumps --device cuda --clump-sizes 1e4 1e5 --out "$OUT/clumps_gpu.json" >>"$L" 2>&1
echo "GPU screws done at $(date +%T)"
"$PY" $B --batch 100 --batch-cycles 20 --state device_in/bed.pkl --out "$OUT/batch.json" >>"$L" 2>&1
echo "batch done at $(date +%T)"
"$PY" $B --bed --device cpu --threads 16 --state device_in/bed.pkl --out "$OUT/bed_cpu.json" >>"$L" 2>&1
"$PY" $B --clumps --device cpu --threads 16 --clump-sizes 1e4 --work 4e8 --out "$OUT/clumps_cpu.json" >>"$L" 2>&1
echo "all done at $(date +%T)"
grep -h "screws\|batch\|bed on" "$L" | head -20
