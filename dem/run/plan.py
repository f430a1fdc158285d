"""``dem plan``: what a case will cost and how accurate it will be, before any grain moves.

:func:`plan` reads a case and, without filling or stepping it, works out the grains and spheres,
the time step and its stability limit, steps per cycle, the memory of the state, an estimate of
the wall time, the error to expect from these settings, and advice: settings stiffer or finer
than the answer needs, a section too short for the grain, too few or too many cycles, and which
rung of the model ladder (point mass, one grain, bed) already answers the question.

Where the numbers come from:

- memory: the state's arrays allocated as a run allocates them (zeros, so nothing is touched),
  with the pair list at its starting capacity (and, on several threads, the parallel pair
  loop's inbox);
- wall time: start-up, the compile where numba's cache lacks this kind of scene, the fill, the
  frames, and particle-steps (spheres x steps: the drive-off settle, the settling cycles and the
  measured cycles) over a rate: the rate the last run of this case measured on this machine
  (``CASE_DIR/output/summary.json``), else the rate of the shipped cases of this grain kind on
  the project's idle 2-core VM (``RATE_1THREAD``; checked against every shipped case by
  validation/performance/plan_check.py);
- expected error: the study (validation/speed_accuracy/) varied one setting at a time around the
  shipped cases (``cases/sphere-bed`` for spheres, ``cases/screw-trough`` for screws and other
  clumps) and measured the bulk velocity against the bed's rigid limit (the converged answer,
  extrapolated over E = 5e7-5e10 Pa by validation/bulk-convergence). The error of a case is the
  error that stiffness sweep measured at the case's stiffness, plus the change each of its other
  settings made against the base settings (interpolated in the logarithm of the setting),
  combined with the statistical error of its cycles and fill, and with the rigid limit's own
  uncertainty. It is a guide for cases like the shipped ones; outside the studied range, and
  under another drive, material or tangential law, the plan says so.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import asdict, dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from dem import config
from dem.run import stiffness
from dem.scene.resolved import resolve

#: The tolerance the study's acceptable settings meet (relative error of the bulk velocity).
TOLERANCE = 0.02
#: Stiffness or step this many times finer than the cheapest acceptable one is "far more".
FAR = 2.0
#: Cost of a step apart from its particles, s (cases/single-sphere: 1.64e6 steps of one sphere in
#: 7.1 s, plan_check.py); it dominates only for a few grains.
STEP_OVERHEAD_S = 4.0e-6
#: Particle-steps per second on one thread where no run of the case has measured it: the
#: shipped cases on the project's idle 2-core VM (2026-11-26, plan_check.py: sphere-bed 9.3e6 on
#: 2 threads; screw-trough 1.4e7 sphere-steps/s) ...
RATE_1THREAD = {"sphere": 5.5e6, "clump": 8.2e6}
#: ... times this on a mesh trough (u-trough 4.3e6, v-trough 6.2e6 against the flat 1.4e7).
MESH_RATE_FACTOR = 0.4
#: Settling cycles an automatic settle ("auto") takes, as the shipped beds took them under the
#: default law (sphere-bed 10; screw-trough 6, u-trough 8, v-trough 6).
AUTO_SETTLE_CYCLES = {"sphere": 10, "clump": 7}
#: Start-up of ``dem run`` (imports, loading the cached kernels, the point mass, summary), s.
#: The figures below were measured on the project's 2-core VM (validation/performance,
#: plan_check.py and its README); another machine scales them all alike, roughly.
STARTUP_S = 3.0
#: Compiling the step kernels where numba's cache holds none yet for this kind of scene (a
#: fresh clone, or the first mesh trough), s: with an empty NUMBA_CACHE_DIR, the whole run's
#: extra time: 56 s (sphere-bed) and 61 s (screw-trough), of which the step kernels 46 and 53.
COMPILE_S = {"sphere": 56.0, "clump": 61.0}
#: Building the scene and placing its grains, s: this much ... (in a run, after the compile
#: check has loaded the kernels: 0.14 s for 1500 spheres, 0.07-0.28 s for 150-200 screws)
FILL_S = {"sphere": 0.05, "clump": 0.05}
#: ... and this much per grain (random sequential placement).
FILL_S_PER_GRAIN = {"sphere": 6e-5, "clump": 1e-3}
#: A frame (VTK files and the results.h5 rows): this much, s (a clump's frame has a grains
#: file too: sphere-bed 12 ms, screw-trough 16 ms, the feeder 22 ms a frame) ...
FRAME_S = {"sphere": 0.008, "clump": 0.012}
#: ... and this much per sphere (1500 spheres 12 ms, 15000 spheres 54 ms a frame).
FRAME_S_PER_SPHERE = 3.0e-6


class PlanWarning(UserWarning):
    """A case asks for far more (or less) than its answer needs (``dem run`` warns at start)."""


@dataclass(frozen=True)
class Advice:
    """One piece of advice about a case key.

    ``level`` is "warn" (the case asks for far more or less than it needs, or leaves the studied
    range) or "note"; ``key`` is the case key it concerns; ``value`` the value the advice sets
    the key to (None where it names none): ``dem plan --suggest`` applies these.
    """

    level: str
    key: str
    text: str
    value: float | int | str | None = None


#: ``dem calibrate``'s comment on the [contact] keys it writes: the drive it fitted them on.
CALIBRATED_AT = re.compile(
    r"#\s*dem calibrate [^:]*:.*? at Gamma (?P<gamma>[-+0-9.eE]+), phi (?P<phi>[-+0-9.eE]+) deg, "
    r"mu (?P<mu>[-+0-9.eE]+), alpha (?P<alpha>[-+0-9.eE]+) deg"
)


def calibration_advice(case) -> Advice | None:
    """A warning where ``[contact]`` holds values ``dem calibrate`` fitted on another drive.

    A ``"coulomb"`` spring's eps_t depends on the incidence of the landings, so k_t / k_n fitted
    at one drive gives another eps_t at another (0.1581 fitted at phi 25 deg, Gamma 1.8 gives
    eps_t 0.824 at phi 30 deg, Gamma 2). The drive is read from the comment ``dem calibrate``
    writes beside the keys; a case run with ``--set`` is compared as run.
    """
    try:
        text = Path(case.source).read_text(encoding="utf-8")
    except (OSError, TypeError):
        return None
    found = CALIBRATED_AT.search(text)
    if found is None or case.contact.tangential != "coulomb":
        return None
    at = {k: float(v) for k, v in found.groupdict().items()}
    d, mu = case.drive, case.wall_material.friction
    now = {"gamma": d.throw_number, "phi": d.angle, "mu": mu, "alpha": case.trough.inclination}
    tolerance = {"phi": 0.5, "mu": 0.005, "alpha": 0.05}  # Gamma: 1 % relative
    differs = abs(now["gamma"] / at["gamma"] - 1.0) > 0.01 or any(
        abs(now[k] - at[k]) > tol for k, tol in tolerance.items()
    )
    if not differs:
        return None
    return Advice(
        "warn", "contact.tangential_stiffness_ratio",
        f"dem calibrate fitted it at Gamma {at['gamma']:g}, phi {at['phi']:g} deg, mu "
        f"{at['mu']:g}, alpha {at['alpha']:g} deg; this run is at Gamma {now['gamma']:.4g}, phi "
        f"{now['phi']:g} deg, mu {now['mu']:g}, alpha {now['alpha']:g} deg, where its eps_t "
        "differs (a \"coulomb\" spring's eps_t depends on the landing's incidence): run dem "
        "calibrate again, or use contact.tangential = \"impact\", which needs no calibration",
    )  # fmt: skip


@dataclass
class Plan:
    """The plan of a case (all SI; ``as_dict`` is what summary.json's ``plan`` holds)."""

    case: str
    grains: int
    spheres_per_grain: int
    spheres: int
    timestep: float
    timestep_auto: float
    timestep_limit: float
    steps_per_cycle: float
    settle_cycles: int
    settle_cycles_auto: bool
    cycles: int
    steps: int
    particle_steps: float
    memory_bytes: int
    threads: int
    particle_steps_per_s: float
    rate_source: str
    wall_time_s: float
    compile_s: float
    fill_s: float
    frames: int
    frames_s: float
    expected_error: float
    error_parts: dict[str, float]
    error_source: str
    advice: list[Advice] = field(default_factory=list)

    def as_dict(self) -> dict:
        """Plain data for JSON."""
        return asdict(self)

    def warnings(self) -> list[Advice]:
        """The advice a run warns about at start."""
        return [a for a in self.advice if a.level == "warn"]

    def text(self) -> str:
        """The plan as ``dem plan`` prints it."""
        lines = [
            f"case {self.case}",
            f"  grains            {self.grains} x {self.spheres_per_grain} sphere(s) = "
            f"{self.spheres} spheres",
            f"  time step         {self.timestep:.3g} s = {self.timestep / self.timestep_limit:.2f}"
            f" x stability limit {self.timestep_limit:.3g} s (automatic {self.timestep_auto:.3g})",
            f"  steps per cycle   {self.steps_per_cycle:.0f}",
            f"  cycles            {self.settle_cycles} settling"
            f"{' (auto: estimated)' if self.settle_cycles_auto else ''} + {self.cycles} measured,"
            f" {self.steps:.3g} steps in all",
            f"  memory            {format_size(self.memory_bytes)} "
            f"({self.memory_bytes / self.spheres:.0f} B per sphere)",
            f"  wall time         about {format_duration(self.wall_time_s)} "
            f"on {self.threads} thread(s)"
            + (
                f": compiling {format_duration(self.compile_s)} "
                "(no numba cache yet, once per machine),"
                if self.compile_s
                else ":"
            )
            + f" filling {format_duration(self.fill_s)}, {self.frames} frames "
            f"{format_duration(self.frames_s)}, steps at "
            f"{self.particle_steps_per_s:.2g} particle-steps/s ({self.rate_source})",
            f"  expected error    {100 * self.expected_error:.1f} % of the bulk velocity ("
            + ", ".join(f"{k} {100 * v:.1f} %" for k, v in self.error_parts.items())
            + f"; {self.error_source})"
            if math.isfinite(self.expected_error)
            else f"  expected error    not estimated: {self.error_source}",
        ]
        if self.advice:
            lines.append("advice:")
            lines += [f"  [{a.level}] {a.key}: {a.text}" for a in self.advice]
        return "\n".join(lines)


def format_size(n: float) -> str:
    """A byte count in B, kB, MB or GB, 3 significant digits."""
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.3g} {unit}"
        n /= 1000.0
    return f"{n:.3g} GB"


