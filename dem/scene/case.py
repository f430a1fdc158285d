"""Case files: ``cases/NAME/case.toml`` -> one validated, frozen :class:`Case`.

Everything a run needs is checked here, once, before anything runs (DESIGN.md section 6): every
key is known, has the right type and lies in its allowed range, and the drive is resolved so that
both the amplitude A and the throw number Gamma are available,

    Gamma = A omega^2 sin(phi) / (g cos(alpha)),   omega = 2 pi f,   g = dem.config.GRAVITY,

with phi the vibration angle and alpha the trough inclination. A bad value raises
:class:`dem.errors.InputError` naming the dotted key (``particles.radius``), the value, what is
allowed, and the file.

Units are SI; angles stay in degrees in the dataclasses (as in the file) and are converted to
radians by the code that uses them.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from dem.errors import InputError
from dem.physics import drive, laws, tangential
from dem.scene.tomltable import Table, suggest

#: File name of a case inside its directory.
CASE_FILE = "case.toml"

#: Grain shapes the schema knows.
SHAPES = ("sphere", "screw", "clump")
#: Grain shapes the engine can run today. Lifting a restriction is adding the name here.
SUPPORTED_SHAPES = ("sphere", "screw", "clump")
#: Whether the engine runs troughs from a mesh file (``trough.mesh``); until it does, the key is
#: refused when the case is loaded, not when it is run.
MESH_TROUGHS = True
#: Contact laws (a selector plus a block of its coefficients, as in OpenFOAM and LIGGGHTS).
CONTACT_MODELS = ("hertz_mindlin", "linear")
#: Tangential conventions: the total force capped at Coulomb, or LIGGGHTS's (dem.kernels.contacts).
TANGENTIAL_CONVENTIONS = ("coulomb", "liggghts", "impact")
#: Where a wall contact's tangential force acts (:data:`dem.kernels.contacts.WALL_LEVER_ARMS`).
WALL_LEVER_ARMS = ("surface", "midpoint")
#: Default k_t / k_n of the linear model under ``tangential = "liggghts"``: 2/7 makes the
#: tangential and normal oscillations of a solid sphere equally fast (Shaefer et al. 1996).
DEFAULT_TANGENTIAL_STIFFNESS_RATIO = 2.0 / 7.0
#: Screw resolution when ``particles.max_bumpiness`` is omitted (:func:`dem.scene.shapes.screw`).
DEFAULT_MAX_BUMPINESS = 0.25


@dataclass(frozen=True)
class TroughSpec:
    """Periodic section of the trough (DESIGN.md section 2).

    Attributes:
        length: Length of the periodic section along x, m.
        width: Distance between the side walls at y = +-width/2, m.
        inclination: alpha, deg; > 0 means the trough rises in +x.
        mesh: Absolute path of an STL trough (U or V section), or None for a flat floor.

    """

    length: float
    width: float
    inclination: float = 0.0
    mesh: Path | None = None


@dataclass(frozen=True)
class DriveSpec:
    """The trough's drive: the paper's straight line, optionally a second component and a ramp.

    s(t) = r(t) [A sin(omega t) (cos phi, 0, sin phi) + A_2 sin(omega t + psi_2) (cos phi_2, 0,
    sin phi_2)] (:class:`dem.physics.drive.Motion`): the first component is the paper's drive, a
    second
    one out of phase with it makes the drive elliptical, and r(t) rises smoothly from 0 to 1 over
    ``ramp_cycles`` cycles (:func:`dem.physics.drive.ramp`).

    Attributes:
        frequency: f, Hz.
        angle: Vibration angle phi of the first component, deg, in (0, 90).
        amplitude: A of the first component, m.
        throw_number: Gamma = A omega^2 sin(phi) / (g cos(alpha)) of the first component.
        given: Which of ``"amplitude"`` and ``"throw_number"`` the file gave; the other was
            computed from it.
        second_amplitude: A_2, m (0: no second component).
        second_angle: phi_2, deg, in [0, 180).
        second_phase: psi_2, deg, the second component's lead over the first.
        ramp_cycles: Drive cycles of the start-up ramp (0: none).

    """

    frequency: float
    angle: float
    amplitude: float
    throw_number: float
    given: str
    second_amplitude: float = 0.0
    second_angle: float = 0.0
    second_phase: float = 0.0
    ramp_cycles: float = 0.0

    @property
    def omega(self) -> float:
        """Angular frequency omega = 2 pi f, rad/s (:func:`dem.physics.drive.omega`)."""
        return drive.omega(self.frequency)

    @property
    def motion(self) -> drive.Motion:
        """The trough's motion s(t) (:class:`dem.physics.drive.Motion`)."""
        components = [drive.Component(self.amplitude, math.radians(self.angle))]
        if self.second_amplitude > 0.0:
            components.append(
                drive.Component(
                    self.second_amplitude,
                    math.radians(self.second_angle),
                    math.radians(self.second_phase),
                )
            )
        return drive.Motion(self.omega, tuple(components), self.ramp_cycles / self.frequency)

    @property
    def elliptical(self) -> bool:
        """Whether the trough moves on an ellipse (two components out of phase), not a line."""
        return self.second_amplitude > 0.0 and not self.motion.is_line

    @property
    def velocity_scale(self) -> float:
        """The normalising velocity, m/s: A omega cos(phi) for the paper's drive, else |X| omega.

        |X| omega is the peak trough speed along the trough
        (:attr:`dem.physics.drive.Motion.velocity_scale`).
        """
        if self.second_amplitude == 0.0:
            return drive.drive_velocity_from_omega(self.amplitude, self.omega, self.angle)
        return self.motion.velocity_scale

    @property
    def peak_speed(self) -> float:
        """Largest trough speed over a cycle, m/s (A omega for the paper's drive)."""
        if self.second_amplitude == 0.0:
            return self.amplitude * self.omega
        return self.motion.peak_speed

    def effective_throw_number(self, inclination: float) -> float:
        """Peak normal trough acceleration over g cos(alpha) (``throw_number`` for a line drive).

        ``inclination`` alpha in degrees (:meth:`dem.physics.drive.Motion.throw_number`).
        """
        if self.second_amplitude == 0.0:
            return self.throw_number
        return self.motion.throw_number(inclination)


