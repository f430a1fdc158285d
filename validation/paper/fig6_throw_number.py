"""Fig. 6: v / (A omega cos phi) against Gamma at phi = 25 deg, mu = 0.35 for three eps_t, and
claims (a) (eps_t does not matter below Gamma = 1) and (b) (the fall near Gamma = 4.5), with
the normal motion's landing phases computed independently and the tests' brute-force twin.
"""

import importlib.util
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from csv_output import write_csv  # noqa: E402

from dem.pointmass import velocities  # noqa: E402
from dem.pointmass.sweep import sweep  # noqa: E402

TESTS = Path(__file__).resolve().parents[2] / "tests" / "oracles"

FIG6 = {"angle": 25.0, "friction": 0.35, "eps_t": (0.2, 0.5, 0.8), "eps_n": 0.0}

GAMMA_ONE_CYCLE = math.sqrt(1.0 + math.pi**2)  # flights last one cycle from here ...
GAMMA_DOUBLING = math.sqrt(4.0 + math.pi**2)  # ... up to the period doubling


def brute(params, **kwargs):
    """The tests' time-stepping twin (tests/oracles/naive_pointmass.py, loaded by path)."""
    name = "naive_pointmass"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, TESTS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name].brute(params, **kwargs)


def normal_landings(gamma: float, cycles: int = 300, keep: int = 8) -> list[float]:
    """Landing phases (deg, mod 360) of the steady normal motion with eps_n = 0.

    Independent of dem.pointmass: the gap after take-off at phase t0 with zero relative
    velocity is z(t) = cos(t0)(t - t0) - (sin t - sin t0) - (t - t0)^2 / (2 Gamma); landing
    is its first root, found on a fine grid and refined by bisection. With eps_n = 0 the
    grain takes off again at once if 1/Gamma - sin(t) < 0 at landing, else at the next phase
    with sin(t) = 1/Gamma on the rising side.
    """
    if gamma <= 1.0:
        return []
    rise = math.asin(1.0 / gamma)
    t0 = rise
    landings = []

    def gap(t):
        d = t - t0
        return math.cos(t0) * d - (math.sin(t) - math.sin(t0)) - d * d / (2.0 * gamma)

    for _ in range(cycles):
        step = 5e-3
        t = t0 + step
        while gap(t) > 0.0:
            t += step
        lo, hi = t - step, t
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if gap(mid) > 0.0 else (lo, mid)
        land = hi
        landings.append(math.degrees(land % (2 * math.pi)))
        if 1.0 / gamma - math.sin(land) < 0.0:
            t0 = land
        else:
            k = math.ceil((land - rise) / (2 * math.pi))
            t0 = rise + 2 * math.pi * k
    return landings[-keep:]


