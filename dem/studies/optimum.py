"""``dem optimum``: the bulk optimum vibration angle (or throw number), searched under noise.

A DEM bulk velocity comes with a standard error (and scatters from fill to fill), so a plain
golden-section search would chase the noise. :func:`maximize_noisy` brackets instead:

1. evaluate a coarse grid over the bounds (``initial`` points);
2. bracket the best point by its evaluated neighbours; evaluate the midpoints on both sides;
   when the best leads its runner-up by less than ``z`` combined standard errors, first add a
   replicate (a new fill) at both, so a bracket is never narrowed on noise, and if they are
   still level, look at the point between them;
3. stop when the bracket is narrower than ``2 tolerance``, when the budget of evaluations is
   spent, or when the best no longer stands out from its neighbours after replication (the
   objective is flat within the noise there);
4. fit a parabola, weighted by 1 / stderr^2, through the points nearest the best; its vertex is
   the optimum, and a parametric bootstrap of the fit (each point redrawn within its standard
   error) gives the optimum's uncertainty. Where the curvature is not negative by two standard
   errors, the objective is flat within the noise: the best point stands, and the uncertainty
   is half the span of the points level with it (within two combined standard errors).

:func:`bulk_optimum` applies it to a case (each evaluation a ``dem run`` of the case with the
scanned key set, in its own folder, run on Dask as ``dem sweep`` runs its points) and sets the
point-mass optimum of the same drive and material beside it: the paper's Figs. 7 and 8 asked of
the bulk. Cost: a few more runs than the grid, each as long as one ``dem run``.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from dem.errors import InputError
from dem.io.files import json_text, refuse_links, replace_text

#: What can be scanned, and what may be held fixed for each (as ``dem pointmass optimum``).
#: The files ``dem optimum`` writes beside its runs' folders.
OPTIMUM_FILES = ("optimum.json", "optimum.csv", "optimum.png")
OVER = {"drive.angle": ("throw_number", "amplitude"), "drive.throw_number": ("frequency",)}


@dataclass
class NoisyOptimum:
    """Result of :func:`maximize_noisy`.

    Attributes:
        x: The optimum (vertex of the fitted parabola, or the best point).
        uncertainty: Its standard uncertainty (bootstrap of the fit, or half the bracket).
        value, value_stderr: The objective at the optimum and its standard error.
        bracket: The final bracket around the best point.
        converged: True if the bracket closed to the tolerance.
        reason: Why the search stopped.
        samples: Every evaluation, ``(x, replicate, value, stderr)``.

    """

    x: float
    uncertainty: float
    value: float
    value_stderr: float
    bracket: tuple[float, float]
    converged: bool
    reason: str
    samples: list[tuple[float, int, float, float]] = field(default_factory=list)


Evaluate = Callable[[Sequence[tuple[float, int]]], list[tuple[float, float]]]


def maximize_noisy(
    evaluate: Evaluate,
    lo: float,
    hi: float,
    *,
    tolerance: float,
    max_evaluations: int = 24,
    initial: int = 5,
    z: float = 2.0,
    seed: int = 0,
) -> NoisyOptimum:
    """Maximise a noisy function of one variable on [lo, hi] (see the module text).

    ``evaluate`` takes a batch of ``(x, replicate)`` (replicate 0, 1, ...: independent draws of
    the noise at x, for a DEM run another fill) and returns ``(value, stderr)`` for each; a
    batch may run in parallel.
    """
    if not lo < hi:
        raise InputError("bounds", (lo, hi), "lower bound below the upper bound")
    if initial < 3 or max_evaluations < initial:
        raise InputError("max_evaluations", max_evaluations, f">= initial points ({initial}) >= 3")
    samples: list[tuple[float, int, float, float]] = []
    runs: dict[float, list[tuple[float, float]]] = {}

    def run(batch: list[tuple[float, int]]) -> None:
        for (x, rep), (v, se) in zip(batch, evaluate(batch), strict=True):
            samples.append((x, rep, v, se))
            runs.setdefault(x, []).append((v, se))

    def est(x: float) -> tuple[float, float]:
        vs = runs[x]
        mean = float(np.mean([v for v, _ in vs]))
        own = math.sqrt(sum(se**2 for _, se in vs)) / len(vs)
        if len(vs) > 1:  # the scatter of the replicates, where it says more
            own = max(own, float(np.std([v for v, _ in vs], ddof=1)) / math.sqrt(len(vs)))
        return mean, own

    run([(float(x), 0) for x in np.linspace(lo, hi, initial)])
    reason, converged = "budget of evaluations spent", False
    while True:
        xs = sorted(runs)
        means = [est(x)[0] for x in xs]
        i = int(np.argmax(means))
        a, b = xs[max(i - 1, 0)], xs[min(i + 1, len(xs) - 1)]
        if b - a <= 2.0 * tolerance:
            reason, converged = "bracket within the tolerance", True
            break
        if len(samples) + 2 > max_evaluations:
            break
        best, best_se = est(xs[i])
        rival = max((j for j in (i - 1, i + 1) if 0 <= j < len(xs)), key=lambda j: means[j])
        lead = best - means[rival]
        if lead < z * math.hypot(best_se, est(xs[rival])[1]):
            reps = min(len(runs[xs[i]]), len(runs[xs[rival]]))
            middle = 0.5 * (xs[i] + xs[rival])
            if reps >= 2 and abs(xs[rival] - xs[i]) > 2.0 * tolerance and middle not in runs:
                run([(middle, 0)])  # level after a replicate: look between them
                continue
            if reps >= 4:  # replicated and still level: flat within the noise here
                reason = "flat within the noise: the best does not stand out after 4 fills"
                break
            run([(xs[i], len(runs[xs[i]])), (xs[rival], len(runs[xs[rival]]))])
            continue
        new = [0.5 * (a + xs[i]), 0.5 * (xs[i] + b)]
        run([(x, 0) for x in new if x not in runs and a < x < b])
    return _fit(runs, est, samples, lo, hi, reason, converged, seed)


def _fit(runs, est, samples, lo, hi, reason, converged, seed) -> NoisyOptimum:
    xs = np.array(sorted(runs))
    m = np.array([est(x)[0] for x in xs])
    s = np.array([max(est(x)[1], 1e-12) for x in xs])
    i = int(np.argmax(m))
    a, b = xs[max(i - 1, 0)], xs[min(i + 1, len(xs) - 1)]
    near = np.argsort(np.abs(xs - xs[i]))[: min(5, len(xs))]
    # Points level with the best within the noise: where the optimum may lie if nothing
    # sharper is known.
    level = xs[m >= m[i] - 2.0 * np.hypot(s, s[i])]
    flat = NoisyOptimum(float(xs[i]), float(0.5 * (level.max() - level.min())), float(m[i]),
                        float(s[i]), (float(level.min()), float(level.max())), False,
                        f"{reason}; no significant curvature: flat within the noise over "
                        f"{level.min():.4g}-{level.max():.4g}", samples)  # fmt: skip
    if len(near) < 3:
        return flat

    def vertex(values):
        c2, c1, c0 = np.polyfit(xs[near], values, 2, w=1.0 / s[near])
        if c2 >= 0:
            return None
        xv = -c1 / (2.0 * c2)
        return float(xv), float(c0 + c1 * xv + c2 * xv**2)

    if len(near) > 3:
        coef, cov = np.polyfit(xs[near], m[near], 2, w=1.0 / s[near], cov="unscaled")
        if coef[0] + 2.0 * math.sqrt(cov[0, 0]) >= 0.0:  # curvature not below zero by 2 sigma
            return flat
    top = vertex(m[near])
    if top is None or not (xs[near].min() <= top[0] <= xs[near].max()):
        return flat
    rng = np.random.default_rng(seed)
    draws = [vertex(m[near] + s[near] * rng.standard_normal(len(near))) for _ in range(400)]
    ok = np.array([d[0] for d in draws if d is not None])
    ok = ok[(ok >= lo) & (ok <= hi)]
    spread = float(np.std(ok)) if ok.size > 20 else float(0.5 * (b - a))
    return NoisyOptimum(top[0], spread, top[1], float(s[i]), (float(a), float(b)), converged,
                        reason, samples)  # fmt: skip


# --- the bulk optimum of a case -------------------------------------------------------------


def _held(case, over: str, hold: str) -> dict:
    """The overrides that keep ``hold`` at the case's value while ``over`` moves."""
    d = case.drive
    if over == "drive.angle":
        if hold == "throw_number":
            return {"drive.throw_number": d.throw_number, "drive.amplitude": None}
        return {"drive.amplitude": d.amplitude, "drive.throw_number": None}
    return {"drive.amplitude": None}  # over throw number at the case's frequency


