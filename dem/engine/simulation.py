"""The DEM step loop: fill, settle, drive; :mod:`dem.run.runner` runs it behind ``dem run``.

The order of operations in one step n -> n + 1 (half kick and drift, neighbour rebuild, pair
forces, gather with walls and body force and the second half kick, all inside
:func:`dem.kernels.integrate.advance`) is written once, in ARCHITECTURE.md ("One DEM step").

The trajectory does not depend on the number of threads, bit for bit: every force sum is taken
in the same order whatever the threads (per-pair rows, then a per-sphere gather in pair order),
and the momentum sum of the measurement adds fixed chunks in order (tests/kernels/test_threads.py).

Rigid clumps (screws, clumps from a file) replace the sphere kicks (items 1 and 4 of the step) by
the rigid-body update of :func:`dem.kernels.integrate.advance_clumps`: bodies half kick, drift and
free rotation, members placed; after the per-member gather (walls, no body force) the forces and
torques are reduced to the bodies, M a_body is added at each centre of mass and the closing half
kick places the members again. Members of one clump never contact each other. Plain spheres keep the
sphere integrator.

Every ``DEM_CHECK_INTERVAL`` steps Python checks for instability (:mod:`dem.engine.checks`:
non-finite values, grains far faster than drive and gravity can make them, overlaps beyond
``DEM_MAX_OVERLAP_FRACTION`` of the radius or growing at consecutive checks, a grain out of the
trough) and raises :class:`dem.errors.SimulationError` naming the measured cause, the grain, where
and when, and the fix. The deepest overlap is recorded (:meth:`Simulation.overlap_summary`); one
above ``DEM_OVERLAP_WARN_FRACTION`` is an accuracy matter, a warning, not a stop.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from dem import config
from dem.engine.checks import InstabilityChecks
from dem.engine.door import Engine, make_engine
from dem.engine.state import Bodies, PairList, Spheres
from dem.errors import SimulationError
from dem.kernels.forces import N_WALLS
from dem.kernels.forces import contact_counts as kernel_contact_counts
from dem.kernels.layout import Geometry, MeshArrays
from dem.kernels.neighbours import OVERFLOW_PAIRS
from dem.kernels.rigid import rotational_energy
from dem.physics.drive import cycle_edge
from dem.scene.mesh import TriangleMesh
from dem.scene.timestep import ContactLaw, timestep_limits  # noqa: F401  (re-exported)
from dem.scene.trough import Trough, check_section_length

if TYPE_CHECKING:
    from dem.engine.threads import ThreadGuard


class Simulation(InstabilityChecks):
    """Spheres in a periodic trough section: the state and the step loop.

    One step's order is in ARCHITECTURE.md ("One DEM step"); instability checks every
    ``DEM_CHECK_INTERVAL`` steps.

    Args:
        spheres: Sphere state (modified in place).
        trough: Geometry and drive.
        law: Contact law.
        dt: Time step, s.
        rotation: False locks rotation (spins stay zero, torques are not integrated).
        skin: Verlet skin, m; default ``DEM_SKIN_FRACTION`` times the largest radius.
        reference_speed: Speed scale for the instability check, m/s (drive and free fall).
        bodies: Rigid clumps owning the spheres (:meth:`dem.engine.state.Bodies.create`), or None
        for
            plain spheres.
        timestep_limit: The stability limit dt was chosen under, s (reported; nan if unknown).
        mesh: A trough mesh (:class:`dem.scene.mesh.TriangleMesh`) replacing the flat floor and side
            walls, or None.
        feeder: A finite feeder (:class:`dem.engine.feeder.Feeder`): grains past the discharge edge
        are
            removed and new ones fed at the back while the drive is on; None for a periodic
            section.
        device: The engine that steps: ``"cpu"`` (numba) or ``"cuda"`` (numba.cuda on a GPU;
            :func:`dem.engine.device.check_device` says what it refuses). ValueError otherwise.

    """

    def __init__(
        self,
        spheres: Spheres,
        trough: Trough,
        law: ContactLaw,
        dt: float,
        *,
        rotation: bool = True,
        skin: float | None = None,
        reference_speed: float | None = None,
        bodies: Bodies | None = None,
        timestep_limit: float = math.nan,
        mesh: TriangleMesh | None = None,
        feeder=None,
        device: str = "cpu",
    ):
        if device not in ("cpu", "cuda"):  # dem.scene.schema.DEVICES
            raise ValueError(f"device = {device!r}: 'cpu' or 'cuda'")
        self.device = device
        self._engine: Engine | None = None  # made at first use (:attr:`engine`)
        self.spheres = spheres
        self.bodies = bodies
        self.trough = trough
        self.law = law
        self.dt = float(dt)
        self.timestep_limit = float(timestep_limit)
        self.rotation = bool(rotation)
        if bodies is not None and not self.rotation:
            bodies.ang_mom[:] = 0.0
            bodies.place(spheres)
        r_max = float(np.max(spheres.radius))
        self.skin = config.DEM_SKIN_FRACTION * r_max if skin is None else float(skin)
        reach = 0.0 if bodies is None else float(np.max(np.linalg.norm(bodies.offsets, axis=1)))
        check_section_length(trough.length, r_max, self.skin, reach)
        self.mesh = mesh
        if mesh is not None:
            mesh.index(r_max + self.skin)
            spheres.use_mesh()
        spheres.set_history_width(law.history_width)
        self.pairs = PairList.for_spheres(spheres.n, law.history_width)
        self.geom = Geometry(trough.length, trough.width, self.skin, self.dt, trough.back)
        self.gravity = trough.gravity
        self.drive_on = False
        self.drive_start_step = 0
        self.step_index = 0
        #: Sums of the step loop since the last reset: sum over steps of the x-momentum, the
        #: steps, and (finite feeders, whose mass changes) sum over steps of the grain mass.
        self.stats = np.zeros(3)
        #: Lasting id of each grain (frames and results.h5); fed grains get new ids.
        self.grain_id = np.arange(self.n_grains, dtype=np.int64)
        #: Type index of each grain (``particles.types``), int64 (n_grains,); None: one type.
        self.grain_type: np.ndarray | None = None
        #: With grain types: each sphere's x at the last cycle's edge, m (its type's velocity over
        #: the cycle is the displacement since); None before the drive starts or for one type.
        self.type_mark: np.ndarray | None = None
        self.feeder = feeder
        if feeder is not None:
            feeder.next_id = self.n_grains
        self.reference_speed = reference_speed or (
            trough.drive_speed + math.sqrt(2 * config.GRAVITY * 10 * r_max)
        )
        self.forces_valid = False
        #: The deepest overlap seen at the checks (:meth:`overlap_summary`).
        self._max_overlap = {
            "fraction": 0.0, "grain": -1, "against": "", "position_m": [math.nan] * 3,
            "time_s": math.nan, "step": -1, "phase": "",
        }  # fmt: skip
        self._growth = None  # (contact, its fractions at consecutive checks) above the bound
        # a grain higher than the fill's top plus the height the largest speed the speed check
        # lets pass throws it is far above the trough (DEM_MAX_SPEED_FACTOR)
        top = float(np.max(spheres.x[:, 2] + spheres.radius))
        self._mesh_box = None
        if mesh is not None:
            self._mesh_box = (mesh.tri.min(axis=(0, 1)), mesh.tri.max(axis=(0, 1)))
            top = max(top, float(self._mesh_box[1][2]))
        throw = config.DEM_MAX_SPEED_FACTOR * self.reference_speed
        self._ceiling = top + throw * throw / (2.0 * config.GRAVITY)
        #: A :class:`dem.engine.threads.ThreadGuard` (the runner sets one for runs on several
        #: threads).
        self.guard: ThreadGuard | None = None
        self._step_seconds = 0.0  # wall time of one step in the last chunk ``run`` advanced

    @property
    def engine(self) -> Engine:
        """The engine that steps this simulation (:class:`dem.engine.door.Engine`).

        Chosen from ``device`` and made at first use (again where ``device`` changed): the CPU
        engine (:class:`dem.engine.cpu.CpuEngine`) or the GPU engine
        (:class:`dem.engine.gpu.engine.GpuEngine`).
        """
        if self._engine is None or self._engine.device != self.device:
            self._engine = make_engine(self, self.device)
        return self._engine

    def use_engine(self, engine: Engine) -> Engine:
        """Step with ``engine`` from now on (the GPU engine of a batch of replicas); returns it."""
        self.device = engine.device
        self._engine = engine
        return engine

    @property
    def pairs(self) -> PairList:
        """The pair list and its springs; after GPU steps, brought to the host when asked for.

        The GPU engine keeps the pairs on the device (copying them back costs more than 500 steps
        of a million spheres); reading this attribute copies them into the host's list first.
        """
        if self._engine is not None:
            self._engine.fetch_pairs(self._pairs)
        return self._pairs

    @pairs.setter
    def pairs(self, value: PairList) -> None:
        if self._engine is not None:  # the host's list is the one now: the engine takes it up
            self._engine.pairs_replaced()
        self._pairs = value

    # --- stepping ---------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time since the start, s."""
        return self.step_index * self.dt

    @property
    def drive_time(self) -> float:
        """Time since the drive was switched on (phase origin), s."""
        return (self.step_index - self.drive_start_step) * self.dt

    def start_drive(self) -> None:
        """Switch the drive on with phase 0 now: a = A omega^2 sin(omega (t - t_now)) e."""
        self.drive_on = True
        self.drive_start_step = self.step_index
        if self.feeder is not None:
            self.feeder.start(self)
        # sin(0) = 0: the stored forces are already those of drive time 0

    def mesh_layout(self) -> MeshArrays | None:
        """The trough mesh and the spheres' contact slots as the kernels take them (or None)."""
        s = self.spheres
        m = self.mesh
        if m is None:
            return None
        return MeshArrays(m.tri, m.grid, m.dims, m.cell_start, m.cell_tris, s.mesh_hist,
                          s.mesh_normal)  # fmt: skip

    def replace_grains(
        self, keep: np.ndarray, new_spheres: Spheres | None = None,
        new_bodies: Bodies | None = None, new_ids: np.ndarray | None = None,
    ) -> None:  # fmt: skip
        """Keep the grains where ``keep`` (bool, per grain) and append new ones at rest.

        The kept grains keep their state, stored forces, wall and mesh springs, and the pairs
        between them keep their contact history: the pair list is renumbered (the order of the
        kept spheres is kept, so it stays sorted by key) and the next step rebuilds it from
        there, carrying the history over as any rebuild does. New grains (``new_spheres``, and
        ``new_bodies`` for clumps, ids ``new_ids``) touch nothing: their stored force is
        m a_body now, exact for the first half kick. O(n) per call; a finite feeder calls it
        only when a grain leaves or arrives.
        """
        s, b, p = self.spheres, self.bodies, self.pairs
        keep = np.asarray(keep, dtype=bool)
        t = self.drive_time if self.drive_on else 0.0
        a_body = self.gravity + (self.trough.frame_acceleration(t) if self.drive_on else 0.0)
        if b is None:
            idx = np.flatnonzero(keep)
            spheres = s.take(idx, np.arange(idx.size))
            bodies = None
            old = idx
        else:
            bodies, old = b.take(np.flatnonzero(keep))
            spheres = s.take(old, bodies.body_of)
        ids = self.grain_id[keep]
        if new_spheres is not None and new_spheres.n:
            new_spheres.set_history_width(self.law.history_width)
            new_spheres.force[:] = new_spheres.mass[:, None] * a_body
            if new_bodies is None:
                spheres = spheres.concat(new_spheres, np.arange(spheres.n + new_spheres.n))
            else:
                new_bodies.force[:] = new_bodies.mass[:, None] * a_body
                assert bodies is not None, "new clumps need a simulation of clumps"
                bodies = bodies.concat(new_bodies)
                spheres = spheres.concat(new_spheres, bodies.body_of)
            ids = np.concatenate([ids, np.asarray(new_ids, dtype=np.int64)])
        # the pairs between kept spheres, renumbered
        where = np.full(s.n, -1, dtype=np.int64)
        where[old] = np.arange(old.size)
        k = p.n_pairs
        pi, pj = where[p.pair_i[:k]], where[p.pair_j[:k]]
        both = (pi >= 0) & (pj >= 0)
        pairs = PairList.for_spheres(spheres.n, self.law.history_width)
        if both.sum() > pairs.capacity:
            pairs.grow(OVERFLOW_PAIRS, int(both.sum()))
        kept = int(both.sum())
        pairs.pair_i[:kept], pairs.pair_j[:kept] = pi[both], pj[both]
        pairs.hist[:kept] = p.hist[:k][both]
        pairs.counters[:] = (kept, p.counters[1])
        self.spheres, self.bodies, self.pairs = spheres, bodies, pairs
        self.grain_id = ids

    def wall_gaps(self, x: np.ndarray) -> np.ndarray:
        """Distance of points (n, 3) from each wall, (walls, n), m.

        The flat floor, side walls and back wall (:meth:`dem.scene.trough.Trough.wall_gaps`), or
        with a mesh two rows: the distance to the mesh and to the back wall (inf without one).
        """
        if self.mesh is None:
            return self.trough.wall_gaps(x)
        return np.stack([self.mesh.gaps(x), self.trough.back_gaps(x)])

    def compute_forces(self) -> None:
        """Rebuild the pair list and evaluate forces and torques at the current state (no kick).

        Updates the contact history once, as a step does; ``spheres.force``/``torque`` hold
        contact forces plus m a_body.
        """
        self.engine.compute_forces()

    def drive_array(self) -> np.ndarray:
        """The drive as the kernels take it (:meth:`dem.physics.drive.Motion.kernel_array`)."""
        return self.trough.drive_array(self.drive_on)

    def advance(self, n_steps: int) -> None:
        """``n_steps`` steps by the engine, without the instability checks (:meth:`run` has them).

        The x-momentum and step sums go to :attr:`stats`.
        """
        self.engine.advance(n_steps)

    def run(self, n_steps: int, stop=None) -> int:
        """Advance ``n_steps`` steps, checking for instability every ``DEM_CHECK_INTERVAL``.

        A finite feeder exchanges grains (discharge, and feed once the drive is on) after every
        chunk of at most :attr:`dem.engine.feeder.Feeder.interval` steps. ``stop`` (a callable, or
        None) is asked after every chunk; when it returns True the run returns early. Without a
        feeder the chunks then shorten to about ``DEM_STOP_LATENCY_S`` of wall time each, from
        the last chunk's speed; the checks (and so the overlap record) stay on every
        ``DEM_CHECK_INTERVAL``-th step of the call and its last, whatever the machine's load.
        Returns the steps advanced.
        """
        left = total = int(n_steps)
        guard = self.guard
        feeder = self.feeder
        limit = config.DEM_CHECK_INTERVAL
        if feeder is not None:
            limit = min(limit, feeder.interval)
        while left > 0:
            # a chunk never crosses a multiple of ``limit`` steps from the call's start: the
            # checks fall there (and on the call's last step) whatever shortens a chunk below,
            # so that the overlap record samples the same steps on a busy machine as on an idle
            # one
            chunk = min(left, limit - (total - left) % limit)
            if stop is not None and feeder is None and self._step_seconds > 0.0:
                # a big scene asks ``stop`` about every DEM_STOP_LATENCY_S, not every 500 steps
                # (a million spheres take a minute for those); a feeder keeps its exchange
                # chunks, so that a resumed run exchanges on the same steps
                chunk = min(chunk, max(1, int(config.DEM_STOP_LATENCY_S / self._step_seconds)))
            if guard is not None and feeder is None and guard.trying:
                # a try of the other thread count may be the slow one: keep it short (a feeder
                # keeps its exchange chunks, so that the exchanges fall on the same steps)
                chunk = min(chunk, config.DEM_THREAD_GUARD_TRY_STEPS)
            if feeder is not None:
                self.stats[2] += chunk * self.total_mass
            t0 = time.perf_counter()
            if guard is None:
                self.advance(chunk)
            else:
                threads = guard.choose()
                self.advance(chunk)
                guard.record(threads, chunk, time.perf_counter() - t0)
            self._step_seconds = (time.perf_counter() - t0) / chunk
            left -= chunk
            if feeder is not None:
                feeder.exchange(self)
            if left == 0 or (total - left) % limit == 0:
                self.check()
            if left > 0 and stop is not None and stop():
                break
        return total - left

    @property
    def n_grains(self) -> int:
        """Number of grains: bodies for clumps, spheres otherwise."""
        return self.spheres.n if self.bodies is None else self.bodies.n

    @property
    def total_mass(self) -> float:
        """Total grain mass, kg (clump members carry the clump mass, so bodies are summed)."""
        b = self.bodies
        return float(np.sum(self.spheres.mass if b is None else b.mass))

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy in the trough frame, J."""
        b = self.bodies
        if b is not None:
            trans = 0.5 * np.sum(b.mass * np.einsum("ij,ij->i", b.v, b.v))
            return float(trans + rotational_energy(b.q, b.ang_mom, b.moments))
        s = self.spheres
        trans = 0.5 * np.sum(s.mass * np.einsum("ij,ij->i", s.v, s.v))
        rot = 0.5 * np.sum(np.einsum("ij,ij->i", s.omega, s.omega) / s.inv_inertia)
        return float(trans + rot)

    def rms_speed(self) -> float:
        """Root mean square sphere speed, m/s."""
        return float(np.sqrt(np.mean(np.einsum("ij,ij->i", self.spheres.v, self.spheres.v))))

    def settle(self, *, max_time: float | None = None, chunk_time: float = 0.005,
               progress=None) -> float:  # fmt: skip
        """Run with the drive off until the rms speed < DEM_SETTLE_SPEED_FRACTION sqrt(g r).

        A sparse bed may never get there: a grain rolling on the floor (a sphere, or a screw
        rolling round its head) keeps its speed, with nothing to stop it. After
        ``DEM_SETTLE_STEADY_AFTER`` s a fill whose rms speed has stayed within
        ``DEM_SETTLE_STEADY_SPREAD`` over the last ``DEM_SETTLE_STEADY_WINDOW`` s, below
        ``DEM_SETTLE_STEADY_FACTOR`` times the threshold, is taken as settled too, with a
        warning that says so (a bed that comes to rest before is untouched, bit for bit).

        Returns the simulated settling time, s; raises SimulationError after ``max_time``.
        ``progress(elapsed_s, rms_speed, threshold, done)`` is called after every chunk.
        """
        max_time = config.DEM_SETTLE_MAX_TIME if max_time is None else max_time
        self.drive_on = False
        threshold = rest_speed(self.spheres.radius)
        chunk = max(1, int(round(chunk_time / self.dt)))
        start = self.time
        recent: list[tuple[float, float]] = []
        while self.time - start < max_time:
            self.run(chunk)
            rms = self.rms_speed()
            elapsed = self.time - start
            recent = [(t, v) for t, v in recent if t >= elapsed - config.DEM_SETTLE_STEADY_WINDOW]
            recent.append((elapsed, rms))
            speeds = [v for _, v in recent]
            steady = (
                elapsed >= config.DEM_SETTLE_STEADY_AFTER
                and elapsed - recent[0][0] >= config.DEM_SETTLE_STEADY_WINDOW - 1.5 * chunk_time
                and max(speeds) < config.DEM_SETTLE_STEADY_FACTOR * threshold
                and max(speeds) <= (1.0 + config.DEM_SETTLE_STEADY_SPREAD) * min(speeds)
            )
            if progress is not None:
                progress(elapsed, rms, threshold, rms < threshold or steady)
            if rms < threshold:
                return elapsed
            if steady:
                warnings.warn(
                    f"the fill came to a steady state, not to rest: after {elapsed:.3g} s its "
                    f"rms speed has stayed at {rms:.2g} m/s ({rms / threshold:.2g} times the "
                    f"rest threshold) for {config.DEM_SETTLE_STEADY_WINDOW:g} s, grains rolling "
                    "on the floor with nothing to stop them (a sparse bed); the drive starts "
                    "from it (material.rolling_friction brings such grains to rest)",
                    stacklevel=2,
                )
                return elapsed
        causes = []
        incline = math.degrees(math.atan2(-self.gravity[0], -self.gravity[2]))
        if abs(incline) > 0.05:
            causes.append(f"the trough is inclined {incline:.3g} deg: grains that roll (spheres "
                          "without material.rolling_friction) or slide (beyond the friction "
                          "angle) never rest on it")  # fmt: skip
        if not self.law.critically_damped:  # eps_n > 0
            causes.append("raise the normal damping (lower material.restitution_normal)")
        causes.append("check the contact stiffness and the time step")
        raise SimulationError(
            f"the fill did not come to rest within {max_time} s of simulated time (rms speed "
            f"{self.rms_speed():.3g} m/s > {threshold:.3g} m/s); "
            + "; ".join(causes)
            + (
                "; in a finite feeder, spheres that roll freely keep running out over the "
                "discharge edge: give material.rolling_friction (e.g. 0.05)"
                if self.feeder is not None
                else ""
            )
        )

    def cycle_velocity(self) -> float:
        """Mass-weighted mean x-velocity over the steps since ``stats`` was last zeroed, m/s.

        The step loop sums the grains' x-momentum after every step into ``stats``; nan if no step
        was taken.
        """
        if not self.stats[1]:
            return math.nan
        if self.feeder is not None:  # the mass changed: sum over steps of the mass present
            return float(self.stats[0] / self.stats[2]) if self.stats[2] else math.nan
        return float(self.stats[0] / (self.stats[1] * self.total_mass))

    def mean_velocity_x(self) -> float:
        """Mass-weighted mean x-velocity now (trough frame), m/s."""
        if self.bodies is not None:
            b = self.bodies
            return float(np.sum(b.mass * b.v[:, 0]) / np.sum(b.mass))
        s = self.spheres
        return float(np.sum(s.mass * s.v[:, 0]) / np.sum(s.mass))

    def contact_snapshot(self) -> dict:
        """Every touching contact now: kind, spheres, point, normal, forces and overlap.

        :func:`dem.kernels.snapshot.contact_snapshot` on the pair list the last force
        evaluation checked (as :meth:`contact_counts`), the state left as it is. A mesh
        trough's triangle contacts are not listed.
        """
        from dem.kernels.snapshot import contact_snapshot

        s, pairs, g = self.spheres, self.pairs, self.geom
        out = _snapshot_arrays(pairs.n_pairs + N_WALLS * s.n)
        n = contact_snapshot(
            self.law.model_id, self.law.params, s.x, s.v, s.omega, s.radius, s.mass,
            pairs.pair_i, pairs.pair_j, pairs.n_pairs, pairs.hist, s.wall_hist, g.length,
            0.5 * g.width, g.back, self.dt, out["kind"], out["i"], out["j"], out["point"],
            out["normal"], out["normal_force"], out["tangential_force"], out["overlap"],
        )  # fmt: skip
        return {k: a[:n] for k, a in out.items()}

    def contact_counts(self) -> np.ndarray:
        """Touching neighbours plus touching walls per sphere, (n,) int64.

        Counted by the force kernels' own tests (:func:`dem.kernels.forces.contact_counts`): a
        mesh contact is one per triangle face or shared edge point the forces add, so a sphere
        in the bottom of a V counts both faces. The pair list is the one the last force
        evaluation checked against the current positions (rebuilding here would reorder the
        pairs, and so the bits, of a run that writes frames).
        """
        count = np.zeros(self.spheres.n, dtype=np.int64)
        kernel_contact_counts(
            self.spheres.n, self.spheres.as_layout(), self.pairs.as_layout(), self.pairs.n_pairs,
            self.geom, self.mesh_layout(), count,
        )  # fmt: skip
        return count


def _snapshot_arrays(rows: int) -> dict:
    return {"kind": np.zeros(rows, np.int64), "i": np.zeros(rows, np.int64),
            "j": np.zeros(rows, np.int64), "point": np.zeros((rows, 3)),
            "normal": np.zeros((rows, 3)), "normal_force": np.zeros(rows),
            "tangential_force": np.zeros((rows, 3)), "overlap": np.zeros(rows)}  # fmt: skip


def rest_speed(radius: np.ndarray) -> float:
    """The rms speed below which a fill is at rest, m/s.

    DEM_SETTLE_SPEED_FRACTION sqrt(g r), r the mean sphere radius.
    """
    r = float(np.mean(radius))
    return config.DEM_SETTLE_SPEED_FRACTION * math.sqrt(config.GRAVITY * r)


def measure_cycles(sim: Simulation, cycles: int, *, settle_cycles: int = 0) -> np.ndarray:
    """Per-cycle mean conveying velocities of whole drive cycles, (cycles,), m/s.

    Switches the drive on (phase 0) if it is off, runs ``settle_cycles`` unmeasured cycles,
    then ``cycles`` measured ones, each ending on a whole number of drive periods since the
    drive started (as ``dem run`` does, without writers). README, A DEM run defines the
    velocity: :meth:`Simulation.cycle_velocity` of each cycle.
    """
    if not sim.drive_on:
        sim.start_drive()
    period = sim.trough.period
    first = int(round((sim.step_index - sim.drive_start_step) * sim.dt / period))
    out = np.empty(int(cycles))
    for c in range(first, first + settle_cycles + cycles):
        end = cycle_edge(sim.drive_start_step, c + 1, period, sim.dt)
        sim.stats[:] = 0.0
        sim.run(end - sim.step_index)
        if c >= first + settle_cycles:
            out[c - first - settle_cycles] = sim.cycle_velocity()
    sim.stats[:] = 0.0
    return out
