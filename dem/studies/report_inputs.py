"""What a report reads: a run's summary.json and results.h5, read and checked, and its cycles.

:func:`read_summary` reads ``summary.json`` (README, A DEM run) with every value a report, a sweep
or an atlas reads checked for its type; :func:`load_results` reads ``results.h5``
(:mod:`dem.io.hdf5_read`) with its last frame; :func:`cycle_series` and :func:`replica_series` are
the per-cycle velocities a report draws. Errors are :class:`dem.errors.InputError` naming the file.

Cost: one read of each file; results.h5's last frame is read whole (O(spheres)).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from dem.errors import InputError

RESULTS = "results.h5"

#: The columns of ``comparison.csv`` (:mod:`dem.studies.report`), in order.
COMPARISON_COLUMNS = (
    "run",
    "case",
    "angle",
    "throw_number",
    "frequency",
    "amplitude",
    "inclination",
    "friction",
    "grains",
    "spheres",
    "cycles",
    "replicas",
    "mean_velocity",
    "mean_velocity_stderr",
    "mean_velocity_norm",
    "mean_velocity_norm_stderr",
    "pointmass_velocity_norm",
    "pointmass_bounded_velocity_norm",
    "dem_over_pointmass",
    "mass_flow_rate",
    "particle_steps_per_s",
)


#: summary.json keys a report reads, by what each must be (null is allowed for every one).
_NUMBERS = tuple(
    dict.fromkeys(
        [c for c in COMPARISON_COLUMNS if c not in ("run", "case")]
        + ["mass_flow_rate_per_width", "total_mass", "timestep", "timestep_limit", "steps",
           "wall_time_s", "threads", "settle_cycles"]
    )
)  # fmt: skip
_WHOLE = ("grains", "spheres", "cycles", "steps", "threads", "settle_cycles")
_TEXTS = ("case", "contact_model")
_FEEDER_NUMBERS = ("discharge_rate", "discharge_rate_stderr", "feed_rate", "length",
                   "grains_inserted", "grains_in_trough", "grains_discharged",
                   "feed_backlog")  # fmt: skip


def is_number(v) -> bool:
    """Whether ``v`` is a JSON number (an int or a float, not a bool)."""
    return isinstance(v, int | float) and not isinstance(v, bool)


def read_summary(path: Path, key: str = "OUT") -> dict:
    """``summary.json`` as a dict, every value a report or a sweep reads checked for its type.

    Raises :class:`InputError` naming ``key`` (the option or argument that led to the file),
    the file and what is wrong: not readable as JSON (a run killed while writing it), not an
    object, or a value of the wrong type (a number as text, a list where a number belongs).
    """
    path = Path(path)

    def refuse(what: str) -> InputError:
        return InputError(key, str(path), f"a summary.json as dem run writes it: {what}")

    try:
        summary = json.loads(path.read_bytes())
    except (ValueError, RecursionError) as err:  # JSONDecodeError, UnicodeDecodeError
        cause = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise refuse(f"it is not valid JSON ({cause}): cut short or damaged; run the case "
                     "again") from None  # fmt: skip
    if not isinstance(summary, dict):
        raise refuse(f"it holds a JSON {type(summary).__name__}, not a JSON object")

    def bad(name: str, value, wanted: str) -> InputError:
        shown = repr(value)
        shown = shown if len(shown) <= 40 else shown[:37] + "..."
        return refuse(f"{name} is {shown}, not {wanted}")

    for name in _NUMBERS:
        v = summary.get(name)
        if v is not None and not is_number(v):
            raise bad(name, v, "a number")
        if name in _WHOLE and v is not None and not (math.isfinite(v) and v == int(v) and v >= 0):
            raise bad(name, v, "a whole number >= 0")
    for name in _TEXTS:
        v = summary.get(name)
        if v is not None and not isinstance(v, str):
            raise bad(name, v, "a text")
    per = summary.get("per_cycle_velocity")
    if per is not None and not (isinstance(per, list) and all(
            v is None or is_number(v) for v in per)):  # fmt: skip
        raise bad("per_cycle_velocity", per, "a list of numbers")
    feeder = summary.get("feeder")
    if feeder is not None:
        if not isinstance(feeder, dict):
            raise bad("feeder", feeder, "an object (or null)")
        for name in _FEEDER_NUMBERS:
            v = feeder.get(name)
            if v is not None and not is_number(v):
                raise bad(f"feeder.{name}", v, "a number")
    return summary


def load_results(d: Path) -> dict | None:
    """``results.h5`` read and checked, with its last frame read now; None where there is none.

    A file HDF5 cannot open, that lacks a group dem writes, or whose columns or last frame are
    not numbers of the shapes dem writes is an :class:`InputError` naming the file.
    """
    path = d / RESULTS
    if not path.is_file():
        return None
    from dem.io.hdf5_read import read_results

    def refuse(what: str) -> InputError:
        return InputError("OUT", str(path), f"a results.h5 as dem run writes it: {what}; move "
                          "it away to report from summary.json alone")  # fmt: skip

    try:
        results = read_results(path)
        if not isinstance(results["case"], dict):
            raise refuse("its case_json is not a JSON object")
        for name, column in results["cycles"].items():
            column = np.asarray(column)
            if column.ndim != 1 or column.dtype.kind not in "biuf":
                raise refuse(f"/cycles/{name} is not a column of numbers")
        last = results["frames"][-1] if results["frame_count"] > 0 else None
        if last is not None:
            n = np.shape(last["radius"])
            for name, shape in (("positions", n + (3,)), ("velocity", n + (3,))):
                value = np.asarray(last[name])
                if value.shape != shape or value.dtype.kind not in "iuf":
                    raise refuse(f"its last frame's {name} is {value.shape}, not {shape} numbers")
            if len(n) != 1 or np.asarray(last["radius"]).dtype.kind not in "iuf":
                raise refuse("its last frame's radius is not a column of numbers")
    except InputError as err:
        if err.key == "OUT":
            raise
        raise refuse(f"{err.key} = {err.value!r}: {err.allowed}") from None
    except (OSError, KeyError, ValueError, TypeError, IndexError, RuntimeError) as err:
        cause = (str(err).splitlines() or [""])[0] or type(err).__name__
        raise refuse(f"it cannot be read ({type(err).__name__}: {cause})") from None
    results["last_frame"] = last
    return results


def cycle_series(summary: dict, results: dict | None):
    """(cycle, velocity, measured mask) from results.h5 /cycles, else summary per_cycle_velocity."""
    cycles = results["cycles"] if results else {}
    if "mean_velocity" in cycles and len(cycles["mean_velocity"]):
        v = np.asarray(cycles["mean_velocity"], dtype=np.float64)
        c = np.asarray(cycles.get("cycle", np.arange(v.size)))
        if "measured" in cycles:
            measured = np.asarray(cycles["measured"]).astype(bool)
        else:
            settle = int(summary.get("settle_cycles") or 0)
            measured = np.arange(v.size) >= min(settle, v.size - 1)
        return c, v, measured, "results.h5 /cycles"
    per = summary.get("per_cycle_velocity") or []
    if per:
        v = np.asarray(per, dtype=np.float64)
        settle = int(summary.get("settle_cycles") or 0)
        return np.arange(settle, settle + v.size), v, np.ones(v.size, bool), "summary.json"
    return None


def replica_series(d: Path, summary: dict) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """The measured cycles of a pooled run's fills 2..N: (seed, cycles, velocities) each.

    From ``replicas/k/summary.json`` (:mod:`dem.run.replicas`); a fill whose summary is missing
    or unreadable is left out.
    """
    out = []
    for k in range(1, int(summary.get("replicas") or 1)):
        try:
            own = json.loads((d / "replicas" / str(k) / "summary.json").read_text())
            v = np.asarray(own["per_cycle_velocity"], dtype=np.float64)
            settle = int(own.get("settle_cycles") or 0)
        except (OSError, ValueError, KeyError, TypeError):
            continue
        out.append((own.get("seed"), np.arange(settle, settle + v.size), v))
    return out
