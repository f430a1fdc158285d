"""A case resolved once: the grain, the contact law, the time step and the trough.

:func:`resolve` turns a :class:`dem.scene.case.Case` into a :class:`Scene`, and the consumers
(:mod:`dem.engine.setup`, :mod:`dem.run.runner`, :mod:`dem.run.plan`, :mod:`dem.io.liggghts`,
:mod:`dem.studies.calibrate`, ``dem export``) take the scene instead of deriving these again. A case
changed after loading (another count, another tangential stiffness) is resolved anew.

The trough mesh is not part of a scene: a :class:`dem.scene.mesh.TriangleMesh` is mutable (the fill
and the simulation each re-index it for their own reach), so every simulation loads its own
(:func:`dem.engine.setup.trough_mesh`) and a scene stays immutable and shareable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from dem.errors import InputError
from dem.physics.contact import ContactLaw
from dem.physics.mass import sphere_mass
from dem.scene import shapes
from dem.scene.timestep import Timestep, timestep_for
from dem.scene.trough import Trough

if TYPE_CHECKING:
    from dem.scene.case import Case


@dataclass(frozen=True)
class Scene:
    """A case resolved once: the grain, the contact law, the time step and the trough.

    Every consumer takes these from here; nobody rebuilds them.

    Attributes:
        case: The :class:`dem.scene.case.Case` it was resolved from.
        grain: The grain as a :class:`dem.scene.shapes.Template`: the one-sphere template
            (:func:`dem.scene.shapes.sphere`) of radius R and density rho for spheres (of
            several types or sizes: the mean grain, the sphere of their mean volume at their
            density by volume), the case's template for screws and clumps.
        law: The contact law in kernel form (:meth:`dem.physics.contact.ContactLaw.from_case`).
        step: The time step of the case's fill (:func:`dem.scene.timestep.timestep_for` with
        ``law``):
            dt, automatic step and stability limit, s, and the impact speed, m/s.
        trough: The trough's geometry and drive (:meth:`dem.scene.trough.Trough.from_case`).

    """

    case: Case
    grain: shapes.Template
    law: ContactLaw
    step: Timestep
    trough: Trough

    @property
    def grain_mass(self) -> float:
        """Mass of one grain, kg.

        A sphere: rho 4/3 pi R^3 (:func:`dem.physics.mass.sphere_mass`, as
        :meth:`dem.engine.state.Spheres.create` gives each sphere; the one-sphere template's
        rho V equals it to rounding); a clump: its template's mass.
        """
        pt = self.case.particles
        if pt.types:
            from dem.scene.sizes import mean_mass

            return mean_mass(pt.types)
        if not pt.clumps:
            return sphere_mass(self.case.material.density, pt.radius)
        return float(self.grain.mass)

    @property
    def max_radius(self) -> float:
        """Largest member sphere radius of the grain, m (a sphere's; of several, the largest)."""
        if self.case.particles.types:
            assert self.case.particles.radius is not None  # the largest radius of the types
            return float(self.case.particles.radius)
        return float(np.max(self.grain.radii))


def resolve(case, *, timestep: float | None = None, check_limit: bool = True) -> Scene:
    """Resolve a case into a :class:`Scene`, building its contact law exactly once.

    Args:
        case: A :class:`dem.scene.case.Case`; a :class:`Scene` passes through as it was resolved
            (with ``timestep`` given: its step taken again with that dt, its law kept).
        timestep: dt, s; default ``case.run.timestep``, else automatic.
        check_limit: As :func:`dem.scene.timestep.timestep_for`: False lets a given step exceed the
            stability limit.

    Raises:
        InputError: A clump case without its template (not read by
        :func:`dem.scene.case.load_case`),
            or a given step above the stability limit (``check_limit``).

    """
    if isinstance(case, Scene):
        if timestep is None:
            return case
        step = timestep_for(case.case, timestep=timestep, check_limit=check_limit, law=case.law)
        return replace(case, step=step)
    check_buildable(case)
    pt = case.particles
    if pt.types:  # the mean grain: the sphere of the mean volume, at the bed's density
        from dem.scene.sizes import mean_volume

        radius = (3.0 * mean_volume(pt.types) / (4.0 * math.pi)) ** (1.0 / 3.0)
        grain = shapes.sphere(radius, case.material.density)
    else:
        grain = pt.grain if pt.clumps else shapes.sphere(pt.radius, case.material.density)
    law = case.law  # built at load_case's time-step check
    step = timestep_for(case, timestep=timestep, check_limit=check_limit, law=law)
    return Scene(case=case, grain=grain, law=law, step=step, trough=Trough.from_case(case))


def check_buildable(case) -> None:
    """Refuse what the engine cannot build (a grain without its template)."""
    pt = case.particles
    if pt.clumps and pt.grain is None:
        raise InputError("particles.shape", pt.shape, "a case read by dem.scene.case.load_case")
