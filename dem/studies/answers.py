"""The answers of ``dem run`` and ``dem calibrate`` in words, as the command prints them.

:func:`run_summary_lines` turns a run's summary.json into lines, each value with its unit and
the digits its error allows (:func:`dem.physics.measure.with_error`): the velocity, its error
bar, the point mass beside it, the mass flow, a feeder's discharge, whether the material is
stiff enough for the rigid answer, and the cost. :func:`calibration_lines` is the table of a
calibration's impacts with eps_t before and after the fit (:mod:`dem.studies.calibrate`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dem.physics.laws import TANGENTIAL_LAWS
from dem.physics.measure import distinct, with_error
from dem.run.stiffness import why_expected
from dem.studies.report import feeder_lines

if TYPE_CHECKING:
    from dem.studies.calibrate import Calibration


def run_summary_lines(s: dict) -> list[str]:
    """The answer of a run (its summary.json ``s``), one line each, labels in a column."""
    lines = []

    def line(label: str, text: str) -> None:
        lines.append(f"{label:<18s} {text}")

    line("mean velocity", with_error(s["mean_velocity"], s["mean_velocity_stderr"], "m/s"))
    line("normalised", with_error(s["mean_velocity_norm"], s["mean_velocity_norm_stderr"])
         + "  (v / A omega cos phi)")  # fmt: skip
    if s.get("replicas", 1) > 1:
        line("error bar", f"{s['replicas']} fills pooled, fill-to-fill spread included (95 %: "
             f"+- {s['mean_velocity_ci95']:.2g} m/s; spread between fills "
             f"{s['replica_spread']:.2g} m/s)")  # fmt: skip
    else:
        line("error bar", "this run only: it excludes the fill-to-fill spread and covered a "
             "bed's long-run mean in 23-53 % of runs (pool fills with --replicas 3: "
             "92-96 %)")  # fmt: skip
    target = s.get("target")
    if target:
        line("target error", target["what"])
    bed = s.get("bed")
    if bed:
        given = {"count": "", "layers": " (given as layers)", "bed_height": " (given as height)",
                 "mass_per_area": " (given as mass per area)"}[bed["given"]]  # fmt: skip
        line("bed", f"{bed['count']} grains{given}: {bed['layers']:.2g} layers of "
             f"{1e3 * bed['layer_thickness_m']:.3g} mm, {1e3 * bed['bed_height_m']:.3g} mm deep "
             f"at solid fraction {bed['packing_assumed']:g}, {bed['mass_per_area_kg_m2']:.3g} "
             "kg/m^2")  # fmt: skip
    steady = s.get("steadiness")
    if steady and "trend_z" in steady:  # one run (a pooled summary says it per replica)
        grew = f"{steady['change_norm']:+.2g} in v_norm over {s['cycles']} measured cycles"
        if steady["steady"]:
            line("steadiness", f"steady: trend {grew}, {steady['trend_z']:+.1f} standard errors"
                 + (f"; {steady['extended_cycles']} cycles added to reach it"
                    if steady["extended_cycles"] else ""))  # fmt: skip
        else:
            line("steadiness", f"NOT STEADY: trend {grew}, {steady['trend_z']:+.1f} standard "
                 f"errors: {steady['what']}")  # fmt: skip
    elif steady:
        line("steadiness", steady["what"])
    paper, bounded = s.get("pointmass_velocity_norm"), s.get("pointmass_bounded_velocity_norm")
    if paper is not None:
        text = f"{paper:.3f} (paper's model)"
        # spheres free to roll: the rolling sphere, or none (their reference is None)
        rolls = s.get("reference", "") in ("pointmass_rolling", None)
        if bounded is not None and abs(bounded - paper) > 5e-4:
            role = ")" if rolls else ", the DEM's reference)"
            text += f", {bounded:.3f} (Coulomb-bounded{role}"
        line("point mass", text + " in v_norm")
    if s.get("pointmass_rolling_velocity_norm") is not None:
        line("rolling sphere", f"{s['pointmass_rolling_velocity_norm']:.3f} in v_norm (the "
             "reference of grains that roll: reference_reason in summary.json)")  # fmt: skip
    elif "reference_reason" in s and s["reference"] is None:
        line("rolling sphere", "no reference: " + s["reference_reason"])
    flow = with_error(s["mass_flow_rate"], s.get("mass_flow_rate_stderr")
                      or abs(s["mass_flow_rate"] * s["mean_velocity_stderr"]
                             / (s["mean_velocity"] or float("nan"))), "kg/s")  # fmt: skip
    line("mass flow", f"{flow} through the section ({s['mass_flow_rate_per_width']:.3g} kg/s "
         "per m of width)")  # fmt: skip
    lines += feeder_lines(s.get("feeder"))  # the discharge: a feeder's answer
    stiff = s.get("stiffness")
    if stiff and stiff.get("single_grain"):
        ratio = f"(omega / omega_c)^2 = {stiff['compliance']:.2g}"
        within = (f"expected within {stiff['expected_error']:.2g} in v_norm of the rigid "
                  f"reference {stiff['reference_velocity_norm']:.3g} "
                  f"({why_expected(stiff)})")  # fmt: skip
        if stiff["converged"]:
            line("stiffness", f"stiff enough for the rigid grain's answer, {ratio}: {within}")
        else:
            line("stiffness", f"TOO SOFT for the rigid grain's answer: {ratio}, {within}, more "
                 f"than the {stiff['allowed_error']:.2g} allowed; set {stiff['key']} >= "
                 f"{stiff['value']:.3g}")  # fmt: skip
    elif stiff:
        sign = "<=" if stiff["converged"] else ">"
        shown, bound = distinct(stiff["compliance"], stiff["compliance_limit"])
        ratio = f"(omega / omega_bed)^2 = {shown} {sign} {bound}"
        near = "; ".join(
            f"{m['bed']} at E = {m['youngs_modulus_pa']:.0e} Pa (c = {m['compliance']:.2g}): "
            f"{100 * m['error_vs_rigid']:+.1f} +- {100 * m['error_stderr']:.1f} %"
            for m in stiff.get("measured") or []
        )
        near = f" (the bulk study against the rigid limit, near this c: {near})" if near else ""
        if stiff["converged"]:
            line("stiffness", f"stiff enough for the rigid material's bulk velocity, {ratio}"
                 + near)  # fmt: skip
        else:
            line("stiffness", f"TOO SOFT for the rigid material's answer: {ratio}, beyond "
                 f"which the bulk study measured more than 2 % off{near}; set "
                 f"{stiff['key']} >= {stiff['value']:.3g}")  # fmt: skip
    rate = s.get("particle_steps_per_s")
    line("cost", f"dt {s['timestep']:.3g} s, {s['steps']} steps, {s['wall_time_s']:.0f} s"
         + (f", {rate:.3g} particle-steps/s" if rate else ""))  # fmt: skip
    return lines


def calibration_lines(case, cal: Calibration) -> list[str]:
    """The impacts of a calibration of ``case``, eps_t per impact, and the fit, one line each."""
    theta = cal.impacts[:, 0]
    lines = [
        f"impacts          {len(theta)}, incidence {theta.min():.1f}-{theta.max():.1f} deg",
        "  incidence  speed   target  eps_t   residual",
    ]
    for (inc, speed), target, eps, bound in zip(
        cal.impacts, cal.targets, cal.after, cal.bounded, strict=True
    ):
        mark = "  friction-bound (Coulomb caps eps_t here)" if bound else ""
        lines.append(
            f"  {inc:6.1f} deg {speed:5.3f}   {target:.4f}  {eps:.4f}  {eps - target:+.4f}{mark}"
        )
    if not cal.fitted:
        lines.append(
            f"nothing to fit     {TANGENTIAL_LAWS[case.contact.tangential].calibration}; "
            f"weighted rms residual {cal.deviation:.4f}"
        )
    else:
        spread = f"{cal.eps_t:.4f} +- {cal.eps_t_spread:.4f}"
        lines += [
            f"before           mean eps_t = {cal.before.mean():.4f}, weighted rms deviation "
            f"{cal.deviation_before:.4f}",
            f"after            k_t / k_n = {cal.kappa:.6g}, zeta_t = {cal.zeta_t:g}",
            f"                 eps_t = {spread}, eps_n = {cal.eps_n:.4f}",
            f"                 weighted rms deviation {cal.deviation:.4f} (the fit minimises it)",
        ]
    lines.append(f"residual         {cal.residual:+.4f} (mean eps_t - mean reachable target)")
    return lines
