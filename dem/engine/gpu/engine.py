"""The GPU engine: a :class:`~dem.engine.simulation.Simulation`'s spheres and clumps on numba.cuda.

The state lives on the device between calls (:mod:`dem.engine.gpu.buffers`: what is copied
when). The step is the CPU engine's (:mod:`dem.kernels.cuda.step`), the pair list the CPU
engine's in per-sphere slots (:mod:`dem.kernels.cuda.neighbours`), the force the CPU engine's
contact law compiled for the GPU (:mod:`dem.kernels.cuda.forces`), rigid clumps the CPU engine's
clump step (:mod:`dem.kernels.cuda.bodies`), a trough mesh's contacts the CPU's mesh functions
compiled for the GPU (:mod:`dem.kernels.cuda.mesh`, :func:`dem.kernels.cuda.step.
mesh_step_kernel`). The finite feeder is refused before a run starts. Which step kernel runs:
:mod:`dem.engine.gpu.schemes`.

The body acceleration g - s''(t) comes from an array, one row a queued step and one column a
scene (:func:`accelerations`, filled once a chunk): replicas of other drives or inclines stepped
together each feel their own.

The host does not wait for each step: it queues up to :attr:`GpuEngine.chunk` step launches and
then reads the rebuild trip once (:mod:`dem.kernels.cuda.step`). The launches queued after the
step that tripped do nothing; the host rebuilds and relaunches from there. The chunk follows the
steps between the last two rebuilds (half of them, 2 to :data:`dem.kernels.cuda.launch.
MAX_CHUNK`), so that few launches are wasted and the GPU is not kept waiting for the host.
"""

from __future__ import annotations

import functools
import inspect
import math
import warnings
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from dem.config import DEM_GROWTH_FACTOR, NUMBA_OPTIONS
from dem.engine.gpu.buffers import SIMULATOR, Buffers
from dem.engine.gpu.schemes import StepSchemes
from dem.kernels.cuda.launch import MAX_CHUNK, THREADS_PER_BLOCK, blocks
from dem.kernels.integrate import body_acceleration
from dem.kernels.neighbours import grid_of


def _grow(need: int) -> int:
    return int(need * DEM_GROWTH_FACTOR) + 1


@numba.njit(**NUMBA_OPTIONS)  # type: ignore[call-overload]  # numba's stubs take no options dict
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