def bulk_optimum(
    case_dir: str | Path,
    over: str,
    hold: str,
    out: str | Path,
    *,
    bounds: tuple[float, float] | None = None,
    tolerance: float | None = None,
    max_runs: int = 20,
    scheduler: str | None = None,
    workers: int | None = None,
    cycles: int | None = None,
    progress: bool = True,
    overrides: dict | None = None,
) -> dict:
    """Search the bulk optimum of a case; writes optimum.json, optimum.csv and optimum.png.

    ``overrides``: case keys set over case.toml (``--set``), at every run of the search; the
    searched key itself is refused there.
    """
    from dem.pointmass.sweep import optimum as pointmass_optimum
    from dem.provenance import record
    from dem.scene.case import load_case
    from dem.studies.sweep import folder_name

    if over not in OVER:
        raise InputError("--over", over, f"one of {', '.join(OVER)}")
    if hold not in OVER[over]:
        raise InputError("--hold", hold, f"for --over {over}: one of {', '.join(OVER[over])}")
    from dem.quantities import check

    # the options first, by their names: the case file is not to blame for them
    if tolerance is not None:
        check("tolerance", tolerance, "--tolerance")
    check("max_runs", max_runs, "--max-runs")
    if cycles is not None:
        check("cycles", cycles, "--cycles")
    if workers is not None:
        check("workers", workers, "--workers")
    lo, hi = bounds or ((10.0, 60.0) if over == "drive.angle" else (0.5, 4.0))
    for x in (lo, hi):
        check(over.split(".")[1], x, "--bounds")
    if not lo < hi:
        raise InputError("--bounds", f"{lo:g}:{hi:g}", "LO:HI with the lower bound below the upper")
    tol = tolerance if tolerance is not None else (1.0 if over == "drive.angle" else 0.05)
    case_dir, out = Path(case_dir), Path(out)
    base = dict(overrides or {})
    if over in base:
        raise InputError("--set", over, f"a key other than the one searched (--over {over})")
    origins = dict.fromkeys(base, "--set")
    case = load_case(case_dir, base, origins)
    measured = cycles if cycles is not None else case.run.cycles
    if measured < 2 and case.run.target_error is None:
        key, value = ("--cycles", cycles) if cycles is not None else ("run.cycles", measured)
        raise InputError(
            key, value, "at least 2 measured cycles: the search weighs each run's velocity by "
            "its error bar, which one cycle does not give",
        )  # fmt: skip
    held = base | _held(case, over, hold)
    for x in (lo, hi):  # the bounds themselves must make valid cases
        try:
            load_case(case_dir, held | {over: x}, origins)
        except InputError as err:
            raise InputError(
                "--bounds", f"{lo:g}:{hi:g}", f"bounds at which the case holds: at {over} = "
                f"{x:g} (holding {hold}) {err.key} = {err.value!r}: {err.allowed}",
            ) from None  # fmt: skip
    if progress and case.run.replicas > 1:
        from dem.run.replicas import fill_keys

        print(f"dem optimum: {fill_keys(case.run)} is not applied: the search "
              "runs one fill a point and adds fills where the noise needs them",
              file=sys.stderr)  # fmt: skip
    objective = "velocity_norm" if (over, hold) == ("drive.angle", "throw_number") else "velocity"
    key = "mean_velocity_norm" if objective == "velocity_norm" else "mean_velocity"
    counter = [0]
    from dem import config
    from dem.studies.sweep import dask_client

    refuse_links(out, OPTIMUM_FILES)
    client, cluster = dask_client(scheduler, workers or config.default_threads(), "dem optimum")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except BaseException:
        client.close()
        if cluster is not None:
            cluster.close()
        raise

    def evaluate(batch):
        from dem.studies.sweep import run_point

        jobs = []
        for x, rep in batch:
            overrides = held | {over: float(x), "run.seed": case.run.seed + rep}
            folder = out / folder_name(counter[0], {over: x, "run.seed": case.run.seed + rep})
            refuse_links(out, [folder.name])
            counter[0] += 1
            jobs.append(client.submit(run_point, str(case_dir), overrides, str(folder), cycles,
                                      1, False, pure=False))  # fmt: skip
        if progress:  # before the runs: each lasts as long as a dem run of the case
            where = ", ".join(f"{x:.4g}" + (f" (fill {rep})" if rep else "") for x, rep in batch)
            print(f"dem optimum: running {len(batch)} run(s) at {over} = {where} "
                  f"({counter[0]} of at most {max_runs} started)", file=sys.stderr,
                  flush=True)  # fmt: skip
        results = client.gather(jobs)
        if progress:
            for (x, rep), r in zip(batch, results, strict=True):
                print(f"dem optimum: {over} = {x:.4g} (fill {rep}): {key} "
                      f"{r[key]:.4f} +- {r[key + '_stderr']:.4f}", file=sys.stderr,
                      flush=True)  # fmt: skip
        return [(r[key], r[key + "_stderr"]) for r in results]

    try:
        result = maximize_noisy(evaluate, lo, hi, tolerance=tol, max_evaluations=max_runs)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    pm = _pointmass(case, over, hold, (lo, hi), pointmass_optimum)
    bulk = {k: v for k, v in asdict(result).items() if k != "samples"}
    band = plateau(result)
    bulk.update(_honest(result, band, lo, hi, tol))
    summary = {
        "case": case.name, "case_dir": str(case_dir.resolve()), "overrides": base,
        "over": over, "hold": hold,
        "objective": objective, "bounds": [lo, hi],
        "bulk": bulk,
        "pointmass": {"value": pm.value, "plateau_90": list(pm.plateau),
                      objective: getattr(pm, objective)},
        "samples": [dict(zip(("x", "fill", "value", "stderr"), s, strict=True))
                    for s in result.samples],
        "plateau": band,
        "csv_columns": dict(zip(_csv_columns(over, objective), (
            f"the scanned {over}", "the fill (replicate: run.seed = the case's seed + fill)",
            f"the {objective} of the run", "its standard error"), strict=True)),
        "provenance": record(),
    }  # fmt: skip
    replace_text(out / "optimum.json", json_text(summary, indent=2) + "\n")
    _write_csv(out / "optimum.csv", result.samples, over, objective)
    _plot(out / "optimum.png", result, pm, over, objective, case.name)
    return summary


