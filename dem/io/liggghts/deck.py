"""Export a case as an equivalent LIGGGHTS-PUBLIC 3.8 input deck (README, A short tour).

The deck simulates the same trough section in the trough's accelerating frame: the walls stay
still and every grain feels the effective gravity (:mod:`dem.io.liggghts.drive`). It is written
by blocks, each a function that returns its lines, in the deck's order: the header (what the
case is and how to run the deck), units, the box (:mod:`dem.io.liggghts.geometry`), the material
and contact law (:mod:`dem.io.liggghts.contact`), the walls, static gravity, the grain template
and its insertion, the output, and the three stages, each its own ``run`` command; a finite
feeder adds its feed and balance to the drive (:mod:`dem.io.liggghts.feeder`).

Grains: spheres are ``fix particletemplate/sphere`` integrated by ``fix nve/sphere`` (``nve``
with rotation locked). Screws and clumps are ``fix particletemplate/multisphere`` reading the
members from ``grain.multisphere`` (``x y z r`` in m, body frame: centre of mass at the origin,
principal axes, written by :func:`dem.scene.shapes.write_clump`), with the template's exact
``mass`` and diagonal ``inertia_tensor`` given (``use_volume``), so LIGGGHTS's Monte Carlo
estimate only sets its volume; ``fix multisphere`` integrates the rigid bodies (``tflag off off
off`` locks rotation) and needs ``atom_modify map array sort 0 0``. LIGGGHTS, like dem, takes
the clump's mass as the mass of a member in a contact. The mean x-velocity is then that of the
bodies' centres of mass (``compute multisphere property vcm``), not of the member spheres.

The deck runs three stages: fill (insert N grains at random in a loose column and let them fall
under static gravity until at rest), settle (drive on, ``settle_steps`` steps not measured) and
measure (``steps`` driven steps). Each stage is its own ``run`` command, so LIGGGHTS prints one
"Loop time of T on P procs for S steps" line per stage; the last one times the driven steps
alone. The mean x-velocity of all grains (``compute reduce ave vx``; equal masses, so the same as
the mass-weighted mean), averaged over windows of ``sample_steps`` steps, goes to ``vx_mean.txt``.
"""

from __future__ import annotations

import math
import shlex
from pathlib import Path
from typing import NamedTuple

from dem import __version__
from dem.config import GRAVITY
from dem.errors import InputError
from dem.io.files import write_input
from dem.io.liggghts.contact import contact_block
from dem.io.liggghts.drive import drive_block, gravity_block, static_gravity
from dem.io.liggghts.feeder import feeder_lines
from dem.io.liggghts.geometry import SKIN_FRACTION, Layout, layout, placement, wall_block
from dem.io.liggghts.text import fmt, prime_at_least
from dem.scene.case import Case
from dem.scene.resolved import Scene, resolve
from dem.scene.shapes import clump_lines

#: LIGGGHTS version the decks are written for.
LIGGGHTS_VERSION = "LIGGGHTS-PUBLIC 3.8.0"
#: File name of the deck inside the output directory.
DECK_NAME = "in.dem"
#: File the deck writes the windowed mean x-velocity to (columns: step, mean vx in m/s).
VX_FILE = "vx_mean.txt"
#: The particle dump's files, one per output frame (``*`` is the step; trough frame, SI units).
DUMP_FILES = "dump*.liggghts"
#: File the clump template's members are written to, next to the deck.
CLUMP_FILE = "grain.multisphere"
#: Monte Carlo samples of ``particletemplate/multisphere`` (only its volume estimate uses them).
MULTISPHERE_NTRY = 1000000


class Grains(NamedTuple):
    """A deck's grain template (:func:`_grain_block`).

    Attributes:
        r_max: Radius of the largest sphere of a grain, m.
        r_min: Radius of the smallest sphere of a grain, m.
        volume: Volume of a grain, m^3.
        mass: Mass of a grain, kg.
        members: Spheres a grain is made of.
        what: The grains in words, for the header.
        template: The ``particletemplate`` lines (and their comments).
        integrator: The integrator fix.
        velocity: The computes whose ``c_vxm`` is the grains' mean x-velocity, m/s.
        distribution: The templates of ``fix pdd`` with their weights (one: ``pts``, 1).
        style: The ``fix pdd`` style: ``particledistribution/discrete`` (mass-based, one
            template) or ``particledistribution/discrete/numberbased`` (dem's number fractions).

    """

    r_max: float
    r_min: float
    volume: float
    mass: float
    members: int
    what: str
    template: list[str]
    integrator: list[str]
    velocity: list[str]
    distribution: tuple = (("pts", 1.0),)
    style: str = "particledistribution/discrete"


