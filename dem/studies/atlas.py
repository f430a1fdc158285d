"""``dem atlas``: the bulk against the point mass over a grid, each point to a target error.

A grid file (TOML) names base cases by grain shape and the axes over which their keys vary::

    [atlas]
    target_error = 0.03        # each point pools fills until its standard error is 3 % of |v|
    max_replicas = 9           # ... or this many fills
    cycles = 20                # measured cycles of each fill (default: the base case's)
    flight_phases = 12         # phase bins at which the grains in flight are counted
    seed = 1001                # the first fill's seed (default: the base case's): a refill

    [atlas.cases]              # one base case per shape, relative to this file
    sphere = "../../cases/sphere-bed"
    screw = "../../cases/screw-trough"

    [[grid]]                   # a Cartesian product; several blocks add their points
    shape = ["sphere", "screw"]
    "drive.throw_number" = [1.0, 1.8, 2.6, 3.5, 4.5]
    "drive.angle" = [10, 22.5, 35, 47.5, 60]
    "material.friction" = [0.35]
    "particles.layers" = [1, 2.5, 5]

A point is a base case with its keys set (:func:`dem.scene.case.load_case` overrides, all of them
checked before anything runs; :mod:`dem.studies.atlas_grid` reads the grid and plans the points)
and ``run.target_error`` from ``[atlas]``: a bulk run that pools fills until its error bar, which
covers a refill, reaches the target (:func:`dem.run.replicas.run_replicas`). Each point runs in its
own folder ``OUT/points/<shape>/<keys>`` and the table ``OUT/atlas.csv`` (with ``atlas.json``, its
provenance and the grid, and ``atlas.h5``) gathers, per point: the bulk's v and v_norm with their
pooled error, the fills, the paper's and the Coulomb-bounded point mass, the ratio of the bulk to
each with its error, the point mass's regime and period, what the bed does (the fraction of its
grains in flight by phase of the drive, :mod:`dem.run.flight`), the bed (grains, layers, mass per
area) and the cost.

Resuming: every point folder holds ``atlas_point.json``, the resolved case it runs (the
checkpoint's fingerprint) with the target, cycles and fill cap. A rerun of the same command skips
every finished point, continues an interrupted one from its finished fills and checkpoints, and
refuses, before anything runs, a point whose record differs from what the grid now asks (a
changed base case, target or cycles), naming it and the keys; ``--rerun-stale`` moves such
folders to ``OUT/stale/`` and runs them again. SIGINT and SIGTERM stop the atlas after writing
the table of the points finished so far (exit 130 / 143).

Parallel: by default one point at a time, its fills on the cores available (one process per
fill); ``--workers N`` runs N points at once on a local Dask cluster and ``--scheduler ADDRESS``
on a running one (each point's fills then run one after the other in its task); ``--device
cuda`` steps each point's fills as one GPU batch (:mod:`dem.run.batch`).

Cost: a point costs its fills' runs (about a minute each for the shipped beds on 2 cores); the
atlas is their sum over the points, O(points); gathering reads each summary once.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import signal
import sys
import time
from pathlib import Path

from dem.errors import InputError
from dem.io.files import refuse_links, replace_text
from dem.studies.atlas_grid import POINTS_DIR as POINTS_DIR
from dem.studies.atlas_grid import AtlasPoint, Grid, plan_points, point_case, read_grid

#: The folder under ``--out`` where stale points are moved (``--rerun-stale``).
STALE_DIR = "stale"
#: A point's record of what it runs, written when it starts and again when it has finished.
RECORD = "atlas_point.json"
TABLE = "atlas"


def status(point: AtlasPoint) -> str:
    """Whether a point is "done" (summary and finished record), "started" or "new"."""
    if not point.folder.is_dir():
        return "new"
    if (point.folder / "summary.json").is_file() and _read_record(point).get("finished"):
        return "done"
    return "started"


def _read_record(point: AtlasPoint) -> dict:
    try:
        data = json.loads((point.folder / RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def stale_points(points: list[AtlasPoint]) -> list[tuple[AtlasPoint, str]]:
    """Points whose folder holds work of another case or other settings, with why."""
    from dem.run.summary import fingerprint_changes

    out = []
    for p in points:
        if status(p) == "new":
            continue
        before = _read_record(p).get("case")
        if not isinstance(before, dict):
            out.append((p, f"its folder holds no readable {RECORD}"))
            continue
        changed = fingerprint_changes(before, p.record)
        if changed:
            shown = "; ".join(changed[:3]) + (f"; and {len(changed) - 3} more" if len(changed) > 3
                                               else "")  # fmt: skip
            out.append((p, "it was run with " + shown))
    return out


def _write_record(point: AtlasPoint, finished: bool) -> None:
    point.folder.mkdir(parents=True, exist_ok=True)
    text = json.dumps({"case": point.record, "shape": point.shape, "overrides": point.overrides,
                       "finished": finished}, indent=1, default=str)  # fmt: skip
    replace_text(point.folder / RECORD, text + "\n")


class AtlasStopped(Exception):
    """SIGINT or SIGTERM stopped the atlas between or inside points."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


