"""Chung and Ooi's (2011) eight impact-level benchmarks, every law dem ships, against theory.

    .venv/bin/python validation/contact-benchmarks/benchmarks.py            # everything, ~2.5 min
    .venv/bin/python validation/contact-benchmarks/benchmarks.py --short    # CI's form, ~40 s
    .venv/bin/python validation/contact-benchmarks/benchmarks.py --report-only  # tables, figures

Y.C. Chung and J.Y. Ooi, "Benchmark tests for verifying discrete element modelling codes at
particle impact level", Granular Matter 13 (2011) 643-656: eight collisions of one or two
spheres, each with an analytic answer. Every collision runs through dem's library as the other
two-body studies run theirs (:mod:`collide`: the case beside this file with keys set over it,
``dem.engine.setup.from_grains``, gravity and drive off), once per contact law (:data:`LAWS`:
Hertz-Mindlin and linear normal laws, each with the "impact", "coulomb" and "liggghts"
tangential laws, ``limit_force`` false and true, and "coulomb" given Mindlin's spring), at dem's
automatic time step and at half (and, in the full run, a quarter) of it. The references
(:mod:`analytic`) are Hertz's closed forms, the set restitution, rigid-body Coulomb sliding (Maw,
Barber and Fawcett's limit), and for each tangential law what it is designed to do.

Materials and speeds (:data:`MATERIALS`, :data:`TESTS`; README.md says where each value comes
from and which ones are not the paper's): a sphere of material 1 against a wall or a sphere of
material 2 is one contact of moduli Y*, G* (:func:`dem.kernels.contact.contact_moduli`), which
dem's one-material law gets through :func:`dem.kernels.contact.equivalent_material`. The
linear law is given the stiffness whose impact lasts as long as Hertz's at the test's speed
(:func:`analytic.linear_stiffness_for`).

Written: results.json (every collision, the references, the command, dem version and commit,
machine and load), results.csv (one row per key number), figures (*.png) and README.md's tables.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

import analytic  # noqa: E402
import collide  # noqa: E402

from dem import provenance  # noqa: E402
from dem.kernels import contact  # noqa: E402
from validation._lib.header import results_header  # noqa: E402

SCRIPT = "validation/contact-benchmarks/benchmarks.py"

#: name -> (Young's modulus Pa, Poisson ratio, density kg/m^3); README.md gives the sources.
MATERIALS = {
    "glass": (4.8e10, 0.20, 2800.0),
    "limestone": (2.0e10, 0.25, 2500.0),
    "al2o3": (3.8e11, 0.23, 4000.0),
    "al_alloy": (7.0e10, 0.33, 2700.0),
    "mg_alloy": (4.0e10, 0.35, 1800.0),
}


@dataclass(frozen=True)
class Law:
    """One of dem's contact laws as case keys: normal law, tangential law, limit_force.

    ``mindlin``: "coulomb" given Mindlin's no-slip spring (k_t / S_n = 4 G* / Y*, no dashpot)
    instead of the spring derived from eps_t: the configuration in which it is Mindlin's law.
    """

    normal: str
    tangential: str
    limit_force: bool
    mindlin: bool = False

    @property
    def name(self) -> str:
        short = {"hertz_mindlin": "hertz", "linear": "linear"}[self.normal]
        tail = "[mindlin]" if self.mindlin else ""
        return f"{short}/{self.tangential}{tail}" + ("/limit" if self.limit_force else "")

    def keys(self, c: Contact) -> dict:
        """Case keys of this law for contact ``c``."""
        keys = {
            "contact.model": self.normal, "contact.tangential": self.tangential,
            "contact.limit_force": self.limit_force, "contact.poisson_ratio": c.nu,
            "material.friction": c.friction, "material.restitution_normal": c.restitution,
        }  # fmt: skip
        if self.normal == "hertz_mindlin":
            keys["contact.youngs_modulus"] = c.youngs
        else:
            keys.update({"contact.youngs_modulus": None, "contact.stiffness": c.stiffness})
        if self.mindlin:
            keys.update({"contact.tangential_stiffness_ratio": c.kappa,
                         "contact.tangential_damping_ratio": 0.0})  # fmt: skip
        return keys


LAWS = [
    Law(normal, tangential, limit)
    for normal in ("hertz_mindlin", "linear")
    for tangential in ("impact", "coulomb", "liggghts")
    for limit in (False, True)
] + [Law("hertz_mindlin", "coulomb", False, mindlin=True)]  # fmt: skip

#: What each tangential law is designed to reproduce (README's tables).
DESIGN = {
    "impact": "eps_t of the slip per impact, capped by Coulomb (no Mindlin compliance)",
    "coulomb": "eps_t of a sticking impact via a spring derived from it; total force <= mu F_n",
    "coulomb[mindlin]": "Mindlin's no-slip spring 8 G* a (total form), total force <= mu F_n",
    "liggghts": "Hertz: Mindlin's no-slip spring 8 G* a (total form); linear: k_t = 2/7 k_n; "
    "spring <= mu F_n",
}


@dataclass(frozen=True)
class Contact:
    """The contact of one test: materials, grains, speed and the laws' material constants.

    Attributes:
        youngs, nu: The one-material equivalent (E Pa, nu) of the pair (dem's law keys).
        y_star, g_star: Hertz's and Mindlin's effective moduli, Pa.
        kappa: k_t / S_n = 4 G* / Y*, Mindlin's no-slip over Hertz's normal tangent stiffness.
        m_eff, r_eff: m* (kg) and R* (m).
        speed: Relative normal approach speed the linear law's stiffness is matched at, m/s.
        stiffness: The linear law's k_n: its impact lasts Hertz's at ``speed``, N/m.
        friction, restitution: mu and eps_n.

    """

    youngs: float
    nu: float
    y_star: float
    g_star: float
    kappa: float
    m_eff: float
    r_eff: float
    speed: float
    stiffness: float
    friction: float
    restitution: float


def make_contact(sphere: str, other: str, radii, speed: float, friction: float,
                 restitution: float) -> Contact:  # fmt: skip
    """The contact of a sphere of material ``sphere`` (radius radii[0]) with a wall (radii[1]
    None) or a sphere (radii[1]) of material ``other``."""
    e1, nu1, rho1 = MATERIALS[sphere]
    e2, nu2, rho2 = MATERIALS[other]
    y_star, g_star = contact.contact_moduli(e1, nu1, e2, nu2)
    youngs, nu = contact.equivalent_material(e1, nu1, e2, nu2)
    m1 = rho1 * 4.0 / 3.0 * math.pi * radii[0] ** 3
    if radii[1] is None:
        m_eff, r_eff = m1, radii[0]
    else:
        m2 = rho2 * 4.0 / 3.0 * math.pi * radii[1] ** 3
        m_eff, r_eff = m1 * m2 / (m1 + m2), radii[0] * radii[1] / (radii[0] + radii[1])
    duration = analytic.hertz_impact(y_star, r_eff, m_eff, speed)["duration_s"]
    stiffness = analytic.linear_stiffness_for(duration, m_eff)
    return Contact(youngs, nu, y_star, g_star, 4.0 * g_star / y_star, m_eff, r_eff, speed,
                   stiffness, friction, restitution)  # fmt: skip


# --- the eight tests ------------------------------------------------------------------------

#: Tests 4-6's sphere and wall, 7's spheres: Al2O3 (r = 2.55 mm) on Al alloy (Kharaz et al.).
R_AO = 2.55e-3
VN = 3.9  # m/s, the normal speed of tests 4-7
#: eps_t of the "impact" and "coulomb" laws: the case's (dem's default).
EPS_T = 0.8
#: Normalised incidences psi_1 of tests 5-8 (full run) and of the short form.
PSI_FULL = (0.1, 0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 16.0)
PSI_SHORT = (0.5, 12.0)
ANGLES_FULL = tuple(float(a) for a in range(5, 90, 5))
ANGLES_SHORT = (10.0, 70.0)


def _case_keys(law: Law, c: Contact, radius: float, density: float) -> dict:
    return {**law.keys(c), "particles.radius": radius, "material.density": density}


def _short_or_full(short, full, is_short):
    return short if is_short else full


def test1(is_short: bool) -> list[dict]:
    """Test 1: elastic normal impact of two identical spheres, 10 m/s each (glass, limestone)."""
    rows = []
    for name in _short_or_full(("glass",), ("glass", "limestone"), is_short):
        r, rho = 0.010, MATERIALS[name][2]
        c = make_contact(name, name, (r, r), 20.0, 0.3, 1.0)
        for law in LAWS:
            scene = collide.scene_for(_case_keys(law, c, r, rho))

            def run(dt, s=scene, r=r, rho=rho):
                return collide.pair_collision(s, (r, r), (rho, rho), (0.0, 10.0), (0.0, -10.0),
                                              timestep=dt)  # fmt: skip

            rows.append(_normal_row(1, name, law, c, run))
    return rows


def test3(is_short: bool) -> list[dict]:
    """Test 3: elastic normal impact of a sphere (r = 0.1 m) on a wall of another material."""
    rows = []
    pairs = (("al_alloy", "mg_alloy"), ("mg_alloy", "al_alloy"))
    for sphere, wall in _short_or_full(pairs[:1], pairs, is_short):
        r, rho = 0.10, MATERIALS[sphere][2]
        c = make_contact(sphere, wall, (r, None), 0.2, 0.3, 1.0)
        for law in LAWS:
            scene = collide.scene_for(_case_keys(law, c, r, rho))
            rows.append(
                _normal_row(
                    3,
                    f"{sphere} on {wall}",
                    law,
                    c,
                    lambda dt, s=scene: collide.wall_collision(s, (0.0, 0.2), timestep=dt),
                )
            )
    return rows


def _normal_row(test: int, case: str, law: Law, c: Contact, run) -> dict:
    """Peak force, largest overlap and duration against Hertz (or the linear spring)."""
    if law.normal == "hertz_mindlin":
        ref = analytic.hertz_impact(c.y_star, c.r_eff, c.m_eff, c.speed)
    else:
        ref = analytic.linear_impact(c.stiffness, c.m_eff, c.speed)
    runs = _converge(run)
    out = {"test": test, "case": case, "law": law.name, "tangential": law.tangential,
           "normal": law.normal, "limit_force": law.limit_force, "kind": "normal",
           "dt_s": [r["dt_s"] for r in runs]}  # fmt: skip
    for key in ("peak_force_n", "max_overlap_m", "duration_s"):
        out[key] = _quantity([r[key] for r in runs], ref[key], runs)
    out["hertz"] = analytic.hertz_impact(c.y_star, c.r_eff, c.m_eff, c.speed)
    out["contact"] = {
        "y_star": c.y_star,
        "r_eff": c.r_eff,
        "m_eff": c.m_eff,
        "speed": c.speed,
        "stiffness": c.stiffness,
    }
    if law.name in ("hertz/impact", "linear/impact"):  # for the figure: every law the same
        out["history"] = _history(runs[0])
    return out


#: Restitutions of test 2, and the short form's.
E_FULL = (0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0)
E_SHORT = (0.1, 0.5)


def test2(is_short: bool) -> list[dict]:
    """Test 2: a sphere normally on a wall at 3.9 m/s, several coefficients of restitution.

    Head-on the tangential law never acts (tests 1 and 3 check that every one gives the same
    bits), so the normal laws run with the default, "impact". The full run adds e = 0.5 at a
    tenth of the speed: the outcome does not depend on it.
    """
    rows = []
    for e in _short_or_full(E_SHORT, E_FULL, is_short):
        c = make_contact("al2o3", "al_alloy", (R_AO, None), VN, 0.092, e)
        for law in (law for law in LAWS if law.tangential == "impact"):
            rows.append(_restitution_row(law, c, VN, f"e = {e:g}"))
    if not is_short:
        c = make_contact("al2o3", "al_alloy", (R_AO, None), 0.39, 0.092, 0.5)
        for law in (law for law in LAWS if law.tangential == "impact"):
            rows.append(_restitution_row(law, c, 0.39, "e = 0.5 at 0.39 m/s"))
    return rows


def _restitution_row(law: Law, c: Contact, speed: float, label: str) -> dict:
    """The rebound of one normal impact on the wall against the set e and the law's e_n."""
    scene = collide.scene_for(_case_keys(law, c, R_AO, MATERIALS["al2o3"][2]))
    runs = _converge(lambda dt: collide.wall_collision(scene, (0.0, speed), timestep=dt))
    # the law's own rebound: e_n of its dashpot, clamped with limit_force; 0 for the impact
    # law's perfectly plastic contact of eps_n = 0 (dem.kernels.contact.plastic_normal), which
    # never pulls, limit_force or not
    plastic = bool(scene.law.wall_params[contact.P_PLASTIC])
    e_n = float(scene.law.wall_params[contact.P_NORMAL_E])
    return {
        "test": 2, "case": label, "law": law.name, "normal": law.normal, "tangential": "any",
        "limit_force": law.limit_force, "plastic": plastic, "kind": "restitution",
        "set": c.restitution,
        "dt_s": [r["dt_s"] for r in runs],
        "normal_law_restitution": e_n,
        "restitution": _quantity([r["restitution"] for r in runs], c.restitution, runs,
                                 absolute=True),
        "after": runs[0]["after"],
    }  # fmt: skip


def _oblique_setups(test: int, is_short: bool):
    """(contact, kind, grains, points) of oblique test 4-8; a point is (label, psi_1, v_n, run),
    v_n the relative normal approach speed (m/s) and run(scene, dt) the collision."""
    psis = _short_or_full(PSI_SHORT, PSI_FULL, is_short)
    rho = MATERIALS["al2o3"][2]
    if test in (4, 5, 6):
        c = make_contact("al2o3", "al_alloy", (R_AO, None), VN, 0.092, 0.98)
        unit = c.friction * VN / c.kappa  # slip speed of psi_1 = 1, m/s
        grains = {"radius": R_AO, "density": rho}

        def wall(vt, vn, w):
            return lambda scene, dt: collide.wall_collision(scene, (vt, vn), w, timestep=dt)

        if test == 4:
            points = []
            for a in _short_or_full(ANGLES_SHORT, ANGLES_FULL, is_short):
                vt, vn = 3.9 * math.sin(math.radians(a)), 3.9 * math.cos(math.radians(a))
                points.append((f"{a:g} deg", c.kappa / c.friction * vt / vn, vn,
                               wall(vt, vn, 0.0)))  # fmt: skip
        elif test == 5:
            points = [(f"psi {p:g}", p, VN, wall(p * unit, VN, 0.0)) for p in psis]
        else:  # spin w_y < 0 gives the contact point a slip u = -r w_y > 0
            points = [(f"psi {p:g}", p, VN, wall(0.0, VN, -p * unit / R_AO)) for p in psis]
        return c, "wall", grains, points
    if test == 7:  # identical spheres, 1.95 m/s each, equal spins: the slip is -2 r w
        c = make_contact("al2o3", "al2o3", (R_AO, R_AO), VN, 0.092, 0.98)
        unit = c.friction * VN / c.kappa
        grains = {"radius": R_AO, "density": rho}

        def spun(w):
            return lambda scene, dt: collide.pair_collision(
                scene, (R_AO, R_AO), (rho, rho), (0.0, 0.5 * VN), (0.0, -0.5 * VN), (w, w),
                timestep=dt)  # fmt: skip

        return c, "pair", grains, [(f"psi {p:g}", p, VN, spun(-p * unit / (2 * R_AO)))
                                   for p in psis]  # fmt: skip
    # test 8: Al alloy (r 10 mm, below) and Mg alloy (r 5 mm, above), 1 m/s relative, mu 0.1,
    # e 0.5, the velocities in the centre-of-mass frame
    r0, r1 = 0.010, 0.005
    rho0, rho1 = MATERIALS["al_alloy"][2], MATERIALS["mg_alloy"][2]
    vn = 1.0
    c = make_contact("al_alloy", "mg_alloy", (r0, r1), vn, 0.1, 0.5)
    m0, m1 = rho0 * 4 / 3 * math.pi * r0**3, rho1 * 4 / 3 * math.pi * r1**3
    f0, f1 = m1 / (m0 + m1), m0 / (m0 + m1)
    unit = c.friction * vn / c.kappa
    grains = {"radius": r1, "density": rho1}

    def slid(vt):
        return lambda scene, dt: collide.pair_collision(
            scene, (r0, r1), (rho0, rho1), (-f0 * vt, f0 * vn), (f1 * vt, -f1 * vn),
            timestep=dt)  # fmt: skip

    return c, "pair", grains, [(f"psi {p:g}", p, vn, slid(p * unit)) for p in psis]


TEST_TITLES = {
    1: "elastic normal impact of two identical spheres",
    2: "normal impact on a wall, several coefficients of restitution",
    3: "elastic normal impact on a wall of another material",
    4: "oblique impact on a wall, constant speed 3.9 m/s, incidence 5-85 deg",
    5: "oblique impact on a wall, constant normal speed 3.9 m/s, tangential speeds",
    6: "impact on a wall with spin, constant normal speed 3.9 m/s",
    7: "two identical spheres, constant normal speed, spins",
    8: "two different spheres, constant normal speed, tangential speeds",
}


def oblique(test: int, is_short: bool) -> list[dict]:
    """Tests 4-8: every law at every incidence, against Coulomb sliding and the law's design."""
    c, kind, grains, points = _oblique_setups(test, is_short)
    psis = np.array([p for _, p, _, _ in points])
    vns = np.array([vn for _, _, vn, _ in points])
    rows = []
    for law in LAWS:
        scene = collide.scene_for(_case_keys(law, c, grains["radius"], grains["density"]))
        reference = None
        if law.tangential != "impact":
            reference = analytic.law_reference(
                law_constants(scene, kind), psis * c.friction * vns / c.kappa, vns, c.m_eff,
                c.r_eff, steps=_short_or_full(4000, 20000, is_short))  # fmt: skip
        for k, (label, psi, _, run) in enumerate(points):
            first = run(scene, None)
            # dt halving where the key numbers are read: the first point, and those where the
            # contact slid throughout (measured, collide.slide_measure)
            key_point = k == 0 or first["slide"]["slid"]
            runs = _converge(lambda dt, r=run, s=scene: r(s, dt), first=first, more=key_point)
            rows.append(_oblique_row(test, label, psi, law, c, kind, scene, runs, reference, k))
    return rows


def _threshold(c: Contact, restitution: float) -> float:
    """psi* = 7/2 (1 + e) kappa: rigid Coulomb sliding throughout from here (analytic.py)."""
    return analytic.ROLL * (1.0 + restitution) * c.kappa


def law_constants(scene, kind: str) -> dict:
    """A spring law's coefficients for :func:`analytic.law_reference`, read from dem's params."""
    law = scene.law
    p = law.wall_params if kind == "wall" else law.params[: contact.N_PARAMS]
    return {
        "normal": law.model, "tangential": law.tangential, "kn": float(p[contact.P_KN_COEF]),
        "dn": float(p[contact.P_DAMP_N] * math.sqrt(p[contact.P_DAMP_N_SCALE])),
        "kt": float(p[contact.P_KT_COEF]),
        "dt": float(p[contact.P_DAMP_T] * math.sqrt(p[contact.P_DAMP_T_SCALE])),
        "mu": float(p[contact.P_MU]), "limit_force": bool(p[contact.P_LIMIT_FORCE]),
    }  # fmt: skip


def _oblique_row(test, label, psi, law, c, kind, scene, runs, reference, k) -> dict:
    """One oblique collision: measured, rigid-body sliding and the law's design, normalised."""
    first = runs[0]
    vn, e = first["vn_in"], first["restitution"]
    j_slide = analytic.sliding_impulse(c.friction, e, c.m_eff, vn)
    masses, radii = first["masses"], first["radii"]
    upper = len(masses) - 1
    # the spin of every sphere changes by (5/2) J / (m r) in rigid-body theory (analytic.py)
    spin_slide = 2.5 * j_slide / (masses[upper] * radii[upper])
    row = {
        "test": test, "case": label, "psi_in": psi, "law": law.name, "normal": law.normal,
        "tangential": law.tangential + ("[mindlin]" if law.mindlin else ""),
        "limit_force": law.limit_force, "kind": "oblique", "first_point": k == 0,
        "dt_s": [r["dt_s"] for r in runs],
        # rigid-body theory's sliding holds where the contact slid throughout: measured
        "sliding": first["slide"]["slid"], "slide": first["slide"],
        "threshold_psi": _threshold(c, e), "restitution": e, "vn_in": vn,
        "psi_out": analytic.normalise(first["u_out"], c.kappa, c.friction, vn),
        "spin_out_norm": analytic.normalise(
            radii[upper] * (first["spin_out"][upper] - first["spin_in"][upper]),
            c.kappa, c.friction, vn) * masses[upper] / c.m_eff,
        "rebound_angle_deg": math.degrees(math.atan2(first["vt_out"], first["vn_out_upper"])),
        "incidence_deg": math.degrees(math.atan2(first["vt_in"], first["vn_in_upper"])),
        "eps_t_centre": first["vt_out"] / first["vt_in"] if first["vt_in"] else math.nan,
        "impulse": _quantity([-r["impulse_t"] for r in runs], j_slide, runs),
        "spin_change": _quantity([r["spin_out"][upper] - r["spin_in"][upper] for r in runs],
                                 spin_slide, runs),
        "coulomb_excess": first["coulomb_excess"],
        "tangential_energy_change": first["tangential_energy_change"],
        "energy": _quantity([r["tangential_energy_change"] for r in runs], 0.0, runs,
                            absolute=True),
        "normal_turn_rad": first["normal_turn_rad"],
        # two spheres pass each other while they touch: the normal turns by phi, and rigid-body
        # theory (an instantaneous contact) misses terms of order phi u1 / v_n
        "turn_slack": first["normal_turn_rad"] * abs(first["u_in"]) / vn,
        "max_overlap_over_r": first["max_overlap_m"] / min(radii),
    }  # fmt: skip
    row["rebound_angle_slide_deg"] = math.degrees(math.atan2(
        first["vt_in"] - j_slide / masses[upper], e * first["vn_in_upper"]))  # fmt: skip
    row["psi_slide"] = psi - _threshold(c, e)
    psi_values = [analytic.normalise(r["u_out"], c.kappa, c.friction, r["vn_in"]) for r in runs]
    if law.tangential == "impact":
        p = scene.law.wall_params if kind == "wall" else scene.law.params
        j = analytic.impact_design(first["u_in"], vn, c.m_eff, eps_t=EPS_T, friction=c.friction,
                                 eps_n=c.restitution, e_n=float(p[contact.P_NORMAL_E]))  # fmt: skip
        psi_design = psi - analytic.normalise(analytic.ROLL * j / c.m_eff, c.kappa, c.friction, vn)
    else:
        psi_design = analytic.normalise(float(reference["u_out"][k]), c.kappa, c.friction, vn)
        row["reference_restitution"] = float(reference["restitution"][k])
    row["design"] = _quantity(psi_values, psi_design, runs, absolute=True)
    if law.tangential == "coulomb" and not law.mindlin:
        # the spring was derived for eps_t = 0.8 of a sticking impact: J = (1 - eps_t) m* u1
        row["eps_t_design"] = _quantity([-r["impulse_t"] for r in runs],
                                        (1.0 - EPS_T) * c.m_eff * first["u_in"], runs)  # fmt: skip
    return row


# --- convergence with the time step --------------------------------------------------------

#: dt factors of the convergence runs: dem's automatic step, then halved (the full run once more).
HALVINGS = {"short": (1, 2), "full": (1, 2, 4)}
_MODE = {"halvings": HALVINGS["full"]}


def _converge(run, first=None, more=True) -> list[dict]:
    """The collision at dem's automatic step, and (``more``) at its halves (:data:`HALVINGS`)."""
    base = first if first is not None else run(None)
    out = [base]
    if more:
        out += [run(base["dt_s"] / f) for f in _MODE["halvings"][1:]]
    return out


def _quantity(values, reference, runs, absolute=False) -> dict:
    """A measured number at each dt with its reference: value (dem's step), errors, order.

    ``error`` is relative (absolute with ``absolute``), ``errors`` at each dt of ``runs`` (the
    row's ``dt_s``); ``order`` the observed order of the error's fall from dt to dt/2 to dt/4,
    where measurable.
    """
    values = [float(v) for v in values]

    def err(v):
        if absolute or reference == 0.0:
            return v - reference
        return (v - reference) / abs(reference)

    errors = [err(v) for v in values]
    order = math.nan
    if len(values) >= 3 and values[1] != values[2] and values[0] != values[1]:
        order = math.log2(abs(values[0] - values[1]) / abs(values[1] - values[2]))
    return {"value": values[0], "reference": float(reference), "error": errors[0],
            "errors": errors, "order": order,
            "absolute": absolute}  # fmt: skip


def _history(run: dict, points: int = 200) -> dict:
    """A collision's force history for the figures, on at most ``points`` samples."""
    h = run["history"]
    t = h["t_s"]
    keep = (t >= -2 * run["dt_s"]) & (t <= run["duration_s"] + 4 * run["dt_s"]
                                      if math.isfinite(run["duration_s"]) else t > -1)  # fmt: skip
    idx = np.flatnonzero(keep)
    if len(idx) > points:
        idx = idx[np.linspace(0, len(idx) - 1, points).astype(int)]
    return {key: [float(x) for x in h[key][idx]] for key in h}


# --- tolerances and verdicts ----------------------------------------------------------------

#: The tolerance of each key number at dem's automatic step, and why (README.md, "Tolerances").
TOLERANCES = {
    "normal": (
        2e-3,
        "relative; velocity Verlet is second order and the automatic step puts "
        "about 50 steps in an impact: measured <= 3e-4, a quarter of it at dt/2",
    ),
    "restitution": (
        0.01,
        "absolute; the dashpot is evaluated at the half-step velocity, a "
        "first-order error: measured <= 0.0074 at 50 steps an impact, halving "
        "with dt",
    ),
    "impulse": (
        5e-3,
        "relative (two spheres: plus the normal's turn times u1 / v_n); Coulomb's impulse is "
        "an integral of mu F_n, second order: measured <= 2.1e-4 at a wall where a law slides",
    ),
    "spin": (
        5e-3,
        "relative, plus delta_max / r: the torque's lever arm is r - delta at a "
        "wall (dem's 'surface' convention) and r - delta/2 between spheres, rigid-body "
        "theory's is r",
    ),
    "design": (
        0.05,
        "absolute, in psi_2 (normalised slip out); the lever arm moves psi_2 by "
        "about (5/2)(1 + e) kappa delta_max / r (0.03 in tests 4-6) and the first "
        "touch's capping is first order in dt (0.02 at psi_1 = 0.5)",
    ),
    "passivity": (
        1e-9,
        "one-sided, the relative change of the kinetic energy of the relative tangential "
        "motion and the spins: a passive contact cannot raise it; round-off, the energies' "
        "float64 sums over some hundred steps, is below 1e-13",
    ),
    "eps_t": (
        0.05,
        "relative, J against (1 - eps_t) m* u1 at the smallest psi_1; the spring "
        "is derived from the linear law's impact (dem.physics.tangential): exact for "
        "a linear contact that sticks",
    ),
}


def verdict(q: dict, kind: str, slack: float = 0.0) -> bool:
    """Whether quantity ``q`` is within :data:`TOLERANCES` [kind] (plus ``slack``); for
    "passivity", one-sided: the energy change at most the tolerance."""
    if kind == "passivity":
        return bool(q["error"] <= TOLERANCES[kind][0] + slack)
    return bool(abs(q["error"]) <= TOLERANCES[kind][0] + slack)


def _slide_note(r: dict) -> str:
    """How far from sliding throughout one oblique point was (collide.slide_measure): the
    shares of its contact's steps with the friction below and above Coulomb's bound."""
    sl = r["slide"]
    parts = [
        f"{word} it for {sl[key]:.0%}"
        for word, key in (("below", "below"), ("above", "above"))
        if sl[key] > 0.0
    ]
    where = r["case"].replace("psi", "psi_1 =")
    if not parts:
        return f"friction at Coulomb's bound mu max(F_n, 0) throughout at {where}"
    return (
        f"friction {' and '.join(parts)} of the impact, Coulomb's bound mu max(F_n, 0), at {where}"
    )


def summarise(rows: list[dict]) -> list[dict]:
    """The key numbers: one line per test, case or law and quantity (results.csv, README).

    ``pass`` is True or False, or None where a number is reported, not judged: the set e of a
    ``limit_force`` law (designed to rebound at e_n, judged there; not the plastic contact of
    eps_n = 0, which rebounds at 0 with or without it), and the rigid-body check of
    a law whose contact slid throughout at no point of a test (not applicable: its note says
    how far from sliding it was; its design checks carry the verdict).
    """
    out = []

    def add(test, case, law, quantity, q, kind, design, slack=0.0, note="", judged=True):
        out.append({
            "test": test, "case": case, "law": law, "quantity": quantity,
            "measured": q["value"], "reference": q["reference"], "error": q["error"],
            "error_kind": "absolute" if q["absolute"] else "relative",
            "tolerance": TOLERANCES[kind][0] + slack,
            "pass": verdict(q, kind, slack) if judged else None,
            "error_dt_half": q["errors"][1] if len(q["errors"]) > 1 else math.nan,
            "order": q["order"], "design": design, "note": note,
        })  # fmt: skip

    for r in rows:
        if r["kind"] == "normal":
            what = "Hertz" if r["normal"] == "hertz_mindlin" else "linear spring"
            for key in ("peak_force_n", "max_overlap_m", "duration_s"):
                add(r["test"], r["case"], r["law"], key, r[key], "normal", what)
        elif r["kind"] == "restitution":
            clamped = r["limit_force"] and not r.get("plastic", False)
            design = (
                "e_n of the clamped dashpot" if clamped
                else "the plastic contact: 0" if r.get("plastic") else "the set e"
            )  # fmt: skip
            q = dict(r["restitution"])
            add(r["test"], r["case"], r["law"], "restitution vs set", q, "restitution", design,
                note=f"after: {r['after']}", judged=not clamped)  # fmt: skip
            if clamped:
                q2 = dict(q, reference=r["normal_law_restitution"],
                          error=q["value"] - r["normal_law_restitution"],
                          errors=[e + q["reference"] - r["normal_law_restitution"]
                                  for e in q["errors"]])  # fmt: skip
                add(r["test"], r["case"], r["law"], "restitution vs e_n", q2, "restitution", design)
    oblique = [r for r in rows if r["kind"] == "oblique"]
    groups: dict = {}
    for r in oblique:
        groups.setdefault((r["test"], r["law"]), []).append(r)
    for (test, law), group in groups.items():
        tangential = group[0]["tangential"]
        design = DESIGN[tangential]
        excess = max(r["coulomb_excess"] for r in group)
        note = f"|F_t| up to {1 + excess:.3g} mu F_n" if excess > 1e-6 else ""
        sliding = [r for r in group if r["sliding"]]
        if sliding:
            worst = max(sliding, key=lambda r: abs(r["impulse"]["error"]) - r["turn_slack"])
            add(test, f"slid throughout: {len(sliding)} points (worst {worst['case']})", law,
                "impulse", worst["impulse"], "impulse", "Coulomb: mu (1 + e) m* v_n",
                slack=worst["turn_slack"], note=note)  # fmt: skip
            worst = max(sliding, key=lambda r: abs(r["spin_change"]["error"])
                        - r["max_overlap_over_r"] - r["turn_slack"])  # fmt: skip
            add(test, f"slid throughout: {len(sliding)} points (worst {worst['case']})", law,
                "spin change", worst["spin_change"], "spin", "(5/2) J / (m r)",
                slack=worst["max_overlap_over_r"] + worst["turn_slack"], note=note)  # fmt: skip
        else:  # the point nearest to sliding throughout
            near = min(group, key=lambda r: r["slide"]["shortfall"] + r["slide"]["excess"])
            add(
                test,
                "slid throughout at no point",
                law,
                "rigid sliding",
                near["impulse"],
                "impulse",
                "Coulomb: mu (1 + e) m* v_n",
                note=f"not applicable: {_slide_note(near)}",
                judged=False,
            )
        worst = max(group, key=lambda r: abs(r["design"]["error"]))
        add(test, f"all {len(group)} points (worst {worst['case']})", law, "psi_2 vs design",
            worst["design"], "design", design, note=note)  # fmt: skip
        first = next(r for r in group if r["first_point"])
        if "eps_t_design" in first:
            add(test, first["case"], law, "J vs (1 - eps_t) m* u1", first["eps_t_design"],
                "eps_t", design, note=_slide_note(first))  # fmt: skip
        worst = max(group, key=lambda r: r["energy"]["value"])
        add(
            test,
            f"all {len(group)} points (worst {worst['case']})",
            law,
            "passivity",
            worst["energy"],
            "passivity",
            "tangential + spin kinetic energy out <= in",
        )
    return out


# --- the whole study --------------------------------------------------------------------------


def run_all(is_short: bool, only: tuple[int, ...] = ()) -> dict:
    """Every test (or ``only`` those), every law; the rows and their timings."""
    _MODE["halvings"] = HALVINGS["short" if is_short else "full"]
    tests = {1: test1, 2: test2, 3: test3}
    rows, seconds = [], {}
    for test in range(1, 9):
        if only and test not in only:
            continue
        t0 = time.perf_counter()
        rows += tests[test](is_short) if test in tests else oblique(test, is_short)
        seconds[test] = round(time.perf_counter() - t0, 2)
        print(f"test {test}: {seconds[test]} s", flush=True)
    return {"rows": rows, "seconds": seconds}


def curves(is_short: bool) -> dict:
    """Theory curves of tests 4-6's contact for the figures, on a dense psi_1 grid.

    Rigid Coulomb sliding (e = 0.98), Mindlin's no-slip spring with Coulomb's cap in total form
    (LIGGGHTS's; the continuous hertz/liggghts law) and in incremental form, and the impact
    law's design.
    """
    c = make_contact("al2o3", "al_alloy", (R_AO, None), VN, 0.092, 0.98)
    psi = np.linspace(0.0, 16.0, 17 if is_short else 65)[1:]
    u1 = psi * c.friction * VN / c.kappa
    scene = collide.scene_for(_case_keys(Law("hertz_mindlin", "liggghts", False), c, R_AO,
                                      MATERIALS["al2o3"][2]))  # fmt: skip
    law = law_constants(scene, "wall")
    steps = 4000 if is_short else 20000
    out = {"psi_in": psi.tolist(), "threshold": _threshold(c, 0.98)}
    for name, inc in (("mindlin_total", False), ("mindlin_incremental", True)):
        ref = analytic.law_reference(law, u1, VN, c.m_eff, c.r_eff, steps=steps, incremental=inc)
        out[name] = analytic.normalise(ref["u_out"], c.kappa, c.friction, VN).tolist()
        out[name + "_restitution"] = ref["restitution"].tolist()
    e_n = contact.normal_law_restitution(scene.law.model_id,
                                         scene.law.wall_params[contact.P_BETA])  # fmt: skip
    out["impact"] = [p - analytic.normalise(analytic.ROLL * analytic.impact_design(
        u, VN, c.m_eff, eps_t=EPS_T, friction=c.friction, eps_n=0.98, e_n=e_n) / c.m_eff,
        c.kappa, c.friction, VN) for p, u in zip(psi, u1, strict=True)]  # fmt: skip
    out["sliding"] = (psi - _threshold(c, 0.98)).tolist()
    out["kappa"] = c.kappa
    return out


#: psi_1 of the "coulomb" laws' time-step study (test 5), and its dt factors.
DT_STUDY_PSI = (0.5, 1.0, 2.0, 4.0, 8.0)
DT_STUDY_FACTORS = (1, 2, 4, 8, 16)


def coulomb_dt_study() -> dict:
    """The "coulomb" laws in test 5 at dt / 1 ... dt / 16 against their continuous-time equations.

    Hertz and linear as shipped and Hertz given Mindlin's spring (``coulomb[mindlin]``), each
    with the full-radius lever arms (:data:`FULL_RADIUS_ARMS`), so that psi_2's difference from
    :func:`analytic.law_reference` (rigid-body kinematics at the full radius) is the time
    step's alone. Per law and dt: the largest |psi_2 - reference| over :data:`DT_STUDY_PSI`,
    and at psi_1 = 1 the impulse over Coulomb's, psi_2, the energy change and (dt and dt/16)
    the force history.
    """
    c, _, grains, points = _oblique_setups(5, False)
    runs = {p: r for _, p, _, r in points if p in DT_STUDY_PSI}
    psis = np.array(DT_STUDY_PSI)
    out = {}
    for law in (Law("hertz_mindlin", "coulomb", False), Law("linear", "coulomb", False),
                Law("hertz_mindlin", "coulomb", False, mindlin=True)):  # fmt: skip
        keys = {**_case_keys(law, c, grains["radius"], grains["density"]), **FULL_RADIUS_ARMS}
        scene = collide.scene_for(keys)
        ref = analytic.law_reference(law_constants(scene, "wall"), psis * c.friction * VN / c.kappa,
                                     VN, c.m_eff, c.r_eff)  # fmt: skip
        reference = {p: analytic.normalise(float(u), c.kappa, c.friction, VN)
                     for p, u in zip(DT_STUDY_PSI, ref["u_out"], strict=True)}  # fmt: skip
        base = {p: runs[p](scene, None) for p in DT_STUDY_PSI}
        rows = []
        for f in DT_STUDY_FACTORS:
            at = {p: base[p] if f == 1 else runs[p](scene, base[p]["dt_s"] / f)
                  for p in DT_STUDY_PSI}  # fmt: skip
            errors = [analytic.normalise(r["u_out"], c.kappa, c.friction, r["vn_in"])
                      - reference[p] for p, r in at.items()]  # fmt: skip
            r = at[1.0]
            j = analytic.sliding_impulse(c.friction, r["restitution"], c.m_eff, r["vn_in"])
            rows.append(
                {
                    "dt_s": r["dt_s"],
                    "impulse_over_coulomb": -r["impulse_t"] / j,
                    "coulomb_excess": r["coulomb_excess"],
                    "tangential_energy_change": r["tangential_energy_change"],
                    "psi_out": analytic.normalise(r["u_out"], c.kappa, c.friction, r["vn_in"]),
                    "reference_psi": reference[1.0],
                    "largest_error": float(np.max(np.abs(errors))),
                    "history": _history(r) if f in (1, DT_STUDY_FACTORS[-1]) else None,
                }
            )
        out[law.name] = rows
    return out


#: dem's lever arms switched to the full radius (LAMMPS's): what is left is the time step's.
FULL_RADIUS_ARMS = {"contact.wall_lever_arm": "radius", "contact.slip_lever_arm": "radius"}


def arm_control() -> list[dict]:
    """Test 5 at psi_1 = 0.5, 1, 2, 12 with dem's lever arms and with the full radius, against
    the continuous-time law (rigid-body kinematics at the full radius): psi_2 each way."""
    c, kind, grains, points = _oblique_setups(5, False)
    chosen = [(p, vn, run) for _, p, vn, run in points if p in (0.5, 1.0, 2.0, 12.0)]
    out = []
    for law in (Law("hertz_mindlin", "liggghts", False), Law("linear", "liggghts", False),
                Law("hertz_mindlin", "impact", False)):  # fmt: skip
        keys = _case_keys(law, c, grains["radius"], grains["density"])
        scenes = {"dem": collide.scene_for(keys),
                  "radius": collide.scene_for({**keys, **FULL_RADIUS_ARMS})}  # fmt: skip
        psis = np.array([p for p, _, _ in chosen])
        if law.tangential == "impact":
            e_n = float(scenes["dem"].law.wall_params[contact.P_NORMAL_E])
            reference = []
            for p, vn, _ in chosen:
                j = analytic.impact_design(p * c.friction * vn / c.kappa, vn, c.m_eff,
                                           eps_t=EPS_T, friction=c.friction,
                                           eps_n=c.restitution, e_n=e_n)  # fmt: skip
                reference.append(p - analytic.normalise(analytic.ROLL * j / c.m_eff, c.kappa,
                                                        c.friction, vn))  # fmt: skip
        else:
            ref = analytic.law_reference(
                law_constants(scenes["dem"], kind),
                psis * c.friction * VN / c.kappa,
                VN,
                c.m_eff,
                c.r_eff,
            )
            reference = [analytic.normalise(u, c.kappa, c.friction, VN) for u in ref["u_out"]]
        for (p, _vn, run), ref_psi in zip(chosen, reference, strict=True):
            row = {"law": law.name, "psi_in": p, "reference": float(ref_psi)}
            for arms, scene in scenes.items():
                r = run(scene, None)
                row[arms] = analytic.normalise(r["u_out"], c.kappa, c.friction, r["vn_in"])
                row[arms + "_dt_quarter"] = analytic.normalise(
                    run(scene, r["dt_s"] / 4)["u_out"], c.kappa, c.friction, r["vn_in"]
                )
            out.append(row)
    return out


def write_results(data: dict, path: Path) -> None:
    """results.json (every row, the summary, the curves) and results.csv (the summary)."""
    path.mkdir(parents=True, exist_ok=True)
    compact = _rounded(data)
    lines = []
    for key, value in compact.items():  # a key a line; the rows one a line
        if key == "rows":
            body = ",\n".join(json.dumps(row, default=_jsonable) for row in value)
            lines.append(f'"rows": [\n{body}\n]')
        else:
            lines.append(f"{json.dumps(key)}: {json.dumps(value, default=_jsonable)}")
    (path / "results.json").write_text("{\n" + ",\n".join(lines) + "\n}\n")
    with (path / "results.csv").open("w", newline="") as fh:
        fields = [
            "test",
            "case",
            "law",
            "quantity",
            "measured",
            "reference",
            "error",
            "error_kind",
            "tolerance",
            "pass",
            "error_dt_half",
            "order",
            "design",
            "note",
        ]
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        for row in data["summary"]:
            writer.writerow({k: _fmt(row[k]) for k in fields})


def _rounded(x):
    """``x`` with every float to 9 significant digits (results.json's size; the step errors
    are 1e-6 of a value at the least)."""
    if isinstance(x, dict):
        return {k: _rounded(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_rounded(v) for v in x]
    if isinstance(x, float | np.floating):
        return float(f"{float(x):.9g}") if math.isfinite(x) else None
    return x


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x))