def _honest(result: NoisyOptimum, band: dict, lo: float, hi: float, tol: float) -> dict:
    """What the optimum's error bar and position can claim (issue 48, item 2).

    ``flat``: no significant curvature, so no error bar, only the range level with the best.
    ``uncertainty``: at least half the plateau (where the fitted top is within a run's error of
    its maximum): the bootstrap of the vertex used each run's own error, which leaves out the
    fill-to-fill scatter, and gave +-0.07 deg inside a plateau 2 deg wide.
    ``at_bound``: the optimum within the tolerance of a search bound ("lower", "upper").
    """
    flat = "no significant curvature" in result.reason
    half = 0.5 * (band["range"][1] - band["range"][0])
    out: dict[str, Any] = {"flat": flat, "uncertainty_bootstrap": result.uncertainty}
    if flat:
        out["uncertainty"] = None
    else:
        out["uncertainty"] = max(result.uncertainty, half)
    out["at_bound"] = ("lower" if result.x - lo <= tol else "upper" if hi - result.x <= tol
                       else None)  # fmt: skip
    return out


def _csv_columns(over: str, objective: str) -> list[str]:
    """optimum.csv's columns: the scanned value, the fill, the objective and its stderr."""
    from dem.io.tables import case_key_unit, column_name

    x = column_name(over.split(".")[1], case_key_unit(over))
    if objective == "velocity_norm":
        return [x, "fill", "velocity_norm", "velocity_norm_stderr"]
    return [x, "fill", "velocity_m_s", "velocity_stderr_m_s"]


