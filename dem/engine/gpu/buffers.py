"""The GPU engine's buffers: the host's state copied to the device and back.

The state lives on the device between calls; the host's spheres (``sim.spheres``) are brought up
to date after every call of :meth:`dem.engine.gpu.engine.GpuEngine.advance`, and the pair list
(``sim.pairs``) when it is read, so the instability checks, checkpoints and writers read the same
arrays whichever engine ran. Before a call the host's positions, velocities and spins are
compared with what the last call left there: anything that changed them in between (a fill, a
restart, a replaced grain) makes the engine upload the host's state again, pair list and history
included. A call costs a copy of the spheres across the bus (about 280 bytes a sphere) besides
the steps; the pairs (16 slots of 4 + 8 w bytes a sphere) cross only when read (a checkpoint,
the summary) and then cost a sort on the host, O(P log P).

The pair list goes to the device in per-sphere slots (:func:`dem.kernels.cuda.forces.
compact_to_slots`) and comes back in the CPU engine's compact layout with its CSR index
(:func:`csr_index`).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from dem.kernels.neighbours import OVERFLOW_PAIRS

#: Starting capacities: partners a sphere is the lower end of (the CPU engine's 16), spheres a
#: cell (a cell's edge is at least a diameter and a skin).
START_SLOTS = 16
START_CELL = 16
#: numba's CUDA simulator runs the kernels as Python: launches go the ordinary way there.
SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


class Buffers:
    """The device arrays of one simulation, uploaded from and downloaded to its host arrays.

    A mixin of :class:`dem.engine.gpu.engine.GpuEngine`: ``self.cuda`` is numba.cuda, and
    :meth:`forget_trial` the step schemes' (:class:`dem.engine.gpu.schemes.StepSchemes`).
    The annotations below name for the type checker what the engine's ``__init__`` sets.
    """

    #: numba.cuda, imported by the engine (a GPU, or the simulator).
    cuda: Any
    #: Spheres on the device (-1 before the first upload).
    n: int
    #: Each sphere's scene, int32 (n,), or None for one scene; ``scenes`` of them.
    scene_host: np.ndarray | None
    scenes: int
    #: Host side of :attr:`acc`: a_body of each queued step and scene, (MAX_CHUNK, scenes, 3).
    acc_host: np.ndarray
    #: The rebuild trip's value where no launch tripped (:data:`dem.kernels.cuda.step.NO_TRIP`).
    NO_TRIP: int
    _prepared: dict
    #: The host arrays as the last call left them (:meth:`_state`), None: upload anew.
    snapshot: tuple | None
    #: The trough mesh's device arrays, then the spheres' mesh slots (None: flat walls).
    mesh: tuple | None

    if TYPE_CHECKING:  # the step schemes', declared for the type checker only

        def forget_trial(self) -> None:
            """:meth:`dem.engine.gpu.schemes.StepSchemes.forget_trial`."""

    @staticmethod
    def _state(sim) -> tuple:
        """The host arrays a step starts from (the bodies' too); :meth:`_stale` compares them."""
        s, b = sim.spheres, sim.bodies
        arrays: tuple = (s.x, s.v, s.omega)
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
        from dem.kernels.cuda.neighbours import reverse_slots

        cuda = self.cuda
        s, pairs = sim.spheres, sim.pairs  # the pairs first come back if the device's are newer
        self.pairs_on_device = False
        if s.n != self.n:  # another scene: time its steps anew
            self.forget_trial()
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
        self.rev, self.rev_count = reverse_slots(self.nbr[0], self.count[0])
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

        (:attr:`dem.engine.simulation.Simulation.pairs` calls :meth:`download_pairs` through
        :meth:`dem.engine.gpu.engine.GpuEngine.fetch_pairs`.)
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