def _fmt(x):
    if isinstance(x, float):
        return "" if math.isnan(x) else f"{x:.6g}"
    return x


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="the CI form: fewer points")
    parser.add_argument("--report-only", action="store_true",
                        help="tables and figures from results.json")  # fmt: skip
    parser.add_argument("--only", type=int, nargs="*", default=(), help="these tests only")
    parser.add_argument("--out", type=Path, default=HERE, help="folder for the results")
    args = parser.parse_args(argv)
    if args.report_only:  # the verdicts again from the recorded rows
        data = json.loads((args.out / "results.json").read_text())
        data["summary"] = summarise(data["rows"])
        write_results(data, args.out)
    else:
        t0 = time.perf_counter()
        header = results_header(SCRIPT, argv, dated=True)
        run = run_all(args.short, tuple(args.only))
        data = {
            **header, "versions": provenance.record()["versions"],
            "mode": "short" if args.short else "full",
            "dt_factors": _MODE["halvings"], "tolerances": TOLERANCES,
            "laws": [law.name for law in LAWS], "materials": MATERIALS,
            "titles": {str(k): v for k, v in TEST_TITLES.items()},
            "rows": run["rows"], "seconds": run["seconds"],
            "curves": curves(args.short),
            "coulomb_dt": {} if args.short else coulomb_dt_study(),
            "arm_control": [] if args.short else arm_control(),
            "summary": summarise(run["rows"]),
        }  # fmt: skip
        data["wall_time_s"] = round(time.perf_counter() - t0, 1)
        data["load_average_end"] = provenance.load_average()
        write_results(data, args.out)
    import draw  # here: matplotlib only where figures are drawn

    draw.figures(data, args.out)
    if args.out == HERE and data["mode"] == "full":
        draw.readme_tables(data, HERE / "README.md")
    failed = [r for r in data["summary"] if r["pass"] is False]
    unjudged = sum(r["pass"] is None for r in data["summary"])
    print(
        f"{len(data['summary'])} key numbers, {len(failed)} outside their tolerance, "
        f"{unjudged} reported and not judged"
    )
    for r in failed:
        print(
            f"  test {r['test']} {r['law']} {r['quantity']} ({r['case']}): "
            f"{r['measured']:.6g} vs {r['reference']:.6g}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
