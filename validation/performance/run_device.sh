#!/usr/bin/env bash
# The GPU benchmark of issue 29 on a machine with a GPU and 16 cores, all jobs of gpu_bench.py in
# one command (a lent machine's time is short): while the GPU runs its sizes, the CPU fills and
# settles the sphere-bed case (compiling the CPU kernels); then the CPU curve on the same lattices
# (1, 4, 16 threads, the GPU idle), then the bed measured on both engines at once (not timed).
# Results in $OUT (default ./device_out): env.txt, gpu.json, gpu.log, ptxas.txt, cpu.json,
# cpu.log, bed_cpu.json, bed_gpu.json.
# Usage: bash validation/performance/run_device.sh [python]
set -u
PY=${1:-python3}
OUT=${OUT:-device_out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 NUMBA_NUM_THREADS=16 PATH="$PATH:/usr/local/cuda/bin"
B=validation/performance/gpu_bench.py
{ nproc; uptime; nvidia-smi; "$PY" -c "import numpy, numba; print('numpy', numpy.__version__, 'numba', numba.__version__); from numba import cuda; print('cuda', cuda.is_available()); cuda.detect()"; } >"$OUT/env.txt" 2>&1
rm -f /tmp/bed.pkl
("$PY" $B --bed-state /tmp/bed.pkl --threads 16 >"$OUT/cpu.log" 2>&1) &
FILL=$!
"$PY" $B --gpu --sizes 1e4 1e5 1e6 4e6 --max-registers 80 --out "$OUT/gpu.json" >"$OUT/gpu.log" 2>&1
"$PY" validation/performance/compile_sm90.py --report "$OUT/ptxas.txt" >>"$OUT/gpu.log" 2>&1
echo "GPU sizes done at $(date +%T)"
wait $FILL
echo "bed filled at $(date +%T)"
"$PY" $B --cpu --sizes 1e4 1e5 1e6 --threads 1 4 16 --work 2e8 --out "$OUT/cpu.json" >>"$OUT/cpu.log" 2>&1
echo "CPU curve done at $(date +%T)"
if [ -f /tmp/bed.pkl ]; then
    "$PY" $B --bed --device cpu --threads 16 --out "$OUT/bed_cpu.json" >>"$OUT/cpu.log" 2>&1 &
    "$PY" $B --bed --device cuda --out "$OUT/bed_gpu.json" >>"$OUT/gpu.log" 2>&1
    wait
fi
echo "all done at $(date +%T)"
tail -5 "$OUT/gpu.log" "$OUT/cpu.log"
