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

What all replicas must share: the contact law, time step, trough section (length, width, back
wall), the drive's period, rotation and the step count (the drive's phase); the batch takes the
largest of their Verlet skins (which changes when lists are rebuilt, never a force). Each
replica's drive (amplitude, angle, phase of its components) and incline are its own: the engine
gives each scene its own body acceleration g - s''(t) (``GpuEngine.drives``), so a sweep of the
vibration angle or throw number at one frequency is one batch. Spheres or clumps (all replicas
the same), periodic, between flat walls or in one trough mesh (the same triangles for all: the
U and V pans, a CAD trough; each sphere's mesh springs are its own, and the mesh, fixed in the
trough frame, is one for the batch, indexed for the batch's skin). The instability checks run
on the whole batch (a replica that blows up stops them all, naming its grain); each replica's
velocity is measured on its own.

Two ways to use it: :meth:`GpuReplicas.measure` (velocities of whole cycles, nothing else), or
:meth:`GpuReplicas.settle` and :meth:`GpuReplicas.run`, after which every replica's own
:class:`~dem.engine.simulation.Simulation` holds its state, pair list and momentum sums as if it
had run alone (:meth:`GpuReplicas.scatter`), so the run's writers, checks and summary work on it
unchanged (``dem run --replicas N --device cuda``, :mod:`dem.run.batch`).
"""

from __future__ import annotations

import copy

import numpy as np

from dem import config
from dem.engine.gpu.buffers import csr_index
from dem.engine.gpu.engine import GpuEngine
from dem.engine.simulation import Simulation, rest_speed
from dem.engine.state import Bodies, PairList, Spheres
from dem.errors import SimulationError
from dem.kernels.forces import N_WALLS
from dem.kernels.mesh import MESH_SLOTS
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
        sims: The replicas (:class:`~dem.engine.simulation.Simulation`, spheres or clumps, flat
            walls or one mesh, periodic), at the same step with the same law, step, trough and
            drive period.

    """

    def __init__(self, sims: list[Simulation]):
        sims = list(sims)
        if not sims:
            raise ValueError("no replicas")
        clumps = sims[0].bodies is not None
        mesh = sims[0].mesh
        for r, sim in enumerate(sims):
            if sim.feeder is not None:
                raise ValueError(f"replica {r}: the GPU batches periodic sections only (a feeder)")
            if (sim.bodies is not None) != clumps:
                raise ValueError(f"replica {r} differs from replica 0 in its grains' shape")
            if (sim.mesh is None) != (mesh is None) or (
                mesh is not None
                and sim.mesh is not None
                and not np.array_equal(sim.mesh.tri, mesh.tri)
            ):
                raise ValueError(f"replica {r} differs from replica 0 in its trough mesh")
        _same(sims, "contact law", lambda s: s.law.params)
        _same(sims, "time step", lambda s: s.dt)
        _same(sims, "rotation", lambda s: s.rotation)
        # one section and one period; the drive's amplitude, angle, phase and the incline may
        # differ (each replica's body acceleration is its own: a sweep of them is one batch)
        _same(sims, "trough section", lambda s: (s.trough.length, s.trough.width, s.geom.back))
        _same(sims, "drive period", lambda s: s.trough.period)
        _same(sims, "step index", lambda s: (s.step_index, s.drive_start_step, s.drive_on))
        self.counts = np.array([s.spheres.n for s in sims])
        self.start = np.concatenate([[0], np.cumsum(self.counts)])
        first = sims[0]
        stacked: tuple[str, ...] = ("x", "v", "omega", "force", "torque", "radius", "mass",
                                    "inv_mass", "inv_inertia", "wall_hist")  # fmt: skip
        if mesh is not None:
            stacked += ("mesh_hist", "mesh_normal")
        spheres = Spheres(
            **{name: np.concatenate([getattr(s.spheres, name) for s in sims]) for name in stacked},
            body=np.arange(self.start[-1], dtype=np.int64),
        )
        bodies = None
        if clumps:
            each = [s.bodies for s in sims if s.bodies is not None]  # all: checked above
            bodies = _stacked_bodies(each)
            spheres.body = bodies.body_of
            self.bcounts = np.array([b.n for b in each])
            self.bstart = np.concatenate([[0], np.cumsum(self.bcounts)])
        sim = Simulation(
            spheres, first.trough, first.law, first.dt, rotation=first.rotation,
            skin=max(s.skin for s in sims),
            reference_speed=first.reference_speed, timestep_limit=first.timestep_limit,
            bodies=bodies, mesh=None if mesh is None else copy.copy(mesh),  # indexed for its skin
        )  # fmt: skip
        sim.pairs = _stacked_pairs([s.pairs for s in sims], self.start, first.law.history_width)
        sim.step_index, sim.drive_start_step, sim.drive_on = (
            first.step_index, first.drive_start_step, first.drive_on,
        )  # fmt: skip
        sim.forces_valid = all(s.forces_valid for s in sims)
        self.scene = np.repeat(np.arange(len(sims)), self.counts)
        # the grains' scene: the momentum sums are per sphere, or per body for clumps
        self.grain_scene = self.scene if bodies is None else np.repeat(
            np.arange(len(sims)), self.bcounts
        )  # fmt: skip
        grain_mass = spheres.mass if bodies is None else bodies.mass
        self.mass = np.bincount(self.grain_scene, weights=grain_mass)
        sim.reference_speed = max(s.reference_speed for s in sims)
        self.sim = sim
        self.sims = sims
        self.engine = GpuEngine(sim, self.scene)
        sim.use_engine(self.engine)
        self.engine.px_sum = np.zeros(self.start[-1])
        self._set_drives()

    @property
    def replicas(self) -> int:
        """Number of replicas."""
        return self.counts.shape[0]

    def spheres(self, r: int) -> slice:
        """Replica r's spheres in the batch's arrays (``self.sim.spheres``)."""
        return slice(int(self.start[r]), int(self.start[r + 1]))

    def step_scheme(self) -> dict:
        """The step kernel the batch runs (``GpuEngine.step_scheme``)."""
        return self.engine.step_scheme()

    def advance(self, n_steps: int) -> np.ndarray:
        """``n_steps`` steps of every replica; each one's mass-weighted mean x-velocity, m/s."""
        sim = self.sim
        sim.stats[:] = 0.0
        self.engine.advance(n_steps)
        return self._px() / (n_steps * self.mass)

    def _set_drives(self) -> None:
        """Each replica's gravity (its incline) and drive for the engine's body accelerations.

        The drive arrays, on and off, follow the batch's ``drive_on``.
        """
        gravity = np.array([rs.gravity for rs in self.sims], dtype=np.float64)
        drive = {
            on: np.array([rs.trough.drive_array(on) for rs in self.sims], dtype=np.float64)
            for on in (False, True)
        }  # fmt: skip
        self.engine.drives = lambda sim: (gravity, drive[bool(sim.drive_on)])

    def run(self, n_steps: int, stop=None) -> int:
        """``n_steps`` steps of the batch with the instability checks, then :meth:`scatter`.

        As :meth:`dem.engine.simulation.Simulation.run` (``stop`` asked after every chunk);
        returns the steps advanced.
        """
        done = self.sim.run(n_steps, stop=stop)
        self.scatter(done)
        return done

    def _px(self) -> np.ndarray:
        """Each replica's momentum sum since the last call, kg m/s (and the engine's zeroed)."""
        engine = self.engine
        assert engine.px_sum is not None, "__init__ sets it"
        grains = self.grain_scene.shape[0]
        px = np.bincount(self.grain_scene, weights=engine.px_sum[:grains],
                         minlength=self.replicas)  # fmt: skip
        engine.px_sum[:] = 0.0
        return px

    def scatter(self, steps: int = 0) -> None:
        """Every replica's Simulation brought up to the batch, ``steps`` after the last scatter.

        Its spheres, pair list and springs, step index and drive; its momentum sums ``stats``
        grow by its own share of those steps. O(spheres + pairs log pairs) (the pairs sorted
        once on the host).
        """
        sim = self.sim
        s, pairs = sim.spheres, sim.pairs
        px = self._px()
        k = pairs.n_pairs
        cut = np.searchsorted(pairs.pair_i[:k], self.start)
        for r, rs in enumerate(self.sims):
            a, b = int(self.start[r]), int(self.start[r + 1])
            for name in ("x", "v", "omega", "force", "torque"):
                getattr(rs.spheres, name)[:] = getattr(s, name)[a:b]
            rs.spheres.wall_hist[:] = s.wall_hist[N_WALLS * a : N_WALLS * b]
            if sim.mesh is not None:
                rs.spheres.mesh_hist[:] = s.mesh_hist[MESH_SLOTS * a : MESH_SLOTS * b]
                rs.spheres.mesh_normal[:] = s.mesh_normal[MESH_SLOTS * a : MESH_SLOTS * b]
            if sim.bodies is not None:
                c, d = int(self.bstart[r]), int(self.bstart[r + 1])
                for name in ("x", "v", "q", "ang_mom", "omega", "force", "torque"):
                    getattr(rs.bodies, name)[:] = getattr(sim.bodies, name)[c:d]
            own = rs.pairs
            lo, hi = int(cut[r]), int(cut[r + 1])
            m = hi - lo
            if m > own.capacity:
                own.grow(OVERFLOW_PAIRS, m)
            own.pair_i[:m] = pairs.pair_i[lo:hi] - a
            own.pair_j[:m] = pairs.pair_j[lo:hi] - a
            own.hist[:m] = pairs.hist[lo:hi]
            own.counters[:] = (m, pairs.builds)
            own.x_ref[:] = pairs.x_ref[a:b]
            csr_index(own.pair_i[:m], own.pair_j[:m], b - a, own.part_start, own.part_slot)
            rs.stats[0] += px[r]
            rs.stats[1] += steps
            rs.step_index, rs.drive_start_step, rs.drive_on = (
                sim.step_index, sim.drive_start_step, sim.drive_on,
            )  # fmt: skip
            rs.forces_valid = True

    def start_drive(self) -> None:
        """The drive on with phase 0 now, for the batch and every replica."""
        self.sim.start_drive()
        for rs in self.sims:
            rs.start_drive()

    def settle(self, *, max_time: float | None = None, chunk_time: float = 0.005,
               progress=None) -> float:  # fmt: skip
        """All replicas with the drive off until every one is at rest.

        As :meth:`dem.engine.simulation.Simulation.settle`, each replica by its own rms speed;
        the batch rests until the last replica is at rest, so every replica rests that long.
        Returns the simulated time; raises SimulationError after ``max_time`` naming the
        replicas still moving.
        """
        max_time = config.DEM_SETTLE_MAX_TIME if max_time is None else max_time
        sim = self.sim
        sim.drive_on = False
        for rs in self.sims:
            rs.drive_on = False
        threshold = rest_speed(sim.spheres.radius)
        chunk = max(1, int(round(chunk_time / sim.dt)))
        start = sim.time
        while sim.time - start < max_time:
            self.run(chunk)
            rms = np.array([rs.rms_speed() for rs in self.sims])
            done = bool(np.all(rms < threshold))
            if progress is not None:
                progress(sim.time - start, float(rms.max()), threshold, done)
            if done:
                return sim.time - start
        moving = np.flatnonzero(rms >= threshold)
        raise SimulationError(
            f"replicas {moving.tolist()} did not come to rest within {max_time} s of simulated "
            f"time (rms speed up to {rms.max():.3g} m/s > {threshold:.3g} m/s): run one of them "
            "alone (--replicas 1) to see why"
        )

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


def _stacked_bodies(parts: list[Bodies]) -> Bodies:
    """The replicas' clumps as one list: members, bodies and CSR offset (O(total), one copy)."""
    sphere_base = np.concatenate([[0], np.cumsum([int(b.start[-1]) for b in parts])])
    body_base = np.concatenate([[0], np.cumsum([b.n for b in parts])])
    per_body = {
        name: np.concatenate([getattr(b, name) for b in parts]) for name in Bodies._PER_BODY
    }
    start = np.concatenate(
        [[0]] + [b.start[1:] + base for b, base in zip(parts, sphere_base, strict=False)]
    )  # fmt: skip
    return Bodies(
        **per_body, start=start.astype(np.int64),
        members=np.concatenate([b.members + base for b, base in zip(
            parts, sphere_base, strict=False)]).astype(np.int64),
        offsets=np.concatenate([b.offsets for b in parts]),
        body_of=np.concatenate([b.body_of + base for b, base in zip(
            parts, body_base, strict=False)]).astype(np.int64),
    )  # fmt: skip


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
