"""The summary of a run (summary.json, README, A DEM run), and the case's fingerprint.

:func:`summarize` gathers what a finished run reports: the conveying velocity over the measured
cycles with its error bar (:func:`dem.physics.measure.conveying_velocity`), the mass flow, a
finite feeder's discharge, the drive and materials used, the point-mass reference on the same
drive (:func:`pointmass_reference`, and :func:`pointmass_bounded`, the DEM's own reference), the
rolling sphere beside them where the grains can roll, and which reference applies and why
(:func:`reference_fields`), cost figures and provenance. :func:`fingerprint` flattens the
resolved case into the record a checkpoint keeps, so that ``--resume`` refuses a changed case
(:func:`fingerprint_changes` names what).
"""

from __future__ import annotations

import json
import math

import numpy as np

from dem.config import GRAVITY
from dem.engine.simulation import Simulation
from dem.physics import measure
from dem.provenance import record
from dem.run.record import Progress, steadiness


def summarize(case, sim: Simulation, progress: Progress, cycles: int, n_threads: int) -> dict:
    """The summary of a finished run of ``case`` on ``n_threads``, less what the runner adds.

    The runner adds the plan, the stiffness assessment, the deepest overlap, its warnings and
    the thread guard's record. An undefined value (a one-cycle run's stderr) is NaN here.
    """
    per_cycle = np.array(progress.per_cycle)
    stat = measure.conveying_velocity(per_cycle, scale=case.drive.velocity_scale)
    d = case.drive
    pm_norm, pm_method = pointmass_reference(case)
    total_mass = sim.total_mass
    flow = measure.mass_flow_rate(total_mass, stat.mean, case.trough.length)
    feeder = feeder_summary(case, sim, progress)
    if feeder is not None:  # the mass changed: the mean mass in the trough over the cycles
        flow = measure.mass_flow_rate(feeder["mean_mass_in_trough"], stat.mean, case.trough.length)
    wall = progress.wall_time_s
    provenance = record()  # versions, commit, date, host and load (the load bears on wall_time_s)
    return {
        "case": case.name,
        "overrides": dict(case.overrides),
        **stat.summary_fields(),
        "replicas": 1,
        "error_bar": "within this run (autocorrelated per-cycle means): it excludes the "
        "fill-to-fill spread, and on the shipped beds at five drives held the long-run mean in "
        "23-53 % of runs, three pooled fills in 92-96 % (validation/steadiness); pool fills "
        "with run.replicas",
        "mass_flow_rate": flow,
        "mass_flow_rate_per_width": flow / case.trough.width,
        "amplitude": case.drive.amplitude,
        "throw_number": d.effective_throw_number(case.trough.inclination),
        "velocity_scale": d.velocity_scale,
        "drive_components": components(case),
        "ramp_cycles": d.ramp_cycles,
        "frequency": case.drive.frequency,
        "angle": case.drive.angle,
        "inclination": case.trough.inclination,
        "friction": case.material.friction,
        "wall": wall_summary(case),
        "contact_model": case.contact.model,
        **sim.law.tangential_coefficients(),
        "contact_law": sim.law.report(),
        "grains": sim.n_grains,
        "bed": bed_summary(case),
        "per_type": type_summary(case, sim, progress),
        "spheres": sim.spheres.n,
        "total_mass": total_mass,
        "timestep": sim.dt,
        "timestep_limit": sim.timestep_limit,
        "steps": progress.steps,
        "settle_cycles": progress.settle_cycles,
        "settle_cycles_auto": case.run.settle_cycles is None,
        "settle_transient_ended": progress.settle_detected,
        "cycles": len(per_cycle),
        "steadiness": steadiness(case, progress),
        "per_cycle_velocity": [float(u) for u in per_cycle],
        "settle_time_s": progress.settle_time_s,
        "settle_wall_time_s": progress.settle_wall_time_s,
        # compile and fill of the process that filled the trough; frames of every process
        "compile_wall_time_s": progress.compile_wall_time_s,
        "fill_wall_time_s": progress.fill_wall_time_s,
        "frames_wall_time_s": progress.frames_wall_time_s,
        "frames_written": progress.h5_frames if progress.frames else 0,
        "wall_time_s": wall,
        "particle_steps_per_s": sim.spheres.n * progress.steps / wall if wall > 0 else None,
        "neighbour_builds": sim.pairs.builds,
        "threads": n_threads,
        "seed": case.run.seed,
        "feeder": feeder,
        "pointmass_velocity_norm": pm_norm,
        "pointmass_method": pm_method,
        "pointmass_bounded_velocity_norm": pointmass_bounded(case),
        **reference_fields(case),
        "dem_version": provenance["versions"]["dem"],
        "git_commit": provenance["git_commit"],
        "provenance": provenance,
    }


