"""Replicas: one case from N independent fills, pooled into one answer with an honest error bar.

One run's standard error comes from its own per-cycle means (autocorrelation-aware,
:func:`dem.physics.measure.correlated_stderr`); it cannot see how much the answer depends on the
fill. Refilled with another seed, a bed conveys a few per cent differently, several times that
error. ``[run] replicas = N`` (or ``dem run --replicas N``) runs the case N times, replica k seeded
``run.seed + k``, on the cores available (up to one process per core, the cores shared out as numba
threads), and pools the N values by a random-effects model (:func:`dem.physics.measure.pooled`), so
the error bar includes the fill-to-fill spread.

Output: replica 0 writes its frames, results.h5 and checkpoint in the output folder itself, as a
single run does; replica k >= 1 writes into ``replicas/k/`` its summary.json (and its frames and
results.h5 with ``all_replicas``; otherwise they are not written or are removed once pooled).
Every replica's own summary is kept as ``replicas/k/summary.json``; the folder's summary.json is
the pooled one, with the per-replica values under ``per_replica``. ``resume`` reruns only the
replicas without a summary, continuing any that left a checkpoint.

Cost: N runs of the case; on C cores, about ceil(N / C) times one single-threaded run's wall time.
On a GPU (``device = "cuda"``) the N replicas run as one batch (:mod:`dem.run.batch`):
one launch a step for all of them; a resumed batch continues its replicas one by one.
"""

from __future__ import annotations

import json
import math
import multiprocessing
import shutil
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path

from dem import config
from dem.engine.device import check_device
from dem.io.files import json_text, replace_text
from dem.physics import measure
from dem.run.batch import batchable, run_batch

#: Folder of the replicas' own outputs, inside the run's output folder.
REPLICAS_DIR = "replicas"
SUMMARY = "summary.json"
#: Seconds a replica worker has to end after SIGTERM (its checkpoint written) before it is killed.
STOP_GRACE_S = 30.0
#: Pooled value keys: (value, its standard error) of the single runs' summaries.
POOLED = (
    ("mean_velocity", "mean_velocity_stderr"),
    ("mean_velocity_norm", "mean_velocity_norm_stderr"),
)


def fill_keys(run) -> str:
    """The keys that ask for more than one fill, as the notes of one-fill commands name them."""
    if run.target_error is not None:
        return f"run.target_error = {run.target_error:g} (with run.replicas = {run.replicas})"
    return f"run.replicas = {run.replicas}"


def replica_case(case, k: int):
    """Replica ``k`` of ``case``: seeded ``run.seed + k``, one fill."""
    return replace(case, run=replace(case.run, seed=case.run.seed + k, replicas=1))


def replica_dir(out_dir: Path, k: int) -> Path:
    """Where replica ``k`` keeps its own summary (and, k >= 1, its run)."""
    return Path(out_dir) / REPLICAS_DIR / str(k)


def _cores(threads: int | None) -> int:
    """Cores to share among the replicas: ``threads`` if given, else the default thread count."""
    if threads is not None:
        return max(1, int(threads))
    return max(1, config.default_threads())


def _run_one(case, k: int, out_dir: str, kwargs: dict, one_line: bool = False) -> dict:
    """Run replica ``k`` in a worker process; its summary, or how it was interrupted.

    ``one_line``: print warnings as the command line does (a spawned worker starts with
    Python's format, file and line included).
    """
    from dem.run.interrupts import RunInterrupted
    from dem.run.runner import run_case

    if one_line:
        import warnings

        from dem.errors import one_line_warning

        warnings.formatwarning = one_line_warning

    try:
        return {"k": k, "summary": run_case(case, Path(out_dir), **kwargs)}
    except RunInterrupted as stop:
        checkpoint = None if stop.checkpoint is None else str(stop.checkpoint)
        return {"k": k, "interrupted": stop.signum, "checkpoint": checkpoint, "text": str(stop)}


