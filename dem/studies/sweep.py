"""``dem sweep``: a grid of cases from one case directory, run on Dask, gathered into one table.

``dem sweep CASE_DIR --set drive.angle=10:60:5 --set material.friction=0.25,0.35`` runs the
Cartesian product of the ``--set`` values. Each point is the case with those keys overridden
(:func:`dem.scene.case.load_case` ``overrides``: checked as if written in the file, all of them
before anything runs) and runs ``dem run`` into its own folder under ``--out``. Points run as tasks
on Dask (``dask.distributed``, the ``sweep`` extra): a local cluster of one-thread workers, one per
core, by default; a running ``dask scheduler`` when ``--scheduler ADDRESS`` is given (the point
folders must then be on storage that every worker sees).

Under ``--device cuda`` (or ``run.device = "cuda"``) the points of a new sweep that differ only in
:data:`BATCH_KEYS` (the drive's angle, amplitude or throw number, the incline, the seed) run as one
GPU job instead (:mod:`dem.run.batch`: each point its own folder, summary and record, one time
step for all, the smallest of theirs); if that batch stops on an error the points run one by one.

A grid of more than :data:`MAX_POINTS` points is refused before a case is loaded: each point
is a whole ``dem run``. A rerun skips the points whose folder holds a summary.json and resumes
the ones that hold a checkpoint. A finished point is reused only when its case and run options
are this sweep's: each finished point's folder holds ``sweep_point.json``, the resolved case
(:func:`dem.run.summary.fingerprint`, as a checkpoint records it) with the measured cycles and the
frames setting; a finished point without it, or of another case or other options, is refused
before anything runs, naming the point and each key that differs, and left as it is. A point
that fails (bad physics the guard stops, a lost worker) is reported with its error and leaves
the others running; the sweep's exit status says that some failed. The results
are gathered into ``sweep.csv`` (units in the column names, its provenance in ``sweep.json``),
``sweep.h5`` (one dataset per column) and ``sweep.png`` (the bulk velocity in m/s and normalised
against the first swept key, the point-mass model beside it, the held values in the title;
:mod:`dem.studies.sweep_table`).

Cost: the points are independent; a grid of P points takes about P / workers times one run.
Gathering reads each summary.json once: O(P).
"""

from __future__ import annotations

import itertools
import json
import logging
import math
import re
import warnings
from pathlib import Path

from dem.errors import InputError
from dem.io.files import refuse_links
from dem.studies.sweep_table import TABLE, SweepPoint, gather, held_values, plot, write_table

#: Keys that take whole numbers.
WHOLE = {"count", "cycles", "settle_cycles", "seed", "frames_per_cycle"}
#: Most points one ``dem sweep`` runs: each is a whole ``dem run`` (seconds to hours), so 1e4
#: points is days of a cluster at the least; ``dem pointmass sweep`` allows 1e6 cheap points.
MAX_POINTS = 10_000
#: The record of the case and options a finished point ran with, beside its summary.json.
RECORD = "sweep_point.json"
#: The files a sweep writes beside its points' folders.
TABLE_FILES = (f"{TABLE}.csv", f"{TABLE}.json", f"{TABLE}.h5", f"{TABLE}.png")
#: Swept keys whose points can share one GPU batch (``--device cuda``): each point's body
#: acceleration is its own (:mod:`dem.engine.gpu.replicas`); law, section and period are shared.
BATCH_KEYS = frozenset(
    {"drive.angle", "drive.throw_number", "drive.amplitude", "trough.inclination", "run.seed"}
)


def parse_set(text: str) -> tuple[str, list]:
    """Parse ``"table.key=values"`` into the key and its list of values.

    Values as ``dem pointmass sweep`` takes them (a number, a comma list, start:stop:step with
    stop included), or words (``contact.model=linear,hertz_mindlin``).
    """
    from dem.pointmass.sweep import parse_values

    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or "." not in key or not values.strip():
        raise InputError("--set", text, "table.key=values, e.g. drive.angle=10:60:5")
    words = [v.strip() for v in values.split(",")]
    try:
        numbers = parse_values(values.strip(), f"--set {key}")
    except InputError:
        if ":" in values:
            raise
        return key, [_word(w) for w in words]
    if key.rsplit(".", 1)[1] in WHOLE:
        if not all(float(v).is_integer() for v in numbers):
            raise InputError(f"--set {key}", values, "whole numbers") from None
        return key, [int(v) for v in numbers]
    if all(re.fullmatch(r"\s*[+-]?\d+\s*", t) for t in re.split(r"[,:]", values)):
        return key, [int(v) for v in numbers]  # written as integers: read as the file would
    return key, numbers


