"""The case file's schema as data: one table of rows per ``[table]`` of ``case.toml``.

Each row (:class:`dem.scene.tomltable.Key`) names a key, how it is read, the quantity of
:data:`dem.quantities.QUANTITIES` that sets its range, its default, and who reads it: every case
(``"all"``), or the grain shapes or contact laws that do. The readers of :mod:`dem.scene.case`
read every key through its row, a key of a shape or law not chosen is refused by walking the rows
(:meth:`dem.scene.tomltable.Table.refuse_foreign`), and ``tests/scene/test_hostile_input.py`` sends
hostile values to every numeric row: a new key is one row here, its range one row in
:mod:`dem.quantities`, and a field of its spec in :mod:`dem.scene.spec`. The owners of the
``[contact]`` coefficients are taken from the contact-law registry (:mod:`dem.physics.laws`),
which says once which law reads which key.
"""

from __future__ import annotations

from dem.kernels import contact
from dem.physics import laws
from dem.scene.tomltable import REQUIRED, Derived, Key

#: How much grain a case puts in the section: exactly one of these ``[particles]`` keys.
DEPTH_KEYS = ("count", "layers", "bed_height", "mass_per_area")
#: Grain shapes (``particles.shape``).
SHAPES = ("sphere", "screw", "clump")
#: Contact laws (a selector plus a block of its coefficients, as in OpenFOAM and LIGGGHTS).
CONTACT_MODELS = tuple(laws.NORMAL_LAWS)
#: Tangential conventions: the total force capped at Coulomb, or LIGGGHTS's (dem.kernels.contacts).
TANGENTIAL_CONVENTIONS = tuple(sorted(laws.TANGENTIAL_LAWS, key=contact.TANGENTIAL.__getitem__))
#: Where a wall contact's tangential force acts (:data:`dem.kernels.contact.WALL_LEVER_ARMS`).
WALL_LEVER_ARMS = ("surface", "midpoint", "radius")
#: The slip velocity's lever arms (:data:`dem.kernels.contact.SLIP_LEVER_ARMS`).
SLIP_LEVER_ARMS = ("contact", "radius")
#: Engines a run can step on (``run.device``): numba on the CPU, or numba.cuda on a GPU
#: (:mod:`dem.engine.device` says what the GPU engine refuses).
DEVICES = ("cpu", "cuda")
#: Size distributions of a sphere grain (``particles.radius_distribution``, and each
#: ``[[particles.types]]`` table's): one radius, uniform in [radius_min, radius_max], a normal
#: or a lognormal truncated to [radius_min, radius_max], or a discrete list of radii
#: (:mod:`dem.scene.sizes`).
RADIUS_DISTRIBUTIONS = ("none", "uniform", "normal", "lognormal", "discrete")
#: Most grain types of one case (``[[particles.types]]``).
MAX_GRAIN_TYPES = 16
#: Most radii of a discrete size distribution (``radii``).
MAX_DISCRETE_RADII = 64
#: Screw resolution when ``particles.max_bumpiness`` is omitted (:func:`dem.scene.shapes.screw`).
DEFAULT_MAX_BUMPINESS = 0.25


def _number(name: str, default=REQUIRED, quantity: str | None = None, **kw) -> Key:
    return Key(name, "number", quantity or name, default, **kw)


def _whole(name: str, default=REQUIRED, **kw) -> Key:
    return Key(name, "whole", name, default, **kw)


def law_owners(key: str) -> tuple[str, ...]:
    """The laws that read the ``[contact]`` coefficient ``key`` (:mod:`dem.physics.laws`).

    A normal law by its name; a tangential law by its name where it reads the key under every
    normal law, else as ``"tangential+model"`` for each normal law it reads it under.
    """
    owners = [name for name, law in laws.NORMAL_LAWS.items() if key in law.keys]
    for name, law in laws.TANGENTIAL_LAWS.items():
        models = [model for model, keys in law.keys.items() if key in keys]
        if models and len(models) == len(law.keys):
            owners.append(name)
        else:
            owners += [f"{name}+{model}" for model in models]
    return tuple(owners)


