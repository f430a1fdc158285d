"""The ``[particles]`` table of a case: its grain, its sizes or types, and its depth in grains.

Read by :func:`dem.scene.case.load_case`: the shape and size distribution (or the grain types),
the grain's template and density against ``[material]``, and a depth (``layers``,
``bed_height``, ``mass_per_area``) turned into a grain count on the trough's floor.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from dem.errors import InputError
from dem.scene import depth
from dem.scene.schema import (
    DEPTH_KEYS,
    MAX_DISCRETE_RADII,
    MAX_GRAIN_TYPES,
    PARTICLE_TYPE,
    SHAPES,
    SIZE_KEYS,
)
from dem.scene.spec import (
    GrainType,
    MaterialSpec,
    ParticlesSpec,
    SizeSpec,
    TroughSpec,
)
from dem.scene.tomltable import REQUIRED, Table

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
    types: list[GrainType] = []
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


def read_particles(t: Table) -> ParticlesSpec:
    """The [particles] table as read: shape, sizes or types, the depth given (no grain yet)."""
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
        count=given.get("count", 0),  # 0 until a depth is turned into grains (count_from_depth)
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


def count_from_depth(particles: ParticlesSpec, density: float, trough: TroughSpec,
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


def grain_diameter(particles: ParticlesSpec) -> float:
    """Largest sphere diameter of a grain cross-section, m (a clump's template is built)."""
    if particles.shape == "sphere":
        assert particles.radius is not None  # a sphere's radius is read with its shape
        return 2.0 * particles.radius
    if particles.shape == "screw":
        assert particles.head_radius is not None and particles.shank_radius is not None
        return 2.0 * max(particles.head_radius, particles.shank_radius)
    return 2.0 * float(max(particles.grain.radii))


def material_density(material: MaterialSpec, particles: ParticlesSpec, t: Table) -> MaterialSpec:
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


def build_grain(particles: ParticlesSpec, density: float | None, t: Table) -> ParticlesSpec:
    """Attach the grain template of a screw or clump (mass if given, else the density)."""
    from dem.scene import shapes

    if particles.shape == "sphere":
        return particles
    mass = particles.mass
    rho = None if mass is not None else density
    try:
        if particles.shape == "screw":
            # a screw's keys are required with its shape; max_bumpiness has a default
            assert particles.length is not None and particles.shank_radius is not None
            assert particles.head_radius is not None and particles.max_bumpiness is not None
            grain = shapes.screw(
                particles.length, particles.shank_radius, particles.head_radius,
                mass=mass, density=rho, max_bumpiness=particles.max_bumpiness,
            )  # fmt: skip
        else:
            assert particles.template is not None  # a clump's template is required
            grain = shapes.clump_from_file(particles.template, mass=mass, density=rho)
    except InputError as exc:
        if exc.source:  # inside the template file: name it, and the key that points to it
            raise InputError(
                exc.key, exc.value, f"{exc.allowed} (the clump template of particles.template "
                f"in {t.source})", source=exc.source,
            ) from exc  # fmt: skip
        raise t.error(exc.key, exc.value, exc.allowed) from exc
    return replace(particles, grain=grain)
