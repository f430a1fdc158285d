"""One collision through dem's library, measured: the engine half of the contact benchmarks.

A collision is built as the other two-body studies build theirs (validation/impact-law,
validation/lammps-two-grain): the study's case (``case.toml`` beside this file) with keys set
over it (:func:`scene_for`), resolved once, and its grains placed by
:func:`dem.engine.setup.from_grains` with chosen velocities and spins, gravity and drive off.
dem steps it one step at a time (``Simulation.run(1)``) and this module reads the state after
every step:

- **a sphere and the floor** (``kind = "wall"``): the floor z = 0 of the trough, normal n = +z,
  the sphere starting 2.5 steps of free flight above it;
- **two spheres** (``kind = "pair"``): sphere 0 below, sphere 1 above, n from 0 to 1 (+z at
  first touch), 2.5 steps apart along their approach.

What is measured (:func:`measure`), all from the recorded positions, velocities, spins and forces:

- the gap g = z - r (wall) or |x_1 - x_0| - r_0 - r_1 (pair) at every step; the contact starts
  and ends where g crosses zero, each crossing interpolated linearly between its two steps (the
  positions are second-order accurate in dt; a step count would be good to dt only), so
  ``duration`` is the time the bodies overlapped;
- the largest overlap and the largest normal force, each refined by the parabola through the
  largest sample and its two neighbours (the sampled maximum misses the true one by O(dt^2));
- the approach speed v_n1 = -(v_r . n) before (free flight, n at first touch) and the
  rebound speed v_n2 = v_r . n after (n at the last touch), e = v_n2 / v_n1, with v_r the
  velocity of the upper sphere (or the only one) relative to the lower (or the floor);
- the contact point's slip velocity u = v_r - (v_r . n) n - (r_1 w_1 + r_0 w_0) x n (wall:
  r w x n) with the **full radii** (outside contact every lever-arm convention agrees), as its
  component along t = y x n (x at n = +z), before (u1) and after (u2); the spins' y component
  (every benchmark turns about y); the tangential impulse on the upper sphere, J = m_1 dv_1 . t.

"After" is the last recorded state: the free flight after separation; with ``limit_force`` a
rebound whose force is clamped to zero while the bodies still overlap (they fly apart freely);
or, where a contact never lets go (e = 0 without ``limit_force``: the critically damped dashpot
holds the bodies while the overlap creeps to zero), the state TAIL_FACTOR repulsions after the
touch, when the normal speed left is a few thousandths of the approach (``after`` says which).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dem.engine import setup
from dem.scene.case import load_case
from dem.scene.resolved import Scene, resolve

HERE = Path(__file__).resolve().parent
#: Steps of free flight before the bodies touch.
START_STEPS = 2.5
#: Steps with the contact over (no force) after which the collision is done.
AFTER_STEPS = 3
#: A contact that holds on this many times its repulsion's duration never lets go (e = 0).
TAIL_FACTOR = 8
MAX_STEPS = 50_000
#: Where the collisions happen in the trough frame: far from the side walls and (pairs) the floor.
WALL_X = np.array([0.5, 0.0, 0.0])
PAIR_CENTRE = np.array([0.5, 0.0, 0.3])


def scene_for(keys: dict) -> Scene:
    """The study's case (``case.toml`` here) with ``keys`` set over it, resolved once."""
    return resolve(load_case(HERE, keys), check_limit=False)


def _spin_y(w: float) -> np.ndarray:
    return np.array([0.0, w, 0.0])


def wall_collision(scene: Scene, v: tuple[float, float], spin: float = 0.0, *,
                   timestep: float | None = None) -> dict:  # fmt: skip
    """A sphere (the case's radius and density) at velocity (v_x, -v_n) and spin w_y onto the floor.

    ``v`` = (v_t, v_n), v_n > 0 the approach speed; ``timestep`` None: dem's automatic step for
    an impact at this speed. Returns :func:`measure`'s dict.
    """
    r = scene.case.particles.radius
    vel = np.array([v[0], 0.0, -v[1]])
    speed = float(np.linalg.norm(vel)) + abs(spin) * r
    touch = WALL_X + [0.0, 0.0, r]

    def build(x):
        return setup.from_grains(scene, [x], velocities=[vel], spins=[_spin_y(spin)],
                                 impact_speed=speed, timestep=timestep)  # fmt: skip

    sim = build(touch - vel * START_STEPS * build(touch).dt)
    return measure(step_through(sim, "wall"), "wall", sim.dt, sim.spheres.radius,
                   sim.spheres.mass, scene.case.material.friction)  # fmt: skip


