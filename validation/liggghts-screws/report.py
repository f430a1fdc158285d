"""The tables printed after a run (or with --report-only), and impact.png."""

from __future__ import annotations

import numpy as np
from compare import flight_segments
from impact_setup import BODIES, IMPACT_DT
from study import HERE, SCRATCH, rel


def print_tables(results: dict) -> None:
    bulk = results.get("bulk", {}).get("runs", {})
    if bulk:
        print("\nbulk | v LIGGGHTS | v dem | dem - L (%) | sigma | v_norm | pointmass norm")
        for tag, r in bulk.items():
            lg, dm, df = r["liggghts"], r["dem"], r["dem_minus_liggghts"]
            print(f"{tag} | {lg['mean_velocity']:.4f} +- {lg['mean_velocity_stderr']:.4f} | "
                  f"{dm['mean_velocity']:.4f} +- {dm['mean_velocity_stderr']:.4f} | "
                  f"{df['percent']:+.1f} | {df['sigma']:+.1f} | {r['v_norm']:.4f} | "
                  f"{r['pointmass_velocity_norm']:.3f}")  # fmt: skip
    runs = results.get("impact", {}).get("runs", {})
    if runs:
        print("\nimpact | dem variant | k | t | vx L | vx dem | dvx % | |dv|/|v| % | "
              "|dw|/|w| % | wz L | wz dem")  # fmt: skip
        for key, r in runs.items():
            for name, d in r["dem"].items():
                for a in d["after_impact"]:
                    print(f"{key} | {name} | {a['impact']} | {a['t']:.4f} | "
                          f"{a['v_liggghts'][0]:.5f} | {a['v_dem'][0]:.5f} | "
                          f"{a['vx_rel_percent']:+.2f} | {a['v_rel_percent']:.2f} | "
                          f"{a['omega_rel_percent']:.2f} | {a['omega_liggghts'][2]:.4f} | "
                          f"{a['omega_dem'][2]:.4f}")  # fmt: skip


def plot(results: dict) -> None:
    """impact.png: per body vx(t), omega(t) of both codes and dem - LIGGGHTS, dt = 5e-7 s."""
    path = SCRATCH / "impact_trajectories.npz"
    if not path.exists():
        print(f"no {rel(path)}: run --part impact first; impact.png not drawn")
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    store = np.load(path)
    tag = f"dt{IMPACT_DT[0]:g}"
    titles = {
        "screw": "screw (8-sphere clump)",
        "sphere_clump": "sphere r = 3.6 mm as a 2-sphere clump",
        "sphere_plain": "plain sphere r = 3.6 mm",
    }
    main_dem = {"screw": "dem", "sphere_clump": "dem", "sphere_plain": "dem_sphere"}
    fig, axes = plt.subplots(3, 4, figsize=(18, 10), sharex=True)
    for row, body in enumerate(BODIES):
        lig = store[f"{tag}/{body}/liggghts"]
        dem = store[f"{tag}/{body}/{main_dem[body]}"]
        t = 1e3 * lig[:, 0]
        flying = np.zeros(len(lig), dtype=bool)  # rows in free flight (LIGGGHTS): for y limits
        for first, last in flight_segments(lig):
            flying[first : last + 1] = True
        ax, bx, cx, dx = axes[row]
        ax.plot(t, lig[:, 4], "-", color="C1", lw=2.0, label="LIGGGHTS $v_x$")
        ax.plot(t, dem[:, 4], "--", color="C0", lw=1.3, label="dem $v_x$")
        ax.set_ylabel("$v_x$ (m/s)")
        ax.set_title(titles[body], fontsize=10, loc="left")
        az = ax.twinx()
        az.plot(t, 1e3 * lig[:, 3], color="0.6", lw=0.8, label="z (LIGGGHTS)")
        az.set_ylabel("centre height z (mm)", color="0.5")
        lines = ax.get_legend_handles_labels()
        lines2 = az.get_legend_handles_labels()
        ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=7, loc="upper right")
        for k, comp in enumerate("xyz"):
            bx.plot(t, lig[:, 7 + k], "-", color=f"C{k + 2}", lw=2.0,
                    label=f"LIGGGHTS $\\omega_{comp}$")  # fmt: skip
            bx.plot(t, dem[:, 7 + k], "--", color="k", lw=0.9,
                    label="dem" if k == 0 else None)  # fmt: skip
        bx.set_ylabel(r"$\omega$ (rad/s)")
        bx.legend(fontsize=7, ncol=2, loc="best")
        variants = [(main_dem[body], "-", "C0", "dem")]
        if body != "sphere_plain":
            variants.append(("dem_liggghts_members", "-", "C3", "dem, LIGGGHTS's member offsets"))
        else:
            variants.append(("replica_liggghts", ":", "C3", "Python replica, lever r - delta/2"))
        lim_v, lim_w = [0.0], [0.0]
        for name, style, color, label in variants:
            d = store[f"{tag}/{body}/{name}"]
            dv = 100.0 * (d[:, 4] - lig[:, 4]) / np.abs(lig[:, 4])
            dw = d[:, 9] - lig[:, 9]
            cx.plot(t, dv, style, color=color, lw=1.2, label=label)
            dx.plot(t, dw, style, color=color, lw=1.2, label=label)
            lim_v += [dv[flying].min(), dv[flying].max()]
            lim_w += [dw[flying].min(), dw[flying].max()]
        for axis, lim in ((cx, lim_v), (dx, lim_w)):
            lo, hi = min(lim), max(lim)
            pad = 0.3 * (hi - lo) or 0.01
            axis.set_ylim(lo - pad, hi + pad)
            axis.axhline(0.0, color="k", lw=0.6)
            axis.legend(fontsize=7, loc="lower left")
        cx.set_ylabel("dem - LIGGGHTS: $v_x$ (% of LIGGGHTS)", fontsize=8)
        dx.set_ylabel(r"dem - LIGGGHTS: $\omega_z$ (rad/s)", fontsize=8)
    axes[0, 2].set_title("(clipped to the free-flight range; spikes: contacts)", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t (ms)")
    fig.suptitle(
        "One body dropped on the floor (e = 0.5, mu = 0.35, Hertz E = 5e7 Pa), dem started from "
        f"LIGGGHTS's state after its first step; dt = {IMPACT_DT[0]:g} s",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(HERE / "impact.png", dpi=110)
    print(f"wrote {rel(HERE / 'impact.png')}")
