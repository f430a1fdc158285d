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
from dem.physics import tangential
from dem.quantities import FRICTIONLESS_WHY, QUANTITIES
from dem.scene import depth
from dem.scene.schema import (
    DEFAULT_TANGENTIAL_STIFFNESS_RATIO,
    DEPTH_KEYS,
    MAX_DISCRETE_RADII,
    MAX_GRAIN_TYPES,
    PARTICLE_TYPE,
    SCHEMA,
    SHAPES,
    SIZE_KEYS,
)
from dem.scene.spec import (
    Case,
    ContactSpec,
    DriveSpec,
    FeederSpec,
    GrainType,
    MaterialSpec,
    OutputSpec,
    ParticlesSpec,
    RunSpec,
    SizeSpec,
    TroughSpec,
    WallSpec,
    resolve_drive,
)
from dem.scene.tomltable import REQUIRED, Table, suggest

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
    hertz = model == "hertz_mindlin"
    ratio = t.read("tangential_stiffness_ratio", None)
    if ratio is None and not hertz and tangential == "liggghts":
        ratio = DEFAULT_TANGENTIAL_STIFFNESS_RATIO
    damping = t.read("tangential_damping_ratio")
    return ContactSpec(
        model=model,
        youngs_modulus=t.read("youngs_modulus") if hertz else None,
        poisson_ratio=t.read("poisson_ratio"),
        stiffness=None if hertz else t.read("stiffness"),
        tangential_stiffness_ratio=ratio,
        limit_force=t.read("limit_force"),
        tangential=tangential,
        tangential_damping_ratio=damping,
        wall_lever_arm=t.read("wall_lever_arm"),
        slip_lever_arm=t.read("slip_lever_arm"),
    )


#: Largest ratio of the largest to the smallest radius of a case: the neighbour grid's cells are
#: sized by the largest sphere, so a step's cost grows as the cube of the ratio.
MAX_SIZE_RATIO = 10.0
#: How far the fractions of the types (or of a discrete distribution's radii) may sum from 1.
FRACTION_SUM_TOLERANCE = 1e-6


def _foreign_why(shape: str, distribution: str) -> Callable[[str], str]:
    """The refusal of a [particles] key that the shape or size distribution chosen does not read."""

    def why(owner: str) -> str:
        if owner in SHAPES:
            return f"a key of shape = {owner!r}, not of {shape!r}"
        return f"a key of radius_distribution = {owner!r}, not of {distribution!r}"

    return why


def _read_size(t: Table) -> SizeSpec:
    """The size distribution of [particles] or of one ``[[particles.types]]`` table (spheres)."""
    dist = t.read("radius_distribution")
    if dist == "none":
        return SizeSpec(radius=t.read("radius"))
    if dist in ("uniform", "discrete") and "radius" in t.data:
        what = "radius_min and radius_max bound it" if dist == "uniform" else "radii lists them"
        raise t.error("radius", t.data["radius"], f"not given with radius_distribution = "
                      f"{dist!r} ({what}): remove it")  # fmt: skip
    if dist == "discrete":
        radii = t.read("radii", REQUIRED)
        fractions = t.read("radius_fractions", REQUIRED)
        if len(fractions) != len(radii):
            raise t.error("radius_fractions", list(fractions), f"one fraction per radius of "
                          f"{t.name}.radii ({len(radii)} radii)")  # fmt: skip
        if len(radii) > MAX_DISCRETE_RADII or len(set(radii)) != len(radii):
            raise t.error("radii", list(radii), f"1 to {MAX_DISCRETE_RADII} different radii, m")
        total = sum(fractions)
        if abs(total - 1.0) > FRACTION_SUM_TOLERANCE:
            raise t.error("radius_fractions", list(fractions), f"shares of the grains by number "
                          f"that sum to 1 (these sum to {total:.9g})")  # fmt: skip
        _check_ratio(t, "radii", list(radii), min(radii), max(radii))
        pairs = sorted(zip(radii, fractions, strict=True))
        return SizeSpec("discrete", radii=tuple(r for r, _ in pairs),
                        radius_fractions=tuple(f for _, f in pairs))  # fmt: skip
    lo, hi = t.read("radius_min", REQUIRED), t.read("radius_max", REQUIRED)
    if hi <= lo:
        raise t.error("radius_max", hi, f"> {t.name}.radius_min = {lo:g} m")
    _check_ratio(t, "radius_max", hi, lo, hi)
    if dist == "uniform":
        return SizeSpec("uniform", radius_min=lo, radius_max=hi)
    centre = t.read("radius")
    if not lo < centre < hi:
        what = "mean" if dist == "normal" else "median"
        raise t.error("radius", centre, f"the distribution's {what}, inside ({t.name}.radius_min"
                      f", radius_max) = ({lo:g}, {hi:g}) m")  # fmt: skip
    if dist == "normal":
        return SizeSpec("normal", radius=centre, radius_min=lo, radius_max=hi,
                        radius_std=t.read("radius_std", REQUIRED))  # fmt: skip
    return SizeSpec("lognormal", radius=centre, radius_min=lo, radius_max=hi,
                    radius_log_std=t.read("radius_log_std", REQUIRED))  # fmt: skip


