"""The drive of a deck: effective gravity in the trough's accelerating frame.

The deck simulates the trough section in the trough's accelerating frame: the walls stay still
and every grain feels the effective gravity

    g_x(t) = -g sin(alpha) + A omega^2 sin(omega tau) cos(phi)
    g_y(t) = 0
    g_z(t) = -g cos(alpha) + A omega^2 sin(omega tau) sin(phi)

in m/s^2, with tau the time since the drive started. ``fix gravity`` takes a magnitude and a
direction; both are equal-style variables, |g(t)| and (g_x, 0, g_z). Before the drive starts
(the fill) gravity is static, (g_x, 0, g_z) at tau = 0 without the drive
(:func:`gravity_block`); :func:`drive_block` switches the drive on.
"""

from __future__ import annotations

import math
import re

from dem.config import GRAVITY
from dem.io.liggghts.text import fmt


def static_gravity(inclination: float) -> tuple[float, float]:
    """Gravity (g_x, g_z), m/s^2, in the frame of a trough inclined by ``inclination`` deg."""
    alpha = math.radians(inclination)
    return -GRAVITY * math.sin(alpha), -GRAVITY * math.cos(alpha)


def gravity_block(gx0: float, gz0: float, group: str = "all") -> list[str]:
    """Static gravity (g_x, 0, g_z), m/s^2, as ``fix grav``: its magnitude and direction.

    ``group`` is the atoms it acts on (a LAMMPS deck of rigid bodies gives an empty group and
    lets ``fix rigid/small ... gravity grav`` apply it to each body's mass).
    """
    g0 = math.hypot(gx0, gz0)
    return [f"fix grav {group} gravity {fmt(g0)} vector {fmt(gx0 / g0)} 0.0 {fmt(gz0 / g0)}"]


def drive_block(
    d, gx0: float, gz0: float, drive_start: int, timestep: float, group: str = "all"
) -> list[str]:
    """The drive from step ``drive_start`` on: ``fix grav`` replaced by the effective gravity.

    ``tau`` counts the drive time, s, from ``drive_start`` in steps of ``timestep`` s; ``d`` is
    the case's drive (:class:`dem.scene.case.DriveSpec`) and (gx0, gz0) the static gravity;
    ``group`` as in :func:`gravity_block`.
    """
    return [
        "# --- drive: effective gravity in the accelerating frame",
        f"variable tau equal (step-{drive_start})*{fmt(timestep)}",
        *drive_variables(d, gx0, gz0),
        "variable gmag equal sqrt(v_gx*v_gx+v_gz*v_gz)",
        "unfix grav",
        f"fix grav {group} gravity v_gmag vector v_gx 0.0 v_gz",
    ]


def drive_variables(d, gx0: float, gz0: float) -> list[str]:
    """Equal-style variables gx, gz: gravity minus the trough's acceleration s''(tau).

    The paper's drive: drive = A w^2 sin(w tau), gx = gx0 + drive cos(phi), gz likewise (as
    before). A second component and a start-up ramp follow :class:`dem.physics.drive.Motion`
    term for term: each component k adds
    A_k w^2 [c_s sin(w tau + psi_k) + c_c cos(w tau + psi_k)] e_k with c_s = r - r''/w^2,
    c_c = -2 r'/w of the smootherstep r(u), u = min(tau / T, 1) (written with comparisons:
    LIGGGHTS's min() is a special function of computes) (r' = r'' = 0 once u = 1, so the same
    expressions hold after the ramp).
    """
    w = d.omega
    phi = math.radians(d.angle)
    if d.is_single and d.ramp_cycles == 0.0:
        peak = d.amplitude * w**2
        return [
            f"variable drive equal {fmt(peak)}*sin({fmt(w)}*v_tau)",
            f"variable gx equal {fmt(gx0)}+v_drive*{fmt(math.cos(phi))}",
            f"variable gz equal {fmt(gz0)}+v_drive*{fmt(math.sin(phi))}",
        ]
    lines = []
    if d.ramp_cycles > 0.0:
        ramp = d.ramp_cycles / d.frequency
        lines += [
            f"variable u equal (v_tau<{fmt(ramp)})*v_tau/{fmt(ramp)}+(v_tau>={fmt(ramp)})",
            "variable r0 equal v_u*v_u*v_u*(10.0-15.0*v_u+6.0*v_u*v_u)",
            f"variable r1 equal 30.0*v_u*v_u*(1.0-v_u)*(1.0-v_u)/{fmt(ramp)}",
            f"variable r2 equal 60.0*v_u*(1.0-v_u)*(1.0-2.0*v_u)/{fmt(ramp * ramp)}",
            f"variable cs equal v_r0-v_r2/{fmt(w * w)}",
            f"variable cc equal -2.0*v_r1/{fmt(w)}",
        ]
        cs, cc = "v_cs", "v_cc"
    else:
        cs, cc = "1.0", "0.0"
    comps = [(d.amplitude, phi, 0.0)]
    if not d.is_single:
        comps.append(
            (d.second_amplitude, math.radians(d.second_angle), math.radians(d.second_phase))
        )
    names = []
    for k, (a, ang, psi) in enumerate(comps, start=1):
        arg = f"{fmt(w)}*v_tau+{fmt(psi)}"
        lines.append(f"variable drive{k} equal {fmt(a * w**2)}*({cs}*sin({arg})+{cc}*cos({arg}))")
        names.append((f"v_drive{k}", ang))
    gx = "+".join(f"{n}*{fmt(math.cos(ang))}" for n, ang in names)
    gz = "+".join(f"{n}*{fmt(math.sin(ang))}" for n, ang in names)
    return lines + [
        f"variable gx equal {fmt(gx0)}+{gx}",
        f"variable gz equal {fmt(gz0)}+{gz}",
    ]


#: The drive's start in a deck: ``variable tau equal (step-N)*dt`` (:func:`drive_block`).
TAU_RE = re.compile(r"variable tau equal \(step-(\d+)\)")


def drive_start_step(deck_text: str) -> int | None:
    """The step at which a deck's drive starts (its ``tau`` variable), or None if it has none."""
    found = TAU_RE.search(deck_text)
    return None if found is None else int(found.group(1))