def _write_csv(path: Path, samples, over: str, objective: str) -> None:
    """optimum.csv: one header line, one row per DEM run, 6 significant digits.

    Its provenance and the meaning of its columns are in optimum.json beside it (the sidecar
    of the same stem, ``provenance`` and ``csv_columns``).
    """
    from dem.io.tables import csv_text

    replace_text(path, csv_text(_csv_columns(over, objective), samples))


def replot(out: str | Path) -> None:
    """Redraw optimum.png from optimum.json (and the point mass, recomputed)."""
    from dem.pointmass.sweep import optimum as pointmass_optimum
    from dem.scene.case import load_case

    out = Path(out)
    d = json.loads((out / "optimum.json").read_text())
    b = d["bulk"]
    samples = [(s["x"], s["fill"], s["value"], s["stderr"]) for s in d["samples"]]
    result = NoisyOptimum(b["x"], b["uncertainty"], b["value"], b["value_stderr"],
                          tuple(b["bracket"]), b["converged"], b["reason"], samples)  # fmt: skip
    case = load_case(d["case_dir"])
    pm = _pointmass(case, d["over"], d["hold"], tuple(d["bounds"]), pointmass_optimum)
    _plot(out / "optimum.png", result, pm, d["over"], d["objective"], case.name)


def _pointmass(case, over, hold, bounds, pointmass_optimum):
    m = case.wall_material  # the point mass touches the floor only
    pm_over = "angle" if over == "drive.angle" else "throw_number"
    held_values = {"throw_number": case.drive.throw_number, "amplitude": case.drive.amplitude}
    return pointmass_optimum(
        pm_over, hold, friction=m.friction, frequency=case.drive.frequency,
        inclination=case.trough.inclination, eps_t=m.restitution_tangential,
        eps_n=m.restitution_normal, bounds=bounds,
        angle=case.drive.angle if pm_over == "throw_number" else None,
        **({hold: held_values[hold]} if hold in held_values else {}),
    )  # fmt: skip


