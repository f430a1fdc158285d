"""Error against cost of the time step: dt as a fraction of the stability limit.

    .venv/bin/python validation/speed_accuracy/timestep.py

The base (the shipped cases) is dt = 4.0e-6 s, 0.82-0.84 of the limit that ``run.timestep`` is
checked against; the automatic step is 0.3 of it; a step above the limit is refused at load,
so 1.0 is the largest a user can ask for.
"""

from study import CASES, FILL_SEEDS, Point, default_points, main

FRACTIONS = (0.15, 0.3, 0.5, 1.0)
#: Run with as many fills as the base, to resolve 1-2 %: the cheapest step, and the step of
#: validation/bulk-convergence's stiffness sweep (0.5), which ``dem plan`` adds the step's
#: effect to (the effect of a step against 0.5 is its effect here minus that of 0.5).
FILLED = (0.5, 1.0)
POINTS = [
    p
    for case in CASES
    for p in default_points("timestep", case, FILL_SEEDS[case])
    + [
        Point("timestep", case, f"dt = {f:g} x limit", f, timestep_fraction=f, seed=s)
        for f in FRACTIONS
        for s in (FILL_SEEDS[case] if f in FILLED else (1,))
    ]
]

if __name__ == "__main__":
    raise SystemExit(main("timestep", POINTS, "time step: dt / stability limit", __file__))