def format_duration(s: float) -> str:
    """A duration in seconds as s, min, h, days or years, readable at a glance."""
    if s < 10:
        return f"{s:.2g} s"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 4 * 86400:
        return f"{s / 3600:.1f} h"
    if s < 2 * 365.25 * 86400:
        return f"{s / 86400:.0f} days"
    return f"{s / (365.25 * 86400):.3g} years"


# --- the study's measurements -------------------------------------------------------------------


@cache
def study_data() -> dict | None:
    """The study's summary, ``dem/data/speed_accuracy.json`` (validation/speed_accuracy/run_all.py).

    None where it is missing: the plan then has no expected error and no study advice.
    """
    try:
        text = resources.files("dem").joinpath("data", "speed_accuracy.json").read_text()
    except FileNotFoundError:
        return None
    return json.loads(text)


def study_kind(case) -> str:
    """The shipped case whose study applies: spheres -> sphere-bed, clumps -> screw-trough."""
    return "sphere-bed" if case.particles.shape == "sphere" else "screw-trough"


def _interpolate(series: list[list[float]], x: float, cheap: str = "low") -> tuple[float, bool]:
    """Value at ``x`` of ``[[x, y], ...]`` and whether x lies inside the studied range.

    Linear in log x, clamped at the ends; "inside" only asks about the cheap side.

    ``cheap`` "low": smaller x is cheaper (stiffness, section size, resolution); "high": larger
    x (the time step). Beyond the expensive end the study's finest value stands: the answer
    only converges further there.
    """
    xs = np.log([p[0] for p in series])
    ys = np.array([p[1] for p in series])
    order = np.argsort(xs)
    xs, ys = xs[order], ys[order]
    lx = math.log(x)
    inside = lx >= xs[0] - 1e-9 if cheap == "low" else lx <= xs[-1] + 1e-9
    return float(np.interp(lx, xs, ys)), inside