class Schedule(NamedTuple):
    """Step counts of a deck's settling and output (:func:`_schedule`).

    Attributes:
        settle_steps: Driven steps before measuring.
        frame_steps: Steps between particle dumps: one output frame.
        sample_steps: Window of the mean x-velocity in ``vx_mean.txt``, steps.
        thermo_every: Steps between thermo lines.

    """

    settle_steps: int
    frame_steps: int
    sample_steps: int
    thermo_every: int


def write_deck(
    case: Case | Scene,
    out_dir: str | Path,
    *,
    timestep: float,
    steps: int,
    settle_steps: int | None = None,
    fill_time: float | None = None,
    sample_steps: int | None = None,
    thermo_every: int | None = None,
    settle_note: str | None = None,
    dump: bool = True,
) -> Path:
    """Write ``out_dir/in.dem``, a LIGGGHTS deck equivalent to a case.

    Args:
        case: A validated case (spheres, screws or clumps), or its
        :class:`dem.scene.resolved.Scene`.
        out_dir: Directory for the deck (created; a clump case also gets ``grain.multisphere``,
            a mesh case ``trough.stl``); LIGGGHTS is run inside it.
        timestep: dt, s.
        steps: Driven steps that are measured (the last ``run``).
        settle_steps: Driven steps before measuring; default ``run.settle_cycles`` drive cycles.
        fill_time: Time, s, for the inserted grains to fall and come to rest under static
            gravity; default sqrt(2 H / g) + 0.1 s for an insertion column of height H.
        sample_steps: Window of the mean x-velocity written to ``vx_mean.txt``; default one
            output frame, 1 / (frequency * frames_per_cycle) s.
        thermo_every: Steps between thermo lines; default one drive cycle.
        settle_note: Where the settle count came from (a comment in the deck), when the case
            says "auto" and the caller chose it.
        dump: Write a particle dump (``dump*.liggghts``, LIGGGHTS's ``custom`` text: id, type,
            x y z, vx vy vz, radius) every output frame, ``output.frames_per_cycle`` per drive
            cycle, from the drive's start: what dem run writes as VTK frames.

    Returns:
        Path of the deck.

    Raises:
        InputError: A clump case without its template, a mesh no insertion block fits in,
            or timestep/steps not positive.

    """
    scene: Scene | None = None
    if isinstance(case, Scene):
        scene, case = case, case.case
    p = case.particles
    if p.clumps and p.grain is None:
        raise InputError(
            "particles.shape", p.shape, "a case read by dem.scene.case.load_case", str(case.source)
        )
    if not timestep > 0.0:
        raise InputError("timestep", timestep, "> 0 (s)")
    if steps < 1:
        raise InputError("steps", steps, ">= 1")
    if scene is None:  # the deck's step is ``timestep``: the scene's own is not checked here
        scene = resolve(case, check_limit=False)

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    seed = case.run.seed
    grains = _grain_block(scene, out, prime_at_least(15485863 + 1000 * seed))
    times = _schedule(case, timestep, settle_steps, sample_steps, thermo_every)
    material_lines, model, settings = contact_block(scene, grains.mass)
    space = layout(case, out, r_min=grains.r_min, r_max=grains.r_max, grain_volume=grains.volume)
    if fill_time is None:
        fill_time = math.sqrt(2.0 * (space.fill_z0 + space.fill_height - space.bottom) / GRAVITY)
        fill_time += 0.1
    fill_steps = max(1, round(fill_time / timestep))
    feed_lines: list[str] = []
    balance_note: list[str] = []
    if case.feeder is not None:
        feed_lines, balance_note = feeder_lines(
            scene, timestep, space.fill_y, space.fill_z0, space.fill_height, grains.members,
            s_feed=prime_at_least(67867967 + 1000 * seed), sample_steps=times.sample_steps,
            drive_start=fill_steps,
        )  # fmt: skip
    gx0, gz0 = static_gravity(case.trough.inclination)
    header = _header_block(
        case, out, grains, times, timestep=timestep, steps=steps, fill_steps=fill_steps,
        settle_note=settle_note, dump=dump, notes=space.wall_note + balance_note,
    )  # fmt: skip
    seeds = (prime_at_least(32452843 + 1000 * seed), prime_at_least(49979687 + 1000 * seed))
    blocks = [
        header,
        _units_block(case, space.boundary),
        _region_block(space, grains.r_min),
        material_lines,
        [f"pair_style gran {model} {settings}", "pair_coeff * *", f"timestep {fmt(timestep)}"],
        wall_block(case, space, model, settings),
        gravity_block(gx0, gz0),
        _insertion_block(case, grains, space, *seeds),
        _thermo_block(case, grains, times),
        _fill_stage(fill_steps, p.count),
        drive_block(case.drive, gx0, gz0, fill_steps, timestep)
        + _output_block(times, dump)
        + feed_lines,
        ["# --- settle: driven, not measured",
         f"run {times.settle_steps}" if times.settle_steps > 0 else "# (no settle steps)"],
        ["# --- measure: driven; the last 'Loop time' line times these steps alone",
         f"run {steps}"],
    ]  # fmt: skip
    lines = [line for block in blocks for line in [*block, ""]]
    return write_input(out / DECK_NAME, lines, key="OUT_DIR")


