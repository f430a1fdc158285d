"""Structure-of-arrays state: spheres (the contact members), rigid bodies and the pair list.

Spheres are what touch: positions, velocities, spins, forces and torques are per sphere, and the
kernels accumulate contact forces per sphere. A grain is a sphere, or a rigid clump
(:class:`Bodies`) that owns several member spheres (``body[s]`` is the grain of sphere s); a
reduction sphere -> body (force, torque about the clump's centre of mass) and the rigid-body
update of :mod:`dem.kernels.rigid` slot in between the force gather and the kick without touching
the pair loop. A run of plain spheres has no :class:`Bodies` and keeps the sphere integrator.

All arrays are float64 C-contiguous unless stated; n spheres, B bodies, ``cap`` pair capacity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dem.config import DEM_GROWTH_FACTOR
from dem.kernels.forces import N_WALLS
from dem.kernels.layout import BodyArrays, PairArrays, SphereArrays
from dem.kernels.neighbours import OVERFLOW_CELLS, OVERFLOW_PAIRS, OVERFLOW_SLOTS
from dem.kernels.rigid import angular_velocity, update_members
from dem.physics.mass import sphere_mass


@dataclass
class Spheres:
    """Per-sphere state.

    Attributes:
        x: Positions in the trough frame, (n, 3), m.
        v: Velocities relative to the trough, (n, 3), m/s.
        omega: Spins, (n, 3), rad/s.
        force: Total force of the last evaluation (contacts + body force), (n, 3), N.
        torque: Total torque of the last evaluation, (n, 3), N m.
        radius: (n,), m.
        mass: (n,), kg.
        inv_mass: 1 / mass, (n,), 1/kg.
        inv_inertia: 1 / I with I = 2/5 m r^2 (solid sphere), (n,), 1/(kg m^2).
        wall_hist: Contact history per sphere and wall, row ``N_WALLS s + w`` (N_WALLS = 4: the
            floor, the side walls at y = -W/2 and +W/2, a feeder's back wall), (N_WALLS n,
            width), width the law's history width (the tangential spring first, m); a row is
            zeroed while its sphere does not touch that wall.
        body: Grain index of each sphere, (n,), int64.
        mesh_hist, mesh_normal: Contact slots with a trough mesh (row ``MESH_SLOTS s + k``):
            each slot's contact history (width floats, the tangential spring first, m),
            (MESH_SLOTS n, width), and the normal of its last contact, (MESH_SLOTS n, 3); no
            rows without a mesh (:mod:`dem.kernels.mesh`, :meth:`use_mesh`).

    """

    x: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    inv_mass: np.ndarray
    inv_inertia: np.ndarray
    wall_hist: np.ndarray
    body: np.ndarray
    mesh_hist: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    mesh_normal: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @classmethod
    def create(
        cls, positions: np.ndarray, radius: np.ndarray | float, density: np.ndarray | float
    ) -> Spheres:
        """Spheres at rest at ``positions`` (n, 3): radius (m), density (kg/m^3), (n,) or scalar."""
        x = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3).copy()
        n = x.shape[0]
        r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,)).copy()
        rho = density if np.ndim(density) == 0 else np.asarray(density, dtype=np.float64)
        if np.any(r <= 0) or np.any(np.asarray(rho) <= 0):
            raise ValueError("radius and density must be positive")
        mass = sphere_mass(rho, r)
        inertia = 0.4 * mass * r**2
        return cls(
            x=x,
            v=np.zeros((n, 3)),
            omega=np.zeros((n, 3)),
            force=np.zeros((n, 3)),
            torque=np.zeros((n, 3)),
            radius=r,
            mass=mass,
            inv_mass=1.0 / mass,
            inv_inertia=1.0 / inertia,
            wall_hist=np.zeros((N_WALLS * n, 3)),
            body=np.arange(n, dtype=np.int64),
        )

    @property
    def n(self) -> int:
        """Number of spheres."""
        return self.x.shape[0]

    def use_mesh(self) -> None:
        """Allocate the mesh contact slots (empty, all springs at rest)."""
        from dem.kernels.mesh import MESH_SLOTS

        if self.mesh_hist.shape[0] != MESH_SLOTS * self.n:
            self.mesh_hist = np.zeros((MESH_SLOTS * self.n, self.wall_hist.shape[1]))
            self.mesh_normal = np.zeros((MESH_SLOTS * self.n, 3))

    def set_history_width(self, width: int) -> None:
        """Give the wall and mesh springs ``width`` floats per contact, at rest, if they differ.

        ``width`` is the contact law's history width (:data:`dem.kernels.contact.HISTORY_WIDTH`).
        """
        if self.wall_hist.shape[1] != width:
            self.wall_hist = np.zeros((self.wall_hist.shape[0], width))
        if self.mesh_hist.shape[1] != width:
            self.mesh_hist = np.zeros((self.mesh_hist.shape[0], width))

    def take(self, index: np.ndarray, body: np.ndarray) -> Spheres:
        """The spheres ``index`` (int, in the order given) as new arrays, owned by grains ``body``.

        Per-sphere rows, wall springs (``N_WALLS`` rows each) and mesh slots follow the
        spheres; a finite feeder drops discharged grains this way (:mod:`dem.engine.feeder`).
        """
        index = np.asarray(index, dtype=np.int64)

        def rows(a, k):
            if a.shape[0] == 0:
                return a.copy()
            w = a.shape[1]
            return np.ascontiguousarray(a.reshape(-1, k, w)[index].reshape(-1, w))

        from dem.kernels.mesh import MESH_SLOTS

        return Spheres(
            x=self.x[index], v=self.v[index], omega=self.omega[index],
            force=self.force[index], torque=self.torque[index], radius=self.radius[index],
            mass=self.mass[index], inv_mass=self.inv_mass[index],
            inv_inertia=self.inv_inertia[index], wall_hist=rows(self.wall_hist, N_WALLS),
            body=np.ascontiguousarray(body, dtype=np.int64),
            mesh_hist=rows(self.mesh_hist, MESH_SLOTS),
            mesh_normal=rows(self.mesh_normal, MESH_SLOTS),
        )  # fmt: skip

    def concat(self, other: Spheres, body: np.ndarray) -> Spheres:
        """These spheres followed by ``other``'s, owned by grains ``body`` (both lists)."""
        mesh = self.mesh_hist.shape[0] > 0
        if mesh:
            other.use_mesh()
        both = {
            name: np.concatenate([getattr(self, name), getattr(other, name)])
            for name in ("x", "v", "omega", "force", "torque", "radius", "mass", "inv_mass",
                         "inv_inertia", "wall_hist", "mesh_hist", "mesh_normal")
        }  # fmt: skip
        return Spheres(body=np.ascontiguousarray(body, dtype=np.int64), **both)

    def as_layout(self) -> SphereArrays:
        """The arrays as the kernels take them (:class:`dem.kernels.layout.SphereArrays`)."""
        return SphereArrays(
            self.x,
            self.v,
            self.omega,
            self.force,
            self.torque,
            self.radius,
            self.mass,
            self.inv_mass,
            self.inv_inertia,
            self.wall_hist,
        )