# --- the pieces ---------------------------------------------------------------------------------


#: Above twice this many grains the memory is extrapolated from this many and twice as many
#: (every array is proportional to the count): a plan of 1e9 grains allocates nothing large.
MEMORY_SAMPLE_GRAINS = 2000


def memory_bytes(case, spheres: int, grains: int, threads: int = 1) -> int:
    """Bytes of the state a run allocates: spheres, clumps and the pair list (at its start).

    ``case``: a :class:`dem.scene.resolved.Scene`, or a case resolved here. Several threads add the
    parallel pair loop's inbox (:meth:`dem.engine.state.PairList.ensure_inbox`). Measured by
    allocating
    the arrays (zeros: no page is touched) up to 2 :data:`MEMORY_SAMPLE_GRAINS` grains, and
    extrapolated linearly beyond.
    """
    scene = resolve(case)
    g1 = MEMORY_SAMPLE_GRAINS
    if grains <= 2 * g1:
        return _allocated_bytes(scene, spheres, grains, threads)
    per = spheres // grains
    m1 = _allocated_bytes(scene, g1 * per, g1, threads)
    m2 = _allocated_bytes(scene, 2 * g1 * per, 2 * g1, threads)
    return int(m1 + (m2 - m1) * (grains - g1) / g1)


def _allocated_bytes(scene, spheres: int, grains: int, threads: int) -> int:
    """The bytes of the state's arrays, allocated for ``grains`` grains of ``spheres``."""
    from dem.engine.state import Bodies, PairList, Spheres

    case = scene.case
    width = scene.law.history_width
    total = 0
    if case.particles.shape == "sphere":
        s = Spheres.create(np.zeros((spheres, 3)), case.particles.radius, case.material.density)
        arrays = [s]
    else:
        q = np.zeros((grains, 4))
        q[:, 0] = 1.0
        b, s = Bodies.create(scene.grain, np.zeros((grains, 3)), q)
        arrays = [s, b]
    s.set_history_width(width)
    if case.trough.mesh is not None:
        s.use_mesh()  # the mesh contact slots (the triangles themselves are not counted)
    pairs = PairList.for_spheres(spheres, width)
    if threads > 1:
        pairs.ensure_inbox()
    arrays.append(pairs)
    seen = set()
    for obj in arrays:
        for value in vars(obj).values():
            if isinstance(value, np.ndarray) and id(value) not in seen:
                seen.add(id(value))
                total += value.nbytes
    return total


def settle_steps(case, dt: float) -> int:
    """Steps of the drive-off settle: twice the fall time from the top of the fill box."""
    from dem.scene import fill

    fall = math.sqrt(2.0 * fill.box_height(case) / config.GRAVITY)
    return int(min(2.0 * fall, config.DEM_SETTLE_MAX_TIME) / dt)


def rate(case, threads: int, data: dict | None) -> tuple[float, str]:
    """Particle-steps per second and where the figure comes from."""
    last = case.directory / "output" / "summary.json"
    if last.is_file():
        try:
            s = json.loads(last.read_text())
            measured, used = float(s["particle_steps_per_s"]), int(s["threads"])
            if s.get("spheres") and measured > 0:
                return _scale(measured, used, threads), f"measured by the last run, {last}"
        except (ValueError, KeyError, TypeError):
            pass  # an older or partial summary: fall back to the study
    kind = "sphere" if case.particles.shape == "sphere" else "clump"
    one = RATE_1THREAD[kind] * (MESH_RATE_FACTOR if case.trough.mesh is not None else 1.0)
    where = ", a mesh trough" if case.trough.mesh is not None else ""
    return _scale(one, 1, threads), f"the rate of the shipped {kind} cases{where} on a 2-core VM"


