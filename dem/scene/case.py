"""Case files: ``cases/NAME/case.toml`` -> one validated, frozen :class:`Case`.

Everything a run needs is checked here, once, before anything runs (README, A DEM run): every
key is known, has the right type and lies in its allowed range (each read through its row of the
schema, :mod:`dem.scene.schema`), keys of a shape or law not chosen are refused, and the drive is
resolved so that both the amplitude A and the throw number Gamma are available,

    Gamma = A omega^2 sin(phi) / (g cos(alpha)),   omega = 2 pi f,   g = dem.config.GRAVITY,

with phi the vibration angle and alpha the trough inclination. The checks that need several
tables (the grain against the trough, the time step against the contact, the frames against the
steps) follow. A bad value raises :class:`dem.errors.InputError` naming the dotted key
(``particles.radius``), the value, what is allowed, and the file.

The dataclasses returned are those of :mod:`dem.scene.spec`, importable from here as well.
"""

from __future__ import annotations

import math
import re
import sys
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from dem.errors import InputError
from dem.physics import laws
from dem.physics.contact import tangential_from_case
from dem.quantities import FRICTIONLESS_WHY, QUANTITIES
from dem.scene.particles import (
    build_grain,
    count_from_depth,
    grain_diameter,
    material_density,
    read_particles,
)
from dem.scene.schema import (
    DEPTH_KEYS,
    SCHEMA,
)
from dem.scene.spec import (
    Case,
    ContactSpec,
    DriveSpec,
    FeederSpec,
    MaterialSpec,
    OutputSpec,
    ParticlesSpec,
    RunSpec,
    TroughSpec,
    WallSpec,
    resolve_drive,
)
from dem.scene.tomltable import Table, suggest

__all__ = [
    "CASE_FILE",
    "Case",
    "ContactSpec",
    "DriveSpec",
    "FeederSpec",
    "MaterialSpec",
    "OutputSpec",
    "ParticlesSpec",
    "RunSpec",
    "TroughSpec",
    "WallSpec",
    "load_case",
]

#: File name of a case inside its directory.
CASE_FILE = "case.toml"
#: The tables of a case file, in the order errors list them.
_TABLES = tuple(SCHEMA)

# --- one reader per table ------------------------------------------------------------------------


def _read_trough(t: Table) -> TroughSpec:
    t.check_known()
    return TroughSpec(
        length=t.read("length"),
        width=t.read("width"),
        inclination=t.read("inclination"),
        mesh=_read_mesh(t),
    )


def _read_mesh(t: Table) -> Path | None:
    """The mesh file, read and checked now (format, triangles, extent against length and width)."""
    mesh = t.read("mesh")
    if mesh is None:
        return None
    from dem.scene.mesh import load_mesh

    length, width = t.read("length"), t.read("width")
    try:
        tri = load_mesh(mesh, length=length).tri
    except InputError as exc:
        raise t.error("mesh", t.data["mesh"], exc.allowed) from None
    span = float(np.ptp(tri[..., 1]))
    if abs(span - width) > 1e-6 * width:
        raise t.error(
            "width", width, f"the mesh's width across y, {span:.6g} m (trough.mesh sets the walls)"
        )
    return mesh


def _check_inclination(trough: TroughSpec, floor: MaterialSpec, by_wall: bool, t: Table) -> None:
    """Refuse a frictionless floor, and a trough steeper than its friction angle atan(mu).

    Without friction on the floor nothing sets a grain's mean velocity along the trough: it
    keeps the one it starts with (the drive starts at full speed, s = A sin(omega t), so a
    grain at rest on the floor starts with v = A omega cos(phi) against it), and a run would
    report that start-up as transport, with an error bar of zero.

    There no friction holds a grain on the floor: the bed slides downhill ever faster, the
    periodic section has no steady conveying velocity to measure, and the run would end only when
    a grain outran the instability check. Refused, not warned: no run of it gives a result.
    """
    limit = math.degrees(math.atan(floor.friction))
    key = "wall.friction" if by_wall else "material.friction"
    if floor.friction == 0.0:
        raise InputError(key, 0.0, f"> 0 on the floor: {FRICTIONLESS_WHY}", source=t.source)
    if abs(trough.inclination) > limit:
        raise t.error(
            "inclination", trough.inclination,
            f"within the friction angle atan({key} = {floor.friction:g}) = "
            f"{limit:.4g} deg: [-{limit:.4g}, {limit:.4g}] degrees (steeper, no friction holds a "
            "grain on the floor and the bed slides downhill ever faster)",
        )  # fmt: skip