def write_clump(path: Path, template, *, frame: str = "body", key: str = "--out") -> Path:
    """Write a clump template's members (:func:`dem.scene.shapes.clump_lines`) to ``path``.

    The file LIGGGHTS's ``particletemplate/multisphere`` reads (``x y z r``, m), and
    :func:`dem.scene.shapes.clump_from_file` reads back; written as every input file is
    (:func:`dem.io.files.write_input`: no link followed, the template's name inert).
    """
    return write_input(path, clump_lines(template, frame=frame), key=key)


def _grain_block(scene: Scene, out: Path, seed: int) -> Grains:
    """The grain template with seed ``seed``; a clump's members go to ``out /`` CLUMP_FILE."""
    case = scene.case
    p = case.particles
    n = p.count
    if p.types:
        return _types_block(scene, seed)
    if not p.clumps:
        assert p.radius is not None  # one sphere size
        grain_volume = 4.0 / 3.0 * math.pi * p.radius**3
        return Grains(
            p.radius, p.radius, grain_volume, case.material.density * grain_volume, 1,
            f"{n} spheres r = {p.radius} m",
            [f"fix pts all particletemplate/sphere {seed} atom_type 1 "
             f"density constant {fmt(case.material.density)} radius constant {fmt(p.radius)}"],
            [f"fix integr all {'nve/sphere' if p.rotation else 'nve'}"],
            ["compute vxm all reduce ave vx"],
        )  # fmt: skip
    g = scene.grain
    members = g.count
    write_clump(out / CLUMP_FILE, g, frame="body", key="OUT_DIR")
    i1, i2, i3 = (fmt(m) for m in g.moments)
    template = [
        f"# {CLUMP_FILE}: members x y z r (m) in the body frame (centre of mass at the origin,",
        "# principal axes); mass and inertia tensor exact from dem.scene.shapes,"
        " Monte Carlo volume",
        f"fix pts all particletemplate/multisphere {seed} atom_type 1 "
        f"density constant {fmt(g.density)} nspheres {members} ntry {MULTISPHERE_NTRY} "
        f"spheres file {CLUMP_FILE} scale 1.0 type 1 mass {fmt(g.mass)} "
        f"inertia_tensor {i1} 0.0 0.0 {i2} 0.0 {i3} use_volume"
        + ("" if p.rotation else " tflag off off off"),
    ]
    return Grains(
        float(max(g.radii)), float(min(g.radii)), g.volume, g.mass, members,
        f"{n} {p.shape}s of {members} spheres, m = {g.mass:.6g} kg", template,
        ["fix integr all multisphere"],
        ["compute vcm all multisphere property vcm", "compute vxm all reduce ave c_vcm[1]"],
    )  # fmt: skip


