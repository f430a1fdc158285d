"""Where the point mass's motion stops repeating: velocity against Gamma up to 10, eps_n 0/0.3/0.6.

Regenerates pointmass_bifurcation.csv and pointmass_bifurcation.png in this folder:

    .venv/bin/python validation/stability/pointmass_bifurcation.py      # about 10 s

The paper reports that "at Gamma >= 6.0 ... the experimental results became rather erratic" and
that bouncing (eps_n > 0) makes transport erratic. The point-mass model (dem.pointmass) follows
a grain from rest until its state at drive phase 0 repeats; an orbit that has not repeated
within the cycle limit is reported as non-periodic, with the spread of its mean velocity over
starting phases. This script sweeps Gamma in 0.1-10 (step 0.01) at phi = 25 deg, mu = 0.35,
eps_t = 0.8 (the paper's Fig. 6) for eps_n = 0, 0.3 and 0.6, and draws

- top: v / (A omega cos phi), with the range over starting phases where the motion does not
  repeat (a non-periodic window is a band, a periodic orbit a line);
- bottom: the orbit's period in drive cycles (0 = non-periodic), so period doubling and the
  windows of erratic motion show where the paper's "erratic" regime begins.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from dem import pointmass

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402

HERE = Path(__file__).resolve().parent
GAMMAS = np.round(np.arange(0.1, 10.0001, 0.01), 4)
ANGLE, FRICTION, EPS_T = 25.0, 0.35, 0.8
EPS_N = (0.0, 0.3, 0.6)


def sweep() -> list[dict]:
    """One row per (eps_n, Gamma): velocity, range over starts, periodic, period, regime."""
    rows = []
    for eps_n in EPS_N:
        r = pointmass.velocities(GAMMAS, ANGLE, FRICTION, 0.0, EPS_T, eps_n)
        for k, g in enumerate(GAMMAS):
            rows.append(
                {
                    "eps_n": eps_n,
                    "throw_number": float(g),
                    "velocity_norm": float(r["velocity_norm"][k]),
                    "velocity_min": float(r["velocity_min"][k]),
                    "velocity_max": float(r["velocity_max"][k]),
                    "periodic": bool(r["periodic"][k]),
                    "period": int(r["period"][k]),
                    "regime": pointmass.REGIMES[int(r["regime_code"][k])],
                }
            )
    return rows


def windows(rows: list[dict], eps_n: float) -> list[tuple[float, float]]:
    """Gamma intervals (first, last) of consecutive non-periodic points for one eps_n."""
    out: list[tuple[float, float]] = []
    for r in (r for r in rows if r["eps_n"] == eps_n):
        if r["periodic"]:
            continue
        g = r["throw_number"]
        if out and g - out[-1][1] < 0.011:
            out[-1] = (out[-1][0], g)
        else:
            out.append((g, g))
    return out


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True,
                             gridspec_kw={"height_ratios": [3, 1.4]})  # fmt: skip
    for eps_n, color in zip(EPS_N, ("k", "C0", "C3"), strict=True):
        sel = [r for r in rows if r["eps_n"] == eps_n]
        g = np.array([r["throw_number"] for r in sel])
        v = np.array([r["velocity_norm"] for r in sel])
        lo = np.array([r["velocity_min"] for r in sel])
        hi = np.array([r["velocity_max"] for r in sel])
        axes[0].plot(g, v, color=color, lw=0.8, label=f"eps_n = {eps_n}")
        axes[0].fill_between(g, lo, hi, color=color, alpha=0.25, lw=0)
        period = np.array([r["period"] for r in sel])
        axes[1].plot(g, period, ".", color=color, ms=2)
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].set_title(f"point mass, phi = {ANGLE:g} deg, mu = {FRICTION}, eps_t = {EPS_T} (band: "
                      "range over starting phases where the motion never repeats)",
                      fontsize=10)  # fmt: skip
    axes[0].legend(fontsize=8)
    axes[1].set_yscale("symlog", linthresh=4)
    axes[1].set_ylabel("period (cycles; 0: none)")
    axes[1].set_xlabel("throw number Gamma")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> int:
    rows = sweep()
    path = HERE / "pointmass_bifurcation.csv"
    with open(path, "w", newline="") as fh:
        cmd = "validation/stability/pointmass_bifurcation.py"
        header.write_csv_header(fh, cmd)
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, HERE / "pointmass_bifurcation.png")
    for eps_n in EPS_N:
        w = windows(rows, eps_n)
        share = sum(not r["periodic"] for r in rows if r["eps_n"] == eps_n) / len(GAMMAS)
        first = f"first at Gamma {w[0][0]:.2f}" if w else "none"
        print(f"eps_n = {eps_n}: {len(w)} non-periodic windows ({100 * share:.1f} % of the "
              f"grid), {first}: {', '.join(f'{a:.2f}-{b:.2f}' for a, b in w[:12])}")  # fmt: skip
    print(f"wrote {path} and pointmass_bifurcation.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
