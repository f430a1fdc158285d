"""Named array layouts the kernels take: no index number carries physics.

Each layout is a :class:`typing.NamedTuple`, which numba compiles as a tuple whose fields are read
by name (``sph.inv_mass``, ``nb.part_slot``). :mod:`dem.engine.state` builds them from its
dataclasses (``as_layout``); shapes and units are documented there. n spheres, B bodies, ``cap``
pair capacity, ``width`` the contact law's history width
(:data:`dem.kernels.contact.HISTORY_WIDTH`), N_WALLS = 4 walls per sphere
(:mod:`dem.kernels.forces`).
"""

import math
from typing import NamedTuple

import numpy as np


class SphereArrays(NamedTuple):
    """Per-sphere state (:class:`dem.engine.state.Spheres`)."""

    x: np.ndarray  # (n, 3) positions, m
    v: np.ndarray  # (n, 3) velocities, m/s
    omega: np.ndarray  # (n, 3) angular velocities, rad/s
    force: np.ndarray  # (n, 3) forces, N
    torque: np.ndarray  # (n, 3) torques, N m
    radius: np.ndarray  # (n,) m
    mass: np.ndarray  # (n,) kg (a clump member carries its clump's mass)
    inv_mass: np.ndarray  # (n,) 1/kg
    inv_inertia: np.ndarray  # (n,) 1/(kg m^2)
    wall_hist: np.ndarray  # (N_WALLS n, width) wall contacts' history, row N_WALLS i + w


class BodyArrays(NamedTuple):
    """Rigid clumps and their members (:class:`dem.engine.state.Bodies`)."""

    x: np.ndarray  # (B, 3) centres of mass, m
    v: np.ndarray  # (B, 3) centre-of-mass velocities, m/s
    q: np.ndarray  # (B, 4) orientation quaternions (w, x, y, z)
    ang_mom: np.ndarray  # (B, 3) angular momenta, trough frame, kg m^2/s
    inv_mass: np.ndarray  # (B,) 1/kg
    mass: np.ndarray  # (B,) kg
    moments: np.ndarray  # (B, 3) principal moments, kg m^2
    force: np.ndarray  # (B, 3) total forces, N
    torque: np.ndarray  # (B, 3) torques about the centre of mass, N m
    omega: np.ndarray  # (B, 3) angular velocities, rad/s
    start: np.ndarray  # (B + 1,) int64 CSR start of each body's members
    members: np.ndarray  # (n,) int64 member sphere indices, body by body
    offsets: np.ndarray  # (n, 3) member offsets in the body frame, m
    body_of: np.ndarray  # (n,) int64 body of each sphere


class PairArrays(NamedTuple):
    """Verlet pair list with contact history, cell work arrays and CSR index (PairList)."""

    x_ref: np.ndarray  # (n, 3) positions at the last build, m
    pair_i: np.ndarray  # (cap,) int64 first sphere of each pair
    pair_j: np.ndarray  # (cap,) int64 second sphere
    hist: np.ndarray  # (cap, width) contact history per pair (tangential spring first, m)
    scratch_j: np.ndarray  # build scratch: partners, int32 (n slots,)
    scratch_hist: np.ndarray  # build scratch: carried history
    counts: np.ndarray  # per-sphere pair counts
    offsets: np.ndarray  # per-sphere pair offsets
    cell_of: np.ndarray  # (n,) cell of each sphere
    cell_start: np.ndarray  # CSR start per cell
    cell_particles: np.ndarray  # spheres, cell by cell
    part_start: np.ndarray  # (n + 1,) CSR start of each sphere's pairs
    part_slot: np.ndarray  # (2 cap,) int64 CSR slot of pair k's end i (2 k) and end j (2 k + 1)
    inbox: np.ndarray  # (2 cap, 6) force and torque of each pair end by CSR slot, N and N m


class MeshArrays(NamedTuple):
    """A trough mesh and its contact slots (:class:`~dem.scene.mesh.TriangleMesh`); None: flat."""

    tri: np.ndarray  # (T, 3, 3) triangle corners, m
    grid: np.ndarray  # (5,) index origin (3), cell edge, period along x (0: none), m
    dims: np.ndarray  # (3,) int64 cells along x, y, z
    cell_start: np.ndarray  # CSR start of each cell's triangles
    cell_tris: np.ndarray  # triangles, cell by cell
    slot_hist: np.ndarray  # (MESH_SLOTS n, width) mesh contacts' history (spring first, m)
    slot_normal: np.ndarray  # (MESH_SLOTS n, 3) normal of each slot's last contact


class Geometry(NamedTuple):
    """The periodic section and the step (:class:`dem.engine.simulation.Simulation`)."""

    length: float  # period along x, m
    width: float  # distance between the side walls, m
    skin: float  # Verlet skin, m
    dt: float  # time step, s
    back: float = -math.inf  # x of a finite feeder's back wall (inward normal +x), m; -inf: none
