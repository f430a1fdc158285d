"""Cost of the neighbour skin (the answer should not move: it changes when lists rebuild).

    .venv/bin/python validation/speed_accuracy/skin.py

Skin = fraction x the largest sphere radius (``dem.config.DEM_SKIN_FRACTION``, default 0.25).
A thin skin rebuilds the list often; a thick one keeps more pairs to test every step.
"""

from study import CASES, FILL_SEEDS, Point, default_points, main

FRACTIONS = (0.05, 0.1, 0.5, 1.0)
POINTS = [
    p
    for case in CASES
    for p in default_points("skin", case, FILL_SEEDS[case])
    + [Point("skin", case, f"skin = {f:g} r", f, skin_fraction=f) for f in FRACTIONS]
]

if __name__ == "__main__":
    raise SystemExit(main("skin", POINTS, "neighbour skin", __file__))