def _check_ratio(t: Table, key: str, value, lo: float, hi: float) -> None:
    if hi > MAX_SIZE_RATIO * lo:
        raise t.error(key, value, f"radii within a ratio of {MAX_SIZE_RATIO:g} (largest over "
                      f"smallest: here {hi / lo:.3g}): the neighbour cells are sized by the "
                      "largest sphere, so a step costs the cube of the ratio")  # fmt: skip


def _read_types(t: Table) -> tuple[GrainType, ...]:
    """``[[particles.types]]``: each table a sphere grain type (:data:`PARTICLE_TYPE`)."""
    given = t.read("types")
    for key in SIZE_KEYS:
        if key in t.data:
            raise t.error(key, t.data[key], "given per grain type under [[particles.types]]: "
                          "with types, [particles] gives no size key")  # fmt: skip
    if len(given) > MAX_GRAIN_TYPES:
        raise t.error("types", f"{len(given)} tables", f"1 to {MAX_GRAIN_TYPES} grain types")
    types = []
    for k, data in enumerate(given):
        tt = Table(f"particles.types[{k + 1}]", data, t.source, t.directory, PARTICLE_TYPE)
        tt.check_known()
        dist = tt.read("radius_distribution")
        tt.refuse_foreign(("sphere", dist), _foreign_why("sphere", dist))
        name = tt.read("name") or f"type{k + 1}"
        if any(name == other.name for other in types):
            raise tt.error("name", name, "a name no other grain type has")
        types.append(GrainType(name, tt.read("fraction"), tt.read("density"), _read_size(tt)))
    total = sum(g.fraction for g in types)
    if abs(total - 1.0) > FRACTION_SUM_TOLERANCE:
        raise t.error("types", [g.fraction for g in types], "grain types whose fractions (by "
                      f"number) sum to 1 (these sum to {total:.9g})")  # fmt: skip
    lo = min(g.size.smallest for g in types)
    hi = max(g.size.largest for g in types)
    _check_ratio(t, "types", f"radii {lo:g} to {hi:g} m", lo, hi)
    return tuple(types)


def _read_particles(t: Table) -> ParticlesSpec:
    t.check_known()
    shape = t.read("shape")
    distribution = t.read("radius_distribution")
    # Keys of the other shapes (and size distributions) are refused rather than silently ignored.
    t.refuse_foreign((shape, distribution), _foreign_why(shape, distribution))
    types: tuple[GrainType, ...] = ()
    radius = None
    if shape == "sphere":
        if "types" in t.data:
            types = _read_types(t)
        else:
            size = _read_size(t)
            if size.distribution != "none":
                types = (GrainType("sphere", 1.0, None, size),)
            radius = size.radius
        if types:
            radius = max(g.size.largest for g in types)
    given = {k: t.read(k) for k in DEPTH_KEYS}
    given = {k: v for k, v in given.items() if v is not None}
    if len(given) != 1:
        key = next(iter(given), "count")
        raise t.error(
            key, given.get(key), "exactly one of particles.count, layers, bed_height and "
            f"mass_per_area (given: {', '.join(given) or 'none'})",
        )  # fmt: skip
    spec = ParticlesSpec(
        shape=shape,
        count=given.get("count", 0),  # 0 until a depth is turned into grains (_count_from_depth)
        layers=given.get("layers"),
        bed_height=given.get("bed_height"),
        mass_per_area=given.get("mass_per_area"),
        radius=radius,
        rotation=t.read("rotation"),
        length=t.read("length") if shape == "screw" else None,
        shank_radius=t.read("shank_radius") if shape == "screw" else None,
        head_radius=t.read("head_radius") if shape == "screw" else None,
        mass=t.read("mass"),
        template=t.read("template") if shape == "clump" else None,
        max_bumpiness=t.read("max_bumpiness") if shape == "screw" else None,
        types=types,
    )
    if shape == "clump" and spec.template is None:
        raise t.error("template", None, "a clump template file is required for shape = 'clump'")
    return spec


def _count_from_depth(particles: ParticlesSpec, density: float, trough: TroughSpec,
                      feeder: bool, t: Table) -> ParticlesSpec:  # fmt: skip
    """The grain count of a case that gives a depth (:mod:`dem.scene.depth`) instead of a count."""
    key = next((k for k in depth.DEPTHS if getattr(particles, k) is not None), None)
    if key is None:
        return particles
    value = getattr(particles, key)
    if trough.mesh is not None or feeder:
        where = ("a finite feeder (its feed sets the bed)" if feeder
                 else "a mesh trough (no flat floor of area length x width)")  # fmt: skip
        raise t.error(key, value, f"particles.count for {where}; a depth is for a flat section")
    n = depth.count_for(key, value, particles, density, trough.length * trough.width)
    count = round(n)
    if count < 1 or count > 10**9:
        raise t.error(
            key, value, f"a depth of 1 to 1e9 grains on the section's {trough.length:g} x "
            f"{trough.width:g} m floor (this gives {n:.3g} grains)",
        )  # fmt: skip
    return replace(particles, count=count)


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