def run_point(point: AtlasPoint, grid: Grid, threads: int | None, device: str | None,
              progress: bool = False) -> dict:  # fmt: skip
    """Run (or continue) one point; returns its pooled summary."""
    import warnings

    from dem.run.plan import PlanWarning
    from dem.run.replicas import run_replicas

    case = point_case(grid, point.shape, point.overrides, device)
    resume = status(point) == "started" and any(point.folder.iterdir())
    _write_record(point, finished=False)
    with warnings.catch_warnings():  # the atlas gave each point's advice once, at its start
        warnings.simplefilter("ignore", PlanWarning)
        summary = run_replicas(case, point.folder, cycles=grid.cycles, threads=threads,
                               progress=progress, overwrite=False, resume=resume,
                               frames=False, warn=False)  # fmt: skip
    _write_record(point, finished=True)
    return summary


def run_atlas(grid_path: str | Path, out: str | Path, *, workers: int | None = None,
              scheduler: str | None = None, threads: int | None = None,
              device: str | None = None, rerun_stale: bool = False, progress: bool = True,
              dry_run: bool = False) -> dict:  # fmt: skip
    """Run a grid's points not yet finished, then write the table; returns a report dict."""
    from dem.run.interrupts import RunInterrupted

    grid = read_grid(grid_path)
    out = Path(out)
    points = plan_points(grid, out, device)
    refuse_links(out, [POINTS_DIR, STALE_DIR, *(f"{TABLE}{x}" for x in (".csv", ".json", ".h5"))])
    stale = stale_points(points)
    if stale and not rerun_stale:
        p, why = stale[0]
        more = f" (and {len(stale) - 1} more)" if len(stale) > 1 else ""
        raise InputError(
            "--out", str(out), f"an atlas folder whose points are this grid's: point {p.name}"
            f"{more} differs: {why}. Use --rerun-stale to move such points to {STALE_DIR}/ and "
            "run them again, or another --out",
        )  # fmt: skip
    done = [p for p in points if status(p) == "done" and all(p is not s for s, _ in stale)]
    todo = [p for p in points if p not in done]
    say = _say(progress)
    say(f"dem atlas: {len(points)} points ({len(done)} finished, {len(todo)} to run"
        + (f", {len(stale)} stale to rerun" if stale else "") + f"), target error "
        f"{grid.target_error:g}, up to {grid.max_replicas} fills a point")  # fmt: skip
    if dry_run:
        return {"points": len(points), "done": len(done), "todo": len(todo),
                "stale": len(stale)}  # fmt: skip
    from dem.run.output import locked

    with locked(out):  # a second atlas into this folder is refused, before it moves anything
        _advise(todo, grid, device, say)
        for p, _ in stale:
            target = out / STALE_DIR / f"{p.shape}-{p.folder.name}-{time.strftime('%Y%m%dT%H%M%S')}"
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.move(str(p.folder), str(target))
            say(f"dem atlas: stale point {p.name} moved to {target}")
        failed: dict[str, str] = {}
        stopped = None
        started = time.perf_counter()
        try:
            with _StopOnSignals():
                if workers and workers > 1 or scheduler:
                    failed = _run_on_dask(todo, grid, scheduler, workers, device, say)
                else:
                    for i, p in enumerate(todo):
                        t0 = time.perf_counter()
                        try:
                            s = run_point(p, grid, threads, device)
                        except AtlasStopped:
                            raise
                        except RunInterrupted as stop:  # run_case's own handler took the signal
                            raise AtlasStopped(stop.signum) from None
                        except Exception as exc:  # one point's failure leaves the others running
                            from dem.studies.sweep import failure_text

                            failed[p.name] = failure_text(exc, p.folder)
                            say(f"dem atlas: point {p.name} failed: {failed[p.name]}")
                            continue
                        say(_point_line(p, s, i + 1, len(todo), time.perf_counter() - t0,
                                        time.perf_counter() - started))  # fmt: skip
        except AtlasStopped as stop:
            stopped = stop.signum
            say(f"dem atlas: {stop} - the finished points are kept; the same command continues "
                "(an interrupted point from its finished fills and checkpoints)")  # fmt: skip
        cases = {p.index: point_case(grid, p.shape, p.overrides, device) for p in points}
        rows = gather(points, failed, cases)
        path = write_table(rows, out, grid)
        plot_maps(rows, out / f"{TABLE}.png")
        finished = sum(r["status"] == "done" for r in rows)
        say(f"dem atlas: {finished} of {len(points)} points finished; table {path}")
    return {"points": len(points), "done": finished, "failed": failed, "csv": str(path),
            "stopped": stopped}  # fmt: skip


