"""One grain's error against the rigid point mass, against its contact's compliance.

A lone block (cases/single-sphere, rotation locked, Hertz, eps_n = 0, the default tangential
law) at sliding drives (Gamma < 1), level and uphill near the sliding threshold, at four Young's
moduli; each run against the Coulomb-bounded point mass. The contact's compliance against the
drive is c = (omega / omega_c)^2 (:func:`dem.run.stiffness.bed_mode`: one layer, the Hertz
contact's tangent stiffness under the grain's weight); the script records the error of v_norm
against c, from which ``dem plan`` and the summary take the single grain's warning
(:data:`dem.run.stiffness.SINGLE_GRAIN_ERROR_PER_COMPLIANCE`).

    .venv/bin/python validation/single-grain-stiffness/run.py          # 28 runs, ~2 min
    .venv/bin/python validation/single-grain-stiffness/run.py figure   # redraw error.png
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from dem import pointmass  # noqa: E402
from dem.run.runner import run_case  # noqa: E402
from dem.run.stiffness import bed_mode  # noqa: E402
from dem.scene.case import load_case  # noqa: E402
from dem.scene.resolved import resolve  # noqa: E402
from validation._lib.header import results_header  # noqa: E402
from validation._lib.tables import write_rows  # noqa: E402

CASE = HERE.parents[1] / "cases" / "single-sphere"
#: (Gamma, phi deg, mu, alpha deg): level sliding drives, and uphill near the threshold (the
#: first uphill one is the hardening check's: point mass 0.174).
DRIVES = [(0.8, 35, 0.35, 0.0), (0.5, 20, 0.35, 0.0), (0.9, 25, 0.35, 0.0), (0.45, 40, 0.35, 0.0),
          (0.6, 25, 0.6, 0.0), (0.35, 30, 0.2, 0.0), (0.8, 35, 0.35, 4.4)]  # fmt: skip
MODULI = (5e7, 5e8, 2e9, 2e10)


def main() -> None:
    rows = []
    started = time.time()
    for youngs in MODULI:
        for gamma, phi, mu, alpha in DRIVES:
            case = load_case(CASE, {
                "contact.model": "hertz_mindlin", "contact.stiffness": None,
                "contact.youngs_modulus": youngs, "drive.throw_number": gamma,
                "drive.angle": float(phi), "material.friction": mu,
                "trough.inclination": alpha, "run.settle_cycles": "auto", "run.cycles": 10,
            })  # fmt: skip
            c = bed_mode(resolve(case)).compliance
            s = run_case(case, HERE / "scratch" / f"E{youngs:g}_{gamma}_{phi}_{mu}_{alpha}",
                         overwrite=True, progress=False, frames=False, threads=1)  # fmt: skip
            pm = pointmass.velocity(gamma, phi, mu, alpha, impact="coulomb").velocity_norm
            dem_v = s["mean_velocity_norm"]
            rows.append({
                "youngs_modulus_pa": youngs, "throw_number": gamma, "angle_deg": phi,
                "friction": mu, "inclination_deg": alpha, "compliance": c,
                "dem_velocity_norm": dem_v, "dem_stderr": s["mean_velocity_norm_stderr"],
                "pointmass_bounded": pm, "error": dem_v - pm, "relative_error": dem_v / pm - 1,
                "error_per_compliance": (dem_v - pm) / c, "settle_cycles": s["settle_cycles"],
            })  # fmt: skip
            print(json.dumps(rows[-1]), flush=True)
    write_rows(HERE / "results.csv", rows)
    worst = max(abs(r["error_per_compliance"]) for r in rows)
    doc = results_header("validation/single-grain-stiffness/run.py", dated=True)
    doc |= {"wall_time_s": time.time() - started, "worst_error_per_compliance": worst,
            "rows": rows}  # fmt: skip
    (HERE / "results.json").write_text(json.dumps(doc, indent=1) + "\n")
    print(f"worst |v_DEM - v_pm| / c = {worst:.3f}")
    figure()


def figure() -> None:
    """error.png: |v_DEM - v_rigid| against c, each drive a line, with the rule K c."""
    import numpy as np

    from dem.run.stiffness import SINGLE_GRAIN_ERROR_PER_COMPLIANCE as K
    from dem.studies import plots

    rows = json.loads((HERE / "results.json").read_text())["rows"]
    fig, ax = plots.plt.subplots(figsize=(6.4, 4.4))
    drives = sorted({(r["throw_number"], r["angle_deg"], r["friction"], r["inclination_deg"])
                     for r in rows})  # fmt: skip
    for g, phi, mu, alpha in drives:
        mine = [r for r in rows if (r["throw_number"], r["angle_deg"], r["friction"],
                                    r["inclination_deg"]) == (g, phi, mu, alpha)]  # fmt: skip
        mine.sort(key=lambda r: r["compliance"])
        ax.loglog([r["compliance"] for r in mine], [abs(r["error"]) for r in mine], "o-",
                  label=f"Gamma {g}, phi {phi}, mu {mu}, alpha {alpha}")  # fmt: skip
    c = np.geomspace(1e-4, 2e-2, 50)
    ax.loglog(c, K * c, "k--", label=f"the rule: {K:g} c")
    ax.set_xlabel("compliance c = (omega / omega_c)^2 (-)")
    ax.set_ylabel("|v_norm(DEM) - v_norm(point mass)| (-)")
    plots.set_title(ax, "One block (rotation locked, Hertz, eps_n 0) at sliding drives, "
                    "E = 5e7, 5e8, 2e9, 2e10 Pa: error against the rigid point mass")  # fmt: skip
    ax.legend(fontsize=7)
    plots.save(fig, HERE / "error.png")


if __name__ == "__main__":
    figure() if sys.argv[1:] == ["figure"] else main()
