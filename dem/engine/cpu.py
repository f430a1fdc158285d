"""The CPU engine: a simulation stepped by the numba kernels on the host's threads.

Each call of :meth:`CpuEngine.advance` is one call of :func:`dem.kernels.integrate.advance`
(spheres) or :func:`~dem.kernels.integrate.advance_clumps` (rigid clumps) for all its steps; a
pair list that outgrows its capacity returns a status, the list is regrown
(:meth:`dem.engine.state.PairList.grow`) and the kernel resumes the same step. A scene below
``DEM_PARALLEL_MIN_SPHERES`` steps on one thread (the threads' start-up would cost more than
they save). One thread adds each pair's force to its two spheres directly; several threads
write per-pair rows into the pair list's inbox and gather them per sphere in pair order: the
same bits (:mod:`dem.kernels.forces`).
"""

from __future__ import annotations

import numba
import numpy as np

from dem import config
from dem.kernels.integrate import (
    DONE,
    advance,
    advance_clumps,
    build,
    evaluate_forces,
    evaluate_forces_clumps,
)
from dem.kernels.neighbours import OK


class CpuEngine:
    """The CPU engine of one simulation (the contract: :class:`dem.engine.door.Engine`).

    Holds no state of its own: the simulation's host arrays are the state.
    """

    device = "cpu"

    def __init__(self, sim):
        self.sim = sim

    def build(self) -> None:
        """Rebuild the pair list at the current positions (history carried by pair key)."""
        sim = self.sim
        while True:
            status, need = build(
                sim.spheres.n, sim.spheres.as_layout(), sim.spheres.body, sim.pairs.as_layout(),
                sim.pairs.counters, sim.geom,
            )  # fmt: skip
            if status == OK:
                return
            sim.pairs.grow(status, need)

    def serial(self) -> bool:
        """One thread: True, the pairs add to the spheres directly; else allocate the inbox.

        Both paths give the same bits (:mod:`dem.kernels.forces`).
        """
        if numba.get_num_threads() == 1:
            return True
        self.sim.pairs.ensure_inbox()
        return False

    def compute_forces(self) -> None:
        """Rebuild the pair list and evaluate forces and torques now (no kick)."""
        sim = self.sim
        self.build()
        serial = self.serial()
        if sim.bodies is not None:
            evaluate_forces_clumps(
                sim.spheres.n, sim.law.model_id, sim.law.params, sim.spheres.as_layout(),
                sim.pairs.as_layout(), sim.pairs.n_pairs, sim.geom, sim.drive_time, sim.gravity,
                sim.drive_array(), sim.bodies.as_layout(), serial, sim.mesh_layout(),
            )  # fmt: skip
        else:
            evaluate_forces(
                sim.spheres.n, sim.law.model_id, sim.law.params, sim.rotation,
                sim.spheres.as_layout(), sim.pairs.as_layout(), sim.pairs.n_pairs, sim.geom,
                sim.drive_time, sim.gravity, sim.drive_array(), False, False, serial,
                sim.mesh_layout(),
            )  # fmt: skip
        sim.forces_valid = True

    def advance(self, n_steps: int) -> None:
        """``n_steps`` steps (one thread below ``DEM_PARALLEL_MIN_SPHERES`` spheres)."""
        threads = numba.get_num_threads()
        if self.sim.spheres.n < config.DEM_PARALLEL_MIN_SPHERES:
            numba.set_num_threads(1)
        try:
            self._steps(n_steps)
        finally:
            numba.set_num_threads(threads)

    def _steps(self, n_steps: int) -> None:
        sim = self.sim
        if not sim.forces_valid:
            self.compute_forces()
        done = 0
        resume = False
        while done < n_steps:
            serial = self.serial()
            step0 = sim.step_index - sim.drive_start_step
            if sim.bodies is None:
                status, steps, need = advance(
                    n_steps - done, step0, resume, sim.spheres.n, sim.law.model_id,
                    sim.law.params, sim.rotation, sim.spheres.as_layout(), sim.spheres.body,
                    sim.pairs.as_layout(), sim.pairs.counters, sim.geom, sim.gravity,
                    sim.drive_array(), sim.stats, serial, sim.mesh_layout(),
                )  # fmt: skip
            else:
                status, steps, need = advance_clumps(
                    n_steps - done, step0, resume, sim.spheres.n, sim.law.model_id,
                    sim.law.params, sim.rotation, sim.spheres.as_layout(), sim.bodies.as_layout(),
                    sim.pairs.as_layout(), sim.pairs.counters, sim.geom, sim.gravity,
                    sim.drive_array(), sim.stats, serial, sim.mesh_layout(),
                )  # fmt: skip
            done += steps
            sim.step_index += steps
            if status == DONE:
                return
            sim.pairs.grow(status, need)
            resume = True

    def fetch_pairs(self, pairs) -> None:
        """Nothing to fetch: the host's pair list is the engine's."""

    def pairs_replaced(self) -> None:
        """Nothing to do: the next call reads the host's list."""

    def deepest_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The whole pair list (i, j): the deepest overlap is among them."""
        p = self.sim.pairs
        return p.pair_i[: p.n_pairs], p.pair_j[: p.n_pairs]
