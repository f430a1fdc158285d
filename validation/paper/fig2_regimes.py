"""Fig. 2: the regime map for mu = 0.75, alpha = 2.5 deg, the limits of Eqs. (1), (2), (4)
over the regimes the point-mass model simulates (fig2_regimes.csv, fig2_regimes.png).
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from csv_output import write_csv  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap  # noqa: E402

from dem.pointmass import REGIMES, thresholds  # noqa: E402
from dem.pointmass.sweep import sweep  # noqa: E402

FIG2 = {"friction": 0.75, "inclination": 2.5}


def backward_upper_branch(angle, friction, inclination):
    """Backward sliding near the top of the cycle when cot(phi) < mu (not in the paper).

    Stick needs |m a_x + m g sin(a)| <= mu N. With cot(phi) < mu the friction limit is
    exceeded backwards where the normal force is small (trough near its upper limit) once
    Gamma > (mu - tan a) / (mu - cot phi); this is below the flight limit 1 only when
    phi > 90 deg - alpha. Eq. (2) (and dem.pointmass.thresholds) say "never" there.
    Returns the limit, or nan where it does not apply.
    """
    cot_phi = 1.0 / np.tan(np.radians(angle))
    tan_a = math.tan(math.radians(inclination))
    with np.errstate(divide="ignore", invalid="ignore"):
        value = (friction - tan_a) / (friction - cot_phi)
    return np.where(cot_phi < friction, value, np.nan)


def expected_regime(gamma, angle, friction, inclination):
    """Regime code predicted by the limits alone (any hopping code for Gamma > 1).

    Eqs. (1), (2), (4), plus the upper branch of backward sliding where cot(phi) < mu.
    """
    t = thresholds(angle, friction, inclination)
    if gamma > t.flight:
        return -1  # any hopping code
    forward = gamma > t.forward_sliding
    upper = float(backward_upper_branch(angle, friction, inclination))
    backward = (t.backward_sliding is not None and gamma > t.backward_sliding) or (
        not math.isnan(upper) and gamma > upper
    )
    if forward and backward:
        return REGIMES.index("forward and backward sliding")
    if forward:
        return REGIMES.index("forward sliding")
    if backward:
        return REGIMES.index("backward sliding")
    return REGIMES.index("rest")


def fig2(g: dict, out: Path, meta: dict) -> dict:
    """Regime map for mu = 0.75, alpha = 2.5 deg: Eqs. (1), (2), (4) over simulated regimes."""
    mu, alpha = FIG2["friction"], FIG2["inclination"]
    angle, gamma = g["fig2_angle"], g["fig2_gamma"]
    r = sweep(gamma, angle, mu, alpha)
    code = r["regime_code"].reshape(gamma.size, angle.size)
    fwd = np.array([thresholds(a, mu, alpha).forward_sliding for a in angle])
    bwd = np.array(
        [np.nan if (b := thresholds(a, mu, alpha).backward_sliding) is None else b for a in angle]
    )
    upper = backward_upper_branch(angle, mu, alpha)
    # agreement away from the limit curves (a band of 2% in Gamma around each)
    hopping = {REGIMES.index("hopping"), REGIMES.index("hopping with backward sliding")}
    agree = total = 0
    mismatches = []
    for i, gi in enumerate(gamma):
        for j, aj in enumerate(angle):
            limits = [fwd[j], 1.0] + [b for b in (bwd[j], upper[j]) if not np.isnan(b)]
            if any(abs(gi - lim) < 0.02 * max(lim, 0.05) for lim in limits):
                continue
            want = expected_regime(gi, aj, mu, alpha)
            ok = (code[i, j] in hopping) if want == -1 else (code[i, j] == want)
            total += 1
            agree += ok
            if not ok and len(mismatches) < 10:
                mismatches.append(
                    {"throw_number": float(gi), "angle": float(aj), "simulated": int(code[i, j])}
                )
    eq2_only = 0  # points that disagree when the upper branch is left out
    for i, gi in enumerate(gamma):
        for j in np.flatnonzero(~np.isnan(upper) & (upper < 1.0)):
            if upper[j] < gi < 1.0 and code[i, j] == REGIMES.index("backward sliding"):
                eq2_only += 1
    summary = {
        "grid_points": int(code.size),
        "backward_sliding_beyond_eq2": eq2_only,
        "upper_branch_below_flight_from_angle": (
            float(angle[np.argmax(upper < 1.0)]) if np.any(upper < 1.0) else None
        ),
        "compared_outside_2pct_bands": total,
        "agreeing": int(agree),
        "first_mismatches": mismatches,
        "paper_example_phi25": {
            "forward_sliding": thresholds(25.0, mu, alpha).forward_sliding,
            "backward_sliding": thresholds(25.0, mu, alpha).backward_sliding,
        },
        "non_periodic_points": int((~r["periodic"]).sum()),
    }
    write_csv(
        out / "fig2_regimes.csv",
        {
            "throw_number": r["throw_number"],
            "angle": r["angle"],
            "regime_code": r["regime_code"],
            "velocity_norm": r["velocity_norm"],
            "slide_backward": r["slide_backward"],
            "flight": r["flight"],
        },
        meta,
        {
            "friction": mu,
            "inclination": alpha,
            "eps_t": 0.8,
            "eps_n": 0.0,
            "regime_code": dict(enumerate(REGIMES)),
        },
    )

    colours = ["#f0f0f0", "#a6cee3", "#fdbf6f", "#fb9a99", "#b2df8a", "#33a02c", "#6a3d9a"]
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(-0.5, len(REGIMES) + 0.5), cmap.N)
    fig, ax = plt.subplots(figsize=(9.0, 5.0), dpi=130)
    ax.pcolormesh(angle, gamma, code, cmap=cmap, norm=norm, shading="nearest")
    ax.plot(angle, fwd, "k-", lw=1.8, label="Eq. (1) forward sliding")
    ax.plot(angle, bwd, "k--", lw=1.8, label="Eq. (2) backward sliding")
    ax.axhline(1.0, color="k", ls=":", lw=1.8, label="Eq. (4) flight, Gamma = 1")
    ax.plot(
        angle,
        np.where(upper <= 1.0, upper, np.nan),  # above 1 the grain flies near the top
        "-.",
        color="C3",
        lw=1.5,
        label="backward sliding, cot(phi) < mu branch (not in Eq. 2), phi > 87.5",
    )
    for k, name in enumerate(REGIMES):
        ax.plot([], [], "s", ms=9, color=colours[k], mec="0.5", label=f"simulated: {name}")
    ax.set_xlim(angle[0], angle[-1])
    ax.set_ylim(0.0, gamma[-1])
    ax.set_xlabel("vibration angle phi (deg)")
    ax.set_ylabel("throw number Gamma = A omega^2 sin(phi) / (g cos(alpha))")
    ax.set_title(
        f"Fig. 2: regimes, mu = {mu}, alpha = {alpha} deg (eps_t = 0.8, eps_n = 0)", fontsize=9
    )
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out / "fig2_regimes.png")
    plt.close(fig)
    return summary