def fig6(g: dict, out: Path, meta: dict) -> dict:
    """Normalised velocity against Gamma, phi = 25 deg, mu = 0.35, three eps_t."""
    p = FIG6
    gamma = g["fig6_gamma"]
    r = sweep(gamma, p["angle"], p["friction"], 0.0, p["eps_t"], p["eps_n"])
    shape = (gamma.size, len(p["eps_t"]))
    v = r["velocity_norm"].reshape(shape)
    periodic = r["periodic"].reshape(shape)
    spread = r["spread"].reshape(shape)
    period = r["period"].reshape(shape)
    back = r["slide_backward"].reshape(shape)
    flight = r["flight"].reshape(shape)
    write_csv(
        out / "fig6_throw_number.csv",
        {
            k: r[k]
            for k in (
                "throw_number",
                "eps_t",
                "velocity_norm",
                "periodic",
                "period",
                "spread",
                "velocity_min",
                "velocity_max",
                "regime",
                "stick",
                "slide_forward",
                "slide_backward",
                "flight",
            )
        },
        meta,
        {"angle": p["angle"], "friction": p["friction"], "inclination": 0.0, "eps_n": p["eps_n"]},
    )

    # claim (a): eps_t irrelevant below Gamma = 1
    below = gamma < 1.0
    diff = v.max(axis=1) - v.min(axis=1)
    claim_a = {
        "max_abs_difference_below_1": float(diff[below].max()) if below.any() else None,
        "max_abs_difference_above_1": float(diff[~below].max()),
        "at_throw_number": float(gamma[~below][np.argmax(diff[~below])]),
        "first_throw_number_with_difference_over_1e-12": (
            float(gamma[np.argmax(diff > 1e-12)]) if (diff > 1e-12).any() else None
        ),
    }

    # the jump at the flight onset: a vanishing flight still ends in a full landing
    onset = np.array([0.99, 1.001, 1.01])
    rows = np.array(
        [[x, p["angle"], p["friction"], 0.0, et, 0.0] for x in onset for et in p["eps_t"]]
    )
    model = velocities(*rows.T)
    twin = brute(rows, steps=16000, transient=(1.5 * model["cycles"]).astype(int) + 300)
    claim_a["flight_onset"] = {
        "throw_number": rows[:, 0].tolist(),
        "eps_t": rows[:, 4].tolist(),
        "event_driven": model["velocity_norm"].tolist(),
        "flight_fraction": model["flight"].tolist(),
        "brute_force_16000_steps": twin.tolist(),
    }

    # claim (b): the fall near Gamma = 4.5
    claim_b = {"per_eps_t": []}
    window = (gamma > GAMMA_DOUBLING) & (gamma < 6.0)
    for k, et in enumerate(p["eps_t"]):
        idx = np.flatnonzero(window)
        i_min = idx[np.argmin(v[idx, k])]
        slope = np.gradient(v[:, k], gamma)
        steep = np.flatnonzero(window & (slope < -1.0) & (gamma < gamma[i_min]))
        i_start = int(steep[0]) if steep.size else int(i_min)
        # recovery: first Gamma past the minimum where v is back at the value at the start
        after = np.flatnonzero((gamma > gamma[i_min]) & (v[:, k] >= v[i_start, k]))
        # the bottom is a cusp: resolve it on a 1e-4 grid around the grid minimum
        fine = np.linspace(gamma[i_min] - 0.01, gamma[i_min] + 0.01, 201)
        rf = velocities(fine, p["angle"], p["friction"], 0.0, et, p["eps_n"])
        vf = rf["velocity_norm"]
        j_min = int(np.argmin(vf))
        jumps = np.abs(np.diff(vf))
        claim_b["per_eps_t"].append(
            {
                "eps_t": et,
                "refined_minimum_at": float(fine[j_min]),
                "refined_velocity_at_minimum": float(vf[j_min]),
                "largest_step_on_1e-4_grid": float(jumps.max()),
                "largest_step_at": float(fine[int(np.argmax(jumps))]),
                "steep_fall_starts_at": float(gamma[i_start]),
                "velocity_at_start": float(v[i_start, k]),
                "minimum_at": float(gamma[i_min]),
                "velocity_at_minimum": float(v[i_min, k]),
                "depth": float(v[i_start, k] - v[i_min, k]),
                "recovered_by": float(gamma[after[0]]) if after.size else None,
                "period_at_minimum": int(period[i_min, k]),
                "backward_sliding_fraction_at_minimum": float(back[i_min, k]),
                "flight_fraction_at_minimum": float(flight[i_min, k]),
                "velocity_at_4.5": float(np.interp(4.5, gamma, v[:, k])),
                "velocity_at_4.0": float(np.interp(4.0, gamma, v[:, k])),
                "velocity_at_3.0": float(np.interp(3.0, gamma, v[:, k])),
                "non_periodic_points": int((~periodic[:, k]).sum()),
            }
        )
    first_back_above_doubling = np.flatnonzero((gamma > GAMMA_DOUBLING) & (back[:, -1] > 1e-9))
    claim_b["backward_sliding_returns_at"] = (
        float(gamma[first_back_above_doubling[0]]) if first_back_above_doubling.size else None
    )
    first_p2 = np.flatnonzero(period[:, -1] == 2)
    claim_b["first_period_2_on_grid"] = float(gamma[first_p2[0]]) if first_p2.size else None
    claim_b["period_doubling_oracle"] = GAMMA_DOUBLING

    # where the period-2 orbit's second, short flight vanishes (two landings become one)
    def n_landings(x):
        return len(set(np.round(normal_landings(x, cycles=400, keep=6), 3)))

    lo, hi = 4.5, 4.7
    if n_landings(lo) == 2 and n_landings(hi) == 1:
        for _ in range(g["merge_bisections"]):  # 12: to 5e-5
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if n_landings(mid) == 2 else (lo, mid)
        claim_b["two_flights_merge_at"] = 0.5 * (lo + hi)
    else:
        claim_b["two_flights_merge_at"] = None
    # the jump at the bottom, checked with the tests' brute-force twin on both sides of it
    if claim_b["two_flights_merge_at"] is not None:
        x = claim_b["two_flights_merge_at"]
        rows = np.array([[x + d, p["angle"], p["friction"], 0.0, 0.8, 0.0] for d in (-4e-4, 4e-4)])
        model = velocities(*rows.T)
        twin = brute(rows, steps=16000, transient=(1.5 * model["cycles"]).astype(int) + 300)
        claim_b["jump_check_eps_t_0.8"] = {
            "throw_number": rows[:, 0].tolist(),
            "event_driven": model["velocity_norm"].tolist(),
            "brute_force_16000_steps": twin.tolist(),
        }
    claim_b["landings_deg"] = {
        f"{x:g}": [round(t, 1) for t in sorted(set(np.round(normal_landings(x), 1)))]
        for x in (3.5, 4.0, 4.3, 4.5, 4.6, 4.61, 5.0, 6.0)
    }

    fig, (ax, bx) = plt.subplots(
        2, 1, figsize=(7.5, 6.5), dpi=130, sharex=True, gridspec_kw={"height_ratios": [3, 1.3]}
    )
    rb = sweep(gamma, p["angle"], p["friction"], 0.0, p["eps_t"], p["eps_n"], impact="coulomb")
    vb = rb["velocity_norm"].reshape(shape)
    for k, et in enumerate(p["eps_t"]):
        ax.plot(gamma, v[:, k], color=f"C{k}", lw=1.2, label=f"eps_t = {et}")
        breaks = np.abs(vb[:, k] - v[:, k]) > 1e-3
        if breaks.any():
            ax.plot(gamma, np.where(breaks, vb[:, k], np.nan), "--", color=f"C{k}", lw=1.0)
            ax.fill_between(gamma, v[:, k], vb[:, k], where=breaks, color=f"C{k}", alpha=0.15,
                            lw=0)  # fmt: skip
        bad = ~periodic[:, k]
        if bad.any():
            ax.errorbar(
                gamma[bad], v[bad, k], yerr=spread[bad, k], fmt="x", color=f"C{k}", ms=4, lw=0.8
            )
        bx.plot(gamma, back[:, k], color=f"C{k}", lw=1.0)
    n_bad = int((~periodic).sum())
    ax.plot([], [], "kx", label=f"non-periodic (bar: spread), {n_bad} points")
    ax.plot([], [], "k--", lw=1.0, label="landings bounded by Coulomb (--impact coulomb)")
    ax.fill_between([], [], [], color="0.5", alpha=0.15, label="Eq. 12 asks more than mu J_n")
    for x, label in ((1.0, "Gamma = 1"), (GAMMA_DOUBLING, "period 2, sqrt(4 + pi^2)")):
        ax.axvline(x, color="0.5", ls=":", lw=1)
        ax.text(
            x,
            0.98,
            label + " ",
            rotation=90,
            va="top",
            ha="right",
            fontsize=7,
            transform=ax.get_xaxis_transform(),
        )
    ax.axhline(0.0, color="0.7", lw=0.6)
    ax.set_ylabel("v / (A omega cos phi)")
    ax.set_title(
        f"Fig. 6: phi = {p['angle']:g} deg, mu = {p['friction']}, eps_n = {p['eps_n']:g}",
        fontsize=10,
    )
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    bx.set_ylabel("backward sliding\n(fraction of cycle)", fontsize=8)
    bx.set_xlabel("throw number Gamma")
    bx.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fig6_throw_number.png")
    plt.close(fig)
    return {"a": claim_a, "b": claim_b}
