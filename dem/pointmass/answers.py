"""The point model's answers as ``dem pointmass`` gives them: a JSON object, or lines of text.

:func:`thresholds_answer` gives the throw numbers where sliding and flight begin (Eqs. 1, 2 and
4), :func:`velocity_answer` the steady motion's velocity and phases (with the velocity in m/s
and the amplitude at a given frequency), :func:`rolling_answer` the same for a sphere free to roll
(:mod:`dem.pointmass.rolling`), and :func:`optimum_lines` an optimum with what it held fixed
(:func:`dem.pointmass.sweep.optimum`). Each answer is a dict for ``--json`` and the
lines the command prints otherwise.
"""

from __future__ import annotations

import math

from dem.pointmass.limits import thresholds
from dem.pointmass.model import amplitude_from_throw_number
from dem.pointmass.rolling import DOWNHILL


def thresholds_answer(angle: float, friction: float, inclination: float) -> tuple[dict, list[str]]:
    """Throw numbers of forward and backward sliding and of flight: the dict and the lines."""
    t = thresholds(angle, friction, inclination)
    result = {
        "angle": angle,
        "friction": friction,
        "inclination": inclination,
        "forward_sliding": t.forward_sliding,
        "backward_sliding": t.backward_sliding,
        "flight": t.flight,
    }
    back = "never" if t.backward_sliding is None else f"{t.backward_sliding:.4f}"
    lines = [
        f"forward sliding  Gamma > {t.forward_sliding:.4f}   (Eq. 1)",
        f"backward sliding Gamma > {back}   (Eq. 2)",
        f"flight           Gamma >= {t.flight:.4f}   (Eq. 4)",
    ]
    return result, lines


def velocity_answer(r, frequency: float | None) -> tuple[dict, list[str]]:
    """A velocity result ``r`` (:func:`dem.pointmass.velocity`): the dict and the lines.

    With ``frequency`` (Hz) the dict adds it, the velocity in m/s and the amplitude, m.
    """
    result = r.as_dict()
    if frequency is not None:
        result["frequency"] = frequency
        result["velocity"] = r.velocity(frequency)
        result["amplitude"] = amplitude_from_throw_number(
            r.throw_number, frequency, r.angle, r.inclination
        )
    lines = [f"velocity_norm  {r.velocity_norm:.6f}   (v / (A omega cos phi))"]
    if frequency is not None:
        lines.append(f"velocity       {result['velocity']:.6g} m/s at {frequency:g} Hz")
    lines += [f"regime         {r.regime}", f"impact         {r.impact}"]
    if r.periodic:
        lines.append(f"periodic       yes, period {r.period} cycle(s), settled after {r.cycles}")
    else:
        lines.append(
            f"periodic       no: mean over starting phases, spread {r.spread:.3g} "
            f"(range {r.velocity_min:.4f} .. {r.velocity_max:.4f})"
        )
    lines.append(
        f"phases         stick {r.stick:.3f}  forward {r.slide_forward:.3f}  "
        f"backward {r.slide_backward:.3f}  flight {r.flight:.3f} (fractions of a cycle)"
    )
    return result, lines


def optimum_lines(o, over: str, hold: str) -> list[str]:
    """An optimum ``o`` (:func:`dem.pointmass.sweep.optimum`) over ``over``, holding ``hold``."""
    unit = "deg" if over == "angle" else ""
    held = ", ".join(
        f"{k} = {v:g}" if isinstance(v, int | float) else f"{k} = {v}" for k, v in o.held.items()
    )
    return [
        f"optimum {over}: {o.value:.3f} {unit}  (holding {hold}; {held})",
        f"maximises      {o.objective}",
        f"velocity       {o.velocity:.5g} m/s   velocity_norm {o.velocity_norm:.5f}",
        f"drive          Gamma {o.throw_number:.4g}, phi {o.angle:.3g} deg, "
        f"A {o.amplitude * 1e3:.4g} mm, f {o.frequency:.4g} Hz",
        f"regime         {o.regime}",
        f"within 90%     {o.plateau[0]:.3g} .. {o.plateau[1]:.3g} {unit}",
    ]


def rolling_answer(r, frequency: float | None, pointmass_norm: float) -> tuple[dict, list[str]]:
    """A rolling sphere's result ``r`` (:func:`dem.pointmass.rolling.velocity`): dict and lines.

    ``pointmass_norm`` is the point mass's v_norm on the same drive and landing (the sphere
    with its rotation locked), printed beside it. With ``frequency`` (Hz) the dict adds it, the
    velocity in m/s and the amplitude, m.
    """
    from dem.config import GRAVITY

    result = r.as_dict() | {"grain": "rolling-sphere", "pointmass_velocity_norm": pointmass_norm}
    if frequency is not None:
        result["frequency"] = frequency
        result["velocity"] = None if r.regime == DOWNHILL else r.velocity(frequency)
        result["amplitude"] = amplitude_from_throw_number(
            r.throw_number, frequency, r.angle, r.inclination
        )
    k = "inf (rotation locked)" if r.inertia_factor == float("inf") else f"{r.inertia_factor:g}"
    if r.regime == DOWNHILL:
        slope = GRAVITY * math.sin(math.radians(r.inclination)) / (1.0 + r.inertia_factor)
        lines = [
            f"velocity_norm  none: no steady state on an incline, it changes by "
            f"{r.drift_per_cycle:+.6f} a cycle (g sin(alpha) / (1 + k) = {slope:.4g} m/s^2 "
            "downhill, whatever the drive)"
        ]
    else:
        lines = [f"velocity_norm  {r.velocity_norm:.6f}   (v / (A omega cos phi))"]
        if frequency is not None:
            lines.append(f"velocity       {result['velocity']:.6g} m/s at {frequency:g} Hz")
    laws = {"centre": "eps_t of the centre's velocity, never past rolling",
            "contact": "eps_t of the contact point's slip"}  # fmt: skip
    start = (
        "at rest on the trough as the drive starts"
        if r.momentum == 1.0
        else f"with a momentum about its contact line P = {r.momentum:g}"
    )
    lines += [
        f"grain          rolling sphere, I = {k} m r^2, started {start}",
        f"regime         {r.regime}",
        f"landing        {r.landing} ({laws[r.landing]}), impact {r.impact}",
    ]
    if r.periodic:
        lines.append(f"periodic       yes, period {r.period} cycle(s), settled after {r.cycles}")
    elif r.regime != DOWNHILL:
        lines.append(
            f"periodic       no: mean over starting phases, spread {r.spread:.3g} "
            f"(range {r.velocity_min:.4f} .. {r.velocity_max:.4f})"
        )
    lines += [
        f"phases         rolling {r.rolling:.3f}  slipping forward {r.slip_forward:.3f}  "
        f"backward {r.slip_backward:.3f}  flight {r.flight:.3f} (fractions of a cycle)",
        f"point mass     {pointmass_norm:.6f} (the same drive and impact law, rotation locked)",
    ]
    return result, lines