def _scale(rate_used: float, used: int, threads: int) -> float:
    """Threads scale at about 0.7 of ideal each beyond the first (a shared 2-core machine)."""

    def speed(n: int) -> float:
        return 1.0 + 0.7 * (max(n, 1) - 1)

    return rate_used * speed(threads) / speed(used)


def grain_mass_radius(case) -> tuple[float, float]:
    """A grain's mass, kg, and its largest sphere radius, m (the grain-floor impact's).

    ``case``: a :class:`dem.scene.resolved.Scene`, or a case resolved here.
    """
    scene = resolve(case)
    return scene.grain_mass, scene.max_radius


def linear_equivalent_stiffness(case) -> float:
    """The linear k_n, N/m, whose contact lasts as long as the case's Hertz impact.

    The impact is a grain on the floor at A omega; k_n = m (pi / t_c)^2. ``case``: a
    :class:`dem.scene.resolved.Scene`, or a case resolved here.
    """
    from dem.kernels import contacts

    scene = resolve(case)
    case = scene.case
    mass, radius = grain_mass_radius(scene)
    c = case.contact
    y_star = c.youngs_modulus / (2.0 * (1.0 - c.poisson_ratio**2))
    speed = case.drive.peak_speed
    t_c = contacts.hertz_collision_time(y_star, radius, mass, speed)
    return mass * (math.pi / t_c) ** 2


def equivalent_youngs_modulus(case) -> float:
    """The study's stiffness axis: the case's Young's modulus, Pa.

    For the linear law: the modulus whose Hertz grain-floor impact at A omega lasts as long as
    the linear contact, pi sqrt(m / k_n). ``case``: a :class:`dem.scene.resolved.Scene`, or a case
    resolved here.
    """
    scene = resolve(case)
    case = scene.case
    c = case.contact
    mass, radius = grain_mass_radius(scene)
    if c.model == "hertz_mindlin":
        return float(c.youngs_modulus)
    t_c = math.pi * math.sqrt(mass / c.stiffness)
    speed = case.drive.peak_speed
    # dem.kernels.contacts.hertz_collision_time inverted:
    # t_c = 2.87 (m^2 / (R Y*^2 v))^(1/5)  ->  Y* = sqrt(m^2 / (R v (t_c / 2.87)^5))
    y_star = math.sqrt(mass**2 / (radius * speed * (t_c / 2.87) ** 5))
    return y_star * 2.0 * (1.0 - c.poisson_ratio**2)


def grain_length(case) -> float:
    """A grain's length, m: a sphere's diameter, a clump's largest extent."""
    pt = case.particles
    if pt.shape == "sphere":
        return 2.0 * pt.radius
    g = pt.grain
    centres, radii = np.asarray(g.centres), np.asarray(g.radii)
    ext = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2)
    ext += radii[:, None] + radii[None, :]
    return float(ext.max())


# --- the plan -----------------------------------------------------------------------------------


#: The conditions the speed-accuracy study measured under (validation/speed_accuracy: each kind's
#: shipped case of the time), where its data file does not record them: the tangential law and
#: the drive and material. Its error figures hold there and nowhere else.
STUDY_CONDITIONS = {
    "sphere-bed": {"tangential": "impact", "throw_number": 3.06, "angle": 25.0,
                   "friction": 0.35, "inclination": 0.0, "restitution_tangential": 0.8,
                   "restitution_normal": 0.0},
    "screw-trough": {"tangential": "impact", "throw_number": 1.8, "angle": 25.0,
                     "friction": 0.35, "inclination": 0.0, "restitution_tangential": 0.8,
                     "restitution_normal": 0.0},
}  # fmt: skip
#: How far a case's drive and material may be from the study's and still share its figures.
SAME_CONDITIONS = {"throw_number": 0.05, "angle": 1.0, "friction": 0.01, "inclination": 0.5,
                   "restitution_tangential": 0.01, "restitution_normal": 0.01}  # fmt: skip


def unmeasured(case, data: dict, kind: str) -> list[str]:
    """Where the case leaves the conditions the study measured: "key = value (study: value)".

    The tangential law must be the study's; the drive and material within
    :data:`SAME_CONDITIONS` (the throw number relative, the rest absolute). Stiffness, time step
    and section are not here: the study's series cover them, with their own range warnings.
    """
    study = data.get("conditions") or STUDY_CONDITIONS.get(kind, {})
    have = {
        "tangential": case.contact.tangential,
        "throw_number": case.drive.throw_number,
        "angle": case.drive.angle,
        "friction": case.material.friction,
        "inclination": case.trough.inclination,
        "restitution_tangential": case.material.restitution_tangential,
        "restitution_normal": case.material.restitution_normal,
    }
    tables = {"tangential": "contact", "throw_number": "drive", "angle": "drive",
              "inclination": "trough"}  # fmt: skip
    out = []
    for key, value in have.items():
        if key not in study:
            continue
        ref = study[key]
        if key == "tangential":
            differs = value != ref
        elif key == "throw_number":
            differs = abs(value / ref - 1.0) > SAME_CONDITIONS[key]
        else:
            differs = abs(value - ref) > SAME_CONDITIONS[key]
        if differs:
            name = f"{tables.get(key, 'material')}.{key}"
            shown = repr(value) if isinstance(value, str) else f"{value:.4g}"
            study_shown = repr(ref) if isinstance(ref, str) else f"{ref:.4g}"
            out.append(f"{name} = {shown} (study: {study_shown})")
    w = case.wall
    for key in w.given if w is not None else ():
        value, own = getattr(w, key), getattr(case.material, key)
        if value != own:  # the study's walls were of the grains' material
            out.append(f"wall.{key} = {value:.4g} (study: the material's, {own:.4g})")
    return out