@dataclass(frozen=True)
class MaterialSpec:
    """Grain material, shared by grain-grain and grain-wall contacts.

    Attributes:
        density: rho, kg/m^3. Given in the file for spheres and for clumps without
            ``particles.mass``; with a mass it is refused there and set here to the grain's own
            density (mass / union volume), so every reader finds the density the run uses.
        friction: Coulomb coefficient mu >= 0.
        restitution_normal: eps_n in [0, 1]; 0 maps to critical damping.
        restitution_tangential: eps_t in [0, 1], the paper's Eq. (12): sets the point-mass
            prediction, the calibration target and, with ``contact.tangential = "coulomb"`` and no
            ``tangential_stiffness_ratio``, the tangential spring (:mod:`dem.physics.tangential`).
        rolling_friction: Rolling resistance coefficient mu_r >= 0 (0: none).

    """

    density: float
    friction: float
    restitution_normal: float = 0.0
    restitution_tangential: float = 0.8
    rolling_friction: float = 0.0


@dataclass(frozen=True)
class WallSpec:
    """Grain-wall interaction (floor, side walls, back wall, mesh triangles): ``[wall]``.

    A value ``[wall]`` does not give is None here and the material's in use
    (:attr:`Case.wall_material`), so a case whose material is changed (``dataclasses.replace``,
    a study) keeps its walls of the new material. The contact stiffness is the material's (the
    wall is as stiff as the grains, as in LIGGGHTS with one Young's modulus). The point-mass
    model sees the wall's values: its grain touches only the floor.

    Attributes:
        friction: mu between a grain and a wall.
        restitution_normal: eps_n of a grain-wall impact.
        restitution_tangential: eps_t of a grain-wall impact (the paper's floor landing).
        rolling_friction: mu_r between a grain and a wall.

    """

    friction: float | None = None
    restitution_normal: float | None = None
    restitution_tangential: float | None = None
    rolling_friction: float | None = None

    @property
    def given(self) -> tuple[str, ...]:
        """The keys ``[wall]`` gave."""
        return tuple(k for k in _WALL_KEYS if getattr(self, k) is not None)

    def over(self, material: MaterialSpec) -> MaterialSpec:
        """``material`` with the values given here."""
        return replace(material, **{k: getattr(self, k) for k in self.given})


