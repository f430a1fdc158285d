"""Reports of finished (or killed) runs: figures, a text summary, and a comparison across runs.

``make_report([OUT])`` reads ``OUT/summary.json`` (README, A DEM run) and, when present,
``OUT/results.h5`` (:mod:`dem.io.hdf5`), both checked (:mod:`dem.studies.report_inputs`), and
writes into the report folder:

- ``velocity_per_cycle.png``: the mass-weighted mean x-velocity of every cycle (settling cycles
  grey). One fill: the running mean over the measured cycles and its +-1 standard-error band,
  the standard error of the first k measured cycles with their correlation accounted for,
  std(ddof=1) sqrt(2 tau_int / k), tau_int their integrated autocorrelation time
  (:func:`dem.physics.measure.correlated_stderr`; its last point is summary.json's). A pooled run
  (``run.replicas`` > 1): the other fills' measured cycles beside the first's, and the pooled
  mean with its +-1 pooled standard error, summary.json's (the fills pooled by a random-effects
  model, the fill-to-fill spread included: :func:`dem.physics.measure.pooled`);
- ``pointmass_comparison.png``: v / (A omega cos phi) of the DEM with +-1 standard error
  (summary.json's ``mean_velocity_norm_stderr``: the pooled one, or one run's correlated one)
  beside the point-mass prediction for the same drive and material;
- ``bed_snapshot.png``: the last frame of ``results.h5``, side view x-z and top view x-y,
  spheres to scale, coloured by the x-velocity relative to the trough;
- ``discharge.png`` (a finite feeder): the discharge rate of every cycle with its steady value
  and the feed, and the mass in the trough against time;
- ``report.txt``: the numbers behind the figures.

With several runs each gets a sub-folder named after its output folder, and the report folder
also holds ``comparison.csv`` (units in the column names, its provenance in ``comparison.json``
beside it), ``comparison.txt`` (one row per run) and ``comparison.png``.
Figures that lack their data (no ``results.h5``, no frames) are skipped and report.txt says so.
"""

from __future__ import annotations

import io
import math
import os
from pathlib import Path

import numpy as np

from dem.io.files import link_refused, own_folder, refuse_links, replace_text
from dem.io.freetext import shown_text
from dem.physics import measure
from dem.studies import plots
from dem.studies.report_inputs import (
    COMPARISON_COLUMNS,
    cycle_series,
    is_number,
    load_results,
    read_summary,
    replica_series,
)

SUMMARY = "summary.json"


#: The files a report writes for each run (in its folder, or in its sub-folder of many runs).
RUN_FILES = ("velocity_per_cycle.png", "pointmass_comparison.png", "atlas_point.png",
             "discharge.png",
             "bed_snapshot.png", "report.txt")  # fmt: skip
#: The files a report of many runs writes beside the runs' sub-folders.
COMPARISON_FILES = ("comparison.csv", "comparison.json", "comparison.txt", "comparison.png")


