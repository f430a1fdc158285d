"""The pinned regression run: 20 seeded screws, one settle cycle and two measured cycles.

``python tests/regression/pinned.py --why "..."`` reruns it and rewrites ``pinned.json``; the
reason is required and recorded beside the numbers, with the commit and the date, so the file's
history says why each change of the physics moved them. tests/regression/test_pinned.py reruns
it and compares every number to 12 significant digits.

A refactor must leave these numbers alone. Regenerate only for a change that is meant to move
them (a fixed law, a new default), and say so in ``--why``; that drops every machine's set.

The same commit can give other last bits on another machine (measured: 1556ccd on an AMD EPYC
without AVX-512 against the record made on the project's earlier machines, up to 8.2e-5 of a
standard error and 4e-7 of the mean velocity, while a drive one ulp off moved them by 5e-12 at
most; neither numba's target CPU nor numpy's AVX2 paths made the difference). ``--machine``
records such a machine's own numbers, with its fingerprint, beside the others; the test passes
when one recorded set matches to 12 digits in every number.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PINNED = HERE / "pinned.json"
CASE = ROOT / "cases" / "screw-trough"
OVERRIDES = {"particles.count": 20, "run.settle_cycles": 1, "run.cycles": 2, "run.seed": 7}
#: summary.json entries that are not the run's physics: timing, provenance, and the contact law's
#: report (the case's own inputs, echoed; the kernel arrays they pack are pinned bit for bit by
#: params.py).
SKIP = ("contact_law", "wall_time", "per_s", "compile", "provenance", "plan", "date", "load", "git",
        "version", "stiffness", "warnings", "rate", "host")  # fmt: skip
DIGITS = 12


def flatten(value, prefix: str = "") -> dict:
    """{"a.b": number} for every number (and list of numbers) in a nested summary."""
    out: dict = {}
    if isinstance(value, dict):
        for key, v in value.items():
            out |= flatten(v, f"{prefix}{key}.")
    elif isinstance(value, bool) or value is None or isinstance(value, str):
        pass
    elif isinstance(value, int | float):
        out[prefix[:-1]] = float(value)
    elif isinstance(value, list) and all(isinstance(v, int | float) for v in value):
        for i, v in enumerate(value):
            out[f"{prefix}{i}"] = float(v)
    return out


def run() -> dict:
    """The run's physical numbers, {"key": value}; one thread, no frames, in a scratch folder."""
    import numba

    from dem.run.runner import run_case
    from dem.scene.case import load_case

    numba.set_num_threads(1)
    case = load_case(CASE, OVERRIDES)
    with tempfile.TemporaryDirectory() as tmp:
        summary = run_case(case, Path(tmp) / "out", threads=1, progress=False, frames=False)
    numbers = flatten(summary)
    return {k: v for k, v in sorted(numbers.items()) if not any(s in k for s in SKIP)}


def fingerprint() -> dict:
    """What of this machine can change a run's last bits: its CPU and the SIMD paths numpy and
    numba's LLVM take on it (the same commit gave other numbers on an AMD EPYC without AVX-512)."""
    import platform

    import llvmlite.binding as llvm
    from numpy._core._multiarray_umath import __cpu_features__

    return {
        "machine": platform.machine(),
        "llvm_cpu": llvm.get_host_cpu_name(),
        "numpy_cpu_features": sorted(k for k, on in __cpu_features__.items() if on),
    }


def matches(numbers: dict, recorded: dict) -> dict:
    """The numbers that moved against one recorded set: {key: (recorded, now)}."""
    return {k: (recorded[k], v) for k, v in numbers.items() if not same(recorded[k], v)}


def same(a: float, b: float) -> bool:
    """Equal to :data:`DIGITS` significant digits (zeros: to 1e-300)."""
    if a == b:
        return True
    return math.isfinite(a) and math.isfinite(b) and abs(a - b) <= 10**-DIGITS * max(abs(a), abs(b))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--why", required=True, help="why the pinned numbers move (recorded)")
    parser.add_argument("--machine", action="store_true",
                        help="keep the numbers; add this machine's own (the same physics, other "
                        "last bits), after checking that no recorded set matches here")  # fmt: skip
    args = parser.parse_args()
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    from dem import provenance

    numbers = run()
    if args.machine:
        record = json.loads(PINNED.read_text())
        sets = [record["numbers"]] + [m["numbers"] for m in record.get("machines", [])]
        if any(not matches(numbers, s) for s in sets):
            raise SystemExit("a recorded set matches this machine already: nothing to add")
        record.setdefault("machines", []).append({
            "why": args.why, "fingerprint": fingerprint(), "provenance": provenance.record(),
            "numbers": numbers,
        })  # fmt: skip
        PINNED.write_text(json.dumps(record, indent=1) + "\n")
        print(f"wrote {PINNED}: this machine's {len(numbers)} numbers beside the others")
        return
    old = json.loads(PINNED.read_text())["numbers"] if PINNED.exists() else {}
    moved = sorted(k for k in numbers if k not in old or not same(old[k], numbers[k]))
    record = {
        "what": __doc__.splitlines()[0],
        "case": str(CASE.relative_to(ROOT)),
        "overrides": OVERRIDES,
        "why": args.why,
        "moved": moved,
        "provenance": provenance.record(),
        "fingerprint": fingerprint(),
        "numbers": numbers,
    }
    PINNED.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {PINNED}: {len(numbers)} numbers, {len(moved)} moved")


if __name__ == "__main__":
    main()
