"""Building a :class:`~dem.engine.simulation.Simulation` from a case: grains, trough, law, step.

:func:`from_case` fills the case's trough at random (:func:`dem.scene.fill.fill`);
:func:`from_grains` places the case's grain at chosen poses and velocities (virtual impacts,
validation studies). Both take a :class:`dem.scene.resolved.Scene` (the case resolved once: grain,
law, step, trough) or a case, which they resolve at the door. The time step is
:func:`dem.scene.timestep.timestep_for`'s, which depends on the case alone.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from dem.engine.simulation import Simulation
from dem.engine.state import Bodies, Spheres
from dem.kernels.rigid import quat_to_matrix
from dem.scene import fill
from dem.scene.mesh import TriangleMesh
from dem.scene.resolved import resolve
from dem.scene.timestep import impact_speed_for, timestep_for
from dem.scene.trough import Trough


def from_case(case, *, timestep: float | None = None, check_limit: bool = True) -> Simulation:
    """The case's trough filled with its grains (seeded), ready to settle and drive.

    ``case`` is a :class:`dem.scene.resolved.Scene`, or a :class:`dem.scene.case.Case` resolved here
    (:func:`dem.scene.resolved.resolve` with ``timestep`` and ``check_limit``).

    Spheres: :func:`dem.scene.fill.random_fill`; of several types or sizes
    (``particles.types``): :func:`dem.scene.fill.fill_types`, each sphere with its radius and
    density, and ``Simulation.grain_type`` its type. Screws and clumps: N copies of the case's grain
    template at random positions and orientations without member overlap
    (:func:`dem.scene.fill.random_fill_clumps`). The time step is the scene's
    (:func:`dem.scene.timestep.timestep_for`, impact from the top of the fill box; ``check_limit``
    as there); the instability check's speed scale takes the box as it was finally drawn.
    """
    scene = resolve(case, timestep=timestep, check_limit=check_limit)
    if scene.case.particles.types:  # spheres of several types or sizes
        positions, radii, densities, kind, height = fill.fill_types(scene.case)
        sim = _build(scene, positions, None, None, scene.step,
                     impact_speed_for(scene.case, height), sizes=(radii, densities))  # fmt: skip
        sim.grain_type = kind
        return sim
    positions, quats, height = fill.fill(scene.case)
    return _build(scene, positions, quats, None, scene.step, impact_speed_for(scene.case, height))


def from_grains(
    case,
    positions: np.ndarray,
    *,
    orientations: np.ndarray | None = None,
    velocities: np.ndarray | None = None,
    spins: np.ndarray | None = None,
    timestep: float | None = None,
    impact_speed: float | None = None,
    radii: np.ndarray | None = None,
    densities: np.ndarray | None = None,
) -> Simulation:
    """The case's grains at chosen poses and velocities (the case's count is not used).

    Args:
        case: A :class:`dem.scene.resolved.Scene`, or a :class:`dem.scene.case.Case` (contact,
        material,
            grain, trough, drive, run) resolved here.
        positions: Centres (spheres) or centres of mass (clumps), trough frame, (G, 3), m.
        orientations: Clumps: unit quaternions (w, x, y, z) body -> trough frame, (G, 4);
            default the template's principal axes along the trough axes.
        velocities: Centre-of-mass velocities relative to the trough, (G, 3), m/s; default 0.
        spins: Angular velocities omega, trough frame, (G, 3), rad/s; default 0. A clump's
            angular momentum is set to L = R (I * (R^T omega)), with R its rotation matrix and
            I its principal moments of inertia, kg m^2. Needs ``particles.rotation`` on
            (ValueError otherwise).
        timestep: dt, s; default ``case.run.timestep``, else automatic.
        impact_speed: Speed of the hardest impact expected, m/s, for the automatic step and
            the instability check; default the drive speed plus the fastest grain plus a
            fall from the highest grain.
        radii: Spheres only: each sphere's radius, (G,), m; default ``particles.radius``.
        densities: Spheres only: each sphere's density, (G,), kg/m^3; default
            ``material.density``. With ``radii``, spheres of several sizes and materials (a
            collision of two different spheres); the contact law stays the case's (one E and
            nu: :func:`dem.kernels.contact.equivalent_material` gives the pair's).

    The time step follows :func:`dem.scene.timestep.timestep_for` with these grains' count and
    impact speed (with ``radii`` or ``densities``: the smallest over the kinds of sphere); a
    given step above the stability limit raises InputError naming ``run.timestep``.

    """
    # the scene's own step is the fill's, not these grains': theirs is taken (and checked) below
    scene = resolve(case, check_limit=False)
    case = scene.case
    positions = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3)
    n = positions.shape[0]
    if velocities is None:
        velocities = np.zeros((n, 3))
    velocities = np.asarray(velocities, dtype=np.float64).reshape(n, 3)
    if impact_speed is None:
        top = float(np.max(positions[:, 2])) if n else 0.0
        fastest = float(np.max(np.linalg.norm(velocities, axis=1))) if n else 0.0
        impact_speed = impact_speed_for(case, top, fastest)
    sizes = None
    if radii is not None or densities is not None:
        if case.particles.clumps:
            raise ValueError("radii and densities are for spheres: a clump's are its template's")
        pt, mat = case.particles, case.material
        radii = np.broadcast_to(np.asarray(pt.radius if radii is None else radii, float), (n,))
        densities = np.broadcast_to(
            np.asarray(mat.density if densities is None else densities, float), (n,)
        )
        sizes = (radii.copy(), densities.copy())
        steps = [
            timestep_for(
                replace(case, particles=replace(pt, radius=float(r)),
                        material=replace(mat, density=float(rho))),
                timestep=timestep, impact_speed=impact_speed, grains=n, law=scene.law,
            )
            for r, rho in sorted(set(zip(sizes[0].tolist(), sizes[1].tolist(), strict=True)))
        ]  # fmt: skip
        step = min(steps, key=lambda s: (s.dt, s.limit))
        step = step._replace(limit=min(s.limit for s in steps), auto=min(s.auto for s in steps))
    else:
        step = timestep_for(
            case, timestep=timestep, impact_speed=impact_speed, grains=n, law=scene.law
        )
    if spins is not None:
        if not case.particles.rotation:
            raise ValueError("spins need particles.rotation = true: the grains cannot turn")
        spins = np.asarray(spins, dtype=np.float64).reshape(n, 3)
    return _build(scene, positions, orientations, velocities, step, impact_speed, spins, sizes)


def _build(
    scene, positions, orientations, velocities, step, reference_speed, spins=None, sizes=None
) -> Simulation:
    case = scene.case
    pt, mat = case.particles, case.material
    n = positions.shape[0]
    bodies = None
    if not pt.clumps:
        radius, density = (pt.radius, mat.density) if sizes is None else sizes
        spheres = Spheres.create(positions, radius, density)
        if velocities is not None:
            spheres.v[:] = velocities
        if spins is not None:
            spheres.omega[:] = spins
    else:
        if orientations is None:
            orientations = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
        quats = np.ascontiguousarray(orientations, dtype=np.float64).reshape(n, 4)
        bodies, spheres = Bodies.create(scene.grain, positions, quats)
        if velocities is not None:
            bodies.v[:] = velocities
        if spins is not None:
            for i in range(n):
                r = quat_to_matrix(bodies.q[i])
                bodies.ang_mom[i] = r @ (bodies.moments[i] * (r.T @ spins[i]))
        bodies.place(spheres)
    trough = scene.trough
    mesh = trough_mesh(case)
    feeder = None
    if case.feeder is not None:
        trough, feeder = _finite(scene, trough, mesh, step.dt, reference_speed)
        if mesh is not None:
            mesh = TriangleMesh(mesh.tri, period=trough.length, source=mesh.source)
            lo = float(mesh.tri[..., 2].min())
            feeder.floor = lo
            feeder.inside = lambda p, r: fill.inside_mesh(mesh, p, float(np.max(r)))
    return Simulation(
        spheres, trough, scene.law, step.dt,
        rotation=pt.rotation, reference_speed=reference_speed, bodies=bodies,
        timestep_limit=step.limit, mesh=mesh, feeder=feeder, device=case.run.device,
    )  # fmt: skip


def _finite(scene, trough: Trough, mesh, dt: float, reference_speed: float):
    """The finite feeder's periodic domain (the trough and an empty gap) and its Feeder."""
    from dem import config
    from dem.engine.feeder import EXCHANGE_FRACTION, Feeder, domain_gap, grain_factory

    case = scene.case
    bound, r_max = scene.grain.bounding_radius, scene.max_radius
    interval = max(1, int(round(EXCHANGE_FRACTION * trough.period / dt)))
    travel = config.DEM_MAX_SPEED_FACTOR * reference_speed * interval * dt
    skin = config.DEM_SKIN_FRACTION * r_max
    length = case.trough.length
    domain = length + domain_gap(bound, r_max, skin, travel)
    width = trough.width
    if mesh is not None:
        width = float(np.ptp(mesh.tri[..., 1]))
    feeder = Feeder(
        discharge=length, width=width, feed_rate=case.feeder.feed_rate,
        feed_length=case.feeder.feed_length, grain_mass=scene.grain_mass, bound=bound,
        interval=interval, make=grain_factory(case),
        random=np.random.default_rng([case.run.seed, 0xFEED]),
    )  # fmt: skip
    return replace(trough, length=domain, discharge=length), feeder


def trough_mesh(case):
    """The case's trough mesh (:class:`dem.scene.mesh.TriangleMesh`), or None for flat walls."""
    if case.trough.mesh is None:
        return None
    from dem.scene.mesh import load_mesh

    return load_mesh(case.trough.mesh, length=case.trough.length)