def _read_drive(t: Table, inclination: float) -> DriveSpec:
    t.check_known()
    frequency = t.read("frequency")
    angle = t.read("angle")
    amplitude = t.read("amplitude")
    throw_number = t.read("throw_number")
    if (amplitude is None) == (throw_number is None):
        both = amplitude is not None
        raise t.error(
            "amplitude" if both else "amplitude|throw_number",
            {"amplitude": amplitude, "throw_number": throw_number} if both else None,
            "exactly one of drive.amplitude (m) and drive.throw_number"
            + (" (both are given)" if both else " (neither is given)"),
        )
    second = _read_second_component(t)
    spec = resolve_drive(
        frequency, angle, inclination, amplitude=amplitude, throw_number=throw_number
    )
    gamma = QUANTITIES["throw_number"]
    if amplitude is not None and not gamma.accepts(spec.throw_number):  # derived: in range too
        raise t.error(
            "amplitude", amplitude, f"an amplitude whose throw number A omega^2 sin(phi) / "
            f"(g cos(alpha)) = {spec.throw_number:.4g} at f = {frequency:g} Hz and phi = "
            f"{angle:g} deg {gamma.allowed}",
        )  # fmt: skip
    return replace(spec, **second, ramp_cycles=t.read("ramp_cycles"))


def _read_second_component(t: Table) -> dict:
    """The second drive component's keys; its angle and phase mean nothing without amplitude."""
    amplitude = t.read("second_amplitude")
    if amplitude == 0.0:
        for key in ("second_angle", "second_phase"):
            if key in t.data:
                raise t.error(
                    key,
                    t.data[key],
                    "given only with drive.second_amplitude > 0 (the second drive component "
                    "it belongs to)",
                )
        return {}
    return {
        "second_amplitude": amplitude,
        "second_angle": t.read("second_angle"),
        "second_phase": t.read("second_phase"),
    }


def _read_wall(t: Table) -> WallSpec:
    """``[wall]``: the keys given (the others are the material's)."""
    t.check_known()
    return WallSpec(**{key: t.read(key) for key in t.keys})


def _read_material(t: Table) -> MaterialSpec:
    t.check_known()
    return MaterialSpec(
        density=t.read("density"),
        friction=t.read("friction"),
        restitution_normal=t.read("restitution_normal"),
        restitution_tangential=t.read("restitution_tangential"),
        rolling_friction=t.read("rolling_friction"),
    )


def _read_contact(t: Table) -> ContactSpec:
    t.check_known()
    model = t.read("model")
    tangential = t.read("tangential")
    # Coefficients the chosen laws do not read are refused rather than silently ignored.
    t.refuse_foreign(
        (model, tangential),
        lambda owner: (
            f"not a coefficient of contact.model = {model!r} with contact.tangential = "
            f"{tangential!r}; remove it"
        ),
    )
    own = laws.NORMAL_LAWS[model].keys  # the normal law's stiffness key: E or k_n
    defaults = laws.TANGENTIAL_LAWS[tangential].defaults.get(model, {})
    ratio = t.read("tangential_stiffness_ratio", None)
    if ratio is None:
        ratio = defaults.get("tangential_stiffness_ratio")
    damping = t.read("tangential_damping_ratio")
    return ContactSpec(
        model=model,
        youngs_modulus=t.read("youngs_modulus") if "youngs_modulus" in own else None,
        poisson_ratio=t.read("poisson_ratio"),
        stiffness=t.read("stiffness") if "stiffness" in own else None,
        tangential_stiffness_ratio=ratio,
        limit_force=t.read("limit_force"),
        tangential=tangential,
        tangential_damping_ratio=damping,
        wall_lever_arm=t.read("wall_lever_arm"),
        slip_lever_arm=t.read("slip_lever_arm"),
    )


#: Fills a run with ``run.target_error`` starts with: three pooled fills held the long-run mean
#: in 92-96 % of runs of the shipped beds at five drives, one in 23-53 % (validation/steadiness).
TARGET_MIN_FILLS = 3