def type_summary(case, sim: Simulation, progress: Progress) -> list[dict] | None:
    """Each grain type of a case with several types or sizes (``particles.types``); else None.

    Per type: its name, fraction (by number), density, size distribution, what the fill placed
    (count, mean, smallest and largest radius, m; :func:`dem.scene.sizes.placed`), its share of
    the mass, and its conveying velocity over the measured cycles as the bulk's
    (mass-weighted mean x-velocity per cycle, :func:`dem.run.record.close_cycle`; mean,
    autocorrelated standard error, normalised by the same velocity scale) with its per-cycle
    series.
    """
    from dem.scene.sizes import placed

    kind = sim.grain_type
    if kind is None or not progress.per_cycle_types:
        return None
    s = sim.spheres
    series = np.array(progress.per_cycle_types, dtype=np.float64)
    total = float(np.sum(s.mass))
    out = []
    for k, row in enumerate(placed(s.radius, kind, case.particles.types)):
        stat = measure.conveying_velocity(series[:, k], scale=case.drive.velocity_scale)
        out.append({
            **row,
            "mass_fraction": float(np.sum(s.mass[kind == k])) / total,
            **stat.summary_fields(),
            "per_cycle_velocity": [float(u) for u in series[:, k]],
        })  # fmt: skip
    return out


def bed_summary(case) -> dict | None:
    """The bed's depth as layers, height and mass per area, and which one the case gave.

    :func:`dem.scene.depth.bed`; None for a mesh trough or a feeder (no flat section).
    """
    from dem.scene import depth

    if case.trough.mesh is not None or case.feeder is not None:
        return None
    return depth.bed(case.particles, case.material.density, case.trough.length,
                     case.trough.width)  # fmt: skip


def feeder_summary(case, sim: Simulation, progress: Progress) -> dict | None:
    """A finite feeder's discharge: its rate per measured cycle, steady value and balance."""
    f = sim.feeder
    if f is None:
        return None
    rates = np.array(progress.discharge_per_cycle or [], dtype=np.float64)
    hold = np.array(progress.hold_up_per_cycle or [], dtype=np.float64)
    mean = stderr = math.nan
    tau = 0.5
    if rates.size:
        mean = float(np.mean(rates))
        if rates.size > 1:
            stderr, tau = measure.correlated_stderr(rates)
    return {
        "length": f.discharge,
        "feed_rate": f.feed_rate,
        "feed_length": f.feed_length,
        "discharge_rate": mean,
        "discharge_rate_stderr": stderr,
        "discharge_autocorrelation_time": tau,
        "discharge_rate_per_cycle": [float(r) for r in rates],
        "mean_mass_in_trough": float(np.mean(hold)) if hold.size else sim.total_mass,
        "grains_inserted": f.inserted,
        "grains_in_trough": sim.n_grains,
        "grains_discharged": f.discharged,
        "mass_inserted": f.inserted_mass,
        "mass_discharged": f.discharged_mass,
        "feed_backlog": f.backlog,
        "domain_length": sim.trough.length,
    }


def pointmass_reference(case) -> tuple[float, str]:
    """The point mass's v / (velocity scale) on the case's drive, and the method that gave it.

    The paper's line drive: the event-driven model; two components: the point mass stepped in
    time on the same motion (:mod:`dem.pointmass.elliptic`).
    """
    from dem import pointmass

    m = case.wall_material  # the point mass touches the floor only
    if not case.drive.is_single:
        from dem.pointmass import elliptic

        r = elliptic.velocity(
            case.drive.motion, m.friction, case.trough.inclination,
            m.restitution_tangential, m.restitution_normal,
        )  # fmt: skip
        return r.velocity_norm, "stepped (two-component drive)"
    return pointmass.velocity(
        throw_number=case.drive.throw_number,
        angle=case.drive.angle,
        friction=case.wall_material.friction,
        inclination=case.trough.inclination,
        eps_t=case.wall_material.restitution_tangential,
        eps_n=case.wall_material.restitution_normal,
    ).velocity_norm, "event-driven (the paper's model)"


