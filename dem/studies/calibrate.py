"""Virtual impact tests and the fit of the tangential contact to eps_t (``dem calibrate``).

A virtual impact throws one grain of a case at the floor, gravity and drive off, at an incidence
angle theta from the floor normal (0: head on, 90: grazing) and a speed V:
v_before = V (sin theta, 0, -cos theta). It ends when the grain leaves the floor or, where it
does not (eps_n = 0 with ``limit_force = false``: the damped contact pulls it back to rest), when
its normal force and normal velocity have died away (below :data:`IMPACT_END_FORCE` of their
peak and of V), or, for a clump that rocks on from member to member, after
:data:`IMPACT_END_TIMES` times the compression time: "after" is the state the point mass is
put in at once by its instantaneous landing. Then, with centre-of-mass velocities relative to
the floor (the paper's Eq. 12),

    eps_n = -v_z(after) / v_z(before),   eps_t = v_x(after) / v_x(before).

The impacts that matter are those conveying produces: :func:`landings` takes them from the
point-mass model of the case's drive (relative velocity at each landing of the periodic orbit).
:func:`calibrate` then finds the tangential stiffness ratio kappa whose mean eps_t over those
landings is the case's ``restitution_tangential`` (for clumps averaged over random
orientations), and says how far the target is out of reach where Coulomb friction forbids it.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dem.errors import InputError
from dem.io.files import append_text, own_folder, replace_file, replace_text
from dem.physics.laws import TANGENTIAL_LAWS
from dem.physics.search import golden_evaluations, golden_section
from dem.pointmass import elliptic
from dem.pointmass.stepped import step_motion, step_point_mass
from dem.scene.case import CASE_FILE, load_case
from dem.scene.resolved import resolve
from dem.scene.tomledit import set_contact_keys

#: Steps per drive cycle of the landing sampler (first order in the step).
LANDING_STEPS = 4000
#: An impact that does not separate has ended when its normal force and normal velocity have
#: fallen below this fraction of their peak and of the impact speed.
IMPACT_END_FORCE = 1e-3
#: ... or, for a clump that rocks on its members, after this many times the compression time.
IMPACT_END_TIMES = 30


@dataclass(frozen=True)
class Impact:
    """Outcome of one virtual impact.

    Attributes:
        incidence: theta, deg from the floor normal.
        speed: V, m/s.
        eps_n: Normal restitution of the centre of mass.
        eps_t: Tangential restitution of the centre of mass.
        duration: From first touch to the end of the impact, s.

    """

    incidence: float
    speed: float
    eps_n: float
    eps_t: float
    duration: float


def _lowest_offset(case, quat: np.ndarray | None) -> float:
    """Height of the centre of mass above the grain's lowest surface point, m."""
    pt = case.particles
    if not pt.clumps:
        return pt.radius
    from dem.kernels.rigid import quat_to_matrix

    g = pt.grain
    z = np.asarray(g.centres, dtype=np.float64) @ quat_to_matrix(quat)[2]
    return float(-np.min(z - np.asarray(g.radii)))


def virtual_impact(case, incidence: float, speed: float, quat=None, max_steps=200_000) -> Impact:
    """Throw one grain of ``case`` at the floor (module docstring) and measure eps_n and eps_t.

    Args:
        case: A :class:`dem.scene.resolved.Scene`, or a :class:`dem.scene.case.Case` resolved here;
        its
            contact, material and grain are used.
        incidence: theta in [0, 90), deg from the floor normal.
        speed: V > 0, m/s.
        quat: Clumps: orientation (w, x, y, z); default the template's principal axes.
        max_steps: Give up (RuntimeError) if the impact has not ended after this many steps.

    """
    from dem.engine import setup

    if not 0.0 <= incidence < 90.0:
        raise ValueError(f"incidence must lie in [0, 90) deg, got {incidence}")
    if speed <= 0.0:
        raise ValueError(f"speed must be > 0, got {speed}")
    # the scene's own step is the fill's; the impact's is taken (and checked) by from_grains
    scene = resolve(case, check_limit=False)
    case = scene.case
    theta = math.radians(incidence)
    v0 = np.array([speed * math.sin(theta), 0.0, -speed * math.cos(theta)])
    if case.particles.clumps and quat is None:
        quat = np.array([1.0, 0.0, 0.0, 0.0])
    q = None if quat is None else np.asarray(quat, dtype=np.float64)
    height = _lowest_offset(case, q)
    x0 = np.array([[0.5 * case.trough.length, 0.0, height + 1e-9]])
    sim = setup.from_grains(
        scene, x0, orientations=None if q is None else q[None, :], velocities=v0[None, :],
        impact_speed=speed,
    )  # fmt: skip
    return measure_impact(sim, max_steps=max_steps)


