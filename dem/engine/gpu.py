"""The GPU engine: a :class:`~dem.engine.simulation.Simulation`'s spheres and clumps on numba.cuda.

The state lives on the device between calls; the host's spheres (``sim.spheres``) are brought up
to date after every call of :meth:`GpuEngine.advance`, and the pair list (``sim.pairs``) when it
is read, so the instability checks, checkpoints and writers read the same arrays whichever engine
ran. Before a call the host's
positions, velocities and spins are compared with what the last call left there: anything that
changed them in between (a fill, a restart, a replaced grain) makes the engine upload the host's
state again, pair list and history included. A call costs a copy of the spheres across the bus
(about 280 bytes a sphere) besides the steps; the pairs (16 slots of 4 + 8 w bytes a sphere)
cross only when read (a checkpoint, the summary) and then cost a sort on the host, O(P log P).

The step is the CPU engine's (:mod:`dem.kernels.cuda.step`), the pair list the CPU engine's in
per-sphere slots (:mod:`dem.kernels.cuda.neighbours`), the force the CPU engine's contact law
compiled for the GPU (:mod:`dem.kernels.cuda.forces`), rigid clumps the CPU engine's clump step
(:mod:`dem.kernels.cuda.bodies`), a trough mesh's contacts the CPU's mesh functions compiled
for the GPU (:mod:`dem.kernels.cuda.mesh`, :func:`dem.kernels.cuda.step.mesh_step_kernel`). The
finite feeder is refused before a run starts.

The body acceleration g - s''(t) comes from an array, one row a queued step and one column a
scene (:func:`accelerations`, filled once a chunk): replicas of other drives or inclines stepped
together each feel their own.

The host does not wait for each step: it queues up to :attr:`GpuEngine.chunk` step launches and
then reads the rebuild trip once (:mod:`dem.kernels.cuda.step`). The launches queued after the
step that tripped do nothing; the host rebuilds and relaunches from there. The chunk follows the
steps between the last two rebuilds (half of them, 2 to :data:`MAX_CHUNK`), so that few launches
are wasted and the GPU is not kept waiting for the host.

Two step kernels give the same bits for spheres between flat walls: the plain one (a thread a
sphere, its contacts in its own loops) and the compact one (a block gathers its touching
contacts first, so a warp's threads run the contact law together). Which is faster depends on
the GPU and the scene, so by default (:attr:`GpuEngine.compact` None) a scene of
:data:`TUNE_MIN_SPHERES` or more runs its first chunks alternately with each, times them by the
host's clock (the queueing and the wait for the chunk, per launch; each kernel's first chunk, its
compile, untimed) and keeps the faster (:attr:`GpuEngine.tuned`); the chunks of the trial are the
run's own steps, so the trial costs only the slower kernel's share of a few chunks.
"""

from __future__ import annotations

import functools
import inspect
import math
import os
import time
import warnings

import numba
import numpy as np

from dem.config import DEM_GROWTH_FACTOR, NUMBA_OPTIONS
from dem.kernels.integrate import body_acceleration
from dem.kernels.neighbours import OVERFLOW_PAIRS, grid_of

#: Starting capacities: partners a sphere is the lower end of (the CPU engine's 16), reverse
#: partners, spheres a cell (a cell's edge is at least a diameter and a skin).
START_SLOTS = 16
START_CELL = 16
#: numba's CUDA simulator runs the kernels as Python: launches go the ordinary way there.
SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")
#: The most step launches queued before the host reads the rebuild trip.
MAX_CHUNK = 64
#: Where :attr:`GpuEngine.compact` is None (the default), scenes of at least this many spheres
#: (flat walls, one lane) time the plain and the compact step on their own first chunks and keep
#: the faster (:meth:`GpuEngine._pick`); smaller scenes are bound by the host's launches.
TUNE_MIN_SPHERES = 20_000
#: The trial times each step over at least this many chunks and launches (after an untimed
#: first chunk: its compile), the two alternating chunk by chunk so that a passing load on the
#: host falls on both.
TUNE_CHUNKS = 3
TUNE_LAUNCHES = 24
#: Launches after a decision before the trial runs again (the scene may have changed).
TUNE_EVERY = 20_000


def _grow(need: int) -> int:
    return int(need * DEM_GROWTH_FACTOR) + 1