def _read_run(t: Table) -> RunSpec:
    t.check_known()
    dt = t.read("timestep")
    settle = t.read("settle_cycles")
    seed, replicas = t.read("seed"), t.read("replicas")
    target, most = t.read("target_error"), t.read("max_replicas")
    if target is not None:
        if "replicas" in t.data and replicas < TARGET_MIN_FILLS:
            raise t.error("replicas", replicas, f">= {TARGET_MIN_FILLS} with run.target_error: "
                          "the fills it starts with (fewer do not measure the fill-to-fill "
                          "spread; validation/steadiness)")  # fmt: skip
        replicas = max(replicas, TARGET_MIN_FILLS)
        if most < replicas:
            raise t.error("max_replicas", most, f">= run.replicas ({replicas}): the fills a run "
                          "with run.target_error starts with")  # fmt: skip
        seed_span = most
    else:
        seed_span = replicas
    if seed + seed_span - 1 >= 2**63:
        raise t.error("seed", seed, f"< 2^63 - {seed_span - 1}: replica k is seeded seed + k")
    return RunSpec(
        settle_cycles=settle,
        cycles=t.read("cycles"),
        timestep=dt,
        seed=seed,
        replicas=replicas,
        device=t.read("device"),
        target_error=target,
        max_replicas=most,
    )


def _read_feeder(t: Table, length: float) -> FeederSpec:
    """The [feeder] table (its presence makes the trough finite)."""
    t.check_known()
    rate = t.read("feed_rate")
    zone = t.read("feed_length", 0.25 * length)
    if zone > length:
        raise t.error(
            "feed_length", zone, f"<= trough.length = {length:g} m (the zone lies in the trough)"
        )
    return FeederSpec(feed_rate=rate, feed_length=zone)


def _read_output(t: Table) -> OutputSpec:
    t.check_known()
    return OutputSpec(frames_per_cycle=t.read("frames_per_cycle"),
                      flight_phases=t.read("flight_phases"),
                      contacts=t.read("contacts"))  # fmt: skip


# --- checks across tables ------------------------------------------------------------------------


def _check_feeder(case: Case, table: Callable[[str], Table]) -> None:
    """A feed zone must hold a grain; a feed rate must be one the zone can be asked for."""
    f = case.feeder
    if f is None:
        return
    if case.particles.grain is not None:
        diameter = 2.0 * case.particles.grain.bounding_radius
    else:
        diameter = grain_diameter(case.particles)
    if f.feed_rate > 0.0 and f.feed_length < diameter:
        raise table("feeder").error(
            "feed_length", f.feed_length,
            f">= one grain's extent ({diameter:.4g} m), the zone fed grains are dropped into",
        )  # fmt: skip


def load_case(
    path: str | Path,
    overrides: Mapping[str, Any] | None = None,
    origins: Mapping[str, str] | None = None,
) -> Case:
    """Read and validate a case.

    Args:
        path: A case directory (holding ``case.toml``) or the ``case.toml`` itself.
        overrides: Keys to set before validation, ``{"drive.angle": 30.0}`` (a study or a sweep
            point); the value None removes the key. Values are checked exactly as if they had
            been written in the file, and an error in one names where it came from instead of
            the file: ``origins[key]`` (``"--replicas"``), else ``"--set"``.
        origins: Where each override was given, for its errors.

    Returns:
        The validated case; relative paths in the file are resolved against its directory.

    Raises:
        InputError: The file is missing, is not valid TOML, or a key is unknown, missing, of the
            wrong type or out of range. The message names the key, the value, the allowed range
            and the file.

    """
    try:
        return _load_case(path, overrides)
    except InputError as exc:
        given = overrides or {}
        if exc.key not in given or given[exc.key] is None:
            raise
        origin = (origins or {}).get(exc.key, "--set")
        raise InputError(exc.key, exc.value, exc.allowed, source=origin) from None