def plan(
    case, *, threads: int | None = None, cycles: int | None = None, frames: bool = True
) -> Plan:
    """The plan of a :class:`~dem.scene.resolved.Scene`, or of a case resolved here.

    No fill, no dynamics. ``frames``: the run writes its VTK and HDF5 frames (``dem run
    --no-frames`` does not).
    """
    scene = resolve(case)
    case = scene.case
    data_all = study_data()
    kind = study_kind(case)
    data = data_all["cases"][kind] if data_all else None
    threads = config.default_threads() if threads is None else int(threads)
    cycles = case.run.cycles if cycles is None else int(cycles)
    pt = case.particles
    per_grain = 1 if pt.shape == "sphere" else pt.grain.count
    grains = pt.count
    spheres = grains * per_grain
    step = scene.step
    per_cycle = 1.0 / case.drive.frequency / step.dt
    auto_settle = case.run.settle_cycles is None
    if not auto_settle:
        settle = case.run.settle_cycles
    elif grains > 1:
        settle = AUTO_SETTLE_CYCLES["sphere" if pt.shape == "sphere" else "clump"]
    else:
        settle = config.DEM_AUTO_SETTLE_MIN_CYCLES
    steps = int(settle_steps(case, step.dt) + (settle + cycles) * per_cycle)
    particle_steps = float(spheres) * steps
    speed, source = rate(case, threads, data)
    from dem import kernels

    shape = "sphere" if pt.shape == "sphere" else "clump"
    cached = kernels.compiled(clumps=shape == "clump", mesh=case.trough.mesh is not None)
    compile_s = 0.0 if cached else COMPILE_S[shape]
    fill_s = FILL_S[shape] + grains * FILL_S_PER_GRAIN[shape]
    n_frames = 1 + (settle + cycles) * case.output.frames_per_cycle if frames else 0
    frames_s = n_frames * (FRAME_S[shape] + spheres * FRAME_S_PER_SPHERE)
    startup = STARTUP_S
    advice: list[Advice] = []
    away = unmeasured(case, data, kind) if data else []
    if data and away:
        expected, parts = math.nan, {}
        measure = (
            f"dem run {case.directory} compares one grain with the point mass "
            "(pointmass_bounded_velocity_norm in summary.json)"
            if grains == 1
            else f"dem sweep {case.directory} --set contact.youngs_modulus=A,B,C (and "
            "run.timestep, trough.length, run.seed) measures it"
        )
        error_source = f"not measured under this case's {'; '.join(away)}: {measure}"
        text = ("the speed-accuracy study measured other conditions: none of its error figures "
                "or advice on stiffness, step and section is claimed for this case")  # fmt: skip
        advice.append(Advice("note", away[0].split(" =")[0], text))
    elif data and grains > 1:
        expected, parts, error_source = _expected_error(scene, data, kind, cycles, advice)
    elif data:  # one grain: the bed study says nothing of its error; the ladder does
        expected, parts = math.nan, {}
        error_source = ("one grain: compare it with the point mass (validation/single-grain, "
                        "validation/single-screw)")  # fmt: skip
        _advise_ladder(case, data, kind, advice)
    else:
        expected, parts = math.nan, {}
        error_source = "no study data: dem/data/speed_accuracy.json is missing"
    if getattr(case, "feeder", None) is not None:
        text = (
            "a finite feeder's grain count changes as grains are fed and discharged: cost "
            "and memory here are those of the initial charge (particles.count)"
        )
        advice.append(Advice("note", "feeder", text))
    stiff = stiffness.advice(scene)  # the bed's lowest mode against the drive (bulk study)
    if stiff is not None:  # one warning per key: this one, which names this bed's own value
        advice = [a for a in advice if not (a.key == stiff.key and a.level == "warn")]
        advice.append(stiff)
    calibrated = calibration_advice(case)
    if calibrated is not None:
        advice.append(calibrated)
    mem = memory_bytes(scene, spheres, grains, threads)
    total = physical_memory()
    if total and mem > 0.5 * total:
        advice.append(Advice("warn", "particles.count", f"the state needs {format_size(mem)}, "
                             f"over half of this machine's {format_size(total)}"))  # fmt: skip
    return Plan(
        case=case.name, grains=grains, spheres_per_grain=per_grain, spheres=spheres,
        timestep=step.dt, timestep_auto=step.auto, timestep_limit=step.limit,
        steps_per_cycle=per_cycle, settle_cycles=settle, settle_cycles_auto=auto_settle,
        cycles=cycles, steps=steps, particle_steps=particle_steps, memory_bytes=mem,
        threads=threads, particle_steps_per_s=speed, rate_source=source,
        wall_time_s=startup + compile_s + fill_s + particle_steps / speed
        + steps * STEP_OVERHEAD_S + frames_s,
        compile_s=compile_s, fill_s=fill_s, frames=n_frames, frames_s=frames_s,
        expected_error=expected, error_parts=parts,
        error_source=error_source, advice=advice,
    )  # fmt: skip


