"""Claims (c) and (d) decided from the optima, and the README's tables (claims.md)."""

import numpy as np


def trend(values):
    """'falls', 'rises' or 'not monotonic' for a sequence."""
    d = np.diff(values)
    if np.all(d < 0):
        return "falls"
    if np.all(d > 0):
        return "rises"
    return "not monotonic"


def verdicts(f7: dict, f8: dict) -> dict:
    """Claims (c) and (d) per reading (hold and objective), decided from the numbers."""
    out = {"c": {}, "d": {}}
    for hold in ("throw_number", "v_over_A_omega", "amplitude", "acceleration"):
        rows = [r for r in f7["optima"] if r["reading"] == hold]
        angles = [r["optimum_angle"] for r in rows]
        widths = [r["plateau_width"] for r in rows]
        out["c"][hold] = {
            "optimum_angle_with_rising_mu": trend(angles),
            "plateau_width_with_rising_mu": trend(widths),
            "falls": trend(angles) == "falls",
            "sharpens": trend(widths) == "falls",
        }
        rows = [r for r in f8["optima"] if r["reading"] == hold]
        angles = [r["optimum_angle"] for r in rows]
        lo = max(r["plateau_90"][0] for r in rows)
        hi = min(r["plateau_90"][1] for r in rows)
        out["d"][hold] = {
            "optimum_angles": angles,
            "undefined_optimum_at": [
                r["nominal_throw_number"] for r in rows if r["plateau_covers_scan"]
            ],
            "optimum_at_scan_bound_at": [
                r["nominal_throw_number"] for r in rows if r["at_scan_bound"]
            ],
            "common_90_plateau": [lo, hi] if lo <= hi else None,
            "range_deg": float(max(angles) - min(angles)),
            "holds_within_5_deg": bool(max(angles) - min(angles) <= 5.0),
        }
    return out


def markdown(claims: dict) -> str:
    """The README's tables, generated from the numbers."""
    lines = ["## Claim (c): optimum angle against mu (Gamma = 1.8 family)", ""]
    lines.append(
        "| reading | held value | mu | optimum phi (deg) | 90% plateau (deg) | width (deg) "
        "| 95% width | v(89 deg) / v(opt) | Gamma at optimum | v_norm | v / (A omega) "
        "| v (m/s, 60 Hz) |"
    )
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in claims["fig7"]["optima"]:
        lines.append(_row(r))
    lines += ["", "## Claim (d): optimum angle against Gamma (mu = 0.35)", ""]
    lines.append(
        "| reading | held value | nominal Gamma | optimum phi (deg) | 90% plateau (deg) "
        "| width (deg) | 95% width | v(89 deg) / v(opt) | Gamma at optimum | v_norm "
        "| v / (A omega) | v (m/s, 60 Hz) |"
    )
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in claims["fig8"]["optima"]:
        lines.append(_row(r, nominal=True))
    lines += ["", "## Verdicts", "", "| claim | reading | result |", "|---|---|---|"]
    for hold, v in claims["verdicts"]["c"].items():
        lines.append(
            f"| (c) | {hold} | optimum angle {v['optimum_angle_with_rising_mu']} with mu "
            f"({'reproduced' if v['falls'] else 'NOT reproduced'}); 90% plateau width "
            f"{v['plateau_width_with_rising_mu']} ("
            f"{'sharpens: reproduced' if v['sharpens'] else 'does not sharpen: NOT reproduced'})"
            " |"
        )
    for hold, v in claims["verdicts"]["d"].items():
        angles = ", ".join(f"{a:.1f}" for a in v["optimum_angles"])
        flat, edge, common = (
            v[k] for k in ("undefined_optimum_at", "optimum_at_scan_bound_at", "common_90_plateau")
        )
        note = (
            f"; at Gamma = {', '.join(f'{x:g}' for x in flat)} the curve is within 90% of its "
            "maximum over all of 1-89 deg (no defined optimum)"
            if flat
            else ""
        )
        edge = [x for x in edge if x not in flat]
        if edge:
            note += f"; at Gamma = {', '.join(f'{x:g}' for x in edge)}: optimum at the scan bound"
        note += (
            f"; 90% plateaus overlap on {common[0]:.1f}-{common[1]:.1f} deg"
            if common
            else "; the 90% plateaus have no common angle"
        )
        lines.append(
            f"| (d) | {hold} | optima {angles} deg, range {v['range_deg']:.1f} deg -> "
            f"{'holds (<= 5 deg)' if v['holds_within_5_deg'] else 'NOT reproduced (> 5 deg)'}"
            f"{note} |"
        )
    return "\n".join(lines) + "\n"


def _row(r, nominal=False):
    held = {
        "throw_number": f"Gamma = {r['held_value']:g}",
        "v_over_A_omega": f"Gamma = {r['held_value']:g}",
        "amplitude": f"A = {r['held_value'] * 1e3:.3f} mm",
        "acceleration": f"K = {r['held_value']:.3f} g",
    }[r["reading"]]
    lo, hi = r["plateau_90"]
    middle = f"{r['nominal_throw_number']:g}" if nominal else f"{r['friction']:g}"
    return (
        f"| {r['reading']} | {held} | {middle} | {r['optimum_angle']:.1f} | {lo:.1f}-{hi:.1f} "
        f"| {r['plateau_width']:.1f} | {r['plateau_95_width']:.1f} | {r['tail_ratio_89deg']:.3f} "
        f"| {r['throw_number_at_optimum']:.3f} "
        f"| {r['velocity_norm_at_optimum']:.4f} | {r['v_over_A_omega_at_optimum']:.4f} "
        f"| {r['velocity_m_per_s_at_optimum']:.4f} |"
    )