@dataclass(frozen=True)
class ContactSpec:
    """Contact law selector and its coefficients.

    Attributes:
        model: ``"hertz_mindlin"`` (needs ``youngs_modulus``) or ``"linear"`` (needs
            ``stiffness``).
        youngs_modulus: Y, Pa (Hertz-Mindlin), else None.
        poisson_ratio: nu in (-1, 0.5); Hertz-Mindlin uses G = Y / (2 (1 + nu)).
        stiffness: Normal spring constant k_n, N/m (linear), else None.
        tangential_stiffness_ratio: kappa = k_t / k_n (Hertz-Mindlin with "coulomb": k_t over
            the tangent normal stiffness S_n). None: derived from eps_t ("coulomb",
            :mod:`dem.physics.tangential`), 2/7 (linear, "liggghts"); Hertz-Mindlin with "liggghts"
            takes k_t from G and refuses the key.
        limit_force: True keeps the normal force repulsive (LIGGGHTS ``limitForce on``).
        tangential: ``"impact"`` (eps_t delivered by each impact, capped by Coulomb, then a
            rigid Coulomb stick), ``"coulomb"`` (one spring-dashpot, total tangential force
            capped at mu |F_n|) or ``"liggghts"`` (spring capped, dashpot on top), see
            :mod:`dem.kernels.contacts`. "impact" refuses the tangential spring's keys.
        tangential_damping_ratio: zeta_t of "coulomb" (None: the default,
            :data:`dem.config.DEM_TANGENTIAL_DAMPING_RATIO`); "liggghts" refuses it.
        wall_lever_arm: Where a wall contact's tangential force acts: ``"surface"`` (default,
            r - delta from the centre: the point on the wall) or ``"midpoint"`` (r - delta / 2,
            as LIGGGHTS 3.8's walls), :data:`dem.kernels.contacts.WALL_LEVER_ARMS`.

    """

    model: str
    youngs_modulus: float | None
    poisson_ratio: float
    stiffness: float | None
    tangential_stiffness_ratio: float | None
    limit_force: bool = False
    tangential: str = "impact"
    tangential_damping_ratio: float | None = None
    wall_lever_arm: str = "surface"


@dataclass(frozen=True)
class ParticlesSpec:
    """The grains.

    Attributes:
        shape: ``"sphere"``, ``"screw"`` or ``"clump"``.
        count: Number of grains N >= 1.
        radius: Sphere radius, m (sphere), else None.
        rotation: False locks rotation (a sliding block, the point mass's DEM twin).
        length: Screw length, m (screw, reserved).
        shank_radius: Screw shank sphere radius, m (screw, reserved).
        head_radius: Screw head sphere radius, m (screw, reserved).
        mass: Target grain mass, kg (screw, clump); None: material.density times the union
            volume.
        template: Absolute path of a clump template, lines ``x y z r`` in metres (clump).
        max_bumpiness: Screw resolution (screw): the deepest valley between neighbouring shank
            spheres as a fraction of the shank radius, 0 < b <= 1; a smaller b takes more
            spheres per screw (:func:`dem.scene.shapes.screw`). Default 0.25: 8 spheres for the
            shipped screw.
        grain: The :class:`dem.scene.shapes.Template` built at load (screw, clump), else None; not
            part of :meth:`Case.as_dict`.

    """

    shape: str
    count: int
    radius: float | None
    rotation: bool = True
    length: float | None = None
    shank_radius: float | None = None
    head_radius: float | None = None
    mass: float | None = None
    template: Path | None = None
    max_bumpiness: float | None = None
    grain: Any = field(default=None, repr=False, compare=False)