def _expected_error(scene, data, kind, cycles, advice) -> tuple[float, dict, str]:
    """The error to expect, its parts and source, and the study's advice (appended)."""
    case, step = scene.case, scene.step
    parts: dict[str, float] = {}
    outside: list[str] = []

    def change(name: str, series: list[list[float]], x: float, key: str, cheap="low") -> None:
        value, inside = _interpolate(series, x, cheap)
        parts[name] = value
        if not inside:
            outside.append(key)

    # The stiffness series is the error against the reference; the others are what one setting
    # changed against the base settings (0 there).
    e_equiv = equivalent_youngs_modulus(scene)
    key = "contact.youngs_modulus" if case.contact.model == "hertz_mindlin" else "contact.stiffness"
    change("stiffness", data["stiffness"], e_equiv, key)
    fraction = step.dt / step.limit
    change("time step", data["timestep"], fraction, "run.timestep", cheap="high")
    # the stiffness series was measured at its own step: count the step's effect against that
    swept = data.get("stiffness_timestep_fraction")
    if swept is not None:
        parts["time step"] -= _interpolate(data["timestep"], swept, "high")[0]
    model = f"{case.contact.model} {case.contact.tangential}"
    parts["contact law"] = data["contact_model"].get(model, 0.0)
    g_len = grain_length(case)
    change("section length", data["section_length"], case.trough.length / g_len, "trough.length")
    change("section width", data["section_width"], case.trough.width / g_len, "trough.width")
    if case.particles.shape == "screw":
        per_grain = case.particles.grain.count
        change("resolution", data["resolution"], per_grain, "particles.max_bumpiness")
    # One run's error: its own noise (falls as 1/sqrt(cycles)) and the fill-to-fill scatter
    # the study found beyond it (a fill's persistent structure: more cycles do not remove it).
    within = data["base_stderr"] * math.sqrt(data["base_cycles"] / cycles)
    between = math.sqrt(max(data["fill_spread"] ** 2 - data["base_stderr"] ** 2, 0.0))
    statistical = math.hypot(between, within)
    systematic = sum(parts.values())
    # The rigid limit's own uncertainty (validation/bulk-convergence's extrapolation).
    reference = data.get("reference_uncertainty", 0.0)
    parts = {"statistical": statistical, "systematic": systematic, "reference": reference} | {
        k: v for k, v in parts.items() if abs(v) > 0
    }
    source = f"study of cases/{kind}"
    if outside:
        source += f"; {', '.join(outside)} outside the studied range"
    _advise_settings(case, data, step, fraction, e_equiv, advice)
    _advise_section(case, data, g_len, advice)
    for key in outside:  # unless a more specific warning already names the key
        if not any(a.key == key and a.level == "warn" for a in advice):
            advice.append(Advice("warn", key, "outside the settings the speed-accuracy study "
                                 "covered: the expected error is an extrapolation"))  # fmt: skip
    _advise_cycles(statistical, within, cycles, advice)
    _advise_ladder(case, data, kind, advice)
    return math.sqrt(systematic**2 + statistical**2 + reference**2), parts, source


def physical_memory() -> int | None:
    """Physical memory of this machine in bytes, or None where the OS does not say."""
    try:
        import os

        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def round_up(x: float) -> float:
    """``x`` rounded up to 3 significant digits (a limit met, not missed by rounding)."""
    digits = 2 - math.floor(math.log10(abs(x)))
    return float(math.ceil(x * 10.0**digits) / 10.0**digits)


def _down(x: float) -> float:
    """``x`` rounded down to 3 significant digits."""
    digits = 2 - math.floor(math.log10(abs(x)))
    return float(math.floor(x * 10.0**digits) / 10.0**digits)


def _advise_settings(case, data, step, fraction, e_equiv, advice) -> None:
    """Stiffer or finer than the answer needs (far more), or past what stayed accurate."""
    cheap = data["cheapest"]
    if case.contact.model == "hertz_mindlin":
        e_ok = cheap["youngs_modulus"]
        if e_equiv > FAR * e_ok:
            advice.append(Advice("warn", "contact.youngs_modulus",
                f"{e_equiv:.3g} Pa is far stiffer than the answer needs: the study stayed within "
                f"{TOLERANCE:.0%} down to {e_ok:.3g} Pa, about "
                f"{(e_equiv / e_ok) ** 0.4:.1f}x fewer steps", round_up(e_ok)))  # fmt: skip
        elif e_equiv < e_ok / FAR:
            advice.append(Advice("warn", "contact.youngs_modulus",
                f"{e_equiv:.3g} Pa is softer than the stiffness sweep found accurate "
                f"(validation/bulk-convergence: {e_ok:.3g} Pa stayed within {TOLERANCE:.0%})",
                round_up(e_ok)))  # fmt: skip
    f_ok = cheap["timestep_fraction"]
    if case.run.timestep is not None and fraction < f_ok / FAR:
        advice.append(Advice("warn", "run.timestep",
            f"{step.dt:.3g} s ({fraction:.2f} x limit) is far finer than the answer needs: "
            f"{f_ok:.2f} x limit ({f_ok * step.limit:.3g} s) stayed within "
            f"{TOLERANCE:.0%}", _down(f_ok * step.limit)))  # fmt: skip
    elif fraction > f_ok * 1.001:
        advice.append(Advice("warn", "run.timestep",
            f"{fraction:.2f} x limit is coarser than the study found accurate "
            f"({f_ok:.2f} x limit)", _down(f_ok * step.limit)))  # fmt: skip
    elif case.run.timestep is None and f_ok > FAR * fraction:
        advice.append(Advice("note", "run.timestep",
            f"the automatic step is {fraction:.2f} x limit; {f_ok:.2f} x limit "
            f"(run.timestep = {f_ok * step.limit:.3g}) stayed within {TOLERANCE:.0%} at "
            f"{f_ok / fraction:.1f}x less cost", _down(f_ok * step.limit)))  # fmt: skip