def pointmass_bounded(case) -> float | None:
    """The Coulomb-bounded point mass (the DEM's reference) on a line drive; None otherwise.

    It differs from the paper's model where Eq. 12 asks a landing for more tangential impulse
    than friction can give (:data:`dem.pointmass.model.IMPACT_LAWS`).
    """
    from dem import pointmass

    if not case.drive.is_single:
        return None
    m = case.wall_material  # the point mass touches the floor only
    return pointmass.velocity(
        case.drive.throw_number, case.drive.angle, m.friction, case.trough.inclination,
        m.restitution_tangential, m.restitution_normal, impact="coulomb",
    ).velocity_norm  # fmt: skip


def grains_roll(case) -> bool:
    """Whether the case's grains can roll: spheres with ``particles.rotation`` on.

    Screws and clumps are not claimed (a screw lying across the trough rolls on its shank, but
    it is no sphere and it need not lie across), nor spheres whose rotation is locked (blocks,
    the point mass's DEM twin).
    """
    return case.particles.shape == "sphere" and case.particles.rotation


def start_momentum(case) -> float:
    """P of :mod:`dem.pointmass.rolling` for a grain at rest on the trough as the drive starts.

    Such a grain has the trough's velocity along x in the laboratory, s'_x(0), and no spin, so
    P = s'_x(0) / (A omega cos phi): 1 for a line drive, 0 for a ramped one.
    """
    motion = case.drive.motion
    return float(motion.velocity(0.0)[0]) / motion.velocity_scale


def pointmass_rolling(case) -> float | None:
    """The rolling sphere's v_norm on the case's line drive and level trough, else None.

    :func:`dem.pointmass.rolling.velocity` with the wall's friction and restitutions (the grain
    touches only the floor), a solid sphere (k = 2/5, as the DEM's spheres), the ``"centre"``
    landing (the impact-aware law's: eps_t of the centre's velocity, never past rolling), each
    landing capped by Coulomb, and the case's start (:func:`start_momentum`). None for grains
    that cannot roll (:func:`grains_roll`), a two-component drive, or an inclined trough (where
    a free sphere has no steady state).
    """
    from dem.pointmass import rolling

    if not grains_roll(case) or not case.drive.is_single or case.trough.inclination != 0.0:
        return None
    m = case.wall_material
    return rolling.velocity(
        case.drive.throw_number, case.drive.angle, m.friction, 0.0, m.restitution_tangential,
        m.restitution_normal, inertia_factor=rolling.SOLID_SPHERE, momentum=start_momentum(case),
    ).velocity_norm  # fmt: skip


