"""The point mass whose landings never take more than Coulomb allows (a time-stepped twin).

The paper's impact law (its Eq. 12) sets the tangential velocity after a landing to eps_t times
the velocity before, whatever the normal velocity. A grain whose contact obeys Coulomb friction
cannot do that at a grazing landing: a plastic impact (eps_n = 0) transmits a tangential
impulse of at most mu times the normal one. This model keeps Eq. 12 and caps the loss there:

    u <- eps_t u,  unless |u - eps_t u| > mu |dw| tan(phi);  then u <- u - mu |dw| tan(phi) sgn(u)

with u the velocity along the trough in units of A omega cos(phi), w the normal velocity in
units of A omega sin(phi) and dw its jump at the landing (horizontal trough, eps_n = 0). It is
integrated by Moreau-Jean time stepping (:func:`dem.pointmass.stepped.step_point_mass`,
``steps`` per drive period), independently of the event-driven kernel of
:mod:`dem.pointmass.model`; below the Coulomb bound the two agree. A DEM grain whose contact
is Coulomb-exact follows this model at grazing landings (validation/single-grain).
"""

import math

import numpy as np

from dem.pointmass.stepped import step_point_mass


def coulomb_bounded_velocity(gamma, phi_deg, mu, eps_t, steps=4000, transient=100, measured=40):
    """Mean conveying velocity over A omega cos(phi) with Coulomb-bounded landings.

    Args:
        gamma: Throw number Gamma > 1 for flight (alpha = 0).
        phi_deg: Vibration angle, deg.
        mu: Friction coefficient.
        eps_t: Tangential restitution of a landing (eps_n = 0).
        steps: Time steps per drive period.
        transient: Periods discarded before measuring.
        measured: Periods averaged.

    """
    phi = math.radians(phi_deg)
    _, mean_u = step_point_mass(
        gamma, phi, mu, 0.0, eps_t, 0.0, steps, transient, measured, True, np.zeros((0, 2))
    )
    return mean_u / math.cos(phi)
