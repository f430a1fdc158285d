"""Contact laws as sub-models (normal, damping, tangential, rolling); one contact routine uses them.

Each sub-model is a small ``@njit`` function of scalars that returns scalars (the contact's
history goes in and comes out as numbers), so the same functions can run inside GPU kernels;
:func:`contact_core` assembles them into one contact (scalars in and out, for the CPU engine and
the GPU kernels of :mod:`dem.kernels.cuda` alike) and :func:`contact_force` is the CPU's thin
wrapper that reads the contact's history row, calls the core and writes the row back.
What the rest of dem asks of a law (case keys, time step, export, calibration) is its row in
:mod:`dem.physics.laws`.

A contact between sphere i and sphere j (or a wall, j = wall) is described by

- the unit normal n pointing from j to i and the overlap delta = r_i + r_j - |x_i - x_j| > 0,
- the relative velocity of the centres v_r = v_i - v_j and the spins omega_i, omega_j,
- the lever arms c_i = r_i - delta / 2, c_j = r_j - delta / 2 (a wall: c_i = r_i - f_w delta,
  c_j = 0, with f_w = 1, the contact point on the wall's surface, f_w = 1/2, LIGGGHTS's
  midpoint of the overlap, or f_w = 0, LAMMPS's full radius: ``[contact] wall_lever_arm``,
  :data:`WALL_LEVER_ARMS`), and the slip velocity's arms a_i, a_j: the same c_i, c_j by
  default, or the full radii r_i, r_j as LAMMPS takes them (``[contact] slip_lever_arm``,
  :data:`SLIP_LEVER_ARMS`),
- the effective mass m* = m_i m_j / (m_i + m_j) and radius R* = r_i r_j / (r_i + r_j) (a wall has
  infinite mass and radius: m* = m_i, R* = r_i),
- the contact's history, one row per contact (a pair, a sphere and a flat wall, a sphere's mesh
  slot) of the law's width (:data:`HISTORY_WIDTH`): the tangential spring elongation s, m
  (3 floats); "impact" adds 2 (below).

A *law* maps (delta, m*, R*) to the four coefficients (k_n, gamma_n, k_t, gamma_t); the
spring-dashpot routine :func:`contact_core` turns them into forces:

    F_n = k_n delta - gamma_n (v_r . n)                    (clamped to >= 0 with limit_force)
    v_t = v_r - (v_r . n) n - (a_i omega_i + a_j omega_j) x n   (slip velocity at the contact)
    s  <- s + v_t dt;  s <- s - (s . n) n                  (increment, then project)
    F_i = F_n n + F_t,  tau_i = -c_i n x F_t,  tau_j = -c_j n x F_t,  F_j = -F_i

with the tangential force F_t by one of three conventions (``[contact] tangential``; the
default is ``"impact"``):

- ``"coulomb"`` (Luding 2008, LAMMPS ``pair granular``): the *total* tangential force, spring
  plus dashpot, is capped at Coulomb's limit, and the spring is reset to match:

      F_t = -k_t s - gamma_t v_t;  if |F_t| > mu |F_n|:
          F_t <- mu |F_n| F_t / |F_t|,  f_s = F_t + gamma_t v_t,
          f_s <- f_s - max(0, f_s . v_t - max(0, -k_t s . v_t)) v_t / |v_t|^2,
          s <- -f_s / k_t

  so a contact never transmits more than mu |F_n|, and a stiff contact converges to rigid
  Coulomb friction (stick, or slide with mu |F_n| opposing the slip). The reset never leaves
  the spring more force along the slip than it held (:func:`coulomb_tangential`): LAMMPS's
  reset stops at f_s = F_t + gamma_t v_t, which where the dashpot alone exceeds the cap (first
  touch) stores a force along the slip, and with Hertz's growing k_t friction then pushed the
  slip forward.
- ``"liggghts"`` (LIGGGHTS ``tangential_model history``, for deck equivalence): the Coulomb test
  is made on the spring alone and the dashpot is added while sticking:

      F_t = -k_t s - gamma_t v_t                            if k_t |s| <= mu |F_n|
      F_t = -mu |F_n| s / |s|,  s <- -F_t / k_t             otherwise (sliding, no damping)

  While sticking, a heavily damped contact can transmit more than mu |F_n|.
- ``"impact"`` (impact-aware: eps_t is a material property, not a per-drive fit). One spring
  cannot be both soft enough during an impact to return eps_t = 0.8 (k_t / k_n ~ 0.02-0.1) and
  stiff enough at rest to stick as Coulomb's rigid stick (that spring rings near the drive
  frequency). So a contact remembers its phase (5 floats of history, :data:`HISTORY_WIDTH`):

  * *impact*, from first touch while approaching (v_n = v_r . n < 0): at first touch the slip
    velocity v_t0 and approach speed |v_n0| fix a force ratio
    c = min((1 - eps_t) |v_t0| / |v_n0|, mu (1 + eps_n)) / (1 + e_n), and the tangential force is
    F_t = -c F_n^+ t0 (t0 = v_t0 / |v_t0| projected on the tangent plane, F_n^+ = max(F_n, 0)).
    Over a free impact the normal impulse is (1 + e_n) m* |v_n0|, e_n the normal law's own
    restitution (:func:`normal_law_restitution`), so the tangential impulse is
    min((1 - eps_t) m* |v_t0|, mu (1 + eps_n) m* |v_n0|): the paper's Eq. 12 where Coulomb allows
    it, the Coulomb-bounded landing (:mod:`dem.pointmass.bounded`) where it does not, and never
    more than mu F_n at any instant. Because F_t is proportional to F_n, a clump landing on
    several members at once gets the same total as on one. The impact ends when the separating
    speed stops growing (the contact force is back to the external load), when the slip along t0
    has stopped (a rolling sphere reaches rolling: it keeps eps_t >= 5/7), or after
    :data:`IMPACT_MAX_PHASE` radians of the local normal oscillation sqrt(k_n / m*).
  * *enduring*, after that: a stick spring-dashpot sized by the time step, not by the material,
    k_s = f_t m* (alpha / dt)^2, gamma_s = 2 zeta_s alpha f_t m* / dt (alpha = ``stick_rate``,
    :data:`dem.config.DEM_STICK_RATE`), total force capped at mu F_n^+ as in "coulomb". Its
    spring is set at the switch so that the force is continuous. As dt shrinks (a stiffer
    material) it converges to Coulomb's rigid stick.

  A contact that breaks (its history reset to zeros) starts a new impact when it re-forms.

  With eps_n = 0 the contact is perfectly plastic (:func:`plastic_normal`; ``P_PLASTIC``): the
  normal dashpot alone would return e_n = 0.135 of the approach speed, or, pulling, catch the
  grain back and hold it after its load has gone (a lone Hertz grain at 2e9 Pa hopped 2-5 % fast
  for it, validation/hopping-bias). So it never pulls; the material law stops the approach, its
  last step capped at the force that stops it within the step (normal impulse m* |v_n0|: e_n = 0
  above; the impact ends in that step); and it then unloads rigidly on a normal stick sized by
  the step (:data:`dem.config.DEM_NORMAL_STICK_RATE`), from zero force, capped by the material
  force and by zero: Walton and Braun's elastic-plastic contact with the stiffest unloading
  branch the step resolves. h4 then holds the normal stick's force.

Optional rolling resistance (LIGGGHTS ``rolling_model cdt``, constant directional torque):
w_r = omega_i - omega_j without its normal part; tau_i -= mu_r |F_n| R* w_r / |w_r|,
tau_j += the same.

Laws (kernel ids :data:`MODELS` and :data:`TANGENTIAL`; a new tangential law is a new function
here and one row in :data:`dem.physics.laws.TANGENTIAL_LAWS`). The normal part is that of LIGGGHTS;
the tangential part depends on the convention:

- linear spring-dashpot (LIGGGHTS ``hooke/stiffness`` with a restitution-derived damping):
  k_n given, gamma_n = -2 beta sqrt(k_n m*); k_t = kappa k_n with kappa =
  ``tangential_stiffness_ratio``. "liggghts": gamma_t = gamma_n. "coulomb":
  gamma_t = 2 zeta_t sqrt(k_t f_t m*) with zeta_t = ``tangential_damping_ratio`` and f_t the
  tangential mass factor (:func:`tangential_mass_factor`).
- Hertz-Mindlin: with S_n = 2 Y* sqrt(R* delta) (the tangent normal stiffness),
  k_n = 4/3 Y* sqrt(R* delta), gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*). "liggghts" (as coded in
  LIGGGHTS, tangential damping on): k_t = S_t = 8 G* sqrt(R* delta),
  gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*). "coulomb": k_t = kappa S_n,
  gamma_t = 2 zeta_t sqrt(k_t f_t m*).

Here beta = ln(e) / sqrt(ln(e)^2 + pi^2) for 0 < e <= 1 and beta = -1 for e = 0 (critical damping
of the linear law; ln 0 is never evaluated), see :func:`damping_beta`. For equal materials
Y* = Y / (2 (1 - nu^2)) and G* = Y / (4 (2 - nu)(1 + nu)). How kappa and zeta_t follow from the
tangential restitution eps_t is in :mod:`dem.physics.tangential`.

Parameters reach the kernels as one float64 array ``params``: a row of :data:`N_PARAMS` floats
indexed by the ``P_*`` constants (:func:`make_params`) for the grain-grain law, then a second
row for the grain-wall law (the material with ``[wall]``'s friction and restitutions), as
:class:`dem.physics.contact.ContactLaw` packs them; the walls read the second row
(:func:`wall_row`), or the only one of a one-row array.
"""

