"""The contact-law registry (dem.physics.laws) and the scalar sub-models of dem.kernels.contact."""

import math
from pathlib import Path

import numpy as np
import pytest

from dem.errors import InputError
from dem.kernels import contact
from dem.physics import laws
from dem.physics.contact import ContactLaw
from dem.scene.case import load_case

SPHERE_BED = Path(__file__).resolve().parents[2] / "cases" / "sphere-bed"


def test_every_kernel_law_has_one_row_and_back():
    assert set(laws.TANGENTIAL_LAWS) == set(contact.TANGENTIAL)
    assert set(laws.NORMAL_LAWS) == set(contact.MODELS)
    for name, row in laws.TANGENTIAL_LAWS.items():
        assert row.name == name
        assert set(row.keys) == set(laws.NORMAL_LAWS)
        assert row.liggghts_as in laws.TANGENTIAL_LAWS
        # a law either fits something, or says why it fits nothing
        assert bool(row.calibrates) != bool(row.calibration)


@pytest.mark.parametrize("model", sorted(laws.NORMAL_LAWS))
@pytest.mark.parametrize("tangential", sorted(laws.TANGENTIAL_LAWS))
def test_history_width_is_the_sum_over_the_sub_models(model, tangential):
    width = laws.history_width(tangential, model)
    assert width == laws.NORMAL_LAWS[model].history_width + (
        laws.TANGENTIAL_LAWS[tangential].history_width
    )
    assert width == contact.HISTORY_WIDTH[tangential]


@pytest.mark.parametrize("model", sorted(laws.NORMAL_LAWS))
@pytest.mark.parametrize("tangential", sorted(laws.TANGENTIAL_LAWS))
def test_a_key_of_another_law_is_refused_at_load_and_its_own_accepted(model, tangential):
    own = {
        "hertz_mindlin": {"contact.youngs_modulus": 5.0e7, "contact.stiffness": None},
        "linear": {"contact.youngs_modulus": None, "contact.stiffness": 4.0e3},
    }[model]
    base = {"contact.model": model, "contact.tangential": tangential, **own}
    case = load_case(SPHERE_BED, base)
    assert (case.contact.model, case.contact.tangential) == (model, tangential)
    foreign = laws.foreign_keys(model, tangential)
    for key in laws.TANGENTIAL_LAWS[tangential].keys[model]:
        assert key not in foreign
        load_case(SPHERE_BED, {**base, f"contact.{key}": 0.3})
    for key in foreign:
        with pytest.raises(InputError, match=key):
            load_case(SPHERE_BED, {**base, f"contact.{key}": 0.3})


def test_calibration_refusal_comes_from_the_row():
    from dem.studies.calibrate import calibrate

    case = load_case(SPHERE_BED, {"contact.tangential": "liggghts", "run.timestep": "auto"})
    assert laws.TANGENTIAL_LAWS["liggghts"].calibration_refused
    with pytest.raises(InputError, match="contact.tangential"):
        calibrate(case)


@pytest.mark.validation
def test_the_time_step_resolves_the_row_spring():
    """A law with a material tangential spring has a limit set by it; "impact" sizes its stick
    by the step itself, so its limit is the normal one."""
    from dem.scene.timestep import timestep_for

    limits = {}
    for tangential in laws.TANGENTIAL_LAWS:
        case = load_case(SPHERE_BED, {"contact.tangential": tangential, "run.timestep": "auto"})
        limits[tangential] = timestep_for(case).limit
    assert limits["impact"] >= limits["coulomb"]
    assert limits["impact"] >= limits["liggghts"]


@pytest.mark.parametrize("model", ["linear", "hertz_mindlin"])
def test_the_liggghts_dashpot_damps_the_rolling_tangential_oscillator(model):
    """The tangential oscillator of a rolling sphere has stiffness k_t and mass 2/7 m*; its
    damping ratio is gamma_t / (2 sqrt(k_t 2/7 m*)), with gamma_t as the kernel applies it
    (linear: gamma_n; Hertz: -2 sqrt(5/6) beta sqrt(S_t m*)). The step limit takes that ratio.
    (It took zeta_n sqrt(2/7) before: 3.5 times too weak a dashpot for eps_n = 0, and a linear
    bed at 0.82 of that limit blew up while settling.)"""
    keys = {"contact.tangential": "liggghts", "run.timestep": "auto"}
    if model == "linear":
        keys |= {"contact.model": "linear", "contact.youngs_modulus": None,
                 "contact.stiffness": 1.68e5}  # fmt: skip
    case = load_case(SPHERE_BED, keys)
    law = ContactLaw.from_case(case)
    p = law.wall_params  # sphere-wall: m* = m, R* = r
    m = case.material.density * 4.0 / 3.0 * math.pi * case.particles.radius**3
    beta = p[contact.P_BETA]
    if model == "linear":
        k_n = p[contact.P_KN]
        k_t = p[contact.P_KT_RATIO] * k_n
        gamma_t = -2.0 * beta * math.sqrt(k_n * m)  # gamma_n
        s_n, a, zeta_n = k_n, 1.0, -beta
    else:
        delta = 1e-6
        a = math.sqrt(case.particles.radius * delta)
        s_n = 2.0 * p[contact.P_YSTAR] * a
        k_t = 8.0 * p[contact.P_GSTAR] * a
        gamma_t = -2.0 * math.sqrt(5.0 / 6.0) * beta * math.sqrt(k_t * m)
        zeta_n = -math.sqrt(5.0 / 6.0) * beta
    m_t = 2.0 / 7.0 * m
    want = gamma_t / (2.0 * math.sqrt(k_t * m_t))
    kt_eff, zeta_t = laws.TANGENTIAL_LAWS[law.tangential].step_spring(p, model, s_n, a, zeta_n, 3.5)
    assert kt_eff == pytest.approx(3.5 * k_t, rel=1e-12)
    assert zeta_t == pytest.approx(want, rel=1e-12)
    assert zeta_t > 1.0  # eps_n = 0: overdamped, the limit well below 2 / omega_t


