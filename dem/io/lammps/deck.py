"""Export a case as a LAMMPS input deck (``pair_style granular``), block by block.

The deck simulates the same periodic trough section as ``dem run``, in the trough's accelerating
frame: the walls stay still and every grain feels the effective gravity of the LIGGGHTS deck
(:mod:`dem.io.liggghts.drive`: ``fix gravity`` with equal-style variables, whose syntax LAMMPS
shares). It starts from dem's own fill, settled by dem with the drive off
(:func:`dem.engine.setup.from_case` and :meth:`~dem.engine.simulation.Simulation.settle`), written
as ``data.fill``; so both engines start from the same packing (LAMMPS starts without the fill's
tangential springs, which a data file cannot carry). Then it runs two stages, each its own
``run``: settle (``settle_steps`` driven steps, not measured) and measure (``steps``). With
``fill="lammps"`` the deck instead creates the empty box and makes its own fill, poured and
settled by LAMMPS before those stages (:mod:`dem.io.lammps.pour`). The mean
x-velocity of the grains is written every step to ``vx_mean.txt`` (step, m/s), from which
:mod:`dem.io.lammps.launcher` takes per-cycle means on dem's own cycle edges.

Geometry: x periodic over the section length, flat side walls y = -+width/2 and the floor z = 0
(``fix wall/gran granular``, the grain-wall law of :mod:`dem.io.lammps.contact`), or a mesh pan as
the intersection of its face planes (``fix wall/gran/region``, :mod:`dem.io.lammps.walls`), the top
open (``boundary p f fm``). Spheres are integrated by ``fix nve/sphere`` (``fix nve`` with rotation
locked, the spins staying zero). Screws and clumps are rigid bodies of ``fix rigid/small molecule``:
each member carries its body's number (``fix property/atom mol``), each body its exact mass, centre
of mass, inertia tensor and motion from dem (``bodies.rigid``, the ``infile``; LAMMPS would
otherwise sum the overlapping members), gravity and the drive act on the body's mass at its centre
(the fix's ``gravity`` keyword), a member's contacts take the body's mass as m* (as in dem), members
of one body do not touch (``neigh_modify exclude molecule/intra``), and the mean x-velocity is that
of the bodies' centres (``compute rigid/local``).

Refused, with the reason (:class:`dem.errors.InputError`): what the contact mapping refuses,
clumps with rotation locked (``fix rigid/small`` has no such switch), meshes that are not a
convex pan extruded along x (LAMMPS's GRANULAR package has no triangle-mesh wall) and finite
feeders (no feed and discharge yet).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dem import __version__
from dem.errors import InputError
from dem.io.files import write_input
from dem.io.lammps import pour
from dem.io.lammps.contact import contact_models, convention_notes
from dem.io.lammps.walls import Pan, flat_wall_lines, pan_planes, pan_wall_lines
from dem.io.liggghts.drive import drive_block, gravity_block, static_gravity
from dem.io.liggghts.text import fmt
from dem.scene.resolved import Scene

#: LAMMPS version the decks are written for and checked against.
LAMMPS_VERSION = "LAMMPS 22 Jul 2025 (GRANULAR)"
#: File name of the deck inside the output directory.
DECK_NAME = "in.lammps"
#: dem's settled fill, as a LAMMPS data file (atom_style sphere).
DATA_NAME = "data.fill"
#: File the deck writes the grains' mean x-velocity to every step (columns: step, m/s).
VX_FILE = "vx_mean.txt"
#: Neighbour skin as a fraction of the largest radius (dem's own skin, :mod:`dem.engine`).
SKIN_FRACTION = 0.4
#: The clumps' exact mass, centre of mass, inertia and motion (``fix rigid/small ... infile``).
BODIES_NAME = "bodies.rigid"


def refuse_unsupported(scene: Scene) -> None:
    """Raise :class:`InputError` for what this exporter cannot write, before anything is run."""
    case = scene.case
    contact_models(scene)  # the law's refusals
    trough_pan(scene)  # a mesh that is not a convex extruded pan
    if case.feeder is not None:
        raise InputError(
            "feeder", "a [feeder] table",
            "a periodic section for a LAMMPS deck (the feed and the discharge are not written yet)",
        )  # fmt: skip
    if case.particles.clumps and not case.particles.rotation:
        raise InputError(
            "particles.rotation", False,
            "true for a LAMMPS deck of clumps (fix rigid/small cannot lock a body's rotation)",
        )  # fmt: skip


def trough_pan(scene: Scene) -> Pan | None:
    """The case's mesh pan as planes (:func:`dem.io.lammps.walls.pan_planes`), or None (flat)."""
    mesh = scene.case.trough.mesh
    if mesh is None:
        return None
    from dem.scene.mesh import load_mesh

    return pan_planes(load_mesh(mesh, length=scene.case.trough.length).tri, str(mesh))


