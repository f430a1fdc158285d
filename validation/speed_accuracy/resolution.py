"""Grain resolution of the screw: spheres per screw (``particles.max_bumpiness``).

    .venv/bin/python validation/speed_accuracy/resolution.py

The shank is a row of overlapping spheres whose valleys are at most b x the shank radius deep;
b = 1 (touching spheres) gives 6 spheres per screw, the shipped 0.25 gives 8, 0.05 gives 15.
The mass (2.5 g) and the head stay; the inertia follows the union of the spheres.
"""

from study import FILL_SEEDS, Point, default_points, main

BUMPINESS = (1.0, 0.5, 0.1, 0.05)
SPHERES = {1.0: 6, 0.5: 7, 0.25: 8, 0.1: 11, 0.05: 15}
POINTS = default_points("resolution", "screw-trough", FILL_SEEDS["screw-trough"]) + [
    Point("resolution", "screw-trough", f"{SPHERES[b]} spheres (b = {b:g})", SPHERES[b],
          {"particles.max_bumpiness": b})
    for b in BUMPINESS
]  # fmt: skip

if __name__ == "__main__":
    raise SystemExit(main("resolution", POINTS, "spheres per screw", __file__))