@dataclass(frozen=True)
class RunSpec:
    """Length of a run.

    Attributes:
        settle_cycles: Drive cycles run before measuring (after the fill has come to rest);
            None ("auto" in the file): until the transient of the per-cycle velocity has ended
            (:func:`dem.physics.measure.steady`), at most ``DEM_AUTO_SETTLE_MAX_CYCLES``.
        cycles: Drive cycles measured.
        timestep: dt, s, or None for automatic (from the stiffest contact).
        seed: Seed of the random generator (insertion positions).
        replicas: Independent fills run and pooled (seeds ``seed``, ``seed + 1``, ...;
            :func:`dem.physics.measure.pooled`); 1: one run, whose error bar excludes the
            fill-to-fill
            spread.

    """

    settle_cycles: int | None = 10
    cycles: int = 30
    timestep: float | None = None
    seed: int = 1
    replicas: int = 1


@dataclass(frozen=True)
class OutputSpec:
    """What is written.

    Attributes:
        frames_per_cycle: Particle frames written per measured drive cycle.

    """

    frames_per_cycle: int = 4


@dataclass(frozen=True)
class FeederSpec:
    """A finite feeder (:mod:`dem.engine.feeder`): back wall at x = 0, discharge edge at x = length.

    Attributes:
        feed_rate: Mass fed at the back per second, kg/s (0: the initial charge is emptied).
        feed_length: Length of the feed zone at the back, m.

    """

    feed_rate: float = 0.0
    feed_length: float = 0.0


@dataclass(frozen=True)
class Case:
    """A validated case.

    Attributes:
        name: Name of the case directory.
        directory: Absolute path of the case directory.
        source: Absolute path of the case.toml it was read from.
        overrides: The ``table.key`` values set over the file when it was read (``dem run
            --set``, a sweep point), as given; the other fields already hold them.

    """

    name: str
    directory: Path
    source: Path
    trough: TroughSpec
    drive: DriveSpec
    material: MaterialSpec
    contact: ContactSpec
    particles: ParticlesSpec
    run: RunSpec
    output: OutputSpec
    feeder: FeederSpec | None = None
    overrides: dict = field(default_factory=dict, compare=False)
    wall: WallSpec | None = None

    @property
    def wall_material(self) -> MaterialSpec:
        """The material a grain-wall contact uses: the grains' with ``[wall]``'s values."""
        return self.material if self.wall is None else self.wall.over(self.material)

    def with_drive(
        self,
        *,
        frequency: float | None = None,
        angle: float | None = None,
        amplitude: float | None = None,
        throw_number: float | None = None,
    ) -> Case:
        """The case with drive values changed and the dependent one recomputed.

        Give at most one of amplitude and throw_number; without either, the quantity the case
        gave is held (a throw-number case keeps Gamma at a new angle and its amplitude follows).
        ``dataclasses.replace`` on the drive would leave A and Gamma inconsistent.
        """
        d = self.drive
        if amplitude is None and throw_number is None:
            if d.given == "amplitude":
                amplitude = d.amplitude
            else:
                throw_number = d.throw_number
        drive = resolve_drive(
            d.frequency if frequency is None else frequency,
            d.angle if angle is None else angle,
            self.trough.inclination,
            amplitude=amplitude,
            throw_number=throw_number,
        )
        drive = replace(
            drive,
            second_amplitude=d.second_amplitude,
            second_angle=d.second_angle,
            second_phase=d.second_phase,
            ramp_cycles=d.ramp_cycles,
        )
        return replace(self, drive=drive)

    def with_tangential(self, tangential: str) -> Case:
        """The case under another tangential convention, with the keys that one refuses cleared.

        ``"liggghts"`` makes a dem run equivalent to the case's exported LIGGGHTS deck: Hertz
        takes Mindlin's k_t, linear keeps its k_t / k_n (2/7 if it was derived from eps_t).
        """
        if tangential not in TANGENTIAL_CONVENTIONS:
            raise ValueError(f"tangential must be one of {TANGENTIAL_CONVENTIONS}")
        c = self.contact
        ratio = c.tangential_stiffness_ratio
        if tangential == "liggghts":
            if c.model == "hertz_mindlin":
                ratio = None
            elif ratio is None:
                ratio = DEFAULT_TANGENTIAL_STIFFNESS_RATIO
        damping = None if tangential == "liggghts" else c.tangential_damping_ratio
        if tangential == "impact":
            ratio, damping = None, None
        contact = replace(
            c,
            tangential=tangential,
            tangential_stiffness_ratio=ratio,
            tangential_damping_ratio=damping,
        )
        return replace(self, contact=contact)

    def as_dict(self) -> dict[str, Any]:
        """Return the resolved case as plain data (paths as strings; None kept), for output."""

        def plain(value: Any) -> Any:
            if isinstance(value, dict):
                return {k: plain(v) for k, v in value.items()}
            if isinstance(value, Path):
                return str(value)
            return value

        data = plain(asdict(replace(self, particles=replace(self.particles, grain=None))))
        data["particles"].pop("grain")
        data.pop("overrides")  # already in the values; summary.json records them apart
        return data