def _types_block(scene: Scene, seed: int) -> Grains:
    """Spheres of several types or sizes: one ``particletemplate/sphere`` per type and radius.

    LIGGGHTS 3.8's template takes one radius, so a continuous size distribution is cut into
    :data:`dem.scene.sizes.DECK_BINS` bins of equal number, each at the radius of its mean
    volume (:func:`dem.scene.sizes.bins`: the bed's mean volume and mass are kept); a discrete
    one is written as it is. The weights are dem's fractions by number (type fraction times
    bin fraction), so ``fix pdd`` is ``particledistribution/discrete/numberbased``. Every
    template is atom type 1: the types share the material and the contact law, and LIGGGHTS's
    Hertz law takes each pair's R* and m* from its atoms. With unequal masses the mean
    x-velocity is weighted by mass: the mean of m vx / m_mean over the atoms (1e-30 keeps
    m_mean finite before the insertion; LIGGGHTS 3.8's formulas have no max()).
    """
    from dem.scene.sizes import DECK_BINS, bins, mean_mass, mean_volume

    case = scene.case
    p = case.particles
    template = [
        f"# grain types (dem's particles.types; fractions by number; a continuous size "
        f"distribution as {DECK_BINS} equal-number bins, each at the radius of its mean volume)"
    ]
    weights, radii, s = [], [], seed
    for k, t in enumerate(p.types):
        size = t.size
        assert t.density is not None  # the case's material.density fills it at load
        what = _size_words(size)
        template.append(f"# type {k + 1} {t.name}: {t.fraction:.6g} of the grains by number, "
                        f"density {t.density:g} kg/m^3, {what}")  # fmt: skip
        for b, (r, f) in enumerate(zip(*bins(size), strict=True)):
            name = f"pts{k + 1}_{b + 1}"
            template.append(
                f"fix {name} all particletemplate/sphere {s} atom_type 1 "
                f"density constant {fmt(t.density)} radius constant {fmt(r)}"
            )
            weights.append((name, t.fraction * f))
            radii.append(r)
            s = prime_at_least(s + 1)
    return Grains(
        max(radii), min(radii), mean_volume(p.types), mean_mass(p.types), 1,
        f"{p.count} spheres of {len(p.types)} types, r = {min(radii):.4g}-{max(radii):.4g} m",
        template, [f"fix integr all {'nve/sphere' if p.rotation else 'nve'}"],
        ["# the mass-weighted mean x-velocity (unequal masses)",
         "variable mmean equal (mass(all)+1e-30)/(count(all)+1e-30)",
         "variable wvx atom mass*vx/v_mmean", "compute vxm all reduce ave v_wvx"],
        tuple(weights), "particledistribution/discrete/numberbased",
    )  # fmt: skip


def _size_words(size) -> str:
    """A size distribution in words, for the deck's comments."""
    bounds = f"in [{size.radius_min}, {size.radius_max}] m"
    return {
        "none": f"radius {size.radius} m",
        "uniform": f"uniform radius {bounds}",
        "normal": f"normal radius, mean {size.radius} m, sd {size.radius_std} m, {bounds}",
        "lognormal": f"lognormal radius, median {size.radius} m, sd of ln r "
        f"{size.radius_log_std}, {bounds}",
        "discrete": "discrete radii",
    }[size.distribution]


def _schedule(
    case: Case,
    timestep: float,
    settle_steps: int | None,
    sample_steps: int | None,
    thermo_every: int | None,
) -> Schedule:
    """The settling and output step counts, each the caller's or its default (write_deck)."""
    steps_per_cycle = 1.0 / (case.drive.frequency * timestep)
    if settle_steps is None:
        if case.run.settle_cycles is None:
            raise InputError(
                "run.settle_cycles",
                "auto",
                "a whole number of cycles for a LIGGGHTS deck (the deck cannot detect the end of "
                "the transient; use the number a dem run of the case reported in summary.json)",
                source=str(case.source),
            )
        settle_steps = round(case.run.settle_cycles * steps_per_cycle)
    frame_steps = max(1, round(steps_per_cycle / case.output.frames_per_cycle))
    if sample_steps is None:
        sample_steps = frame_steps
    if thermo_every is None:
        thermo_every = max(1, round(steps_per_cycle))
    return Schedule(settle_steps, frame_steps, sample_steps, thermo_every)


def _header_block(
    case: Case,
    out: Path,
    grains: Grains,
    times: Schedule,
    *,
    timestep: float,
    steps: int,
    fill_steps: int,
    settle_note: str | None,
    dump: bool,
    notes: list[str],
) -> list[str]:
    """The comments at the top: the case, how to run the deck, its stages, output and frame."""
    d, t = case.drive, case.trough
    dumped = (
        f", {DUMP_FILES} (every {times.frame_steps} steps: "
        f"{case.output.frames_per_cycle} a cycle, from the drive's start)"
    )
    return [
        f"# LIGGGHTS deck exported by dem {__version__} (dem export liggghts)",
        f"# case {case.name}: {grains.what}, {case.contact.model}, "
        f"f = {d.frequency} Hz, phi = {d.angle} deg, A = {d.amplitude:.6g} m, "
        f"Gamma = {d.throw_number:.6g}, alpha = {t.inclination} deg",
        f"# made for {LIGGGHTS_VERSION} (Debian package 'liggghts')",
        f"# run:  cd {shlex.quote(out.name)} && liggghts -in {DECK_NAME}",
        f"#   or: cd {shlex.quote(out.name)} && mpirun -np 2 liggghts -in {DECK_NAME}",
        f"# stages: fill {fill_steps} steps (static gravity), settle {times.settle_steps} driven "
        f"steps, measure {steps} driven steps; dt = {timestep} s",
        f"# output: {VX_FILE} (step, mean vx in m/s averaged over {times.sample_steps} steps), "
        "log.liggghts" + (dumped if dump else ""),
        *([f"# settle: {settle_note}"] if settle_note else []),
        "# frame: the trough's accelerating frame; walls still, effective gravity",
        "#   g(t) = (-g sin(alpha) + A w^2 sin(w tau) cos(phi), 0, "
        "-g cos(alpha) + A w^2 sin(w tau) sin(phi))",
        *notes,
    ]