def _advise(todo: list[AtlasPoint], grid: Grid, device: str | None, say) -> None:
    """The plan's warnings for the points to run, each distinct one once, with how many."""
    from dem.run import plan

    if len(todo) > 20:
        say(f"dem atlas: planning the {len(todo)} points to run (their advice, once each)")
    seen: dict[tuple[str, str], list[tuple[str, str]]] = {}
    for p in todo:
        case = point_case(grid, p.shape, p.overrides, device)
        for a in plan.plan(case, cycles=grid.cycles).warnings():
            shape = re.sub(r"[-+]?\d[\d.e+-]*", "#", a.text)  # the same advice, other numbers
            seen.setdefault((a.key, shape), []).append((p.name, a.text))
    for (key, _), names in seen.items():
        more = f" (and {len(names) - 1} more points)" if len(names) > 1 else ""
        say(f"dem atlas: warning: point {names[0][0]}{more}: {key}: {names[0][1]}")


def _say(progress: bool):
    def say(text: str) -> None:
        if progress:
            print(text, file=sys.stderr, flush=True)

    return say


def _point_line(p: AtlasPoint, s: dict, i: int, n: int, took: float, elapsed: float) -> str:
    eta = elapsed / i * (n - i)
    keys = ", ".join(f"{k.rsplit('.', 1)[-1]} {v:g}" if isinstance(v, float) else
                     f"{k.rsplit('.', 1)[-1]} {v}" for k, v in p.overrides.items())  # fmt: skip
    target = s.get("target", {})
    return (f"dem atlas: [{i}/{n}] {p.shape}, {keys}: v_norm {s['mean_velocity_norm']:.3f} +- "
            f"{s['mean_velocity_norm_stderr']:.2g} ({s['replicas']} fills"
            f"{'' if target.get('reached', True) else ', target NOT reached'}), {took:.0f} s; "
            f"ETA {eta / 60:.0f} min")  # fmt: skip


class _StopOnSignals:
    """SIGINT and SIGTERM raise :class:`AtlasStopped` in the main thread (workers are stopped).

    Only the first signal raises: a second one (a signal to the process group reaches this
    process and, forwarded, again) must not break off the stop itself, which stops the fill
    workers and writes the table.
    """

    def __enter__(self):
        self.old = {}
        self.raised = False
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self.old[sig] = signal.signal(sig, self._raise)
            except ValueError:  # not the main thread
                pass
        return self

    def _raise(self, signum, frame):
        if not self.raised:
            self.raised = True
            raise AtlasStopped(signum)

    def __exit__(self, *exc):
        for sig, handler in self.old.items():
            signal.signal(sig, handler)