def run_replicas(
    case,
    out_dir: Path,
    *,
    cycles: int | None = None,
    threads: int | None = None,
    progress: bool = True,
    overwrite: bool = False,
    resume: bool = False,
    frames: bool = True,
    lab_frame: bool = False,
    all_replicas: bool = False,
    warn: bool = True,
) -> dict:
    """Run ``case.run.replicas`` fills of ``case`` into ``out_dir`` and pool them.

    Arguments as :func:`dem.run.runner.run_case`; ``threads`` is the number of cores shared among
    the replicas (default: the default thread count); ``all_replicas`` keeps every replica's
    frames and results.h5 (default: replica 0's only); ``warn``: replica 0 gives the plan's
    warnings (a study that gave them already passes False). Returns the pooled summary, also
    written to ``out_dir/summary.json``. With one replica this is :func:`dem.run.runner.run_case`.

    Raises:
        dem.run.interrupts.RunInterrupted: a signal stopped a replica; finished replicas are
            kept and the interrupted ones left a checkpoint (``resume`` continues them).

    """
    from dem.run.runner import run_case

    n = case.run.replicas
    if n == 1:
        return run_case(case, out_dir, cycles=cycles, threads=threads, progress=progress,
                        overwrite=overwrite, resume=resume, frames=frames,
                        lab_frame=lab_frame)  # fmt: skip
    out_dir = Path(out_dir)
    check_device(case.run.device, case)  # at the door, not in each worker after the spawn
    if not resume:
        _check_outputs(out_dir, n, overwrite)
    cores = _cores(threads)
    started = time.perf_counter()
    options = {"cycles": cycles, "progress": progress, "overwrite": overwrite, "resume": resume,
               "frames": frames, "lab_frame": lab_frame, "all_replicas": all_replicas,
               "warn": warn}  # fmt: skip
    summaries: dict[int, dict] = {}
    processes = _run_fills(case, out_dir, range(n), summaries, cores, started, options)
    target = case.run.target_error
    history = []
    while target is not None:
        pooled = pool_summaries([summaries[k] for k in range(n)])
        error, goal = target_gap(pooled, target)
        history.append({"fills": n, "error_norm": error, "mean_velocity_norm":
                        pooled["mean_velocity_norm"]})  # fmt: skip
        if error <= goal or n >= case.run.max_replicas:
            break
        more = fills_for(n, error, goal, case.run.max_replicas)
        if progress:
            say(f"dem: {n} fills give +- {error:.2g} in v_norm, the target is {goal:.2g}: "
                f"{more - n} fills more")  # fmt: skip
        processes = _run_fills(case, out_dir, range(n, more), summaries, cores, started, options)
        n = more
    summary = pool_summaries([summaries[k] for k in range(n)], time.perf_counter() - started,
                             processes=processes)  # fmt: skip
    if target is not None:
        summary["target"] = target_record(summary, target, history, case.run.max_replicas)
        summary["replicas_requested"] = case.run.replicas
    summary["replica_outputs"] = "all" if all_replicas else "replica 0 (frames, results.h5)"
    if not all_replicas:
        for k in range(1, n):
            _drop_run_files(replica_dir(out_dir, k))
    replace_text(out_dir / SUMMARY, json_text(summary))
    return summary


def say(text: str) -> None:
    """A line on stderr that starts a line of its own.

    Replica 0's progress bar, drawn by a worker process on the same terminal, leaves its line
    open; on a terminal the line is cleared first (as ``tqdm.write`` does), so a "done" line
    is not glued to the bar; into a file or pipe the text is written as it is.
    """
    clear = "\r\x1b[K" if sys.stderr.isatty() else ""
    print(clear + text, file=sys.stderr, flush=True)


def target_gap(pooled: dict, target: float) -> tuple[float, float]:
    """The pooled error in v_norm and the goal it must reach: ``target`` max(|v_norm|, 0.1).

    Near a regime's threshold, where v -> 0, a relative error means nothing: the goal is then
    ``target`` of 0.1 A omega cos phi (as the lone grain's tolerance, :mod:`dem.run.stiffness`).
    """
    error = float(pooled["mean_velocity_norm_stderr"])
    return error, target * max(abs(float(pooled["mean_velocity_norm"])), TARGET_FLOOR)


#: The v_norm below which ``run.target_error`` is a fraction of this instead of |v_norm|.
TARGET_FLOOR = 0.1


def fills_for(n: int, error: float, goal: float, most: int) -> int:
    """How many fills to pool next: the error falls as 1 / sqrt(fills), one more at least."""
    if not math.isfinite(error) or goal <= 0.0:
        return min(most, n + 1)
    return max(n + 1, min(most, math.ceil(n * (error / goal) ** 2)))


def target_record(summary: dict, target: float, history: list[dict], most: int) -> dict:
    """What a run with ``run.target_error`` reached, in summary.json's ``target``."""
    error, goal = target_gap(summary, target)
    reached = error <= goal
    n = summary["replicas"]
    cost = summary.get("elapsed_s")
    what = (
        f"{'reached' if reached else 'NOT REACHED'}: +- {error:.2g} in v_norm with {n} fills "
        f"pooled (target {target:g} of max(|v_norm|, {TARGET_FLOOR:g}) = {goal:.2g})"
    )
    if not reached:
        what += f"; run.max_replicas = {most} fills reached: raise it, or run.cycles"
    if cost is not None:
        what += f", {cost:.0f} s"
    return {"target_error": target, "reached": reached, "error_norm": error, "goal_norm": goal,
            "fills": n, "max_replicas": most, "steps": history, "what": what}  # fmt: skip