def measure_impact(sim, *, max_steps: int = 200_000) -> Impact:
    """Run one grain's impact on the floor (gravity and drive off) and measure it.

    ``sim`` holds one grain (a sphere or a clump) just above the floor, moving towards it; its
    velocity now is "before". Raises RuntimeError if the impact has not ended in ``max_steps``.
    """

    def velocity():
        return (sim.bodies.v if sim.bodies is not None else sim.spheres.v)[0].copy()

    v0 = velocity()
    speed = float(np.linalg.norm(v0))
    incidence = math.degrees(math.atan2(abs(v0[0]), -v0[2]))
    sim.gravity[:] = 0.0
    sim.drive_on = False
    sim.compute_forces()
    touched, compressed, peak = -1, -1, 0.0
    for step in range(max_steps):
        sim.run(1)
        fz = float(np.sum(sim.spheres.force[:, 2]))
        v = velocity()
        if touched < 0:
            if fz > 0.0:
                touched = step
            continue
        if compressed < 0 and v[2] >= 0.0:
            compressed = step
        peak = max(peak, abs(fz))
        apart = fz == 0.0 and v[2] > 0.0
        at_rest = abs(fz) < IMPACT_END_FORCE * peak and abs(v[2]) < IMPACT_END_FORCE * speed
        # a clump may rock on after its impact: that is no longer the impact
        rocking = compressed >= 0 and step - touched > IMPACT_END_TIMES * (compressed - touched + 1)
        if apart or at_rest or rocking:
            eps_t = float(v[0] / v0[0]) if v0[0] != 0.0 else math.nan
            return Impact(incidence, speed, float(-v[2] / v0[2]), eps_t, (step - touched) * sim.dt)
    raise RuntimeError(f"the impact did not end within {max_steps} steps")


# --- the impacts conveying produces ------------------------------------------------------------


def landings(case, cycles: int = 40, transient: int = 60) -> np.ndarray:
    """Landings of the point mass on the case's drive: rows (incidence deg, speed m/s), (L, 2).

    The point mass (paper's impact law with the case's eps_n and eps_t) is stepped at
    :data:`LANDING_STEPS` per cycle for ``transient`` cycles, then its landings over ``cycles``
    cycles are recorded (relative velocity just before touching). Empty below Gamma = 1.
    """
    d, m = case.drive, case.wall_material  # the point mass's landings: the floor's
    out = np.zeros((cycles * 8, 2))
    if not d.is_single:  # two components: the point mass on the same motion
        args, length = elliptic.stepping_args(d.motion, case.trough.inclination)
        k, _ = step_motion(
            *args, m.friction, m.restitution_tangential, m.restitution_normal, LANDING_STEPS,
            transient, cycles, False, out,
        )  # fmt: skip
        scale = length * d.omega
    else:
        k, _ = step_point_mass(
            d.throw_number, math.radians(d.angle), m.friction,
            math.radians(case.trough.inclination), m.restitution_tangential,
            m.restitution_normal, LANDING_STEPS, transient, cycles, False, out,
        )  # fmt: skip
        scale = d.amplitude * d.omega
    u, w = out[:k, 0] * scale, out[:k, 1] * scale
    keep = w < 0.0
    incidence = np.degrees(np.arctan2(np.abs(u[keep]), -w[keep]))
    return np.column_stack([incidence, np.hypot(u[keep], w[keep])])


# --- the fit -------------------------------------------------------------------------------------

#: Landings closer to the normal than this (deg) carry too little tangential velocity to fit
#: eps_t on: if all are, :func:`calibrate` uses a fan of incidences instead.
MIN_INCIDENCE = 5.0
#: Range of log(kappa) searched by :func:`calibrate`.
LOG_KAPPA_RANGE = (math.log(1e-4), math.log(10.0))


