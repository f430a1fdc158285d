"""Matplotlib figures (Agg backend, PNG files); no computation here.

Every figure states on its axes what is plotted and in which unit ("vibration angle phi (deg)",
"conveying velocity v (m/s)", "(-)" for a dimensionless number: :func:`axis_label`), and in its
title what was held fixed (:func:`held_text`); long titles are wrapped and every figure is laid
out before it is written (:func:`save`), so nothing is cut off at an edge.
"""

import re
import textwrap
import warnings
from pathlib import Path
from typing import cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from dem.io.files import replace_file  # noqa: E402

#: Quantities by key (a case key's last part, a point-mass input): (words with the symbol,
#: the symbol alone, the unit; "" dimensionless).
QUANTITY = {
    "angle": ("vibration angle phi", "phi", "deg"),
    "throw_number": ("throw number Gamma", "Gamma", ""),
    "friction": ("friction coefficient mu", "mu", ""),
    "inclination": ("inclination alpha", "alpha", "deg"),
    "eps_t": ("tangential restitution eps_t", "eps_t", ""),
    "eps_n": ("normal restitution eps_n", "eps_n", ""),
    "restitution_tangential": ("tangential restitution eps_t", "eps_t", ""),
    "restitution_normal": ("normal restitution eps_n", "eps_n", ""),
    "frequency": ("drive frequency f", "f", "Hz"),
    "amplitude": ("drive amplitude A", "A", "m"),
    "peak_acceleration": ("peak trough acceleration A omega^2", "A omega^2", "g"),
    "drive_velocity": ("drive velocity A omega", "A omega", "m/s"),
    "impact": ("landing law", "landing law", ""),
    "count": ("grains", "grains", ""),
    "radius": ("grain radius r", "r", "m"),
    "density": ("density rho", "rho", "kg/m^3"),
    "youngs_modulus": ("Young's modulus E", "E", "Pa"),
    "stiffness": ("normal stiffness k_n", "k_n", "N/m"),
}
#: Axis text of the conveying velocity, in m/s and normalised.
VELOCITY_LABEL = "conveying velocity v (m/s)"
NORM_LABEL = "normalised velocity\nv / (A omega cos phi) (-)"


def axis_label(key: str) -> str:
    """Axis text of a quantity with its unit: ``drive.angle`` -> "vibration angle phi (deg)".

    A key not in :data:`QUANTITY` keeps its name, with the unit of
    :data:`dem.quantities.QUANTITIES` where that table knows it; "(-)" marks a dimensionless
    number.
    """
    name = key.rsplit(".", 1)[-1]
    if name in QUANTITY:
        words, _, unit = QUANTITY[name]
        return f"{words} ({unit or '-'})"
    from dem.quantities import QUANTITIES

    q = QUANTITIES.get(name)
    return f"{key} ({(q.unit if q is not None else '') or '-'})"


def held_text(values: dict) -> str:
    """Each held value with its symbol and unit: "Gamma = 1.8, f = 60 Hz, mu = 0.35".

    An amplitude is given in mm; a word (the landing law) as it is; a key not in
    :data:`QUANTITY` by its name.
    """
    parts = []
    for key, v in values.items():
        name = key.rsplit(".", 1)[-1]
        _, symbol, unit = QUANTITY.get(name, (name, name, ""))
        if isinstance(v, bool) or not isinstance(v, int | float):
            text = f"{symbol} {v}"
        else:
            if unit == "m" and 0 < abs(v) < 0.1:
                v, unit = 1e3 * v, "mm"
            text = f"{symbol} = {v:.4g}" + (f" {unit}" if unit else "")
        parts.append(text.replace(" ", NBSP))  # a wrapped title keeps "phi = 25 deg" whole
    return ", ".join(parts)


#: A space that a wrapped title does not break at.
NBSP = "\u00a0"


def wrap_title(text: str, fig=None, fontsize: float = 9.0) -> str:
    """``text`` wrapped to the figure's width (about 0.55 fontsize per character)."""
    width_in = fig.get_figwidth() if fig is not None else 6.5
    chars = max(30, int(width_in * 72.0 / (0.55 * fontsize)) - 4)
    return "\n".join(textwrap.fill(line, chars) for line in text.split("\n"))


def set_title(ax, text: str, fontsize: float = 9.0) -> None:
    """A title wrapped to the figure's width."""
    ax.set_title(wrap_title(text, ax.figure, fontsize), fontsize=fontsize)


def save(fig, path: str | Path, *, key: str = "--out") -> Path:
    """Lay out, write and close a figure; returns the path.

    Laid out so that titles, labels and legends stay inside the figure (tight layout, or the
    figure's constrained layout), and written with a tight bounding box besides.
    """
    if not fig.get_constrained_layout():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # tight_layout's warning on an odd axes mix
            fig.tight_layout()
    path = Path(path)
    kind = path.suffix.lstrip(".").lower() or "png"
    try:  # written whole to a fresh name and renamed: never through a link (dem.io.files)
        replace_file(path, lambda tmp: fig.savefig(tmp, format=kind, bbox_inches="tight",
                                                   pad_inches=0.08), key=key)  # fmt: skip
    finally:
        plt.close(fig)
    return path