def reference_fields(case) -> dict:
    """The summary's single-grain references: the rolling sphere, and which one applies and why.

    ``reference`` names the summary key ``<reference>_velocity_norm`` that holds the applicable
    reference: ``"pointmass_rolling"`` (spheres free to roll: :func:`pointmass_rolling`),
    ``"pointmass_bounded"`` (grains that cannot roll, line drive), ``"pointmass"`` (grains that
    cannot roll, two-component drive: the stepped point mass), or None (spheres free to roll
    where no rolling steady state exists or is computed); ``reference_reason`` says why in
    words.
    """
    from dem.pointmass import rolling

    roll = pointmass_rolling(case)
    out = {"pointmass_rolling_velocity_norm": roll}
    pt = case.particles
    if not grains_roll(case):
        if pt.shape != "sphere":
            why = (f"the grains are {pt.shape}s: no rolling reference is claimed for them (a "
                   "rolling model is for round grains), so the single grain's reference is the "
                   "point mass")  # fmt: skip
        else:
            why = ("particles.rotation = false: the spheres cannot roll, they slide as blocks "
                   "(the point mass's DEM twin)")  # fmt: skip
        if case.drive.is_single:
            return out | {"reference": "pointmass_bounded",
                          "reference_reason": why + "; its landings capped by Coulomb, as the "
                          "DEM's contacts are"}  # fmt: skip
        return out | {"reference": "pointmass",
                      "reference_reason": why + "; a two-component drive: the point mass "
                      "stepped in time on the same motion"}  # fmt: skip
    rolls = "the grains are spheres free to rotate: a single one rolls where the point mass sticks"
    if not case.drive.is_single:
        return out | {"reference": None,
                      "reference_reason": rolls + "; the rolling sphere is computed for line "
                      "drives only, and the point mass (the sphere with its rotation locked) "
                      "is no reference for a grain that rolls"}  # fmt: skip
    if roll is None:
        k = rolling.SOLID_SPHERE
        a = GRAVITY * math.sin(math.radians(abs(case.trough.inclination))) / (1.0 + k)
        return out | {"reference": None,
                      "reference_reason": rolls + f"; on a trough inclined by "
                      f"{case.trough.inclination:g} deg a free sphere has no steady state: "
                      f"whatever the drive it rolls downhill at g sin(alpha) / (1 + 2/5) = "
                      f"{a:.3g} m/s^2 on average (dem.pointmass.rolling), so no single grain "
                      "conveys at a steady velocity"}  # fmt: skip
    why = (rolls + ", so its reference is the rolling sphere (dem.pointmass.rolling: solid, "
           "I = 2/5 m r^2, the wall's friction and restitutions, landings capped by Coulomb; the "
           "point mass is the same sphere with its rotation locked)")  # fmt: skip
    p = start_momentum(case)
    start = ("a drive switched on at phase 0" if p == 1.0
             else "a ramped drive (not the 1 of a drive switched on at phase 0)")  # fmt: skip
    why += (f"; a lone free sphere keeps its momentum about the contact line (friction and "
            f"landings act at the contact), so its mean velocity is set by how it started, "
            f"P = {p:g} for {start}, not by the drive alone: contacts with other grains in a "
            "bed, or rolling friction, remove that memory")  # fmt: skip
    if case.wall_material.rolling_friction > 0.0:
        why += (f"; the wall's rolling friction ({case.wall_material.rolling_friction:g}) is "
                "not in the rolling model")  # fmt: skip
    return out | {"reference": "pointmass_rolling", "reference_reason": why}


def components(case) -> list[dict]:
    """The drive's components as the summary lists them (angles and phase in degrees)."""
    d = case.drive
    out = [{"amplitude": d.amplitude, "angle": d.angle, "phase": 0.0}]
    if not d.is_single:
        out.append({"amplitude": d.second_amplitude, "angle": d.second_angle,
                    "phase": d.second_phase})  # fmt: skip
    return out


def wall_summary(case) -> dict:
    """The grain-wall values in use, and which ``[wall]`` gave (the rest are the material's)."""
    w = case.wall_material
    return {"friction": w.friction, "restitution_normal": w.restitution_normal,
            "restitution_tangential": w.restitution_tangential,
            "rolling_friction": w.rolling_friction,
            "given": list(case.wall.given) if case.wall is not None else []}  # fmt: skip


#: Case keys a resumed run may change: how long it runs and where its name comes from.
RESUMABLE_KEYS = ("name", "directory", "source", "run.cycles")
#: Case keys added after checkpoints (and sweep records) were first written, with the value
#: every older record ran with: an older record without the key is taken to hold that value.
ADDED_KEYS: dict[str, object] = {
    "run.device": "cpu",
    "particles.layers": None,
    "particles.bed_height": None,
    "particles.mass_per_area": None,
    "run.target_error": None,
    "run.max_replicas": 12,
    "output.flight_phases": 0,
    "output.contacts": False,
    "particles.types": [],
}


def fingerprint(case) -> dict:
    """The resolved case as flat JSON data, {"table.key": value}: what a checkpoint records."""
    flat: dict = {}

    def walk(prefix: str, value) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else k, v)
        else:
            flat[prefix] = value

    walk("", json.loads(json.dumps(case.as_dict(), default=str)))
    for key in RESUMABLE_KEYS:
        flat.pop(key, None)
    return flat


def fingerprint_changes(before: dict | None, now: dict) -> list[str]:
    """Each key that differs, as "key = old (now new)"; none for a checkpoint without a record."""
    if before is None:
        return []
    before = ADDED_KEYS | before
    keys = sorted(set(before) | set(now))
    return [
        f"{k} = {before.get(k)!r} (now {now.get(k)!r})" for k in keys if before.get(k) != now.get(k)
    ]
