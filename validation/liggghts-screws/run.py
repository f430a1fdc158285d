"""dem's rigid screws (clumps of spheres) against LIGGGHTS-PUBLIC 3.8 multisphere.

Regenerates results.json, impact.png and the decks under decks/ in this folder:

    .venv/bin/python validation/liggghts-screws/run.py                 # everything (~5 min)
    .venv/bin/python validation/liggghts-screws/run.py --part bulk     # part A only
    .venv/bin/python validation/liggghts-screws/run.py --part impact   # part B only
    .venv/bin/python validation/liggghts-screws/run.py --report-only   # table + impact.png

One simulation at a time, dem on one numba thread, LIGGGHTS on one rank (``liggghts -in
in.dem`` in a scratch copy of the deck). Run folders go to scratch/ (git-ignored).

Part A, bulk: ``cases/screw-trough`` (200 screws of 8 spheres, 2.5 g, Hertz E = 5e7 Pa,
mu = 0.35, 60 Hz, phi = 25 deg, Gamma = 1.8) with restitution_normal = 0.06 in both codes
(LIGGGHTS refuses e <= 0.05), 5 settle + 10 measured cycles, seeds 1, 2, 3, and rotation locked
(seed 1). The same explicit time step in both codes: dt = 1/5482 of the drive period
(3.0402529490453606e-06 s, dem's automatic step for this case at commit 425bb6c), and all four
runs again at 2 dt as a check. LIGGGHTS: ``write_deck(case, dir, timestep=dt,
steps=cycles/f/dt)``; the mean
x-velocity of the bodies' centres of mass is written to vx_mean.txt in windows of
1/(f frames_per_cycle) (absolute step multiples, not aligned to drive phase 0); the windows
after fill + settle (the first two ``run N`` of in.dem) are grouped in blocks of
frames_per_cycle = one drive period each, giving per-cycle means. dem: ``run_case`` (own fill
and settle), per-cycle means from its summary. Both: v = mean of the per-cycle means, standard
error the correlated standard error of the per-cycle means (validation/_lib/replicas.py).

Part B, single impacts: one body, no drive, static gravity, 0.15 s, Hertz e = 0.5, mu = 0.35,
periodic 0.06 m x 0.06 m section of the case's trough. LIGGGHTS inserts it with
``fix insert/pack`` (constant velocity, spin and orientation) into a 1 mm box; its state after
the first step is read back (``compute multisphere/single``, or x[1], vx[1] and
``property/atom omegax`` for a plain sphere) and dem starts from exactly that state; both are
then compared at the same times. Bodies: the screw of the case; a sphere r = 3.6 mm, 2.5 g as a
two-sphere clump (a 1 mm sphere inside it: LIGGGHTS multisphere needs >= 2 spheres); the same
sphere as a plain LIGGGHTS sphere (``nve/sphere``) against dem's plain sphere and dem's
one-sphere clump. Time steps 5e-7 s and 2e-6 s. ``replica_sphere`` integrates the plain
sphere once more in Python with the contact law of dem.kernels.contact and either lever arm of
a wall contact (dem: r - delta, LIGGGHTS: r - delta/2) to show where the plain-sphere
difference comes from.

The parts live beside this entry point: study.py (paths, results.json), bulk.py (part A),
impact_setup.py (part B's case, bodies and deck), impact.py (part B's runs), compare.py,
replica.py and report.py (tables, impact.png). Not part of the test suite.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numba
from bulk import part_bulk
from impact import part_impact
from report import plot, print_tables
from study import RESULTS, write_results

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("all", "bulk", "impact"), default="all")
    parser.add_argument("--report-only", action="store_true", help="tables + impact.png only")
    args = parser.parse_args(argv)
    # a full run starts results.json afresh; a partial run or --report-only updates it
    results = {}
    if RESULTS.exists() and (args.report_only or args.part != "all"):
        results = json.loads(RESULTS.read_text())
    if not args.report_only:
        numba.set_num_threads(1)
        t_start = time.perf_counter()
        results.update(header.results_header("validation/liggghts-screws/run.py", argv, dated=True))
        if args.part in ("all", "bulk"):
            part_bulk(results)
        if args.part in ("all", "impact"):
            part_impact(results)
        versions = {
            r["liggghts"]["version"]
            for p in ("bulk", "impact")
            for r in results.get(p, {}).get("runs", {}).values()
        }
        results["liggghts_version"] = sorted(v for v in versions if v)
        results[f"wall_time_s_part_{args.part}"] = time.perf_counter() - t_start
        write_results(results)
    print_tables(results)
    plot(results)


if __name__ == "__main__":
    main()
