"""The engine door: what a simulation asks of the engine that steps it, CPU or GPU.

A :class:`~dem.engine.simulation.Simulation` steps through an :class:`Engine`. Two keep the
contract: the CPU engine (:class:`dem.engine.cpu.CpuEngine`, numba on the
host's threads) and the GPU engine (:class:`dem.engine.gpu.engine.GpuEngine`, numba.cuda). The
simulation chooses one, once, from ``run.device`` (:func:`make_engine`) and asks nothing else of
it: the step loop's checks, the feeder, the writers and the checkpoints read the simulation's
host arrays, which the engine keeps up to date (the GPU engine's pair list when it is read).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from dem.engine.state import PairList


class Engine(Protocol):
    """One simulation's stepping engine (it holds its simulation, ``sim``)."""

    #: ``run.device``: "cpu" or "cuda".
    device: str

    def advance(self, n_steps: int) -> None:
        """``n_steps`` velocity-Verlet steps, no instability checks.

        Adds to ``sim.stats`` the sum over the steps of the grains' x-momentum (kg m/s) and the
        step count, advances ``sim.step_index``, and leaves the host's spheres (and bodies) at
        the new state.
        """

    def compute_forces(self) -> None:
        """Rebuild the pair list and evaluate forces and torques now, no kick.

        The contact history is updated once, as a step does; ``sim.spheres.force``/``torque``
        hold the contact forces plus m a_body, and ``sim.forces_valid`` is set.
        """

    def fetch_pairs(self, pairs: PairList) -> None:
        """Bring the host's pair list ``pairs`` up to date (a no-op where it is the engine's)."""

    def pairs_replaced(self) -> None:
        """The host's pair list was set anew: the engine takes it up at its next call."""

    def deepest_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The pairs (i, j) among which the deepest overlap lies, int arrays.

        The CPU engine: its whole pair list; the GPU engine: the deepest pair alone, found on
        the device without copying the list back (none where nothing is listed).
        """


def make_engine(sim, device: str) -> Engine:
    """The engine of ``device`` ("cpu" or "cuda") for ``sim``; ValueError otherwise."""
    if device == "cpu":
        from dem.engine.cpu import CpuEngine

        return CpuEngine(sim)
    if device == "cuda":
        from dem.engine.gpu.engine import GpuEngine

        return GpuEngine(sim)
    raise ValueError(f"device = {device!r}: 'cpu' or 'cuda'")
