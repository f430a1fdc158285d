"""How accurate a case's answer will be, and the advice that makes it cheaper or right.

The expected error comes from the study (validation/speed_accuracy/), which varied one setting
at a time around the shipped cases (``cases/sphere-bed`` for spheres, ``cases/screw-trough`` for
screws and other clumps) and measured the bulk velocity against the bed's rigid limit (the
converged answer, extrapolated over E = 5e7-5e10 Pa by validation/bulk-convergence); its summary
is ``dem/data/speed_accuracy.json``. The error of a case is the error that stiffness sweep
measured at the case's stiffness, plus the change each of its other settings made against the
base settings (interpolated in the logarithm of the setting), combined with the statistical
error of its cycles and fill, and with the rigid limit's own uncertainty. It is a guide for cases
like the shipped ones; outside the studied range, and under another drive, material or
tangential law, the plan says so. The advice (:class:`Advice`) names settings stiffer or finer
than the answer needs, a section too short for the grain, too few or too many cycles, and which
rung of the model ladder (point mass, one grain, bed) already answers the question.
"""

from __future__ import annotations

import json
import math
import re
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from dem.physics.contact import Hertz
from dem.physics.laws import TANGENTIAL_LAWS
from dem.run.advice import Advice, round_up
from dem.scene.resolved import resolve

#: The tolerance the study's acceptable settings meet (relative error of the bulk velocity).
TOLERANCE = 0.02
#: Stiffness or step this many times finer than the cheapest acceptable one is "far more".
FAR = 2.0


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
    if found is None or not TANGENTIAL_LAWS[case.contact.tangential].calibrates:
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
    return "screw-trough" if case.particles.clumps else "sphere-bed"


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


# --- the study's axes ---------------------------------------------------------------------------


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
    scene = resolve(case)
    case = scene.case
    mass, radius = grain_mass_radius(scene)
    hertz = Hertz(case.contact.youngs_modulus, case.contact.poisson_ratio)
    t_c = hertz.collision_time(radius, mass, case.drive.peak_speed, beta=0.0)
    return mass * (math.pi / t_c) ** 2


def equivalent_youngs_modulus(case) -> float:
    """The study's stiffness axis: the case's Young's modulus, Pa.

    For the linear law: the modulus whose Hertz grain-floor impact at A omega lasts as long as
    the linear contact, pi sqrt(m / k_n). ``case``: a :class:`dem.scene.resolved.Scene`, or a case
    resolved here.
    """
    scene = resolve(case)
    case = scene.case
    mass, radius = grain_mass_radius(scene)
    return scene.law.normal.equivalent_youngs_modulus(mass, radius, case.drive.peak_speed)


def grain_length(case) -> float:
    """A grain's length, m: a sphere's diameter, a clump's largest extent."""
    pt = case.particles
    if not pt.clumps:
        return 2.0 * pt.radius
    g = pt.grain
    centres, radii = np.asarray(g.centres), np.asarray(g.radii)
    ext = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2)
    ext += radii[:, None] + radii[None, :]
    return float(ext.max())


# --- the expected error and advice ---------------------------------------------------------------


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


#: The depth of the study's beds, in layers (:mod:`dem.scene.depth`): 1500 spheres of 2 mm in
#: 0.10 x 0.04 m, 200 screws of 2.5 g in 0.12 x 0.06 m (the shipped cases).
STUDY_LAYERS = {"sphere-bed": 5.2, "screw-trough": 1.75}
#: How far (a factor either way) a bed's depth may be from the study's and share its figures.
SAME_DEPTH = 2.0