def _run_fills(case, out_dir: Path, ks, summaries: dict[int, dict], cores: int, started: float,
               options: dict) -> int:  # fmt: skip
    """Run replicas ``ks`` of ``case`` (those not already in ``summaries``) into ``out_dir``.

    Each finished replica's summary goes into ``summaries`` and ``replicas/k/``. Returns the
    processes that ran at once (1 on a GPU batch).

    Raises:
        dem.run.interrupts.RunInterrupted: a signal stopped a replica.

    """
    from dem.run.interrupts import RunInterrupted

    ks = list(ks)
    resume, overwrite = options["resume"], options["overwrite"]
    progress, frames = options["progress"], options["frames"]
    workers = min(len(ks), cores)
    per_worker = max(1, cores // workers)
    jobs = []
    for k in ks:
        own = replica_dir(out_dir, k) / SUMMARY
        if resume and own.is_file() and not _has_checkpoint(out_dir if k == 0 else own.parent):
            summaries[k] = json.loads(own.read_text(encoding="utf-8"))
            continue
        run_dir = out_dir if k == 0 else replica_dir(out_dir, k)
        pending_resume = resume and _has_checkpoint(run_dir)
        kwargs = {
            "cycles": options["cycles"], "threads": per_worker, "progress": progress and k == 0,
            "overwrite": overwrite or (resume and not pending_resume),
            "resume": pending_resume, "frames": frames and (k == 0 or options["all_replicas"]),
            "lab_frame": options["lab_frame"], "warn": options["warn"] and k == 0,
        }  # fmt: skip
        jobs.append((replica_case(case, k), k, str(run_dir), kwargs))
    first = ks[0] if ks else 0
    batched = bool(jobs) and not resume and batchable(case) is None
    if progress and jobs and not batched:
        print(
            f"dem: {len(ks)} replicas (seeds {case.run.seed + first}..{case.run.seed + ks[-1]}), "
            f"{len(jobs)} to run on {workers} process(es) x {per_worker} thread(s)",
            file=sys.stderr, flush=True,
        )  # fmt: skip
    if batched:
        if progress:
            print(f"dem: the {len(jobs)} replicas run as one GPU batch (dem.run.batch)",
                  file=sys.stderr, flush=True)  # fmt: skip
        run_dirs = [out_dir if k == 0 else replica_dir(out_dir, k) for k in ks]
        done = run_batch([replica_case(case, k) for k in ks], run_dirs, cycles=options["cycles"],
                         progress=progress, overwrite=True, frames=frames,
                         lab_frame=options["lab_frame"],
                         keep_frames=[k == 0 or options["all_replicas"] for k in ks])  # fmt: skip
        for i, summary in done.items():
            k = ks[i]
            summaries[k] = summary
            _keep_own_summary(out_dir, k, summary)
        return 1
    interrupted = []

    def finished(result: dict) -> None:
        k = result["k"]
        if "interrupted" in result:
            interrupted.append(result)
            return
        summaries[k] = result["summary"]
        _keep_own_summary(out_dir, k, result["summary"])
        if progress:
            s = result["summary"]
            say(
                f"dem: replica {k} (seed {s['seed']}) done: v = "
                f"{s['mean_velocity']:.4g} +- {s['mean_velocity_stderr']:.2g} m/s "
                f"({len(summaries)} done, {time.perf_counter() - started:.0f} s)"
            )

    if jobs and workers == 1:  # one core: in this process, one after the other (no children,
        for job in jobs:  # so a daemonic Dask worker can run it too)
            finished(_run_one(*job))
            if interrupted:
                break
    elif jobs:
        context = multiprocessing.get_context("spawn")  # fork after numba's threads is unsafe
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # the workers checkpoint
        try:
            with ProcessPoolExecutor(max_workers=min(workers, len(jobs)),
                                     mp_context=context) as pool:  # fmt: skip
                import warnings

                from dem.errors import one_line_warning

                one_line = warnings.formatwarning is one_line_warning
                try:  # the submissions too: a signal while they start must not wait for them
                    futures = [pool.submit(_run_one, *job, one_line) for job in jobs]
                    for future in as_completed(futures):
                        finished(future.result())
                except BaseException:  # a replica failed, or the caller's signal handler raised
                    _stop_workers(pool)
                    raise
        finally:
            signal.signal(signal.SIGINT, previous)
    if interrupted:
        first = min(interrupted, key=lambda r: r["k"])
        checkpoint = first["checkpoint"]
        raise RunInterrupted(first["interrupted"], None if checkpoint is None else
                             Path(checkpoint), -1, f"replica {first['k']}")  # fmt: skip
    return workers


def _check_outputs(out_dir: Path, n: int, overwrite: bool) -> None:
    """Refuse, before any replica starts, a folder holding an earlier run (unless overwrite).

    With ``overwrite`` an earlier ``replicas/`` folder is removed whole (a run with more
    replicas leaves no stale ones behind).
    """
    from dem.errors import InputError
    from dem.run.output import RUN_OUTPUTS

    folder = out_dir / REPLICAS_DIR
    if folder.is_symlink():
        raise InputError("--out", str(folder), "a real folder, not a symbolic link")
    earlier = [out_dir / name for name in RUN_OUTPUTS if (out_dir / name).exists()]
    if folder.is_dir():
        earlier.append(folder)
    if earlier and not overwrite:
        raise InputError(
            "--out", str(out_dir), f"a folder without an earlier run (it holds {earlier[0].name}); "
            "use --overwrite to replace it, --resume to continue it, or another --out",
        )  # fmt: skip
    if overwrite and folder.is_dir():
        shutil.rmtree(folder)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """One replica failed (or a signal stopped the caller): stop the others now.

    The worker processes are taken before the shutdown, which forgets them. Each gets SIGTERM (a
    running replica writes its checkpoint and stops, an idle worker ends) and
    :data:`STOP_GRACE_S` to end; one still alive then is killed, so that neither this process's
    exit nor the pool's shutdown waits on it.
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    deadline = time.monotonic() + STOP_GRACE_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            say(f"dem: replica worker {process.pid} did not stop within {STOP_GRACE_S:g} s of "
                "SIGTERM: killed")  # fmt: skip
            process.kill()
            process.join()


def _has_checkpoint(run_dir: Path) -> bool:
    from dem.run.output import CHECKPOINT

    return (Path(run_dir) / CHECKPOINT).is_file()


def _keep_own_summary(out_dir: Path, k: int, summary: dict) -> None:
    """Replica k's own summary in ``replicas/k/`` (replica 0's is overwritten by the pool)."""
    own = replica_dir(out_dir, k)
    own.mkdir(parents=True, exist_ok=True)
    replace_text(own / SUMMARY, json_text(summary))


def _drop_run_files(run_dir: Path) -> None:
    """Remove a replica's results.h5 and frames (never written with frames off but the h5)."""
    from dem.io.vtk import FRAMES_DIR, PVD_NAME
    from dem.run.output import RESULTS

    for name in (RESULTS, PVD_NAME):
        (run_dir / name).unlink(missing_ok=True)
    frames = run_dir / FRAMES_DIR
    if frames.is_dir() and not frames.is_symlink():
        shutil.rmtree(frames)


