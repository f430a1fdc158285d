"""Figures and README tables of the contact benchmarks, from what benchmarks.py measured.

Every figure is drawn from results.json alone (``benchmarks.py --report-only`` redraws them);
every axis carries its unit, every title says what is held fixed.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402

STYLE = {  # tangential law -> colour; normal law -> line style; limit_force -> marker fill
    "impact": "tab:blue", "coulomb": "tab:red", "liggghts": "tab:green",
    "coulomb[mindlin]": "tab:purple",
}  # fmt: skip
DASH = {"hertz_mindlin": "-", "linear": "--"}
DPI = 120


def _style(row: dict) -> dict:
    return {
        "color": STYLE[row["tangential"]] if row["tangential"] in STYLE else "k",
        "linestyle": DASH[row["normal"]],
        "marker": "o" if not row["limit_force"] else "x",
        "markersize": 3.5,
        "linewidth": 1.0,
    }


def _rows(data, test, kind=None):
    return [r for r in data["rows"] if r["test"] == test and (kind is None or r["kind"] == kind)]


def _by_law(rows):
    laws: dict = {}
    for r in rows:
        laws.setdefault(r["law"], []).append(r)
    return laws


def hertz_curve(y_star: float, r_eff: float, m_eff: float, speed: float, n: int = 4000):
    """F_n(t) of the elastic Hertz impact (RK4 of m* delta'' = -4/3 Y* sqrt(R*) delta^1.5)."""
    k = 4.0 / 3.0 * y_star * math.sqrt(r_eff)
    t_c = 2.9432 * (15.0 * m_eff * speed**2 / (16.0 * y_star * math.sqrt(r_eff))) ** 0.4 / speed
    h = 1.02 * t_c / n

    def acc(d):
        return -k * max(d, 0.0) ** 1.5 / m_eff

    d, v, ts, fs = 0.0, speed, [0.0], [0.0]
    for i in range(n):
        k1 = (v, acc(d))
        k2 = (v + 0.5 * h * k1[1], acc(d + 0.5 * h * k1[0]))
        k3 = (v + 0.5 * h * k2[1], acc(d + 0.5 * h * k2[0]))
        k4 = (v + h * k3[1], acc(d + h * k3[0]))
        d += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        v += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        ts.append((i + 1) * h)
        fs.append(k * max(d, 0.0) ** 1.5)
    return ts, fs


def fig_normal(data, out: Path) -> None:
    """Tests 1 and 3: F_n(t) of the Hertz and linear laws against the closed forms."""
    cases = [(r["test"], r["case"]) for r in data["rows"] if r["kind"] == "normal"]
    cases = list(dict.fromkeys(cases))
    if not cases:
        return
    cols = min(2, len(cases))
    rows_n = math.ceil(len(cases) / cols)
    fig, axes = plt.subplots(rows_n, cols, figsize=(5.6 * cols, 4.0 * rows_n), squeeze=False)
    for ax, (test, case) in zip(axes.flat, cases, strict=False):
        rows = [r for r in data["rows"] if r["test"] == test and r["case"] == case]
        for law in ("hertz/impact", "linear/impact"):
            r = next(x for x in rows if x["law"] == law)
            h = r["history"]
            ax.plot([t * 1e6 for t in h["t_s"]], [f / 1e3 for f in h["fn_n"]], "o",
                    markersize=2.5, color="tab:blue" if "hertz" in law else "tab:orange",
                    label=f"dem, {law.split('/')[0]} normal law")  # fmt: skip
        hz = rows[0]["hertz"]
        c = _contact_of(data, test, case)
        ts, fs = hertz_curve(c["y_star"], c["r_eff"], c["m_eff"], c["speed"])
        ax.plot([t * 1e6 for t in ts], [f / 1e3 for f in fs], "-", color="k", linewidth=1,
                label="Hertz (closed form)")  # fmt: skip
        lin = next(x for x in rows if x["law"] == "linear/impact")
        t_l = lin["duration_s"]["reference"]
        f_l = lin["peak_force_n"]["reference"]
        tt = [t_l * i / 200 for i in range(201)]
        ax.plot([t * 1e6 for t in tt], [f_l * math.sin(math.pi * t / t_l) / 1e3 for t in tt],
                ":", color="k", linewidth=1, label="linear spring (closed form)")  # fmt: skip
        ax.axhline(hz["peak_force_n"] / 1e3, color="0.7", linewidth=0.6)
        ax.set_xlabel("time since first touch (us)")
        ax.set_ylabel("normal force F_n (kN)")
        if test == 1:
            what = f"Test 1: two {case} spheres, r 10 mm, 10 m/s each"
        else:
            sphere, wall = case.split(" on ")
            what = f"Test 3: {sphere} sphere, r 0.1 m, onto a {wall} wall at 0.2 m/s"
        ax.set_title(what + "\n(e = 1; every tangential law and limit_force)", fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "normal.png", dpi=DPI)
    plt.close(fig)


def _contact_of(data, test, case):
    return next(r["contact"] for r in data["rows"] if r["test"] == test and r["case"] == case)


def fig_restitution(data, out: Path) -> None:
    """Test 2: the rebound's restitution against the set one, each normal law, limit_force."""
    rows = [r for r in _rows(data, 2, "restitution") if "m/s" not in r["case"]]
    if not rows:
        return
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    for law, group in _by_law(rows).items():
        xs = [r["set"] for r in group]
        ax.plot(xs, [r["restitution"]["value"] for r in group], label=f"dem {law}",
                **_style(group[0]))  # fmt: skip
    lims = [0.0, 1.0]
    ax.plot(lims, lims, color="k", linewidth=0.8, label="the set e (design without limit_force)")
    hz = [r for r in rows if r["law"] == "hertz/impact/limit"]
    ax.plot([r["set"] for r in hz], [r["normal_law_restitution"] for r in hz], color="0.5",
            linewidth=2, alpha=0.5, label="e_n of the clamped dashpot (dem's own)")  # fmt: skip
    ax.set_xlabel("set coefficient of restitution eps_n (-)")
    ax.set_ylabel("measured rebound v_n,out / v_n,in (-)")
    ax.set_title("Test 2: Al2O3 sphere onto Al alloy, 3.9 m/s, normal\n"
                 "at dem's automatic step (50 steps an impact)", fontsize=9)  # fmt: skip
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "restitution.png", dpi=DPI)
    plt.close(fig)


