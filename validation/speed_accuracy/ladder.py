"""The model ladder: point mass, one grain, the bed soft, shipped and stiff; cost and answer.

    .venv/bin/python validation/speed_accuracy/ladder.py

Each rung answers the same question, v / (A omega cos phi) at the case's drive and material:
the paper's point mass (dem.pointmass.velocity, event-driven), one DEM grain alone on the trough
(``particles.count = 1``), the bed at 5e7 Pa (the LIGGGHTS-parity stiffness,
validation/liggghts-bulk), the bed at its shipped settings (2e9 Pa, the base fills), and the
bed at 5e10 Pa (the stiffest point of validation/bulk-convergence). The error of every rung is
taken against the bed's rigid limit (study.py), so the table says how far down the ladder a
question can be answered. The 5e7 and 5e10 Pa rungs are validation/bulk-convergence's sweep
points (dt = 0.5 of the limit, their fills pooled); their cost is one fill's CPU time there.
"""

import math
import time

from study import (
    CASES,
    FILL_SEEDS,
    HERE,
    ROOT,
    TOLERANCE,
    Point,
    cached,
    default_points,
    ensure,
    print_table,
    reference,
    rigid_limit,
    support_points,
    table,
    write_csv,
)

from dem import pointmass
from dem.scene.case import load_case

POINTS = [
    p
    for case in CASES
    for p in [Point("ladder", case, "one grain", "one grain", {"particles.count": 1})]
    + default_points("ladder", case, FILL_SEEDS[case])
]
#: The bulk-convergence sweep points shown as rungs: Young's modulus, label.
SWEEP_RUNGS = ((5e7, "bed, 5e7 Pa (soft)"), (5e10, "bed, 5e10 Pa (stiffest)"))


def sweep_rows() -> list[dict]:
    """The soft and the stiff bed from validation/bulk-convergence, as ladder rows (each E's
    fills pooled with its extra fills, as the rigid-limit fit takes them)."""
    import stiffness

    out = []
    for name in CASES:
        ref = rigid_limit(name)
        swept = {r["x"]: r for r in stiffness.rows() if r["case"] == name}
        for e, label in SWEEP_RUNGS:
            r = swept[e]
            out.append(r | {"study": "ladder", "label": label, "x": label,
                            "speedup": math.nan, "particle_steps": math.nan,
                            "spheres": math.nan, "grains": math.nan})  # fmt: skip
            assert r["reference"] == ref["velocity_norm"]
    return out


def pointmass_rows(rows: dict) -> list[dict]:
    out = []
    for name in CASES:
        case = load_case(ROOT / "cases" / name)
        d, m = case.drive, case.material
        t0 = time.perf_counter()
        for _ in range(10):
            v = pointmass.velocity(throw_number=d.throw_number, angle=d.angle,
                                   friction=m.friction, inclination=case.trough.inclination,
                                   eps_t=m.restitution_tangential,
                                   eps_n=m.restitution_normal).velocity_norm  # fmt: skip
        wall = (time.perf_counter() - t0) / 10
        ref = reference(name, rows)
        err = v - ref.velocity_norm
        out.append({"case": name, "study": "ladder", "label": "point mass", "x": "point mass",
                    "seed": "", "fills": 0, "velocity_norm": v, "stderr": 0.0,
                    "reference": ref.velocity_norm, "error": err,
                    "relative_error": err / ref.velocity_norm, "error_uncertainty": ref.stderr,
                    "fill_spread": ref.fill_spread,
                    "acceptable": abs(err) <= TOLERANCE * ref.velocity_norm,
                    "wall_time_s": wall, "speedup": ref.wall_time_s / wall, "particle_steps": 0,
                    "spheres": 0, "grains": 1, "failed": ""})  # fmt: skip
    return out


def plot(rows: list[dict], path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for i, name in enumerate(CASES):
        sel = [r for r in rows if r["case"] == name]
        ax.errorbar([r["wall_time_s"] for r in sel], [r["velocity_norm"] for r in sel],
                    yerr=[r["stderr"] for r in sel], fmt="o-", color=f"C{i}", label=name,
                    capsize=2)  # fmt: skip
        for r in sel:
            ax.annotate(r["label"], (r["wall_time_s"], r["velocity_norm"]), fontsize=7,
                        xytext=(4, 3), textcoords="offset points")  # fmt: skip
        ax.axhline(sel[0]["reference"], color=f"C{i}", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_xlabel("wall time, s (DEM: one thread beside one busy process)")
    ax.set_ylabel("v / (A omega cos phi)")
    ax.set_title("model ladder (dotted: the bed's rigid limit)", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> int:
    import sys

    rows = cached() if "--figures" in sys.argv else ensure(support_points(CASES) + POINTS)
    bed = [r | {"label": "bed, shipped (2e9 Pa)"} if r["label"] == "base" else r
           for r in table(POINTS, rows)]  # fmt: skip
    out = pointmass_rows(rows) + bed + sweep_rows()
    out.sort(key=lambda r: (r["case"], r["wall_time_s"]))
    write_csv("ladder", out, __file__)
    plot(out, HERE / "ladder.png")
    print_table(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
