"""Error against cost of the contact stiffness: Young's modulus 5e7 to 5e10 Pa (Hertz-Mindlin).

    .venv/bin/python validation/speed_accuracy/stiffness.py

No runs of its own: the points are validation/bulk-convergence's stiffness sweep (both beds,
the default tangential law, dt = 0.5 of the stability limit, 3 fills per modulus, 8 at the
screws' stiff points), their error against the bed's rigid limit and their cost, one fill's
CPU time. The step scales as E^(-2/5) (Hertz collision time), so a softer grain is cheaper;
below 2e9 Pa it is also wrong by more than 2 % (validation/bulk-convergence/README.md).
"""

import math

from study import CASES, HERE, ROOT, TOLERANCE, plot, print_table, rigid_limit, write_csv

POINTS: list = []  # nothing to run
#: dt over the stability limit of every point of the sweep (validation/bulk-convergence).
SWEEP_TIMESTEP_FRACTION = 0.5


def rows() -> list[dict]:
    """One row per bed and modulus, in the study's table form."""
    import json

    data = json.loads((ROOT / "dem" / "data" / "stiffness_convergence.json").read_text())
    out = []
    for case in CASES:
        ref = rigid_limit(case)
        rows = [r for r in data["rows"] if r["bed"] == case]
        cost = {r["youngs_modulus_pa"]: r["cpu_s_per_fill"] for r in rows}
        for r in rows:
            e = r["youngs_modulus_pa"]
            err, unc = (
                r["error_vs_rigid"],
                math.hypot(r["error_stderr"], ref["stderr_norm"] / ref["velocity_norm"]),
            )
            v_ref = ref["velocity_norm"]
            out.append({
                "case": case, "study": "stiffness", "label": f"E = {e:.0e}", "x": e,
                "fills": r["fills"], "seed": "", "reference": v_ref, "fill_spread": math.nan,
                "velocity_norm": v_ref * (1.0 + err), "stderr": r["error_stderr"] * v_ref,
                "error": err * v_ref, "relative_error": err, "error_uncertainty": unc * v_ref,
                "acceptable": abs(err) <= TOLERANCE and abs(err) <= 2.0 * unc,
                "compliance": r["compliance"], "bed_mode_hz": r["bed_mode_hz"],
                "wall_time_s": cost[e], "speedup": cost[2e9] / cost[e], "failed": "",
            })  # fmt: skip
    return out


def main() -> int:
    out = rows()
    write_csv("stiffness", out, __file__)
    plot(out, HERE / "stiffness.png", "contact stiffness: Young's modulus (bulk-convergence sweep)")
    print_table(out)
    print("wrote stiffness.csv and stiffness.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
