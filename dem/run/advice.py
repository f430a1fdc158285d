"""A piece of advice about a case key, and the rounding its suggested values take.

:mod:`dem.run.accuracy` (the expected error, the settings' advice) and :mod:`dem.run.stiffness`
(the contact's compliance against the drive) both give advice; ``dem plan --suggest`` applies its
values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Advice:
    """One piece of advice about a case key.

    ``level`` is "warn" (the case asks for far more or less than it needs, or leaves the studied
    range) or "note"; ``key`` is the case key it concerns; ``value`` the value the advice sets
    the key to (None where it names none): ``dem plan --suggest`` applies these.
    """

    level: str
    key: str
    text: str
    value: float | int | str | None = None


def round_up(x: float) -> float:
    """``x`` rounded up to 3 significant digits (a limit met, not missed by rounding)."""
    digits = 2 - math.floor(math.log10(abs(x)))
    return float(math.ceil(x * 10.0**digits) / 10.0**digits)
