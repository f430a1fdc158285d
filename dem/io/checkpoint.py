"""Checkpoints: the whole state of a :class:`dem.engine.simulation.Simulation` in one ``.npz`` file.

A checkpoint holds everything the step loop reads, so that a run restored from it continues bit
for bit: sphere arrays (``sph.*``), rigid bodies (``body.*``), the pair list with its contact
history, scratch and CSR index (``nb.*``, capacities included; not the parallel pair loop's
``inbox``, which every step writes before it reads it), the step counters, the stored
forces (a fresh force evaluation would update the contact history a second time) and the
measurement sums; the runner adds its own loop position as JSON (``loop.json``).

Files are written to a temporary name and renamed, so an interrupted write never leaves a
truncated checkpoint in place of a good one.

A checkpoint is a file the user hands back (``dem run --resume``), so it is validated in full
before anything of it is used: :func:`read` checks the file on its own (every key, shape and
dtype, finite values where the step loop needs them, pair indices within the spheres and the
pair index rebuilt from them, the loop record within its run), :func:`load_state` against the
simulation built from the case (counts, time step, mesh slots, grain kind, the loop's cycle
against the steps done). Each refusal is one :class:`CheckpointError` naming what is wrong; the
runner reports it as a bad ``--resume`` file (exit 2). A tampered file used to give a KeyError
traceback, a segmentation fault in the pair loop, or a NaN summary.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import TypeGuard

import numpy as np

from dem import config
from dem.engine.state import PairList
from dem.errors import SimulationError
from dem.io.files import replace_file
from dem.kernels.contact import HISTORY_WIDTH
from dem.kernels.forces import N_WALLS
from dem.kernels.mesh import MESH_SLOTS
from dem.physics.drive import cycle_edge

LOOP_KEY = "loop.json"
#: Pair-list arrays each step writes before reading them: not saved.
TRANSIENT = ("inbox",)


class CheckpointError(SimulationError):
    """A checkpoint that cannot be resumed; the message names the key and what is wrong."""


_F, _I = np.dtype(np.float64), np.dtype(np.int64)
_Row = tuple[str | int | None, tuple[int | str, ...], np.dtype, str | None]
#: Saved arrays: name -> (rows, trailing shape, dtype, values). Rows are in terms of n spheres,
#: B bodies, ``cap`` pairs, ``cells`` cell capacity, ``slots`` per sphere and ``mesh`` (the mesh
#: slots per sphere, 0 without a mesh). Values: "finite", "positive" (finite and > 0),
#: "no-nan" (inf allowed: x_ref starts at inf to force a build), "index" (checked below) or
#: None (work arrays each neighbour build writes before reading them).
LAYOUT: dict[str, _Row] = {
    "sph.x": ("n", (3,), _F, "finite"),
    "sph.v": ("n", (3,), _F, "finite"),
    "sph.omega": ("n", (3,), _F, "finite"),
    "sph.force": ("n", (3,), _F, "finite"),
    "sph.torque": ("n", (3,), _F, "finite"),
    "sph.radius": ("n", (), _F, "positive"),
    "sph.mass": ("n", (), _F, "positive"),
    "sph.inv_mass": ("n", (), _F, "positive"),
    "sph.inv_inertia": ("n", (), _F, "positive"),
    "sph.wall_hist": ("walls", ("hist",), _F, "finite"),
    "sph.body": ("n", (), _I, "index"),
    "sph.mesh_hist": ("mesh", ("hist",), _F, "finite"),
    "sph.mesh_normal": ("mesh", (3,), _F, "finite"),
    "nb.counters": (2, (), _I, "index"),
    "nb.x_ref": ("n", (3,), _F, "no-nan"),
    "nb.pair_i": ("cap", (), _I, "index"),
    "nb.pair_j": ("cap", (), _I, "index"),
    "nb.hist": ("cap", ("hist",), _F, None),  # the valid pairs' rows are checked below
    "nb.scratch_j": ("n*slots", (), np.dtype(np.int32), None),
    "nb.scratch_hist": ("cap", ("hist",), _F, None),
    "nb.counts": ("n", (), _I, None),
    "nb.offsets": ("n+1", (), _I, None),
    "nb.cell_of": ("n", (), _I, None),
    "nb.cell_start": ("cells+1", (), _I, None),
    "nb.cell_particles": ("n", (), _I, None),
    "nb.part_start": ("n+1", (), _I, "index"),
    "nb.part_slot": ("2cap", (), _I, "index"),
    "nb.sizes": (4, (), _I, "index"),
    "sim.counters": (4, (), _I, "index"),
    "sim.stats": ("stats", (), _F, "finite"),
    "sim.dt": (None, (), _F, "positive"),
    "sim.grain_id": ("grains", (), _I, "index"),
}
BODY_LAYOUT: dict[str, _Row] = {
    "body.x": ("B", (3,), _F, "finite"),
    "body.v": ("B", (3,), _F, "finite"),
    "body.q": ("B", (4,), _F, "finite"),
    "body.ang_mom": ("B", (3,), _F, "finite"),
    "body.inv_mass": ("B", (), _F, "positive"),
    "body.mass": ("B", (), _F, "positive"),
    "body.moments": ("B", (3,), _F, "positive"),
    "body.force": ("B", (3,), _F, "finite"),
    "body.torque": ("B", (3,), _F, "finite"),
    "body.omega": ("B", (3,), _F, "finite"),
    "body.start": ("B+1", (), _I, "index"),
    "body.members": ("n", (), _I, "index"),
    "body.offsets": ("n", (3,), _F, "finite"),
    "body.body_of": ("n", (), _I, "index"),
}
#: The loop record's keys (runner): JSON types and what else is allowed.
LOOP_KEYS = {
    "case": (dict,),
    "discharged_mark": (float, int),
    "cycle": (int,),
    "chunk": (int,),
    "total_cycles": (int, type(None)),
    "settle_cycles": (int, type(None)),
    "cycles": (int,),
    "settle_series": (list,),
    "steps": (int,),
    "wall_time_s": (float, int),
    "settle_time_s": (float, int),
    "settle_wall_time_s": (float, int),
    "per_cycle": (list,),
    "vtk_entries": (list,),
    "h5_cycles": (int,),
    "h5_frames": (int,),
}
#: Keys a loop record may hold besides (feeders, auto settling).
LOOP_OPTIONAL = {
    "feeder": (dict,),
    "settle_detected": (bool,),
    "discharge_per_cycle": (list,),
    "hold_up_per_cycle": (list,),
    "frames": (bool,),
    "lab_frame": (bool,),
    "extended_cycles": (int,),
    "per_cycle_types": (list,),
}
_FRAME_FILE = re.compile(r"[A-Za-z0-9_.-]+\.vtp")


def state_dict(sim) -> dict[str, np.ndarray]:
    """Everything the step loop of ``sim`` reads, as named arrays (the arrays themselves)."""
    state = {f"sph.{k}": v for k, v in vars(sim.spheres).items()}
    if sim.bodies is not None:
        state |= {f"body.{k}": v for k, v in vars(sim.bodies).items()}
    pairs = sim.pairs
    state |= {
        f"nb.{k}": v
        for k, v in vars(pairs).items()
        if isinstance(v, np.ndarray) and k not in TRANSIENT
    }
    state["nb.sizes"] = np.array([pairs.n, pairs.capacity, pairs.cell_capacity, pairs.slots])
    state["sim.counters"] = np.array(
        [sim.step_index, sim.drive_start_step, int(sim.drive_on), int(sim.forces_valid)]
    )
    state["sim.stats"] = sim.stats
    state["sim.dt"] = np.array(sim.dt)
    state["sim.grain_id"] = sim.grain_id
    if getattr(sim, "type_mark", None) is not None:
        state["sim.type_mark"] = sim.type_mark
    return state


def load_state(sim, state: dict[str, np.ndarray]) -> None:
    """Restore :func:`state_dict` output into ``sim`` (built from the same case).

    ``state`` is validated first (:func:`validate`, and against ``sim``: the sphere count (a
    finite feeder's count changes: any), time step, grain kind, mesh slots and, when ``state``
    holds the loop record as :func:`read` returns it, the loop's cycle against the steps done).

    Raises:
        CheckpointError: (a SimulationError) naming the first thing that is wrong; nothing of
            ``sim`` has changed then.

    """
    validate(state)
    n, capacity, cell_capacity, slots = (int(v) for v in state["nb.sizes"])
    same_n = n == sim.spheres.n or sim.feeder is not None
    if not same_n or float(state["sim.dt"]) != sim.dt:
        raise CheckpointError(
            f"checkpoint holds {n} spheres at dt = {float(state['sim.dt'])} s, the case "
            f"{sim.spheres.n} at dt = {sim.dt} s: it belongs to another case"
        )
    _against(sim, state, n)
    for key in vars(sim.spheres):
        setattr(sim.spheres, key, np.ascontiguousarray(state[f"sph.{key}"]).copy())
    if sim.bodies is not None:
        for key in vars(sim.bodies):
            setattr(sim.bodies, key, np.ascontiguousarray(state[f"body.{key}"]).copy())
        sim.spheres.body = sim.bodies.body_of
    sim.pairs = PairList(n, capacity, cell_capacity, slots, sim.law.history_width)
    for key, value in vars(sim.pairs).items():
        if isinstance(value, np.ndarray) and key not in TRANSIENT:
            setattr(sim.pairs, key, np.ascontiguousarray(state[f"nb.{key}"]).copy())
    step, drive_start, drive_on, forces_valid = (int(v) for v in state["sim.counters"])
    sim.step_index, sim.drive_start_step = step, drive_start
    sim.drive_on, sim.forces_valid = bool(drive_on), bool(forces_valid)
    sim.stats[:] = state["sim.stats"]
    sim.grain_id = np.ascontiguousarray(state["sim.grain_id"]).copy()
    if "sim.type_mark" in state:
        sim.type_mark = np.ascontiguousarray(state["sim.type_mark"], dtype=np.float64).copy()


def _against(sim, state: dict[str, np.ndarray], n: int) -> None:
    """The checks of a valid checkpoint against the simulation of the case it is resumed with."""
    other = "it belongs to another case; start the run again without --resume"
    width = state["nb.hist"].shape[1]
    if width != sim.law.history_width:
        raise CheckpointError(
            f"checkpoint keeps {width} floats of contact history, the case's tangential law "
            f"({sim.law.tangential!r}) {sim.law.history_width}: {other}"
        )
    if ("body.x" in state) != (sim.bodies is not None):
        kind = "rigid clumps" if "body.x" in state else "single spheres"
        raise CheckpointError(f"checkpoint holds {kind}, the case not: {other}")
    if sim.bodies is not None and sim.feeder is None and len(state["body.x"]) != sim.bodies.n:
        raise CheckpointError(
            f"checkpoint holds {len(state['body.x'])} grains, the case {sim.bodies.n}: {other}"
        )
    mesh = sim.spheres.mesh_hist.shape[0] > 0
    if (len(state["sph.mesh_hist"]) > 0) != mesh and n > 0:
        raise CheckpointError(
            f"checkpoint {'lacks' if mesh else 'holds'} mesh contact slots, the case "
            f"{'has' if mesh else 'has no'} trough.mesh: {other}"
        )
    if state["sim.stats"].shape != sim.stats.shape:
        raise CheckpointError(
            "checkpoint was written by another version of dem (its measurement sums differ "
            "from this one's); start the run again without --resume"
        )
    if LOOP_KEY not in state:
        return
    loop = json.loads(str(state[LOOP_KEY]))
    step, drive_start = (int(v) for v in state["sim.counters"][:2])
    if loop["steps"] != step - drive_start:
        raise CheckpointError(
            f"loop.json: steps = {loop['steps']} disagrees with the {step - drive_start} driven "
            "steps of sim.counters"
        )
    period, c = sim.trough.period, loop["cycle"]
    lo, hi = cycle_edge(0, c, period, sim.dt), cycle_edge(0, c + 1, period, sim.dt)
    if not lo <= step - drive_start <= hi:
        raise CheckpointError(
            f"loop.json: cycle = {c} is not where sim.counters stands ({step - drive_start} "
            f"driven steps; cycle {c} spans steps {lo} to {hi})"
        )
    if sim.feeder is not None:
        _check_feeder(sim.feeder, loop.get("feeder"))
    elif "feeder" in loop:
        raise CheckpointError(f"loop.json holds a feeder's state, the case has none: {other}")


def _check_feeder(feeder, state) -> None:
    """A finite feeder's counters and generator state (restored by the runner after the load)."""
    import copy

    if not isinstance(state, dict):
        raise CheckpointError("loop.json lacks the feeder's state (the case has a [feeder])")
    for key in ("inserted", "discharged", "next_id", "spilled"):
        value = state.get(key)
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
            raise CheckpointError(f"loop.json: feeder.{key} = {value!r}: a whole number >= 0")
    for key in ("inserted_mass", "discharged_mass", "owed", "last_time"):
        value = state.get(key)
        if not (_real(value) and math.isfinite(value)):
            raise CheckpointError(f"loop.json: feeder.{key} = {value!r}: a finite number")
    if not isinstance(state.get("started"), type(feeder.started)):
        raise CheckpointError(f"loop.json: feeder.started = {state.get('started')!r}")
    try:
        copy.deepcopy(feeder.random).bit_generator.state = state.get("random")
    except (TypeError, ValueError, KeyError) as exc:
        raise CheckpointError(f"loop.json: feeder.random is no generator state ({exc})") from None


def _real(value: object) -> TypeGuard[int | float]:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def validate(state: dict[str, np.ndarray]) -> None:
    """Check a checkpoint's arrays (and its loop record, if ``state`` holds it) on their own.

    Every key of :data:`LAYOUT` (and :data:`BODY_LAYOUT` for clumps) present with its dtype
    and shape, the shapes from ``nb.sizes``; finite values where the step loop reads them; the
    sphere and body indices in range; the valid pairs i < j < n, sorted, with the pair index
    (``part_start``, ``part_slot``) the neighbour build makes from them; the counters sane.

    Raises:
        CheckpointError: naming the first key that is wrong and what it should be.

    """
    missing = [k for k in LAYOUT if k not in state]
    clumps = "body.x" in state
    if clumps:
        missing += [k for k in BODY_LAYOUT if k not in state]
    if missing:
        raise CheckpointError(
            f"checkpoint lacks {', '.join(missing)}: it was written by another version of dem "
            "or altered"
        )
    for key in ("nb.sizes", "sim.counters"):
        _dtype_shape(key, state[key], _I, (4,))
    n, cap, cells, slots = (int(v) for v in state["nb.sizes"])
    if min(n, cap, cells, slots) < 0 or (n > 0 and min(cap, cells, slots) < 1):
        raise CheckpointError(f"nb.sizes = {state['nb.sizes'].tolist()}: counts >= 1")
    bodies = len(state["body.x"]) if clumps and np.ndim(state["body.x"]) else n
    mesh_rows = len(state["sph.mesh_hist"]) if np.ndim(state["sph.mesh_hist"]) else -1
    rows: dict[str | int | None, int | None] = {
        "n": n, "walls": N_WALLS * n, "mesh": mesh_rows if mesh_rows == 0 else MESH_SLOTS * n,
        "cap": cap, "n*slots": n * slots, "n+1": n + 1, "cells+1": cells + 1, "2cap": 2 * cap,
        "stats": len(state["sim.stats"]) if np.ndim(state["sim.stats"]) == 1 else 3,
        "grains": bodies, "B": bodies, "B+1": bodies + 1, None: None,
    }  # fmt: skip
    # the contact history's width is the tangential law's (HISTORY_WIDTH): one of its values,
    # the same in every history array
    width = np.shape(state["nb.hist"])[1] if np.ndim(state["nb.hist"]) == 2 else -1
    if width not in set(HISTORY_WIDTH.values()):
        raise CheckpointError(
            f"nb.hist has shape {np.shape(state['nb.hist'])}: (pairs, w) with w one of "
            f"{sorted(set(HISTORY_WIDTH.values()))}, a tangential law's history width"
        )
    layout = LAYOUT | (BODY_LAYOUT if clumps else {})
    for key, (row, trailing, dtype, values) in layout.items():
        trailing = tuple(width if t == "hist" else t for t in trailing)
        shape = () if row is None else (rows.get(row, row), *trailing)
        array = _dtype_shape(key, state[key], dtype, shape)
        if values == "finite" and not np.isfinite(array).all():
            raise CheckpointError(f"{key} holds non-finite values: finite numbers")
        if values == "positive" and not (np.isfinite(array).all() and (array > 0).all()):
            raise CheckpointError(f"{key} holds values <= 0 or non-finite: finite numbers > 0")
        if values == "no-nan" and np.isnan(array).any():
            raise CheckpointError(f"{key} holds NaN: numbers (inf before the first build)")
    _check_indices(state, n, bodies, clumps)
    if "sim.type_mark" in state:  # grain types: x at the last cycle's edge
        mark = _dtype_shape("sim.type_mark", state["sim.type_mark"], _F, (n,))
        if not np.isfinite(mark).all():
            raise CheckpointError("sim.type_mark holds non-finite values: finite numbers")
    if LOOP_KEY in state:
        try:
            loop = json.loads(str(state[LOOP_KEY]))
        except ValueError as exc:
            raise CheckpointError(f"{LOOP_KEY} is not JSON ({exc})") from None
        validate_loop(loop)


def _dtype_shape(key: str, array, dtype, shape) -> np.ndarray:
    array = np.asarray(array)
    if array.dtype != dtype or array.shape != shape:
        raise CheckpointError(
            f"{key} is {array.dtype} {array.shape}: {dtype} {shape} (from nb.sizes and the "
            "grain count); the file was altered or written by another version of dem"
        )
    return array


def _range(key: str, values: np.ndarray, lo: int, hi: int, what: str) -> None:
    if values.size and (values.min() < lo or values.max() >= hi):
        bad = values[(values < lo) | (values >= hi)][0]
        raise CheckpointError(f"{key} holds {int(bad)}: {what} in [{lo}, {hi})")


def _check_indices(state: dict[str, np.ndarray], n: int, bodies: int, clumps: bool) -> None:
    n_pairs, builds = (int(v) for v in state["nb.counters"])
    cap = len(state["nb.pair_i"])
    if not (0 <= n_pairs <= cap and builds >= 0):
        raise CheckpointError(
            f"nb.counters = [{n_pairs}, {builds}]: 0 <= pairs <= capacity {cap}, builds >= 0"
        )
    pi, pj = state["nb.pair_i"][:n_pairs], state["nb.pair_j"][:n_pairs]
    _range("nb.pair_i", pi, 0, n, "sphere indices")
    _range("nb.pair_j", pj, 0, n, "sphere indices")
    if np.any(pi >= pj) or np.any(np.diff(pi * n + pj) <= 0):
        raise CheckpointError("nb.pair_i, nb.pair_j: pairs i < j, sorted by i n + j, each once")
    if not np.isfinite(state["nb.hist"][:n_pairs]).all():
        raise CheckpointError("nb.hist holds non-finite values: finite numbers")
    # the pair index the neighbour build makes: sphere by sphere, its pair ends in pair order
    owner = np.empty(2 * n_pairs, dtype=np.int64)
    owner[0::2], owner[1::2] = pi, pj
    slot = np.empty(2 * n_pairs, dtype=np.int64)
    slot[np.argsort(owner, kind="stable")] = np.arange(2 * n_pairs)
    start = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=n))])
    if not np.array_equal(state["nb.part_start"], start) or not np.array_equal(
        state["nb.part_slot"][: 2 * n_pairs], slot
    ):
        raise CheckpointError("nb.part_start, nb.part_slot: the pair index of nb.pair_i, pair_j")
    step, drive_start, drive_on, forces_valid = (int(v) for v in state["sim.counters"])
    if not (0 <= drive_start <= step and drive_on == 1 and forces_valid in (0, 1)):
        raise CheckpointError(
            f"sim.counters = {state['sim.counters'].tolist()}: 0 <= drive start <= step, the "
            "drive on (1) and forces valid 0 or 1"
        )
    ids = state["sim.grain_id"]
    if ids.size and (ids.min() < 0 or np.unique(ids).size != ids.size):
        raise CheckpointError("sim.grain_id: distinct grain ids >= 0")
    if not clumps:
        _range("sph.body", state["sph.body"], 0, max(n, 1), "grain indices")
        return
    start, members, body_of = state["body.start"], state["body.members"], state["body.body_of"]
    counts = np.diff(start)
    if start[0] != 0 or start[-1] != n or np.any(counts < 1):
        raise CheckpointError(f"body.start: from 0 to {n} spheres, each body >= 1 member")
    if not np.array_equal(np.sort(members), np.arange(n)):
        raise CheckpointError(f"body.members: each sphere 0 to {n - 1} once")
    if not np.array_equal(body_of[members], np.repeat(np.arange(bodies), counts)):
        raise CheckpointError("body.body_of: each member's body, as body.start lists them")
    if not np.array_equal(state["sph.body"], body_of):
        raise CheckpointError("sph.body: the same as body.body_of")
    if np.any(np.abs(np.linalg.norm(state["body.q"], axis=1) - 1.0) > 1e-6):
        raise CheckpointError("body.q: unit quaternions")


