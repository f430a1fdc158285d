"""The validated case as frozen dataclasses: one spec per table of ``case.toml``, and :class:`Case`.

These are what :func:`dem.scene.case.load_case` returns and what every consumer reads; nothing
here reads a file or checks a range (the readers in :mod:`dem.scene.case` do, through the schema
in :mod:`dem.scene.schema`). The drive is held with both the amplitude A and the throw number

    Gamma = A omega^2 sin(phi) / (g cos(alpha)),   omega = 2 pi f,   g = dem.config.GRAVITY,

(:func:`resolve_drive` computes the one the file did not give). Units are SI; angles stay in
degrees (as in the file) and are converted to radians by the code that uses them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from dem.physics import drive, laws
from dem.physics.contact import ContactLaw
from dem.scene.schema import TANGENTIAL_CONVENTIONS


@dataclass(frozen=True)
class TroughSpec:
    """Periodic section of the trough (README, Symbols).

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
    second one out of phase with it makes the drive elliptical, and r(t) rises smoothly from 0 to
    1 over ``ramp_cycles`` cycles (:func:`dem.physics.drive.ramp`).

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
    def is_single(self) -> bool:
        """Whether this is the paper's drive: one straight-line component (no second one)."""
        return self.second_amplitude == 0.0

    @functools.cached_property
    def motion(self) -> drive.Motion:
        """The trough's motion s(t) (:class:`dem.physics.drive.Motion`)."""
        components = [drive.Component(self.amplitude, math.radians(self.angle))]
        if not self.is_single:
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
        return not self.is_single and not self.motion.is_line

    @property
    def velocity_scale(self) -> float:
        """The normalising velocity, m/s: the peak trough speed along the trough, |X| omega.

        A omega cos(phi) for the paper's drive (:attr:`dem.physics.drive.Motion.velocity_scale`).
        """
        return self.motion.velocity_scale

    @property
    def peak_speed(self) -> float:
        """Largest trough speed over a cycle, m/s (A omega for the paper's drive)."""
        if self.is_single:
            return self.amplitude * self.omega
        return self.motion.peak_speed

    def effective_throw_number(self, inclination: float) -> float:
        """Peak normal trough acceleration over g cos(alpha) (``throw_number`` for a line drive).

        ``inclination`` alpha in degrees (:meth:`dem.physics.drive.Motion.throw_number`).
        """
        if self.is_single:
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
        return tuple(f.name for f in fields(self) if getattr(self, f.name) is not None)

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
            r - delta from the centre: the point on the wall), ``"midpoint"`` (r - delta / 2,
            as LIGGGHTS 3.8's walls) or ``"radius"`` (r, as LAMMPS's ``fix wall/gran``),
            :data:`dem.kernels.contact.WALL_LEVER_ARMS`.
        slip_lever_arm: The slip velocity's lever arms: ``"contact"`` (default, the torque's
            arms: the contact point's slip) or ``"radius"`` (the full radii, as LAMMPS's ``pair
            granular``), :data:`dem.kernels.contact.SLIP_LEVER_ARMS`.

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
    slip_lever_arm: str = "contact"


@dataclass(frozen=True)
class SizeSpec:
    """The radius distribution of one sphere grain type (:mod:`dem.scene.sizes` draws it).

    Attributes:
        distribution: ``"none"`` (every grain of ``radius``), ``"uniform"`` (uniform in
            [radius_min, radius_max]), ``"normal"`` (mean ``radius``, standard deviation
            ``radius_std``), ``"lognormal"`` (median ``radius``: ln r normal with standard
            deviation ``radius_log_std``), both truncated to [radius_min, radius_max], or
            ``"discrete"`` (the ``radii`` with their ``radius_fractions``).
        radius: m: the one radius, the normal's mean or the lognormal's median; else None.
        radius_min, radius_max: The smallest and largest radius drawn, m (uniform, normal,
            lognormal), else None.
        radius_std: Standard deviation of the (untruncated) normal, m, else None.
        radius_log_std: Standard deviation of ln r of the (untruncated) lognormal, else None.
        radii: The radii of a discrete distribution, m, increasing; else empty.
        radius_fractions: Their shares of the type's grains, by number (sum 1); else empty.

    All fractions in dem are by number of grains (a LIGGGHTS deck converts them for its
    mass-based distribution: :mod:`dem.io.liggghts.deck`).

    """

    distribution: str = "none"
    radius: float | None = None
    radius_min: float | None = None
    radius_max: float | None = None
    radius_std: float | None = None
    radius_log_std: float | None = None
    radii: tuple[float, ...] = ()
    radius_fractions: tuple[float, ...] = ()

    @property
    def smallest(self) -> float:
        """The smallest radius a grain of this distribution can have, m."""
        if self.distribution == "discrete":
            return min(self.radii)
        smallest = self.radius if self.distribution == "none" else self.radius_min
        assert smallest is not None  # set for its distribution when read
        return smallest

    @property
    def largest(self) -> float:
        """The largest radius a grain of this distribution can have, m."""
        if self.distribution == "discrete":
            return max(self.radii)
        largest = self.radius if self.distribution == "none" else self.radius_max
        assert largest is not None  # set for its distribution when read
        return largest