def _velocity_lines(case) -> list[str]:
    """The spheres' mean x-velocity ``c_vxm``, mass-weighted, and one group per grain type.

    Spheres of several types or sizes (``particles.types``) have unequal masses: the mean of
    m vx / m_mean over the atoms is the mass-weighted mean (m_mean = mass(all) / count(all));
    each grain type is its atom type (:func:`write_data`) and gets a group named after it.
    """
    types = case.particles.types
    if not types:
        return [
            "# the grains' mean x-velocity (equal masses: the mass-weighted mean), every step",
            "compute vxm all reduce ave vx",
        ]
    return [
        "# grain types as atom types (dem's particles.types, in order): "
        + ", ".join(f"{k + 1} {t.name}" for k, t in enumerate(types)),
        *(f"group {t.name} type {k + 1}" for k, t in enumerate(types)),
        "# the grains' mass-weighted mean x-velocity (unequal masses), every step",
        "variable mmean equal (mass(all)+1e-30)/(count(all)+1e-30)",
        "variable wvx atom mass*vx/v_mmean",
        "compute vxm all reduce ave v_wvx",
    ]


def write_data(path: Path, scene: Scene, x: np.ndarray, v: np.ndarray, omega: np.ndarray,
               radius: np.ndarray, mass: np.ndarray, body=None, kind=None) -> Path:  # fmt: skip
    """Write the spheres as a LAMMPS data file (atom_style sphere): the box and every atom.

    Each atom carries its own diameter and density, so a fill of several sizes is written as
    it is; ``kind`` (n,) the grain type of each sphere from 0 (``particles.types``) makes it
    atom type ``kind + 1`` (None: all type 1).

    ``body`` (n,) numbers each clump member's body from 0 (a ``Molecules`` section, read by
    ``fix property/atom mol``); a member's x is its body's wrapped centre plus its offset, so
    LAMMPS remaps it into the box with the image flag that keeps the body whole.
    """
    trough = scene.trough
    n = len(x)
    r_max = float(radius.max())
    pan = trough_pan(scene)
    y_lo, y_hi = (
        (-0.5 * trough.width, 0.5 * trough.width) if pan is None else (pan.lo[1], pan.hi[1])
    )
    z_lo = 0.0 if pan is None else min(0.0, float(pan.lo[2]))
    top = max(float(x[:, 2].max()) + 4.0 * r_max, z_lo + 8.0 * r_max)
    density = mass / (4.0 / 3.0 * math.pi * radius**3)
    lines = [
        f"dem {__version__}: the settled fill of case {scene.case.name} (SI units, trough frame)",
        "",
        f"{n} atoms",
        f"{1 if kind is None else len(scene.case.particles.types)} atom types",
        "",
        f"0.0 {float(trough.length)!r} xlo xhi",
        f"{float(y_lo) - r_max!r} {float(y_hi) + r_max!r} ylo yhi",
        f"{z_lo!r} {top!r} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    xw = np.mod(x[:, 0], trough.length) if body is None else x[:, 0]

    def row(*values) -> str:
        return " ".join(repr(float(u)) for u in values)

    for i in range(n):
        t = 1 if kind is None else int(kind[i]) + 1
        lines.append(f"{i + 1} {t} {row(2.0 * radius[i], density[i], xw[i], x[i, 1], x[i, 2])}")
    lines += ["", "Velocities", ""]
    for i in range(n):
        lines.append(f"{i + 1} {row(*v[i], *omega[i])}")
    if body is not None:
        lines += ["", "Molecules", ""]
        lines += [f"{i + 1} {int(body[i]) + 1}" for i in range(n)]
    return write_input(path, lines, key="OUT_DIR")


def _extent(scene: Scene) -> float:
    """The largest distance of a grain's surface from its centre of mass, m."""
    g = scene.grain
    return float(np.max(np.linalg.norm(g.centres, axis=1) + g.radii))


def write_bodies(path: Path, bodies, inertia_space: np.ndarray, length: float) -> Path:
    """The clumps for ``fix rigid/small ... infile``: one line a body.

    molecule id, M, centre of mass (x wrapped into [0, length)), the inertia tensor about it in
    the trough's axes (Ixx Iyy Izz Ixy Ixz Iyz), the centre's velocity, the angular momentum and
    zero image flags. LAMMPS takes these instead of summing the member spheres (which would count
    their overlaps twice).
    """
    lines = [str(len(bodies.x))]
    for b in range(len(bodies.x)):
        i = inertia_space[b]
        values = [bodies.mass[b], np.mod(bodies.x[b, 0], length), bodies.x[b, 1], bodies.x[b, 2],
                  i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2], *bodies.v[b],
                  *bodies.ang_mom[b]]  # fmt: skip
        lines.append(f"{b + 1} " + " ".join(repr(float(u)) for u in values) + " 0 0 0")
    return write_input(path, lines, key="OUT_DIR")