@dataclass
class Bodies:
    """Rigid clumps of member spheres (all copies of one template).

    Attributes:
        x: Centres of mass X, trough frame, (B, 3), m (x wrapped into [0, length) each step).
        v: Centre-of-mass velocities V relative to the trough, (B, 3), m/s.
        q: Orientations, unit quaternions (w, x, y, z), body -> trough frame, (B, 4).
        ang_mom: Angular momenta L about X, trough frame, (B, 3), kg m^2/s.
        inv_mass: 1 / M, (B,), 1/kg.
        mass: M, (B,), kg.
        moments: Principal moments of inertia (body frame), (B, 3), kg m^2.
        force: Force F_b of the last evaluation (contacts + M a_body), (B, 3), N.
        torque: Torque T_b about X of the last evaluation, trough frame, (B, 3), N m.
        omega: Angular velocities, trough frame, (B, 3), rad/s.
        start: CSR start of each body's members in ``members``, int64 (B + 1,).
        members: Sphere indices grouped by body, int64 (n,).
        offsets: Member offsets d_s from X in the body frame, (n, 3), m.
        body_of: Body of each sphere, int64 (n,) (the same array as ``Spheres.body``).

    """

    x: np.ndarray
    v: np.ndarray
    q: np.ndarray
    ang_mom: np.ndarray
    inv_mass: np.ndarray
    mass: np.ndarray
    moments: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    omega: np.ndarray
    start: np.ndarray
    members: np.ndarray
    offsets: np.ndarray
    body_of: np.ndarray

    @classmethod
    def create(
        cls, template, positions: np.ndarray, orientations: np.ndarray
    ) -> tuple[Bodies, Spheres]:
        """Clumps of ``template`` at rest; returns the bodies and their member spheres.

        ``positions`` (B, 3) are the centres of mass, m; ``orientations`` (B, 4) unit
        quaternions (normalised here).

        Member spheres are numbered body by body (sphere b k + i is member i of body b). They
        carry the clump mass M as ``mass`` (the contact law's effective mass m* = M_a M_b /
        (M_a + M_b), M against a wall, as LIGGGHTS multisphere does) and the sphere inertia of
        M as ``inv_inertia`` (unused: members do not rotate on their own).
        """
        x = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3).copy()
        q = np.ascontiguousarray(orientations, dtype=np.float64).reshape(-1, 4).copy()
        q /= np.linalg.norm(q, axis=1)[:, None]
        n_bodies, k = x.shape[0], template.count
        n = n_bodies * k
        mass = float(template.mass)
        body_of = np.repeat(np.arange(n_bodies, dtype=np.int64), k)
        offsets = np.tile(np.asarray(template.centres, dtype=np.float64), (n_bodies, 1))
        radius = np.tile(np.asarray(template.radii, dtype=np.float64), n_bodies)
        bodies = cls(
            x=x,
            v=np.zeros((n_bodies, 3)),
            q=q,
            ang_mom=np.zeros((n_bodies, 3)),
            inv_mass=np.full(n_bodies, 1.0 / mass),
            mass=np.full(n_bodies, mass),
            moments=np.tile(np.asarray(template.moments, dtype=np.float64), (n_bodies, 1)),
            force=np.zeros((n_bodies, 3)),
            torque=np.zeros((n_bodies, 3)),
            omega=np.zeros((n_bodies, 3)),
            start=np.arange(0, n + 1, k, dtype=np.int64),
            members=np.arange(n, dtype=np.int64),
            offsets=np.ascontiguousarray(offsets),
            body_of=body_of,
        )
        member_mass = np.full(n, mass)
        spheres = Spheres(
            x=np.zeros((n, 3)),
            v=np.zeros((n, 3)),
            omega=np.zeros((n, 3)),
            force=np.zeros((n, 3)),
            torque=np.zeros((n, 3)),
            radius=radius,
            mass=member_mass,
            inv_mass=1.0 / member_mass,
            inv_inertia=1.0 / (0.4 * member_mass * radius**2),
            wall_hist=np.zeros((N_WALLS * n, 3)),
            body=body_of,
        )
        bodies.place(spheres)
        return bodies, spheres

    @property
    def n(self) -> int:
        """Number of bodies B."""
        return self.x.shape[0]

    def place(self, spheres: Spheres) -> None:
        """Set omega from L and the members' positions, velocities and spins from the bodies."""
        angular_velocity(self.q, self.ang_mom, self.moments, self.omega)
        update_members(
            self.x, self.v, self.q, self.omega, self.offsets, self.body_of, spheres.x, spheres.v,
            spheres.omega,
        )  # fmt: skip

    _PER_BODY = ("x", "v", "q", "ang_mom", "inv_mass", "mass", "moments", "force", "torque",
                 "omega")  # fmt: skip

    def take(self, index: np.ndarray) -> tuple[Bodies, np.ndarray]:
        """The bodies ``index`` (int, in the order given) and their members' old sphere indices.

        Members are renumbered body by body in the new order; ``body_of`` follows.
        """
        index = np.asarray(index, dtype=np.int64)
        counts = self.start[index + 1] - self.start[index]
        old = (
            np.concatenate([self.members[self.start[b] : self.start[b + 1]] for b in index])
            if index.size
            else np.zeros(0, dtype=np.int64)
        )
        start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        n = int(start[-1])
        per_body = {name: getattr(self, name)[index] for name in self._PER_BODY}
        out = Bodies(
            **per_body, start=start, members=np.arange(n, dtype=np.int64),
            offsets=np.ascontiguousarray(self.offsets[old]),
            body_of=np.repeat(np.arange(index.size, dtype=np.int64), counts),
        )  # fmt: skip
        return out, old

    def concat(self, other: Bodies) -> Bodies:
        """These bodies followed by ``other``'s (its members numbered after these)."""
        n = int(self.start[-1])
        per_body = {
            name: np.concatenate([getattr(self, name), getattr(other, name)])
            for name in self._PER_BODY
        }
        return Bodies(
            **per_body,
            start=np.concatenate([self.start, other.start[1:] + n]).astype(np.int64),
            members=np.arange(n + int(other.start[-1]), dtype=np.int64),
            offsets=np.concatenate([self.offsets, other.offsets]),
            body_of=np.concatenate([self.body_of, other.body_of + self.n]).astype(np.int64),
        )

    def as_layout(self) -> BodyArrays:
        """The arrays as the kernels take them (:class:`dem.kernels.layout.BodyArrays`)."""
        return BodyArrays(
            self.x,
            self.v,
            self.q,
            self.ang_mom,
            self.inv_mass,
            self.mass,
            self.moments,
            self.force,
            self.torque,
            self.omega,
            self.start,
            self.members,
            self.offsets,
            self.body_of,
        )