def pair_collision(scene: Scene, radii, densities, v0, v1, spins=(0.0, 0.0), *,
                   timestep: float | None = None) -> dict:  # fmt: skip
    """Sphere 0 (below) at velocity ``v0`` = (v_x, v_z), sphere 1 (above) at ``v1``, spins w_y.

    The two touch with n = +z after START_STEPS steps of their free flight. Returns
    :func:`measure`'s dict.
    """
    radii = np.asarray(radii, dtype=float)
    vel = np.array([[v0[0], 0.0, v0[1]], [v1[0], 0.0, v1[1]]])
    rel = vel[1] - vel[0]
    speed = float(np.linalg.norm(rel)) + abs(spins[0]) * radii[0] + abs(spins[1]) * radii[1]
    touch = np.array([PAIR_CENTRE - [0.0, 0.0, radii[0]], PAIR_CENTRE + [0.0, 0.0, radii[1]]])

    def build(x):
        return setup.from_grains(scene, x, velocities=vel, radii=radii, densities=densities,
                                 spins=[_spin_y(spins[0]), _spin_y(spins[1])],
                                 impact_speed=speed, timestep=timestep)  # fmt: skip

    sim = build(touch - vel * START_STEPS * build(touch).dt)
    return measure(step_through(sim, "pair"), "pair", sim.dt, sim.spheres.radius,
                   sim.spheres.mass, scene.case.material.friction)  # fmt: skip


def _gap_normal(kind: str, x: np.ndarray, radius: np.ndarray):
    """Gap (m) and unit normal n (lower body to upper) of one state x, (G, 3)."""
    if kind == "wall":
        return x[0, 2] - radius[0], np.array([0.0, 0.0, 1.0])
    d = x[1] - x[0]
    dist = math.sqrt(d @ d)
    return dist - radius[0] - radius[1], d / dist


def step_through(sim, kind: str) -> dict:
    """Step ``sim`` one step at a time, gravity and drive off, until the collision is over.

    Returns the states after every step (row 0 the start) as arrays: x, v, omega, f (the force
    on each sphere: the contact's alone, gravity being off).
    """
    sim.gravity[:] = 0.0
    sim.drive_on = False
    sim.compute_forces()
    s = sim.spheres
    rows = {"x": [s.x.copy()], "v": [s.v.copy()], "omega": [s.omega.copy()],
            "f": [s.force.copy()]}  # fmt: skip
    touch, repulsion_end, apart = None, None, 0
    for step in range(1, MAX_STEPS + 1):
        sim.run(1)
        s = sim.spheres
        for key, value in zip(rows, (s.x, s.v, s.omega, s.force), strict=True):
            rows[key].append(value.copy())
        if not np.any(s.force):
            apart += 1 if touch is not None else 0
            if apart >= AFTER_STEPS:
                break
            continue
        apart = 0
        if touch is None:
            touch = step
            continue
        _, n = _gap_normal(kind, s.x, s.radius)
        fn = s.force[-1] @ n
        if repulsion_end is None and fn <= 0.0:
            repulsion_end = step
        if repulsion_end is not None and step - touch > TAIL_FACTOR * (repulsion_end - touch):
            break
    else:
        raise RuntimeError(f"the collision did not end within {MAX_STEPS} steps")
    return {key: np.array(value) for key, value in rows.items()}


def _crossing(g: np.ndarray, k: int) -> float:
    """Fractional step where the gap crosses zero between samples k - 1 and k."""
    return (k - 1) + g[k - 1] / (g[k - 1] - g[k])