def _units_block(case: Case, boundary: str) -> list[str]:
    """Atom style, boundary, communication and SI units (``hard_particles`` for E > 1e9 Pa)."""
    # LIGGGHTS refuses E > 1e9 Pa in SI units unless told the grains are hard on purpose
    youngs = case.contact.youngs_modulus  # None under the linear law (no modulus)
    hard = (["hard_particles yes  # E > 1e9 Pa: LIGGGHTS 3.8 refuses it in SI units otherwise"]
            if youngs is not None and youngs > 1.0e9 else [])  # fmt: skip
    return [
        "atom_style granular",
        "atom_modify map array" + (" sort 0 0" if case.particles.clumps else ""),
        boundary,
        "newton off",
        "communicate single vel yes",
        "processors * 1 1  # split x only: the bed is uniform across y and z",
        "units si",
        *hard,
    ]


def _region_block(space: Layout, r_min: float) -> list[str]:
    """The box (two atom types) and the neighbour skin, :data:`SKIN_FRACTION` of ``r_min``."""
    box_x, box_y = space.box_x, space.box_y
    return [
        f"region domain block {fmt(box_x[0])} {fmt(box_x[1])} {fmt(box_y[0])} {fmt(box_y[1])} "
        f"{fmt(space.box_z0)} {fmt(space.top)} units box",
        "create_box 2 domain",
        f"neighbor {fmt(SKIN_FRACTION * r_min)} bin",
        "neigh_modify delay 0",
    ]


def _insertion_block(
    case: Case, grains: Grains, space: Layout, s_dist: int, s_insert: int
) -> list[str]:
    """The grain template, its insertion into the fill block, and the integrator."""
    fill_x, fill_y, fill_z0 = space.fill_x, space.fill_y, space.fill_z0
    return [
        *grains.template,
        f"fix pdd all {grains.style} {s_dist} {len(grains.distribution)} "
        + " ".join(f"{name} {fmt(w)}" for name, w in grains.distribution),
        f"region fill block {fmt(fill_x[0])} {fmt(fill_x[1])} "
        f"{fmt(fill_y[0])} {fmt(fill_y[1])} "
        f"{fmt(fill_z0)} {fmt(fill_z0 + space.fill_height)} units box",
        f"fix ins all insert/pack seed {s_insert} distributiontemplate pdd "
        "maxattempt 1000 vel constant 0.0 0.0 0.0 insert_every once "
        f"overlapcheck yes{placement(case)} particles_in_region {case.particles.count} region fill",
        *grains.integrator,
    ]


def _thermo_block(case: Case, grains: Grains, times: Schedule) -> list[str]:
    """The mean x-velocity ``c_vxm`` and the thermo output (a feeder's lost atoms ignored)."""
    lost = "" if case.feeder is None else " lost ignore"
    return [
        *grains.velocity,
        "thermo_style custom step atoms ke c_vxm",
        f"thermo {times.thermo_every}",
        "thermo_modify norm no" + lost,
    ]


def _fill_stage(fill_steps: int, n: int) -> list[str]:
    """The fill: insert ``n`` grains, let them fall for ``fill_steps``, stop if any is missing."""
    return [
        "# --- fill: insert and let the grains come to rest under static gravity",
        f"run {fill_steps}",
        "variable ninserted equal f_ins[1]",
        f'if "${{ninserted}} < {n}" then '
        f'"print \'ERROR: only ${{ninserted}} of {n} grains inserted\'" "quit"',
        "unfix ins",
        "variable natoms0 equal atoms",
    ]


def _output_block(times: Schedule, dump: bool) -> list[str]:
    """From the drive's start: the windowed mean x-velocity and, if ``dump``, the frames."""
    return [
        f"fix vxout all ave/time 1 {times.sample_steps} {times.sample_steps} c_vxm file {VX_FILE}",
    ] + (
        [f"dump frames all custom {times.frame_steps} {DUMP_FILES} id type x y z vx vy vz radius"]
        if dump
        else []
    )
