"""dem's rigid screws (clumps of spheres) against LIGGGHTS-PUBLIC 3.8 multisphere.

Regenerates results.json, impact.png and the decks under decks/ in this folder:

    .venv/bin/python validation/liggghts-screws/run.py                 # everything (~5 min)
    .venv/bin/python validation/liggghts-screws/run.py --part bulk     # part A only
    .venv/bin/python validation/liggghts-screws/run.py --part impact   # part B only
    .venv/bin/python validation/liggghts-screws/run.py --report-only   # table + impact.png

One simulation at a time, dem on one numba thread, LIGGGHTS on one rank (``liggghts -in
in.dem`` in a scratch copy of the deck). Run folders go to scratch/ (git-ignored).

Part A, bulk: ``cases/screw-trough`` (200 screws of 8 spheres, 2.5 g, Hertz E = 5e7 Pa,
mu = 0.35, 60 Hz, phi = 25 deg, Gamma = 1.8) with restitution_normal = 0.06 in both codes
(LIGGGHTS refuses e <= 0.05), 5 settle + 10 measured cycles, seeds 1, 2, 3, and rotation locked
(seed 1). The same explicit time step in both codes: dt = 1/5482 of the drive period
(3.0402529490453606e-06 s, dem's automatic step for this case at commit 425bb6c), and all four
runs again at 2 dt as a check. LIGGGHTS: ``write_deck(case, dir, timestep=dt,
steps=cycles/f/dt)``; the mean
x-velocity of the bodies' centres of mass is written to vx_mean.txt in windows of
1/(f frames_per_cycle) (absolute step multiples, not aligned to drive phase 0); the windows
after fill + settle (the first two ``run N`` of in.dem) are grouped in blocks of
frames_per_cycle = one drive period each, giving per-cycle means. dem: ``run_case`` (own fill
and settle), per-cycle means from its summary. Both: v = mean of the per-cycle means, standard
error std(ddof=1)/sqrt(cycles).

Part B, single impacts: one body, no drive, static gravity, 0.15 s, Hertz e = 0.5, mu = 0.35,
periodic 0.06 m x 0.06 m section of the case's trough. LIGGGHTS inserts it with
``fix insert/pack`` (constant velocity, spin and orientation) into a 1 mm box; its state after
the first step is read back (``compute multisphere/single``, or x[1], vx[1] and
``property/atom omegax`` for a plain sphere) and dem starts from exactly that state; both are
then compared at the same times. Bodies: the screw of the case; a sphere r = 3.6 mm, 2.5 g as a
two-sphere clump (a 1 mm sphere inside it: LIGGGHTS multisphere needs >= 2 spheres); the same
sphere as a plain LIGGGHTS sphere (``nve/sphere``) against dem's plain sphere and dem's
one-sphere clump. Time steps 5e-7 s and 2e-6 s. ``replica_sphere`` integrates the plain
sphere once more in Python with the contact law of dem.kernels.contacts and either lever arm of
a wall contact (dem: r - delta, LIGGGHTS: r - delta/2) to show where the plain-sphere
difference comes from.

Not part of the test suite.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import math
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

from dem import __version__, measure, shapes  # noqa: E402
from dem.case import load_case  # noqa: E402
from dem.io.liggghts import (  # noqa: E402
    DECK_NAME,
    LOOP_RE,
    VERSION_RE,
    VX_FILE,
    machine_info,
    write_deck,
)
from dem.kernels import contacts  # noqa: E402
from dem.kernels.rigid import quat_to_matrix  # noqa: E402
from dem.simulation import ContactLaw, Simulation  # noqa: E402
from dem.state import Bodies, Spheres  # noqa: E402
from dem.trough import Trough  # noqa: E402

CASE = ROOT / "cases" / "screw-trough"
SCRATCH = HERE / "scratch"
DECKS = HERE / "decks"
RESULTS = HERE / "results.json"

# --- part A
BULK_RESTITUTION = 0.06  # both codes; LIGGGHTS refuses e <= 0.05
BULK_SETTLE_CYCLES = 5
BULK_CYCLES = 10
BULK_SEEDS = (1, 2, 3)
BULK_LOCKED_SEED = 1
# Both codes get the same explicit step: 1/5482 of the 60 Hz period = 3.0402529490453606e-06 s,
# dem's automatic step for this case at commit 425bb6c (the hand runs). Pinned because dem's
# automatic clump step is being changed (6.36e-6 s in the working tree of 2026-11-21 17:50 UTC).
# The second value, twice as long, checks how much the comparison depends on dt.
BULK_STEPS_PER_PERIOD = (5482, 2741)
RUN_RE = re.compile(r"^run (\d+)", re.MULTILINE)

# --- part B
IMPACT_RESTITUTION = 0.5
IMPACT_SECTION = 0.06  # m, length (periodic) and width of the section
IMPACT_TIME = 0.15  # s
IMPACT_DT = (5e-7, 2e-6)  # s; the first is the reference, the second checks integration
IMPACT_OUTPUT = 2.5e-4  # s between output rows
IMPACT_X0 = (0.03, 0.0, 0.02)  # m, corner of the 1 mm insertion box
IMPACT_V0 = (0.2, 0.1, 0.0)  # m/s
IMPACT_W0 = (5.0, -20.0, 10.0)  # rad/s
IMPACT_Q0 = (0.9, 0.2, 0.3, 0.1)  # orientation (w, x, y, z), normalised
SPHERE_RADIUS = 0.0036  # m
SPHERE_MASS = 0.0025  # kg
INNER_RADIUS, INNER_OFFSET = 0.001, 0.001  # m, the hidden member of the two-sphere clump
BODIES = ("screw", "sphere_clump", "sphere_plain")
START_FILE, TRAJ_FILE, MEMBERS_FILE = "start.txt", "traj.txt", "members.txt"
FLIGHT_TOL = 1e-9  # m/s: rows whose velocity moved less than this are free flight


def now() -> str:
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def git_commit() -> str | None:
    try:
        done = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        )
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "dem"],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
    except OSError:
        return None
    return done.stdout.strip() + (" + uncommitted changes in dem/" if dirty.stdout.strip() else "")


def run_liggghts(work: Path) -> tuple[str, float, list]:
    """Run ``liggghts -in in.dem`` in ``work``; returns (stdout, wall s, Loop-time tuples)."""
    exe = shutil.which("liggghts")
    if exe is None:
        raise SystemExit("liggghts is not on PATH (apt-get install -y liggghts)")
    t0 = time.perf_counter()
    done = subprocess.run([exe, "-in", DECK_NAME], cwd=work, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    (work / "stdout.txt").write_text(done.stdout + done.stderr)
    loops = LOOP_RE.findall(done.stdout)
    if done.returncode != 0 or not loops:
        raise SystemExit(f"LIGGGHTS failed in {work}:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return done.stdout, wall, loops


def liggghts_version(stdout: str) -> str | None:
    found = VERSION_RE.search(stdout)
    return found.group(1) if found else None


def fresh_copy(deck_dir: Path, work: Path) -> None:
    if work.exists():
        shutil.rmtree(work)
    shutil.copytree(deck_dir, work)


def fmt(x) -> str:
    """A float exactly (shortest repr), also for numpy scalars."""
    return repr(float(x))


def rel(path: Path) -> str:
    return str(Path(path).resolve().relative_to(ROOT))


# =========================================================================== part A: bulk
def bulk_cases() -> dict:
    """Seeds 1-3 with rotation and seed 1 with rotation locked, at each pinned time step."""
    base = load_case(CASE)
    out = {}
    for k, per_period in enumerate(BULK_STEPS_PER_PERIOD):
        dt = 1.0 / (base.drive.frequency * per_period)
        for seed, rotation in [(s, True) for s in BULK_SEEDS] + [(BULK_LOCKED_SEED, False)]:
            case = dataclasses.replace(
                base.with_tangential("liggghts"),
                material=dataclasses.replace(base.material, restitution_normal=BULK_RESTITUTION),
                particles=dataclasses.replace(base.particles, rotation=rotation),
                run=dataclasses.replace(
                    base.run,
                    settle_cycles=BULK_SETTLE_CYCLES,
                    cycles=BULK_CYCLES,
                    seed=seed,
                    timestep=dt,
                ),
            )
            tag = f"seed{seed}" + ("" if rotation else "_rotlocked") + ("" if k == 0 else "_dt2x")
            out[tag] = case
    return out


def per_cycle_stats(per_cycle) -> tuple[float, float]:
    u = np.asarray(per_cycle, dtype=float)
    return float(u.mean()), float(u.std(ddof=1) / math.sqrt(u.size))


def bulk_liggghts(case, tag: str, dt: float) -> dict:
    f, fpc = case.drive.frequency, case.output.frames_per_cycle
    steps = round(case.run.cycles / f / dt)
    deck_dir = DECKS / f"bulk_{tag}"
    deck = write_deck(case, deck_dir, timestep=dt, steps=steps)
    runs = [int(n) for n in RUN_RE.findall(deck.read_text())]
    if len(runs) != 3:
        raise SystemExit(f"{deck}: expected three 'run N' lines (fill, settle, measure): {runs}")
    fill, settle, measured = runs
    work = SCRATCH / "liggghts" / f"bulk_{tag}"
    fresh_copy(deck_dir, work)
    stdout, wall, loops = run_liggghts(work)
    atoms = int(loops[-1][3])
    members = case.particles.count * case.particles.grain.count
    if atoms != members:
        raise SystemExit(f"LIGGGHTS kept {atoms} spheres, not {members}")
    data = np.loadtxt(work / VX_FILE, comments="#", ndmin=2)
    start, end = fill + settle, fill + settle + measured
    inside = (data[:, 0] > start) & (data[:, 0] <= end)
    windows = data[inside]
    n_win = case.run.cycles * fpc
    if len(windows) < n_win:
        raise SystemExit(f"{work / VX_FILE}: {len(windows)} measured windows, not {n_win}")
    windows = windows[:n_win]
    sample = int(round(windows[1, 0] - windows[0, 0]))
    per_cycle = windows[:, 1].reshape(case.run.cycles, fpc).mean(axis=1)
    mean, se = per_cycle_stats(per_cycle)
    print(f"  LIGGGHTS {tag}: v = {mean:.5f} +- {se:.5f} m/s ({wall:.0f} s)")
    return {
        "version": liggghts_version(stdout),
        "deck": rel(deck),
        "command": f"cd {rel(work)} && liggghts -in {DECK_NAME}",
        "write_deck": f"write_deck(case, {rel(deck_dir)}, timestep={dt!r}, steps={steps})",
        "timestep": dt,
        "fill_steps": fill,
        "settle_steps": settle,
        "measured_steps": measured,
        "window_steps": sample,
        "first_window_end_step": int(windows[0, 0]),
        "windows_per_cycle": fpc,
        "mean_velocity": mean,
        "mean_velocity_stderr": se,
        "per_cycle_velocity": [float(u) for u in per_cycle],
        "loop_times_s": [float(x[0]) for x in loops],
        "wall_time_s": wall,
    }


def bulk_dem(case, tag: str) -> dict:
    from dem.runner import run_case

    out = SCRATCH / "dem" / f"bulk_{tag}"
    t0 = time.perf_counter()
    s = run_case(case, out, threads=1, progress=False, frames=False, overwrite=True)
    wall = time.perf_counter() - t0
    print(f"  dem      {tag}: v = {s['mean_velocity']:.5f} +- {s['mean_velocity_stderr']:.5f} "
          f"m/s ({wall:.0f} s)")  # fmt: skip
    keys = (
        "mean_velocity", "mean_velocity_stderr", "mean_velocity_norm", "per_cycle_velocity",
        "timestep", "timestep_limit", "steps", "settle_time_s", "settle_wall_time_s",
        "wall_time_s", "threads", "pointmass_velocity_norm",
    )  # fmt: skip
    return {
        "command": f"run_case(case, {rel(out)}, threads=1, progress=False, frames=False, "
        "overwrite=True)",
        **{k: s[k] for k in keys},
        "total_wall_time_s": wall,
    }


def part_bulk(results: dict) -> None:
    section = results.setdefault("bulk", {})
    section.update(
        {
            "case": rel(CASE),
            "restitution_normal": BULK_RESTITUTION,
            "settle_cycles": BULK_SETTLE_CYCLES,
            "cycles": BULK_CYCLES,
        }
    )
    runs = section.setdefault("runs", {})
    cases = bulk_cases()
    first = next(iter(cases.values()))
    auto = Simulation.from_case(
        dataclasses.replace(first, run=dataclasses.replace(first.run, timestep=None))
    )
    section["dem_automatic_timestep_now"] = auto.dt  # for the record only; not used
    for tag, case in cases.items():
        dt = case.run.timestep  # pinned, the same in both codes
        print(f"bulk {tag}: rotation {case.particles.rotation}, dt = {dt:.6g} s")
        d = case.drive
        entry = {
            "date": now(),
            "seed": case.run.seed,
            "rotation": case.particles.rotation,
            "v_norm": measure.drive_velocity_scale(d.amplitude, d.omega, d.angle),
            "liggghts": bulk_liggghts(case, tag, dt),
            "dem": bulk_dem(case, tag),
        }
        entry["pointmass_velocity_norm"] = entry["dem"]["pointmass_velocity_norm"]
        lig, dem = entry["liggghts"], entry["dem"]
        diff = dem["mean_velocity"] - lig["mean_velocity"]
        sigma = math.hypot(dem["mean_velocity_stderr"], lig["mean_velocity_stderr"])
        entry["dem_minus_liggghts"] = {
            "m_per_s": diff,
            "percent": 100.0 * diff / lig["mean_velocity"],
            "sigma": diff / sigma,
        }
        runs[tag] = entry
        RESULTS.write_text(json.dumps(results, indent=2) + "\n")
    for suffix in ("", "_dt2x"):
        free = [runs[f"seed{s}{suffix}"] for s in BULK_SEEDS if f"seed{s}{suffix}" in runs]
        if len(free) < 2:
            continue
        lv = np.array([r["liggghts"]["mean_velocity"] for r in free])
        dv = np.array([r["dem"]["mean_velocity"] for r in free])
        section["seeds_pooled" + suffix] = {
            "liggghts_mean": float(lv.mean()),
            "liggghts_seed_stderr": float(lv.std(ddof=1) / math.sqrt(lv.size)),
            "dem_mean": float(dv.mean()),
            "dem_seed_stderr": float(dv.std(ddof=1) / math.sqrt(dv.size)),
            "percent": float(100.0 * (dv.mean() - lv.mean()) / lv.mean()),
        }
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")


# =========================================================================== part B: impacts
def impact_case():
    """The screw case with e = 0.5 on a 0.06 m x 0.06 m periodic section (drive never on)."""
    base = load_case(CASE)
    return dataclasses.replace(
        base.with_tangential("liggghts"),
        material=dataclasses.replace(base.material, restitution_normal=IMPACT_RESTITUTION),
        trough=dataclasses.replace(base.trough, length=IMPACT_SECTION, width=IMPACT_SECTION),
    )


def grain_of(body: str, case):
    if body == "screw":
        return case.particles.grain
    if body == "sphere_clump":
        return shapes.clump(
            [[0.0, 0.0, 0.0], [INNER_OFFSET, 0.0, 0.0]],
            [SPHERE_RADIUS, INNER_RADIUS],
            mass=SPHERE_MASS,
            name="sphere_clump",
        )
    return shapes.clump([[0.0, 0.0, 0.0]], [SPHERE_RADIUS], mass=SPHERE_MASS, name="sphere")


def unit_q0() -> np.ndarray:
    q = np.asarray(IMPACT_Q0, dtype=float)
    return q / np.linalg.norm(q)


def impact_deck(body: str, case, dt: float, deck_dir: Path) -> Path:
    """Write the single-body deck: insert once, print the state, integrate IMPACT_TIME."""
    deck_dir.mkdir(parents=True, exist_ok=True)
    grain = grain_of(body, case)
    m, c = case.material, case.contact
    mu, e, y, nu = m.friction, m.restitution_normal, c.youngs_modulus, c.poisson_ratio
    half = 0.5 * IMPACT_SECTION
    x0, v0, w0, q = IMPACT_X0, IMPACT_V0, IMPACT_W0, unit_q0()
    every = round(IMPACT_OUTPUT / dt)
    steps = round(IMPACT_TIME / dt)
    model = "model hertz tangential history"
    settings = "limitForce off tangential_damping on"
    if body == "sphere_plain":
        density = SPHERE_MASS / (4.0 / 3.0 * math.pi * SPHERE_RADIUS**3)
        grain_lines = [
            f"fix pts all particletemplate/sphere 15485863 atom_type 1 density constant "
            f"{density!r} radius constant {SPHERE_RADIUS!r}",
        ]
        integrator = "fix integr all nve/sphere"
        state = [
            "compute om all property/atom omegax omegay omegaz",
            "compute wsx all reduce sum c_om[1]",
            "compute wsy all reduce sum c_om[2]",
            "compute wsz all reduce sum c_om[3]",
            "variable x equal x[1]",
            "variable y equal y[1]",
            "variable z equal z[1]",
            "variable vx equal vx[1]",
            "variable vy equal vy[1]",
            "variable vz equal vz[1]",
            "variable wx equal c_wsx",
            "variable wy equal c_wsy",
            "variable wz equal c_wsz",
            *[f"variable q{k} equal {int(k == 0)}" for k in range(4)],
        ]
        members = []
    else:
        shapes.write_clump(deck_dir / "grain.multisphere", grain, frame="body")
        i1, i2, i3 = (fmt(v) for v in grain.moments)
        grain_lines = [
            "# grain.multisphere: members x y z r (m), body frame (centre of mass at the origin,",
            "# principal axes); mass and principal moments exact from dem.shapes",
            f"fix pts all particletemplate/multisphere 15485863 atom_type 1 density constant "
            f"{fmt(grain.density)} nspheres {grain.count} ntry 1000000 spheres file "
            f"grain.multisphere scale 1.0 type 1 mass {fmt(grain.mass)} inertia_tensor {i1} 0.0 "
            f"0.0 {i2} 0.0 {i3} use_volume",
        ]
        integrator = "fix integr all multisphere"
        state = [
            "compute cx all multisphere/single id 1 property xcm",
            "compute cv all multisphere/single id 1 property vcm",
            "compute cw all multisphere/single id 1 property omega",
            "compute cq all multisphere/single id 1 property quat",
            *[f"variable {a} equal c_cx[{k + 1}]" for k, a in enumerate("xyz")],
            *[f"variable v{a} equal c_cv[{k + 1}]" for k, a in enumerate("xyz")],
            *[f"variable w{a} equal c_cw[{k + 1}]" for k, a in enumerate("xyz")],
            *[f"variable q{k} equal c_cq[{k + 1}]" for k in range(4)],
        ]
        # member positions after insertion: LIGGGHTS re-centres the members on a Monte Carlo
        # centre of mass, so they may sit slightly off dem's offsets
        cols = " ".join(f"${{x{i}}} ${{y{i}}} ${{z{i}}}" for i in range(1, grain.count + 1))
        members = [
            *[f"variable {a}{i} equal {a}[{i}]" for i in range(1, grain.count + 1) for a in "xyz"],
            f'fix mem all print 1 "${{t}} {cols}" file {MEMBERS_FILE} screen no',
        ]
    row = "${t} ${x} ${y} ${z} ${vx} ${vy} ${vz} ${wx} ${wy} ${wz} ${q0} ${q1} ${q2} ${q3}"
    lines = [
        f"# single-body impact deck written by validation/liggghts-screws/run.py (dem "
        f"{__version__}): {body}",
        "# no drive, static gravity; columns of start.txt/traj.txt: t x y z vx vy vz wx wy wz "
        "q0 q1 q2 q3",
        "atom_style granular",
        "atom_modify map array" + ("" if body == "sphere_plain" else " sort 0 0"),
        "boundary p f f",
        "newton off",
        "communicate single vel yes",
        "units si",
        f"region domain block 0.0 {IMPACT_SECTION!r} {-half!r} {half!r} 0.0 0.1 units box",
        "create_box 2 domain",
        "neighbor 0.0009 bin",
        "neigh_modify delay 0",
        f"fix m_mu all property/global coefficientFriction peratomtypepair 2 {mu} {mu} {mu} {mu}",
        f"fix m_Y all property/global youngsModulus peratomtype {y!r} {y!r}",
        f"fix m_nu all property/global poissonsRatio peratomtype {nu!r} {nu!r}",
        f"fix m_e all property/global coefficientRestitution peratomtypepair 2 {e} {e} {e} {e}",
        f"pair_style gran {model} {settings}",
        "pair_coeff * *",
        f"timestep {dt!r}",
        f"fix floor all wall/gran {model} primitive type 2 zplane 0.0 {settings}",
        f"fix side_lo all wall/gran {model} primitive type 2 yplane {-half!r} {settings}",
        f"fix side_hi all wall/gran {model} primitive type 2 yplane {half!r} {settings}",
        "fix grav all gravity 9.81 vector 0.0 0.0 -1.0",
        *grain_lines,
        "fix pdd all particledistribution/discrete 32452843 1 pts 1.0",
        f"region ins block {x0[0]} {x0[0] + 1e-3!r} {x0[1]} {x0[1] + 1e-3!r} {x0[2]} "
        f"{x0[2] + 1e-3!r} units box",
        "fix ins all insert/pack seed 49979687 distributiontemplate pdd maxattempt 1000 "
        f"vel constant {v0[0]} {v0[1]} {v0[2]} omega constant {w0[0]} {w0[1]} {w0[2]} "
        f"orientation constant {fmt(q[0])} {fmt(q[1])} {fmt(q[2])} {fmt(q[3])} insert_every once "
        "overlapcheck yes all_in no particles_in_region 1 region ins",
        integrator,
        "variable t equal time",
        *state,
        *members,
        f'fix first all print 1 "{row}" file {START_FILE} screen no',
        "run 2",
        "unfix first",
        *(["unfix mem"] if members else []),
        f'fix out all print {every} "{row}" file {TRAJ_FILE} screen no',
        f"run {steps - 2}",
        "",
    ]
    deck = deck_dir / DECK_NAME
    deck.write_text("\n".join(lines))
    return deck


def impact_liggghts(body: str, case, dt: float) -> dict:
    tag = f"dt{dt:g}"
    deck_dir = DECKS / f"impact_{tag}" / body
    deck = impact_deck(body, case, dt, deck_dir)
    work = SCRATCH / "liggghts" / f"impact_{tag}" / body
    fresh_copy(deck_dir, work)
    stdout, wall, _ = run_liggghts(work)
    start = np.loadtxt(work / START_FILE, comments="#", ndmin=2)[0]
    traj = np.loadtxt(work / TRAJ_FILE, comments="#", ndmin=2)
    out = {
        "version": liggghts_version(stdout),
        "deck": rel(deck),
        "command": f"cd {rel(work)} && liggghts -in {DECK_NAME}",
        "wall_time_s": wall,
        "start": start.tolist(),
        "traj": traj,
    }
    if body != "sphere_plain":
        grain = grain_of(body, case)
        mem = np.loadtxt(work / MEMBERS_FILE, comments="#", ndmin=2)[0, 1:].reshape(-1, 3)
        rot = quat_to_matrix(start[10:14])
        expected = start[1:4] + np.asarray(grain.centres) @ rot.T
        dev = mem - expected  # the same vector for every member: a shifted centre of mass
        out["member_shift_world_m"] = dev.mean(axis=0).tolist()
        out["member_shift_body_m"] = (rot.T @ dev.mean(axis=0)).tolist()
        out["member_shift_spread_m"] = float(np.ptp(dev, axis=0).max())
    return out


def impact_dem(
    body: str, case, dt: float, start: np.ndarray, times: np.ndarray, shift=None
) -> np.ndarray:
    """dem from LIGGGHTS's state ``start`` (row of start.txt); rows like traj.txt at ``times``.

    ``body`` "sphere_plain" is dem's one-sphere clump, "sphere_plain_dem_sphere" dem's plain
    sphere. ``shift`` (body frame, m) moves every member of the template by the same vector,
    leaving mass and moments as they are: LIGGGHTS's body, whose members sit off the centre of
    mass by the error of its Monte Carlo centre of mass.
    """
    t0, x, v, w, q = start[0], start[1:4], start[4:7], start[7:10], start[10:14]
    trough = Trough.from_case(case)
    law = ContactLaw.from_case(case)
    if body == "sphere_plain_dem_sphere":
        density = SPHERE_MASS / (4.0 / 3.0 * math.pi * SPHERE_RADIUS**3)
        spheres = Spheres.create(np.array([x]), SPHERE_RADIUS, density)
        spheres.v[0] = v
        spheres.omega[0] = w
        sim = Simulation(spheres, trough, law, dt, rotation=True)
    else:
        grain = grain_of(body, case)
        if shift is not None:
            grain = dataclasses.replace(grain, centres=np.asarray(grain.centres) + shift)
        bodies, spheres = Bodies.create(grain, np.array([x]), np.array([q]))
        sim = Simulation(spheres, trough, law, dt, rotation=True, bodies=bodies)
        rot = quat_to_matrix(bodies.q[0])
        bodies.v[0] = v
        bodies.ang_mom[0] = rot @ np.diag(grain.moments) @ rot.T @ w
        bodies.place(sim.spheres)
    rows, done = [], 0
    for t in times:
        target = round((t - t0) / dt)
        sim.run(target - done)
        done = target
        if sim.bodies is None:
            s = sim.spheres
            rows.append([t, *s.x[0], *s.v[0], *s.omega[0], 1.0, 0.0, 0.0, 0.0])
        else:
            b = sim.bodies
            rows.append([t, *b.x[0], *b.v[0], *b.omega[0], *b.q[0]])
    return np.array(rows)


def replica_sphere(start: np.ndarray, times: np.ndarray, case, dt: float, lever: str):
    """The plain sphere on the floor once more, in Python, with a chosen wall lever arm.

    Velocity Verlet (half kick, drift, forces, half kick) as both codes integrate a sphere;
    gravity plus the floor contact through :func:`dem.kernels.contacts.contact_force` (the law
    dem uses and documents as LIGGGHTS's); ``lever`` = "dem" passes c = r - delta, "liggghts"
    c = r - delta/2 (surface_model_default.h: radi - deltan/2 for a wall). Only the floor: the
    sphere never reaches the side walls.
    """
    law = ContactLaw.from_case(case)
    p, model = law.params, law.model_id
    r, m = SPHERE_RADIUS, SPHERE_MASS
    inv_i = 1.0 / (0.4 * m * r * r)
    g = -9.81
    x, v, w = start[1:4].copy(), start[4:7].copy(), start[7:10].copy()
    hist = np.zeros((1, 3))

    def forces():
        delta = r - x[2]
        if delta <= 0.0:
            hist[0] = 0.0
            return np.array([0.0, 0.0, m * g]), np.zeros(3)
        c = r - delta if lever == "dem" else r - 0.5 * delta
        f = contact_force(
            model, p, 0.0, 0.0, 1.0, delta, v[0], v[1], v[2], w[0], w[1], w[2],
            0.0, 0.0, 0.0, c, 0.0, m, r, hist, 0, dt,
        )  # fmt: skip
        return np.array([f[0], f[1], f[2] + m * g]), np.array(f[3:6])

    contact_force = contacts.contact_force.py_func
    f, tq = forces()
    rows, n = [], 0
    for t in times:
        target = round((t - start[0]) / dt)
        while n < target:
            v += 0.5 * dt * f / m
            w += 0.5 * dt * tq * inv_i
            x += dt * v
            f, tq = forces()
            v += 0.5 * dt * f / m
            w += 0.5 * dt * tq * inv_i
            n += 1
        rows.append([t, *x, *v, *w])
    return np.array(rows)


def flight_segments(traj: np.ndarray, min_rows: int = 4) -> list[tuple[int, int]]:
    """Runs of rows (first, last) in free flight: horizontal velocity unchanged row to row."""
    still = np.all(np.abs(np.diff(traj[:, 4:6], axis=0)) < FLIGHT_TOL, axis=1)
    segments, first = [], None
    for i, s in enumerate(still):
        if s and first is None:
            first = i
        if not s and first is not None:
            segments.append((first, i))
            first = None
    if first is not None:
        segments.append((first, len(traj) - 1))
    return [seg for seg in segments if seg[1] - seg[0] + 1 >= min_rows]


def compare_rows(lig: np.ndarray, dem: np.ndarray) -> dict:
    """Differences dem - LIGGGHTS of one output row (t x y z v w q)."""
    vl, vd, wl, wd = lig[4:7], dem[4:7], lig[7:10], dem[7:10]
    return {
        "t": float(lig[0]),
        "v_liggghts": vl.tolist(),
        "v_dem": vd.tolist(),
        "omega_liggghts": wl.tolist(),
        "omega_dem": wd.tolist(),
        "vx_rel_percent": float(100.0 * (vd[0] - vl[0]) / abs(vl[0])),
        "v_rel_percent": float(100.0 * np.linalg.norm(vd - vl) / np.linalg.norm(vl)),
        "omega_rel_percent": float(100.0 * np.linalg.norm(wd - wl) / np.linalg.norm(wl)),
        "dx_um": (1e6 * (dem[1:4] - lig[1:4])).tolist(),
    }


def impact_table(lig: np.ndarray, dem: np.ndarray, n_impacts: int = 2) -> dict:
    """Free flight before the first impact and the states after the first impacts."""
    segs = flight_segments(lig)
    first_contact = segs[0][1] if segs else len(lig) - 1
    before = slice(0, first_contact + 1)
    out = {
        "first_contact_row_time": float(lig[first_contact, 0]),
        "free_flight_max_dx_m": float(np.abs(dem[before, 1:4] - lig[before, 1:4]).max()),
        "free_flight_max_dv": float(np.abs(dem[before, 4:7] - lig[before, 4:7]).max()),
        "free_flight_max_domega": float(np.abs(dem[before, 7:10] - lig[before, 7:10]).max()),
        "after_impact": [],
    }
    for k, (first, _last) in enumerate(segs[1 : n_impacts + 1], start=1):
        row = compare_rows(lig[first], dem[first])
        dem_flying = bool(np.all(np.abs(dem[first + 1, 4:6] - dem[first, 4:6]) < FLIGHT_TOL))
        out["after_impact"].append({"impact": k, "dem_in_flight": dem_flying, **row})
    out["final"] = compare_rows(lig[-1], dem[-1])
    return out


def part_impact(results: dict) -> None:
    case = impact_case()
    section = results.setdefault("impact", {})
    section.update(
        {
            "case": rel(CASE) + " with restitution_normal = 0.5, 0.06 m x 0.06 m section",
            "time_s": IMPACT_TIME,
            "output_every_s": IMPACT_OUTPUT,
            "x0_box_corner": IMPACT_X0,
            "v0": IMPACT_V0,
            "omega0": IMPACT_W0,
            "q0": unit_q0().tolist(),
            "runs": {},
        }
    )
    SCRATCH.mkdir(parents=True, exist_ok=True)
    store = {}
    for dt in IMPACT_DT:
        tag = f"dt{dt:g}"
        for body in BODIES:
            print(f"impact {tag} {body}")
            lig = impact_liggghts(body, case, dt)
            traj = lig.pop("traj")
            start, times = np.array(lig["start"]), traj[:, 0]
            store[f"{tag}/{body}/liggghts"] = traj
            entry = {"date": now(), "timestep": dt, "liggghts": lig, "dem": {}}
            variants = {"dem": (body, None)}
            if body == "sphere_plain":
                variants = {"dem_sphere": ("sphere_plain_dem_sphere", None),
                            "dem_one_sphere_clump": ("sphere_plain", None)}  # fmt: skip
            else:
                shift = np.array(lig["member_shift_body_m"])
                variants["dem_liggghts_members"] = (body, shift)
            for name, (kind, shift) in variants.items():
                t0 = time.perf_counter()
                dem = impact_dem(kind, case, dt, start, times, shift)
                store[f"{tag}/{body}/{name}"] = dem
                entry["dem"][name] = {
                    "wall_time_s": time.perf_counter() - t0,
                    **impact_table(traj, dem),
                }
            if body == "sphere_plain":
                for lever in ("dem", "liggghts"):
                    rep = replica_sphere(start, times, case, dt, lever)
                    store[f"{tag}/{body}/replica_{lever}"] = rep
                    ref = store[f"{tag}/{body}/" + ("dem_sphere" if lever == "dem" else "liggghts")]
                    entry[f"replica_lever_{lever}_max_diff"] = {
                        "against": "dem plain sphere" if lever == "dem" else "LIGGGHTS",
                        "x_m": float(np.abs(rep[:, 1:4] - ref[:, 1:4]).max()),
                        "v_m_per_s": float(np.abs(rep[:, 4:7] - ref[:, 4:7]).max()),
                        "omega_rad_per_s": float(np.abs(rep[:, 7:10] - ref[:, 7:10]).max()),
                    }
            section["runs"][f"{tag}/{body}"] = entry
    np.savez_compressed(SCRATCH / "impact_trajectories.npz", **store)
    results["impact"] = section
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")


# =========================================================================== report
def print_tables(results: dict) -> None:
    bulk = results.get("bulk", {}).get("runs", {})
    if bulk:
        print("\nbulk | v LIGGGHTS | v dem | dem - L (%) | sigma | v_norm | pointmass norm")
        for tag, r in bulk.items():
            lg, dm, df = r["liggghts"], r["dem"], r["dem_minus_liggghts"]
            print(f"{tag} | {lg['mean_velocity']:.4f} +- {lg['mean_velocity_stderr']:.4f} | "
                  f"{dm['mean_velocity']:.4f} +- {dm['mean_velocity_stderr']:.4f} | "
                  f"{df['percent']:+.1f} | {df['sigma']:+.1f} | {r['v_norm']:.4f} | "
                  f"{r['pointmass_velocity_norm']:.3f}")  # fmt: skip
    runs = results.get("impact", {}).get("runs", {})
    if runs:
        print("\nimpact | dem variant | k | t | vx L | vx dem | dvx % | |dv|/|v| % | "
              "|dw|/|w| % | wz L | wz dem")  # fmt: skip
        for key, r in runs.items():
            for name, d in r["dem"].items():
                for a in d["after_impact"]:
                    print(f"{key} | {name} | {a['impact']} | {a['t']:.4f} | "
                          f"{a['v_liggghts'][0]:.5f} | {a['v_dem'][0]:.5f} | "
                          f"{a['vx_rel_percent']:+.2f} | {a['v_rel_percent']:.2f} | "
                          f"{a['omega_rel_percent']:.2f} | {a['omega_liggghts'][2]:.4f} | "
                          f"{a['omega_dem'][2]:.4f}")  # fmt: skip


def plot(results: dict) -> None:
    """impact.png: per body vx(t), omega(t) of both codes and dem - LIGGGHTS, dt = 5e-7 s."""
    path = SCRATCH / "impact_trajectories.npz"
    if not path.exists():
        print(f"no {rel(path)}: run --part impact first; impact.png not drawn")
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    store = np.load(path)
    tag = f"dt{IMPACT_DT[0]:g}"
    titles = {
        "screw": "screw (8-sphere clump)",
        "sphere_clump": "sphere r = 3.6 mm as a 2-sphere clump",
        "sphere_plain": "plain sphere r = 3.6 mm",
    }
    main_dem = {"screw": "dem", "sphere_clump": "dem", "sphere_plain": "dem_sphere"}
    fig, axes = plt.subplots(3, 4, figsize=(18, 10), sharex=True)
    for row, body in enumerate(BODIES):
        lig = store[f"{tag}/{body}/liggghts"]
        dem = store[f"{tag}/{body}/{main_dem[body]}"]
        t = 1e3 * lig[:, 0]
        flying = np.zeros(len(lig), dtype=bool)  # rows in free flight (LIGGGHTS): for y limits
        for first, last in flight_segments(lig):
            flying[first : last + 1] = True
        ax, bx, cx, dx = axes[row]
        ax.plot(t, lig[:, 4], "-", color="C1", lw=2.0, label="LIGGGHTS $v_x$")
        ax.plot(t, dem[:, 4], "--", color="C0", lw=1.3, label="dem $v_x$")
        ax.set_ylabel("$v_x$ (m/s)")
        ax.set_title(titles[body], fontsize=10, loc="left")
        az = ax.twinx()
        az.plot(t, 1e3 * lig[:, 3], color="0.6", lw=0.8, label="z (LIGGGHTS)")
        az.set_ylabel("centre height z (mm)", color="0.5")
        lines = ax.get_legend_handles_labels()
        lines2 = az.get_legend_handles_labels()
        ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=7, loc="upper right")
        for k, comp in enumerate("xyz"):
            bx.plot(t, lig[:, 7 + k], "-", color=f"C{k + 2}", lw=2.0,
                    label=f"LIGGGHTS $\\omega_{comp}$")  # fmt: skip
            bx.plot(t, dem[:, 7 + k], "--", color="k", lw=0.9,
                    label="dem" if k == 0 else None)  # fmt: skip
        bx.set_ylabel(r"$\omega$ (rad/s)")
        bx.legend(fontsize=7, ncol=2, loc="best")
        variants = [(main_dem[body], "-", "C0", "dem")]
        if body != "sphere_plain":
            variants.append(("dem_liggghts_members", "-", "C3", "dem, LIGGGHTS's member offsets"))
        else:
            variants.append(("replica_liggghts", ":", "C3", "Python replica, lever r - delta/2"))
        lim_v, lim_w = [0.0], [0.0]
        for name, style, color, label in variants:
            d = store[f"{tag}/{body}/{name}"]
            dv = 100.0 * (d[:, 4] - lig[:, 4]) / np.abs(lig[:, 4])
            dw = d[:, 9] - lig[:, 9]
            cx.plot(t, dv, style, color=color, lw=1.2, label=label)
            dx.plot(t, dw, style, color=color, lw=1.2, label=label)
            lim_v += [dv[flying].min(), dv[flying].max()]
            lim_w += [dw[flying].min(), dw[flying].max()]
        for axis, lim in ((cx, lim_v), (dx, lim_w)):
            lo, hi = min(lim), max(lim)
            pad = 0.3 * (hi - lo) or 0.01
            axis.set_ylim(lo - pad, hi + pad)
            axis.axhline(0.0, color="k", lw=0.6)
            axis.legend(fontsize=7, loc="lower left")
        cx.set_ylabel("dem - LIGGGHTS: $v_x$ (% of LIGGGHTS)", fontsize=8)
        dx.set_ylabel(r"dem - LIGGGHTS: $\omega_z$ (rad/s)", fontsize=8)
    axes[0, 2].set_title("(clipped to the free-flight range; spikes: contacts)", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t (ms)")
    fig.suptitle(
        "One body dropped on the floor (e = 0.5, mu = 0.35, Hertz E = 5e7 Pa), dem started from "
        f"LIGGGHTS's state after its first step; dt = {IMPACT_DT[0]:g} s",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(HERE / "impact.png", dpi=110)
    print(f"wrote {rel(HERE / 'impact.png')}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("all", "bulk", "impact"), default="all")
    parser.add_argument("--report-only", action="store_true", help="tables + impact.png only")
    args = parser.parse_args(argv)
    # a full run starts results.json afresh; a partial run or --report-only updates it
    results = {}
    if RESULTS.exists() and (args.report_only or args.part != "all"):
        results = json.loads(RESULTS.read_text())
    if not args.report_only:
        import numba

        numba.set_num_threads(1)
        t_start = time.perf_counter()
        results.update(
            {
                "script": "validation/liggghts-screws/run.py "
                + " ".join(sys.argv[1:] if argv is None else argv),
                "date": now(),
                "dem_version": __version__,
                "git_commit": git_commit(),
                "machine": machine_info(),
            }
        )
        if args.part in ("all", "bulk"):
            part_bulk(results)
        if args.part in ("all", "impact"):
            part_impact(results)
        versions = {
            r["liggghts"]["version"]
            for p in ("bulk", "impact")
            for r in results.get(p, {}).get("runs", {}).values()
        }
        results["liggghts_version"] = sorted(v for v in versions if v)
        results[f"wall_time_s_part_{args.part}"] = time.perf_counter() - t_start
        RESULTS.write_text(json.dumps(results, indent=2) + "\n")
    print_tables(results)
    plot(results)


if __name__ == "__main__":
    main()