def _advise_section(case, data, g_len, advice) -> None:
    min_len = data["cheapest"]["section_length_grains"]
    n_len = case.trough.length / g_len
    if n_len < min_len * 0.999:
        advice.append(Advice("warn", "trough.length",
            f"{case.trough.length:g} m is {n_len:.1f} grain lengths, shorter than the "
            f"{min_len:.1f} the study needed to stay within {TOLERANCE:.0%}: the periodic "
            "section holds too few grains along the flow", round_up(min_len * g_len)))  # fmt: skip
    min_w = data["cheapest"]["section_width_grains"]
    n_w = case.trough.width / g_len
    if n_w < min_w * 0.999:
        advice.append(Advice("warn", "trough.width",
            f"{case.trough.width:g} m is {n_w:.1f} grain lengths, narrower than the "
            f"{min_w:.1f} the study needed: the side walls set the answer",
            round_up(min_w * g_len)))  # fmt: skip


def _advise_cycles(statistical, within, cycles, advice) -> None:
    if statistical > TOLERANCE and within > TOLERANCE:
        need = int(math.ceil(cycles * (within / TOLERANCE) ** 2))
        advice.append(Advice("warn", "run.cycles",
            f"{cycles} cycles leave a statistical error of {100 * within:.1f} %: "
            f"about {need} reach {TOLERANCE:.0%}", need))  # fmt: skip
    elif statistical > TOLERANCE:
        advice.append(Advice("note", "run.seed",
            f"one fill scatters by {100 * statistical:.1f} % from the next (the study's "
            "fill-to-fill spread): average runs with several seeds for a tighter "
            "answer"))  # fmt: skip
    elif within < TOLERANCE / 8 and cycles > 40:
        need = max(20, int(math.ceil(cycles * (8 * within / TOLERANCE) ** 2)))
        advice.append(Advice("note", "run.cycles",
            f"{cycles} cycles give {100 * within:.2f} %, far below {TOLERANCE:.0%}: "
            f"{need} would do", need))  # fmt: skip


def _advise_ladder(case, data, kind, advice) -> None:
    """Which rung of the ladder (point mass, one grain, bed) already answers the question."""
    d, m = case.drive, case.wall_material  # the point mass touches the floor only
    command = (f"dem pointmass velocity --throw-number {d.throw_number:.4g} "
               f"--angle {d.angle:g} --friction {m.friction:g} "
               f"--inclination {case.trough.inclination:g} "
               f"--eps-t {m.restitution_tangential:g} "
               f"--eps-n {m.restitution_normal:g}")  # fmt: skip
    if d.second_amplitude > 0.0:  # the event-driven command knows the line drive only
        command = ("dem.pointmass.elliptic.velocity on the case's drive; its summary.json "
                   "gives it as pointmass_velocity_norm")  # fmt: skip
    pm = data["ladder"]["point mass"]
    one_vs_pm = data["ladder"]["one grain vs point mass"]
    if case.particles.count == 1:
        advice.append(Advice("note", "particles.count",
            f"one grain: the point-mass model answers in milliseconds ({command}); the study's "
            f"single grain differed from it by {100 * one_vs_pm:.1f} %"))  # fmt: skip
    elif abs(pm) <= TOLERANCE:
        advice.append(Advice("note", "particles.count",
            f"for the study's {kind} the point mass was within {100 * abs(pm):.1f} % of the "
            f"bed: {command} may already answer"))  # fmt: skip
    else:
        advice.append(Advice("note", "particles.count",
            f"the bed is needed: for the study's {kind} the point mass ({command}) differed "
            f"from the bed by {100 * pm:+.1f} %"))  # fmt: skip