def _word(text: str):
    return {"true": True, "false": False}.get(text.lower(), text)


def grid(sets: list[tuple[str, list]]) -> list[dict]:
    """The Cartesian product of the ``--set`` values, in order (the last key varies fastest)."""
    keys = [k for k, _ in sets]
    if len(set(keys)) != len(keys):
        raise InputError("--set", ", ".join(keys), "each key at most once")
    sizes = [len(v) for _, v in sets]
    total = math.prod(sizes)
    if total > MAX_POINTS:
        shape = " x ".join(str(n) for n in sizes)
        raise InputError(
            "--set", total, f"a DEM sweep of at most {MAX_POINTS} points ({shape} values of "
            f"{', '.join(keys)}): each point is a whole dem run; sweep fewer values, or in parts",
        )  # fmt: skip
    return [
        dict(zip(keys, combo, strict=True)) for combo in itertools.product(*(v for _, v in sets))
    ]


def folder_name(index: int, overrides: dict) -> str:
    """``003_drive.angle=25_material.friction=0.35`` (safe on every file system)."""
    parts = [f"{k}={_fmt(v)}" for k, v in overrides.items()]
    return re.sub(r"[^A-Za-z0-9_.=+-]", "-", f"{index:03d}_" + "_".join(parts))


def _fmt(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def plan_points(case_dir: Path, sets: list[tuple[str, list]], out: Path, *,
                cycles: int | None = None, frames: bool = False,
                device: str | None = None) -> list[SweepPoint]:  # fmt: skip
    """The points, each checked by loading its case (an error names the point and the key).

    ``device`` (``--device``) overrides every point's ``run.device``; each point's device is
    checked against its case (:func:`dem.engine.device.check_device`) here, before any runs.
    """
    from dem.engine.device import check_device
    from dem.scene.case import load_case

    points = []
    for i, overrides in enumerate(grid(sets)):
        try:
            case = load_case(case_dir, overrides | device_override(device))
            check_device(case.run.device, case)
        except InputError as err:
            raise InputError(err.key, err.value, f"{err.allowed} (sweep point {overrides})",
                             err.source) from None  # fmt: skip
        points.append(SweepPoint(i, overrides, out / folder_name(i, overrides),
                                 record(case, cycles, frames)))  # fmt: skip
    return points


def device_override(device: str | None) -> dict:
    """``--device`` as a load_case override of every point (none when it is not given).

    Kept apart from a point's own overrides, which name its folder and its row of the table.
    """
    return {} if device is None else {"run.device": device}


def record(case, cycles: int | None, frames: bool) -> dict:
    """What a finished point ran, as :data:`RECORD` holds it.

    The resolved case as a checkpoint records it (every key but the name and the folder), the
    measured cycles and whether frames were written.
    """
    from dem.run.summary import fingerprint

    measured = case.run.cycles if cycles is None else int(cycles)
    return fingerprint(case) | {"cycles": measured, "frames": bool(frames)}


def check_finished(points: list[SweepPoint], out: Path) -> None:
    """Refuse to reuse a finished point that this sweep would not have made.

    Each finished point's :data:`RECORD` must equal its planned record and its summary.json
    must read (:func:`dem.studies.report.read_summary`); otherwise an :class:`InputError` names the
    point and each key that differs (or what is missing). Nothing is changed: the finished
    point stays for the user to keep or move away.
    """
    from dem.run.output import SUMMARY
    from dem.run.summary import fingerprint_changes
    from dem.studies.report_inputs import read_summary

    differ: list[tuple[SweepPoint, str]] = []
    for p in points:
        if status(p) != "done":
            continue
        path = p.folder / RECORD
        try:
            before = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
        except (OSError, ValueError):
            before = None
        if not isinstance(before, dict):
            why = (f"it holds {SUMMARY} but no readable record ({RECORD}) of the case and "
                   "options that made it (an older dem, or copied in)")  # fmt: skip
            differ.append((p, why))
            continue
        assert p.record is not None  # a planned point carries its record
        changed = fingerprint_changes(before, p.record)
        if changed:
            differ.append((p, "it was run with " + "; ".join(changed)))
        else:
            read_summary(p.folder / SUMMARY, "--out")
    if differ:
        p, why = differ[0]
        more = f" (and {len(differ) - 1} more points)" if len(differ) > 1 else ""
        raise InputError(
            "--out", str(out), f"a sweep folder whose finished points are of this case and "
            f"options: point {p.name}{more} differs: {why}. Choose another --out, or move the "
            "point's folder away to run it again",
        )  # fmt: skip


def written_names(points: list[SweepPoint]) -> list[str]:
    """Every name a sweep writes under its folder, checked for links at the door.

    The table, the figure, the points' folders, and what ``dem run`` and the record write in
    each.
    """
    from dem.run.output import RUN_OUTPUTS

    names = [*TABLE_FILES]
    for p in points:
        names += [p.name] + [f"{p.name}/{n}" for n in (RECORD, *RUN_OUTPUTS)]
    return names


def status(point: SweepPoint) -> str:
    """Whether a point is "done" (summary.json), "interrupted" (a checkpoint) or "new"."""
    from dem.run.output import CHECKPOINT, SUMMARY

    if (point.folder / SUMMARY).is_file():
        return "done"
    if (point.folder / CHECKPOINT).is_file():
        return "interrupted"
    return "new"


def one_fill_note(command: str, case_dir: Path, sets, progress: bool) -> None:
    """Say that a sweep's point is one fill whatever run.replicas says.

    A point's error bar is then one run's, which leaves out the fill-to-fill spread.
    """
    import sys

    from dem.scene.case import load_case

    if not progress or any(key == "run.seed" for key, _ in sets):
        return
    from dem.run.replicas import fill_keys

    run = load_case(case_dir).run
    if run.replicas > 1:
        print(f"{command}: {fill_keys(run)} is not applied: each point is one fill "
              "(its error bar leaves out the fill-to-fill spread); sweep run.seed too "
              "(--set run.seed=1,2,3) and pool the fills of a point", file=sys.stderr,
              flush=True)  # fmt: skip


def run_point(case_dir: str, overrides: dict, folder: str, cycles, threads: int,
              frames: bool, device: str | None = None) -> dict:  # fmt: skip
    """Run one point (a Dask task; also callable directly); returns its summary.

    The point's :data:`RECORD` is removed before the run and written after it finished, so a
    summary.json beside a record is always the record's. ``device``: ``--device``, over the
    case's ``run.device``.
    """
    from dem.io.files import replace_text
    from dem.run.plan import PlanWarning
    from dem.run.runner import run_case
    from dem.scene.case import load_case

    case = load_case(case_dir, overrides | device_override(device))
    point = SweepPoint(0, overrides, Path(folder))
    refuse_links(point.folder.parent, [point.name, f"{point.name}/{RECORD}"])
    resume = status(point) == "interrupted"
    (point.folder / RECORD).unlink(missing_ok=True)
    with warnings.catch_warnings():  # the sweep warns once, for its first point
        warnings.simplefilter("ignore", PlanWarning)
        summary = run_case(case, Path(folder), cycles=cycles, threads=threads, progress=False,
                           overwrite=not resume and Path(folder).exists(), resume=resume,
                           frames=frames)  # fmt: skip
    replace_text(point.folder / RECORD, json.dumps(record(case, cycles, frames), indent=1) + "\n")
    return summary


def run_sweep(
    case_dir: str | Path,
    sets: list[tuple[str, list]],
    out: str | Path,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    threads: int = 1,
    cycles: int | None = None,
    frames: bool = False,
    progress: bool = True,
    device: str | None = None,
) -> dict:
    """Run a sweep; returns ``{"points", "done", "skipped", "failed": {name: error}, "csv"}``.

    ``device``: ``"cpu"`` or ``"cuda"`` over every point's ``run.device`` (``--device``).
    """
    case_dir, out = Path(case_dir), Path(out)
    points = plan_points(case_dir, sets, out, cycles=cycles, frames=frames, device=device)
    one_fill_note("dem sweep", case_dir, sets, progress)
    refuse_links(out, written_names(points))
    check_finished(points, out)
    todo = [p for p in points if status(p) != "done"]
    skipped = len(points) - len(todo)
    failed: dict[str, str] = {}
    if _run_as_batch(case_dir, todo, cycles, frames, device, progress):
        todo = []
    if todo:
        from dask.distributed import as_completed

        from dem import config

        n = workers or max(1, config.default_threads() // max(threads, 1))
        client, cluster = dask_client(scheduler, min(n, len(todo)), "dem sweep")
        try:
            out.mkdir(parents=True, exist_ok=True)
            _warn_plan(case_dir, todo[0], threads, cycles, device)
            futures = {
                client.submit(run_point, str(case_dir), p.overrides, str(p.folder), cycles,
                              threads, frames, device, key=f"dem-sweep-{p.name}",
                              pure=False): p
                for p in todo
            }  # fmt: skip
            bar = None
            if progress:
                from tqdm import tqdm

                bar = tqdm(total=len(points), initial=skipped, unit="point", desc="dem sweep")
            for future in as_completed(futures):
                p = futures[future]
                if future.status == "error":
                    failed[p.name] = failure_text(future.exception(), p.folder)
                    if bar is not None:
                        bar.write(f"dem sweep: point {p.name} failed: {failed[p.name]}")
                if bar is not None:
                    bar.update(1)
            if bar is not None:
                bar.close()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    out.mkdir(parents=True, exist_ok=True)
    rows = gather(points, failed)
    context = {"case_dir": str(case_dir.resolve()), "set": dict(sets),
               "cycles": cycles, "frames": frames}  # fmt: skip
    csv_path = write_table(rows, out, context)
    plot(rows, out / f"{TABLE}.png", [k for k, _ in sets], held=held_values(case_dir, sets))
    return {"points": len(points), "done": len(points) - len(failed), "skipped": skipped,
            "failed": failed, "csv": str(csv_path)}  # fmt: skip


def _run_as_batch(case_dir: Path, todo: list[SweepPoint], cycles, frames: bool,
                  device: str | None, progress: bool) -> bool:  # fmt: skip
    """Run the points as one GPU batch (:func:`dem.run.batch.run_batch`) where they can be.

    They can where they run on ``cuda``, are new (none to resume) and differ only in
    :data:`BATCH_KEYS`. Returns whether they ran. If the batch stops on an error (one point's
    blow-up stops them all) it says so and returns False: the points then run one by one, so
    that a failing point leaves the others running.
    """
    from dem.errors import SimulationError
    from dem.io.files import replace_text
    from dem.run.batch import batchable, run_batch
    from dem.scene.case import load_case

    if len(todo) < 2 or any(status(p) != "new" for p in todo):
        return False
    if any(set(p.overrides) - BATCH_KEYS for p in todo):
        return False
    cases = [load_case(case_dir, p.overrides | device_override(device)) for p in todo]
    if batchable(cases[0]) is not None:
        return False
    if progress:
        print(f"dem sweep: {len(todo)} points as one GPU batch", flush=True)
    for p in todo:
        (p.folder / RECORD).unlink(missing_ok=True)
    try:
        run_batch(cases, [p.folder for p in todo], cycles=cycles, progress=progress,
                  overwrite=True, frames=frames, lab_frame=False)  # fmt: skip
    except (SimulationError, ValueError) as exc:
        print(f"dem sweep: the GPU batch stopped ({type(exc).__name__}: {exc}); the points run "
              "one by one", flush=True)  # fmt: skip
        return False
    for p, case in zip(todo, cases, strict=True):
        replace_text(p.folder / RECORD, json.dumps(record(case, cycles, frames), indent=1) + "\n")
    return True


def failure_text(err: BaseException, folder: Path) -> str:
    """Why a point failed, in one line: the error's type and message.

    For an OSError, the file it could not write (the point's folder where the system names
    none, as on a full disk).
    """
    if isinstance(err, OSError):
        where = err.filename or f"a file in {folder}"
        return f"{type(err).__name__}: cannot write or read {where}: {err.strerror or err}"
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0] if text else ''}".rstrip(": ")