def _peak(y: np.ndarray) -> float:
    """Largest value of a sampled smooth peak: the parabola through the top sample and its two
    neighbours (the sample itself at an end of the series)."""
    k = int(np.argmax(y))
    if k == 0 or k == len(y) - 1:
        return float(y[k])
    a, b, c = y[k - 1], y[k], y[k + 1]
    curv = a - 2.0 * b + c
    if curv >= 0.0:
        return float(b)
    return float(b - (c - a) ** 2 / (8.0 * curv))


def _kinematics(kind, x, v, w, radius, n):
    """(v_n, u_t, t) of one state: normal relative speed v_r . n, slip along t = y x n, t."""
    t = np.array([n[2], 0.0, -n[0]])
    if kind == "wall":
        vr = v[0]
        rw = radius[0] * w[0]
    else:
        vr = v[1] - v[0]
        rw = radius[1] * w[1] + radius[0] * w[0]
    u = vr - (vr @ n) * n - np.cross(rw, n)
    return float(vr @ n), float(u @ t), t


#: A contact slid throughout where its friction departs from Coulomb's bound by at most this
#: share of the bound's impulse (below it and above it, each), and a step is below (above) the
#: bound where its friction is (1 -+ SLIDE_TOL) of it: a fifth of the sliding impulse's tolerance.
SLIDE_TOL = 1e-3


def slide_measure(fn: np.ndarray, against: np.ndarray, friction: float) -> dict:
    """Whether a contact slid throughout, from its steps in contact (first to last overlap).

    Rigid-body theory's sliding impact (Maw et al.'s limit) has, on every instant of contact,
    the friction mu F_n against the slip, F_n >= 0 the compressive normal force: Coulomb's bound
    B = mu max(F_n, 0). ``fn``: F_n of each step, N; ``against``: the tangential force along
    the incoming slip's opposite (> 0 opposes the slip), N. Returned: ``below`` and ``above``,
    the shares of the steps whose friction is below (the contact sticks, or pushes the slip)
    and above B (a dashpot beyond the cap while the spring sticks, friction while the normal
    force pulls) by more than :data:`SLIDE_TOL` of it; ``shortfall`` and ``excess``, the
    friction's impulse below and above B over B's impulse; ``slid``: both impulses within
    SLIDE_TOL, the stated equivalent of "at Coulomb's bound on every step".
    """
    bound = friction * np.maximum(fn, 0.0)
    total = float(bound.sum())
    shortfall = float(np.maximum(bound - against, 0.0).sum()) / total if total > 0 else 1.0
    excess = float(np.maximum(against - bound, 0.0).sum()) / total if total > 0 else 0.0
    floor = 1e-9 * float(bound.max(initial=0.0))  # a force of zero's round-off (1e-18 N)
    return {
        "below": float(np.mean(against < (1.0 - SLIDE_TOL) * bound - floor)),
        "above": float(np.mean(against > (1.0 + SLIDE_TOL) * bound + floor)),
        "shortfall": shortfall,
        "excess": excess,
        "slid": shortfall <= SLIDE_TOL and excess <= SLIDE_TOL,
    }


