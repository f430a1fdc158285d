"""Matplotlib figures (Agg backend, PNG files); no computation here."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def _save(fig, path: str | Path) -> Path:
    """Lay out, write and close a figure; returns the path."""
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


def optimum_figure(opt, path: str | Path) -> Path:
    """Plot the scanned objective of an :class:`dem.pointmass.sweep.Optimum` and mark the best."""
    x = opt.curve[opt.over]
    y = opt.curve[opt.objective]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(x, y, color="C0")
    best = opt.velocity_norm if opt.objective == "velocity_norm" else opt.velocity
    ax.plot([opt.value], [best], "o", color="C3", label=f"optimum {opt.value:.3g}")
    ax.axvspan(*opt.plateau, color="C0", alpha=0.12, label="within 90%")
    ax.set_xlabel("vibration angle phi (deg)" if opt.over == "angle" else "throw number Gamma")
    ax.set_ylabel("v / (A omega cos phi)" if opt.objective == "velocity_norm" else "v (m/s)")
    held = ", ".join(
        f"{k}={v:g}" if isinstance(v, int | float) else f"{k}={v}" for k, v in opt.held.items()
    )
    ax.set_title(f"holding {opt.hold}: {held}", fontsize=8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def velocity_cycles_figure(
    cycle,
    velocity,
    running_mean,
    running_stderr,
    path: str | Path,
    *,
    measured=None,
    title: str = "",
) -> Path:
    """Per-cycle mean x-velocity (m/s) with its running mean and +-1 standard-error band.

    Args:
        cycle: Cycle numbers, (C,).
        velocity: Mass-weighted mean x-velocity of each cycle, (C,), m/s.
        running_mean: Running mean over the measured cycles so far, (C,), m/s (nan where none).
        running_stderr: Its standard error, (C,), m/s (nan with fewer than two cycles).
        path: PNG file.
        measured: Boolean mask (C,) of measured cycles; settling cycles are drawn grey.
        title: Figure title.

    """
    import numpy as np

    cycle = np.asarray(cycle)
    velocity = np.asarray(velocity)
    measured = np.ones(cycle.shape, bool) if measured is None else np.asarray(measured, bool)
    m, s = np.asarray(running_mean), np.asarray(running_stderr)
    fig, ax = plt.subplots(figsize=(6.5, 4), dpi=120)
    if np.any(~measured):
        ax.plot(cycle[~measured], velocity[~measured], "o", ms=3, color="0.6", label="settling")
    ax.plot(cycle[measured], velocity[measured], "o-", ms=3, lw=0.8, color="C0", label="cycle")
    ax.plot(cycle, m, color="C3", label="running mean")
    ax.fill_between(cycle, m - s, m + s, color="C3", alpha=0.2, label="+-1 standard error")
    ax.set_xlabel("drive cycle")
    ax.set_ylabel("mean x-velocity v (m/s)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def discharge_figure(
    time, rate, mass_in_trough, path: str | Path, *, measured=None, steady=None, steady_err=None,
    feed_rate=None, title: str = "",
) -> Path:  # fmt: skip
    """A finite feeder's discharge rate per drive cycle (kg/s) and the mass in the trough.

    Args:
        time: Drive time at the end of each cycle, (C,), s.
        rate: Mass discharged in the cycle over its period, (C,), kg/s.
        mass_in_trough: Grain mass in the trough at the end of each cycle, (C,), kg.
        path: PNG file.
        measured: Boolean mask (C,) of measured cycles; settling cycles are drawn grey.
        steady, steady_err: The steady rate over the measured cycles and its standard error,
            kg/s (a line and a band).
        feed_rate: The feed, kg/s (a dashed line; None or 0: no feed).
        title: Figure title.

    """
    import numpy as np

    time, rate = np.asarray(time), np.asarray(rate)
    measured = np.ones(time.shape, bool) if measured is None else np.asarray(measured, bool)
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(6.5, 5.5), dpi=120, sharex=True)
    if np.any(~measured):
        ax.step(time[~measured], rate[~measured], where="pre", color="0.6", label="settling")
    ax.step(time[measured], rate[measured], where="pre", color="C0", lw=0.6, alpha=0.5,
            label="per cycle")  # fmt: skip
    window = min(10, max(1, rate.size // 5))
    if window > 1:  # a few grains a cycle: the moving mean shows the trend
        smooth = np.convolve(rate, np.ones(window) / window, mode="valid")
        ax.plot(time[window - 1 :], smooth, color="C1", lw=1.4, label=f"mean of {window} cycles")
    if steady is not None and np.isfinite(steady):
        t = time[measured] if measured.any() else time
        ax.axhline(steady, color="C3", lw=1.2, label=f"steady {steady:.4g} kg/s")
        if steady_err is not None and np.isfinite(steady_err):
            ax.fill_between([t.min(), t.max()], steady - steady_err, steady + steady_err,
                            color="C3", alpha=0.2, label="+-1 standard error")  # fmt: skip
    if feed_rate:
        ax.axhline(feed_rate, color="k", ls="--", lw=1.0, label=f"feed {feed_rate:.4g} kg/s")
    ax.set_ylabel("discharge (kg/s)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    bx.plot(time, 1e3 * np.asarray(mass_in_trough), "o-", ms=3, lw=0.8, color="C2")
    bx.set_xlabel("drive time (s)")
    bx.set_ylabel("mass in the trough (g)")
    bx.grid(alpha=0.3)
    return _save(fig, path)


def pointmass_comparison_figure(
    labels, dem_norm, dem_stderr, pointmass_norm, path: str | Path, *, xlabel: str = "",
    bounded_norm=None,
) -> Path:  # fmt: skip
    """DEM normalised velocity v / (A omega cos phi) with +-1 s.e. bars beside the point mass.

    Args:
        labels: One x tick label per run (strings) or numbers (a parameter, drawn as lines).
        dem_norm: DEM normalised velocity per run, (R,).
        dem_stderr: Its standard error, (R,) (nan: no bar).
        pointmass_norm: Point-mass prediction per run, (R,) (nan: not available).
        path: PNG file.
        xlabel: Axis label (for numeric labels).
        bounded_norm: The Coulomb-bounded point mass per run, (R,) (the DEM's reference), drawn
            where it differs from ``pointmass_norm`` (the paper's Eq. 12) by more than 1e-3.

    """
    import numpy as np

    bounded = np.full(len(dem_norm), np.nan)
    if bounded_norm is not None:
        bounded = np.asarray(bounded_norm, float)
    differs = np.isfinite(bounded) & (np.abs(bounded - np.asarray(pointmass_norm, float)) > 1e-3)
    bounded = np.where(differs, bounded, np.nan)
    y = np.asarray(dem_norm, float)
    e = np.nan_to_num(np.asarray(dem_stderr, float))
    pm = np.asarray(pointmass_norm, float)
    fig, ax = plt.subplots(figsize=(min(4 + 1.2 * len(y), 10), 4), dpi=120)
    numeric = all(isinstance(v, int | float) for v in labels) and len(labels) > 1
    if numeric:
        x = np.asarray(labels, float)
        order = np.argsort(x)
        ax.errorbar(x[order], y[order], yerr=e[order], fmt="o-", capsize=3, label="DEM")
        if np.any(np.isfinite(pm)):
            ax.plot(x[order], pm[order], "s--", color="C1", label="point mass (paper, Eq. 12)")
        if np.any(np.isfinite(bounded)):
            ax.plot(x[order], bounded[order], "^:", color="C2",
                    label="point mass, landings bounded by Coulomb")  # fmt: skip
        ax.set_xlabel(xlabel)
    else:
        x = np.arange(len(y))
        w = 0.38
        ax.bar(x - w / 2, y, w, yerr=e, capsize=4, color="C0", label="DEM (+-1 s.e.)")
        ax.bar(x + w / 2, np.nan_to_num(pm), w, color="C1", label="point mass (paper, Eq. 12)")
        if np.any(np.isfinite(bounded)):
            ax.plot(x + w / 2, bounded, "^", color="C2", ms=8,
                    label="point mass, landings bounded by Coulomb")  # fmt: skip
        for xi, p in zip(x, pm, strict=True):
            if not np.isfinite(p):
                ax.text(xi + w / 2, 0.0, "n/a", ha="center", va="bottom", fontsize=8)
        for xi, yi, ei, p in zip(x, y, e, pm, strict=True):
            ax.text(xi - w / 2, yi + ei, f"{yi:.3g}", ha="center", va="bottom", fontsize=8)
            if np.isfinite(p):
                ax.text(xi + w / 2, p, f"{p:.3g}", ha="center", va="bottom", fontsize=8)
        ax.set_xticks(x, [str(v) for v in labels], fontsize=8)
        ax.set_xlim(-0.7, len(y) - 0.3)
        ax.axhline(0.0, color="k", lw=0.6)
    ax.set_ylabel("v / (A omega cos phi)")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    return _save(fig, path)


def bed_snapshot_figure(
    positions,
    radius,
    vx,
    length: float,
    width: float,
    path: str | Path,
    *,
    title: str = "",
) -> Path:
    """Side view (x-z) and top view (x-y) of the bed, spheres drawn to scale, coloured by v_x.

    Args:
        positions: Sphere centres in the trough frame, (N, 3), m (x wrapped into [0, length)).
        radius: (N,), m.
        vx: x-velocity relative to the trough, (N,), m/s.
        length, width: Trough section, m.
        path: PNG file.
        title: Figure title.

    """
    import numpy as np
    from matplotlib.collections import EllipseCollection

    from dem.trough import Trough

    x = Trough(length, width).wrap(positions)
    r = np.asarray(radius, float)
    vx = np.asarray(vx, float)
    top = float(max(np.max(x[:, 2] + r), 0.25 * width)) if len(r) else 0.25 * width
    lim = float(np.max(np.abs(vx))) if len(vx) else 1.0
    lim = lim if lim > 0 else 1.0
    fig, (a1, a2) = plt.subplots(
        2,
        1,
        figsize=(7, min(max(1.8 + 5.0 * (top + width) / length, 3.0), 9.0)),
        dpi=120,
        height_ratios=[top, width],
        sharex=True,
        layout="constrained",
    )
    coll = None
    for ax, (i, j), depth in ((a1, (0, 2), 1), (a2, (0, 1), 2)):
        order = np.argsort(x[:, depth] if depth == 2 else -x[:, depth])  # nearest drawn last
        coll = EllipseCollection(
            2 * r[order], 2 * r[order], np.zeros(len(r)), units="xy",
            offsets=x[order][:, [i, j]], offset_transform=ax.transData, cmap="coolwarm",
            edgecolors="k", linewidths=0.2,
        )  # fmt: skip
        coll.set_array(vx[order])
        coll.set_clim(-lim, lim)
        ax.add_collection(coll)
        ax.set_aspect("equal")
        ax.set_xlim(0.0, length)
    a1.set_ylim(0.0, 1.05 * top)
    a1.axhline(0.0, color="k", lw=1.0)
    a1.set_ylabel("z (m)")
    a1.set_title(title, fontsize=9)
    a2.set_ylim(-0.5 * width, 0.5 * width)
    a2.axhline(-0.5 * width, color="k", lw=1.0)
    a2.axhline(0.5 * width, color="k", lw=1.0)
    a2.set_ylabel("y (m)")
    a2.set_xlabel("x (m)")
    fig.colorbar(coll, ax=[a1, a2], label="v_x relative to the trough (m/s)", shrink=0.8)
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


def calibration_figure(cal, friction: float, path: str | Path) -> Path:
    """eps_t of the virtual impacts against incidence, before and after ``dem calibrate``.

    ``cal`` is a :class:`dem.calibrate.Calibration`; the Coulomb bound 1 - mu cot(theta) of a
    sliding impact (eps_n = 0) is drawn for reference.
    """
    import numpy as np

    theta = cal.impacts[:, 0]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    if cal.fitted:
        ax.plot(cal.fan, cal.fan_before, "-", color="C7", lw=1, label="before (case as given)")
        after = f"after (k_t / k_n = {cal.kappa:.4g})"
        ax.plot(theta, cal.before, "o", mfc="none", color="C7", ms=7)
    else:
        after = "impact-aware law (nothing to fit)"
    ax.plot(cal.fan, cal.fan_after, "-", color="C0", label=after)
    ax.plot(theta, cal.after, "o", color="C0", label="landings of the point mass")
    if cal.bounded.any():
        ax.plot(theta[cal.bounded], cal.targets[cal.bounded], "x", color="C2", ms=8,
                label="friction-bound landings: reachable value")  # fmt: skip
    ax.axhline(cal.target, color="C3", lw=1, label=f"target eps_t = {cal.target:g}")
    grid = np.linspace(5.0, 89.0, 200)
    bound = 1.0 - friction / np.tan(np.radians(grid))
    ax.plot(grid, bound, "--", color="C2", lw=1, label="Coulomb bound 1 - mu cot(theta)")
    ax.set_xlabel("incidence theta (deg from the floor normal)")
    ax.set_ylabel("eps_t (centre of mass, after / before)")
    ax.set_ylim(min(0.0, np.nanmin(cal.fan_before), np.nanmin(cal.fan_after)) - 0.05, 1.05)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(
        f"{len(theta)} landings of the point mass; residual {cal.residual:+.3f}", fontsize=8
    )
    return _save(fig, path)