def running_statistics(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Running mean and its standard error over the first k values, k = 1..C.

    :func:`dem.physics.measure.running_mean_and_stderr`, so the last point is the run's summary
    value.

    Args:
        values: (C,) samples (per-cycle means, m/s).

    Returns:
        (mean (C,), stderr (C,)); stderr_k = std(first k, ddof=1) sqrt(2 tau_k / k), tau_k the
        integrated autocorrelation time of the first k values
        (:func:`dem.physics.measure.correlated_stderr`); nan for k = 1.

    """
    return measure.running_mean_and_stderr(values)


def make_report(out_dirs: list[Path], dest: Path | None = None,
                atlas: Path | None = None) -> list[Path]:  # fmt: skip
    """Write the figures and texts of one or several runs (see the module docstring).

    Every ``summary.json`` and ``results.h5`` is read and checked before the first report file
    is written, so a corrupt one ends the report with nothing written.

    Args:
        out_dirs: Run output folders, each with ``summary.json`` (``results.h5`` optional).
        dest: Report folder; default ``OUT/report`` for one run, ``<common parent>/report`` for
            several.
        atlas: An atlas.csv of ``dem atlas`` to draw each run's drive on (``atlas_point.png``);
            default the shipped one (``dem/data/atlas``), none where it is not there.

    Returns:
        The files written.

    Raises:
        FileNotFoundError: A folder has no ``summary.json``.
        InputError: A ``summary.json`` or ``results.h5`` that is not what a dem run writes
            (cut short, of another shape, mistyped, unreadable): one line naming the file.

    """
    out_dirs = [Path(d) for d in out_dirs]
    if not out_dirs:
        raise ValueError("make_report needs at least one output folder")
    for d in out_dirs:
        if not (d / SUMMARY).is_file():
            raise FileNotFoundError(f"{d / SUMMARY} not found: is {d} a dem run folder?")
    inputs = [(read_summary(d / SUMMARY), load_results(d)) for d in out_dirs]
    from dem.run import bulk

    table = bulk.default_table() if atlas is None else Path(atlas)
    atlas_rows = bulk.read_table(table) if table is not None else None
    given = dest
    if dest is None:
        if len(out_dirs) == 1:
            dest = out_dirs[0] / "report"
        else:
            dest = Path(os.path.commonpath([d.resolve() for d in out_dirs])) / "report"
    dest = Path(dest)
    labels = _labels(out_dirs)
    # every name the report writes checked for a link before anything is drawn or written: the
    # default folder (a name dem chose), the runs' sub-folders and the files in them
    names = list(COMPARISON_FILES) if len(out_dirs) > 1 else []
    for label in labels:
        run_names = RUN_FILES if len(out_dirs) == 1 else [f"{label}/{n}" for n in RUN_FILES]
        names += run_names
    if given is None and dest.is_symlink():  # OUT/report: a name dem chose
        raise link_refused(dest)
    refuse_links(dest, names)
    dest.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    rows = []
    for label, d, (summary, results) in zip(labels, out_dirs, inputs, strict=True):
        run_dest = dest if len(out_dirs) == 1 else own_folder(dest / label)
        files, row = _report_run(d, run_dest, label, summary, results, atlas_rows)
        written += files
        rows.append(row)
    if len(out_dirs) > 1:
        written += _comparison(rows, dest)
    return written


def _labels(out_dirs: list[Path]) -> list[str]:
    names = [d.resolve().name or "run" for d in out_dirs]
    if len(set(names)) < len(names):  # e.g. several cases/*/output: use the parent's name too
        names = [f"{d.resolve().parent.name}_{d.resolve().name}" for d in out_dirs]
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}_{seen[n]}")
    return out


def _num(summary: dict, key: str) -> float:
    v = summary.get(key)
    return float(v) if isinstance(v, int | float) else math.nan


def _report_run(d: Path, dest: Path, label: str, summary: dict, results: dict | None,
                atlas_rows: list[dict] | None = None) -> tuple[list[Path], dict]:  # fmt: skip
    files: list[Path] = []
    notes: list[str] = []
    case = summary.get("case", label)
    title = f"{case}: " + plots.held_text(_drive_values(summary))

    series = cycle_series(summary, results)
    if series is not None:
        c, v, measured, source = series
        mean = np.full(v.size, np.nan)
        err = np.full(v.size, np.nan)
        mean[measured], err[measured] = running_statistics(v[measured])
        others = replica_series(d, summary)
        pooled = None
        if others:
            pooled = (_num(summary, "mean_velocity"), _num(summary, "mean_velocity_stderr"))
        files.append(
            plots.velocity_cycles_figure(
                c, v, mean, err, dest / "velocity_per_cycle.png", measured=measured, title=title,
                replicas=others, pooled=pooled,
            )
        )  # fmt: skip
        notes.append(f"per-cycle velocities from {source} ({v.size} cycles)"
                     + (f" and {len(others)} more fills' summaries" if others else ""))  # fmt: skip
    else:
        notes.append("no per-cycle velocities: velocity_per_cycle.png skipped")

    dem_norm = _num(summary, "mean_velocity_norm")
    dem_err = _num(summary, "mean_velocity_norm_stderr")
    if math.isnan(dem_err):
        scale = _num(summary, "mean_velocity") / dem_norm if dem_norm else math.nan
        dem_err = _num(summary, "mean_velocity_stderr") / scale if scale else math.nan
    pm = _num(summary, "pointmass_velocity_norm")
    bounded = _num(summary, "pointmass_bounded_velocity_norm")
    files.append(
        plots.pointmass_comparison_figure(
            [label],
            [dem_norm],
            [dem_err],
            [pm],
            dest / "pointmass_comparison.png",
            bounded_norm=[bounded],
            title=f"DEM and point mass, {title}",
        )  # fmt: skip
    )

    drawn = _atlas_point(dest, summary, results, atlas_rows, dem_norm, dem_err, bounded)
    if isinstance(drawn, Path):
        files.append(drawn)
    else:
        notes.append(f"atlas_point.png skipped: {drawn}")

    feeder = summary.get("feeder")
    cycles = results["cycles"] if results is not None else {}
    if feeder and "discharge_rate" in cycles:
        files.append(
            plots.discharge_figure(
                cycles["time"],
                cycles["discharge_rate"],
                cycles["mass_in_trough"],
                dest / "discharge.png",
                measured=cycles.get("measured", None),
                steady=feeder.get("discharge_rate"),
                steady_err=feeder.get("discharge_rate_stderr"),
                feed_rate=feeder.get("feed_rate"),
                title=f"{case}: discharge at x = {feeder.get('length', math.nan):g} m",
            )  # fmt: skip
        )
    elif feeder:
        notes.append("no per-cycle discharge in results.h5: discharge.png skipped")

    if results is not None and results["frame_count"] > 0:
        frame = results["last_frame"]
        tr = results["case"].get("trough", {}) if isinstance(results["case"], dict) else {}
        length = float(tr.get("length") or np.ptp(frame["positions"][:, 0]) or 1.0)
        width = float(tr.get("width") or 2 * np.max(np.abs(frame["positions"][:, 1])) or 1.0)
        files.append(
            plots.bed_snapshot_figure(
                frame["positions"],
                frame["radius"],
                frame["velocity"][:, 0],
                length,
                width,
                dest / "bed_snapshot.png",
                title=f"{title}; last frame, t = {frame['time']:.4g} s",
            )  # fmt: skip
        )
        complete = "complete" if results["complete"] else "INCOMPLETE (run did not close it)"
        notes.append(f"results.h5: {results['frame_count']} frames, {complete}")
    else:
        notes.append("no frames in results.h5: bed_snapshot.png skipped")

    ratio = dem_norm / pm if pm and not math.isnan(pm) else math.nan
    row = {k: summary.get(k) for k in COMPARISON_COLUMNS}
    row.update(
        run=label,
        case=case,
        mean_velocity_norm_stderr=dem_err,
        dem_over_pointmass=ratio,
        cycles=summary.get("cycles"),
        replicas=summary.get("replicas", 1),
    )
    text = _run_text(label, d, summary, dem_err, ratio, notes)
    replace_text(dest / "report.txt", shown_text(text), encoding="ascii", errors="replace")
    files.append(dest / "report.txt")
    return files, row


def _atlas_point(dest, summary, results, rows, dem_norm, dem_err, bounded) -> Path | str:
    """``atlas_point.png``, the run's drive on the atlas's map; else why not, in words.

    The map: bulk / bounded point mass over phi and Gamma, for the run's shape at the atlas's
    nearest depth and friction; the run's own ratio as a star.
    """
    if rows is None:
        return "no atlas (dem/data/atlas/atlas.csv is computed by validation/atlas; --atlas CSV)"
    case = results["case"] if results is not None and isinstance(results.get("case"), dict) else {}
    shape = (case.get("particles") or {}).get("shape")
    if shape is None:
        shape = "sphere" if summary.get("spheres") == summary.get("grains") else "screw"
    layers = (summary.get("bed") or {}).get("layers")
    friction, gamma, phi = (summary.get(k) for k in ("friction", "throw_number", "angle"))
    if not all(is_number(v) for v in (layers, friction, gamma, phi)):
        return "the summary lacks the bed's layers, friction, throw number or angle"
    mine = [r for r in rows if r["shape"] == shape]
    if not mine:
        return f"the atlas has no {shape}s"
    near_layers = min({r["particles.layers"] for r in mine}, key=lambda v: abs(v - layers))
    mine = [r for r in mine if r["particles.layers"] == near_layers]
    near_mu = min({r["material.friction"] for r in mine}, key=lambda v: abs(v - friction))
    mine = [r for r in mine if r["material.friction"] == near_mu]
    points = []
    for r in mine:
        pm = r.get("pointmass_bounded_velocity_norm")
        if is_number(pm) and abs(pm) > 1e-3:
            points.append(
                (
                    r["drive.angle_deg"],
                    r["drive.throw_number"],
                    r["mean_velocity_norm"] / pm,
                    r["mean_velocity_norm_stderr"] / abs(pm),
                )
            )
    ratio = dem_norm / bounded if is_number(bounded) and abs(bounded) > 1e-3 else math.nan
    err = dem_err / abs(bounded) if is_number(bounded) and abs(bounded) > 1e-3 else math.nan
    title = (
        f"atlas: {shape}s, {near_layers:g} layers (this bed {layers:.2g}), mu "
        f"{near_mu:g} (this run {friction:g})"
    )
    return plots.atlas_point_figure(points, (phi, gamma, ratio, err), dest / "atlas_point.png",
                                    title=title)  # fmt: skip


def _fmt(v, spec: str = ".4g") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "n/a"
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def feeder_lines(f: dict | None) -> list[str]:
    """A finite feeder's discharge and grain balance as report.txt and ``dem run`` print them.

    ``f`` is summary.json's ``feeder`` (None or empty for a periodic section: no lines).
    """
    if not f:
        return []
    from dem.physics.measure import with_error

    return [
        f"discharge          {with_error(f.get('discharge_rate'), f.get('discharge_rate_stderr'))}"
        f" kg/s at x = {_fmt(f.get('length'))} m (feed {_fmt(f.get('feed_rate'))} kg/s)",
        f"grain balance      {_fmt(f.get('grains_inserted'))} inserted = "
        f"{_fmt(f.get('grains_in_trough'))} in the trough + {_fmt(f.get('grains_discharged'))} "
        f"discharged; feed backlog {_fmt(f.get('feed_backlog'))}",
    ]


def _run_text(label, d, s, dem_err, ratio, notes) -> str:
    g = s.get
    lines = [
        f"dem report: {label} ({d})",
        "",
        f"case            {g('case', 'n/a')}",
        f"drive           f = {_fmt(g('frequency'))} Hz, A = {_fmt(g('amplitude'))} m, "
        f"phi = {_fmt(g('angle'))} deg, Gamma = {_fmt(g('throw_number'))}, "
        f"alpha = {_fmt(g('inclination'))} deg",
        f"material        mu = {_fmt(g('friction'))}, contact {g('contact_model', 'n/a')}",
        f"grains          {_fmt(g('grains'))} ({_fmt(g('spheres'))} spheres, "
        f"{_fmt(g('total_mass'))} kg)",
        f"cycles          {_fmt(g('settle_cycles'))} settling + {_fmt(g('cycles'))} measured",
        "",
        f"v               {_fmt(g('mean_velocity'))} +- {_fmt(g('mean_velocity_stderr'))} m/s"
        + _error_label(s),
        f"v/(A w cos phi) {_fmt(g('mean_velocity_norm'))} +- {_fmt(dem_err)}",
        f"point mass      {_fmt(g('pointmass_velocity_norm'))}  (DEM / point mass = "
        f"{_fmt(ratio, '.3f')})",
        *_bounded_lines(g("pointmass_velocity_norm"), g("pointmass_bounded_velocity_norm")),
        f"mass flow       {_fmt(g('mass_flow_rate'))} kg/s "
        f"({_fmt(g('mass_flow_rate_per_width'))} kg/(s m))",
        *feeder_lines(g("feeder")),
        "",
        f"timestep        {_fmt(g('timestep'))} s (limit {_fmt(g('timestep_limit'))} s), "
        f"{_fmt(g('steps'))} steps",
        f"wall time       {_fmt(g('wall_time_s'))} s, {_fmt(g('particle_steps_per_s'), '.3g')} "
        f"particle-steps/s on {_fmt(g('threads'))} threads",
        "",
        *[f"note: {n}" for n in notes],
        "",
    ]
    return "\n".join(lines)


def _comparison(rows: list[dict], dest: Path) -> list[Path]:
    from dem.io.tables import SUMMARY_UNITS, summary_column, write_csv

    names = [summary_column(k) for k in COMPARISON_COLUMNS]
    meaning = {"run": "the run's output folder (its report sub-folder)",
               "dem_over_pointmass": "mean_velocity_norm over pointmass_velocity_norm",
               "replicas": "fills pooled in the run's error (1: its own per-cycle error, which "
                           "leaves the fill-to-fill spread out)"}  # fmt: skip
    columns = {
        n: {"unit": SUMMARY_UNITS.get(k, ""), "meaning": meaning.get(k, f"summary.json {k}")}
        for n, k in zip(names, COMPARISON_COLUMNS, strict=True)
    }
    csv_path = write_csv(
        dest / "comparison.csv", names, ([r.get(k) for k in COMPARISON_COLUMNS] for r in rows),
        meta={"columns": columns}, command="dem report",
    )  # fmt: skip
    shown = (
        ("run", "run", "s"),
        ("angle", "phi", ".4g"),
        ("throw_number", "Gamma", ".4g"),
        ("frequency", "f", ".4g"),
        ("friction", "mu", ".4g"),
        ("inclination", "alpha", ".4g"),
        ("grains", "grains", "d"),
        ("replicas", "fills", "d"),
        ("mean_velocity", "v m/s", ".4g"),
        ("mean_velocity_stderr", "se m/s", ".2g"),
        ("mean_velocity_norm", "v_norm", ".4g"),
        ("pointmass_velocity_norm", "pm_norm", ".4g"),
        ("dem_over_pointmass", "dem/pm", ".3f"),
        ("mass_flow_rate", "flow kg/s", ".4g"),
    )
    table = [[h for _, h, _ in shown]]
    for r in rows:
        table.append([_fmt(r.get(k), spec) if spec != "s" else str(r[k]) for k, _, spec in shown])
    widths = [max(len(row[i]) for row in table) for i in range(len(shown))]
    buf = io.StringIO()
    for row in table:
        buf.write("  ".join(c.rjust(wd) for c, wd in zip(row, widths, strict=True)).rstrip() + "\n")
    txt_path = dest / "comparison.txt"
    replace_text(txt_path, shown_text(buf.getvalue()), encoding="ascii", errors="replace")

    labels, xlabel = [r["run"] for r in rows], ""
    for key in ("angle", "throw_number"):
        vals = [r.get(key) for r in rows]
        numbers = [v for v in vals if isinstance(v, int | float)]
        if len(numbers) == len(vals) and len(set(numbers)) == len(numbers):
            others = [k for k in ("angle", "throw_number") if k != key]
            if all(len({r.get(k) for r in rows}) == 1 for k in others):
                labels, xlabel = [float(v) for v in numbers], plots.axis_label(key)
                break
    same = [k for k in _DRIVE_KEYS if len({repr(r.get(k)) for r in rows}) == 1]
    shared = {k: rows[0][k] for k in same if is_number(rows[0].get(k))}
    title = "DEM and point mass of the runs" + (
        f" at {plots.held_text(shared)}" if shared else " (no drive value in common)"
    )
    png = plots.pointmass_comparison_figure(
        labels,
        [_as_float(r.get("mean_velocity_norm")) for r in rows],
        [_as_float(r.get("mean_velocity_norm_stderr")) for r in rows],
        [_as_float(r.get("pointmass_velocity_norm")) for r in rows],
        dest / "comparison.png",
        xlabel=xlabel,
        bounded_norm=[_as_float(r.get("pointmass_bounded_velocity_norm")) for r in rows],
        title=title,
    )
    return [csv_path, txt_path, png]


#: summary.json keys that say what a run's drive and material were, in a title's order.
_DRIVE_KEYS = ("angle", "throw_number", "frequency", "friction", "inclination")


def _drive_values(summary: dict) -> dict:
    """The drive and material of a run by key, where summary.json gives them as numbers."""
    return {k: summary[k] for k in _DRIVE_KEYS if is_number(summary.get(k))}


def _error_label(s: dict) -> str:
    """What a run's +- is: one run's per-cycle error, or a pool of fills (issue 48, item 6)."""
    fills = s.get("replicas", 1)
    if isinstance(fills, int) and fills > 1:
        return (f" (+-1 standard error of {fills} fills pooled, the fill-to-fill spread "
                "included; the per-cycle figure is fill 0's)")  # fmt: skip
    return (" (+-1 standard error of this run's per-cycle means: it leaves out the "
            "fill-to-fill spread)")  # fmt: skip


def _bounded_lines(paper, bounded) -> list[str]:
    """The Coulomb-bounded point mass, where it differs from the paper's model."""
    if not isinstance(bounded, int | float) or not isinstance(paper, int | float):
        return []
    if abs(bounded - paper) <= 1e-3:
        return []
    return [
        f"bounded p. mass {_fmt(bounded)}  (landings capped by Coulomb: the DEM's reference; "
        "the paper's Eq. 12 asks for more tangential impulse than friction gives here)"
    ]


def _as_float(v) -> float:
    return float(v) if isinstance(v, int | float) else math.nan