def _random_contact(rng):
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    return n, rng.normal(0.0, 0.2, 3)


@pytest.mark.parametrize("model", ["linear", "hertz_mindlin"])
@pytest.mark.parametrize("tangential", ["coulomb", "liggghts", "impact"])
def test_coefficients_are_the_formulas_of_the_docstring(model, tangential):
    """law_coefficients against the textbook forms, written out here independently."""
    kn0, youngs, nu, e, kappa, zeta_t, f_t = 4.0e3, 5.0e7, 0.3, 0.4, 0.3, 0.6, 2.0 / 7.0
    p = contact.make_params(
        model=model, stiffness=kn0, youngs_modulus=youngs, poisson_ratio=nu, restitution=e,
        tangential=tangential, tangential_stiffness_ratio=kappa,
        tangential_damping_ratio=zeta_t, tangential_mass_factor=f_t, friction=0.3,
    )  # fmt: skip
    beta = math.log(e) / math.sqrt(math.log(e) ** 2 + math.pi**2)
    y_star = youngs / (2.0 * (1.0 - nu * nu))
    g_star = youngs / (4.0 * (2.0 - nu) * (1.0 + nu))
    for delta, m_eff, r_eff in [(1e-6, 1e-4, 1e-3), (3e-5, 2e-3, 2e-3)]:
        kn, gn, kt, gt = contact.law_coefficients(contact.MODELS[model], delta, m_eff, r_eff, p)
        if model == "linear":
            want_kn, s_n = kn0, kn0
            want_gn = -2.0 * beta * math.sqrt(kn0 * m_eff)
            want_kt = kappa * kn0 if tangential != "impact" else 0.0
            want_gt = {
                "coulomb": 2.0 * zeta_t * math.sqrt(want_kt * f_t * m_eff),
                "liggghts": want_gn,
            }.get(tangential, 0.0)
        else:
            a = math.sqrt(r_eff * delta)
            want_kn, s_n = 4.0 / 3.0 * y_star * a, 2.0 * y_star * a
            want_gn = -2.0 * math.sqrt(5.0 / 6.0) * beta * math.sqrt(s_n * m_eff)
            s_t = 8.0 * g_star * a
            want_kt = {"coulomb": kappa * s_n, "liggghts": s_t}.get(tangential, 0.0)
            want_gt = {
                "coulomb": 2.0 * zeta_t * math.sqrt(kappa * s_n * f_t * m_eff),
                "liggghts": -2.0 * math.sqrt(5.0 / 6.0) * beta * math.sqrt(s_t * m_eff),
            }.get(tangential, 0.0)
        assert (kn, gn, kt, gt) == pytest.approx((want_kn, want_gn, want_kt, want_gt), rel=1e-12)


@pytest.mark.parametrize("plastic", [False, True])
def test_the_impact_core_is_a_function_of_scalars(plastic):
    """impact_tangential and plastic_normal run as plain Python on floats (as in numba's CUDA
    simulator) and give the compiled result bit for bit over a random sequence of contact
    states, the plastic contact's (eps_n = 0) and the other's."""
    p = contact.make_params(
        model="hertz_mindlin", youngs_modulus=5e7, restitution=0.0 if plastic else 0.3,
        friction=0.35, tangential="impact", tangential_mass_factor=1.0,
    )  # fmt: skip
    assert p[contact.P_PLASTIC] == float(plastic)
    args = (p[contact.P_IMPACT_RATIO], p[contact.P_IMPACT_CAP], p[contact.P_MU],
            p[contact.P_MASS_T], p[contact.P_STICK_RATE], p[contact.P_STICK_ZETA])  # fmt: skip
    rng = np.random.default_rng(5)
    compiled = python = (0.0, 0.0, 0.0, 0.0, 0.0)
    for _ in range(200):
        n, vt = _random_contact(rng)
        vn, fn = rng.normal(0.0, 0.3), abs(rng.normal(0.0, 2.0))
        h = [compiled, python]
        stopped = False
        if plastic:
            normal = (vn, 2e-4, p[contact.P_STICK_RATE], p[contact.P_STICK_ZETA], 1e-6)
            fa = contact.plastic_normal(fn, *normal, compiled[3], compiled[4])
            fb = contact.plastic_normal.py_func(fn, *normal, python[3], python[4])
            assert fa == fb
            h = [(*compiled[:3], fa[1], compiled[4]), (*python[:3], fb[1], python[4])]
            fn, stopped = fa[0], fa[3]
        state = (*n, vn, fn, *vt, 3e5, 1e-4, 1e-6)
        a = contact.impact_tangential(*args, *state, *h[0], plastic, stopped)
        b = contact.impact_tangential.py_func(*args, *state, *h[1], plastic, stopped)
        assert a == b
        compiled, python = a[3:], b[3:]
        if plastic:
            compiled = (*compiled[:4], fa[2])
            python = (*python[:4], fb[2])
        if rng.random() < 0.1:  # the contact breaks: its history is reset
            compiled = python = (0.0, 0.0, 0.0, 0.0, 0.0)
