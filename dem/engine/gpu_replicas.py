"""Replicas of one scene stepped together on the GPU: one launch a step for all of them.

A 1500-sphere bed is too small for a GPU: a step is a few microseconds of work and some tens of
launch and read-back (validation/performance: the sphere-bed took 17 s on an H200 and 8 s on 16
CPU cores). R replicas of it (other fills, other seeds, perturbed copies) stepped as one scene of
R times the spheres fill the GPU. Each replica keeps its own coordinates (the same trough, walls
and drive); the neighbour search gives every replica a cell grid of its own
(:mod:`dem.kernels.cuda.neighbours`), so no sphere of one replica ever meets one of another, and
the step is the single scene's, sphere by sphere. A replica stepped in a batch is the same
computation as the replica alone except that the pair lists are rebuilt whenever any replica
needs it (a superset of its own builds): in numba's CUDA simulator identical replicas give the
single run's bits (tests/engine/test_gpu_replicas.py).

What all replicas must share: the contact law, time step, trough (length, width, inclination,
drive), rotation and the step count (the drive's phase); the batch takes the largest of their
Verlet skins (which changes when lists are rebuilt, never a force). Plain spheres only, as the GPU
engine. The instability checks run on the whole batch once a cycle (a replica that blows up stops
them all, naming its grain); each replica's velocity is measured on its own.
"""

from __future__ import annotations

import numpy as np

from dem.engine.simulation import Simulation
from dem.engine.state import PairList, Spheres
from dem.kernels.neighbours import OVERFLOW_PAIRS
from dem.physics.drive import cycle_edge


def _same(sims, what, get) -> None:
    first = get(sims[0])
    for r, sim in enumerate(sims[1:], start=1):
        value = get(sim)
        equal = np.array_equal(value, first) if isinstance(first, np.ndarray) else value == first
        if not equal:
            raise ValueError(f"replica {r} differs from replica 0 in its {what}: {value!r}")


class GpuReplicas:
    """R simulations of one scene as one GPU job.

    Args:
        sims: The replicas (:class:`~dem.engine.simulation.Simulation`, plain spheres, flat walls,
            periodic), at the same step with the same law, step, trough, drive and skin.

    """

    def __init__(self, sims: list[Simulation]):
        sims = list(sims)
        if not sims:
            raise ValueError("no replicas")
        for r, sim in enumerate(sims):
            if sim.bodies is not None or sim.mesh is not None or sim.feeder is not None:
                raise ValueError(f"replica {r}: the GPU batches plain spheres in a periodic trough")
        _same(sims, "contact law", lambda s: s.law.params)
        _same(sims, "time step", lambda s: s.dt)
        _same(sims, "rotation", lambda s: s.rotation)
        _same(sims, "trough", lambda s: s.trough)
        _same(sims, "step index", lambda s: (s.step_index, s.drive_start_step, s.drive_on))
        self.counts = np.array([s.spheres.n for s in sims])
        self.start = np.concatenate([[0], np.cumsum(self.counts)])
        first = sims[0]
        spheres = Spheres(
            **{
                name: np.concatenate([getattr(s.spheres, name) for s in sims])
                for name in (
                    "x",
                    "v",
                    "omega",
                    "force",
                    "torque",
                    "radius",
                    "mass",
                    "inv_mass",
                    "inv_inertia",
                    "wall_hist",
                )
            },  # fmt: skip
            body=np.arange(self.start[-1], dtype=np.int64),
        )
        sim = Simulation(
            spheres, first.trough, first.law, first.dt, rotation=first.rotation,
            skin=max(s.skin for s in sims),
            reference_speed=first.reference_speed, timestep_limit=first.timestep_limit,
        )  # fmt: skip
        sim.pairs = _stacked_pairs([s.pairs for s in sims], self.start, first.law.history_width)
        sim.step_index, sim.drive_start_step, sim.drive_on = (
            first.step_index, first.drive_start_step, first.drive_on,
        )  # fmt: skip
        sim.forces_valid = all(s.forces_valid for s in sims)
        self.scene = np.repeat(np.arange(len(sims)), self.counts)
        self.mass = np.bincount(self.scene, weights=spheres.mass)
        self.sim = sim
        self.engine = sim.use_gpu(self.scene)

    @property
    def replicas(self) -> int:
        """Number of replicas."""
        return self.counts.shape[0]

    def spheres(self, r: int) -> slice:
        """Replica r's spheres in the batch's arrays (``self.sim.spheres``)."""
        return slice(int(self.start[r]), int(self.start[r + 1]))

    def advance(self, n_steps: int) -> np.ndarray:
        """``n_steps`` steps of every replica; each one's mass-weighted mean x-velocity, m/s."""
        sim = self.sim
        sim.stats[:] = 0.0
        sim.stats[0] += self.engine.advance(
            sim, n_steps, sim.step_index - sim.drive_start_step, sim.drive_array()
        )  # fmt: skip
        sim.stats[1] += n_steps
        sim.step_index += n_steps
        px = np.bincount(self.scene, weights=self.engine.last_px, minlength=self.replicas)
        return px / (n_steps * self.mass)

    def measure(self, cycles: int, *, settle_cycles: int = 0, progress=None) -> np.ndarray:
        """Per-cycle velocities of whole drive cycles, (cycles, replicas), m/s.

        As :func:`dem.engine.simulation.measure_cycles` for each replica: the drive switched on
        (phase 0) if it is off, ``settle_cycles`` unmeasured cycles, then ``cycles`` measured
        ones ending on whole drive periods. The instability checks run after every cycle;
        ``progress(done, total)`` is called after every cycle.
        """
        sim = self.sim
        if not sim.drive_on:
            sim.start_drive()
        period = sim.trough.period
        first = int(round((sim.step_index - sim.drive_start_step) * sim.dt / period))
        total = settle_cycles + cycles
        out = np.empty((cycles, self.replicas))
        for k, c in enumerate(range(first, first + total)):
            end = cycle_edge(sim.drive_start_step, c + 1, period, sim.dt)
            v = self.advance(end - sim.step_index)
            sim.check()
            if k >= settle_cycles:
                out[k - settle_cycles] = v
            if progress is not None:
                progress(k + 1, total)
        return out


def _stacked_pairs(lists: list[PairList], start: np.ndarray, width: int) -> PairList:
    """The replicas' pair lists as one, sphere numbers offset (still sorted by key)."""
    n = int(start[-1])
    pairs = PairList.for_spheres(n, width)
    total = sum(p.n_pairs for p in lists)
    if total > pairs.capacity:
        pairs.grow(OVERFLOW_PAIRS, total)
    k = 0
    for p, base in zip(lists, start[:-1], strict=False):
        m = p.n_pairs
        pairs.pair_i[k : k + m] = p.pair_i[:m] + base
        pairs.pair_j[k : k + m] = p.pair_j[:m] + base
        pairs.hist[k : k + m] = p.hist[:m]
        k += m
    pairs.counters[:] = (k, 0)
    pairs.x_ref[:] = np.concatenate([p.x_ref for p in lists])
    return pairs
