"""The normal damping sub-model: the dashpot that gives the normal restitution eps_n."""

from __future__ import annotations

import math
from dataclasses import dataclass

from dem.kernels import contact


def restitution_for_beta(beta: float) -> float:
    """The e whose beta = ln e / sqrt(ln^2 e + pi^2) is ``beta`` (-1 < beta <= 0); 0 for -1."""
    if beta <= -1.0:
        return 0.0
    if beta >= 0.0:
        return 1.0
    return math.exp(beta * math.pi / math.sqrt(1.0 - beta * beta))


@dataclass(frozen=True)
class Damping:
    """Restitution-derived damping (LIGGGHTS ``coeff_restitution``, Tsuji et al. 1992 for Hertz).

    Attributes:
        restitution: eps_n, the normal restitution in [0, 1] (0: critical damping).
        beta_override: Overrides the damping parameter derived from eps_n (over-critical damping,
            beta < -1, for studies); None derives it.

    """

    restitution: float
    beta_override: float | None = None

    @property
    def beta(self) -> float:
        """Beta = ln e / sqrt(ln^2 e + pi^2), -1 for e = 0 (kernels: damping_beta)."""
        if self.beta_override is not None:
            return self.beta_override
        return contact.damping_beta(self.restitution)

    @property
    def critically_damped(self) -> bool:
        """True at or beyond critical damping (beta <= -1: eps_n = 0)."""
        return not self.beta > -1.0 + 1e-12

    def ratio(self, model: str) -> float:
        """zeta_n against the tangent stiffness S_n (:func:`dem.kernels.contact.damping_ratio`)."""
        return contact.damping_ratio(model, self.beta)

    def kernel_args(self) -> dict:
        """The keyword arguments of :func:`dem.kernels.contact.make_params` it decides."""
        args = {"restitution": self.restitution}
        if self.beta_override is not None:
            args["beta"] = self.beta_override
        return args
