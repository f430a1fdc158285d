"""The impact-aware tangential law: virtual impacts, and one grain against the point mass.

Regenerates the CSV files, provenance.json and figures of this folder (README.md shows them):

    .venv/bin/python validation/impact-law/run.py impacts    # eps_t vs incidence/speed, ~2 min
    .venv/bin/python validation/impact-law/run.py sliding    # 24 drives x 6 stiffnesses, ~6 min
    .venv/bin/python validation/impact-law/run.py hopping    # Figs. 6 and 7, sphere and screw
    .venv/bin/python validation/impact-law/run.py sliding_before  # the same under "coulomb"
    .venv/bin/python validation/impact-law/run.py compliance  # sliding.csv vs a compliant floor
    .venv/bin/python validation/impact-law/run.py all
    .venv/bin/python validation/impact-law/run.py figures    # redraw from the CSV files

Every run uses the library's defaults for the law (``[contact] tangential = "impact"``, no
calibration, no per-drive setting): the grains are cases/single-sphere (r = 2 mm steel, rotation
locked unless stated) and the screw of cases/screw-trough (2.5 g, 8 spheres, laid along the
trough on head and tip, rotation locked), placed by dem.engine.setup.from_grains and measured by
dem.engine.simulation.measure_cycles. The reference is the Coulomb-bounded point mass
(``dem.pointmass.velocity(..., impact="coulomb")``), which equals the paper's model except at
landings where Eq. 12 asks for more tangential impulse than friction gives.
"""

import argparse
import dataclasses
import importlib.util
import json
import math
import sys
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from dem import pointmass, provenance
from dem.config import GRAVITY
from dem.engine import setup
from dem.engine.simulation import measure_cycles
from dem.physics.measure import conveying_velocity
from dem.scene.case import load_case
from dem.scene.fill import random_orientations
from dem.studies import calibrate

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))  # validation._lib
SETTLE, CYCLES = 30, 20
#: (model, stiffness) of the sliding map: Hertz from the bed's 5e7 Pa up 100x; linear from the
#: single sphere's shipped 1.6e7 N/m down 100x (above it the step gets too short to sweep)
STIFFNESSES = [("hertz_mindlin", 5e7), ("hertz_mindlin", 5e8), ("hertz_mindlin", 5e9),
               ("linear", 1.6e5), ("linear", 1.6e6), ("linear", 1.6e7)]  # fmt: skip