# --- reading -------------------------------------------------------------------------------------

# --- one reader per table ------------------------------------------------------------------------

_TROUGH_KEYS = ("length", "width", "inclination", "mesh")
_DRIVE_KEYS = (
    "frequency",
    "angle",
    "amplitude",
    "throw_number",
    "second_amplitude",
    "second_angle",
    "second_phase",
    "ramp_cycles",
)
_MATERIAL_KEYS = (
    "density",
    "friction",
    "restitution_normal",
    "restitution_tangential",
    "rolling_friction",
)
_CONTACT_KEYS = (
    "model",
    "youngs_modulus",
    "poisson_ratio",
    "stiffness",
    "tangential_stiffness_ratio",
    "tangential_damping_ratio",
    "tangential",
    "limit_force",
    "wall_lever_arm",
)
_PARTICLES_KEYS = (
    "shape",
    "count",
    "radius",
    "rotation",
    "length",
    "shank_radius",
    "head_radius",
    "mass",
    "template",
    "max_bumpiness",
)
_RUN_KEYS = ("settle_cycles", "cycles", "timestep", "seed", "replicas")
_OUTPUT_KEYS = ("frames_per_cycle",)
_FEEDER_KEYS = ("feed_rate", "feed_length")


def _read_trough(t: Table) -> TroughSpec:
    t.check_known(_TROUGH_KEYS)
    return TroughSpec(
        length=t.quantity("length"),
        width=t.quantity("width"),
        inclination=t.quantity("inclination", 0.0),
        mesh=_read_mesh(t),
    )


def _read_mesh(t: Table) -> Path | None:
    """The mesh file, read and checked now (format, triangles, extent against length and width)."""
    mesh = t.path("mesh")
    if mesh is None:
        return None
    if not MESH_TROUGHS:
        raise t.error(
            "mesh", t.data["mesh"], "no mesh troughs yet: a flat floor and side walls (remove it)"
        )
    from dem.scene.mesh import load_mesh

    length, width = t.quantity("length"), t.quantity("width")
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
    """Refuse a trough steeper than the floor's friction angle atan(mu), either way.

    There no friction holds a grain on the floor: the bed slides downhill ever faster, the
    periodic section has no steady conveying velocity to measure, and the run would end only when
    a grain outran the instability check. Refused, not warned: no run of it gives a result.
    """
    limit = math.degrees(math.atan(floor.friction))
    key = "wall.friction" if by_wall else "material.friction"
    if abs(trough.inclination) > limit:
        raise t.error(
            "inclination", trough.inclination,
            f"within the friction angle atan({key} = {floor.friction:g}) = "
            f"{limit:.4g} deg: [-{limit:.4g}, {limit:.4g}] degrees (steeper, no friction holds a "
            "grain on the floor and the bed slides downhill ever faster)",
        )  # fmt: skip


def _read_drive(t: Table, inclination: float) -> DriveSpec:
    t.check_known(_DRIVE_KEYS)
    frequency = t.quantity("frequency")
    angle = t.quantity("angle")
    amplitude = t.quantity("amplitude", None)
    throw_number = t.quantity("throw_number", None)
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
    return replace(spec, **second, ramp_cycles=t.quantity("ramp_cycles", 0.0))