from dem.kernels.contact.force import (
    add_wall_contact,
    contact_core,
    contact_force,
    contact_force_inlined,
    pair_arms,
    wall_arms,
    wall_row,
)
from dem.kernels.contact.laws import (
    coulomb_tangential,
    impact_tangential,
    law_coefficients,
    liggghts_tangential,
    normal_scale,
    plastic_normal,
    rolling_cdt,
    spring_step,
)
from dem.kernels.contact.params import (
    HERTZ,
    HERTZ_TIME_CONSTANT,
    HISTORY_WIDTH,
    IMPACT,
    IMPACT_MAX_PHASE,
    LINEAR,
    MODELS,
    N_PARAMS,
    P_BETA,
    P_DAMP_N,
    P_DAMP_N_SCALE,
    P_DAMP_T,
    P_DAMP_T_SCALE,
    P_GSTAR,
    P_IMPACT_CAP,
    P_IMPACT_RATIO,
    P_KN,
    P_KN_COEF,
    P_KT_COEF,
    P_KT_RATIO,
    P_LIMIT_FORCE,
    P_MASS_N,
    P_MASS_T,
    P_MU,
    P_MU_ROLL,
    P_NORMAL_E,
    P_NORMAL_STICK_RATE,
    P_PLASTIC,
    P_SLIP_ARM,
    P_STICK_RATE,
    P_STICK_ZETA,
    P_TANGENTIAL,
    P_WALL_ARM,
    P_YSTAR,
    P_ZETA_T,
    SLIP_LEVER_ARMS,
    TANGENTIAL,
    WALL_LEVER_ARMS,
    contact_moduli,
    critical_timestep,
    damping_beta,
    damping_ratio,
    equivalent_material,
    hertz_collision_time,
    hertz_max_overlap,
    hertz_youngs_star_for_time,
    linear_collision_time,
    make_params,
    normal_law_restitution,
    rayleigh_time,
    tangent_stiffness,
    youngs_modulus_from_star,
    youngs_star,
)