def _run_on_dask(todo: list[AtlasPoint], grid: Grid, scheduler, workers, device, say) -> dict:
    """Points as Dask tasks (each point's fills one after the other in its task)."""
    from dask.distributed import as_completed

    from dem.studies.sweep import dask_client, failure_text

    failed: dict[str, str] = {}
    if not todo:
        return failed
    client, cluster = dask_client(scheduler, min(workers or 1, len(todo)), "dem atlas")
    try:
        futures = {client.submit(run_point, p, grid, 1, device, key=f"dem-atlas-{p.index}",
                                 pure=False): p for p in todo}  # fmt: skip
        started = time.perf_counter()
        for i, future in enumerate(as_completed(futures), 1):
            p = futures[future]
            if future.status == "error":
                failed[p.name] = failure_text(future.exception(), p.folder)
                say(f"dem atlas: point {p.name} failed: {failed[p.name]}")
                continue
            elapsed = time.perf_counter() - started
            say(_point_line(p, future.result(), i, len(todo), elapsed / i, elapsed))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return failed


#: The table's columns beyond the point's own keys, in order.
COLUMNS = (
    "mean_velocity", "mean_velocity_stderr", "mean_velocity_norm", "mean_velocity_norm_stderr",
    "fills", "target_reached", "pointmass_velocity_norm", "pointmass_bounded_velocity_norm",
    "ratio_bounded", "ratio_bounded_stderr", "ratio_paper", "ratio_paper_stderr",
    "pointmass_regime", "pointmass_period", "throw_number", "angle", "friction",
    "youngs_modulus", "timestep", "in_flight_mean", "in_flight_max", "in_flight_max_phase",
    "in_flight_by_phase", "grains",
    "spheres", "layers", "mass_per_area", "velocity_scale", "elapsed_s", "cpu_s",
    "particle_steps",
)  # fmt: skip


def gather(
    points: list[AtlasPoint], failed: dict[str, str], cases: dict | None = None
) -> list[dict]:
    """One row per point: shape and keys, the bulk, the point masses, the ratios and the cost.

    ``cases``: each point's case by index, for the point mass's regime (none: no regime).
    """
    from dem import pointmass
    from dem.studies.report_inputs import read_summary

    cases = cases or {}
    rows = []
    keys = sorted({k for p in points for k in p.overrides})
    for p in points:
        row = {"shape": p.shape} | {k: p.overrides.get(k) for k in keys}
        state = status(p)
        if state != "done":
            rows.append(row | {c: None for c in COLUMNS} | {
                "status": "failed" if p.name in failed else
                ("interrupted" if state == "started" else "not run"),
                "error": failed.get(p.name, "")})  # fmt: skip
            continue
        s = read_summary(p.folder / "summary.json", "--out")
        v, e = s["mean_velocity_norm"], s["mean_velocity_norm_stderr"]
        pm, bounded = s.get("pointmass_velocity_norm"), s.get("pointmass_bounded_velocity_norm")
        regime, period = None, None
        case = cases.get(p.index)
        if case is not None and case.drive.is_single:
            w = case.wall_material  # the point mass touches the floor only
            r = pointmass.velocity(case.drive.throw_number, case.drive.angle, w.friction,
                                   case.trough.inclination, w.restitution_tangential,
                                   w.restitution_normal)  # fmt: skip
            regime, period = r.regime, r.period
        bed = s.get("bed") or {}
        fraction = (s.get("flight") or {}).get("fraction") or []
        top = max(range(len(fraction)), key=fraction.__getitem__) if fraction else None
        rate, loops = s.get("particle_steps_per_s"), s.get("wall_time_s")
        steps = rate * loops / s.get("processes", 1) if rate and loops else None
        rows.append(row | {
            "mean_velocity": s["mean_velocity"], "mean_velocity_stderr": s["mean_velocity_stderr"],
            "mean_velocity_norm": v, "mean_velocity_norm_stderr": e,
            "fills": s.get("replicas", 1),
            "target_reached": (s.get("target") or {}).get("reached"),
            "pointmass_velocity_norm": pm, "pointmass_bounded_velocity_norm": bounded,
            "ratio_bounded": _ratio(v, bounded), "ratio_bounded_stderr": _ratio(e, bounded, True),
            "ratio_paper": _ratio(v, pm), "ratio_paper_stderr": _ratio(e, pm, True),
            "pointmass_regime": regime, "pointmass_period": period,
            "throw_number": s["throw_number"], "angle": s["angle"],
            "friction": (s.get("wall") or {}).get("friction", s["friction"]),
            "youngs_modulus": case.contact.youngs_modulus if case is not None else None,
            "timestep": s["timestep"],
            "in_flight_mean": sum(fraction) / len(fraction) if fraction else None,
            "in_flight_max": fraction[top] if top is not None else None,
            "in_flight_max_phase": s["flight"]["phase_deg"][top] if top is not None else None,
            "in_flight_by_phase": ";".join(f"{x:.4g}" for x in fraction) or None,
            "grains": s["grains"], "spheres": s["spheres"], "layers": bed.get("layers"),
            "mass_per_area": bed.get("mass_per_area_kg_m2"),
            "velocity_scale": s["velocity_scale"], "elapsed_s": s.get("elapsed_s"),
            "cpu_s": s.get("wall_time_s"), "particle_steps": steps,
            "status": "done", "error": "",
        })  # fmt: skip
    return rows