#: Width in ln(k_t / k_n) the golden-section refinement of the fit stops at
#: (:func:`dem.physics.search.golden_section`).
GOLDEN_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate`.

    Attributes:
        target: The case's eps_t.
        kappa: Fitted k_t / k_n ("coulomb").
        zeta_t: Tangential damping ratio used.
        eps_t: Mean eps_t over the impacts at the fitted kappa.
        eps_t_spread: Standard deviation of eps_t over the impacts.
        eps_n: Mean eps_n over the impacts.
        residual: eps_t - target.
        reachable: Whether |residual| <= tolerance.
        impacts: (incidence deg, speed m/s) of the impacts measured, (L, 2).
        before: eps_t per impact with the case's contact as given, (L,).
        after: eps_t per impact at the fitted kappa, (L,).
        deviation: Weighted rms of eps_t - target over the impacts at the fitted kappa.
        deviation_before: The same with the case's contact as given.
        fan: Incidences 5-85 deg at the mean impact speed, (F,), deg.
        fan_before, fan_after: eps_t over ``fan`` before and after, (F,).
        targets: What each impact can reach, (L,): eps_t, or the Coulomb-bounded value
            1 - mu (1 + eps_n) cot(theta) where friction binds (the rigid landing's bound).
        bounded: Where friction binds, (L,) bool.
        fitted: Whether anything was fitted: False for ``tangential = "impact"``, whose law
            delivers eps_t by construction (kappa is then nan and ``after`` is ``before``).

    """

    target: float
    kappa: float
    zeta_t: float
    eps_t: float
    eps_t_spread: float
    eps_n: float
    residual: float
    reachable: bool
    impacts: np.ndarray
    before: np.ndarray
    after: np.ndarray
    deviation: float
    deviation_before: float
    fan: np.ndarray
    fan_before: np.ndarray
    fan_after: np.ndarray
    targets: np.ndarray
    bounded: np.ndarray
    fitted: bool = True

    @property
    def worst(self) -> float:
        """Largest |eps_t - reachable target| over the impacts after the fit."""
        return float(np.nanmax(np.abs(self.after - self.targets)))


def bounded_targets(eps_t: float, eps_n: float, mu: float, incidence) -> np.ndarray:
    """eps_t a landing at ``incidence`` (deg from the normal) can reach under Coulomb.

    A rigid landing takes at most mu (1 + eps_n) v_n from v_t, so eps_t >= 1 - mu (1 + eps_n)
    cot(theta) (:mod:`dem.pointmass.bounded`): the target is the larger of the two.
    """
    theta = np.radians(np.asarray(incidence, dtype=float))
    with np.errstate(divide="ignore"):
        bound = 1.0 - mu * (1.0 + eps_n) / np.tan(theta)
    return np.maximum(eps_t, bound)


def _nanmean_rows(values: np.ndarray) -> np.ndarray:
    """Row means ignoring nan; nan for a row that is all nan (no warning)."""
    count = np.sum(~np.isnan(values), axis=1)
    total = np.nansum(values, axis=1)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def _with_tangential(case, kappa: float, zeta_t: float):
    contact = dataclasses.replace(
        case.contact, tangential_stiffness_ratio=kappa, tangential_damping_ratio=zeta_t
    )
    return dataclasses.replace(case, contact=contact)


def _measure(case, impacts, quats, strict=True) -> tuple[np.ndarray, np.ndarray]:
    """Return eps_t per impact and orientation, (L, Q), and eps_n, (L Q,).

    ``case``: a :class:`dem.scene.resolved.Scene`, or a case resolved here once for all its impacts.
    An impact that never ends is left out (nan) rather than stopping the fit, unless every
    orientation of one impact fails and ``strict``.
    """
    scene = resolve(case, check_limit=False)
    eps_t, eps_n = [], []
    for incidence, speed in impacts:
        for q in quats:
            try:
                r = virtual_impact(scene, float(incidence), float(speed), q, max_steps=50_000)
            except RuntimeError:
                eps_t.append(math.nan)
                eps_n.append(math.nan)
                continue
            eps_t.append(r.eps_t)
            eps_n.append(r.eps_n)
    e_t = np.array(eps_t).reshape(len(impacts), -1)
    if strict and np.isnan(e_t).all(axis=1).any():
        raise RuntimeError("every orientation of an impact failed to end: see measure_impact")
    return e_t, np.array(eps_n)


def calibrate(
    case,
    *,
    start: float | None = None,
    max_impacts: int = 12,
    orientations: int = 4,
    poses: np.ndarray | None = None,
    tolerance: float = 0.02,
    progress=None,
) -> Calibration:
    """Fit kappa = k_t / k_n so that the case's landings have its eps_t, in least squares.

    The impacts are the point mass's distinct landings for the case's drive (:func:`landings`,
    at most ``max_impacts`` of them, spread over the range of incidence), weighted by
    sin^2(theta), the share of the landing's speed that eps_t acts on. Below Gamma = 1, where the
    grain never lands and eps_t does not enter, or where every landing is within
    :data:`MIN_INCIDENCE` of the normal (Gamma about 2.5-3.7 at phi 25 deg; a bed's impacts are
    not the point mass's anyway), a fan of incidences 10-70 deg at the drive or landing speed
    is used instead. Clumps are thrown in ``orientations`` random orientations (seeded by
    ``run.seed``), or in the given ``poses`` (quaternions (P, 4), e.g. a screw lying on head and
    tip), and their eps_t averaged per landing. The fit minimises
    sum_i w_i (eps_t,i(kappa) - eps_t)^2 over log kappa in :data:`LOG_KAPPA_RANGE`: a scan of 16
    points over the whole range plus ``start`` (default the case's own kappa), then a
    golden-section search to 1e-3 in log kappa around the best of them. eps_t,i need not be
    monotone in kappa (a rolling sphere's is not: its spin stores part of the slip), and it
    stops changing where Coulomb caps it, so a landing out of reach does not pull the others
    away from the target. ``reachable`` says
    whether every landing is within ``tolerance`` of the target at the fitted kappa.

    The target of each landing is what Coulomb lets it reach (:func:`bounded_targets`), so a
    grazing landing that friction bounds neither pulls the fit nor counts against it.
    ``tangential = "impact"`` leaves nothing to fit: its impacts are measured and reported as
    they are (``fitted`` False). ``case`` is a :class:`dem.scene.resolved.Scene`, or a
    :class:`dem.scene.case.Case` resolved here.

    What a law leaves to fit, and whether it may be calibrated, is its registry row's
    (:data:`dem.physics.laws.TANGENTIAL_LAWS`). ``progress(kappa, mean_eps_t, done, total)`` is
    called after each evaluation (``total`` is the most the search can make: the grid, the start and
    the golden section's bound).

    Raises:
        InputError: the law refuses calibration ("liggghts").

    """
    # the case as given, resolved once (each kappa tried is another case, resolved in _measure)
    scene = resolve(case, check_limit=False)
    case = scene.case
    row = TANGENTIAL_LAWS[case.contact.tangential]
    if row.calibration_refused:
        allowed = [k for k, r in TANGENTIAL_LAWS.items() if not r.calibration_refused]
        raise InputError(
            "contact.tangential",
            case.contact.tangential,
            f"one of {allowed} ({row.calibration})",
            source=str(case.source),
        )
    target = case.wall_material.restitution_tangential  # impacts on the floor
    impacts = landings(case)
    if impacts.shape[0]:
        # a periodic orbit lands the same way every cycle: measure each distinct landing once
        key = np.column_stack([np.round(impacts[:, 0], 1), np.round(np.log(impacts[:, 1]), 3)])
        impacts = impacts[np.unique(key, axis=0, return_index=True)[1]]
    if impacts.shape[0] == 0 or np.max(impacts[:, 0]) < MIN_INCIDENCE:
        speed = case.drive.peak_speed
        if impacts.shape[0]:
            speed = float(np.mean(impacts[:, 1]))
        impacts = np.column_stack([np.linspace(10.0, 70.0, 7), np.full(7, speed)])
    if impacts.shape[0] > max_impacts:
        order = np.argsort(impacts[:, 0])
        impacts = impacts[order[np.linspace(0, len(order) - 1, max_impacts).round().astype(int)]]
    quats: list = [None]
    if case.particles.clumps and poses is not None:
        quats = [np.asarray(q, dtype=np.float64) for q in np.reshape(poses, (-1, 4))]
    elif case.particles.clumps:
        from dem.scene.fill import random_orientations

        rng = np.random.default_rng(case.run.seed)
        quats = list(random_orientations(orientations, rng))

    m = case.wall_material
    targets = bounded_targets(m.restitution_tangential, m.restitution_normal, m.friction,
                              impacts[:, 0])  # fmt: skip
    bounded = targets > target
    fan = np.arange(5.0, 86.0, 10.0)
    fan_impacts = np.column_stack([fan, np.full(fan.size, np.mean(impacts[:, 1]))])
    if not row.calibrates:
        e_t, e_n = _measure(scene, impacts, quats)
        after = np.nanmean(e_t, axis=1)
        fan_values = _nanmean_rows(_measure(scene, fan_impacts, quats, strict=False)[0])
        weights = np.sin(np.radians(impacts[:, 0])) ** 2
        weights /= weights.sum()
        deviation = math.sqrt(float(np.sum(weights * (after - targets) ** 2)))
        eps = float(np.nanmean(e_t))
        return Calibration(
            target=target, kappa=math.nan, zeta_t=math.nan, eps_t=eps,
            eps_t_spread=float(np.nanstd(e_t)), eps_n=float(np.nanmean(e_n)),
            residual=eps - float(np.mean(targets)),
            reachable=bool(np.max(np.abs(after - targets)) <= tolerance), impacts=impacts,
            before=after, after=after, deviation=deviation, deviation_before=deviation,
            fan=fan, fan_before=fan_values, fan_after=fan_values, targets=targets,
            bounded=bounded, fitted=False,
        )  # fmt: skip
    zeta_t = float(scene.law.grain_grain.tangential.damping_ratio)
    # a landing matters by the tangential momentum at stake: weight (v_t / V)^2 = sin^2(theta)
    weights = np.sin(np.radians(impacts[:, 0])) ** 2
    weights /= weights.sum()
    cache: dict[float, tuple] = {}

    def evaluate(log_kappa):
        """Sum of squared eps_t deviations over the impacts (orientations averaged)."""
        log_kappa = min(max(log_kappa, LOG_KAPPA_RANGE[0]), LOG_KAPPA_RANGE[1])
        if log_kappa not in cache:
            kappa = math.exp(log_kappa)
            e_t, e_n = _measure(_with_tangential(case, kappa, zeta_t), impacts, quats)
            deviation = np.nanmean(e_t, axis=1) - targets
            cache[log_kappa] = (float(np.sum(weights * deviation**2)), e_t, e_n)
            if progress is not None:
                progress(kappa, float(np.nanmean(e_t)), len(cache), total)
        return cache[log_kappa][0]

    before = np.nanmean(_measure(scene, impacts, quats)[0], axis=1)
    # eps_t need not be monotone in kappa (a rolling grain's is not): scan the whole range
    # coarsely, then refine around the best point of the scan and the start
    grid = np.linspace(*LOG_KAPPA_RANGE, 16)
    step = float(grid[1] - grid[0])
    # evaluations: the grid, the start, and the golden section on two grid steps to 1e-3
    total = len(grid) + 1 + golden_evaluations(2.0 * step, GOLDEN_TOLERANCE)
    for x in grid:
        evaluate(float(x))
    kappa = scene.law.grain_grain.tangential.stiffness_ratio
    x = math.log(start if start is not None else float(kappa))
    evaluate(x)
    x = min(cache, key=lambda k: cache[k][0])
    lo, hi = max(x - step, LOG_KAPPA_RANGE[0]), min(x + step, LOG_KAPPA_RANGE[1])
    golden_section(evaluate, lo, hi, tol=GOLDEN_TOLERANCE)
    best_log = min(cache, key=lambda k: cache[k][0])  # the best point evaluated
    best = math.exp(best_log)
    _, e_t, e_n = cache[best_log]
    eps = float(np.nanmean(e_t))
    after = np.nanmean(e_t, axis=1)
    fan_before = _nanmean_rows(_measure(scene, fan_impacts, quats, strict=False)[0])
    fan_after = _nanmean_rows(
        _measure(_with_tangential(case, best, zeta_t), fan_impacts, quats, strict=False)[0]
    )
    return Calibration(
        target=target,
        kappa=best,
        zeta_t=zeta_t,
        eps_t=eps,
        eps_t_spread=float(np.nanstd(e_t)),
        eps_n=float(np.nanmean(e_n)),
        residual=eps - float(np.mean(targets)),
        reachable=bool(np.max(np.abs(after - targets)) <= tolerance),
        impacts=impacts,
        before=before,
        after=after,
        deviation=math.sqrt(cache[best_log][0]),
        deviation_before=math.sqrt(float(np.sum(weights * (before - targets) ** 2))),
        fan=fan,
        fan_before=fan_before,
        fan_after=fan_after,
        targets=targets,
        bounded=bounded,
    )


# --- what dem calibrate keeps: every evaluation, and the case file written back ------------------

#: File in the case's output folder that keeps every evaluation of ``dem calibrate``.
EVALUATIONS_FILE = "calibration_evaluations.csv"


class EvaluationTrail:
    """Every evaluation of a fit, written as it comes, so that a stopped search keeps them.

    :data:`EVALUATIONS_FILE` in the case's output folder gets its header when the trail is
    made and a row per :meth:`record`: the evaluation's number, k_t / k_n, the mean eps_t and
    the target eps_t (the floor's ``restitution_tangential``).
    """

    def __init__(self, case) -> None:
        self.target = case.wall_material.restitution_tangential
        self.path = own_folder(case.directory / "output", "CASE_DIR") / EVALUATIONS_FILE
        self.tried: list[tuple[float, float]] = []
        header = "evaluation,tangential_stiffness_ratio,mean_eps_t,target_eps_t\n"
        replace_text(self.path, header, key="CASE_DIR")

    def record(self, kappa: float, eps: float, done: int) -> None:
        """Keep evaluation ``done``: k_t / k_n = ``kappa`` gave the mean eps_t ``eps``."""
        self.tried.append((kappa, eps))
        append_text(self.path, f"{done},{kappa:.6g},{eps:.6g},{self.target:g}\n")

    def closest(self) -> tuple[float, float] | None:
        """(k_t / k_n, mean eps_t) of the evaluation nearest the target so far; None if none."""
        return min(self.tried, key=lambda t: abs(t[1] - self.target), default=None)


def write_calibration(
    case, cal: Calibration, on_keep: Callable[[Path], None] | None = None
) -> Path:
    """Write the fitted k_t / k_n and zeta_t into the case's case.toml and return its path.

    The two ``[contact]`` keys are set in place (:func:`dem.scene.tomledit.set_contact_keys`), k_t /
    k_n to 6 digits, with a comment naming the day and the drive they fit (eps_t reached, Gamma,
    phi, mu, alpha); the rest of the file, comments included, is kept. The first calibration
    keeps the file as it was in ``case.toml.orig`` and calls ``on_keep`` with that path. The new
    file replaces the old one whole (:func:`dem.io.files.replace_file`), and only if it loads.
    """
    source = case.directory / CASE_FILE
    stamp = datetime.date.today().isoformat()
    text = set_contact_keys(
        source,
        {
            "tangential_stiffness_ratio": float(f"{cal.kappa:.6g}"),
            "tangential_damping_ratio": cal.zeta_t,
        },
        f"dem calibrate {stamp}: eps_t {cal.eps_t:.3f} for {cal.target:g} at Gamma "
        f"{case.drive.throw_number:.6g}, phi {case.drive.angle:g} deg, mu "
        f"{case.wall_material.friction:g}, alpha {case.trough.inclination:g} deg",
    )
    original = source.with_name(CASE_FILE + ".orig")
    if not os.path.lexists(original):
        replace_text(original, source.read_text(encoding="utf-8"), key="CASE_DIR")
        if on_keep is not None:
            on_keep(original)

    def write_checked(tmp):
        tmp.write_text(text, encoding="utf-8")
        load_case(tmp)  # never replace a case with one that does not load

    replace_file(source, write_checked, key="CASE_DIR")
    return source
