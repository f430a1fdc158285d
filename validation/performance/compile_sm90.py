"""Compile every GPU kernel for sm_90 (H100/H200) without a GPU; registers and spills by ptxas.

Each kernel of :mod:`dem.kernels.cuda` is compiled to PTX by numba-cuda for compute capability
9.0 with the argument types the engine launches it with (:data:`SIGNATURES`). Where ``ptxas``
is found (the CUDA toolkit, or the ``nvidia-cuda-nvcc`` wheel), each PTX is assembled for sm_90
with ``-v``: its report (registers per thread, spill stores and loads, local memory) is written
to ``--report``, and a kernel that spills fails the check (exit status 1). Without ptxas the PTX
alone is checked (exit status 0 and a line saying the report is missing).

Needs numba-cuda (``pip install -e '.[cuda]'``), not a GPU: numba-cuda compiles a device
function for the current device even when asked for another, so the current device is reported
as an sm_90 here.

Usage: python validation/performance/compile_sm90.py [--report ptxas_sm90.txt] [--ptx DIR]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import types as pytypes
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

CC = (9, 0)


def signatures() -> dict:
    """Kernel name -> (kernel, argument types), the types of the engine's launches."""
    from numba import types

    from dem.kernels.contact import N_PARAMS
    from dem.kernels.cuda import bodies, compact, forces, neighbours, step

    f8, i8, b1 = types.float64, types.int64, types.boolean
    a2 = types.Array(f8, 2, "C")
    a1 = types.Array(f8, 1, "C")
    a3 = types.Array(f8, 3, "C")
    i4a = types.Array(types.int32, 1, "C")
    i8a = types.Array(i8, 1, "C")
    row = types.UniTuple(f8, N_PARAMS)
    grid = (i8, i8, i8, f8, f8, f8, f8)
    return {
        "forces_kernel": (forces.forces_kernel, (
            i8, row, row, a2, a2, a2, a1, a1, i4a, i4a, i4a, i4a, a2, a2, a2, a2,
            f8, f8, f8, f8, f8, f8, f8, a2, a2)),
        "fill_int_kernel": (neighbours.fill_int_kernel, (i4a, i8)),
        "wrap_kernel": (neighbours.wrap_kernel, (a2, f8, a1)),
        "bin_kernel": (neighbours.bin_kernel, (a2, i4a, *grid, f8, i4a, i4a, i8, i8a)),
        "scan_kernel": (neighbours.scan_kernel, (
            a2, a1, i8a, i4a, f8, f8, f8, *grid, i4a, i4a, i8, i4a, i4a, a2, i4a, i4a, a2, a2,
            i8a)),
        "reverse_kernel": (neighbours.reverse_kernel, (i4a, i4a, i4a, i4a, i8a)),
        "sort_reverse_kernel": (neighbours.sort_reverse_kernel, (i4a, i4a)),
        "deepest_kernel": (neighbours.deepest_kernel, (a2, a1, i4a, i4a, f8, a1, i4a)),
        "kick_drift_kernel": (step.kick_drift_kernel, (
            i8, i8a, f8, a2, a2, a2, a2, a2, a1, a1, b1, a2, f8, f8)),
        "step_kernel": (step.step_kernel, (
            i8, i8a, i8, row, row, a2, a2, a2, a2, a2, a2, a1, a1, a1, a1, i4a, i4a, i4a, i4a,
            a2, a2, a2, a2, f8, f8, f8, f8, a3, i8, i4a, b1, b1, b1, a2, f8, a2, a2, a1)),
        "mesh_step_kernel": (step.mesh_step_kernel, (
            i8, i8a, i8, row, row, a2, a2, a2, a2, a2, a2, a1, a1, a1, a1, i4a, i4a, i4a, i4a,
            a2, a2, a2, a2, f8, f8, f8, f8, a3, i8, i4a, b1, b1, b1, a2, f8, a2, a2, a1,
            a3, a1, i8a, i8a, i8a, a2, a2)),
        "compact_step_kernel": (compact.compact_step_kernel, (
            i8, i8, i8a, i8, row, row, a2, a2, a2, a2, a2, a2, a1, a1, a1, a1, i4a, i4a, i4a,
            i4a, a2, a2, a2, a2, f8, f8, f8, f8, a3, i8, i4a, b1, b1, b1, a2, f8, a2, a2, a1)),
        "reduce_kernel": (bodies.reduce_kernel, (
            a2, a2, a2, a2, i8a, i8a, f8, a1, a3, i8, i4a, a2, a2)),
        "half_step_kernel": (bodies.half_step_kernel, (
            i8, i8a, f8, b1, a2, a2, a2, a2, a2, a2, a1, a2, a2, a2, i8a, i8a, a2, a2, a2, a2,
            f8, f8)),
        "bodies_kernel": (bodies.bodies_kernel, (
            i8, i8a, f8, a3, i8, i4a, b1, b1, a2, a2, a2, a2, a2, a2, a2, a2, a2, a2, a2, a2, a1,
            a1, a2, a2, i8a, i8a, a2, f8, f8, a1)),
    }  # fmt: skip


