"""The converged reference of each shipped case and the fill-to-fill spread.

    .venv/bin/python validation/speed_accuracy/reference.py   # about 10 min on 2 cores

Fills at the reference settings (Young's modulus 5e8 Pa, ten times the shipped value;
dt = 0.15 of the stability limit, half the automatic step there) and as many at the shipped
settings: seeds 1-3 for the sphere bed, 1-6 for the screws, whose fill-to-fill spread is
larger. Every other study measures its error against the mean of the reference fills
(study.py).
"""

from study import CASES, FILL_SEEDS, default_points, main, reference_points

POINTS = [
    p
    for case in CASES
    for p in reference_points("reference", case)
    + default_points("reference", case, FILL_SEEDS[case])
]
POINTS = [p.__class__(**{**p.__dict__, "label": f"{p.label} seed {p.seed}"}) for p in POINTS]

if __name__ == "__main__":
    raise SystemExit(main("reference", POINTS, "reference and shipped fills", __file__))