def _oblique_axes(ax, rows, xkey, ykey, scale=1.0):
    for _, group in _by_law(rows).items():
        group = sorted(group, key=lambda r: r[xkey])
        ax.plot([r[xkey] for r in group], [scale * r[ykey] for r in group],
                label=f"dem {group[0]['law']}", **_style(group[0]))  # fmt: skip


def fig_incidence(data, out: Path) -> None:
    """Test 4: rebound angle, spin and the contact point's restitution against the incidence."""
    rows = [r for r in _rows(data, 4, "oblique") if not r["limit_force"]]
    if not rows:
        return
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.4))
    _oblique_axes(axes[0], rows, "incidence_deg", "rebound_angle_deg")
    slide = sorted((r for r in rows if r["law"] == "hertz/liggghts"),
                   key=lambda r: r["incidence_deg"])  # fmt: skip
    sl = [r for r in slide if r["psi_in"] >= r["threshold_psi"]]
    axes[0].plot([r["incidence_deg"] for r in sl], [r["rebound_angle_slide_deg"] for r in sl],
                 color="k", linewidth=2, alpha=0.4, label="rigid Coulomb sliding")  # fmt: skip
    axes[0].set_ylabel("rebound angle of the centre from the normal (deg)")
    for r in rows:
        r["_spin"] = r["spin_change"]["value"]
        r["_et"] = (r["psi_out"] / r["psi_in"]) if r["psi_in"] else math.nan
    _oblique_axes(axes[1], rows, "incidence_deg", "_spin")
    axes[1].plot([r["incidence_deg"] for r in sl], [r["spin_change"]["reference"] for r in sl],
                 color="k", linewidth=2, alpha=0.4, label="rigid Coulomb sliding")  # fmt: skip
    axes[1].set_ylabel("spin after the impact w_y (rad/s)")
    _oblique_axes(axes[2], rows, "incidence_deg", "_et")
    axes[2].plot([r["incidence_deg"] for r in sl], [r["psi_slide"] / r["psi_in"] for r in sl],
                 color="k", linewidth=2, alpha=0.4, label="rigid Coulomb sliding")  # fmt: skip
    axes[2].set_ylabel("contact point's slip out / in, u2 / u1 (-)")
    for ax in axes:
        ax.set_xlabel("incidence from the normal (deg)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6.5, ncol=1)
    fig.suptitle(
        "Test 4: Al2O3 sphere (r 2.55 mm) onto Al alloy at 3.9 m/s, mu 0.092, e 0.98, "
        "no spin in; limit_force false (true: the same within 1e-3)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out / "incidence.png", dpi=DPI)
    plt.close(fig)


def fig_maw(data, out: Path) -> None:
    """Test 5 in Maw et al.'s normalisation: psi_2 and the spin against psi_1, per law."""
    rows = _rows(data, 5, "oblique")
    if not rows:
        return
    cv = data["curves"]
    psi = cv["psi_in"]
    panels = [("impact", ("impact",)), ("coulomb", ("coulomb", "coulomb[mindlin]")),
              ("liggghts", ("liggghts",))]  # fmt: skip
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5), sharex=True)
    for col, (title, tangentials) in enumerate(panels):
        sub = [r for r in rows if r["tangential"] in tangentials]
        for r in sub:
            r["_omega"] = r["spin_out_norm"]
        _oblique_axes(axes[0, col], sub, "psi_in", "psi_out")
        _oblique_axes(axes[1, col], sub, "psi_in", "_omega")
        for ax, conv in ((axes[0, col], False), (axes[1, col], True)):

            def spin(values):
                return [5.0 / 7.0 * (p - v) for p, v in zip(psi, values, strict=True)]

            curves = [("sliding", "rigid Coulomb sliding", "k", 2.5),
                      ("mindlin_total", "Mindlin no-slip, total form (LIGGGHTS)", "tab:olive", 1.5),
                      ("mindlin_incremental", "Mindlin no-slip, incremental form", "tab:brown",
                       1.5),
                      ("impact", "impact law's design (eps_t 0.8)", "tab:cyan", 1.5)]  # fmt: skip
            for name, label, colour, width in curves:
                values = cv[name]
                if conv:
                    values = spin(values)
                if name == "sliding":
                    pairs = [(p, v) for p, v in zip(psi, values, strict=True)
                             if p >= cv["threshold"]]  # fmt: skip
                    ax.plot([p for p, _ in pairs], [v for _, v in pairs], color=colour,
                            linewidth=width, alpha=0.35, label=label)  # fmt: skip
                else:
                    ax.plot(psi, values, color=colour, linewidth=width, alpha=0.6, label=label)
            ax.grid(alpha=0.3)
        axes[0, col].set_title(f"'{title}' tangential law(s)", fontsize=10)
        axes[0, col].set_ylabel("psi_2 = kappa u2 / (mu v_n) (-)")
        axes[1, col].set_ylabel("spin change Omega = kappa r dw / (mu v_n) (-)")
        axes[1, col].set_xlabel("psi_1 = kappa u1 / (mu v_n) (-)")
        axes[0, col].legend(fontsize=6)
    fig.suptitle(
        "Test 5 in Maw, Barber and Fawcett's normalisation: Al2O3 onto Al alloy, v_n 3.9 m/s, "
        f"mu 0.092, e 0.98, kappa = 4 G*/Y* = {cv['kappa']:.4f}; slip u1 from the tangential "
        "speed, no spin in", fontsize=10)  # fmt: skip
    fig.tight_layout()
    fig.savefig(out / "maw.png", dpi=DPI)
    plt.close(fig)


