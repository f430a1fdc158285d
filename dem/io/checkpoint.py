"""Checkpoints: the whole state of a :class:`dem.simulation.Simulation` in one ``.npz`` file.

A checkpoint holds everything the step loop reads, so that a run restored from it continues bit
for bit: sphere arrays (``sph.*``), rigid bodies (``body.*``), the pair list with its contact
history, scratch and CSR index (``nb.*``, capacities included; not the parallel pair loop's
``inbox``, which every step writes before it reads it), the step counters, the stored
forces (a fresh force evaluation would update the contact history a second time) and the
measurement sums; the runner adds its own loop position as JSON (``loop.json``).

Files are written to a temporary name and renamed, so an interrupted write never leaves a
truncated checkpoint in place of a good one.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from dem.errors import SimulationError
from dem.io.files import replace_file
from dem.kernels.forces import N_WALLS
from dem.state import PairList

LOOP_KEY = "loop.json"
#: Pair-list arrays each step writes before reading them: not saved.
TRANSIENT = ("inbox",)


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
    return state


def load_state(sim, state: dict[str, np.ndarray]) -> None:
    """Restore :func:`state_dict` output into ``sim`` (built from the same case).

    Raises SimulationError if the checkpoint holds another sphere count (a finite feeder's
    count changes: any) or time step, or was written by a dem with other arrays.
    """
    n, capacity, cell_capacity, slots = (int(v) for v in state["nb.sizes"])
    same_n = n == sim.spheres.n or sim.feeder is not None
    if not same_n or float(state["sim.dt"]) != sim.dt:
        raise SimulationError(
            f"checkpoint holds {n} spheres at dt = {float(state['sim.dt'])} s, the case "
            f"{sim.spheres.n} at dt = {sim.dt} s: it belongs to another case"
        )
    rows = state["sph.wall_hist"].shape[0]
    if (
        rows != N_WALLS * n
        or state["sim.stats"].shape != sim.stats.shape
        or ("sim.grain_id" not in state)
    ):
        raise SimulationError(
            "checkpoint was written by another version of dem (its wall springs, measurement "
            "sums or grain ids differ from this one's); start the run again without --resume"
        )
    for key in vars(sim.spheres):
        setattr(sim.spheres, key, np.ascontiguousarray(state[f"sph.{key}"]).copy())
    if sim.bodies is not None:
        for key in vars(sim.bodies):
            setattr(sim.bodies, key, np.ascontiguousarray(state[f"body.{key}"]).copy())
        sim.spheres.body = sim.bodies.body_of
    sim.pairs = PairList(n, capacity, cell_capacity, slots)
    missing = [
        f"nb.{key}"
        for key, value in vars(sim.pairs).items()
        if isinstance(value, np.ndarray) and key not in TRANSIENT and f"nb.{key}" not in state
    ]
    if missing:
        raise SimulationError(
            f"checkpoint lacks {', '.join(missing)}: it was written by another version of dem; "
            "start the run again without --resume"
        )
    for key, value in vars(sim.pairs).items():
        if isinstance(value, np.ndarray) and key not in TRANSIENT:
            setattr(sim.pairs, key, np.ascontiguousarray(state[f"nb.{key}"]).copy())
    step, drive_start, drive_on, forces_valid = (int(v) for v in state["sim.counters"])
    sim.step_index, sim.drive_start_step = step, drive_start
    sim.drive_on, sim.forces_valid = bool(drive_on), bool(forces_valid)
    sim.stats[:] = state["sim.stats"]
    sim.grain_id = np.ascontiguousarray(state["sim.grain_id"]).copy()


def write(path: Path, sim, loop: dict) -> None:
    """Write ``sim``'s state and the caller's ``loop`` position (JSON-serialisable) to ``path``."""
    state = state_dict(sim)
    state[LOOP_KEY] = np.array(json.dumps(loop))
    replace_file(path, lambda tmp: np.savez(tmp, **state), suffix=".tmp.npz")


def read(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """The state arrays and the loop position of a checkpoint written by :func:`write`."""
    with np.load(path) as data:
        state = {k: data[k] for k in data.files if k != LOOP_KEY}
        loop = json.loads(str(data[LOOP_KEY]))
    return state, loop