@dataclass(frozen=True)
class GrainType:
    """One sphere grain type of a case with several (``[[particles.types]]``) or a distribution.

    Attributes:
        name: The type's name (``[[particles.types]]`` ``name``; ``"type1"``, ... by default).
        fraction: Its share of the grains by number, in (0, 1]; the types' sum to 1.
        density: rho of its grains, kg/m^3 (default ``material.density``).
        size: Its radius distribution.

    Every type shares the material's friction and restitution and the contact law; the pair
    law takes R* and m* of each pair's own two spheres.

    """

    name: str
    fraction: float
    density: float | None
    size: SizeSpec


@dataclass(frozen=True)
class ParticlesSpec:
    """The grains.

    Attributes:
        shape: ``"sphere"``, ``"screw"`` or ``"clump"``.
        count: Number of grains N >= 1.
        radius: Sphere radius, m (sphere), else None.
        rotation: False locks rotation (a sliding block, the point mass's DEM twin).
        length: Screw length, m (screw), else None.
        shank_radius: Screw shank sphere radius, m (screw), else None.
        head_radius: Screw head sphere radius, m (screw), else None.
        mass: Target grain mass, kg (screw, clump); None: material.density times the union
            volume.
        template: Absolute path of a clump template, lines ``x y z r`` in metres (clump).
        max_bumpiness: Screw resolution (screw): the deepest valley between neighbouring shank
            spheres as a fraction of the shank radius, 0 < b <= 1; a smaller b takes more
            spheres per screw (:func:`dem.scene.shapes.screw`). Default 0.25: 8 spheres for the
            shipped screw.
        layers, bed_height, mass_per_area: The depth the case gave instead of ``count`` (grain
            layers, m, kg/m^2; :mod:`dem.scene.depth`), else None; ``count`` is derived from it.
        grain: The :class:`dem.scene.shapes.Template` built at load (screw, clump), else None; not
            part of :meth:`Case.as_dict`.
        types: Spheres of several types or sizes (``[[particles.types]]``, or a
            ``radius_distribution`` in [particles], then one type): the types, else empty (one
            size, ``radius``). With types, ``radius`` is the largest radius of any type (the
            grains' reach: walls, skin, section) and ``count`` the grains of all types.

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
    layers: float | None = None
    bed_height: float | None = None
    mass_per_area: float | None = None
    grain: Any = field(default=None, repr=False, compare=False)
    types: tuple[GrainType, ...] = ()

    @property
    def clumps(self) -> bool:
        """Whether the grains are rigid clumps of spheres (screw, clump), not single spheres."""
        return self.shape != "sphere"

    @property
    def kind(self) -> str:
        """The kernel family the grains run in: ``"sphere"`` or ``"clump"``."""
        return "clump" if self.clumps else "sphere"

    @property
    def reach(self) -> float:
        """How far a grain reaches from its centre, m: the radius, or a clump's bounding radius."""
        reach = self.grain.bounding_radius if self.clumps else self.radius
        assert reach is not None  # a sphere's radius, or a clump's template, is set at load
        return reach

    @property
    def spheres_per_grain(self) -> int:
        """Contact spheres in one grain: 1, or a clump's member count."""
        return self.grain.count if self.clumps else 1


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
            fill-to-fill spread. With ``target_error`` the first batch of fills.
        target_error: Standard error, as a fraction of |v| (of 0.1 A omega cos phi at least),
            that the run reaches by pooling more fills, up to ``max_replicas``
            (:mod:`dem.run.replicas`); None: ``replicas`` fills, whatever their error.
        max_replicas: Most fills pooled while reaching ``target_error``.
        device: The engine that steps the grains: ``"cpu"`` (numba, the default) or ``"cuda"``
            (numba.cuda on a GPU; :func:`dem.engine.device.check_device` refuses what it cannot
            run yet).

    """

    settle_cycles: int | None = 10
    cycles: int = 30
    timestep: float | None = None
    seed: int = 1
    replicas: int = 1
    device: str = "cpu"
    target_error: float | None = None
    max_replicas: int = 12


@dataclass(frozen=True)
class OutputSpec:
    """What is written.

    Attributes:
        frames_per_cycle: Particle frames written per measured drive cycle.
        flight_phases: Phase bins of one drive cycle at which the fraction of grains in
            flight (touching nothing) is sampled over :data:`dem.config.DEM_FLIGHT_CYCLES`
            cycles after the measured ones (:mod:`dem.run.flight`); 0: not sampled.
        contacts: Write every contact of each frame (point, normal and tangential force,
            overlap; the walls' loads) as the frames' ``contacts`` block
            (:mod:`dem.kernels.snapshot`).

    """

    frames_per_cycle: int = 4
    flight_phases: int = 0
    contacts: bool = False


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

    @functools.cached_property
    def law(self) -> ContactLaw:
        """The case's contact law, built once per case (:meth:`ContactLaw.from_case`).

        :func:`dem.scene.case.load_case` checks the time step against it and
        :func:`dem.scene.resolved.resolve` takes the same law; a case changed by
        :func:`dataclasses.replace` is another case and builds its own.
        """
        return ContactLaw.from_case(self)

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
        row = laws.TANGENTIAL_LAWS[tangential]
        keys, defaults = row.keys[c.model], row.defaults.get(c.model, {})
        ratio = c.tangential_stiffness_ratio if "tangential_stiffness_ratio" in keys else None
        if ratio is None:
            ratio = defaults.get("tangential_stiffness_ratio")
        damping = c.tangential_damping_ratio if "tangential_damping_ratio" in keys else None
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
        assert throw_number is not None  # exactly one of the two (checked above)
        amplitude = drive.amplitude(throw_number, frequency, angle, inclination)
    return DriveSpec(frequency, angle, amplitude, throw_number, given)