def write_study_data(path: Path, data: dict) -> None:
    """Write the study's summary where :func:`study_data` reads it (run_all.py calls this)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    from dem.io.files import finite_or_none

    text = json.dumps(finite_or_none(data), indent=1, sort_keys=True, allow_nan=False)
    path.write_text(text + "\n")
    study_data.cache_clear()


# --- dem plan --suggest ----------------------------------------------------------------------

#: Rounds of apply-and-plan again before ``suggest`` gives up on advice that keeps moving.
SUGGEST_ROUNDS = 4


@dataclass
class Suggestion:
    """What :func:`suggest` wrote: the keys it set and the plans before and after."""

    path: Path
    changes: dict[str, Any]
    before: Plan
    after: Plan

    def text(self) -> str:
        """The suggestion as ``dem plan --suggest`` prints it."""
        if not self.changes:
            return f"no advice names a value to set: wrote {self.path} as it was"
        b, a = self.before, self.after
        lines = [f"wrote {self.path}, with:"]
        lines += [f"  {key} = {value!r}" for key, value in self.changes.items()]
        lines.append(
            f"wall time about {format_duration(a.wall_time_s)} "
            f"(was {format_duration(b.wall_time_s)}, "
            f"{a.wall_time_s / b.wall_time_s:.2g}x)"
        )
        if math.isfinite(a.expected_error) or math.isfinite(b.expected_error):
            lines.append(
                f"expected error {100 * a.expected_error:.1f} % (was "
                f"{100 * b.expected_error:.1f} %)"
            )
        return "\n".join(lines)


def suggest(
    case_dir: str | Path,
    out_dir: str | Path,
    overrides: dict | None = None,
    *,
    threads: int | None = None,
    cycles: int | None = None,
) -> Suggestion:
    """Write the case the plan recommends into ``out_dir``: every advice with a value applied.

    The advice of the case (with ``overrides``, as ``--set``) is applied, the result planned
    again, and so on until no advice names a new value (at most ``SUGGEST_ROUNDS`` rounds); advice
    that moves a key back to an earlier value is an error, not a suggestion. ``out_dir`` gets
    the case folder's files (not its outputs) and a case.toml with the changed keys, each with a
    comment; a relative ``trough.mesh`` is rewritten to reach the same file. The written case is
    loaded and planned before this returns. ``out_dir`` must not hold a case.toml already.
    """
    import datetime
    import os
    import shutil

    from dem.errors import InputError
    from dem.scene.case import CASE_FILE, load_case, set_case_keys

    case_dir = Path(case_dir).expanduser().resolve()
    source = case_dir / CASE_FILE if case_dir.is_dir() else case_dir
    case_dir = source.parent
    out = Path(out_dir).expanduser().resolve()
    if (out / CASE_FILE).exists():
        raise InputError("--suggest", str(out), "a folder without a case.toml (none is replaced)")
    if out == case_dir or case_dir in out.parents:
        raise InputError("--suggest", str(out), "a folder outside the case folder")
    overrides = dict(overrides or {})
    case = load_case(source, overrides)
    before = plan(case, threads=threads, cycles=cycles)
    changes: dict[str, Any] = dict(overrides)
    seen: dict[str, list] = {}
    current, current_case = before, case
    for _ in range(SUGGEST_ROUNDS):
        todo = {
            a.key: a.value
            for a in current.advice
            if a.value is not None and changes.get(a.key) != a.value
        }
        if not todo:
            break
        for key, value in todo.items():
            if value in seen.get(key, []):
                raise InputError(
                    key, value, "advice that settles: applied together, the plan's advice "
                    f"moves {key} back and forth ({', '.join(map(repr, seen[key]))}); set it "
                    "with --set and plan again",
                )  # fmt: skip
            seen.setdefault(key, []).append(value)
        stiffer = {"contact.youngs_modulus", "contact.stiffness"} & set(todo)
        if stiffer and ("run.timestep" in todo or current_case.run.timestep is not None):
            # a step set by hand, or advised at the old stiffness, keeps its fraction of the
            # stability limit, which moves with the stiffness (the automatic step follows by
            # itself)
            step = todo.get("run.timestep", current.timestep)
            automatic = load_case(source, changes | todo | {"run.timestep": None})
            limit = resolve(automatic).step.limit
            todo["run.timestep"] = _down(step / current.timestep_limit * limit)
        changes.update(todo)
        current_case = load_case(source, changes)
        current = plan(current_case, threads=threads, cycles=cycles)
    else:
        raise InputError("--suggest", str(source), "advice that settles within "
                         f"{SUGGEST_ROUNDS} rounds: {changes}")  # fmt: skip
    mesh = case.trough.mesh
    if mesh is not None and "trough.mesh" not in changes:
        changes["trough.mesh"] = os.path.relpath(mesh, out)
    out.mkdir(parents=True, exist_ok=True)
    for item in case_dir.iterdir():  # the case's own files (grain meshes...), not its outputs
        if item.name in (CASE_FILE, "README.md") or item.is_dir():
            continue  # the README describes the case as it was
        if not (out / item.name).exists():
            shutil.copy2(item, out / item.name)
    stamp = datetime.date.today().isoformat()
    as_filed = load_case(source) if overrides else case  # "was": the file's value, not --set's
    was = {k: _case_value(as_filed, k) for k in changes}
    text_lines = set_case_keys(source, changes, f"dem plan --suggest {stamp}").splitlines()
    for i, line in enumerate(text_lines):  # each changed key's comment says what it was
        for key, old in was.items():
            name = key.rpartition(".")[2]
            if line.startswith(f"{name} = ") and line.endswith(f"# dem plan --suggest {stamp}"):
                text_lines[i] = f"{line}, was {old}"
    (out / CASE_FILE).write_text("\n".join(text_lines) + "\n", encoding="utf-8")
    after = plan(load_case(out), threads=threads, cycles=cycles)
    return Suggestion(out / CASE_FILE, {k: v for k, v in changes.items()}, before, after)


def _case_value(case, dotted: str) -> str:
    """The case's value of ``table.key`` as text (``automatic`` for an automatic step)."""
    obj = case
    for part in dotted.split("."):
        obj = getattr(obj, part, None)
    if dotted == "run.timestep" and obj is None:
        return "automatic"
    if isinstance(obj, Path):
        return str(obj)
    return "unset" if obj is None else repr(obj)
