"""Error against cost of the contact stiffness: Young's modulus 1e6 to 1e9 Pa (Hertz-Mindlin).

    .venv/bin/python validation/speed_accuracy/stiffness.py

The automatic step scales as E^(-2/5) (Hertz collision time) to E^(-1/2) (Rayleigh time), so a
softer grain is cheaper. Each modulus runs at the automatic step, and the softer ones also at the
largest step allowed (dt = the stability limit), the cheapest combination a user can ask for.
"""

from study import CASES, Point, default_points, main

MODULI = (1e6, 3e6, 1e7, 1e8, 1e9)
FAST = (1e6, 1e7)
POINTS = [
    p
    for case in CASES
    for p in default_points("stiffness", case)
    + [Point("stiffness", case, f"E = {e:.0e}", e, {"contact.youngs_modulus": e}) for e in MODULI]
    + [
        Point(
            "stiffness",
            case,
            f"E = {e:.0e}, dt = limit",
            e,
            {"contact.youngs_modulus": e},
            timestep_fraction=1.0,
        )
        for e in FAST
    ]  # fmt: skip
]

if __name__ == "__main__":
    raise SystemExit(main("stiffness", POINTS, "contact stiffness: Young's modulus", __file__))
