"""The base fills of each shipped case against its rigid limit; the fill-to-fill spread.

    .venv/bin/python validation/speed_accuracy/reference.py   # about 5 min on 2 cores

Fills at the base settings (the shipped cases: Young's modulus 2e9 Pa, dt = 4.0e-6 s): seeds
1-4 for the sphere bed, 1-8 for the screws, whose fill-to-fill spread is larger. Every study
measures its error against the bed's rigid limit (validation/bulk-convergence) and its effect
against the mean of these fills (study.py).
"""

from study import CASES, FILL_SEEDS, default_points, main

POINTS = [p for case in CASES for p in default_points("reference", case, FILL_SEEDS[case])]
POINTS = [p.__class__(**{**p.__dict__, "label": f"{p.label} seed {p.seed}"}) for p in POINTS]

if __name__ == "__main__":
    raise SystemExit(main("reference", POINTS, "shipped fills against the rigid limit", __file__))