__all__ = [
    "HERTZ",
    "HERTZ_TIME_CONSTANT",
    "HISTORY_WIDTH",
    "IMPACT",
    "IMPACT_MAX_PHASE",
    "LINEAR",
    "MODELS",
    "N_PARAMS",
    "P_BETA",
    "P_DAMP_N",
    "P_DAMP_N_SCALE",
    "P_DAMP_T",
    "P_DAMP_T_SCALE",
    "P_GSTAR",
    "P_IMPACT_CAP",
    "P_IMPACT_RATIO",
    "P_KN",
    "P_KN_COEF",
    "P_KT_COEF",
    "P_KT_RATIO",
    "P_LIMIT_FORCE",
    "P_MASS_N",
    "P_MASS_T",
    "P_MU",
    "P_MU_ROLL",
    "P_NORMAL_E",
    "P_NORMAL_STICK_RATE",
    "P_PLASTIC",
    "P_SLIP_ARM",
    "P_STICK_RATE",
    "P_STICK_ZETA",
    "P_TANGENTIAL",
    "P_WALL_ARM",
    "P_YSTAR",
    "P_ZETA_T",
    "SLIP_LEVER_ARMS",
    "TANGENTIAL",
    "WALL_LEVER_ARMS",
    "add_wall_contact",
    "contact_core",
    "contact_force",
    "contact_force_inlined",
    "contact_moduli",
    "coulomb_tangential",
    "critical_timestep",
    "damping_beta",
    "damping_ratio",
    "equivalent_material",
    "hertz_collision_time",
    "hertz_max_overlap",
    "hertz_youngs_star_for_time",
    "impact_tangential",
    "law_coefficients",
    "liggghts_tangential",
    "linear_collision_time",
    "make_params",
    "normal_law_restitution",
    "normal_scale",
    "pair_arms",
    "plastic_normal",
    "rayleigh_time",
    "tangent_stiffness",
    "youngs_modulus_from_star",
    "youngs_star",
    "rolling_cdt",
    "spring_step",
    "wall_arms",
    "wall_row",
]