def fig_others(data, out: Path) -> None:
    """Tests 6, 7 and 8: psi_2 against psi_1 for every law, with the rigid limits."""
    tests = [t for t in (6, 7, 8) if _rows(data, t, "oblique")]
    if not tests:
        return
    fig, axes = plt.subplots(1, len(tests), figsize=(5.2 * len(tests), 4.6), squeeze=False)
    titles = {6: "Test 6: spin onto the wall, v_n 3.9 m/s, Al2O3 on Al alloy",
              7: "Test 7: two Al2O3 spheres, 1.95 m/s each, equal spins",
              8: "Test 8: Al alloy (r 10 mm) and Mg alloy (r 5 mm),\n1 m/s, mu 0.1, e 0.5, "
                 "tangential speeds"}  # fmt: skip
    for ax, test in zip(axes[0], tests, strict=True):
        rows = [r for r in _rows(data, test, "oblique") if not r["limit_force"]]
        _oblique_axes(ax, rows, "psi_in", "psi_out")
        ref = sorted((r for r in rows if r["law"] == "hertz/impact"), key=lambda r: r["psi_in"])
        sl = [r for r in ref if r["psi_in"] >= r["threshold_psi"]]
        ax.plot([r["psi_in"] for r in sl], [r["psi_slide"] for r in sl], color="k", linewidth=2.5,
                alpha=0.35, label="rigid Coulomb sliding")  # fmt: skip
        ax.plot(
            [r["psi_in"] for r in ref],
            [r["design"]["reference"] for r in ref],
            color="tab:cyan",
            linewidth=1.5,
            alpha=0.6,
            label="impact law's design",
        )
        ax.set_xlabel("psi_1 = kappa u1 / (mu v_n) (-)")
        ax.set_ylabel("psi_2 = kappa u2 / (mu v_n) (-)")
        ax.set_title(titles[test] + "\n(limit_force false)", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / "spin_and_pairs.png", dpi=DPI)
    plt.close(fig)


