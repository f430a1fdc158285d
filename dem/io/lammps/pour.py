"""LAMMPS's own fill for a LAMMPS deck (``dem export lammps --fill lammps``): pour, then rest.

Instead of starting from dem's settled fill (``data.fill``), the deck makes its own: it creates
the empty box, pours ``particles.count`` grains into it with ``fix pour`` and lets them come to
rest with the drive off, all inside LAMMPS, so a bed of a million grains needs no fill on the
machine that writes the deck. The stages, in the deck's order:

1. Pour (``fix pour``, drive off, gravity along -z, which fix pour requires at every ``run``):
   the grains are inserted batch by batch into a block above the future bed, clear of the
   walls, as tall as dem's own fill box (:class:`PourGeometry`); each grain at a random place (seed
   ``run.seed``), a clump also with a random orientation. Spheres take the case's one diameter
   and density (``diam one``, ``dens``; dem's spheres have one size). A clump is the molecule
   template :data:`MOLECULE_NAME`, written from dem's grain: the members in the body frame (the
   centre of mass at the origin, the principal axes along x, y, z) and the header's ``mass``,
   ``com`` and ``inertia`` set to dem's exact mass, centre and principal moments of the union
   (overlaps counted once). ``fix pour ... mol ... rigid`` hands these to ``fix rigid/small``
   (``FixRigidSmall::set_molecule`` takes the template's ``masstotal``, ``com`` and
   ``inertia``); ``reinit no`` keeps a later ``run`` from recomputing each body from its
   members (``setup_bodies_static``, which would sum the overlapping spheres).
2. Rest: the run stops (``fix halt ... error continue``) at the first check, every
   :data:`REST_CHECK_TIME` (dem's settle chunk), at which all grains are in and
   the rms speed of the spheres (members for clumps) is below
   ``DEM_SETTLE_SPEED_FRACTION sqrt(g r)``, dem's own criterion
   (:meth:`dem.engine.simulation.Simulation.settle`); if the step cap (a fall through the box
   for each batch and one more, plus ``DEM_SETTLE_MAX_TIME``) comes first, the deck stops with
   exit status 3 and says so. On
   an inclined trough the pour is removed, gravity turns to the trough's static gravity and the
   same rest test runs again (cap ``DEM_SETTLE_MAX_TIME``).
3. ``reset_timestep 0``: the drive's clock and ``vx_mean.txt`` count from the drive's start, as
   in the deck from dem's fill.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dem import __version__
from dem.config import DEM_SETTLE_MAX_TIME, DEM_SETTLE_SPEED_FRACTION, GRAVITY
from dem.errors import InputError
from dem.io.files import write_input
from dem.io.liggghts.drive import gravity_block
from dem.io.liggghts.text import fmt
from dem.scene.fill import clump_box_height, sphere_box_height
from dem.scene.resolved import Scene

#: How an exported deck gets its grains (``--fill``): dem's settled fill or LAMMPS's own pour.
FILLS = ("dem", "lammps")
#: The clump template for ``fix pour ... mol`` (``--fill lammps``).
MOLECULE_NAME = "grain.mol"
#: Peak volume fraction (in fix pour's spheres) of a pour batch near the block's top; denser,
#: pour's random insertion leaves grains out and retries them a batch later.
POUR_PEAK_FRACTION = 0.15
#: Insertion tries per grain (``fix pour ... vol`` second value).
POUR_TRIES = 200
#: Simulated time between two rest checks, s (dem's settle chunk).
REST_CHECK_TIME = 0.005
#: Exit status of a deck whose fill did not come to rest within its step cap.
NOT_AT_REST_STATUS = 3


def molecule_radius(scene: Scene) -> float:
    """The grain's radius for fix pour, m: the farthest member surface from the members' mean.

    ``Molecule::compute_center`` takes the mean of the member centres as the grain's centre and
    ``molradius`` as this distance; pour keeps it clear of the pour block's faces.
    """
    g = scene.grain
    centre = g.centres.mean(axis=0)
    return float(np.max(np.linalg.norm(g.centres - centre, axis=1) + g.radii))


def write_molecule(path: Path, scene: Scene) -> Path:
    """The clump as a LAMMPS molecule template, with dem's exact mass, centre and inertia.

    Coordinates are dem's body frame (centre of mass at the origin, principal axes along x, y,
    z), so the header's centre is the origin and its inertia tensor diag(moments). The members'
    masses are the density times each sphere's own volume (their sum counts the overlaps twice);
    they only fill the per-atom mass, which nothing reads once the header sets the body (fix
    rigid/small ``reinit no``; gravity acts on the body's mass, contacts take it as m*).
    """
    g = scene.grain
    k = g.count

    def row(*values) -> str:
        return " ".join(repr(float(u)) for u in values)

    lines = [
        f"dem {__version__}: one {g.name} of case {scene.case.name} (SI units, body frame)",
        "",
        f"{k} atoms",
        f"{g.mass!r} mass",
        "0.0 0.0 0.0 com",
        f"{row(*g.moments, 0.0, 0.0, 0.0)} inertia",
        "",
        "Coords",
        "",
        *(f"{i + 1} {row(*c)}" for i, c in enumerate(g.centres)),
        "",
        "Types",
        "",
        *(f"{i + 1} 1" for i in range(k)),
        "",
        "Diameters",
        "",
        *(f"{i + 1} {row(2.0 * r)}" for i, r in enumerate(g.radii)),
        "",
        "Masses",
        "",
        *(f"{i + 1} {row(g.density * 4.0 / 3.0 * math.pi * r**3)}" for i, r in enumerate(g.radii)),
    ]
    return write_input(path, lines, key="OUT_DIR")


def refuse_unpourable(scene: Scene) -> None:
    """Raise :class:`InputError` where fix pour has no room or no block yet.

    No room: a trough narrower than a grain; no block: a mesh pan.

    fix pour keeps a grain's centre ``molecule_radius`` (a sphere's radius) from each side wall.
    """
    case = scene.case
    if case.particles.types:
        key = "types" if len(case.particles.types) > 1 else "radius_distribution"
        raise InputError(
            f"particles.{key}", f"{len(case.particles.types)} grain types",
            "one sphere size for --fill lammps (fix pour takes one diameter here; --fill dem "
            "exports dem's own fill, every sphere with its diameter and density)",
        )  # fmt: skip
    if case.trough.mesh is not None:
        raise InputError(
            "trough.mesh", Path(case.trough.mesh).name,
            "none for --fill lammps (the pour block above a mesh pan is not written yet; "
            "--fill dem exports the pan from dem's own fill)",
        )  # fmt: skip
    clearance = molecule_radius(scene) if case.particles.clumps else float(case.particles.reach)
    if case.trough.width <= 2.002 * clearance:
        raise InputError(
            "trough.width", case.trough.width,
            f"over {2.002 * clearance:.4g} m for --fill lammps (fix pour keeps each grain's "
            f"centre {clearance:.4g} m from the side walls)",
        )  # fmt: skip


class PourGeometry:
    """Where the grains are poured, m: the block (x, y, z bounds), the box's top, pour's ``vol``.

    The block spans the periodic length, stays ``clearance`` (fix pour's grain radius) from the
    side walls, starts above the settled bed (dem's bed height: the grains' volume at packing
    0.6 for spheres, 0.3 for clumps, over the floor) and is as tall as dem's own fill box
    (:func:`dem.scene.fill.sphere_box_height`, :func:`~dem.scene.fill.clump_box_height`). fix
    pour draws each grain's height h = top - u^2 (top - bottom), u uniform, so that grains
    arrive evenly in time: their density near the top is sqrt(height / (2 clearance)) times
    the mean. ``vol`` (pour's fraction of the block, in spheres of radius ``clearance``) keeps
    that peak at :data:`POUR_PEAK_FRACTION`, where random insertion still finds room; pour then
    inserts ``batches`` batches, one each fall through the block, above the growing bed.
    """

    def __init__(self, scene: Scene):
        case = scene.case
        t = case.trough
        pt = case.particles
        n = pt.count
        self.clearance = molecule_radius(scene) if pt.clumps else float(pt.reach)
        c = 1.001 * self.clearance
        self.x = (0.0, float(t.length))
        self.y = (-0.5 * t.width + c, 0.5 * t.width - c)
        width = self.y[1] - self.y[0]
        if pt.clumps:
            height = clump_box_height(n, scene.grain, t.length, width)
            bed = n * scene.grain.volume / (0.3 * t.length * width)
        else:
            assert pt.radius is not None  # one sphere size
            height = sphere_box_height(n, pt.radius, t.length, width)
            bed = n * 4.0 / 3.0 * math.pi * pt.radius**3 / (0.6 * t.length * width)
        self.z = (c + bed, c + bed + height)
        self.top = self.z[1] + c
        one = 4.0 / 3.0 * math.pi * self.clearance**3
        filled = (n + 1) * one / (t.length * width * height)
        self.vol = min(filled, POUR_PEAK_FRACTION / math.sqrt(height / (2.0 * c)))
        self.batches = math.ceil(filled / self.vol)

    def fall_time(self) -> float:
        """Time to fall from the block's top to the floor, s."""
        return math.sqrt(2.0 * self.top / GRAVITY)


def header_lines(scene: Scene, geometry: PourGeometry, timestep: float) -> list[str]:
    """The deck's header comments on the fill: how the grains go in and when they rest."""
    pt = scene.case.particles
    chunk = max(1, round(REST_CHECK_TIME / timestep))
    how = (
        f"the molecule template {MOLECULE_NAME} (dem's exact mass, centre and inertia of the "
        "union; fix rigid/small reinit no keeps them)"
        if pt.clumps
        else f"diameter {fmt(2.0 * pt.reach)} m, density {fmt(scene.case.material.density)} kg/m^3"
    )
    (z0, z1) = geometry.z
    return [
        f"# fill: LAMMPS pours the {pt.count} grains (fix pour, seed {scene.case.run.seed}, about "
        f"{geometry.batches} batches at random places and orientations, gravity -z) into the "
        f"block z = {z0:.4g} to {z1:.4g} m clear of the walls by {geometry.clearance:.4g} m; {how}",
        f"# rest: the drive off, until every grain is in and the rms sphere speed is below "
        f"{rest_threshold(scene):.4g} m/s (dem's settle criterion), checked every {chunk} steps "
        f"(fix halt); past the step cap the deck quits with status {NOT_AT_REST_STATUS}; then "
        "reset_timestep 0 starts the drive's clock",
    ]


def rest_threshold(scene: Scene) -> float:
    """The rest speed of dem's settle, m/s: DEM_SETTLE_SPEED_FRACTION sqrt(g r), r mean radius."""
    return DEM_SETTLE_SPEED_FRACTION * math.sqrt(GRAVITY * float(np.mean(scene.grain.radii)))


def box_lines(scene: Scene, geometry: PourGeometry, r_max: float) -> list[str]:
    """The empty box: x over the section, y to the side walls plus a radius, z to above the pour."""
    t = scene.case.trough
    lo, hi = -0.5 * t.width - r_max, 0.5 * t.width + r_max
    return [
        f"region box block 0.0 {fmt(t.length)} {fmt(lo)} {fmt(hi)} 0.0 {fmt(geometry.top)}",
        "create_box 1 box",
    ]


def pour_lines(scene: Scene, geometry: PourGeometry, timestep: float, group: str) -> list[str]:
    """Gravity along -z, the pour, and the run that ends when the grains rest (or fails)."""
    case = scene.case
    pt = case.particles
    n = pt.count
    atoms = n * pt.spheres_per_grain
    (x0, x1), (y0, y1), (z0, z1) = geometry.x, geometry.y, geometry.z
    seed = case.run.seed
    if pt.clumps:
        what = "mol grain rigid integrate"
        ntype = 0  # the template's types, offset by 0
    else:
        assert pt.radius is not None  # one sphere size
        d, rho = 2.0 * pt.radius, case.material.density
        what = f"diam one {fmt(d)} dens {fmt(rho)} {fmt(rho)}"
        ntype = 1
    chunk = max(1, round(REST_CHECK_TIME / timestep))
    pour_time = (geometry.batches + 1) * geometry.fall_time()
    cap = chunk * math.ceil((pour_time + DEM_SETTLE_MAX_TIME) / timestep / chunk)
    g = GRAVITY
    return [
        "# --- fill: pour (fix pour needs gravity along -z), then rest with the drive off",
        f"fix grav {group} gravity {fmt(g)} vector 0.0 0.0 -1.0",
        f"region pour block {fmt(x0)} {fmt(x1)} {fmt(y0)} {fmt(y1)} {fmt(z0)} {fmt(z1)}",
        f"fix pour all pour {n} {ntype} {seed} region pour {what} vol {fmt(geometry.vol)} "
        f"{POUR_TRIES}",
        *rest_lines(scene, atoms, chunk),
        f"run {cap}",
        *rest_check(f"{n} grains poured did not rest within {cap} steps"),
        "unfix pour",
    ]


def rest_lines(scene: Scene, atoms: int, chunk: int) -> list[str]:
    """The rest test: all atoms in and rms speed below dem's threshold, checked every chunk."""
    return [
        f"# rest: all {atoms} spheres in and their rms speed < {fmt(rest_threshold(scene))} m/s "
        f"(dem's settle criterion), checked every {chunk} steps",
        "variable speed2 atom vx*vx+vy*vy+vz*vz",
        "compute speed2 all reduce ave v_speed2",
        "variable rms equal sqrt(c_speed2)",
        f"variable rest equal (atoms=={atoms})*(v_rms<{fmt(rest_threshold(scene))})",
        f"fix rest all halt {chunk} v_rest > 0.5 error continue",
        f"thermo {chunk}",
        "thermo_style custom step time atoms v_rms v_rest cpu",
        "thermo_modify lost error norm no",
    ]


def rest_check(message: str) -> list[str]:
    """Stop the deck with :data:`NOT_AT_REST_STATUS` unless the last rest test passed."""
    return [
        f'if "${{rest}} < 0.5" then "print \'ERROR: {message} (rms speed ${{rms}} m/s)\'" '
        f'"quit {NOT_AT_REST_STATUS}"',
    ]


def tilt_lines(scene: Scene, timestep: float, group: str, gx0: float, gz0: float) -> list[str]:
    """An inclined trough: its static gravity, and rest again (capped at DEM_SETTLE_MAX_TIME)."""
    chunk = max(1, round(REST_CHECK_TIME / timestep))
    cap = chunk * math.ceil(DEM_SETTLE_MAX_TIME / timestep / chunk)
    return [
        "# the trough's static gravity (inclined), and rest again",
        "unfix grav",
        *gravity_block(gx0, gz0, group),
        f"run {cap}",
        *rest_check(f"the fill did not rest within {cap} steps on the inclined trough"),
    ]


def fill_lines(scene: Scene, timestep: float, group: str, gx0: float, gz0: float,
               geometry: PourGeometry) -> list[str]:  # fmt: skip
    """Pour, rest, (tilt and rest,) then clear the fill's fixes and restart the step count."""
    lines = pour_lines(scene, geometry, timestep, group)
    if gx0 != 0.0:
        lines += tilt_lines(scene, timestep, group, gx0, gz0)
    else:  # gravity is already the trough's: (0, 0, -g)
        lines.append("# the trough is level: its static gravity is the pour's")
    return [
        *lines,
        "unfix rest",
        "uncompute speed2",
        "reset_timestep 0",
    ]