def validate_loop(loop) -> None:
    """Check the runner's loop record: every key with its type, the position within the run.

    Raises:
        CheckpointError: naming the key, its value and what it should be.

    """
    if not isinstance(loop, dict):
        raise CheckpointError(f"{LOOP_KEY} is {type(loop).__name__}: an object")
    for key in LOOP_KEYS:
        if key not in loop:
            raise CheckpointError(f"{LOOP_KEY} lacks {key!r}: written by another dem or altered")
    for key, types in (LOOP_KEYS | LOOP_OPTIONAL).items():
        value = loop.get(key)
        if key in loop and (not isinstance(value, types) or isinstance(value, bool) != (
            bool in types
        )):  # fmt: skip
            raise CheckpointError(f"{LOOP_KEY}: {key} = {value!r}: {_names(types)}")
    for key in ("discharged_mark", "wall_time_s", "settle_time_s", "settle_wall_time_s"):
        if not (math.isfinite(loop[key]) and loop[key] >= 0):
            raise CheckpointError(f"{LOOP_KEY}: {key} = {loop[key]!r}: a finite number >= 0")
    for key in ("cycle", "chunk", "steps", "h5_cycles", "h5_frames"):
        if loop[key] < 0:
            raise CheckpointError(f"{LOOP_KEY}: {key} = {loop[key]!r}: a whole number >= 0")
    for key in ("settle_series", "per_cycle", "discharge_per_cycle", "hold_up_per_cycle"):
        values = loop.get(key, [])
        if not all(_real(v) and math.isfinite(v) for v in values):
            raise CheckpointError(f"{LOOP_KEY}: {key} holds a value that is no finite number")
    cycle, cycles, settle, total = (loop[k] for k in ("cycle", "cycles", "settle_cycles",
                                                       "total_cycles"))  # fmt: skip
    if cycles < 1:
        raise CheckpointError(f"{LOOP_KEY}: cycles = {cycles}: a whole number >= 1")
    if settle is None:
        limit = config.DEM_AUTO_SETTLE_MAX_CYCLES
        if total is not None or cycle >= limit or len(loop["settle_series"]) != cycle:
            raise CheckpointError(
                f"{LOOP_KEY}: cycle = {cycle} while settling: below {limit}, with one "
                "settling velocity a cycle and no total_cycles yet"
            )
        measured = 0
    else:
        if settle < 0 or total != settle + cycles:
            raise CheckpointError(
                f"{LOOP_KEY}: total_cycles = {total!r}: settle_cycles + cycles = "
                f"{settle} + {cycles}"
            )
        if cycle > total:
            raise CheckpointError(
                f"{LOOP_KEY}: cycle = {cycle} is beyond the run's end: 0 <= cycle <= "
                f"total_cycles = {total}"
            )
        measured = max(0, cycle - settle)
    if len(loop["per_cycle"]) != measured:
        raise CheckpointError(
            f"{LOOP_KEY}: per_cycle holds {len(loop['per_cycle'])} velocities: one per measured "
            f"cycle, {measured} at cycle {cycle}"
        )
    frames = loop["case"].get("output.frames_per_cycle")
    if isinstance(frames, int) and not loop["chunk"] < frames:
        raise CheckpointError(
            f"{LOOP_KEY}: chunk = {loop['chunk']}: below output.frames_per_cycle = {frames}"
        )
    if loop["h5_cycles"] != cycle:
        raise CheckpointError(f"{LOOP_KEY}: h5_cycles = {loop['h5_cycles']}: the cycle, {cycle}")
    entries = loop["vtk_entries"]
    if loop["h5_frames"] != len(entries):
        raise CheckpointError(
            f"{LOOP_KEY}: h5_frames = {loop['h5_frames']}: one per VTK entry, {len(entries)}"
        )
    for entry in entries:
        ok = isinstance(entry, list) and len(entry) == 3 and _real(entry[0])
        ok = ok and all(isinstance(e, str) and _FRAME_FILE.fullmatch(e) for e in entry[1:])
        if not ok or not math.isfinite(entry[0]):
            raise CheckpointError(
                f"{LOOP_KEY}: vtk_entries holds {entry!r}: [time, particles file, trough file] "
                "with plain .vtp file names"
            )