def fig_coulomb(data, out: Path) -> None:
    """The "coulomb" laws against dt: friction along the slip (test 5, psi_1 = 1) and psi_2's
    convergence to the law's own equations in continuous time (full-radius arms)."""
    study = data.get("coulomb_dt") or {}
    if not study:
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {"hertz/coulomb": "tab:red", "linear/coulomb": "tab:orange",
               "hertz/coulomb[mindlin]": "tab:purple"}  # fmt: skip
    for name, rows in study.items():
        colour = colours.get(name, "k")
        for r, style in ((rows[0], "-"), (rows[-1], ":")):
            h = r["history"]
            ratio = [ft / (0.092 * fn) if fn > 0 else math.nan
                     for ft, fn in zip(h["ft_n"], h["fn_n"], strict=True)]  # fmt: skip
            t_end = max(t for t, fn in zip(h["t_s"], h["fn_n"], strict=True) if fn > 0)
            axes[0].plot([t / t_end for t in h["t_s"]], ratio, style, color=colour,
                         linewidth=1, label=f"{name}, dt = {r['dt_s']:.3g} s")  # fmt: skip
        axes[1].plot([r["dt_s"] for r in rows], [r["largest_error"] for r in rows], "o-",
                     color=colour, label=name)  # fmt: skip
    rows = next(iter(study.values()))
    dts = [r["dt_s"] for r in rows]
    top = max(r["largest_error"] for rs in study.values() for r in rs)
    axes[1].plot(dts, [top * d / dts[0] for d in dts], color="k", linewidth=0.8,
                 linestyle="--", label="first order (slope 1)")  # fmt: skip
    axes[0].axhline(-1.0, color="k", linewidth=0.8)
    axes[0].axhline(1.0, color="k", linewidth=0.8, linestyle="--")
    axes[0].set_xlabel("time since first touch / contact duration (-)")
    axes[0].set_ylabel("F_t / (mu F_n) along the incoming slip (-)")
    axes[0].set_ylim(-1.2, 1.2)
    axes[0].set_title("Test 5, psi_1 = 1: -1 is Coulomb's sliding against the incoming slip; "
                      "+1 late: Mindlin's\nspring returning, capped, what a reversed slip "
                      "stored", fontsize=9)  # fmt: skip
    axes[0].legend(fontsize=6)
    for ax in (axes[1],):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xticks(dts, [f"{t:.2g}" for t in dts])
    axes[1].set_xlabel("time step dt (s)")
    axes[1].set_ylabel("largest |psi_2 - the law in continuous time| (-)")
    axes[1].set_title("Test 5, psi_1 = 0.5-8, full-radius arms: psi_2 against dt", fontsize=9)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "coulomb_hertz.png", dpi=DPI)
    plt.close(fig)


