"""Part B, single impacts: LIGGGHTS's run of one body, and dem started from its state.

dem starts from LIGGGHTS's state after its first step and writes the same rows at the same
times; compare.py sets the two side by side, replica.py adds the Python replica of the plain
sphere. The trajectories go to scratch/impact_trajectories.npz for report.py's impact.png.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from compare import impact_table
from impact_setup import (
    BODIES,
    IMPACT_DT,
    IMPACT_OUTPUT,
    IMPACT_TIME,
    IMPACT_V0,
    IMPACT_W0,
    IMPACT_X0,
    MEMBERS_FILE,
    SPHERE_MASS,
    SPHERE_RADIUS,
    START_FILE,
    TRAJ_FILE,
    grain_of,
    impact_case,
    impact_deck,
    unit_q0,
)
from replica import replica_sphere
from study import CASE, DECKS, SCRATCH, fresh_copy, rel, write_results

from dem import provenance
from dem.engine import setup
from dem.io.liggghts import DECK_NAME, run_liggghts
from dem.kernels.rigid import quat_to_matrix


def impact_liggghts(body: str, case, dt: float) -> dict:
    """LIGGGHTS on one body's deck: its first state, its trajectory, its members' offsets.

    For clumps, ``member_shift_*`` is how far LIGGGHTS's members sit from where the exact centre
    of mass puts them (the same vector for every member).
    """
    tag = f"dt{dt:g}"
    deck_dir = DECKS / f"impact_{tag}" / body
    deck = impact_deck(body, case, dt, deck_dir)
    work = SCRATCH / "liggghts" / f"impact_{tag}" / body
    fresh_copy(deck_dir, work)
    run = run_liggghts(work, DECK_NAME)
    start = np.loadtxt(work / START_FILE, comments="#", ndmin=2)[0]
    traj = np.loadtxt(work / TRAJ_FILE, comments="#", ndmin=2)
    out = {
        "version": run.version,
        "deck": rel(deck),
        "command": f"cd {rel(work)} && liggghts -in {DECK_NAME}",
        "wall_time_s": run.wall_s,
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
    mass by the error of its Monte Carlo centre of mass. The body is placed by
    ``dem.engine.setup.from_grains`` at LIGGGHTS's position, orientation, velocity and spin (a
    clump's spin through its angular momentum L = R (I * (R^T omega))).
    """
    t0, x, v, w, q = start[0], start[1:4], start[4:7], start[7:10], start[10:14]
    if body == "sphere_plain_dem_sphere":
        density = SPHERE_MASS / (4.0 / 3.0 * math.pi * SPHERE_RADIUS**3)
        one = dataclasses.replace(
            case,
            particles=dataclasses.replace(
                case.particles, shape="sphere", radius=SPHERE_RADIUS, grain=None, rotation=True
            ),
            material=dataclasses.replace(case.material, density=density),
        )
        sim = setup.from_grains(one, [x], velocities=[v], spins=[w], timestep=dt)
    else:
        grain = grain_of(body, case)
        if shift is not None:
            grain = dataclasses.replace(grain, centres=np.asarray(grain.centres) + shift)
        one = dataclasses.replace(
            case, particles=dataclasses.replace(case.particles, grain=grain, rotation=True)
        )
        sim = setup.from_grains(one, [x], orientations=[q], velocities=[v], spins=[w], timestep=dt)
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


def part_impact(results: dict) -> None:
    """Every body at both time steps into ``results["impact"]``; trajectories to scratch/."""
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
            entry = {"date": provenance.utc_now(), "timestep": dt, "liggghts": lig, "dem": {}}
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
    write_results(results)