def _load_case(path: str | Path, overrides: Mapping[str, Any] | None) -> Case:
    """:func:`load_case`, every error sourced in the file."""
    try:
        path = Path(path).expanduser().resolve()
    except ValueError as exc:  # a NUL in the path
        raise InputError("case", str(path), f"a path without NUL characters ({exc})") from None
    source = path / CASE_FILE if path.is_dir() else path
    if not source.is_file():
        raise InputError(
            "case", str(path), f"a case directory holding {CASE_FILE}, or a {CASE_FILE} file"
        )
    where = str(source)
    try:
        with source.open("rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        line = re.search(r"line (\d+)", str(exc))
        key = f"line {line.group(1)}" if line else "file"
        raise InputError(key, str(exc), "valid TOML syntax (https://toml.io)", where) from exc
    except UnicodeDecodeError as exc:
        raise InputError("file", str(exc), "UTF-8 encoded TOML", where) from exc
    except RecursionError:  # tomllib recurses once per level of nested arrays or tables
        raise InputError(
            "file", f"values nested deeper than Python's recursion limit "
            f"({sys.getrecursionlimit()})", "a case file of tables, keys and values (nested a "
            "few levels at most)", where,
        ) from None  # fmt: skip
    if overrides:
        _apply_overrides(data, overrides, where)

    for name, value in data.items():
        if name not in _TABLES:
            raise InputError(
                name, value, f"a table: {', '.join(_TABLES)}{suggest(name, _TABLES)}", where
            )
        if not isinstance(value, dict):
            raise InputError(name, value, f"a table [{name}]", where)

    directory = source.parent

    def table(name: str) -> Table:
        return Table(name, data.get(name, {}), where, directory, SCHEMA[name])

    trough = _read_trough(table("trough"))
    drive = _read_drive(table("drive"), trough.inclination)
    material = _read_material(table("material"))
    wall = _read_wall(table("wall"))
    _check_inclination(trough, wall.over(material), "friction" in wall.given, table("trough"))
    contact = _read_contact(table("contact"))
    particles = read_particles(table("particles"))
    material = material_density(material, particles, table("material"))
    if particles.types:  # each type's density; material.density: the bed's, by volume
        from dem.scene.sizes import mean_density

        types = tuple(g if g.density is not None else replace(g, density=material.density)
                      for g in particles.types)  # fmt: skip
        particles = replace(particles, types=types)
        material = replace(material, density=mean_density(types))
    particles = build_grain(particles, material.density, table("particles"))
    if material.density is None:  # the grain's mass set it
        rho = particles.grain.density
        if not QUANTITIES["density"].accepts(rho):
            raise table("particles").error(
                "mass", particles.mass, f"a grain of plausible density: {particles.mass:g} kg in "
                f"the grain's {particles.grain.volume:.3g} m^3 is {rho:.3g} kg/m^3, outside what "
                f"material.density takes: {QUANTITIES['density'].allowed} (a mass in g for kg?)",
            )  # fmt: skip
        material = replace(material, density=rho)
    particles = count_from_depth(particles, material.density, trough, "feeder" in data,
                                  table("particles"))  # fmt: skip
    try:  # the tangential sub-model alone: a derived spring's search is cached for the law
        tangential_from_case(contact, material, particles)
    except ValueError as exc:
        raise table("material").error(
            "restitution_tangential",
            material.restitution_tangential,
            f"{exc}, when contact.tangential = {contact.tangential!r} derives the tangential "
            "spring from it; or give contact.tangential_stiffness_ratio",
        ) from None
    run = _read_run(table("run"))
    output = _read_output(table("output"))
    feeder = _read_feeder(table("feeder"), trough.length) if "feeder" in data else None

    if run.settle_cycles is not None and drive.ramp_cycles > run.settle_cycles:
        raise table("drive").error(
            "ramp_cycles",
            drive.ramp_cycles,
            f"<= run.settle_cycles = {run.settle_cycles}: the start-up ramp must end before the "
            'measured cycles begin (or settle_cycles = "auto", which waits for it)',
        )
    diameter = grain_diameter(particles)
    if trough.width < diameter:
        raise table("trough").error(
            "width", trough.width, f">= one grain diameter ({diameter:g} m) between the walls"
        )
    case = Case(
        name=directory.name,
        directory=directory,
        source=source,
        trough=trough,
        drive=drive,
        material=material,
        contact=contact,
        particles=particles,
        run=run,
        output=output,
        feeder=feeder,
        overrides=dict(overrides or {}),
        wall=wall,
    )
    _check_feeder(case, table)
    _check_types(case, table)
    _check_engine(case, table)
    return case


def _check_types(case: Case, table: Callable[[str], Table]) -> None:
    """Refuse grain types and size distributions where the engine does not take them yet.

    A mesh trough's fill, a finite feeder's feed and the GPU engine place or step grains of one
    size; rather than run them with one size and report the distribution, they are refused.
    """
    pt = case.particles
    if not pt.types:
        return
    key = "types" if "types" in table("particles").data else "radius_distribution"
    value = table("particles").data[key]
    where = None
    if case.trough.mesh is not None:
        where = "a mesh trough (its fill places grains of one size)"
    elif case.feeder is not None:
        where = "a finite feeder (its feed drops grains of one size)"
    elif case.run.device == "cuda":
        where = "the GPU engine (run.device = 'cuda'; not yet checked with several sizes)"
    if where is not None:
        raise table("particles").error(
            key, value if key != "types" else f"{len(pt.types)} tables",
            f"one sphere size (particles.radius) for {where}: grain types and size "
            "distributions run on a flat periodic section on the CPU engine",
        )  # fmt: skip


#: Keys of which a case gives exactly one: an override of one replaces the file's others
#: (``--set drive.amplitude=3e-4`` on a case that gives drive.throw_number, ``--set
#: particles.layers=3`` on one that gives particles.count).
_ONE_OF = (
    ("drive.amplitude", "drive.throw_number"),
    tuple(f"particles.{k}" for k in DEPTH_KEYS),
)
_EITHER = {key: tuple(k for k in group if k != key) for group in _ONE_OF for key in group}


def _apply_overrides(data: dict, overrides: Mapping[str, Any], where: str) -> None:
    """Set ``table.key`` values in the parsed file ``data`` (None removes the key).

    An override of one of a group the case gives exactly one of (:data:`_ONE_OF`) removes the
    file's others, unless the overrides set them too (then both are given, and refused as such).
    """
    for dotted, others in _EITHER.items():
        if overrides.get(dotted) is None:
            continue
        for other in others:
            if other not in overrides:
                name, _, key = other.partition(".")
                data.get(name, {}).pop(key, None)
    for dotted, value in overrides.items():
        name, _, key = str(dotted).partition(".")
        if name not in _TABLES or not key or "." in key:
            raise InputError(
                "override", dotted, f"table.key with a table of {', '.join(_TABLES)}", where
            )
        table = data.setdefault(name, {})
        if value is None:
            table.pop(key, None)
        else:
            table[key] = value


def _check_engine(case: Case, table: Callable[[str], Table]) -> None:
    """The checks the engine would make when building the case, made at load instead.

    The periodic section must hold a grain and its skin twice over (the minimum image must be
    unique) and more than twice a clump's reach; a given ``run.timestep`` must lie within the
    stability limit of the contact (:func:`dem.scene.timestep.timestep_for`, no fill needed); and
    ``output.frames_per_cycle`` must not exceed the time steps per cycle.
    """
    from dem import config
    from dem.scene.timestep import timestep_for
    from dem.scene.trough import check_section_length

    pt, length = case.particles, case.trough.length
    r_max, reach = pt.radius, 0.0
    if pt.grain is not None:  # a screw or clump: built at load
        r_max = float(max(pt.grain.radii))
        reach = float(max(math.hypot(*c) for c in pt.grain.centres))
    assert r_max is not None  # a sphere's radius, else the clump's largest member
    skin = config.DEM_SKIN_FRACTION * r_max  # the Simulation's default skin
    check_section_length(length, r_max, skin, reach, source=str(case.source))
    step = timestep_for(case)  # checks a given run.timestep against the limit
    steps_per_cycle = 1.0 / (case.drive.frequency * step.dt)
    if case.output.contacts and (case.trough.mesh is not None or case.run.device == "cuda"):
        where = (
            "a mesh trough (its triangle contacts are not listed yet)"
            if case.trough.mesh is not None
            else "the GPU engine (run.device = 'cuda')"
        )
        raise table("output").error("contacts", True, f"false for {where}: the contacts are "
                                    "listed for flat troughs on the CPU engine")  # fmt: skip
    if case.output.frames_per_cycle > steps_per_cycle:
        raise table("output").error(
            "frames_per_cycle",
            case.output.frames_per_cycle,
            f"<= the time steps per drive cycle, {math.floor(steps_per_cycle)} at dt = "
            f"{step.dt:.4g} s (at most one frame a step)",
        )