def _estimates(samples) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per scanned value: (x, mean over its fills, standard error), as the search weighs them.

    The error is the fills' own standard errors combined, or the scatter of the fills over
    sqrt(fills) where that is larger (:func:`maximize_noisy`).
    """
    runs: dict[float, list[tuple[float, float]]] = {}
    for x, _, v, se in samples:
        runs.setdefault(float(x), []).append((float(v), float(se)))
    xs = np.array(sorted(runs))
    m, s = np.zeros(xs.size), np.zeros(xs.size)
    for j, x in enumerate(xs):
        vs = runs[x]
        m[j] = np.mean([v for v, _ in vs])
        s[j] = math.sqrt(sum(se**2 for _, se in vs)) / len(vs)
        if len(vs) > 1:
            s[j] = max(s[j], float(np.std([v for v, _ in vs], ddof=1)) / math.sqrt(len(vs)))
    return xs, m, s


def plateau(result: NoisyOptimum, z: float = 2.0) -> dict:
    """The range of the scanned value where the velocity is within its error of the maximum.

    A weighted parabola (weights 1 / stderr^2) is fitted through the top of the curve: the
    scanned values whose mean is within 5 typical standard errors of the best mean (at least the
    3 nearest the best). Where it curves down with its vertex among them, the plateau is where
    the parabola is within one typical standard error s of a run (the median over those values)
    of its maximum: x_v +- sqrt(s / |c2|), kept inside the scanned values. Using the fitted
    maximum, not the best mean, keeps one lucky run from narrowing the band to itself.
    Otherwise (the top is flat within the noise) it is the span of the scanned values whose mean
    is within ``z`` combined standard errors of the best, the search's "level with the best".

    Returns ``{"range": [lo, hi], "rule": text, "parabola": [c2, c1, c0] or None}`` and, with a
    parabola, ``"fitted_over"``: the span of the values it was fitted through.
    """
    xs, m, s = _estimates(result.samples)
    s = np.maximum(s, 1e-12)
    i = int(np.argmax(m))
    typical = float(np.median(s))
    top = np.flatnonzero(m >= m[i] - 5.0 * typical)
    if top.size < 3:
        top = np.argsort(np.abs(xs - xs[i]))[: min(3, xs.size)]
    if top.size >= 3:
        c2, c1, c0 = np.polyfit(xs[top], m[top], 2, w=1.0 / s[top])
        xv = -c1 / (2.0 * c2) if c2 < 0 else math.nan
        if c2 < 0 and xs[top].min() <= xv <= xs[top].max():
            err = float(np.median(s[top]))
            half = math.sqrt(err / -c2)
            lo, hi = float(max(xv - half, xs.min())), float(min(xv + half, xs.max()))
            return {"range": [lo, hi], "parabola": [float(c2), float(c1), float(c0)],
                    "fitted_over": [float(xs[top].min()), float(xs[top].max())],
                    "rule": f"a weighted parabola through the top of the curve within a run's "
                            f"standard error ({err:.3g}) of its maximum"}  # fmt: skip
    level = xs[m >= m[i] - z * np.hypot(s, s[i])]
    return {"range": [float(level.min()), float(level.max())], "parabola": None,
            "rule": f"the scanned values whose mean is within {z:g} combined standard errors "
                    "of the best (no maximum stands out)"}  # fmt: skip


def _plot(path: Path, result: NoisyOptimum, pm, over: str, objective: str, name: str) -> None:
    from dem.studies import plots

    plt = plots.plt
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    unit = plots.QUANTITY[over.split(".")[1]][2]
    band = plateau(result)
    lo, hi = band["range"]
    label = f"plateau {lo:.3g} .. {hi:.3g} {unit}: within the error of the maximum"
    ax.axvspan(lo, hi, color="C2", alpha=0.15, label=label)
    x = np.array([s[0] for s in result.samples])
    ax.errorbar(x, [s[2] for s in result.samples], yerr=[s[3] for s in result.samples], fmt="o",
                color="C0", capsize=2, ms=4, label="DEM runs (each fill, +-1 s.e.)")  # fmt: skip
    if band["parabola"] is not None:
        start, stop = band["fitted_over"]
        grid = np.linspace(start, stop, 100)
        ax.plot(grid, np.polyval(band["parabola"], grid), "-", color="C2", lw=1,
                label="weighted parabola through the top")  # fmt: skip
    ax.errorbar([result.x], [result.value], xerr=[result.uncertainty], fmt="D", color="C3",
                capsize=4, ms=6, label=f"bulk optimum {result.x:.3g} +- "
                f"{result.uncertainty:.2g} {unit}")  # fmt: skip
    curve_x = pm.curve["angle" if over == "drive.angle" else "throw_number"]
    ax.plot(curve_x, pm.curve[objective], "--", color="C1", label="point mass")
    ax.axvline(pm.value, color="C1", ls=":", label=f"point-mass optimum {pm.value:.3g} {unit}")
    ax.set_xlim(min(x.min(), lo) - 0.05 * np.ptp(x), max(x.max(), hi) + 0.05 * np.ptp(x))
    ax.set_xlabel(plots.axis_label(over))
    ax.set_ylabel(plots.NORM_LABEL if objective == "velocity_norm" else plots.VELOCITY_LABEL)
    scanned = over.split(".")[1]
    key = pm.hold if pm.hold in pm.held else "peak_acceleration"
    fixed = plots.held_text({key: pm.held.get(key)})
    others = plots.held_text({k: v for k, v in pm.held.items() if k not in (key, scanned)})
    symbol = plots.QUANTITY[scanned][1]
    plots.set_title(ax, f"{name}: bulk optimum {symbol} at fixed {fixed}\n{others}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    plots.save(fig, path)