def figures(data: dict, out: Path) -> None:
    """Every figure of the study into ``out``."""
    for draw in (fig_normal, fig_restitution, fig_incidence, fig_maw, fig_others, fig_coulomb):
        draw(data, out)


# --- README tables ----------------------------------------------------------------------------


def _g(x, digits=4):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:.{digits}g}"


def _e(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:+.1e}"


def _ok(flag):
    if flag is None:
        return "n/a"
    return "pass" if flag else "**FAIL**"


def normal_table(data, test) -> list[str]:
    """Tests 1 and 3: one line per case, normal law and quantity (the tangential laws and
    limit_force give the same bits head-on: checked, else listed apart)."""
    lines = ["| case | laws | quantity | measured | closed form | error | error at dt/2 | "
             "tolerance | verdict |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    rows = [r for r in data["summary"] if r["test"] == test]
    groups: dict = {}
    for r in rows:
        normal = r["law"].split("/")[0]
        groups.setdefault((r["case"], normal, r["quantity"]), []).append(r)
    for (case, normal, quantity), group in groups.items():
        same = len({g["measured"] for g in group}) == 1
        members = f"{normal}: all {len(group)} (identical)" if same else ", ".join(
            g["law"] for g in group)  # fmt: skip
        for g in group[:1] if same else group:
            lines.append(
                f"| {case} | {members if same else g['law']} | {quantity} | "
                f"{_g(g['measured'], 6)} | {_g(g['reference'], 6)} | {_e(g['error'])} | "
                f"{_e(g['error_dt_half'])} | {_g(g['tolerance'])} | {_ok(g['pass'])} |"
            )
    return lines


def restitution_table(data) -> list[str]:
    lines = [
        "| case | law | measured e | set e | error | e_n (clamped dashpot) | error vs e_n | "
        "designed to | verdict (design) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    summary = [r for r in data["summary"] if r["test"] == 2]
    for r in summary:
        if r["quantity"] != "restitution vs set":
            continue
        en = next((x for x in summary if x["case"] == r["case"] and x["law"] == r["law"]
                   and x["quantity"] == "restitution vs e_n"), None)  # fmt: skip
        design = en if en is not None else r
        lines.append(
            f"| {r['case']} | {r['law']} | {_g(r['measured'], 5)} | "
            f"{_g(r['reference'], 3)} | {_e(r['error'])} | "
            f"{_g(en['reference'], 5) if en else '-'} | "
            f"{_e(en['error']) if en else '-'} | {r['design']} | "
            f"{_ok(design['pass'])} |"
        )
    return lines


def oblique_table(data, test) -> list[str]:
    lines = [
        "| law | quantity | points | measured | reference | error | error at dt/2 | "
        "tolerance | verdict | note |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in (x for x in data["summary"] if x["test"] == test):
        lines.append(
            f"| {r['law']} | {r['quantity']} | {r['case']} | {_g(r['measured'])} | "
            f"{_g(r['reference'])} | {_e(r['error'])} | {_e(r['error_dt_half'])} | "
            f"{_g(r['tolerance'], 3)} | {_ok(r['pass'])} | {r['note']} |"
        )
    return lines


def curve_table(data) -> list[str]:
    """The theory curves of Maw et al.'s figure at a few psi_1 (tests 4-6's contact)."""
    cv = data["curves"]
    lines = ["| psi_1 | rigid Coulomb sliding | Mindlin no-slip, total form | incremental form | "
             "impact law's design |", "|---|---|---|---|---|"]  # fmt: skip
    for want in (0.25, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 12.0):
        k = min(range(len(cv["psi_in"])), key=lambda i: abs(cv["psi_in"][i] - want))
        p = cv["psi_in"][k]
        slide = _g(cv["sliding"][k]) if p >= cv["threshold"] else "(sticks)"
        lines.append(f"| {_g(p, 3)} | {slide} | {_g(cv['mindlin_total'][k])} | "
                     f"{_g(cv['mindlin_incremental'][k])} | {_g(cv['impact'][k])} |")  # fmt: skip
    return lines


def arm_table(data) -> list[str]:
    """Test 5 with dem's lever arms and with the full radius, against the law's reference."""
    lines = ["| law | psi_1 | reference | dem's arms | dt/4 | full-radius arms | dt/4 |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in data.get("arm_control", []):
        lines.append(f"| {r['law']} | {_g(r['psi_in'])} | {_g(r['reference'])} | {_g(r['dem'])} | "
                     f"{_g(r['dem_dt_quarter'])} | {_g(r['radius'])} | "
                     f"{_g(r['radius_dt_quarter'])} |")  # fmt: skip
    return lines


def coulomb_table(data) -> list[str]:
    """Test 5: the "coulomb" laws against dt (full-radius arms), psi_1 = 1 and the grid."""
    lines = [
        "| law | dt (s) | impulse / mu (1 + e) m v_n | psi_2 | psi_2, the law in continuous "
        "time | tangential kinetic energy out / in - 1 | largest abs(psi_2 - continuous), "
        "psi_1 = 0.5-8 |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, rows in (data.get("coulomb_dt") or {}).items():
        for r in rows:
            lines.append(f"| {name} | {_g(r['dt_s'], 3)} | {_g(r['impulse_over_coulomb'])} | "
                         f"{_g(r['psi_out'])} | {_g(r['reference_psi'])} | "
                         f"{_e(r['tangential_energy_change'])} | "
                         f"{_e(r.get('largest_error'))} |")  # fmt: skip
    return lines


def readme_tables(data: dict, readme: Path) -> None:
    """Write the tables between README.md's ``<!-- tables: begin -->`` and ``end`` markers."""
    parts = [f"Measured {data['date']} with dem {data['dem_version']} at commit "
             f"{data['git_commit']} on {data['machine']['cpu']} ({data['machine']['cores']} "
             f"cores, load average {data['load_average']} at the start), mode {data['mode']}, "
             f"{data['wall_time_s']} s in all.", ""]  # fmt: skip
    for test in range(1, 9):
        if not any(r["test"] == test for r in data["summary"]):
            continue
        parts += [f"**Test {test}**: {data['titles'][str(test)]}.", ""]
        if test in (1, 3):
            parts += normal_table(data, test)
        elif test == 2:
            parts += restitution_table(data)
        else:
            parts += oblique_table(data, test)
        parts.append("")
    parts += [
        "**Maw et al.'s normalised curves** for tests 4-6's contact (kappa "
        f"{data['curves']['kappa']:.4f}, e 0.98), from analytic.py:",
        "",
    ]
    parts += curve_table(data) + [""]
    if data.get("arm_control"):
        parts += ["**Lever arms**: test 5's psi_2 with dem's arms (a wall's torque at r - delta, "
                  "the slip at the contact point) and with the full radius, against each law's "
                  "design (the spring laws integrated in continuous time at the full radius):",
                  ""]  # fmt: skip
        parts += arm_table(data) + [""]
    if data.get("coulomb_dt"):
        parts += [
            "**The 'coulomb' laws against the time step** (test 5, e 0.98, full-radius lever "
            "arms; the first five columns at psi_1 = 1):",
            "",
        ]
        parts += coulomb_table(data) + [""]
    text = readme.read_text()
    begin, end = "<!-- tables: begin (benchmarks.py writes these) -->", "<!-- tables: end -->"
    new = begin + "\n\n" + "\n".join(parts) + "\n" + end
    text = re.sub(re.escape(begin) + r".*?" + re.escape(end), lambda _: new, text, flags=re.S)
    readme.write_text(text)