def measure(h: dict, kind: str, dt: float, radius: np.ndarray, mass: np.ndarray,
            friction: float) -> dict:  # fmt: skip
    """What one collision gives (module docstring): times s, overlaps m, forces N, speeds m/s.

    ``coulomb_excess``: max |F_t| / (mu F_n) - 1 over the loaded steps (> 0: the tangential
    force exceeded Coulomb's bound). ``tangential_energy_change``: the kinetic energy of the
    relative tangential motion and of the spins after the collision over before, minus 1: a
    passive contact (friction, dashpots, a spring that returns what it took) cannot make it
    positive. ``slide``: whether the contact slid throughout as rigid-body theory's Coulomb
    friction does (:func:`slide_measure`).
    """
    x, v, w, f = h["x"], h["v"], h["omega"], h["f"]
    gaps, normals = zip(*(_gap_normal(kind, xi, radius) for xi in x), strict=True)
    gap = np.array(gaps)
    fn = np.array([fi[-1] @ ni for fi, ni in zip(f, normals, strict=True)])
    inside = np.flatnonzero(gap < 0.0)
    first, last = int(inside[0]), int(inside[-1])
    t_touch = _crossing(gap, first) * dt
    after, t_apart = -1, math.nan
    if last + 1 < len(gap):
        t_apart = _crossing(gap, last + 1) * dt
        n_after, where = normals[last + 1], "separation"
    elif not np.any(f[-1]):
        n_after, where = normals[-1], "free (F_n clamped to 0, still overlapping)"
    else:
        n_after, where = normals[-1], "held (touching at the end of the record)"
    # n at first touch: the straight free flight before it, interpolated
    frac = _crossing(gap, first) - (first - 1)
    if kind == "wall":
        n_before = normals[0]
    else:
        d = (1 - frac) * (x[first - 1, 1] - x[first - 1, 0]) + frac * (x[first, 1] - x[first, 0])
        n_before = d / np.linalg.norm(d)
    vn1, u1, t1 = _kinematics(kind, x[0], v[0], w[0], radius, n_before)
    vn2, u2, t2 = _kinematics(kind, x[after], v[after], w[after], radius, n_after)
    upper = 0 if kind == "wall" else 1
    ft = np.array([fi[-1] - fn_i * ni for fi, fn_i, ni in zip(f, fn, normals, strict=True)])
    # the tangential force on the upper sphere along t, step by step
    ft_t = np.array([f[k, -1] @ np.array([nk[2], 0.0, -nk[0]]) for k, nk in enumerate(normals)])
    loaded = fn > 0.0
    excess = float(np.max(np.abs(ft_t[loaded]) / (friction * fn[loaded]))) if friction else 0.0
    # the tangential impulse on the upper sphere along the mean tangent: the normal turns a
    # little while two spheres pass each other, and its impulse must not leak into J
    n_mid = (n_before + n_after) / np.linalg.norm(n_before + n_after)
    t_mid = np.array([n_mid[2], 0.0, -n_mid[0]])
    inertia = 0.4 * mass * radius**2

    def tangential_energy(k, n):
        """Kinetic energy of the relative tangential motion and of the spins, J."""
        t = np.array([n[2], 0.0, -n[0]])
        if kind == "wall":
            vt, m = v[k, 0] @ t, mass[0]
        else:
            vt, m = (v[k, 1] - v[k, 0]) @ t, mass[0] * mass[1] / (mass[0] + mass[1])
        return 0.5 * m * vt * vt + 0.5 * float(np.sum(inertia * w[k, :, 1] ** 2))

    energy_in = tangential_energy(0, n_before)
    span = slice(first, last + 1)
    slide = slide_measure(fn[span], -ft_t[span] * (1.0 if u1 >= 0.0 else -1.0), friction)
    return {
        "dt_s": dt,
        "contact_steps": last - first + 1,
        "duration_s": t_apart - t_touch,
        "max_overlap_m": _peak(-gap),
        "peak_force_n": _peak(fn),
        "peak_tangential_force_n": float(np.max(np.linalg.norm(ft, axis=1))),
        "after": where,
        "vn_in": -vn1,
        "vn_out": vn2,
        "restitution": -vn2 / vn1,
        "u_in": u1,
        "u_out": u2,
        "vt_in": float(v[0, upper] @ t1),
        "vt_out": float(v[after, upper] @ t2),
        "vn_in_upper": float(-(v[0, upper] @ n_before)),
        "vn_out_upper": float(v[after, upper] @ n_after),
        "spin_in": [float(s) for s in w[0, :, 1]],
        "spin_out": [float(s) for s in w[after, :, 1]],
        "impulse_t": float(mass[upper] * (v[after, upper] - v[0, upper]) @ t_mid),
        "normal_turn_rad": float(math.acos(min(1.0, float(n_before @ n_after)))),
        "masses": [float(m) for m in mass],
        "radii": [float(r) for r in radius],
        "coulomb_excess": excess - 1.0,
        "slide": slide,
        "tangential_energy_change": (tangential_energy(after, n_after) - energy_in) / energy_in
        if energy_in > 0.0
        else 0.0,
        "history": {
            "t_s": (np.arange(len(x)) - _crossing(gap, first)) * dt,
            "fn_n": fn,
            "ft_n": ft_t,
            "overlap_m": -gap,
        },
    }