def dask_client(scheduler: str | None, workers: int, command: str):
    """A Dask client and its local cluster (None with ``scheduler``); close both.

    The client is of the running scheduler at ``scheduler``, or of a new local cluster of
    ``workers`` one-thread processes.
    """
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - the message is the point
        raise InputError(
            command, "dask", "the sweep extra, from the checkout: pip install -e '.[sweep]' "
            "(a package named dem on the public index is another project)",
        ) from None  # fmt: skip
    if scheduler:
        try:
            return Client(scheduler), None
        except (OSError, ValueError, TypeError) as err:  # TimeoutError is an OSError
            cause = (str(err).splitlines() or [""])[0] or type(err).__name__
            raise InputError("--scheduler", scheduler, f"the address of a running dask scheduler "
                             f"that answers ({cause})") from None  # fmt: skip
    # a failing task is logged by its worker as a warning with the task and a traceback: the
    # sweep says why a point failed in one line of its own, so only errors are let through
    cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)  # fmt: skip
    return Client(cluster), cluster


def _warn_plan(case_dir: Path, point: SweepPoint, threads: int, cycles, device) -> None:
    """The plan's warnings for one point, once (``dem run`` would give them for every point)."""
    from dem.run import plan
    from dem.scene.case import load_case

    case = load_case(case_dir, point.overrides | device_override(device))
    estimate = plan.plan(case, threads=threads, cycles=cycles)
    for a in estimate.warnings():
        warnings.warn(f"sweep point {point.name}: {a.key}: {a.text}", plan.PlanWarning,
                      stacklevel=3)  # fmt: skip