def _names(types: tuple) -> str:
    words = {dict: "an object", list: "a list", int: "a whole number", float: "a number",
             bool: "true or false", type(None): "null"}  # fmt: skip
    return " or ".join(words[t] for t in types)


def write(path: Path, sim, loop: dict) -> None:
    """Write ``sim``'s state and the caller's ``loop`` position (JSON-serialisable) to ``path``."""
    state = state_dict(sim)
    state[LOOP_KEY] = np.array(json.dumps(loop))

    def save(tmp: Path) -> None:
        # numpy's stub lets ``**state`` fill allow_pickle, but its keys are array names only
        np.savez(tmp, **state)  # type: ignore[arg-type]

    replace_file(path, save, suffix=".tmp.npz")


def read(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """The state arrays and the loop position of a checkpoint written by :func:`write`.

    Both are validated on their own first (:func:`validate`); the state keeps the loop record
    under ``LOOP_KEY`` as in the file, so :func:`load_state` can check it against the
    simulation. Raises CheckpointError for a file that is not a checkpoint dem can resume,
    OSError where the file cannot be read.
    """
    with np.load(path) as data:
        state = {k: data[k] for k in data.files}
    if LOOP_KEY not in state:
        raise CheckpointError(f"checkpoint lacks {LOOP_KEY}: written by another dem or altered")
    validate(state)
    return state, json.loads(str(state[LOOP_KEY]))
