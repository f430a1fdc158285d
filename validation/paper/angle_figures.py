"""Figs. 7 and 8: velocity against the vibration angle for three mu (Gamma = 1.8) and for three
Gamma (mu = 0.35), with the optimum under each hold (claims (c) and (d)).
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from csv_output import write_csv  # noqa: E402
from optima import (  # noqa: E402
    FREQUENCY,
    REFERENCE_ANGLE,
    amplitude_at_acceleration,
    amplitude_for,
    held_drive,
    m_per_s,
    optimum_row,
    peak_acceleration,
    sweep_along,
    v_over_a_omega_row,
)

from dem.pointmass.sweep import sweep  # noqa: E402

FIG7 = {"throw_number": 1.8, "friction": (0.25, 0.35, 0.60), "amplitude": 0.5e-3}
FIG8 = {"friction": 0.35, "throw_number": (1.8, 3.0, 4.5)}

# panels and optima rows, in this order, and what each panel plots at the optimum
READINGS = {
    "norm": "velocity_norm_at_optimum",
    "drive": "v_over_A_omega_at_optimum",
    "amp": "velocity_m_per_s_at_optimum",
    "acc": "velocity_m_per_s_at_optimum",
}


def angle_figure(path, angle, families, fixed_label, title):
    """Four panels: Gamma held (v_norm; v / (A omega)), m/s holding A, m/s holding A omega^2."""
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.6), dpi=120)
    axes = axes.ravel()
    for k, fam in enumerate(families):
        for ax, key, opt in zip(axes, READINGS, fam["optima"], strict=True):
            ax.plot(angle, fam[key], color=f"C{k}", lw=1.3, label=fam[f"label_{key}"])
            ax.axvspan(*opt["plateau_90"], color=f"C{k}", alpha=0.08)
            ax.plot([opt["optimum_angle"]], [fam[f"best_{key}"]], "o", color=f"C{k}", ms=5)
        if "bounded_norm" in fam:  # the Gamma-held panel: the Coulomb-bounded landings
            breaks = np.abs(fam["bounded_norm"] - fam["norm"]) > 1e-3
            if breaks.any():
                axes[0].plot(angle, np.where(breaks, fam["bounded_norm"], np.nan), "--",
                             color=f"C{k}", lw=1.0)  # fmt: skip
                axes[0].fill_between(angle, fam["norm"], fam["bounded_norm"], where=breaks,
                                     color=f"C{k}", alpha=0.15, lw=0)  # fmt: skip
    axes[0].plot([], [], "k--", lw=1.0, label="landings bounded by Coulomb")
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].set_title("Gamma held, v_norm = v / (A omega cos phi)", fontsize=9)
    axes[1].set_ylabel("v / (A omega)")
    axes[1].set_title("Gamma held, v / (A omega) = v_norm cos phi", fontsize=9)
    axes[2].set_title(f"amplitude A held, f = {FREQUENCY:g} Hz", fontsize=9)
    axes[3].set_title(f"peak acceleration A omega^2 = K g held, f = {FREQUENCY:g} Hz", fontsize=9)
    for ax in axes[2:]:
        ax.set_ylabel("v (m/s)")
    for ax in axes:
        ax.set_xlabel("vibration angle phi (deg)")
        ax.axhline(0.0, color="0.7", lw=0.6)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"{title}  (dots: optimum; shading: 90% plateau; {fixed_label})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def fig7(g: dict, out: Path, meta: dict) -> dict:
    """Velocity against phi at Gamma = 1.8 for three mu; optima under each hold (claim c)."""
    angle = g["angle"]
    gamma0 = FIG7["throw_number"]
    amp_fixed = FIG7["amplitude"]
    k_fixed = peak_acceleration(amplitude_for(gamma0))  # Gamma0 at 25 deg
    columns = {"angle": [], "friction": [], "velocity_norm": [], "v_over_A_omega": []}
    columns.update(regime=[], periodic=[])
    extra = {
        "throw_number_amp": [],
        "velocity_norm_amp": [],
        "velocity_amp": [],
        "period_amp": [],
        "period_acc": [],
        "throw_number_acc": [],
        "velocity_norm_acc": [],
        "velocity_acc": [],
    }
    families, rows = [], []
    for mu in FIG7["friction"]:
        fam = {}
        r = sweep(gamma0, angle, mu)
        fam["norm"] = r["velocity_norm"]
        fam["bounded_norm"] = sweep(gamma0, angle, mu, impact="coulomb")["velocity_norm"]
        fam["drive"] = r["velocity_norm"] * np.cos(np.radians(angle))
        for name, (hold, value) in {
            "amp": ("amplitude", amp_fixed),
            "acc": ("acceleration", k_fixed),
        }.items():
            gam, amp = held_drive(angle, hold, value)
            rr = sweep_along(gam, angle, mu)
            fam[name] = m_per_s(rr["velocity_norm"], angle, amp)
            extra[f"throw_number_{name}"].append(gam)
            extra[f"velocity_norm_{name}"].append(rr["velocity_norm"])
            extra[f"period_{name}"].append(rr["period"])  # 0: non-periodic
            extra[f"velocity_{name}"].append(fam[name])
        columns["angle"].append(angle)
        columns["friction"].append(np.full_like(angle, mu))
        columns["velocity_norm"].append(r["velocity_norm"])
        columns["v_over_A_omega"].append(fam["drive"])
        columns["regime"].append(r["regime"])
        columns["periodic"].append(r["periodic"])
        opts = [
            optimum_row(mu, "throw_number", gamma0, g["optimum_points"]),
            v_over_a_omega_row(mu, gamma0, g["optimum_points"]),
            optimum_row(mu, "amplitude", amp_fixed, g["optimum_points"]),
            optimum_row(mu, "acceleration", k_fixed, g["optimum_points"]),
        ]
        rows += opts
        fam["optima"] = opts
        for key, opt in zip(READINGS, opts, strict=True):
            fam[f"best_{key}"] = opt[READINGS[key]]
            fam[f"label_{key}"] = f"mu = {mu}: optimum {opt['optimum_angle']:.1f} deg"
        families.append(fam)
    table = {k: np.concatenate(v) for k, v in {**columns, **extra}.items()}
    write_csv(
        out / "fig7_friction.csv",
        table,
        meta,
        {
            "throw_number (velocity_norm, v_over_A_omega)": gamma0,
            "amplitude_m (_amp columns)": amp_fixed,
            "peak_acceleration_g (_acc columns)": k_fixed,
            "frequency_hz": FREQUENCY,
            "inclination": 0.0,
            "eps_t": 0.8,
            "eps_n": 0.0,
        },
    )
    angle_figure(
        out / "fig7_friction.png",
        angle,
        families,
        f"A = {amp_fixed * 1e3:g} mm; K = {k_fixed:.3f} (Gamma = {gamma0} at {REFERENCE_ANGLE:g}"
        f" deg)",
        f"Fig. 7: Gamma = {gamma0} (top row), eps_t = 0.8, eps_n = 0",
    )
    return {
        "amplitude_m": amp_fixed,
        "peak_acceleration_g": k_fixed,
        "amplitude_equivalent_to_K_m": amplitude_at_acceleration(k_fixed),
        "optima": rows,
    }


def fig8(g: dict, out: Path, meta: dict) -> dict:
    """Velocity against phi at mu = 0.35 for three Gamma; optima under each hold (claim d)."""
    angle = g["angle"]
    mu = FIG8["friction"]
    columns = {
        "angle": [],
        "throw_number_nominal": [],
        "velocity_norm": [],
        "v_over_A_omega": [],
        "regime": [],
        "periodic": [],
        "period": [],
        "throw_number_amp": [],
        "velocity_amp": [],
        "period_amp": [],
    }
    families, rows = [], []
    orbits = []
    for gamma0 in FIG8["throw_number"]:
        fam = {}
        r = sweep(gamma0, angle, mu)
        fam["norm"] = r["velocity_norm"]
        fam["drive"] = r["velocity_norm"] * np.cos(np.radians(angle))
        amp = amplitude_for(gamma0)
        k = peak_acceleration(amp)
        gam, amps = held_drive(angle, "amplitude", amp)
        rr = sweep_along(gam, angle, mu)
        fam["amp"] = m_per_s(rr["velocity_norm"], angle, amps)
        orbits.append(
            {
                "amplitude_m": amp,
                "peak_acceleration_g": k,
                "longest_period": int(rr["period"].max()),
                "non_periodic_points": int((~rr["periodic"]).sum()),
                "points": int(angle.size),
            }
        )
        gam_k, amps_k = held_drive(angle, "acceleration", k)
        fam["acc"] = m_per_s(sweep_along(gam_k, angle, mu)["velocity_norm"], angle, amps_k)
        for key, values in (
            ("angle", angle),
            ("throw_number_nominal", np.full_like(angle, gamma0)),
            ("velocity_norm", r["velocity_norm"]),
            ("v_over_A_omega", fam["drive"]),
            ("regime", r["regime"]),
            ("periodic", r["periodic"]),
            ("period", r["period"]),
            ("throw_number_amp", gam),
            ("velocity_amp", fam["amp"]),
            ("period_amp", rr["period"]),
        ):
            columns[key].append(values)
        opts = [
            optimum_row(mu, "throw_number", gamma0, g["optimum_points"]),
            v_over_a_omega_row(mu, gamma0, g["optimum_points"]),
            optimum_row(mu, "amplitude", amp, g["optimum_points"]),
            optimum_row(mu, "acceleration", k, g["optimum_points"]),
        ]
        for o in opts:
            o["nominal_throw_number"] = gamma0
        rows += opts
        fam["optima"] = opts
        for key, opt in zip(READINGS, opts, strict=True):
            fam[f"best_{key}"] = opt[READINGS[key]]
            held = {
                "norm": f"Gamma = {gamma0}",
                "drive": f"Gamma = {gamma0}",
                "amp": f"A = {amp * 1e3:.3f} mm",
                "acc": f"K = {k:.2f}",
            }[key]
            fam[f"label_{key}"] = f"{held}: optimum {opt['optimum_angle']:.1f} deg"
        families.append(fam)
    table = {k: np.concatenate(v) for k, v in columns.items()}
    write_csv(
        out / "fig8_throw_number.csv",
        table,
        meta,
        {
            "friction": mu,
            "amplitude (_amp columns)": f"Gamma_nominal g / (omega^2 sin {REFERENCE_ANGLE:g} deg)",
            "frequency_hz": FREQUENCY,
            "inclination": 0.0,
            "eps_t": 0.8,
            "eps_n": 0.0,
        },
    )
    angle_figure(
        out / "fig8_throw_number.png",
        angle,
        families,
        f"A, K give the nominal Gamma at phi = {REFERENCE_ANGLE:g} deg",
        f"Fig. 8: mu = {mu}, eps_t = 0.8, eps_n = 0",
    )
    return {"optima": rows, "held_amplitude_orbits": orbits}