def _ratio(value, reference, error: bool = False):
    if value is None or reference is None or not math.isfinite(value) or abs(reference) < 1e-3:
        return None  # a point mass at rest: no ratio
    return abs(value / reference) if error else value / reference


def write_table(rows: list[dict], out: Path, grid: Grid) -> Path:
    """``atlas.csv``, its sidecar ``atlas.json`` (provenance, the grid) and ``atlas.h5``."""
    from dem.studies.sweep_table import write_table as write_sweep_table

    context = {"grid": str(grid.path), "target_error": grid.target_error,
               "stiffness": grid.stiffness,
               "max_replicas": grid.max_replicas, "cycles": grid.cycles,
               "cases": {k: str(v) for k, v in grid.cases.items()},
               "meaning": {
                   "ratio_bounded": "bulk v_norm over the Coulomb-bounded point mass's",
                   "ratio_paper": "bulk v_norm over the paper's point mass's (its Eq. 12)",
                   "fills": "fills pooled (run.target_error reached, or run.max_replicas)",
                   "pointmass_regime": "the paper's point mass's regime on the point's drive",
                   "in_flight_by_phase": "fraction of grains touching nothing at the end of "
                   "each phase bin (flight_phases per cycle, from phase 0), ';'-separated",
                   "in_flight_max_phase": "the phase bin's end, deg, where most grains fly",
                   "cpu_s": "the fills' step loops, summed (compile and fill excluded)",
                   "elapsed_s": "the point's wall time, as waited",
               }}  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    return write_sweep_table(rows, out, context, table=TABLE, command="dem atlas")


def plot_maps(rows: list[dict], path: Path) -> None:
    """The ratio to the bounded point mass over (angle, throw number), a panel per shape x depth."""
    from dem.studies import plots

    done = [r for r in rows if r["status"] == "done" and r["ratio_bounded"] is not None]
    if not done:
        return
    plt = plots.plt
    depth_key = next((k for k in ("particles.layers", "particles.bed_height",
                                  "particles.mass_per_area") if k in rows[0]), None)  # fmt: skip
    panels = sorted({(r["shape"], r.get(depth_key) if depth_key else None) for r in done},
                    key=lambda t: (t[0], t[1] or 0))  # fmt: skip
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.8), squeeze=False)
    for ax, (shape, depth) in zip(axes[0], panels, strict=True):
        sel = [r for r in done if r["shape"] == shape and (not depth_key or r[depth_key] == depth)]
        sc = ax.scatter([r["angle"] for r in sel], [r["throw_number"] for r in sel],
                        c=[r["ratio_bounded"] for r in sel], cmap="coolwarm", vmin=0.5, vmax=1.5,
                        s=90, edgecolors="k")  # fmt: skip
        for r in sel:
            ax.annotate(f"{r['ratio_bounded']:.2f}", (r["angle"], r["throw_number"]),
                        fontsize=6, ha="center", va="bottom", xytext=(0, 6),
                        textcoords="offset points")  # fmt: skip
        ax.set_xlabel("vibration angle phi (deg)")
        ax.set_ylabel("throw number Gamma")
        ax.set_title(f"{shape}" + (f", {depth_key.split('.')[-1]} {depth:g}" if depth_key else ""),
                     fontsize=9)  # fmt: skip
        ax.grid(alpha=0.3)
    fig.colorbar(sc, ax=axes[0].tolist(), label="bulk / bounded point mass (v_norm)")
    fig.suptitle("The bulk against the point mass", fontsize=10)
    plots.save(fig, path)