TROUGH = (
    _number("length"),
    _number("width"),
    _number("inclination", 0.0),
    Key("mesh", "path", default=None),
)
DRIVE = (
    _number("frequency"),
    _number("angle"),
    _number("amplitude", None),  # exactly one of amplitude and throw_number
    _number("throw_number", None),
    _number("second_amplitude", 0.0),
    _number("second_angle"),  # given only with second_amplitude > 0
    _number("second_phase", 0.0),
    _number("ramp_cycles", 0.0),
)
MATERIAL = (
    _number("density", None),  # required unless particles.mass sets it
    _number("friction"),
    _number("restitution_normal", 0.0, "restitution"),
    _number("restitution_tangential", 0.8, "restitution"),
    _number("rolling_friction", 0.0),
)
#: [wall]: a key not given is the material's (None).
WALL = (
    _number("friction", None),
    _number("restitution_normal", None, "restitution"),
    _number("restitution_tangential", None, "restitution"),
    _number("rolling_friction", None),
)
CONTACT = (
    Key("model", "choice", default="hertz_mindlin", choices=CONTACT_MODELS),
    _number("youngs_modulus", owners=law_owners("youngs_modulus")),
    _number("poisson_ratio", 0.3, owners=law_owners("poisson_ratio")),
    _number("stiffness", owners=law_owners("stiffness")),
    _number(
        "tangential_stiffness_ratio",
        Derived("from eps_t under 'coulomb'; 2/7 for 'linear' under 'liggghts'"),
        owners=law_owners("tangential_stiffness_ratio"),
    ),
    _number(  # None: dem.config.DEM_TANGENTIAL_DAMPING_RATIO
        "tangential_damping_ratio", None, owners=law_owners("tangential_damping_ratio")
    ),
    Key("tangential", "choice", default="impact", choices=TANGENTIAL_CONVENTIONS),
    Key("limit_force", "boolean", default=False),
    Key("wall_lever_arm", "choice", default="surface", choices=WALL_LEVER_ARMS),
    Key("slip_lever_arm", "choice", default="contact", choices=SLIP_LEVER_ARMS),
)
PARTICLES = (
    Key("shape", "choice", default="sphere", choices=SHAPES),
    _whole("count", None),  # exactly one of count and the depths (DEPTH_KEYS)
    _number("layers", None),
    _number("bed_height", None),
    _number("mass_per_area", None),
    _number("radius", owners=("sphere",)),
    *(
        # a sphere's size distribution (dem.scene.sizes); owned by the distributions that read
        # them, and refused for screws and clumps through radius_distribution's owner
        Key(
            "radius_distribution",
            "choice",
            default="none",
            choices=RADIUS_DISTRIBUTIONS,
            owners=("sphere",),
        ),
        _number("radius_min", None, "radius", owners=("uniform", "normal", "lognormal")),
        _number("radius_max", None, "radius", owners=("uniform", "normal", "lognormal")),
        _number("radius_std", None, "radius", owners=("normal",)),
        _number("radius_log_std", None, owners=("lognormal",)),
        Key("radii", "numbers", "radius", default=None, owners=("discrete",)),
        Key("radius_fractions", "numbers", "fraction", default=None, owners=("discrete",)),
    ),
    # several sphere grain types, [[particles.types]] (each table's keys: PARTICLE_TYPE)
    Key("types", "tables", default=None, owners=("sphere",)),
    Key("rotation", "boolean", default=True),
    _number("length", owners=("screw",)),
    _number("shank_radius", quantity="radius", owners=("screw",)),
    _number("head_radius", quantity="radius", owners=("screw",)),
    _number("mass", None, owners=("screw", "clump")),  # None: density times the volume
    Key("template", "path", owners=("clump",)),
    _number("max_bumpiness", DEFAULT_MAX_BUMPINESS, owners=("screw",)),
)
#: The keys of the size distribution, read from [particles] or from each grain type's table.
SIZE_KEYS = ("radius", "radius_distribution", "radius_min", "radius_max", "radius_std",
             "radius_log_std", "radii", "radius_fractions")  # fmt: skip
#: One ``[[particles.types]]`` table: a sphere grain type with its share of the grains, its
#: density and its size distribution (the size keys of [particles], same rows).
PARTICLE_TYPE = (
    Key("name", "name", default=None),  # None: "type1", "type2", ... in table order
    _number("fraction"),  # by number of grains; the types' fractions sum to 1
    _number("density", None),  # None: material.density
    *(k for k in PARTICLES if k.name in SIZE_KEYS),
)
RUN = (
    _whole("settle_cycles", 10, auto=True),
    _whole("cycles", 30),
    _number("timestep", None, auto=True),  # None: from the stiffest contact
    _whole("seed", 1),
    _whole("replicas", 1),
    _number("target_error", None),  # None: run.replicas fills, whatever their error
    _whole("max_replicas", 12),
    Key("device", "choice", default="cpu", choices=DEVICES),
)
OUTPUT = (
    _whole("frames_per_cycle", 4),
    _whole("flight_phases", 0),
    Key("contacts", "boolean", default=False),
)
#: [feeder]: its presence makes the trough finite.
FEEDER = (
    _number("feed_rate", 0.0),
    _number("feed_length", Derived("0.25 trough.length"), "length"),
)

#: Every table of a case file, in the order errors list them.
SCHEMA: dict[str, tuple[Key, ...]] = {
    "trough": TROUGH,
    "drive": DRIVE,
    "material": MATERIAL,
    "wall": WALL,
    "contact": CONTACT,
    "particles": PARTICLES,
    "run": RUN,
    "output": OUTPUT,
    "feeder": FEEDER,
}