def _read_second_component(t: Table) -> dict:
    """The second drive component's keys; its angle and phase mean nothing without amplitude."""
    amplitude = t.quantity("second_amplitude", 0.0)
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
        "second_angle": t.quantity("second_angle"),
        "second_phase": t.quantity("second_phase", 0.0),
    }


def resolve_drive(
    frequency: float,
    angle: float,
    inclination: float,
    *,
    amplitude: float | None = None,
    throw_number: float | None = None,
) -> DriveSpec:
    """The drive from exactly one of amplitude (m) and throw_number; the other is computed.

    Gamma = A omega^2 sin(phi) / (g cos(alpha)) (:mod:`dem.physics.drive`), phi = ``angle`` and
    alpha = ``inclination`` in degrees. Values are not range-checked here (``load_case`` checks
    a file's values first).
    """
    if (amplitude is None) == (throw_number is None):
        raise ValueError("give exactly one of amplitude and throw_number")
    given = "amplitude" if amplitude is not None else "throw_number"
    if amplitude is not None:
        throw_number = drive.throw_number(amplitude, frequency, angle, inclination)
    else:
        amplitude = drive.amplitude(throw_number, frequency, angle, inclination)
    return DriveSpec(frequency, angle, amplitude, throw_number, given)


_WALL_KEYS = ("friction", "restitution_normal", "restitution_tangential", "rolling_friction")


def _read_wall(t: Table) -> WallSpec:
    """``[wall]``: the keys given (the others are the material's)."""
    t.check_known(_WALL_KEYS)
    return WallSpec(**{
        key: t.quantity(key, None, "restitution" if key.startswith("restitution") else None)
        for key in _WALL_KEYS
    })  # fmt: skip


def _read_material(t: Table) -> MaterialSpec:
    t.check_known(_MATERIAL_KEYS)
    return MaterialSpec(
        density=t.quantity("density", None),
        friction=t.quantity("friction"),
        restitution_normal=t.quantity("restitution_normal", 0.0, "restitution"),
        restitution_tangential=t.quantity("restitution_tangential", 0.8, "restitution"),
        rolling_friction=t.quantity("rolling_friction", 0.0),
    )


def _read_contact(t: Table) -> ContactSpec:
    t.check_known(_CONTACT_KEYS)
    model = t.choice("model", CONTACT_MODELS, "hertz_mindlin")
    tangential = t.choice("tangential", TANGENTIAL_CONVENTIONS, "impact")
    # Coefficients the chosen laws do not read are refused rather than silently ignored.
    for key in laws.foreign_keys(model, tangential):
        if key in t.data:
            raise t.error(
                key,
                t.data[key],
                f"not a coefficient of contact.model = {model!r} with contact.tangential = "
                f"{tangential!r}; remove it",
            )
    hertz = model == "hertz_mindlin"
    ratio = None
    if "tangential_stiffness_ratio" in t.data:
        ratio = t.quantity("tangential_stiffness_ratio")
    elif not hertz and tangential == "liggghts":
        ratio = DEFAULT_TANGENTIAL_STIFFNESS_RATIO
    damping = None
    if "tangential_damping_ratio" in t.data:
        damping = t.quantity("tangential_damping_ratio")
    return ContactSpec(
        model=model,
        youngs_modulus=t.quantity("youngs_modulus") if hertz else None,
        poisson_ratio=t.quantity("poisson_ratio", 0.3),
        stiffness=None if hertz else t.quantity("stiffness"),
        tangential_stiffness_ratio=ratio,
        limit_force=t.boolean("limit_force", False),
        tangential=tangential,
        tangential_damping_ratio=damping,
        wall_lever_arm=t.choice("wall_lever_arm", WALL_LEVER_ARMS, "surface"),
    )


