"""Part D0: 300 measured cycles of part A's seed-1 case in both codes, each from its own fill.

Part A measured 10 cycles. Over 300 the per-cycle means of both codes wander by several per
cent over tens of cycles, and dem's rises from its fill's value towards LIGGGHTS's: the bulk
velocity remembers the bed it started from. Part A's case (seed 1, P/2741, E from part A's deck)
with ``cycles`` measured cycles:

    nice -n 10 .venv/bin/python validation/liggghts-screws/long_run.py [cycles]   # ~4 min for 300

Writes results.json "long_run" (per-cycle velocities of both codes and means of blocks of 10).
The run recorded there used LIGGGHTS's template orientation (part A's deck, before the export
inserted clumps at random orientations): see README.md, part D.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys

import numpy as np
from bulk import bulk_cases, bulk_dem, bulk_liggghts
from lever_arm import deck_youngs_modulus
from study import RESULTS, write_results

from dem import provenance

TAG = "seed1_dt2x"


def main() -> int:
    cycles = int(sys.argv[1]) if len(sys.argv) > 1 else 300
    base = bulk_cases()[TAG]
    case = dataclasses.replace(
        base,
        contact=dataclasses.replace(base.contact, youngs_modulus=deck_youngs_modulus(TAG)),
        run=dataclasses.replace(base.run, cycles=cycles),
    )
    results = json.loads(RESULTS.read_text())
    out = results["long_run"] = {
        "script": "validation/liggghts-screws/long_run.py",
        "git_commit": provenance.git_commit(),
        "date": provenance.utc_now(),
        "case_tag": TAG,
        "cycles": cycles,
        "load_average_start": os.getloadavg()[0],
    }
    out["dem"] = bulk_dem(case, f"drift_{TAG}_{cycles}")
    out["liggghts"] = bulk_liggghts(case, f"drift_{TAG}_{cycles}", case.run.timestep)
    for key in ("liggghts", "dem"):
        v = np.array(out[key]["per_cycle_velocity"])
        blocks = v[: v.size // 10 * 10].reshape(-1, 10).mean(axis=1)
        out[key]["blocks_of_10"] = [float(b) for b in blocks]
        print(key, " ".join(f"{b:.4f}" for b in blocks), flush=True)
    out["load_average_end"] = os.getloadavg()[0]
    write_results(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
