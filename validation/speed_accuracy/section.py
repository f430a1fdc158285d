"""Periodic-size and wall effects: the section's length and width, in grain lengths.

    .venv/bin/python validation/speed_accuracy/section.py

Length (periodic, along x) and width (between the side walls) are halved and doubled with the
grain count scaled by the floor area, so the bed keeps its depth. Grain length: a sphere's
diameter (4 mm), a screw's length (22 mm).
"""

from study import CASES, FILL_SEEDS, Point, default_points, load, main

FACTORS = (0.5, 2.0)


def points(case_name: str) -> list[Point]:
    case = load(Point("section", case_name, "base", "base"))
    t, pt = case.trough, case.particles
    grain = 2.0 * pt.radius if pt.shape == "sphere" else pt.length
    out = default_points("section", case_name, FILL_SEEDS[case_name])
    for f in FACTORS:
        n = int(round(pt.count * f))
        out.append(
            Point(
                "section",
                case_name,
                f"length {t.length * f / grain:.1f} grains",
                f"length x{f:g}",
                {"trough.length": t.length * f, "particles.count": n},
            )
        )
        out.append(
            Point(
                "section",
                case_name,
                f"width {t.width * f / grain:.1f} grains",
                f"width x{f:g}",
                {"trough.width": t.width * f, "particles.count": n},
            )
        )
    return out  # fmt: skip


POINTS = [p for case in CASES for p in points(case)]

if __name__ == "__main__":
    raise SystemExit(main("section", POINTS, "section length and width", __file__))