def _read_particles(t: Table) -> ParticlesSpec:
    t.check_known(_PARTICLES_KEYS)
    shape = t.choice("shape", SHAPES, "sphere")
    # Keys of the other shapes are refused rather than silently ignored.
    own = {
        "sphere": ("radius",),
        "screw": ("length", "shank_radius", "head_radius", "mass", "max_bumpiness"),
        "clump": ("template", "mass"),
    }
    for other, keys in own.items():
        for key in keys:
            if other != shape and key in t.data and key not in own[shape]:
                raise t.error(key, t.data[key], f"a key of shape = {other!r}, not of {shape!r}")
    count = t.whole("count")
    spec = ParticlesSpec(
        shape=shape,
        count=count,
        radius=t.quantity("radius") if shape == "sphere" else None,
        rotation=t.boolean("rotation", True),
        length=t.quantity("length") if shape == "screw" else None,
        shank_radius=t.quantity("shank_radius", name="radius") if shape == "screw" else None,
        head_radius=t.quantity("head_radius", name="radius") if shape == "screw" else None,
        mass=t.quantity("mass", None),
        template=t.path("template") if shape == "clump" else None,
        max_bumpiness=t.quantity("max_bumpiness", DEFAULT_MAX_BUMPINESS)
        if shape == "screw"
        else None,
    )
    if shape == "clump" and spec.template is None:
        raise t.error("template", None, "a clump template file is required for shape = 'clump'")
    if shape not in SUPPORTED_SHAPES:
        raise t.error(
            "shape",
            shape,
            f"one of {', '.join(map(repr, SUPPORTED_SHAPES))}: shape {shape!r} is not supported "
            "yet",
        )
    return spec


def _read_run(t: Table) -> RunSpec:
    t.check_known(_RUN_KEYS)
    timestep = t.data.get("timestep", "auto")
    if timestep == "auto":
        dt = None
    else:
        dt = t.quantity("timestep")
    settle = None if t.data.get("settle_cycles") == "auto" else t.whole("settle_cycles", 10)
    seed, replicas = t.whole("seed", 1), t.whole("replicas", 1)
    if seed + replicas - 1 >= 2**63:
        raise t.error("seed", seed, f"< 2^63 - {replicas - 1}: replica k is seeded seed + k")
    return RunSpec(
        settle_cycles=settle,
        cycles=t.whole("cycles", 30),
        timestep=dt,
        seed=seed,
        replicas=replicas,
    )


def _read_feeder(t: Table, length: float) -> FeederSpec:
    """The [feeder] table (its presence makes the trough finite)."""
    t.check_known(_FEEDER_KEYS)
    rate = t.quantity("feed_rate", 0.0)
    zone = t.quantity("feed_length", 0.25 * length, "length")
    if zone > length:
        raise t.error(
            "feed_length", zone, f"<= trough.length = {length:g} m (the zone lies in the trough)"
        )
    return FeederSpec(feed_rate=rate, feed_length=zone)


def _check_feeder(case: Case, table: Callable[[str], Table]) -> None:
    """A feed zone must hold a grain; a feed rate must be one the zone can be asked for."""
    f = case.feeder
    if f is None:
        return
    diameter = _grain_diameter(case.particles) or 0.0
    if case.particles.grain is not None:
        diameter = 2.0 * case.particles.grain.bounding_radius
    if f.feed_rate > 0.0 and f.feed_length < diameter:
        raise table("feeder").error(
            "feed_length", f.feed_length,
            f">= one grain's extent ({diameter:.4g} m), the zone fed grains are dropped into",
        )  # fmt: skip


def _read_output(t: Table) -> OutputSpec:
    t.check_known(_OUTPUT_KEYS)
    return OutputSpec(frames_per_cycle=t.whole("frames_per_cycle", 4))


_TABLES = (
    "trough", "drive", "material", "wall", "contact", "particles", "run", "output", "feeder",
)  # fmt: skip


def _grain_diameter(particles: ParticlesSpec) -> float | None:
    """Largest sphere diameter of a grain cross-section, m, where the schema knows it."""
    if particles.shape == "sphere":
        return 2.0 * particles.radius
    if particles.shape == "screw":
        return 2.0 * max(particles.head_radius, particles.shank_radius)
    if particles.grain is not None:
        return 2.0 * float(max(particles.grain.radii))
    return None


def _material_density(material: MaterialSpec, particles: ParticlesSpec, t: Table) -> MaterialSpec:
    """Require ``material.density`` unless ``particles.mass`` sets a clump's density.

    Beside the mass it is refused: one of the two would be read and ignored.
    """
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