def _single_screw_module():
    path = HERE.parent / "single-screw" / "run.py"
    spec = importlib.util.spec_from_file_location("single_screw", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: The tangential law every run uses: "impact" (the default); ``--before`` runs "coulomb", the
#: previous default, with k_t / k_n from eps_t (no per-drive calibration), for the comparison.
LAW = {"tangential": "impact"}


def sphere_case(model="linear", stiffness=1.6e7, *, rotation=False, eps_t=0.8, **drive):
    case = load_case(ROOT / "cases" / "single-sphere")
    contact = dataclasses.replace(
        case.contact, model=model, tangential=LAW["tangential"], tangential_stiffness_ratio=None,
        tangential_damping_ratio=None,
        youngs_modulus=stiffness if model == "hertz_mindlin" else None,
        stiffness=stiffness if model == "linear" else None,
    )  # fmt: skip
    case = dataclasses.replace(
        case,
        contact=contact,
        material=dataclasses.replace(case.material, restitution_tangential=eps_t),
        particles=dataclasses.replace(case.particles, rotation=rotation),
    )
    return _with_drive(case, **drive)


def screw_case(model="linear", stiffness=4.0e7, *, eps_t=0.8, **drive):
    base = load_case(ROOT / "cases" / "screw-trough", AS_MEASURED["screw-trough"])
    case = dataclasses.replace(
        base,
        contact=dataclasses.replace(
            base.contact, model=model, tangential=LAW["tangential"],
            youngs_modulus=stiffness if model == "hertz_mindlin" else None,
            stiffness=stiffness if model == "linear" else None,
        ),
        material=dataclasses.replace(base.material, restitution_tangential=eps_t),
        particles=dataclasses.replace(base.particles, count=1, rotation=False),
        run=dataclasses.replace(base.run, timestep=None),
    )  # fmt: skip
    return _with_drive(case, **drive)


def _with_drive(case, throw_number=None, angle=None, friction=None, inclination=None):
    """The case on another drive; the incline first: the amplitude of a throw number depends on
    it (Gamma = A omega^2 sin(phi) / (g cos(alpha)))."""
    if inclination is not None:
        case = dataclasses.replace(
            case, trough=dataclasses.replace(case.trough, inclination=inclination)
        )
    if friction is not None:
        case = dataclasses.replace(
            case, material=dataclasses.replace(case.material, friction=friction)
        )
    if throw_number is not None:
        case = case.with_drive(angle=angle, throw_number=throw_number)
    return case


def reference(case, impact="coulomb"):
    d, m = case.drive, case.material
    return pointmass.velocity(
        d.throw_number, d.angle, m.friction, case.trough.inclination,
        m.restitution_tangential, m.restitution_normal, impact=impact,
    ).velocity_norm  # fmt: skip


def grain_velocity(job):
    """One grain on the job's drive: a row with the DEM value and both point-mass values."""
    grain, model, stiffness, drive, eps_t = job[:5]
    LAW["tangential"] = job[5] if len(job) > 5 else "impact"
    t0 = time.perf_counter()
    if grain == "sphere":
        case = sphere_case(model, stiffness, eps_t=eps_t, **drive)
        r = case.particles.radius
        sim = setup.from_grains(case, [[0.5 * case.trough.length, 0.0, r]])
    else:
        case = screw_case(model, stiffness, eps_t=eps_t, **drive)
        sim = _single_screw_module().lying_simulation(case, "auto")
    per_cycle = measure_cycles(sim, CYCLES, settle_cycles=SETTLE)
    d = case.drive
    v = conveying_velocity(per_cycle, scale=d.velocity_scale)
    return {
        "grain": grain, "model": model, "stiffness": stiffness, "tangential": LAW["tangential"],
        "throw_number": d.throw_number, "angle": d.angle, "friction": case.material.friction,
        "inclination": case.trough.inclination, "eps_t": eps_t,
        "dem_velocity_norm": v.norm, "dem_stderr": v.norm_stderr,
        "bounded_velocity_norm": reference(case), "paper_velocity_norm": reference(case, "paper"),
        "timestep": sim.dt, "wall_time_s": round(time.perf_counter() - t0, 2),
    }  # fmt: skip


def impact_row(job):
    grain, model, stiffness, rotation, incidence, speed, quat = job
    if grain == "sphere":
        case = sphere_case(model, stiffness, rotation=rotation)
    else:
        case = screw_case(model, stiffness)
        case = dataclasses.replace(
            case, particles=dataclasses.replace(case.particles, rotation=rotation)
        )
    r = calibrate.virtual_impact(case, incidence, speed, quat)
    target = float(calibrate.bounded_targets(0.8, 0.0, case.material.friction, incidence))
    return {
        "grain": grain, "model": model, "stiffness": stiffness, "rotation": rotation,
        "incidence": incidence, "speed": speed, "eps_t": r.eps_t, "eps_n": r.eps_n,
        "target": target, "friction_bound": target > 0.8,
    }  # fmt: skip


def write_csv(rows, name):
    from validation._lib.tables import write_rows

    print(f"wrote {write_rows(HERE / name, rows)}")


def read_csv(name):
    from validation._lib.tables import read_rows

    return read_rows(HERE / name)


def pool_map(func, jobs, processes=2):
    # spawn: the parent may already run OpenMP threads (the point mass), which fork would break
    with get_context("spawn").Pool(processes) as pool:
        return pool.map(func, jobs, chunksize=1)


def impacts():
    jobs = []
    for model, stiffnesses in (("linear", (4e5, 4e6, 4e7)), ("hertz_mindlin", (5e7, 5e8, 5e9))):
        for k in stiffnesses:
            for rotation in (False, True):
                for inc in range(5, 90, 10):
                    for speed in (0.05, 0.3, 1.0):
                        jobs.append(("sphere", model, k, rotation, float(inc), speed, None))
    quats = random_orientations(8, np.random.default_rng(1))
    for rotation in (False, True):
        for inc in range(5, 90, 10):
            for q in quats:
                jobs.append(("screw", "hertz_mindlin", 5e8, rotation, float(inc), 0.3, q))
    write_csv(pool_map(impact_row, jobs), "impacts.csv")


def _sliding_drives():
    """24 drives drawn at random over the sliding map (none of them tuned on)."""
    rng = np.random.default_rng(25)
    drives = []
    while len(drives) < 24:
        d = {
            "throw_number": float(np.round(rng.uniform(0.1, 0.95), 3)),
            "angle": float(np.round(rng.uniform(10.0, 60.0), 1)),
            "inclination": float(np.round(rng.uniform(-5.0, 5.0), 1)),
            "friction": float(np.round(rng.uniform(0.2, 0.6), 2)),
        }
        pm = pointmass.velocity(d["throw_number"], d["angle"], d["friction"], d["inclination"])
        if abs(pm.velocity_norm) > 0.02 and pm.flight == 0.0:  # moves, and never leaves the floor
            drives.append(d)
    return drives


def sliding(before=False):
    """The 24 drives of :func:`_sliding_drives` at 6 stiffnesses; ``before``: the same drives
    under "coulomb" at the Hertz stiffnesses, for comparison."""
    drives = _sliding_drives()
    if before:
        jobs = [("sphere", m, k, d, 0.8, "coulomb") for m, k in STIFFNESSES[:3] for d in drives]
        write_csv(pool_map(grain_velocity, jobs), "sliding_coulomb.csv")
        return
    jobs = [("sphere", m, k, d, 0.8) for m, k in STIFFNESSES for d in drives]
    jobs += [("screw", "linear", 4e7, d, 0.8) for d in drives]
    write_csv(pool_map(grain_velocity, jobs), "sliding.csv")


def sliding_before():
    sliding(before=True)


def compliant_reference(case) -> tuple[float, float]:
    """The bounded point mass on a floor as compliant as the grain's resting contact.

    A resting contact is a spring of stiffness S (linear: k_n; Hertz: the tangent stiffness
    2 Y* sqrt(R delta_0) at the resting overlap delta_0 under m g cos(alpha)), so the trough's
    normal acceleration reaches the grain amplified by the spring's steady response
    f = 1 / (1 - (omega / omega_n)^2), omega_n = sqrt(S / m): a point mass whose normal drive
    is f times the trough's (Gamma f, tan(phi') = f tan(phi): the tangential drive, and so the
    velocity scale A omega cos(phi), unchanged). Returns (v_norm, f).
    """
    d, m = case.drive, case.material
    r, alpha = case.particles.radius, math.radians(case.trough.inclination)
    mass = m.density * 4.0 / 3.0 * math.pi * r**3
    c = case.contact
    if c.model == "linear":
        stiffness = c.stiffness
    else:
        y_star = c.youngs_modulus / (2.0 * (1.0 - c.poisson_ratio**2))
        rest = (mass * GRAVITY * math.cos(alpha) / (4.0 / 3.0 * y_star * math.sqrt(r))) ** (2 / 3)
        stiffness = 2.0 * y_star * math.sqrt(r * rest)
    f = 1.0 / (1.0 - d.omega**2 * mass / stiffness)
    angle = math.degrees(math.atan(f * math.tan(math.radians(d.angle))))
    v = pointmass.velocity(
        d.throw_number * f, angle, m.friction, case.trough.inclination,
        m.restitution_tangential, m.restitution_normal, impact="coulomb",
    )  # fmt: skip
    return v.velocity_norm, f


def compliance():
    """The sliding map's sphere rows against the rigid and the compliant-floor point mass.

    No DEM run: the DEM values are those of sliding.csv; this only adds the reference of a point
    mass on a floor as compliant as the grain's contact (:func:`compliant_reference`), to show
    what the soft contacts' remaining error is.
    """
    rows = []
    for r in read_csv("sliding.csv"):
        if r["grain"] != "sphere":
            continue
        case = sphere_case(r["model"], float(r["stiffness"]), throw_number=float(r["throw_number"]),
                           angle=float(r["angle"]), friction=float(r["friction"]),
                           inclination=float(r["inclination"]))  # fmt: skip
        v_compliant, f = compliant_reference(case)
        dem, rigid = float(r["dem_velocity_norm"]), float(r["bounded_velocity_norm"])
        rows.append({
            "model": r["model"], "stiffness": r["stiffness"], "throw_number": r["throw_number"],
            "angle": r["angle"], "friction": r["friction"], "inclination": r["inclination"],
            "normal_amplification_f": f, "dem_velocity_norm": dem,
            "rigid_bounded_velocity_norm": rigid, "compliant_bounded_velocity_norm": v_compliant,
            "error_vs_rigid": dem / rigid - 1.0, "error_vs_compliant": dem / v_compliant - 1.0,
        })  # fmt: skip
    write_csv(rows, "compliance.csv")


#: The enduring stick's settings compared by ``run.py stick``: (alpha rad per step, zeta).
STICK_SETTINGS = [(0.2, 0.7), (0.5, 0.7), (0.8, 0.5), (0.8, 0.7), (1.2, 0.5), (0.5, 0.5)]
#: The beds whose grains hold many sticking contacts at once (shipped cases, as shipped).
STICK_BEDS = ("sphere-bed", "screw-trough", "u-trough")
#: The beds' keys as shipped when this study was measured (2e9 Pa and 4e-6 s since 2026-11-26).
AS_MEASURED = {"sphere-bed": {"contact.youngs_modulus": 5.0e7, "run.timestep": "auto"},
               "screw-trough": {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6},
               "u-trough": {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}}  # fmt: skip


def _set_stick(rate, zeta):
    """Every law built after this call uses the stick (``rate``, ``zeta``) (a study knob, not
    a case key: the stick is a numerical device sized by the step)."""
    from dem.kernels import contact

    contact.make_params.__kwdefaults__["stick_rate"] = rate
    contact.make_params.__kwdefaults__["stick_damping_ratio"] = zeta


def stick_bed_row(job):
    """One shipped bed as shipped, run with the stick ``(rate, zeta)``: finishes, or the
    instability guard that stopped it; its velocity and the settled bed's jitter."""
    import tempfile

    from dem.run.runner import run_case

    name, rate, zeta = job
    _set_stick(rate, zeta)
    t0 = time.perf_counter()
    row = {"case": name, "stick_rate": rate, "stick_damping_ratio": zeta}
    with tempfile.TemporaryDirectory() as tmp:
        try:
            case = load_case(ROOT / "cases" / name, AS_MEASURED[name])
            s = run_case(case, Path(tmp) / "out", threads=1, cycles=10, progress=False,
                         frames=False)  # fmt: skip
        except Exception as exc:  # the guards' errors are the result here
            row.update(finished=False, error=f"{type(exc).__name__}: {exc}"[:300])
        else:
            row.update(
                finished=True,
                error="",
                velocity_norm=s["mean_velocity_norm"],
                stderr=s["mean_velocity_norm_stderr"],
                settle_cycles=s["settle_cycles"],
                max_overlap_fraction=s["max_overlap_fraction"],
            )
    row["wall_time_s"] = round(time.perf_counter() - t0, 1)
    print(row, flush=True)
    return row


def stick_grain_row(job):
    _set_stick(*job[-2:])
    row = grain_velocity(job[:-2])
    row.update(stick_rate=job[-2], stick_damping_ratio=job[-1])
    return row


#: Inclines of the creep test, as fractions of the friction angle (below it: no creep).
CREEP_FRACTIONS = (0.5, 0.9)


def stick_creep_row(job):
    """Grains at rest on a floor tilted below the friction angle, drive off: a stable stick
    holds them (the creep speed decays to nothing); a stick past its explicit stability limit
    chatters against its Coulomb cap and creeps, or blows up. ``what`` is "screw" (one lying
    screw, rotation free) or "bed" (the screw-trough fill, 200 screws, many sticking contacts
    each). Returns the mean x-velocity over the last of 0.3 s and the rms speed."""
    what, fraction, rate, zeta = job
    _set_stick(rate, zeta)
    incline = math.degrees(math.atan(fraction * 0.35))  # mu 0.35 in both
    base = load_case(ROOT / "cases" / "screw-trough", AS_MEASURED["screw-trough"])
    case = dataclasses.replace(base, trough=dataclasses.replace(base.trough, inclination=incline))
    row = {"what": what, "incline_deg": round(incline, 3), "friction_angle_fraction": fraction,
           "stick_rate": rate, "stick_damping_ratio": zeta}  # fmt: skip
    try:
        if what == "screw":
            case = dataclasses.replace(
                case, particles=dataclasses.replace(case.particles, count=1),
                run=dataclasses.replace(case.run, timestep=None),
            )  # fmt: skip
            sim = _single_screw_module().lying_simulation(case, "auto")
        else:
            sim = setup.from_case(case)
        sim.settle()  # drive off, until at rest (refused if it never rests)
        n = max(1, round(0.05 / sim.dt))
        speeds = []
        for _ in range(6):  # 0.3 s, drive off
            sim.run(n)
            speeds.append((sim.mean_velocity_x(), sim.rms_speed()))
        row.update(finished=True, error="", creep_velocity_m_s=speeds[-1][0],
                   rms_speed_m_s=speeds[-1][1], creep_velocity_first_m_s=speeds[0][0])  # fmt: skip
    except Exception as exc:
        row.update(finished=False, error=f"{type(exc).__name__}: {exc}"[:300])
    print(row, flush=True)
    return row


def stick_creep():
    jobs = [(w, f, r, z) for r, z in STICK_SETTINGS for w in ("screw", "bed")
            for f in CREEP_FRACTIONS]  # fmt: skip
    write_csv(pool_map(stick_creep_row, jobs), "stick_creep.csv")


def stick():
    """The enduring stick's rate: a stiffer stick is closer to Coulomb's rigid stick (the
    sliding map's soft end), but grains with many sticking contacts see their stiffnesses add
    (alpha sqrt(n) per step): the shipped beds show where that stays stable."""
    rows = pool_map(stick_bed_row, [(n, r, z) for r, z in STICK_SETTINGS for n in STICK_BEDS])
    write_csv(rows, "stick_beds.csv")
    stick_creep()
    rng_drives = _sliding_drives()
    jobs = [("sphere", "hertz_mindlin", 5e7, d, 0.8, r, z)
            for r, z in STICK_SETTINGS for d in rng_drives]  # fmt: skip
    write_csv(pool_map(stick_grain_row, jobs), "stick_sliding.csv")


def hopping():
    gammas = [float(g) for g in np.round(np.arange(1.1, 5.01, 0.3), 2)]
    jobs = []
    for grain, model, k in (("sphere", "linear", 1.6e7), ("screw", "linear", 4e7)):
        for e in (0.2, 0.5, 0.8):
            jobs += [(grain, model, k, {"throw_number": g, "angle": 25.0, "friction": 0.35}, e)
                     for g in gammas]  # fmt: skip
        for mu in (0.25, 0.35, 0.6):
            jobs += [(grain, model, k, {"throw_number": 1.8, "angle": float(a), "friction": mu},
                      0.8) for a in range(10, 71, 10)]  # fmt: skip
    write_csv(pool_map(grain_velocity, jobs), "hopping.csv")


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def figures():
    plt = _plt()
    if (HERE / "impacts.csv").exists():
        rows = read_csv("impacts.csv")
        fig, axes = plt.subplots(1, 2, figsize=(10, 4), dpi=120, sharey=True)
        for ax, grain in zip(axes, ("sphere", "screw"), strict=True):
            for rotation, marker, alpha in ((False, "o", 0.6), (True, "x", 0.35)):
                sel = [r for r in rows if r["grain"] == grain and r["rotation"] == rotation]
                label = f"rotation {'free' if rotation else 'locked'}"
                ax.plot([r["incidence"] for r in sel], [r["eps_t"] for r in sel], marker, ms=4,
                        alpha=alpha, label=label)  # fmt: skip
            grid = np.linspace(2, 88, 200)
            ax.plot(grid, calibrate.bounded_targets(0.8, 0.0, 0.35, grid), "k-", lw=1,
                    label="target: 0.8, or the Coulomb bound 1 - mu cot(theta)")  # fmt: skip
            ax.set_xlabel("incidence theta (deg from the floor normal)")
            ax.set_title(
                f"{grain}: eps_t = 0.8, mu = 0.35, eps_n = 0 ("
                + (
                    "linear and Hertz, 3 stiffnesses each, 0.05-1 m/s)"
                    if grain == "sphere"
                    else "Hertz 5e8 Pa, 8 random orientations, 0.3 m/s)"
                ),
                fontsize=8,
            )
            ax.set_ylim(0.6, 1.05)
            ax.grid(alpha=0.3)
        axes[0].set_ylabel("eps_t (centre of mass, after / before)")
        axes[0].legend(fontsize=7)
        axes[1].text(
            6,
            0.62,
            "a rotating screw's centre turns normal into tangential speed:\n"
            "off the plot at small incidence (geometry, not the contact law)",
            fontsize=7,
        )
        fig.tight_layout()
        fig.savefig(HERE / "impacts.png")
        print(f"wrote {HERE / 'impacts.png'}")
    if (HERE / "sliding.csv").exists():
        rows = read_csv("sliding.csv")
        fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
        for model, marker in (("hertz_mindlin", "o"), ("linear", "s")):
            sel = [r for r in rows if r["grain"] == "sphere" and r["model"] == model]
            ks = sorted({r["stiffness"] for r in sel})
            err = [[100 * abs(r["dem_velocity_norm"] / r["bounded_velocity_norm"] - 1)
                    for r in sel if r["stiffness"] == k] for k in ks]  # fmt: skip
            ax.plot(ks, [np.median(e) for e in err], marker + "-", label=f"{model}: median")
            ax.plot(ks, [np.max(e) for e in err], marker + "--", label=f"{model}: worst")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("stiffness (Pa for Hertz, N/m for linear)")
        ax.set_ylabel("|v_DEM / v_point mass - 1| (%)")
        ax.set_title("sphere, rotation locked, 24 sliding drives", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(HERE / "sliding.png")
        print(f"wrote {HERE / 'sliding.png'}")
    if (HERE / "hopping.csv").exists():
        _hopping_figure(plt, read_csv("hopping.csv"))


def _panel(ax, x, curves, points, xkey):
    """Bounded point mass (solid), the paper's (dotted), shaded between, DEM markers.

    ``curves``: (label, paper v_norm, bounded v_norm) per family; ``points``: the DEM rows of
    each family, drawn against ``xkey``.
    """
    for i, ((label, paper, bounded), sel) in enumerate(zip(curves, points, strict=True)):
        ax.plot(x, paper, ":", color=f"C{i}", lw=1)
        ax.plot(x, bounded, "-", color=f"C{i}", lw=1, label=f"bounded point mass, {label}")
        ax.fill_between(x, paper, bounded, where=np.abs(bounded - paper) > 1e-3,
                        color=f"C{i}", alpha=0.12)  # fmt: skip
        for grain, marker in (("sphere", "o"), ("screw", "^")):
            mine = [r for r in sel if r["grain"] == grain]
            ax.plot([r[xkey] for r in mine], [r["dem_velocity_norm"] for r in mine], marker,
                    color=f"C{i}", mfc="none", ms=5)  # fmt: skip
    ax.set_ylabel("v / (A omega cos phi)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _hopping_figure(plt, rows):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), dpi=120)

    def v(*args):
        paper = pointmass.velocities(*args)["velocity_norm"]
        return paper, pointmass.velocities(*args, impact="coulomb")["velocity_norm"]

    g = np.linspace(0.2, 5.0, 400)
    fig6 = [r for r in rows if r["angle"] == 25.0 and r["friction"] == 0.35]
    _panel(
        axes[0], g, [(f"eps_t {e}", *v(g, 25.0, 0.35, 0.0, e, 0.0)) for e in (0.2, 0.5, 0.8)],
        [[r for r in fig6 if r["eps_t"] == e] for e in (0.2, 0.5, 0.8)], "throw_number",
    )  # fmt: skip
    axes[0].set_xlabel("throw number Gamma")
    axes[0].set_title("Fig. 6: phi 25 deg, mu 0.35 (dotted: paper's Eq. 12; shaded: it breaks "
                      "Coulomb; o sphere, ^ screw)", fontsize=8)  # fmt: skip
    phi = np.linspace(5.0, 75.0, 300)
    fig7 = [r for r in rows if r["throw_number"] == 1.8 and r["eps_t"] == 0.8]
    _panel(
        axes[1], phi, [(f"mu {mu}", *v(1.8, phi, mu, 0.0, 0.8, 0.0)) for mu in (0.25, 0.35, 0.6)],
        [[r for r in fig7 if r["friction"] == mu] for mu in (0.25, 0.35, 0.6)], "angle",
    )  # fmt: skip
    axes[1].set_xlabel("vibration angle phi (deg)")
    axes[1].set_title("Fig. 7: Gamma 1.8, eps_t 0.8 (o sphere, ^ screw)", fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "hopping.png")
    print(f"wrote {HERE / 'hopping.png'}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "part",
        choices=(
            "impacts",
            "sliding",
            "sliding_before",
            "hopping",
            "stick_creep",
            "compliance",
            "stick",
            "all",
            "figures",
        ),
    )
    args = parser.parse_args()
    parts = ("impacts", "sliding", "hopping") if args.part == "all" else (args.part,)
    record = {}
    if (HERE / "provenance.json").exists():
        record = json.loads((HERE / "provenance.json").read_text())
    for part in parts:
        if part != "figures":
            t0 = time.perf_counter()
            globals()[part]()
            record[part] = {**provenance.record(), "command": " ".join(sys.argv),
                            "wall_time_s": round(time.perf_counter() - t0, 1)}  # fmt: skip
    (HERE / "provenance.json").write_text(json.dumps(record, indent=2, default=str) + "\n")
    figures()


if __name__ == "__main__":
    main()