def optimum_figure(opt, path: str | Path) -> Path:
    """Plot the scanned objective of an :class:`dem.pointmass.sweep.Optimum` and mark the best."""
    x = opt.curve[opt.over]
    y = opt.curve[opt.objective]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(x, y, color="C0")
    best = opt.velocity_norm if opt.objective == "velocity_norm" else opt.velocity
    unit = QUANTITY[opt.over][2]
    ax.plot([opt.value], [best], "o", color="C3", label=f"optimum {opt.value:.3g} {unit}".strip())
    ax.axvspan(*opt.plateau, color="C0", alpha=0.12, label="within 90 % of the optimum")
    ax.set_xlabel(axis_label(opt.over))
    ax.set_ylabel(NORM_LABEL if opt.objective == "velocity_norm" else VELOCITY_LABEL)
    symbol = QUANTITY[opt.over][1]
    main = held_text({k: v for k, v in opt.held.items() if k == _HELD_KEY.get(opt.hold)})
    rest = held_text({k: v for k, v in opt.held.items() if k != _HELD_KEY.get(opt.hold)})
    set_title(ax, f"point mass: optimum {symbol} at fixed {main or opt.hold}\n{rest}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, path)


#: The key of ``Optimum.held`` that ``hold`` names.
_HELD_KEY = {"acceleration": "peak_acceleration"}
_HELD_KEY |= {k: k for k in ("throw_number", "amplitude", "frequency", "drive_velocity")}


def velocity_cycles_figure(
    cycle,
    velocity,
    running_mean,
    running_stderr,
    path: str | Path,
    *,
    measured=None,
    title: str = "",
    replicas=None,
    pooled=None,
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
        replicas: The other fills of a pooled run: (seed, cycles, velocities) each, their
            measured cycles drawn beside the first fill's.
        pooled: (mean, standard error) pooled over the fills, m/s: a line and its band.

    """
    import numpy as np

    cycle = np.asarray(cycle)
    velocity = np.asarray(velocity)
    measured = np.ones(cycle.shape, bool) if measured is None else np.asarray(measured, bool)
    m, s = np.asarray(running_mean), np.asarray(running_stderr)
    fig, ax = plt.subplots(figsize=(6.5, 4), dpi=120)
    if np.any(~measured):
        ax.plot(cycle[~measured], velocity[~measured], "o", ms=3, color="0.6", label="settling")
    first = "cycle" if not replicas else "cycle, fill 1"
    ax.plot(cycle[measured], velocity[measured], "o-", ms=3, lw=0.8, color="C0", label=first)
    for k, (seed, c_k, v_k) in enumerate(replicas or (), start=2):
        ax.plot(c_k, v_k, "o-", ms=2, lw=0.6, alpha=0.7, color=f"C{(k + 1) % 10}",
                label=f"fill {k} (seed {seed})")  # fmt: skip
    if pooled is None:
        ax.plot(cycle, m, color="C3", label="running mean")
        ax.fill_between(cycle, m - s, m + s, color="C3", alpha=0.2, label="+-1 standard error")
    else:
        mean, err = pooled
        ax.axhline(mean, color="C3", label=f"pooled over {len(replicas or ()) + 1} fills")
        ax.axhspan(mean - err, mean + err, color="C3", alpha=0.2,
                   label="+-1 pooled standard error (fill-to-fill spread included)")  # fmt: skip
    ax.set_xlabel("drive cycle (-)")
    # a linear axis's locator is an AutoLocator, a MaxNLocator: it takes ``integer``
    cast(MaxNLocator, ax.xaxis.get_major_locator()).set_params(integer=True)
    ax.set_ylabel("cycle's mean x-velocity v (m/s)")
    set_title(ax, title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, path)


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
    ax.set_ylabel("discharge rate (kg/s)")
    set_title(ax, title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    bx.plot(time, 1e3 * np.asarray(mass_in_trough), "o-", ms=3, lw=0.8, color="C2")
    bx.set_xlabel("drive time (s)")
    bx.set_ylabel("mass in the trough (g)")
    bx.grid(alpha=0.3)
    return save(fig, path)


def pointmass_comparison_figure(
    labels, dem_norm, dem_stderr, pointmass_norm, path: str | Path, *, xlabel: str = "",
    bounded_norm=None, title: str = "",
) -> Path:  # fmt: skip
    """DEM normalised velocity v / (A omega cos phi) with +-1 s.e. bars beside the point mass.

    Args:
        labels: One x tick label per run (strings) or numbers (a parameter, drawn as lines).
        dem_norm: DEM normalised velocity per run, (R,).
        dem_stderr: Its standard error, (R,) (nan: no bar).
        pointmass_norm: Point-mass prediction per run, (R,) (nan: not available).
        path: PNG file.
        xlabel: Axis label with its unit (for numeric labels; runs by name: "run").
        title: What the runs share (drive, material), wrapped to the figure.
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
        # a bar pair's width in characters of 8 pt (about 4.8 pt each), the axes 65 % wide
        chars = max(10, int(0.65 * 0.9 * 72 * fig.get_figwidth() / len(y) / 4.8))
        ticks = [_wrap_name(str(v), chars) for v in labels]
        ax.set_xticks(x, ticks, fontsize=8)
        ax.set_xlim(-0.7, len(y) - 0.3)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel(xlabel or "run (output folder)")
    ax.set_ylabel(NORM_LABEL)
    if title:
        set_title(ax, title)
    ax.grid(alpha=0.3, axis="y")
    if not numeric:  # room above the bars and their numbers for the legend
        tops = [v for v in (*(y + e), *pm, *bounded) if np.isfinite(v)]
        if tops and max(tops) > 0:
            ax.set_ylim(top=1.35 * max(tops))
        ax.legend(fontsize=8, loc="upper right", ncols=2 if len(y) > 1 else 1)
    else:
        ax.legend(fontsize=8)
    return save(fig, path)


def _wrap_name(text: str, chars: int) -> str:
    """A folder name on lines of at most ``chars``, broken after "_" where it can be."""
    lines = [""]
    for piece in re.split(r"(?<=_)", text):
        if lines[-1] and len(lines[-1]) + len(piece) > chars:
            lines.append("")
        lines[-1] += piece
    return "\n".join(textwrap.fill(line, chars) if len(line) > chars else line for line in lines)


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

    from dem.scene.trough import Trough

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
    set_title(a1, title)
    a2.set_ylim(-0.5 * width, 0.5 * width)
    a2.axhline(-0.5 * width, color="k", lw=1.0)
    a2.axhline(0.5 * width, color="k", lw=1.0)
    a2.set_ylabel("y (m)")
    a2.set_xlabel("x, along the trough (m)")
    assert coll is not None  # both panels drew theirs
    fig.colorbar(coll, ax=[a1, a2], label="v_x relative to the trough (m/s)", shrink=0.8)
    return save(fig, path)


def calibration_figure(cal, friction: float, path: str | Path) -> Path:
    """eps_t of the virtual impacts against incidence, before and after ``dem calibrate``.

    ``cal`` is a :class:`dem.studies.calibrate.Calibration`; the Coulomb bound 1 - mu cot(theta) of
    a sliding impact (eps_n = 0) is drawn for reference.
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
    ax.set_xlabel("incidence theta from the floor normal (deg)")
    ax.set_ylabel("tangential restitution eps_t, centre of mass (-)")
    ax.set_ylim(min(0.0, np.nanmin(cal.fan_before), np.nanmin(cal.fan_after)) - 0.05, 1.05)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    set_title(
        ax, f"eps_t of virtual impacts, mu = {friction:.4g}: {len(theta)} point-mass landings, "
        f"residual {cal.residual:+.3f}",
    )  # fmt: skip
    return save(fig, path)


def atlas_point_figure(points, case_point, path: str | Path, *, title: str = "") -> Path:
    """A run's drive on the atlas's map: bulk / bounded point mass over (phi, Gamma).

    Args:
        points: The atlas's points of the run's shape, depth and friction: (phi deg, Gamma,
            ratio, ratio standard error) each.
        case_point: The run's (phi deg, Gamma, ratio, ratio standard error); ratio may be nan.
        path: PNG to write.
        title: The panel's title (what the points hold: shape, depth, friction).

    """
    import numpy as np

    fig, ax = plt.subplots(figsize=(6.0, 4.4), dpi=120)
    lo, hi = 0.4, 1.6
    sc = None
    if points:
        phi, gamma, ratio, err = (np.array(c, dtype=float) for c in zip(*points, strict=True))
        sc = ax.scatter(phi, gamma, c=ratio, cmap="coolwarm", vmin=lo, vmax=hi, s=260,
                        edgecolors="k", linewidths=0.6, label="atlas points")  # fmt: skip
        for x, y, r, e in zip(phi, gamma, ratio, err, strict=True):
            ax.annotate(f"{r:.2f}\n+-{e:.2f}", (x, y), fontsize=6, ha="center", va="center")
    x, y, r, e = case_point
    colour = "none" if not np.isfinite(r) else plt.get_cmap("coolwarm")((r - lo) / (hi - lo))
    ax.scatter([x], [y], marker="*", s=520, c=[colour], edgecolors="k", linewidths=1.2,
               zorder=5, label="this run")  # fmt: skip
    text = "this run" if not np.isfinite(r) else f"this run: {r:.3f} +- {e:.3f}"
    ax.annotate(text, (x, y), xytext=(8, 10), textcoords="offset points", fontsize=8)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="bulk v / Coulomb-bounded point mass v")
    ax.margins(0.15)
    ax.set_xlabel("vibration angle phi (deg)")
    ax.set_ylabel("throw number Gamma")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=7, markerscale=0.5)
    ax.set_title(title, fontsize=9)
    return save(fig, path)