def write_deck(scene: Scene, out: Path, *, timestep: float, steps: int, settle_steps: int,
               r_max: float, settle_note: str | None = None,
               fill: str = "dem") -> Path:  # fmt: skip
    """Write ``out/in.lammps`` for ``scene``.

    ``fill`` "dem": its fill already in ``out/data.fill`` (and ``bodies.rigid``); "lammps": the
    deck pours and settles its own (:mod:`dem.io.lammps.pour`; a clump's template in
    ``out/grain.mol``).
    """
    own = fill == "lammps"
    geometry = pour.PourGeometry(scene) if own else None
    case = scene.case
    pair, wall = contact_models(scene)
    d = case.drive
    gx0, gz0 = static_gravity(case.trough.inclination)
    pan = trough_pan(scene)
    mesh_name = "" if case.trough.mesh is None else Path(case.trough.mesh).name  # with a pan
    period_steps = 1.0 / (d.frequency * timestep)
    lines = [
        f"# LAMMPS deck of dem case {case.name}, written by dem {__version__} "
        f"(dem export lammps), for {LAMMPS_VERSION}",
        f"# run: lmp -in {DECK_NAME}   or on N ranks: mpirun -np N lmp -in {DECK_NAME}",
        f"# {case.particles.count} {case.particles.shape} grains "
        + (
            "poured and settled by LAMMPS (fix pour, see the fill stage)"
            if own
            else f"from dem's settled fill ({DATA_NAME})"
        )
        + "; drive "
        f"{d.frequency:g} Hz, {d.angle:g} deg, throw number {d.throw_number:.4g}; dt = "
        f"{timestep:.6g} s ({period_steps:.1f} steps a cycle); {settle_steps} settling and "
        f"{steps} measured driven steps",
    ]
    if settle_note:
        lines.append(f"# settle: {settle_note}")
    if geometry is not None:  # own fill
        lines += pour.header_lines(scene, geometry, timestep)
    lines.append("# contact law mapped from dem's (dem.io.lammps.contact):")
    lines += [f"#   grain-grain: {n}" for n in pair.notes]
    lines += [f"#   grain-wall: {n}" for n in wall.notes]
    lines += [f"#   NOTE: {n}" for n in convention_notes(scene)]
    rotate = case.particles.rotation
    clumps = case.particles.clumps
    group = "nobody" if clumps else "all"  # rigid bodies take gravity from fix rigid/small
    lines += [
        "",
        "units si",
        "atom_style sphere",
        "atom_modify map array",
        "boundary p f fm",
        "newton off",
        "comm_modify vel yes"
        + (
            f" cutoff {fmt(2.0 * _extent(scene) + 2.0 * r_max + SKIN_FRACTION * r_max)}"
            if clumps
            else ""
        ),  # a body's members within the ghost cutoff
    ]
    if geometry is not None:
        lines += pour.box_lines(scene, geometry, r_max)
    if clumps:
        lines += [
            "# clump members carry their body's number (molecule id): fix property/atom mol",
            "fix pmol all property/atom mol ghost yes",
            f"molecule grain {pour.MOLECULE_NAME}"
            if own
            else f"read_data {DATA_NAME} fix pmol NULL Molecules",
            "neigh_modify exclude molecule/intra all",
        ]
    elif not own:
        lines.append(f"read_data {DATA_NAME}")
    lines += [
        "",
        "pair_style granular",
        f"pair_coeff * * {pair.words}",
        f"neighbor {fmt(SKIN_FRACTION * r_max)} bin",
        "neigh_modify delay 0 every 1 check yes",
        "",
        *(
            flat_wall_lines(wall.words, case.trough.width)
            if pan is None
            else pan_wall_lines(wall.words, pan, mesh_name)
        ),
        "",
        f"timestep {fmt(timestep)}",
    ]
    if clumps:
        # gravity acts on each body's exact mass at its centre (fix rigid/small's gravity
        # keyword, with fix grav on an empty group); a contact on a member takes the body's mass
        # as m*, as in dem
        lines += [
            "group nobody empty",
            *([] if own else gravity_block(gx0, gz0, group)),
            "fix integrate all rigid/small molecule mol grain reinit no gravity grav"
            if own
            else f"fix integrate all rigid/small molecule infile {BODIES_NAME} gravity grav",
            "",
            "# the bodies' mean x-velocity (equal masses: the mass-weighted mean), every step",
            "compute bodies all rigid/local integrate vx",
            "compute vxm all reduce ave c_bodies inputs local",
        ]
    else:
        lines += [
            "fix integrate all nve/sphere"
            if rotate
            else "fix integrate all nve  # particles.rotation = false: the spins stay zero",
            *([] if own else gravity_block(gx0, gz0)),
            "",
            *_velocity_lines(case),
        ]
    if geometry is not None:
        lines += ["", *pour.fill_lines(scene, timestep, group, gx0, gz0, geometry), ""]
    lines += [
        f"fix vxout all ave/time 1 1 1 c_vxm file {VX_FILE}",
        f"thermo {max(1, round(period_steps))}",
        "thermo_style custom step time c_vxm atoms cpu",
        "thermo_modify lost error norm no",
        "",
        *drive_block(d, gx0, gz0, 0, timestep, group),
        "",
        "# stage 1: settle (driven, not measured)",
        f"run {settle_steps}",
        "# stage 2: measure",
        f"run {steps}",
    ]
    path = out / DECK_NAME
    return write_input(path, lines, key="OUT_DIR")
