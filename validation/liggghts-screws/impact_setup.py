"""Part B, single impacts: the case, the bodies and the LIGGGHTS deck of one dropped body.

One body, no drive, static gravity, IMPACT_TIME s, Hertz e = 0.5, mu = 0.35, on a periodic
0.06 m x 0.06 m section of the case's trough. LIGGGHTS inserts it with ``fix insert/pack``
(constant velocity, spin and orientation) into a 1 mm box and writes its state after the first
step (start.txt), then every IMPACT_OUTPUT s (traj.txt); for clumps also the member positions
after insertion (members.txt).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from study import AS_MEASURED, CASE, fmt

from dem import __version__
from dem.io.liggghts import DECK_NAME, write_clump
from dem.scene import shapes
from dem.scene.case import load_case

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


def impact_case():
    """The screw case with e = 0.5 on a 0.06 m x 0.06 m periodic section (drive never on)."""
    base = load_case(CASE, AS_MEASURED)
    return dataclasses.replace(
        base.with_tangential("liggghts"),
        material=dataclasses.replace(base.material, restitution_normal=IMPACT_RESTITUTION),
        trough=dataclasses.replace(base.trough, length=IMPACT_SECTION, width=IMPACT_SECTION),
    )


def grain_of(body: str, case):
    """dem's template of a body: the case's screw, or the sphere as a two- or one-sphere clump."""
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
    """IMPACT_Q0 normalised: the orientation LIGGGHTS inserts the body with."""
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
        write_clump(deck_dir / "grain.multisphere", grain, frame="body")
        i1, i2, i3 = (fmt(v) for v in grain.moments)
        grain_lines = [
            "# grain.multisphere: members x y z r (m), body frame (centre of mass at the origin,",
            "# principal axes); mass and principal moments exact from dem.scene.shapes",
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