def load_case(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Case:
    """Read and validate a case.

    Args:
        path: A case directory (holding ``case.toml``) or the ``case.toml`` itself.
        overrides: Keys to set before validation, ``{"drive.angle": 30.0}`` (a study or a sweep
            point); the value None removes the key. Values are checked exactly as if they had
            been written in the file.

    Returns:
        The validated case; relative paths in the file are resolved against its directory.

    Raises:
        InputError: The file is missing, is not valid TOML, or a key is unknown, missing, of the
            wrong type or out of range. The message names the key, the value, the allowed range
            and the file.

    """
    path = Path(path).expanduser().resolve()
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
        return Table(name, data.get(name, {}), where, directory)

    trough = _read_trough(table("trough"))
    drive = _read_drive(table("drive"), trough.inclination)
    material = _read_material(table("material"))
    wall = _read_wall(table("wall"))
    _check_inclination(trough, wall.over(material), "friction" in wall.given, table("trough"))
    contact = _read_contact(table("contact"))
    particles = _read_particles(table("particles"))
    material = _material_density(material, particles, table("material"))
    particles = _build_grain(particles, material.density, table("particles"))
    if material.density is None:  # the grain's mass set it
        material = replace(material, density=particles.grain.density)
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
    if diameter is not None and trough.width < diameter:
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
    _check_engine(case, table)
    return case


def _apply_overrides(data: dict, overrides: Mapping[str, Any], where: str) -> None:
    """Set ``table.key`` values in the parsed file ``data`` (None removes the key)."""
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
    r_max = pt.radius if pt.shape == "sphere" else None
    reach = 0.0
    if pt.grain is not None:
        r_max = float(max(pt.grain.radii))
        reach = float(max(math.hypot(*c) for c in pt.grain.centres))
    if r_max is not None:
        skin = config.DEM_SKIN_FRACTION * r_max  # the Simulation's default skin
        check_section_length(length, r_max, skin, reach, source=str(case.source))
    step = timestep_for(case)  # checks a given run.timestep against the limit
    steps_per_cycle = 1.0 / (case.drive.frequency * step.dt)
    if case.output.frames_per_cycle > steps_per_cycle:
        raise table("output").error(
            "frames_per_cycle",
            case.output.frames_per_cycle,
            f"<= the time steps per drive cycle, {math.floor(steps_per_cycle)} at dt = "
            f"{step.dt:.4g} s (at most one frame a step)",
        )


def set_contact_keys(path: Path, values: dict[str, float], comment: str) -> str:
    """Return the text of the case file ``path`` with ``values`` set in its [contact] table.

    As :func:`set_case_keys` with every key in [contact].
    """
    return set_case_keys(path, {f"contact.{k}": v for k, v in values.items()}, comment)


def set_case_keys(path: Path, values: dict[str, object], comment: str) -> str:
    """Return the text of the case file ``path`` with ``values`` ({"table.key": value}) set.

    Existing lines of those keys in their table are replaced; the new lines follow the table's
    header with ``comment``; the rest of the file (comments, order) is kept. A missing table is
    appended. Values are written as TOML: numbers, strings and booleans.
    """
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    any_header = re.compile(r"^\s*\[")
    tables: dict[str, dict[str, object]] = {}
    for dotted, value in values.items():
        table, _, key = dotted.rpartition(".")
        tables.setdefault(table, {})[key] = value
    for table, keys in tables.items():
        header = re.compile(r"^\s*\[\s*" + re.escape(table) + r"\s*\]\s*(#.*)?$")
        new = [f"{key} = {_toml_value(value)}  # {comment}" for key, value in keys.items()]
        start = next((i for i, line in enumerate(lines) if header.match(line)), None)
        if start is None:
            lines = [*lines, "", f"[{table}]", *new]
            continue
        end = next(
            (i for i in range(start + 1, len(lines)) if any_header.match(lines[i])), len(lines)
        )
        own = re.compile(r"^\s*(" + "|".join(map(re.escape, keys)) + r")\s*=")
        body = [line for line in lines[start + 1 : end] if not own.match(line)]
        lines = [*lines[: start + 1], *new, *body, *lines[end:]]
    return "\n".join(lines) + "\n"


def _toml_value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string
    return repr(value)