def find_ptxas() -> str | None:
    """ptxas of this environment's CUDA wheels first, else CUDA_HOME's, else on PATH."""
    for p in sorted(Path(sys.prefix).rglob("bin/ptxas")):
        return str(p)
    for base in (os.environ.get("CUDA_HOME"), "/usr/local/cuda"):
        if base and (Path(base) / "bin" / "ptxas").exists():
            return str(Path(base) / "bin" / "ptxas")
    return shutil.which("ptxas")


def read_report(report: str, returncode: int) -> tuple[str, bool]:
    """ptxas -v's report in a few words, and whether it fails the check (a spill, an error)."""
    regs = re.search(r"Used (\d+) registers", report)
    spills = [int(v) for v in re.findall(r"(\d+) bytes spill (?:stores|loads)", report)]
    if returncode != 0:
        return "ptxas FAILED", True
    used = regs.group(1) if regs else "?"
    if any(spills):
        return f"{used} registers, SPILLS ({max(spills)} bytes)", True
    return f"{used} registers, no spills", False


def _ptxas(ptxas: str, path: Path):
    return subprocess.run(
        [ptxas, "-arch=sm_90", "-v", str(path), "-o", os.devnull],
        capture_output=True, text=True, check=False,
    )  # fmt: skip


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--report", default="ptxas_sm90.txt", help="ptxas -v report, one per kernel")
    p.add_argument("--ptx", help="keep the PTX files in this folder")
    args = p.parse_args()
    import numba.cuda.dispatcher as dispatcher
    from numba import cuda

    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        print("compile_sm90: NUMBA_ENABLE_CUDASIM=1 compiles nothing; unset it")
        return 2
    if not cuda.is_available():  # no driver: say the current device is an sm_90
        dispatcher.get_current_device = lambda: pytypes.SimpleNamespace(compute_capability=CC)
    ptx_dir = Path(args.ptx) if args.ptx else Path(tempfile.mkdtemp(prefix="dem_ptx_"))
    ptx_dir.mkdir(parents=True, exist_ok=True)
    ptxas = find_ptxas()
    lines, failed = [], False
    for name, (kernel, sig) in signatures().items():
        fn = getattr(kernel, "py_func", None) or kernel
        ptx, _ = cuda.compile_ptx(fn, sig, cc=CC)
        path = ptx_dir / f"{name}.ptx"
        path.write_text(ptx)
        head = f"{name}: PTX {ptx.count(chr(10))} lines, {ptx.count('fma.rn.f64')} fma.rn.f64"
        if ptxas is None:
            lines.append(head)
            print(head)
            continue
        res = _ptxas(ptxas, path)
        report = (res.stdout + res.stderr).strip()
        older = re.search(r"Unsupported \.version (\S+); current version is '(\S+)'", report)
        if older:  # a ptxas older than the compiler: assemble as its own PTX version
            path.write_text(ptx.replace(f".version {older[1]}", f".version {older[2]}", 1))
            res = _ptxas(ptxas, path)
            report = (res.stdout + res.stderr).strip()
            report = f"(PTX {older[1]} assembled as {older[2]}, this ptxas's version)\n{report}"
        verdict, bad = read_report(report, res.returncode)
        failed |= bad
        head += f"; {verdict}"
        print(head)
        lines += [head, report, ""]
    if ptxas is None:
        lines.append("ptxas not found: no register or spill report (install nvidia-cuda-nvcc)")
        print(lines[-1])
    Path(args.report).write_text("\n".join(lines) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