@numba.njit(**NUMBA_OPTIONS)
def accelerations(times, gravity, drive, out):
    """a_body of every scene at every time: out[k, s] = a_body(times[k]) of scene s, m/s^2.

    ``gravity`` (S, 3) and ``drive`` (S, 12) per scene (:func:`dem.kernels.integrate.
    body_acceleration`, whose values these are to the bit).
    """
    for k in range(times.shape[0]):
        for s in range(gravity.shape[0]):
            ax, ay, az = body_acceleration(times[k], gravity[s], drive[s])
            out[k, s, 0] = ax
            out[k, s, 1] = ay
            out[k, s, 2] = az


@functools.cache
def _position(kernel, name: str) -> int:
    """The position of argument ``name`` of a numba.cuda kernel."""
    return list(inspect.signature(kernel.py_func).parameters).index(name)


class GpuEngine:
    """Device arrays of one simulation and the host loop that launches the kernels."""

    def __init__(self, sim, scene=None):
        """Engine for ``sim``; ``scene``: each sphere's scene, int (n,), or None for one.

        Scenes are independent copies of one trough stepped together
        (:mod:`dem.engine.gpu_replicas`): each has a cell grid of its own, so none touches another.
        """
        from numba import cuda

        from dem.kernels.cuda import bodies, forces, neighbours, step

        if sim.feeder is not None:
            raise ValueError("the GPU engine steps periodic sections only (no feeder)")
        self.cuda, self.forces, self.nb, self.step = cuda, forces, neighbours, step
        self.bodies = bodies
        self.NO_TRIP = step.NO_TRIP
        #: The step launches queued before the trip is read; it follows the rebuild interval.
        self.chunk = 4
        self.skipped = 0  # launches queued after a trip (done nothing), in all
        self._since_build = 0  # steps since the last build
        self._begin(sim)
        #: Launch the step through :class:`dem.kernels.cuda.launch.PreparedLaunch` (on a GPU).
        self.fast = not SIMULATOR
        self._prepared = {}
        #: Threads per block of the prepared (per-step) launches: a tuning knob, the same bits.
        self.threads = forces.THREADS_PER_BLOCK
        #: Threads a sphere in the step (1: :func:`dem.kernels.cuda.step.step_kernel`; more, one
        #: of ``step.LANE_COUNTS``: :func:`dem.kernels.cuda.step.lanes_step_kernel`, the same
        #: bits). Not yet timed on a GPU against 1, so 1 stays the default.
        self.lanes = 1
        #: The step that gathers each block's touching candidates before the contact law
        #: (:func:`dem.kernels.cuda.step.compact_step_kernel`, the same bits), listing at most
        #: ``compact_keep`` a sphere a pass (1 to ``step.COMPACT_KEEP``). True or False: that
        #: step; None (the default): timed against the plain step on the run's own chunks where
        #: the scene has ``tune_min`` spheres or more, flat walls and one lane (the plain below).
        self.compact = None
        self.compact_keep = step.COMPACT_KEEP
        self.tune_min = TUNE_MIN_SPHERES
        #: The last trial's outcome: {"chose": "plain" | "compact", "us_per_step": {"plain":
        #: mean, "compact": mean}, "trials": trials so far} (None: no trial, or none decided).
        self.tuned = None
        self._trial = None  # the trial under way: seconds, launches and chunks of each step
        self._since_trial = 0  # launches since the last decision
        self._chosen = None  # the step kernel and its launch of the chunk (:meth:`_choose`)
        self._clock = time.perf_counter
        self.mesh = None  # the trough mesh's device arrays (upload)
        #: Seconds the host spent queueing step launches and then waiting for them, in all.
        self.host_s = 0.0
        self.wait_s = 0.0
        # a small scene's grid is below numba's occupancy rule of thumb: no warning every step
        warnings.filterwarnings("ignore", message=".*Grid size .* under-utilization")
        self.scene_host = None if scene is None else np.asarray(scene, dtype=np.int32)
        self.scenes = 1 if scene is None else int(self.scene_host.max()) + 1
        #: Where scenes differ in their drive or incline: ``drives(sim)`` gives each scene's
        #: gravity (S, 3) and drive (S, 12); None: the simulation's, the same for all.
        self.drives = None
        self.acc_host = np.zeros((MAX_CHUNK, self.scenes, 3))
        self.last_px = None  # sum over the last call's steps of m_i v_x,i per sphere, kg m/s
        #: Where set (an array like ``last_px``), every call's ``last_px`` is added to it.
        self.px_sum = None
        self.snapshot = None  # the host arrays as the last call left them
        self.n = -1
        #: The device's pair list is newer than the host's (:meth:`download_pairs` on demand).
        self.pairs_on_device = False

    # --- host <-> device ----------------------------------------------------------------------

    @staticmethod
    def _state(sim) -> tuple:
        """The host arrays a step starts from (the bodies' too); :meth:`_stale` compares them."""
        s, b = sim.spheres, sim.bodies
        arrays = (s.x, s.v, s.omega)
        if sim.mesh is not None:
            arrays += (s.mesh_hist, s.mesh_normal)
        if b is not None:
            arrays += (b.x, b.v, b.q, b.ang_mom)
        return arrays

    def _stale(self, sim) -> bool:
        if self.snapshot is None or sim.spheres.n != self.n:
            return True
        now = self._state(sim)
        return len(now) != len(self.snapshot) or not all(
            np.array_equal(a, b) for a, b in zip(now, self.snapshot, strict=True)
        )

    def upload(self, sim) -> None:
        """Copy the host's state, pair list and history to the device."""
        from dem.kernels.cuda.forces import compact_to_slots

        cuda = self.cuda
        s, pairs = sim.spheres, sim.pairs  # the pairs first come back if the device's are newer
        self.pairs_on_device = False
        if s.n != self.n:  # another scene: time its steps anew
            self._trial = self.tuned = None
        n = self.n = s.n
        to = cuda.to_device
        self.x = [to(s.x), cuda.device_array((n, 3))]
        self.v = [to(s.v), cuda.device_array((n, 3))]
        self.omega = [to(s.omega), cuda.device_array((n, 3))]
        self.force, self.torque = to(s.force), to(s.torque)
        self.radius, self.mass = to(s.radius), to(s.mass)
        self.inv_mass, self.inv_inertia = to(s.inv_mass), to(s.inv_inertia)
        self.body = to(s.body)
        scene = np.zeros(n, dtype=np.int32) if self.scene_host is None else self.scene_host
        if scene.shape != (n,):
            raise ValueError(f"{scene.shape[0]} scene numbers for {n} spheres")
        self.scene = to(scene)
        self.wall = [to(s.wall_hist), to(s.wall_hist)]
        m = sim.mesh
        #: The mesh's triangles and index, then the spheres' mesh slots (None: flat walls).
        self.mesh = None
        if m is not None:
            self.mesh = (
                to(m.tri), to(m.grid), to(m.dims), to(m.cell_start), to(m.cell_tris),
                to(s.mesh_hist), to(s.mesh_normal),
            )  # fmt: skip
        self.x_ref = to(pairs.x_ref)
        self.width = pairs.hist.shape[1]
        nbr, count, slot_hist, self.slots = compact_to_slots(
            pairs.pair_i, pairs.pair_j, pairs.hist, pairs.n_pairs, n, START_SLOTS
            if pairs.n_pairs == 0 else None,
        )  # fmt: skip
        self.nbr = [to(nbr), None]
        self.count = [to(count), None]
        self.hist = [to(slot_hist), cuda.device_array_like(slot_hist)]
        self.rev, self.rev_count = self.nb.reverse_slots(self.nbr[0], self.count[0])
        self.cell_cap = START_CELL
        self.cell_count = cuda.device_array(0, dtype=np.int32)
        self.cell_items = cuda.device_array(0, dtype=np.int32)
        b = sim.bodies
        self.n_bodies = 0 if b is None else b.n
        if b is not None:
            self.body_x, self.body_v, self.q = to(b.x), to(b.v), to(b.q)
            self.ang_mom, self.body_omega = to(b.ang_mom), to(b.omega)
            self.body_force, self.body_torque = to(b.force), to(b.torque)
            self.body_mass, self.body_inv_mass, self.moments = (
                to(b.mass), to(b.inv_mass), to(b.moments),
            )  # fmt: skip
            self.start, self.members, self.offsets = to(b.start), to(b.members), to(b.offsets)
            first = scene[b.members[b.start[:-1]]]  # a body's scene: its first member's
            self.bscene = to(np.ascontiguousarray(first, dtype=np.int32))
        self.acc = cuda.to_device(self.acc_host)
        self.no_acc = cuda.to_device(np.zeros((1, self.scenes, 3)))  # clump members: no a_body
        self.px = cuda.to_device(np.zeros(max(n, self.n_bodies)))
        # the rebuild trip: mapped host memory on a GPU (read without a copy)
        none = np.full(1, self.NO_TRIP, dtype=np.int64)
        if SIMULATOR:
            self.trip = cuda.to_device(none)
        else:
            self.trip = cuda.mapped_array(1, dtype=np.int64)
            self.trip[0] = self.NO_TRIP
        self._prepared.clear()
        self.status = cuda.to_device(np.zeros(4, dtype=np.int64))
        self.builds = pairs.builds
        self.r_max = float(np.max(s.radius))
        self.length = float(sim.geom.length)

    def download(self, sim) -> None:
        """Bring the host's spheres up to date; the pairs stay on the device until asked for.

        (:attr:`dem.engine.simulation.Simulation.pairs` calls :meth:`download_pairs`.)
        """
        s = sim.spheres
        self.x[0].copy_to_host(s.x)
        self.v[0].copy_to_host(s.v)
        self.omega[0].copy_to_host(s.omega)
        self.force.copy_to_host(s.force)
        self.torque.copy_to_host(s.torque)
        self.wall[0].copy_to_host(s.wall_hist)
        if self.mesh is not None:
            self.mesh[5].copy_to_host(s.mesh_hist)
            self.mesh[6].copy_to_host(s.mesh_normal)
        b = sim.bodies
        if b is not None:
            for name, array in (
                ("body_x", b.x), ("body_v", b.v), ("q", b.q), ("ang_mom", b.ang_mom),
                ("body_omega", b.omega), ("body_force", b.force), ("body_torque", b.torque),
            ):  # fmt: skip
                getattr(self, name).copy_to_host(array)
        self.pairs_on_device = True
        self.snapshot = tuple(a.copy() for a in self._state(sim))

    def download_pairs(self, pairs) -> None:
        """Copy the pair list, its springs, x_ref and the CPU's CSR index into ``pairs``."""
        from dem.kernels.cuda.forces import slots_to_compact

        pi, pj, hist = slots_to_compact(
            self.nbr[0].copy_to_host(), self.count[0].copy_to_host(), self.hist[0].copy_to_host(),
            self.slots,
        )  # fmt: skip
        k = pi.shape[0]
        if k > pairs.capacity:
            pairs.grow(OVERFLOW_PAIRS, k)
        pairs.pair_i[:k], pairs.pair_j[:k], pairs.hist[:k] = pi, pj, hist
        pairs.counters[:] = (k, self.builds)
        self.x_ref.copy_to_host(pairs.x_ref)
        csr_index(pi, pj, self.n, pairs.part_start, pairs.part_slot)
        self.pairs_on_device = False

    def deepest_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The deepest pair overlap now, found on the device: ([a], [b]), or two empty arrays.

        For the instability check, which otherwise reads the whole pair list: O(N) on the
        device and 12 bytes a sphere across the bus (:func:`dem.kernels.cuda.neighbours.
        deepest_kernel`). The positions are the last call's (the host's, after a download).
        """
        cuda, n = self.cuda, self.n
        frac = cuda.device_array(n)
        partner = cuda.device_array(n, dtype=np.int32)
        self._launch(self.nb.deepest_kernel, n)(
            self.x[0], self.radius, self.nbr[0], self.count[0], self.length, frac, partner
        )  # fmt: skip
        frac, partner = frac.copy_to_host(), partner.copy_to_host()
        a = int(np.argmax(frac)) if n else 0
        if not n or partner[a] < 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        return np.array([a]), np.array([int(partner[a])])

    # --- the build and the step ---------------------------------------------------------------

    def _launch(self, kernel, n, block=None):
        t = self.forces.THREADS_PER_BLOCK if block is None else block
        return kernel[max(1, (n + t - 1) // t), t]

    def build(self, sim) -> None:
        """Rebuild the pair slots at the current positions, carrying the history over."""
        cuda, nb, n, geom = self.cuda, self.nb, self.n, sim.geom
        x = self.x[0]
        zrange = cuda.to_device(np.array([math.inf, -math.inf]))
        self._launch(nb.wrap_kernel, n)(x, geom.length, zrange)
        zmin, zmax = zrange.copy_to_host()
        if not (math.isfinite(zmin) and math.isfinite(zmax)):
            raise FloatingPointError("a sphere's height is not finite at a neighbour build")
        grid = grid_of(zmin, zmax, 2.0 * self.r_max + geom.skin, geom.length, geom.width)
        ncx, ncy, ncz = grid[0], grid[1], grid[2]
        n_cells = ncx * ncy * ncz * self.scenes
        while True:
            if self.cell_count.shape[0] < n_cells:
                self.cell_count = cuda.device_array(_grow(n_cells), dtype=np.int32)
            if self.cell_items.shape[0] < n_cells * self.cell_cap:
                self.cell_items = cuda.device_array(
                    self.cell_count.shape[0] * self.cell_cap, dtype=np.int32
                )
            if self.nbr[1] is None or self.nbr[1].shape[0] != n * self.slots:
                self.nbr[1] = cuda.device_array(n * self.slots, dtype=np.int32)
                self.count[1] = cuda.device_array(n, dtype=np.int32)
            if self.hist[1].shape[0] != n * self.slots:
                self.hist[1] = cuda.device_array((n * self.slots, self.width))
            self.status.copy_to_device(np.zeros(4, dtype=np.int64))
            self._launch(nb.fill_int_kernel, n_cells)(self.cell_count[:n_cells], 0)
            self._launch(nb.bin_kernel, n)(
                x, self.scene, ncx, ncy, ncz, grid[3], grid[4], grid[5], grid[6], geom.width,
                self.cell_count, self.cell_items, self.cell_cap, self.status,
            )  # fmt: skip
            self._launch(nb.scan_kernel, n)(
                x, self.radius, self.body, self.scene, geom.skin, geom.length, geom.width, ncx,
                ncy, ncz,
                grid[3], grid[4], grid[5], grid[6], self.cell_count, self.cell_items,
                self.cell_cap, self.nbr[0], self.count[0], self.hist[0], self.nbr[1],
                self.count[1], self.hist[1], self.x_ref, self.status,
            )  # fmt: skip
            need = self.status.copy_to_host()
            if need[nb.NEED_CELL] > self.cell_cap:
                self.cell_cap = _grow(int(need[nb.NEED_CELL]))
                continue
            if need[nb.NEED_SLOTS] > self.slots:
                self.slots = _grow(int(need[nb.NEED_SLOTS]))
                continue
            break
        self.nbr.reverse()
        self.count.reverse()
        self.hist.reverse()
        if self.hist[1].shape[0] != self.hist[0].shape[0]:
            self.hist[1] = cuda.device_array_like(self.hist[0])
        self.rev, self.rev_count = nb.reverse_slots(self.nbr[0], self.count[0],
                                                    self.rev.shape[0] // n)  # fmt: skip
        self.builds += 1
        self._prepared.clear()  # new slot arrays
        self.chunk = max(2, min(MAX_CHUNK, self._since_build // 2))
        self._since_build = 0

    def _sphere_args(self, sim, seq, acc, row, kick, next_drift) -> tuple:
        """The arguments of :func:`dem.kernels.cuda.step.step_kernel` for the buffers now."""
        geom = sim.geom
        p, pw = self.rows
        x, v, om = self.x, self.v, self.omega
        return (
            seq, self.trip, sim.law.model_id, p, pw, x[0], v[0], om[0], x[1], v[1], om[1],
            self.radius, self.mass, self.inv_mass, self.inv_inertia, self.nbr[0], self.count[0],
            self.rev, self.rev_count, self.hist[0], self.hist[1], self.wall[0], self.wall[1],
            geom.length, 0.5 * geom.width, geom.back, geom.dt, acc, row, self.scene,
            sim.rotation, kick, next_drift, self.x_ref, 0.25 * geom.skin * geom.skin, self.force,
            self.torque, self.px,
        )  # fmt: skip

    def _body_args(self, sim, seq, row, next_drift) -> tuple:
        """The arguments of :func:`dem.kernels.cuda.bodies.bodies_kernel`."""
        geom = sim.geom
        return (
            seq, self.trip, geom.dt, self.acc, row, self.bscene, sim.rotation, next_drift,
            self.force,
            self.torque, self.x[0], self.v[0], self.omega[0], self.body_x, self.body_v, self.q,
            self.ang_mom, self.body_force, self.body_torque, self.body_omega, self.body_inv_mass,
            self.body_mass, self.moments, self.offsets, self.start, self.members, self.x_ref,
            geom.length, 0.25 * geom.skin * geom.skin, self.px,
        )  # fmt: skip

    def _begin(self, sim) -> None:
        """Take up the simulation's law and scalars for this call.

        The user may change them between calls; prepared launches are keyed by them.
        """
        from dem.kernels.cuda.forces import law_rows

        geom = sim.geom
        self.rows = law_rows(sim.law.params)
        self._scalars = (
            sim.law.model_id, self.rows, geom.length, geom.width, geom.back, geom.dt, geom.skin,
            sim.rotation,
        )  # fmt: skip

    def _run(self, kernel, n, key, args, changing, block=None) -> None:
        """Launch ``kernel`` over n threads with ``args``, ``block`` a block (None: the default).

        On a GPU the launch is prepared once per ``key`` and only the arguments named in
        ``changing`` are set anew.
        """
        launch = self._prepared_launch(kernel, n, key, args, block) if self.fast else None
        if launch is None:
            self._launch(kernel, n, block)(*args)
            return
        for name in changing:
            i = _position(kernel, name)
            value = args[i]
            if isinstance(value, bool):
                launch.set_bool(i, value)
            elif isinstance(value, int):
                launch.set_int(i, value)
            else:
                launch.set_float(i, value)
        launch()

    def _step_kernel(self, compact: bool | None = None) -> tuple:
        """The step kernel :attr:`lanes`, ``compact`` and the trough's mesh choose.

        ``compact`` None: :attr:`compact`'s (None there: the plain step). Returns (kernel,
        threads, block, its leading arguments, its trailing arguments), the block None for the
        default :attr:`threads`.
        """
        step, lanes = self.step, self.lanes
        compact = bool(self.compact) if compact is None else compact
        if self.mesh is not None:
            if lanes != 1 or compact:
                raise ValueError(
                    f"lanes = {lanes}, compact = {self.compact} in a trough mesh: the GPU's mesh "
                    "step has one thread a sphere (lanes = 1, compact = False or None)"
                )
            return step.mesh_step_kernel, self.n, None, (), self.mesh
        if compact:
            keep = self.compact_keep
            if lanes != 1:
                raise ValueError(f"compact with lanes = {lanes}: the compact step has one lane")
            if not 1 <= keep <= step.COMPACT_KEEP:
                raise ValueError(f"compact_keep = {keep}: 1 to {step.COMPACT_KEEP}")
            return step.compact_step_kernel, self.n, step.COMPACT_BLOCK, (int(keep),), ()
        if lanes == 1:
            return step.step_kernel, self.n, None, (), ()
        if lanes not in step.LANE_COUNTS:
            raise ValueError(f"lanes = {lanes}: one of {step.LANE_COUNTS}")
        return step.lanes_step_kernel, self.n * lanes, step.LANE_BLOCK, (lanes,), ()

    def _choose(self) -> None:
        """Take up :attr:`lanes`, :attr:`compact` and the mesh for this call's steps.

        Once a call, not once a step: :meth:`_step` runs for every step. Where the plain and
        the compact step are timed against each other (:attr:`compact` None), both are made
        ready: the trial's chunks alternate (:meth:`_pick`), the others run the faster.
        """
        trial = (
            self.compact is None and self.lanes == 1 and self.mesh is None
            and self.n >= self.tune_min
        )  # fmt: skip
        if not trial:
            self._trial, self.tuned = None, None
        elif self._trial is None and self.tuned is None:
            self._start_trial()
        options = (False, True) if trial else (None,)
        self._options = {}
        for compact in options:
            step, n, block, lead, trail = self._step_kernel(compact)
            scheme = (self.lanes, compact) + lead + tuple(id(a) for a in trail)
            self._options[compact] = (step, n, block, lead, trail, scheme)
        faster = self.tuned is not None and self.tuned["chose"] == "compact"
        self._chosen = self._options[faster if trial else None]

    def _start_trial(self) -> None:
        self._trial = {"seconds": {False: 0.0, True: 0.0}, "launches": {False: 0, True: 0},
                       "chunks": {False: 0, True: 0}}  # fmt: skip

    def _pick(self) -> bool | None:
        """The step of the next chunk in a trial (the one with fewer chunks run), else None."""
        if self._trial is None:
            return None  # nothing to time
        pick = min((False, True), key=self._trial["chunks"].get)
        self._chosen = self._options[pick]
        return pick

    def _timed(self, compact, seconds: float, launches: int) -> None:
        """Take one chunk's time into the trial; decide once each step has its timings.

        A step's first chunk in a trial is not counted (it compiles); the chunks after count
        with all their launches, those queued after a rebuild's trip included (they cost each
        step the same). :data:`TUNE_EVERY` launches after a decision the trial runs again (the
        scene changes: a fill settles, the drive starts).
        """
        t = self._trial
        if t is None:
            self._since_trial += launches
            if self.tuned is not None and self._since_trial >= TUNE_EVERY:
                self._start_trial()
            return
        if t["chunks"][compact]:
            t["seconds"][compact] += seconds
            t["launches"][compact] += launches
        t["chunks"][compact] += 1
        if any(t["chunks"][c] <= TUNE_CHUNKS or t["launches"][c] < TUNE_LAUNCHES
               for c in (False, True)):  # fmt: skip
            return
        us = {("compact" if c else "plain"): 1e6 * t["seconds"][c] / t["launches"][c]
              for c in (False, True)}  # fmt: skip
        chose = "compact" if us["compact"] < us["plain"] else "plain"
        trials = 1 if self.tuned is None else self.tuned["trials"] + 1
        self.tuned = {"chose": chose, "us_per_step": us, "trials": trials}
        self._trial, self._since_trial = None, 0
        self._chosen = self._options[chose == "compact"]

    def step_scheme(self) -> dict:
        """The step kernel of the run (None before a call), and the last trial's timings.

        After a trial, the kernel it chose (a later trial's chunks alternate meanwhile).
        """
        chosen = self._chosen
        if self.tuned is not None:
            chosen = self._options[self.tuned["chose"] == "compact"]
        out = {"kernel": None if chosen is None else chosen[0].py_func.__name__}
        if self.tuned is not None:
            out["trial_us_per_step"] = self.tuned["us_per_step"]
            out["trials"] = self.tuned["trials"]
        return out

    def _step(self, sim, seq: int, row: int, kick: bool, next_drift: bool) -> None:
        """Launch step ``seq`` with the body accelerations of row ``row`` of :attr:`acc`.

        Spheres: the step kernel. Clumps: the members' forces, then the bodies' step. With
        ``kick`` False the forces alone (for clumps reduced to the bodies).
        """
        clumps = self.n_bodies > 0
        step, n, block, lead, trail, scheme = self._chosen
        if clumps:
            args = lead + self._sphere_args(sim, seq, self.no_acc, 0, False, False) + trail
            key = ("forces", scheme, id(self.hist[0]), id(self.wall[0]))
            self._run(step, n, key, args, ("seq",), block)
        else:
            args = lead + self._sphere_args(sim, seq, self.acc, row, kick, next_drift) + trail
            key = ("step", scheme, kick, id(self.x[0]), id(self.hist[0]), id(self.wall[0]))
            self._run(step, n, key, args, ("seq", "row", "next_drift"), block)
        self._swap(kick and not clumps)
        if not clumps:
            return
        if kick:
            self._run(
                self.bodies.bodies_kernel, self.n_bodies, ("bodies",),
                self._body_args(sim, seq, row, next_drift), ("seq", "row", "next_drift"),
            )  # fmt: skip
        else:
            self._launch(self.bodies.reduce_kernel, self.n_bodies)(
                self.force, self.torque, self.x[0], self.body_x, self.start, self.members,
                sim.geom.length, self.body_mass, self.acc, row, self.bscene, self.body_force,
                self.body_torque,
            )  # fmt: skip

    def _accelerate(self, sim, drive, times: np.ndarray) -> None:
        """Rows 0.. of :attr:`acc`: every scene's a_body at ``times`` (one row a time)."""
        if self.drives is None:
            gravity, drives = np.asarray(sim.gravity, dtype=np.float64)[None], drive[None]
        else:
            gravity, drives = self.drives(sim)
        k = times.shape[0]
        if gravity.shape[0] == 1 and self.scenes > 1:  # every scene the same
            gravity = np.repeat(gravity, self.scenes, axis=0)
            drives = np.repeat(drives, self.scenes, axis=0)
        accelerations(times, gravity, drives, self.acc_host[:k])
        self.acc[:k].copy_to_device(self.acc_host[:k])

    def _swap(self, state: bool) -> None:
        """The other history buffers (and with ``state``, the other sphere buffers) are current."""
        self.hist.reverse()
        self.wall.reverse()
        if state:
            self.x.reverse()
            self.v.reverse()
            self.omega.reverse()

    def _prepared_launch(self, kernel, n, key, args, block=None):
        """The launch of ``kernel`` for ``key``'s buffers, prepared once (None: not possible)."""
        from dem.kernels.cuda.launch import prepare

        key = (key, self._scalars, block, self.threads)
        launch = self._prepared.get(key)
        if launch is None:
            t = self.threads if block is None else block
            launch = prepare(kernel, max(1, (n + t - 1) // t), t, args)
            if launch is None:
                self.fast = False
                return None
            self._prepared[key] = launch
        return launch

    def _read_trip(self) -> int:
        """The ``seq`` of the launch that tripped a rebuild, or ``NO_TRIP``; waits for the queue."""
        if SIMULATOR:
            return int(self.trip.copy_to_host()[0])
        self.cuda.synchronize()
        return int(self.trip[0])

    def _reset_trip(self) -> None:
        if SIMULATOR:
            self.trip.copy_to_device(np.full(1, self.NO_TRIP, dtype=np.int64))
        else:
            self.trip[0] = self.NO_TRIP

    def _evaluate(self, sim, drive) -> None:
        """Rebuild and evaluate the forces at the current state, no kick."""
        self._reset_trip()
        self.build(sim)
        self._accelerate(sim, drive, np.array([sim.drive_time]))
        self._step(sim, 0, 0, False, False)

    def compute_forces(self, sim, drive) -> None:
        """Rebuild and evaluate forces at the current state (no kick), as the CPU engine does.

        ``drive``: :meth:`dem.physics.drive.Motion.kernel_array` (zeros: drive off).
        """
        self._begin(sim)
        if self._stale(sim):
            self.upload(sim)
        self._choose()
        self._evaluate(sim, drive)
        self.download(sim)

    def advance(self, sim, n_steps: int, step0: int, drive) -> float:
        """``n_steps`` steps from step index ``step0``, then the host's arrays brought up to date.

        t = step dt; ``drive`` as :meth:`compute_forces`. Returns the sum over the steps of
        sum_i m_i v_x,i (over the bodies for clumps), kg m/s.
        """
        px = self.steps(sim, n_steps, step0, drive)
        self.download(sim)
        return px

    def steps(self, sim, n_steps: int, step0: int, drive) -> float:
        """The steps of :meth:`advance` alone: the state stays on the device."""
        if n_steps <= 0:  # as the CPU engine: not even the first half kick
            self.last_px = np.zeros(max(self.n, 0))
            return 0.0
        self._begin(sim)
        if self._stale(sim):
            self.upload(sim)
        self._choose()
        if not sim.forces_valid:
            self._evaluate(sim, drive)
            sim.forces_valid = True
        geom = sim.geom
        dt, limit = geom.dt, 0.25 * geom.skin * geom.skin
        self.px.copy_to_device(np.zeros(self.px.shape[0]))
        self._reset_trip()
        if self.n_bodies:
            self._launch(self.bodies.half_step_kernel, self.n_bodies)(
                0, self.trip, dt, sim.rotation, self.body_x, self.body_v, self.q, self.ang_mom,
                self.body_force, self.body_torque, self.body_inv_mass, self.moments,
                self.body_omega, self.offsets, self.start, self.members, self.x[0], self.v[0],
                self.omega[0], self.x_ref, geom.length, limit,
            )  # fmt: skip
        else:
            self._launch(self.step.kick_drift_kernel, self.n)(
                0, self.trip, dt, self.x[0], self.v[0], self.omega[0], self.force, self.torque,
                self.inv_mass, self.inv_inertia, sim.rotation, self.x_ref, geom.length, limit,
            )  # fmt: skip
        trip = self._read_trip()
        s = 0
        while s < n_steps:
            if trip != self.NO_TRIP:
                self._reset_trip()
                self.build(sim)
            chunk = min(self.chunk, n_steps - s)
            compact = self._pick()
            t0 = self._clock()
            self._accelerate(sim, drive, (step0 + np.arange(s, s + chunk) + 1) * dt)
            for k in range(s, s + chunk):
                self._step(sim, k + 1, k - s, True, k < n_steps - 1)
            t1 = self._clock()
            trip = self._read_trip()
            t2 = self._clock()
            self.host_s += t1 - t0
            self.wait_s += t2 - t1
            self._timed(compact, t2 - t0, chunk)
            done = chunk if trip == self.NO_TRIP else trip - s
            if (chunk - done) % 2:  # the skipped launches swapped no buffers
                self._swap(self.n_bodies == 0)
            self.skipped += chunk - done
            self._since_build += done
            s += done
        self.last_px = self.px.copy_to_host()
        if self.px_sum is not None:
            self.px_sum += self.last_px
        return float(np.sum(self.last_px))


def csr_index(pair_i, pair_j, n, part_start, part_slot) -> None:
    """The CPU engine's index sphere -> its pair ends (:func:`dem.kernels.neighbours.rebuild`)."""
    k = pair_i.shape[0]
    ends = np.empty(2 * k, dtype=np.int64)
    ends[0::2], ends[1::2] = pair_i, pair_j
    part_start[0] = 0
    np.cumsum(np.bincount(ends, minlength=n), out=part_start[1 : n + 1])
    order = np.argsort(ends, kind="stable")  # each sphere's ends in increasing pair index
    slot = np.empty(2 * k, dtype=np.int64)
    slot[order] = np.arange(2 * k)
    part_slot[: 2 * k] = slot
