"""Error against cost of the time step: dt as a fraction of the stability limit.

    .venv/bin/python validation/speed_accuracy/timestep.py

The automatic step is 0.3 of the limit that ``run.timestep`` is checked against; a step above
the limit is refused at load, so 1.0 is the largest a user can ask for.
"""

from study import CASES, FILL_SEEDS, Point, default_points, main

FRACTIONS = (0.1, 0.2, 0.6, 1.0)
#: The cheapest step, run with as many fills as the reference to resolve 2 %.
CHEAPEST = 1.0
POINTS = [
    p
    for case in CASES
    for p in default_points("timestep", case, FILL_SEEDS[case])
    + [
        Point("timestep", case, f"dt = {f:g} x limit", f, timestep_fraction=f, seed=s)
        for f in FRACTIONS
        for s in (FILL_SEEDS[case] if f == CHEAPEST else (1,))
    ]
]

if __name__ == "__main__":
    raise SystemExit(main("timestep", POINTS, "time step: dt / stability limit", __file__))