def _grain_diameter(particles: ParticlesSpec) -> float:
    """Largest sphere diameter of a grain cross-section, m (a clump's template is built)."""
    if particles.shape == "sphere":
        return 2.0 * particles.radius
    if particles.shape == "screw":
        return 2.0 * max(particles.head_radius, particles.shank_radius)
    return 2.0 * float(max(particles.grain.radii))


def _check_feeder(case: Case, table: Callable[[str], Table]) -> None:
    """A feed zone must hold a grain; a feed rate must be one the zone can be asked for."""
    f = case.feeder
    if f is None:
        return
    if case.particles.grain is not None:
        diameter = 2.0 * case.particles.grain.bounding_radius
    else:
        diameter = _grain_diameter(case.particles)
    if f.feed_rate > 0.0 and f.feed_length < diameter:
        raise table("feeder").error(
            "feed_length", f.feed_length,
            f">= one grain's extent ({diameter:.4g} m), the zone fed grains are dropped into",
        )  # fmt: skip


def _material_density(material: MaterialSpec, particles: ParticlesSpec, t: Table) -> MaterialSpec:
    """Require ``material.density`` unless ``particles.mass`` sets a clump's density.

    Beside the mass it is refused: one of the two would be read and ignored.
    """
    if particles.types:
        missing = [g.name for g in particles.types if g.density is None]
        if missing and material.density is None:
            raise t.error("density", None, "a value is required (the key is missing): the "
                          f"density of grain type {missing[0]!r}, which gives none")  # fmt: skip
        if not missing and material.density is not None:
            raise t.error("density", material.density, "not given when every "
                          "[[particles.types]] table gives its density: it would be read and "
                          "ignored; remove it")  # fmt: skip
        return material
    by_mass = particles.shape != "sphere" and particles.mass is not None
    if by_mass and material.density is not None:
        raise t.error(
            "density", material.density, "not given beside particles.mass: the mass and the "
            "grain's volume set its density; remove one of the two",
        )  # fmt: skip
    if not by_mass and material.density is None:
        raise t.error("density", None, "a value is required (the key is missing), or "
                      "particles.mass for a screw or clump")  # fmt: skip
    return material


def _build_grain(particles: ParticlesSpec, density: float | None, t: Table) -> ParticlesSpec:
    """Attach the grain template of a screw or clump (mass if given, else the density)."""
    from dem.scene import shapes

    if particles.shape == "sphere":
        return particles
    mass = particles.mass
    rho = None if mass is not None else density
    try:
        if particles.shape == "screw":
            grain = shapes.screw(
                particles.length, particles.shank_radius, particles.head_radius,
                mass=mass, density=rho, max_bumpiness=particles.max_bumpiness,
            )  # fmt: skip
        else:
            grain = shapes.clump_from_file(particles.template, mass=mass, density=rho)
    except InputError as exc:
        if exc.source:  # inside the template file: name it, and the key that points to it
            raise InputError(
                exc.key, exc.value, f"{exc.allowed} (the clump template of particles.template "
                f"in {t.source})", source=exc.source,
            ) from exc  # fmt: skip
        raise t.error(exc.key, exc.value, exc.allowed) from exc
    return replace(particles, grain=grain)


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
    particles = _read_particles(table("particles"))
    material = _material_density(material, particles, table("material"))
    if particles.types:  # each type's density; material.density: the bed's, by volume
        from dem.scene.sizes import mean_density

        types = tuple(g if g.density is not None else replace(g, density=material.density)
                      for g in particles.types)  # fmt: skip
        particles = replace(particles, types=types)
        material = replace(material, density=mean_density(types))
    particles = _build_grain(particles, material.density, table("particles"))
    if material.density is None:  # the grain's mass set it
        rho = particles.grain.density
        if not QUANTITIES["density"].accepts(rho):
            raise table("particles").error(
                "mass", particles.mass, f"a grain of plausible density: {particles.mass:g} kg in "
                f"the grain's {particles.grain.volume:.3g} m^3 is {rho:.3g} kg/m^3, outside what "
                f"material.density takes: {QUANTITIES['density'].allowed} (a mass in g for kg?)",
            )  # fmt: skip
        material = replace(material, density=rho)
    particles = _count_from_depth(particles, material.density, trough, "feeder" in data,
                                  table("particles"))  # fmt: skip
    if contact.tangential == "coulomb":
        try:
            tangential.resolve(contact, material, particles)
        except ValueError as exc:
            raise table("material").error(
                "restitution_tangential",
                material.restitution_tangential,
                f"{exc}, when contact.tangential = 'coulomb' derives the tangential spring from "
                "it; or give contact.tangential_stiffness_ratio",
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
    diameter = _grain_diameter(particles)
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
