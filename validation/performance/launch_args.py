"""The prepared launch's arguments: the same bytes for the driver, and what they cost the host.

:class:`dem.kernels.cuda.launch.PreparedLaunch` hands its converted arguments to
``cuda.core.launch`` as Python floats and ints (:func:`dem.kernels.cuda.launch.fast_arg`)
where numba-cuda hands ctypes scalars. For each kernel of ``compile_sm90.signatures()`` this
builds the argument list numba-cuda's ``_prepare_args`` builds for its types (an array: meminfo,
parent, size, itemsize, pointer, shape, strides as Python ints; a float64 or int64: a ctypes
scalar; a tuple: its items; a boolean: a Python bool), converts it as the prepared launch does,
and has cuda.core's ``ParamHolder`` (the object ``cuda.core.launch`` builds every launch) lay out
both: every argument must point at the same bytes (8 for a double, an int64 or an array's
fields, 1 for a bool), else the exit status is 1. It then times ``ParamHolder`` on both lists,
interleaved and repeated (no GPU is needed: this is the host's share of every launch).

Needs cuda.core (``pip install -e '.[cuda]'``), not a GPU.

Usage: python validation/performance/launch_args.py [--out launch_args.json]
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import platform
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))
sys.path.insert(0, str(HERE))


def numba_args(argtypes) -> tuple[list, list[int]]:
    """numba-cuda's converted arguments for ``argtypes`` (dummy values), and each one's bytes."""
    from numba import types

    args, sizes = [], []
    value = 3
    for ty in argtypes:
        value += 1
        if isinstance(ty, types.Array):
            shape = [value + d for d in range(ty.ndim)]
            fields = [0, 0, value * 7, 8, 0x7F0000000000 + 256 * value, *shape]
            fields += [8 * value * (ty.ndim - d) for d in range(ty.ndim)]
            args += fields
            sizes += [8] * len(fields)
        elif isinstance(ty, types.UniTuple):
            args += [ctypes.c_double(0.1 * value + k / 7.0) for k in range(ty.count)]
            sizes += [8] * ty.count
        elif ty == types.float64:
            args.append(ctypes.c_double(value / 3.0))
            sizes.append(8)
        elif ty == types.int64:
            args.append(ctypes.c_int64(-(value << 33) + 5))
            sizes.append(8)
        elif ty == types.boolean:
            args.append(value % 2 == 0)
            sizes.append(1)
        else:
            raise TypeError(f"no dummy for {ty}")
    return args, sizes


def same_bytes(a, b, sizes) -> list[int]:
    """Indices where ParamHolder lays out lists ``a`` and ``b`` differently."""
    from cuda.core._kernel_arg_handler import ParamHolder

    pa, pb = ParamHolder(a), ParamHolder(b)
    n = len(sizes)
    addr_a = (ctypes.c_void_p * n).from_address(pa.ptr)
    addr_b = (ctypes.c_void_p * n).from_address(pb.ptr)
    return [i for i, size in enumerate(sizes)
            if ctypes.string_at(addr_a[i], size) != ctypes.string_at(addr_b[i], size)]  # fmt: skip


def holder_us(args, repeats: int = 2000) -> float:
    """Microseconds for cuda.core to lay out ``args`` (one ParamHolder, as at each launch)."""
    from cuda.core._kernel_arg_handler import ParamHolder

    t0 = time.perf_counter()
    for _ in range(repeats):
        ParamHolder(args)
    return 1e6 * (time.perf_counter() - t0) / repeats


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default=str(HERE / "launch_args.json"))
    p.add_argument("--rounds", type=int, default=5)
    args = p.parse_args()
    try:
        import cuda.core  # noqa: F401
    except ImportError as exc:
        print(f"cuda.core is missing ({exc}): pip install -e '.[cuda]'", file=sys.stderr)
        return 2
    from compile_sm90 import signatures

    from dem.kernels.cuda.launch import fast_arg

    failed = False
    rows = {}
    for name, (_, argtypes) in signatures().items():
        ctypes_args, sizes = numba_args(argtypes)
        fast = [fast_arg(a) for a in ctypes_args]
        bad = same_bytes(ctypes_args, fast, sizes)
        if bad:
            failed = True
            print(f"{name}: arguments {bad} differ", flush=True)
        rows[name] = {"arguments": len(sizes), "differing": bad, "numba_us": [], "fast_us": []}
    for _ in range(args.rounds):  # interleaved
        for name, (_, argtypes) in signatures().items():
            ctypes_args, _ = numba_args(argtypes)
            fast = [fast_arg(a) for a in ctypes_args]
            rows[name]["numba_us"].append(round(holder_us(ctypes_args), 2))
            rows[name]["fast_us"].append(round(holder_us(fast), 2))
    for name, row in rows.items():
        row["numba_us_median"] = sorted(row["numba_us"])[len(row["numba_us"]) // 2]
        row["fast_us_median"] = sorted(row["fast_us"])[len(row["fast_us"]) // 2]
        print(f"{name}: {row['arguments']} arguments, the same bytes: {not row['differing']}; "
              f"cuda.core lays them out in {row['numba_us_median']:.1f} us as numba-cuda passes "
              f"them, {row['fast_us_median']:.1f} us as the prepared launch does",
              flush=True)  # fmt: skip
    import cuda.core

    out = {
        "what": "cuda.core's ParamHolder (built at every launch) on each GPU kernel's converted "
        "arguments as numba-cuda passes them (ctypes scalars) and as PreparedLaunch passes them "
        "(fast_arg: Python floats and ints): the bytes compared, and the host time of each",
        "command": "python validation/performance/launch_args.py (in the cuda extra's venv)",
        "machine": f"{platform.node()}, {os.cpu_count()} cores, load {os.getloadavg()}",
        "cuda_core": cuda.core.__version__,
        "python": platform.python_version(),
        "date": time.strftime("%Y-%m-%d"),
        "kernels": rows,
    }
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
