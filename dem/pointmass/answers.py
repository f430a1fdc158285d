"""The point model's answers as ``dem pointmass`` gives them: a JSON object, or lines of text.

:func:`thresholds_answer` gives the throw numbers where sliding and flight begin (Eqs. 1, 2 and
4), :func:`velocity_answer` the steady motion's velocity and phases (with the velocity in m/s
and the amplitude at a given frequency), and :func:`optimum_lines` an optimum with what it
held fixed (:func:`dem.pointmass.sweep.optimum`). Each answer is a dict for ``--json`` and the
lines the command prints otherwise.
"""

from __future__ import annotations

from dem.pointmass.limits import thresholds
from dem.pointmass.model import amplitude_from_throw_number


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
