"""Part C: does the wall lever arm explain the bulk gap? dem with r - delta and r - delta/2.

LIGGGHTS 3.8 puts a wall contact's point halfway into the overlap (lever arm r - delta/2); dem
puts it on the wall (r - delta). The difference grows with the overlap, so with softness, as
the gap does (8-9 % at E = 5e7 Pa, 1.6 % at 5e8 Pa). This reruns dem on part A's cases at the
longer pinned step (P/2741, seeds 1-3, rotation free) with ``contact.wall_lever_arm`` =
"surface" and = "midpoint", and sets each beside part A's LIGGGHTS run of the same case
(results.json "bulk" "runs" "seed<N>_dt2x" "liggghts": not rerun). Young's modulus is taken
from that run's deck (decks/bulk_<tag>/in.dem, 5e7 Pa): cases/screw-trough has since moved to
5e8 Pa, and part A's other settings are pinned by bulk.bulk_cases.

    nice -n 10 .venv/bin/python validation/liggghts-screws/lever_arm.py

Writes results.json "lever_arm". One dem run at a time, one thread, about 25 s each.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import sys
from pathlib import Path

import numpy as np
from bulk import bulk_cases
from study import DECKS, RESULTS, SCRATCH, rel, write_results

from dem import provenance

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import pair, replicas  # noqa: E402

ARMS = ("surface", "midpoint")
TAGS = ("seed1_dt2x", "seed2_dt2x", "seed3_dt2x")
YOUNG_RE = re.compile(r"^fix m_Y all property/global youngsModulus peratomtype (\S+) ", re.M)


def deck_youngs_modulus(tag: str) -> float:
    """Young's modulus, Pa, of part A's LIGGGHTS deck for this case."""
    return float(YOUNG_RE.search((DECKS / f"bulk_{tag}" / "in.dem").read_text())[1])


def main() -> int:
    results = json.loads(RESULTS.read_text())
    runs = results["bulk"]["runs"]
    cases = bulk_cases()
    out = results["lever_arm"] = {"runs": {}}
    out.update(
        script="validation/liggghts-screws/lever_arm.py",
        git_commit=provenance.git_commit(),
        date=provenance.utc_now(),
    )
    for tag in TAGS:
        lig = runs[tag]["liggghts"]["mean_velocity"]
        for arm in ARMS:
            base = cases[tag]
            young = deck_youngs_modulus(tag)
            case = dataclasses.replace(
                base,
                contact=dataclasses.replace(base.contact, wall_lever_arm=arm, youngs_modulus=young),
            )
            work = SCRATCH / "dem" / f"lever_{arm}_{tag}"
            dem = pair.run_dem(case, work, threads=1)
            s, wall = dem.summary, dem.wall_s
            v, se = s["mean_velocity"], s["mean_velocity_stderr"]
            print(f"{tag} {arm:8s} v = {v:.5f} +- {se:.5f} m/s, LIGGGHTS {lig:.5f}: "
                  f"{100 * (v - lig) / lig:+.1f} % ({wall:.0f} s)", flush=True)  # fmt: skip
            out["runs"][f"{arm}_{tag}"] = {
                "wall_lever_arm": arm,
                "case_tag": tag,
                "youngs_modulus": young,
                "command": f"run_case(case, {rel(work)}, threads=1, progress=False, "
                "frames=False, overwrite=True)",
                "mean_velocity": v,
                "mean_velocity_stderr": se,
                "per_cycle_velocity": s["per_cycle_velocity"],
                "timestep": s["timestep"],
                "liggghts_mean_velocity": lig,
                "percent_of_liggghts": 100.0 * (v - lig) / lig,
                "wall_time_s": wall,
                "load_average": os.getloadavg()[0],
            }
            write_results(results)
    for arm in ARMS:
        rows = [out["runs"][f"{arm}_{t}"] for t in TAGS if f"{arm}_{t}" in out["runs"]]
        if len(rows) < 2:
            continue
        d = np.array([r["percent_of_liggghts"] for r in rows])
        out[f"pooled_{arm}"] = {
            "percent_of_liggghts": float(d.mean()),
            "seed_stderr_percent": replicas.replica_stderr(d),
            "seeds": len(rows),
        }
        print(arm, out[f"pooled_{arm}"])
    write_results(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