@dataclass
class PairList:
    """Verlet pair list with per-pair contact history, cell work arrays and the CSR index.

    Attributes:
        n: Number of spheres.
        capacity: Pair capacity ``cap``; ``cell_capacity`` cells (+1 for the start array).
        slots: Neighbour slots j > i per sphere during a build (``scratch_j``, (n slots,)).
        counters: int64 (2,): valid pairs, builds so far.
        x_ref: Positions at the last build, (n, 3).
        pair_i, pair_j: int64 (cap,): i < j, sorted by the key i n + j (:attr:`pair_key`).
        width: Floats of contact history per pair (the law's, 3 or 5).
        hist: Contact history per pair, (cap, width): the tangential elongation, m, first.
        part_start: CSR sphere -> its pair ends, int64 (n + 1,): sphere s owns the slots
            ``part_start[s]`` to ``part_start[s + 1]``, in increasing pair index.
        part_slot: The slot of pair k's end i (entry 2 k) and end j (entry 2 k + 1), int64
            (2 cap,).
        inbox: Force and torque each pair end received in the last parallel evaluation, by
            slot, (2 cap, 6), N and N m (one thread never touches it).

    """

    n: int
    capacity: int
    cell_capacity: int
    slots: int = 16
    width: int = 3
    counters: np.ndarray = field(init=False)

    def __post_init__(self):
        n, cap = self.n, self.capacity
        self.counters = np.zeros(2, dtype=np.int64)
        self.x_ref = np.full((n, 3), np.inf)  # forces a build at the first step
        self.pair_i = np.zeros(cap, dtype=np.int64)
        self.pair_j = np.zeros(cap, dtype=np.int64)
        self.hist = np.zeros((cap, self.width))
        self.scratch_j = np.zeros(n * self.slots, dtype=np.int32)
        self.scratch_hist = np.zeros((cap, self.width))
        self.counts = np.zeros(n, dtype=np.int64)
        self.offsets = np.zeros(n + 1, dtype=np.int64)
        self.cell_of = np.zeros(n, dtype=np.int64)
        self.cell_start = np.zeros(self.cell_capacity + 1, dtype=np.int64)
        self.cell_particles = np.zeros(n, dtype=np.int64)
        self.part_start = np.zeros(n + 1, dtype=np.int64)
        self.part_slot = np.zeros(2 * cap, dtype=np.int64)
        self.inbox = np.zeros((0, 6))  # allocated by ensure_inbox() for the parallel pair loop

    @classmethod
    def for_spheres(cls, n: int, width: int = 3) -> PairList:
        """A list for n spheres with room for 4 pairs each, regrown when a build overflows.

        A dense bed of equal spheres uses 2.9 pairs a sphere with the skin.
        """
        return cls(n=n, capacity=max(16, 4 * n), cell_capacity=max(64, 4 * n), width=width)

    @property
    def pair_key(self) -> np.ndarray:
        """The history key i n + j of every pair slot, (cap,) int64 (sorted over the valid ones)."""
        return self.pair_i * self.n + self.pair_j

    def ensure_inbox(self) -> None:
        """Allocate ``inbox`` before a parallel pair loop (one thread never needs it)."""
        if self.inbox.shape[0] < 2 * self.capacity:
            self.inbox = np.zeros((2 * self.capacity, 6))

    @property
    def n_pairs(self) -> int:
        """Number of valid pairs."""
        return int(self.counters[0])

    @property
    def builds(self) -> int:
        """Number of builds so far."""
        return int(self.counters[1])

    def as_layout(self) -> PairArrays:
        """The arrays as the kernels take them (:class:`dem.kernels.layout.PairArrays`)."""
        return PairArrays(
            self.x_ref,
            self.pair_i,
            self.pair_j,
            self.hist,
            self.scratch_j,
            self.scratch_hist,
            self.counts,
            self.offsets,
            self.cell_of,
            self.cell_start,
            self.cell_particles,
            self.part_start,
            self.part_slot,
            self.inbox,
        )

    def grow(self, status: int, need: int) -> None:
        """Regrow after a kernel reported overflow ``status`` needing ``need``; keeps the pairs."""
        if status == OVERFLOW_SLOTS:
            self.slots = int(need * DEM_GROWTH_FACTOR) + 1
            self.scratch_j = np.zeros(self.n * self.slots, dtype=np.int32)
            return
        if status == OVERFLOW_CELLS:
            self.cell_capacity = int(need * DEM_GROWTH_FACTOR) + 1
            self.cell_start = np.zeros(self.cell_capacity + 1, dtype=np.int64)
            return
        if status != OVERFLOW_PAIRS:
            raise ValueError(f"unknown overflow status {status}")
        old = self.n_pairs
        keep = {name: getattr(self, name)[:old].copy() for name in ("pair_i", "pair_j", "hist")}
        counters = self.counters.copy()
        x_ref = self.x_ref.copy()
        self.capacity = int(need * DEM_GROWTH_FACTOR) + 1
        self.__post_init__()
        self.counters[:] = counters
        self.x_ref[:] = x_ref
        for name, values in keep.items():
            getattr(self, name)[:old] = values