def pool_summaries(
    summaries: list[dict], wall_time_s: float | None = None, processes: int = 1
) -> dict:
    """The pooled summary of replica summaries (replica 0's fields, pooled values over all).

    Each (value, standard error) pair of :data:`POOLED` is pooled by
    :func:`dem.physics.measure.pooled` and gets a ``_ci95`` half-width; the mass flow rates are
    the pooled velocity times each replica's mass over length, pooled likewise; ``per_replica``
    lists every replica's values; ``replica_spread`` is the fill-to-fill standard deviation of v
    beyond the runs' own errors. ``wall_time_s`` sums the replicas' step loops and
    ``particle_steps_per_s`` is their mean rate times the ``processes`` that ran at once;
    ``elapsed_s`` is the whole wait.
    """
    first = summaries[0]
    out = dict(first)
    for key, err in POOLED:
        p = measure.pooled([s[key] for s in summaries], [s[err] for s in summaries])
        out[key], out[err], out[key + "_ci95"] = p.mean, p.stderr, p.half_width
        if key == "mean_velocity":
            out["replica_spread"] = p.between
    flows, flow_errors = [], []
    for s in summaries:
        v, v_err = s["mean_velocity"], s["mean_velocity_stderr"]
        flows.append(s["mass_flow_rate"])
        ratio = abs(v_err / v) if v else math.nan
        flow_errors.append(abs(s["mass_flow_rate"]) * ratio)
    p = measure.pooled(flows, flow_errors)
    out["mass_flow_rate"], out["mass_flow_rate_stderr"] = p.mean, p.stderr
    out["mass_flow_rate_per_width"] = (
        p.mean * first["mass_flow_rate_per_width"] / (first["mass_flow_rate"] or math.nan)
    )
    if first.get("feeder"):
        rates = [s["feeder"]["discharge_rate"] for s in summaries]
        errs = [s["feeder"]["discharge_rate_stderr"] for s in summaries]
        p = measure.pooled(rates, errs)
        out["feeder"] = dict(first["feeder"], discharge_rate=p.mean, discharge_rate_stderr=p.stderr,
                             discharge_rate_ci95=p.half_width)  # fmt: skip
    if first.get("per_type"):
        out["per_type"] = _pooled_types(summaries)
    out["replicas"] = len(summaries)
    out["error_bar"] = (
        f"pooled over {len(summaries)} fills (random-effects, fill-to-fill spread included; "
        "dem.physics.measure.pooled)"
    )
    out["per_replica"] = [
        {
            "seed": s["seed"],
            **(
                {"per_type_velocity": [t["mean_velocity"] for t in s["per_type"]]}
                if s.get("per_type")
                else {}
            ),  # fmt: skip
            "mean_velocity": s["mean_velocity"],
            "mean_velocity_stderr": s["mean_velocity_stderr"],
            "mean_velocity_norm": s["mean_velocity_norm"],
            "mass_flow_rate": s["mass_flow_rate"],
            "settle_cycles": s["settle_cycles"],
            "cycles": s["cycles"],
            "steadiness": s.get("steadiness"),
            "wall_time_s": s["wall_time_s"],
        }
        for s in summaries
    ]
    unsteady = [s["seed"] for s in summaries if not (s.get("steadiness") or {}).get("steady", True)]
    out["steadiness"] = {
        "steady": not unsteady,
        "unsteady_seeds": unsteady,
        "what": "every fill's measured series without a trend beyond its error" if not unsteady
        else f"fills with seeds {unsteady} still drifting (per_replica: their steadiness); the "
        "pooled error bar includes their spread, not the drift common to all fills",
    }  # fmt: skip
    flights = [s.get("flight") or {} for s in summaries]
    flight = flights[0]
    if flight and all(f.get("fraction") for f in flights):
        columns = zip(*(f["fraction"] for f in flights), strict=True)
        what = flight["what"] + f", and over {len(flights)} fills"
        out["flight"] = dict(flight, fraction=[sum(x) / len(flights) for x in columns],
                             what=what)  # fmt: skip
    out["per_cycle_velocity_replica"] = 0
    steps = sum(s["spheres"] * s["steps"] for s in summaries)
    loops = sum(s["wall_time_s"] for s in summaries)
    out["wall_time_s"] = loops  # the replicas' step loops, summed
    out["particle_steps_per_s"] = steps / loops * processes if loops > 0 else None
    if wall_time_s is not None:
        out["elapsed_s"] = wall_time_s  # compile, fills and every replica, as the user waited
    out["processes"] = processes
    return out


