# Sourced by the run_device_*.sh scripts (after setting PY and BUDGET): the output folder ($OUT,
# the device tool's, or device_out), the benchmark, the carried bed state, and two helpers.
OUT=${OUT:-device_out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
B=validation/performance/gpu_bench.py
S=device_in/bed.pkl
# numba's warnings off the log
quiet() { grep -v "Warning\|warn(" || true; }
# seconds left of the script's BUDGET
left() { echo $((${BUDGET:-600} - SECONDS)); }
