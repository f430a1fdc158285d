#!/usr/bin/env bash
# The GPU half of run_device.sh alone, the bed state carried in (device_in/bed.pkl, made by
# gpu_bench.py --bed-state on another machine): for a second, shorter loan.
set -u
PY=${1:-python3}
OUT=${OUT:-device_out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 PATH="$PATH:/usr/local/cuda/bin"
B=validation/performance/gpu_bench.py
"$PY" $B --gpu --sizes 1e4 1e5 1e6 4e6 --max-registers 80 --out "$OUT/gpu.json" >"$OUT/gpu.log" 2>&1
echo "GPU sizes done at $(date +%T)"
"$PY" validation/performance/compile_sm90.py --report "$OUT/ptxas.txt" >>"$OUT/gpu.log" 2>&1
"$PY" $B --bed --device cuda --state device_in/bed.pkl --out "$OUT/bed_gpu.json" >>"$OUT/gpu.log" 2>&1
echo "all done at $(date +%T)"
grep -h "GPU\|bed on\|registers" "$OUT/gpu.log" | head -30