def _pooled_types(summaries: list[dict]) -> list[dict]:
    """Each grain type over the fills: its velocity pooled as the bulk's, what the fills placed.

    Per type: the first fill's name, fraction, density and distribution; count and mass_fraction
    averaged over the fills, the placed radii's mean averaged and their extremes over all fills;
    mean_velocity and mean_velocity_norm pooled (:func:`dem.physics.measure.pooled`, the
    fill-to-fill spread included); the per-cycle series are each fill's (``per_replica``).
    """
    out = []
    for k, row in enumerate(summaries[0]["per_type"]):
        rows = [s["per_type"][k] for s in summaries]
        merged = {key: row[key] for key in ("name", "fraction", "density", "distribution")}
        merged["count"] = sum(r["count"] for r in rows) / len(rows)
        merged["radius_mean"] = sum(r["radius_mean"] for r in rows) / len(rows)
        merged["radius_min"] = min(r["radius_min"] for r in rows)
        merged["radius_max"] = max(r["radius_max"] for r in rows)
        merged["mass_fraction"] = sum(r["mass_fraction"] for r in rows) / len(rows)
        for key, err in POOLED:
            p = measure.pooled([r[key] for r in rows], [r[err] for r in rows])
            merged[key], merged[err], merged[key + "_ci95"] = p.mean, p.stderr, p.half_width
        out.append(merged)
    return out