class GpuEngine(Buffers, StepSchemes):
    """The GPU engine of one simulation: its device arrays and the host loop of the launches.

    The engine door's contract (:class:`dem.engine.door.Engine`): :meth:`advance`,
    :meth:`compute_forces`, :meth:`fetch_pairs`, :meth:`pairs_replaced`, :meth:`deepest_pair`.
    """

    device = "cuda"

    def __init__(self, sim, scene=None) -> None:
        """Engine for ``sim``; ``scene``: each sphere's scene, int (n,), or None for one.

        Scenes are independent copies of one trough stepped together
        (:mod:`dem.engine.gpu.replicas`): each has a cell grid of its own, so none touches
        another.
        """
        from numba import cuda

        from dem.kernels.cuda import bodies, neighbours, step

        if sim.feeder is not None:
            raise ValueError("the GPU engine steps periodic sections only (no feeder)")
        self.sim = sim
        self.cuda, self.nb, self.step, self.bodies = cuda, neighbours, step, bodies
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
        self.threads = THREADS_PER_BLOCK
        self.init_schemes()
        self.mesh = None  # the trough mesh's device arrays (upload)
        #: Seconds the host spent queueing step launches and then waiting for them, in all.
        self.host_s = 0.0
        self.wait_s = 0.0
        # a small scene's grid is below numba's occupancy rule of thumb: no warning every step
        warnings.filterwarnings("ignore", message=".*Grid size .* under-utilization")
        if scene is None:
            self.scene_host, self.scenes = None, 1
        else:
            self.scene_host = np.asarray(scene, dtype=np.int32)
            self.scenes = int(self.scene_host.max()) + 1
        #: Where scenes differ in their drive or incline: ``drives(sim)`` gives each scene's
        #: gravity (S, 3) and drive (S, 12); None: the simulation's, the same for all.
        self.drives: Callable[[Any], tuple[np.ndarray, np.ndarray]] | None = None
        self.acc_host = np.zeros((MAX_CHUNK, self.scenes, 3))
        #: Sum over the last call's steps of m_i v_x,i per sphere, kg m/s (None before a call).
        self.last_px: np.ndarray | None = None
        #: Where set (an array like ``last_px``), every call's ``last_px`` is added to it.
        self.px_sum: np.ndarray | None = None
        self.snapshot = None  # the host arrays as the last call left them
        self.n = -1
        #: The device's pair list is newer than the host's (:meth:`download_pairs` on demand).
        self.pairs_on_device = False

    # --- the engine door ----------------------------------------------------------------------

    def advance(self, n_steps: int) -> None:
        """``n_steps`` steps of the simulation, its host arrays then brought up to date.

        Adds the steps' momentum sum (over the bodies for clumps) and count to ``sim.stats``
        and advances ``sim.step_index``, as the CPU engine does.
        """
        sim = self.sim
        step0 = sim.step_index - sim.drive_start_step
        sim.stats[0] += self.steps(sim, n_steps, step0, sim.drive_array())
        self.download(sim)
        sim.stats[1] += n_steps
        sim.step_index += n_steps

    def compute_forces(self) -> None:
        """Rebuild and evaluate forces at the current state (no kick), as the CPU engine does."""
        sim = self.sim
        self._begin(sim)
        if self._stale(sim):
            self.upload(sim)
        self._choose()
        self._evaluate(sim, sim.drive_array())
        self.download(sim)
        sim.forces_valid = True

    def fetch_pairs(self, pairs) -> None:
        """Bring the host's pair list ``pairs`` up to date where the device's is newer."""
        if self.pairs_on_device:
            self.download_pairs(pairs)

    def pairs_replaced(self) -> None:
        """The host's pair list was set anew: the next call uploads it."""
        self.pairs_on_device = False
        self.snapshot = None

    def deepest_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The deepest pair overlap now, found on the device: ([a], [b]), or two empty arrays.

        For the instability check, which otherwise reads the whole pair list: O(N) on the
        device and 12 bytes a sphere across the bus (:func:`dem.kernels.cuda.neighbours.
        deepest_kernel`). The positions are the last call's (the host's, after a download).
        """
        if not self.pairs_on_device:  # the host's list is the current one
            p = self.sim.pairs
            return p.pair_i[: p.n_pairs], p.pair_j[: p.n_pairs]
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
        if block is None:
            return kernel[blocks(n), THREADS_PER_BLOCK]
        return kernel[max(1, (n + block - 1) // block), block]

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
        geom = sim.geom
        from dem.kernels.cuda.forces import law_rows

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

    def _step(self, sim, seq: int, row: int, kick: bool, next_drift: bool) -> None:
        """Launch step ``seq`` with the body accelerations of row ``row`` of :attr:`acc`.

        Spheres: the step kernel. Clumps: the members' forces, then the bodies' step. With
        ``kick`` False the forces alone (for clumps reduced to the bodies).
        """
        clumps = self.n_bodies > 0
        assert self._chosen is not None, "_choose runs before a call's steps"
        step, n, block, lead, trail, scheme = self._chosen
        key: tuple
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

    def steps(self, sim, n_steps: int, step0: int, drive) -> float:
        """``n_steps`` steps from step index ``step0``; the state stays on the device.

        t = step dt; ``drive``: :meth:`dem.physics.drive.Motion.kernel_array` (zeros: drive
        off). Returns the sum over the steps of sum_i m_i v_x,i (over the bodies for clumps),
        kg m/s.
        """
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
