"""Error against cost of the contact stiffness: Young's modulus 1e6 to 1e9 Pa (Hertz-Mindlin).

    .venv/bin/python validation/speed_accuracy/stiffness.py

The automatic step scales as E^(-2/5) (Hertz collision time) to E^(-1/2) (Rayleigh time), so a
softer grain is cheaper. Each modulus runs at the automatic step, and the softer ones also at the
largest step allowed (dt = the stability limit), the cheapest combination a user can ask for.
"""

from study import CASES, FILL_SEEDS, Point, default_points, main

MODULI = (1e6, 3e6, 1e7, 1e8, 2e8, 3e8, 1e9, 2e9)
FAST = (1e6, 1e7, 5e8)
#: Fills per modulus: the screws' fill-to-fill spread (2.7 %) needs three to resolve 2 %.
SEEDS = {"sphere-bed": (1,), "screw-trough": (1, 2, 3)}


def points(case: str) -> list[Point]:
    out = default_points("stiffness", case, FILL_SEEDS[case])
    for e in MODULI:
        for s in SEEDS[case] if e >= 1e8 else (1,):
            out.append(Point("stiffness", case, f"E = {e:.0e}", e,
                             {"contact.youngs_modulus": e}, seed=s))  # fmt: skip
    for e in FAST:
        for s in FILL_SEEDS[case] if e == 5e8 else (1,):
            out.append(Point("stiffness", case, f"E = {e:.0e}, dt = limit", e,
                             {"contact.youngs_modulus": e}, timestep_fraction=1.0,
                             seed=s))  # fmt: skip
    return out


POINTS = [p for case in CASES for p in points(case)]

if __name__ == "__main__":
    raise SystemExit(main("stiffness", POINTS, "contact stiffness: Young's modulus", __file__))
