"""The DEM step loop: fill, settle, drive; :mod:`dem.runner` runs it behind ``dem run``.

Order of operations in one step n -> n + 1 (t_n = n dt, drive time counted from the moment the
drive was switched on), all inside :func:`dem.kernels.integrate.advance`:

1. half kick and drift: v += dt/2 F_n/m, omega += dt/2 T_n/I (rotation on), x += dt v;
2. neighbour list rebuilt if a sphere moved more than skin/2 since the last build (history kept
   per pair key; overflowing capacities are regrown here in Python and the step resumed);
3. pair forces at x_{n+1} with the half-step velocities (parallel over pairs);
4. per sphere: gather its pairs, wall contacts, body force m (g + A omega^2 sin(omega t) e); second
   half kick; x-momentum summed for the measurement (within one call of ``advance``, step n+1's
   item 1 runs in this same parallel loop).

The trajectory does not depend on the number of threads, bit for bit: every force sum is taken
in the same order whatever the threads (per-pair rows, then a per-sphere gather in CSR order);
only the momentum sum of the measurement is a parallel reduction (last-bit differences).

Rigid clumps (screws, clumps from a file) replace items 1 and 4 by the rigid-body update of
:func:`dem.kernels.integrate.advance_clumps`: bodies half kick, drift and free rotation, members
placed; after the per-member gather (walls, no body force) the forces and torques are reduced to
the bodies, M a_body is added at each centre of mass and the closing half kick places the members
again. Members of one clump never contact each other. Plain spheres keep the sphere integrator.

Every ``DEM_CHECK_INTERVAL`` steps Python checks for instability (non-finite values, overlaps
beyond ``DEM_MAX_OVERLAP_FRACTION`` of the radius, grains far faster than drive and gravity can
make them) and raises :class:`dem.errors.SimulationError` naming the cause and the fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from dem import config, tangential
from dem.errors import InputError, SimulationError
from dem.kernels import contacts
from dem.kernels.integrate import (
    DONE,
    advance,
    advance_clumps,
    build,
    evaluate_forces,
    evaluate_forces_clumps,
)
from dem.kernels.neighbours import OK
from dem.kernels.rigid import rotational_energy
from dem.state import Bodies, PairList, Spheres, random_fill, random_fill_clumps
from dem.trough import Trough


@dataclass(frozen=True)
class ContactLaw:
    """A contact law selector with its kernel parameters.

    Attributes:
        model: ``"linear"`` or ``"hertz_mindlin"`` (:data:`dem.kernels.contacts.MODELS`).
        params: Kernel parameter array (:func:`dem.kernels.contacts.make_params`).

    """

    model: str
    params: np.ndarray

    @classmethod
    def from_case(cls, case) -> ContactLaw:
        """Law of a :class:`dem.case.Case` (one material for grain-grain and grain-wall).

        With ``tangential = "coulomb"`` the tangential mass factor follows the grain (a rolling
        sphere 2/7, rotation locked 1, a clump its contact mass over its mass) and an omitted
        ``tangential_stiffness_ratio`` is derived from eps_t (:mod:`dem.tangential`).
        """
        c, m = case.contact, case.material
        ratio, zeta_t, factor = c.tangential_stiffness_ratio, 0.0, 1.0
        if c.tangential == "coulomb":
            ratio, zeta_t, factor = tangential.resolve(c, m, case.particles)
        return cls(
            model=c.model,
            params=contacts.make_params(
                stiffness=c.stiffness or 0.0,
                tangential_stiffness_ratio=ratio or 0.0,
                youngs_modulus=c.youngs_modulus or 0.0,
                poisson_ratio=c.poisson_ratio,
                restitution=m.restitution_normal,
                friction=m.friction,
                rolling_friction=m.rolling_friction,
                limit_force=c.limit_force,
                tangential=c.tangential,
                tangential_damping_ratio=zeta_t,
                tangential_mass_factor=factor,
            ),
        )

    @property
    def tangential(self) -> str:
        """Tangential convention, ``"coulomb"`` or ``"liggghts"``."""
        code = self.params[contacts.P_TANGENTIAL]
        return next(k for k, v in contacts.TANGENTIAL.items() if v == code)

    def tangential_coefficients(self) -> dict:
        """The tangential coefficients in use: convention, kappa, zeta_t and f_t ("coulomb")."""
        p = self.params
        out = {"tangential": self.tangential}
        if self.tangential == "coulomb" or self.model == "linear":
            out["tangential_stiffness_ratio"] = float(p[contacts.P_KT_RATIO])
        if self.tangential == "coulomb":
            out["tangential_damping_ratio"] = float(p[contacts.P_ZETA_T])
            out["tangential_mass_factor"] = float(p[contacts.P_MASS_T])
        return out

    @property
    def model_id(self) -> int:
        """Integer id used by the kernels."""
        return contacts.MODELS[self.model]


def timestep_limits(
    law: ContactLaw,
    radius: float,
    density: float,
    impact_speed: float,
    *,
    rotation: bool = True,
    pairs: bool = True,
    youngs_modulus: float = 0.0,
    poisson_ratio: float = 0.3,
    mass: float | None = None,
) -> tuple[float, float]:
    """Automatic time step and stability limit, s, for equal spheres.

    ``mass`` replaces the sphere's own mass (a clump member: the clump's effective mass at the
    member, see :meth:`Simulation.from_case`).

    Stability: ``DEM_DT_STABILITY_FRACTION`` of the critical step 2/w0 (sqrt(1 + z^2) - z) of
    the stiffest single contact, normal (k_n) and tangential (k_t, times 7/2 with rotation on:
    a rolling sphere's tangential effective mass is 2/7 m*; damping ratio zeta_t with
    ``tangential = "coulomb"``), sphere-sphere (m* = m/2, R* = r/2;
    only if ``pairs``) and sphere-wall (m* = m, R* = r). Hertz stiffnesses are the tangent
    stiffnesses S_n, S_t at the overlap of an impact at ``impact_speed``.

    Automatic: linear: ``DEM_DT_COLLISION_FRACTION`` of the collision time; Hertz: the smaller
    of ``DEM_DT_RAYLEIGH_FRACTION`` of the Rayleigh time and ``DEM_DT_HERTZ_FRACTION`` of the
    Hertz collision time at ``impact_speed``; never above the stability limit.
    """
    p = law.params
    if mass is None:
        mass = density * 4.0 / 3.0 * math.pi * radius**3
    beta = p[contacts.P_BETA]
    tangential_factor = 3.5 if rotation else 1.0
    liggghts = law.tangential == "liggghts"
    contacts_list = [(mass, radius)] + ([(0.5 * mass, 0.5 * radius)] if pairs else [])
    limit = math.inf
    auto = math.inf
    for m_eff, r_eff in contacts_list:
        if law.model == "linear":
            kn = p[contacts.P_KN]
            kt = p[contacts.P_KT_RATIO] * kn
            zeta = -beta
            auto = min(auto, contacts.linear_collision_time(kn, m_eff, beta))
        else:
            delta = contacts.hertz_max_overlap(p[contacts.P_YSTAR], r_eff, m_eff, impact_speed)
            root = math.sqrt(r_eff * delta)
            kn = 2.0 * p[contacts.P_YSTAR] * root
            kt = 8.0 * p[contacts.P_GSTAR] * root if liggghts else p[contacts.P_KT_RATIO] * kn
            zeta = -math.sqrt(5.0 / 6.0) * beta
            auto = min(
                auto,
                contacts.hertz_collision_time(p[contacts.P_YSTAR], r_eff, m_eff, impact_speed),
            )
        kt_eff = tangential_factor * kt
        if liggghts:
            zeta_t = zeta * math.sqrt(kt / kt_eff) if kt > 0 else 0.0
        else:
            zeta_t = p[contacts.P_ZETA_T]
        limit = min(limit, contacts.critical_timestep(kn, m_eff, zeta))
        if kt > 0:
            limit = min(limit, contacts.critical_timestep(kt_eff, m_eff, zeta_t))
    limit *= config.DEM_DT_STABILITY_FRACTION
    if law.model == "linear":
        auto *= config.DEM_DT_COLLISION_FRACTION
    else:
        auto = min(
            auto * config.DEM_DT_HERTZ_FRACTION,
            config.DEM_DT_RAYLEIGH_FRACTION
            * contacts.rayleigh_time(radius, density, youngs_modulus, poisson_ratio),
        )
    return min(auto, limit), limit


class Simulation:
    """Spheres in a periodic trough section: the state and the step loop.

    Order of operations in one step (n -> n + 1, see the module docstring):
    half kick + drift -> neighbour rebuild if needed -> pair forces -> gather + walls + body force
    + half kick. Instability checks every ``DEM_CHECK_INTERVAL`` steps.

    Args:
        spheres: Sphere state (modified in place).
        trough: Geometry and drive.
        law: Contact law.
        dt: Time step, s.
        rotation: False locks rotation (spins stay zero, torques are not integrated).
        skin: Verlet skin, m; default ``DEM_SKIN_FRACTION`` times the largest radius.
        reference_speed: Speed scale for the instability check, m/s (drive and free fall).
        bodies: Rigid clumps owning the spheres (:meth:`dem.state.Bodies.create`), or None for
            plain spheres.

    """

    def __init__(
        self,
        spheres: Spheres,
        trough: Trough,
        law: ContactLaw,
        dt: float,
        *,
        rotation: bool = True,
        skin: float | None = None,
        reference_speed: float | None = None,
        bodies: Bodies | None = None,
    ):
        self.spheres = spheres
        self.bodies = bodies
        self.trough = trough
        self.law = law
        self.dt = float(dt)
        self.rotation = bool(rotation)
        if bodies is not None and not self.rotation:
            bodies.ang_mom[:] = 0.0
            bodies.place(spheres)
        r_max = float(np.max(spheres.radius))
        self.skin = config.DEM_SKIN_FRACTION * r_max if skin is None else float(skin)
        if trough.length < 2.0 * (2.0 * r_max + self.skin):
            raise InputError(
                "trough.length",
                trough.length,
                f"at least 2 (2 r + skin) = {2 * (2 * r_max + self.skin):.6g} m "
                "(the periodic image must be unique)",
            )
        if bodies is not None:
            reach = float(np.max(np.linalg.norm(bodies.offsets, axis=1)))
            if trough.length <= 2.0 * reach:
                raise InputError(
                    "trough.length",
                    trough.length,
                    f"more than twice the largest member offset, {2 * reach:.6g} m (a clump's "
                    "members must lie within half a period of its centre of mass)",
                )
        self.pairs = PairList.for_spheres(spheres.n)
        self.geom = np.array([trough.length, trough.width, self.skin, self.dt])
        self.gravity = trough.gravity
        self.drive_on = False
        self.drive_start_step = 0
        self.step_index = 0
        self.stats = np.zeros(2)
        self.reference_speed = reference_speed or (
            trough.drive_speed + math.sqrt(2 * config.GRAVITY * 10 * r_max)
        )
        self._forces_valid = False

    # --- stepping ---------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time since the start, s."""
        return self.step_index * self.dt

    @property
    def drive_time(self) -> float:
        """Time since the drive was switched on (phase origin), s."""
        return (self.step_index - self.drive_start_step) * self.dt

    def start_drive(self) -> None:
        """Switch the drive on with phase 0 now: a = A omega^2 sin(omega (t - t_now)) e."""
        self.drive_on = True
        self.drive_start_step = self.step_index
        # sin(0) = 0: the stored forces are already those of drive time 0

    def _drive(self) -> np.ndarray:
        return self.trough.drive_array(self.drive_on)

    def _build(self) -> None:
        while True:
            status, need = build(
                self.spheres.n, self.spheres.as_tuple(), self.spheres.body,
                self.pairs.as_tuple(), self.pairs.counters, self.geom,
            )  # fmt: skip
            if status == OK:
                return
            self.pairs.grow(status, need)

    def compute_forces(self) -> None:
        """Rebuild the pair list and evaluate forces and torques at the current state (no kick).

        Updates the contact history once, as a step does; ``spheres.force``/``torque`` hold
        contact forces plus m a_body.
        """
        self._build()
        if self.bodies is not None:
            evaluate_forces_clumps(
                self.spheres.n, self.law.model_id, self.law.params, self.spheres.as_tuple(),
                self.pairs.as_tuple(), self.pairs.n_pairs, self.geom, self.drive_time,
                self.gravity, self._drive(), self.bodies.as_tuple(),
            )  # fmt: skip
            self._forces_valid = True
            return
        evaluate_forces(
            self.spheres.n, self.law.model_id, self.law.params, self.rotation,
            self.spheres.as_tuple(), self.pairs.as_tuple(), self.pairs.n_pairs, self.geom,
            self.drive_time, self.gravity, self._drive(), False, False,
        )  # fmt: skip
        self._forces_valid = True

    def _advance(self, n_steps: int) -> None:
        threads = numba.get_num_threads()
        if self.spheres.n < config.DEM_PARALLEL_MIN_SPHERES:
            numba.set_num_threads(1)
        try:
            self._advance_steps(n_steps)
        finally:
            numba.set_num_threads(threads)

    def _advance_steps(self, n_steps: int) -> None:
        if not self._forces_valid:
            self.compute_forces()
        done = 0
        resume = False
        while done < n_steps:
            if self.bodies is None:
                status, steps, need = advance(
                    n_steps - done, self.step_index - self.drive_start_step, resume,
                    self.spheres.n, self.law.model_id, self.law.params, self.rotation,
                    self.spheres.as_tuple(), self.spheres.body, self.pairs.as_tuple(),
                    self.pairs.counters, self.geom, self.gravity, self._drive(), self.stats,
                )  # fmt: skip
            else:
                status, steps, need = advance_clumps(
                    n_steps - done, self.step_index - self.drive_start_step, resume,
                    self.spheres.n, self.law.model_id, self.law.params, self.rotation,
                    self.spheres.as_tuple(), self.bodies.as_tuple(), self.pairs.as_tuple(),
                    self.pairs.counters, self.geom, self.gravity, self._drive(), self.stats,
                )  # fmt: skip
            done += steps
            self.step_index += steps
            if status == DONE:
                return
            self.pairs.grow(status, need)
            resume = True

    def run(self, n_steps: int) -> None:
        """Advance ``n_steps`` steps, checking for instability every ``DEM_CHECK_INTERVAL``."""
        left = int(n_steps)
        while left > 0:
            chunk = min(left, config.DEM_CHECK_INTERVAL)
            self._advance(chunk)
            left -= chunk
            self.check()

    # --- diagnostics -------------------------------------------------------------------------

    def max_overlap_fraction(self) -> float:
        """Largest overlap over the smaller radius, pairs and walls (0 if nothing touches)."""
        s, p = self.spheres, self.pairs
        r = s.radius
        worst = 0.0
        k = p.n_pairs
        if k:
            i, j = p.pair_i[:k], p.pair_j[:k]
            d = s.x[i] - s.x[j]
            d[:, 0] -= self.trough.length * np.round(d[:, 0] / self.trough.length)
            delta = r[i] + r[j] - np.sqrt(np.einsum("ij,ij->i", d, d))
            worst = max(worst, float(np.max(delta / np.minimum(r[i], r[j]))))
        half = 0.5 * self.trough.width
        gaps = np.stack([s.x[:, 2], s.x[:, 1] + half, half - s.x[:, 1]])
        worst = max(worst, float(np.max((r - gaps) / r)))
        return worst

    def check(self) -> None:
        """Raise SimulationError if the state is non-finite, overlapping or far too fast."""
        s = self.spheres
        where = f"at t = {self.time:.6g} s (step {self.step_index}, dt = {self.dt:.3g} s)"
        if not (np.isfinite(s.x).all() and np.isfinite(s.v).all() and np.isfinite(s.omega).all()):
            raise SimulationError(
                f"non-finite positions or velocities {where}: the integration blew up; "
                "use a smaller run.timestep (or 'auto') or a softer contact"
            )
        overlap = self.max_overlap_fraction()
        if overlap > config.DEM_MAX_OVERLAP_FRACTION:
            raise SimulationError(
                f"overlap of {overlap:.3g} radii {where} exceeds "
                f"{config.DEM_MAX_OVERLAP_FRACTION} (DEM_MAX_OVERLAP_FRACTION): the contact is "
                "too soft for these impacts or the time step too large; use a stiffer contact "
                "(contact.youngs_modulus / contact.stiffness), a smaller run.timestep or a "
                "smaller drive.throw_number"
            )
        speed = float(np.sqrt(np.max(np.einsum("ij,ij->i", s.v, s.v))))
        bound = config.DEM_MAX_SPEED_FACTOR * self.reference_speed
        if speed > bound:
            raise SimulationError(
                f"a grain moves at {speed:.3g} m/s {where}, more than {bound:.3g} m/s that drive "
                "and gravity can explain (kinetic energy far above the drive's input): the "
                "integration is unstable; use a smaller run.timestep (or 'auto'), a stiffer "
                "contact or a smaller drive.throw_number"
            )

    @property
    def n_grains(self) -> int:
        """Number of grains: bodies for clumps, spheres otherwise."""
        return self.spheres.n if self.bodies is None else self.bodies.n

    @property
    def total_mass(self) -> float:
        """Total grain mass, kg (clump members carry the clump mass, so bodies are summed)."""
        b = self.bodies
        return float(np.sum(self.spheres.mass if b is None else b.mass))

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy in the trough frame, J."""
        b = self.bodies
        if b is not None:
            trans = 0.5 * np.sum(b.mass * np.einsum("ij,ij->i", b.v, b.v))
            return float(trans + rotational_energy(b.q, b.ang_mom, b.moments))
        s = self.spheres
        trans = 0.5 * np.sum(s.mass * np.einsum("ij,ij->i", s.v, s.v))
        rot = 0.5 * np.sum(np.einsum("ij,ij->i", s.omega, s.omega) / s.inv_inertia)
        return float(trans + rot)

    def rms_speed(self) -> float:
        """Root mean square sphere speed, m/s."""
        return float(np.sqrt(np.mean(np.einsum("ij,ij->i", self.spheres.v, self.spheres.v))))

    def settle(self, *, max_time: float | None = None, chunk_time: float = 0.005) -> float:
        """Run with the drive off until the rms speed < DEM_SETTLE_SPEED_FRACTION sqrt(g r).

        Returns the simulated settling time, s; raises SimulationError after ``max_time``.
        """
        max_time = config.DEM_SETTLE_MAX_TIME if max_time is None else max_time
        self.drive_on = False
        r = float(np.mean(self.spheres.radius))
        threshold = config.DEM_SETTLE_SPEED_FRACTION * math.sqrt(config.GRAVITY * r)
        chunk = max(1, int(round(chunk_time / self.dt)))
        start = self.time
        while self.time - start < max_time:
            self.run(chunk)
            if self.rms_speed() < threshold:
                return self.time - start
        raise SimulationError(
            f"the fill did not come to rest within {max_time} s of simulated time (rms speed "
            f"{self.rms_speed():.3g} m/s > {threshold:.3g} m/s); raise "
            "material.restitution_normal damping (lower eps_n) or check the contact stiffness"
        )

    def cycle_velocity(self) -> float:
        """Mass-weighted mean x-velocity over the steps since ``stats`` was last zeroed, m/s.

        The step loop sums the grains' x-momentum after every step into ``stats``; nan if no step
        was taken.
        """
        if not self.stats[1]:
            return math.nan
        return float(self.stats[0] / (self.stats[1] * self.total_mass))

    def mean_velocity_x(self) -> float:
        """Mass-weighted mean x-velocity now (trough frame), m/s."""
        if self.bodies is not None:
            b = self.bodies
            return float(np.sum(b.mass * b.v[:, 0]) / np.sum(b.mass))
        s = self.spheres
        return float(np.sum(s.mass * s.v[:, 0]) / np.sum(s.mass))

    def contact_counts(self) -> np.ndarray:
        """Touching neighbours plus touching walls (floor, side walls) per sphere, (n,) int64."""
        s, p = self.spheres, self.pairs
        count = np.zeros(s.n, dtype=np.int64)
        k = p.n_pairs
        if k:
            i, j = p.pair_i[:k], p.pair_j[:k]
            d = s.x[i] - s.x[j]
            d[:, 0] -= self.trough.length * np.round(d[:, 0] / self.trough.length)
            touch = np.einsum("ij,ij->i", d, d) < (s.radius[i] + s.radius[j]) ** 2
            np.add.at(count, i[touch], 1)
            np.add.at(count, j[touch], 1)
        half = 0.5 * self.trough.width
        count += s.x[:, 2] < s.radius
        count += s.x[:, 1] + half < s.radius
        count += half - s.x[:, 1] < s.radius
        return count

    # --- checkpoints ---------------------------------------------------------------------------

    def state_dict(self) -> dict[str, np.ndarray]:
        """Everything the step loop reads, as arrays: restoring it continues bit for bit.

        Sphere arrays (``sph.*``), the pair list with its contact history, scratch and CSR
        index (``nb.*``, capacities included), the step counters and the stored forces (a
        fresh force evaluation would update the contact history a second time).
        """
        state = {f"sph.{k}": v for k, v in vars(self.spheres).items()}
        if self.bodies is not None:
            state |= {f"body.{k}": v for k, v in vars(self.bodies).items()}
        state |= {f"nb.{k}": v for k, v in vars(self.pairs).items() if isinstance(v, np.ndarray)}
        state["nb.sizes"] = np.array(
            [self.pairs.n, self.pairs.capacity, self.pairs.cell_capacity, self.pairs.slots]
        )
        state["sim.counters"] = np.array(
            [self.step_index, self.drive_start_step, int(self.drive_on), int(self._forces_valid)]
        )
        state["sim.stats"] = self.stats
        state["sim.dt"] = np.array(self.dt)
        return state

    def load_state(self, state: dict[str, np.ndarray]) -> None:
        """Restore :meth:`state_dict` output (same case; refuses a different sphere count)."""
        n, capacity, cell_capacity, slots = (int(v) for v in state["nb.sizes"])
        if n != self.spheres.n or float(state["sim.dt"]) != self.dt:
            raise SimulationError(
                f"checkpoint holds {n} spheres at dt = {float(state['sim.dt'])} s, the case "
                f"{self.spheres.n} at dt = {self.dt} s: it belongs to another case"
            )
        for key in vars(self.spheres):
            setattr(self.spheres, key, np.ascontiguousarray(state[f"sph.{key}"]).copy())
        if self.bodies is not None:
            for key in vars(self.bodies):
                setattr(self.bodies, key, np.ascontiguousarray(state[f"body.{key}"]).copy())
            self.spheres.body = self.bodies.body_of
        self.pairs = PairList(n, capacity, cell_capacity, slots)
        for key, value in vars(self.pairs).items():
            if isinstance(value, np.ndarray):
                setattr(self.pairs, key, np.ascontiguousarray(state[f"nb.{key}"]).copy())
        step, drive_start, drive_on, forces_valid = (int(v) for v in state["sim.counters"])
        self.step_index, self.drive_start_step = step, drive_start
        self.drive_on, self._forces_valid = bool(drive_on), bool(forces_valid)
        self.stats[:] = state["sim.stats"]

    # --- construction from a case --------------------------------------------------------------

    @classmethod
    def from_case(cls, case, *, timestep: float | None = None) -> Simulation:
        """Fill the case's trough with grains (seeded) and set up the time step.

        Spheres: :func:`dem.state.random_fill`. Screws and clumps: N copies of the case's grain
        template at random positions and orientations without member overlap
        (:func:`dem.state.random_fill_clumps`). The rest is :meth:`from_grains`, with the
        impact speed of the time step taken from the fill height.
        """
        pt = case.particles
        _check_buildable(case)
        trough = Trough.from_case(case)
        rng = np.random.default_rng(case.run.seed)
        if pt.shape == "sphere":
            positions, height = random_fill(pt.count, pt.radius, trough.length, trough.width, rng)
            quats = None
        else:
            positions, quats, height = random_fill_clumps(
                pt.count, pt.grain, trough.length, trough.width, rng
            )
        impact = trough.drive_speed + math.sqrt(2.0 * config.GRAVITY * height)
        sim = cls.from_grains(
            case, positions, orientations=quats, timestep=timestep, impact_speed=impact
        )
        sim.fill_height = height
        return sim

    @classmethod
    def from_grains(
        cls,
        case,
        positions: np.ndarray,
        *,
        orientations: np.ndarray | None = None,
        velocities: np.ndarray | None = None,
        timestep: float | None = None,
        impact_speed: float | None = None,
    ) -> Simulation:
        """The case's grains at chosen poses and velocities (the case's count is not used).

        Args:
            case: A :class:`dem.case.Case` (contact, material, grain, trough, drive, run).
            positions: Centres (spheres) or centres of mass (clumps), trough frame, (G, 3), m.
            orientations: Clumps: unit quaternions (w, x, y, z) body -> trough frame, (G, 4);
                default the template's principal axes along the trough axes.
            velocities: Centre-of-mass velocities relative to the trough, (G, 3), m/s; default 0.
            timestep: dt, s; default ``case.run.timestep``, else automatic.
            impact_speed: Speed of the hardest impact expected, m/s, for the automatic step and
                the instability check; default the drive speed plus the fastest grain plus a
                fall from the highest grain.

        The time step of a clump takes the smallest effective mass a point of its surface has
        for a force in any direction (:meth:`dem.shapes.Template.contact_mass`; the clump mass M
        with rotation locked), for every member radius. A given step above the stability limit
        raises InputError naming ``run.timestep``; an automatic step is shortened so that a
        drive period holds a whole number of steps.

        """
        pt, mat = case.particles, case.material
        _check_buildable(case)
        positions = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3)
        n = positions.shape[0]
        grain = pt.grain
        trough = Trough.from_case(case)
        law = ContactLaw.from_case(case)
        if velocities is None:
            velocities = np.zeros((n, 3))
        velocities = np.asarray(velocities, dtype=np.float64).reshape(n, 3)
        if impact_speed is None:
            top = float(np.max(positions[:, 2])) if n else 0.0
            fastest = float(np.max(np.linalg.norm(velocities, axis=1))) if n else 0.0
            impact_speed = (
                trough.drive_speed + fastest + math.sqrt(2.0 * config.GRAVITY * max(top, 0.0))
            )
        if pt.shape == "sphere":
            sizes = [(pt.radius, None)]
            density = mat.density
        else:
            # the clump's own compliance (rotation included) is in its contact mass, so the
            # sphere's rolling factor is not applied again below
            m_eff = grain.contact_mass() if pt.rotation else grain.mass
            sizes = [(float(r), m_eff) for r in np.unique(grain.radii)]
            density = grain.density
        auto, limit = math.inf, math.inf
        for radius, mass in sizes:
            a, b = timestep_limits(
                law, radius, density, impact_speed, rotation=pt.rotation and mass is None,
                pairs=n > 1,
                youngs_modulus=case.contact.youngs_modulus or 0.0,
                poisson_ratio=case.contact.poisson_ratio, mass=mass,
            )  # fmt: skip
            auto, limit = min(auto, a), min(limit, b)
        user = timestep if timestep is not None else case.run.timestep
        if user is not None:
            if user > limit:
                raise InputError(
                    "run.timestep",
                    user,
                    f"<= {limit:.4g} s, the stability limit of this contact "
                    f"({config.DEM_DT_STABILITY_FRACTION} of the critical step; 'auto' gives "
                    f"{auto:.4g} s)",
                    source=str(case.source),
                )
            dt = float(user)
        else:
            dt = trough.period / math.ceil(trough.period / auto)
        bodies = None
        if pt.shape == "sphere":
            spheres = Spheres.create(positions, pt.radius, mat.density)
            spheres.v[:] = velocities
        else:
            if orientations is None:
                orientations = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
            quats = np.ascontiguousarray(orientations, dtype=np.float64).reshape(n, 4)
            bodies, spheres = Bodies.create(grain, positions, quats)
            bodies.v[:] = velocities
            bodies.place(spheres)
        sim = cls(
            spheres, trough, law, dt, rotation=pt.rotation, reference_speed=impact_speed,
            bodies=bodies,
        )  # fmt: skip
        sim.fill_height = float(np.max(positions[:, 2])) if n else 0.0
        sim.timestep_limit = limit
        return sim


def measure_cycles(sim: Simulation, cycles: int, *, settle_cycles: int = 0) -> np.ndarray:
    """Per-cycle mean conveying velocities of whole drive cycles, (cycles,), m/s.

    Switches the drive on (phase 0) if it is off, runs ``settle_cycles`` unmeasured cycles,
    then ``cycles`` measured ones, each ending on a whole number of drive periods since the
    drive started (as ``dem run`` does, without writers). DESIGN.md section 3 defines the
    velocity: :meth:`Simulation.cycle_velocity` of each cycle.
    """
    if not sim.drive_on:
        sim.start_drive()
    period = sim.trough.period
    first = int(round((sim.step_index - sim.drive_start_step) * sim.dt / period))
    out = np.empty(int(cycles))
    for c in range(first, first + settle_cycles + cycles):
        end = sim.drive_start_step + int(round((c + 1) * period / sim.dt))
        sim.stats[:] = 0.0
        sim.run(end - sim.step_index)
        if c >= first + settle_cycles:
            out[c - first - settle_cycles] = sim.cycle_velocity()
    sim.stats[:] = 0.0
    return out


def _check_buildable(case) -> None:
    """Refuse what the engine cannot build yet (a mesh trough, a grain without its template)."""
    pt = case.particles
    if case.trough.mesh is not None:
        raise InputError(
            "trough.mesh", str(case.trough.mesh), "no mesh yet: flat floor and side walls"
        )
    if pt.shape != "sphere" and pt.grain is None:
        raise InputError("particles.shape", pt.shape, "a case read by dem.case.load_case")