def bed_and_contact_away(scene, data: dict, kind: str) -> list[str]:
    """Where a bed leaves the study's by its depth or a contact too soft for the rigid answer.

    A bed of a tenth of a layer (grains alone on the floor) or one whose contact the stiffness
    rule finds too soft is not one the study's error figures describe, whatever its drive. The
    study's depth: its ``conditions["layers"]`` (None: not checked), else :data:`STUDY_LAYERS`.
    """
    from dem.run import stiffness
    from dem.run.summary import bed_summary

    case, out = scene.case, []
    bed = bed_summary(case)
    study = (data.get("conditions") or {}).get("layers", STUDY_LAYERS.get(kind))
    if bed is not None and study is not None:
        if not study / SAME_DEPTH <= bed["layers"] <= study * SAME_DEPTH:
            out.append(f"particles.layers = {bed['layers']:.3g} ({bed['count']} grains; study: "
                       f"{study:g} layers)")  # fmt: skip
    soft = stiffness.assessment(scene)
    if soft is not None and not soft.get("converged", True):
        out.append(
            f"{soft['key']} = {getattr(case.contact, soft['key'].split('.')[1]):.3g} "
            f"(the bed's (omega / omega_bed)^2 = {soft['compliance']:.3g} > "
            f"{soft['compliance_limit']:.3g}: too soft for the rigid material's answer)"
        )
    return out


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


def expected_error(scene, data, kind, cycles, advice) -> tuple[float, dict, str]:
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
    key = scene.law.normal.key
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
    # N replicas (run.replicas) pool N fills: both shrink as 1/sqrt(N).
    replicas = max(1, int(getattr(case.run, "replicas", 1) or 1))
    within = data["base_stderr"] * math.sqrt(data["base_cycles"] / cycles / replicas)
    between = math.sqrt(max(data["fill_spread"] ** 2 - data["base_stderr"] ** 2, 0.0) / replicas)
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
    advise_ladder(case, data, kind, advice)
    return math.sqrt(systematic**2 + statistical**2 + reference**2), parts, source


def round_down(x: float) -> float:
    """``x`` rounded down to 3 significant digits."""
    digits = 2 - math.floor(math.log10(abs(x)))
    return float(math.floor(x * 10.0**digits) / 10.0**digits)


def _advise_settings(case, data, step, fraction, e_equiv, advice) -> None:
    """Stiffer or finer than the answer needs (far more), or past what stayed accurate."""
    cheap = data["cheapest"]
    if case.contact.youngs_modulus is not None:  # Hertz: the study's axis is E
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
            f"{step.dt:.3g} s ({fraction:.3g} x limit) is far finer than the answer needs: "
            f"{f_ok:.2f} x limit ({f_ok * step.limit:.3g} s) stayed within "
            f"{TOLERANCE:.0%}", round_down(f_ok * step.limit)))  # fmt: skip
    elif fraction > f_ok * 1.001:
        advice.append(Advice("warn", "run.timestep",
            f"{fraction:.3g} x limit is coarser than the study found accurate "
            f"({f_ok:.2f} x limit)", round_down(f_ok * step.limit)))  # fmt: skip
    elif case.run.timestep is None and f_ok > FAR * fraction:
        advice.append(Advice("note", "run.timestep",
            f"the automatic step is {fraction:.3g} x limit; {f_ok:.2f} x limit "
            f"(run.timestep = {f_ok * step.limit:.3g}) stayed within {TOLERANCE:.0%} at "
            f"{f_ok / fraction:.1f}x less cost", round_down(f_ok * step.limit)))  # fmt: skip


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


def advise_ladder(case, data, kind, advice) -> None:
    """Which rung of the ladder (point mass, one grain, bed) already answers the question."""
    d, m = case.drive, case.wall_material  # the point mass touches the floor only
    command = (f"dem pointmass velocity --throw-number {d.throw_number:.4g} "
               f"--angle {d.angle:g} --friction {m.friction:g} "
               f"--inclination {case.trough.inclination:g} "
               f"--eps-t {m.restitution_tangential:g} "
               f"--eps-n {m.restitution_normal:g}")  # fmt: skip
    if not d.is_single:  # the event-driven command knows the line drive only
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
    from dem.io.files import finite_or_none, replace_text

    text = json.dumps(finite_or_none(data), indent=1, sort_keys=True, allow_nan=False)
    replace_text(path, text + "\n")
    study_data.cache_clear()
