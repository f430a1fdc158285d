"""What every speed-accuracy study shares: a run point, a cache of finished runs, the reference.

A point is one ``dem run`` of a shipped case (``cases/sphere-bed`` or ``cases/screw-trough``)
with some keys overridden (:func:`dem.scene.case.load_case` ``overrides``), through the same runner
a user calls (:func:`dem.run.runner.run_case`: fill, settle, "auto" settle cycles, 20 measured
cycles), without frames, on one thread. Two points run at a time (one per core), so every wall time
is a one-thread time beside one other busy process, the same for every point.

Finished points are appended to ``runs.jsonl`` in this folder, keyed by their settings, so a
study reruns only what is missing (``--fresh`` reruns everything it needs). Each study script
then reads its points, writes ``<study>.csv`` and ``<study>.png`` and prints its table.

Error of a setting: ``v - v_ref`` of the normalised bulk velocity v / (A omega cos phi), v
averaged over the setting's fills (seeds), ``v_ref`` the bed's rigid limit, the converged answer
that validation/bulk-convergence extrapolated from its stiffness sweep (E 5e7 to 5e10 Pa,
``dem/data/stiffness_convergence.json``). Its uncertainty combines the fill-to-fill spread
s_fill / sqrt(fills) (s_fill: the standard deviation of the base fills, each run 20 measured
cycles) with the standard error of the rigid limit. A setting is *acceptable* when
``|error| <= 2 %`` of v_ref and ``|error| <= 2 x`` its uncertainty: within the tolerance and
within the fill-to-fill spread.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from multiprocessing import Pool
from pathlib import Path

# Every run is one thread (two run at a time); set before numba is first imported, since numba
# refuses a thread count changed after its threads start.
os.environ["NUMBA_NUM_THREADS"] = "1"

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CASES = ("sphere-bed", "screw-trough")
RUNS = HERE / "runs.jsonl"
#: Relative tolerance a setting must meet against the reference.
TOLERANCE = 0.02
#: Seeds of the base-setting fills: eight for the screws, whose fill-to-fill spread (about
#: 2 %) is as large as the tolerance, four for the sphere bed (under 1 %).
FILL_SEEDS = {"sphere-bed": (1, 2, 3, 4), "screw-trough": (1, 2, 3, 4, 5, 6, 7, 8)}
#: The study's base: the shipped cases' settings (cases/*/case.toml: Young's modulus 2e9 Pa,
#: where validation/bulk-convergence measured both beds within 2 % of their rigid limits, and
#: dt = 4.0e-6 s, 0.82-0.84 of the stability limit there, under the limit of every law).
#: Every point starts from the case file with these keys set, so the study stays the same
#: study when the shipped cases change.
BASE = {"contact.youngs_modulus": 2.0e9, "run.timestep": 4.0e-6}
#: dt over the stability limit for points whose contact law differs from the base's (the base
#: step's fraction of the limit, rounded down).
BASE_TIMESTEP_FRACTION = 0.82
#: Part of every run's cache key: the study's version. Version 2: the default "impact"
#: tangential law, the base above, errors against the rigid limit. The runs of version 1
#: (the "coulomb" law, base 5e7 Pa, reference 5e8 Pa) are not reused.
VERSION = 2
#: Where the reference comes from.
REFERENCE = "rigid limit, validation/bulk-convergence (dem/data/stiffness_convergence.json)"


@dataclass(frozen=True)
class Point:
    """One run: a case, its overrides, a seed, and engine settings that are not case keys.

    Attributes:
        study: Name of the study the point belongs to (for the tables; not part of the key).
        case: Shipped case name.
        label: Short text for plots and tables.
        x: The value the study varies (for its chart).
        overrides: ``{"table.key": value}`` for :func:`dem.scene.case.load_case`.
        timestep_fraction: dt as a fraction of the case's stability limit (None: the case's).
        skin_fraction: Neighbour skin over the largest radius (None: ``DEM_SKIN_FRACTION``).
        seed: ``run.seed``.

    """

    study: str
    case: str
    label: str
    x: float | str
    overrides: dict = field(default_factory=dict)
    timestep_fraction: float | None = None
    skin_fraction: float | None = None
    seed: int = 1

    @property
    def key(self) -> str:
        """Identity of the run's settings (two studies share a run with the same key)."""
        spec = {"case": self.case, "overrides": self.overrides, "seed": self.seed,
                "timestep_fraction": self.timestep_fraction,
                "skin": self.skin_fraction, "version": VERSION}  # fmt: skip
        return hashlib.sha1(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]


def default_points(study: str, case: str, seeds: Iterable[int] = (1,)) -> list[Point]:
    """The study's base settings (seed 1 unless given)."""
    return [Point(study, case, "base", "base", seed=s) for s in seeds]


def support_points(cases) -> list[Point]:
    """The base fills every study's errors and effects need."""
    return [q for c in sorted(cases) for q in default_points("reference", c, FILL_SEEDS[c])]


def rigid_limit(case: str) -> dict:
    """The bed's rigid limit: ``velocity_norm``, ``stderr_norm`` (validation/bulk-convergence)."""
    data = json.loads((ROOT / "dem" / "data" / "stiffness_convergence.json").read_text())
    return data["rigid_limits"][case]


def load(point: Point):
    """The case of a point (its overrides and time step applied, checked as a file would be)."""
    from dem.scene.case import load_case
    from dem.scene.timestep import timestep_for

    overrides = BASE | point.overrides
    overrides["run.seed"] = point.seed
    if point.timestep_fraction is not None:  # the base step may exceed another law's limit
        overrides["run.timestep"] = "auto"
    case = load_case(ROOT / "cases" / point.case, overrides)
    if point.timestep_fraction is not None:
        limit = timestep_for(case).limit
        overrides["run.timestep"] = float(point.timestep_fraction * limit * (1.0 - 1e-12))
        case = load_case(ROOT / "cases" / point.case, overrides)
    return case


def run_point(point: Point) -> dict:
    """Run one point on one thread and return its row (also the cache record)."""
    from dem import config
    from dem.errors import SimulationError
    from dem.run import runner

    default_skin = config.DEM_SKIN_FRACTION
    if point.skin_fraction is not None:
        config.DEM_SKIN_FRACTION = point.skin_fraction  # this worker only; reset below
    skin = config.DEM_SKIN_FRACTION
    try:
        case = load(point)
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            summary = runner.run_case(case, Path(tmp) / "out", threads=1, progress=False,
                                      frames=False)  # fmt: skip
        total = time.perf_counter() - t0
    except SimulationError as err:  # the guard stopped it: a result of the study, kept
        print(f"{point.case} {point.label} seed {point.seed}: stopped: {err}", flush=True)
        return {"key": point.key, "case": point.case, "seed": point.seed, "failed": str(err),
                "velocity_norm": math.nan, "stderr": math.nan, "wall_time_s": math.nan,
                "load_1min": os.getloadavg()[0]}  # fmt: skip
    finally:
        config.DEM_SKIN_FRACTION = default_skin
    dynamics = summary["wall_time_s"] + summary["settle_wall_time_s"]
    row = {
        "key": point.key, "case": point.case, "seed": point.seed,
        "overrides": json.dumps(point.overrides, sort_keys=True),
        "timestep_fraction": point.timestep_fraction, "skin_fraction": skin,
        "grains": summary["grains"], "spheres": summary["spheres"],
        "timestep": summary["timestep"], "timestep_limit": summary["timestep_limit"],
        "steps": summary["steps"], "settle_cycles": summary["settle_cycles"],
        "cycles": summary["cycles"],
        "velocity_norm": summary["mean_velocity_norm"],
        "stderr": summary["mean_velocity_norm_stderr"],
        "autocorrelation_time": summary["cycle_autocorrelation_time"],
        "pointmass_velocity_norm": summary["pointmass_velocity_norm"],
        "wall_time_s": round(dynamics, 3), "total_time_s": round(total, 3),
        "particle_steps": summary["spheres"] * summary["steps"],
        "neighbour_builds": summary["neighbour_builds"],
        "load_1min": os.getloadavg()[0], "git_commit": summary["git_commit"],
    }  # fmt: skip
    print(f"{point.case:13s} {point.study:14s} {point.label:24s} seed {point.seed}: "
          f"v_norm {row['velocity_norm']:.4f} +- {row['stderr']:.4f}, "
          f"{row['wall_time_s']:.1f} s, load {row['load_1min']:.2f}", flush=True)  # fmt: skip
    return row


def cached() -> dict[str, dict]:
    """Finished runs by key (the last record of a key wins)."""
    rows = {}
    if RUNS.exists():
        for line in RUNS.read_text().splitlines():
            if line.strip():
                row = json.loads(line)
                rows[row["key"]] = row
    return rows


def _init_worker() -> None:
    os.environ["NUMBA_NUM_THREADS"] = "1"


def ensure(points: Iterable[Point], *, fresh: bool = False, processes: int = 2) -> dict[str, dict]:
    """Run the points not yet in the cache (all of them if ``fresh``); return the cache."""
    have = {} if fresh else cached()
    todo, seen = [], set()
    for p in points:
        if p.key not in have and p.key not in seen:
            todo.append(p)
            seen.add(p.key)
    # Longest first (more spheres, smaller steps), so the two workers finish together.
    todo.sort(key=lambda p: -_cost_guess(p))
    if todo:
        print(f"{len(todo)} runs to do ({len(have)} cached in {RUNS.name})", flush=True)
        with Pool(processes, initializer=_init_worker) as pool:
            for row in pool.imap_unordered(run_point, todo):
                with RUNS.open("a") as fh:
                    fh.write(json.dumps(row) + "\n")
    return cached()


def _cost_guess(p: Point) -> float:
    cost = 1.0 / (p.timestep_fraction or BASE_TIMESTEP_FRACTION)
    e = p.overrides.get("contact.youngs_modulus")
    if e:
        cost *= (e / BASE["contact.youngs_modulus"]) ** 0.4
    return cost * p.overrides.get("particles.count", 1000) / 1000


# --- the reference and the errors -----------------------------------------------------------


@dataclass(frozen=True)
class Reference:
    """The converged answer of one case and the fill-to-fill spread."""

    case: str
    velocity_norm: float  # the bed's rigid limit (validation/bulk-convergence)
    stderr: float  # its standard error
    fill_spread: float  # fill-to-fill standard deviation at the base settings
    shipped: float  # mean over the base-setting fills
    shipped_stderr: float  # its standard error (fill-to-fill)
    wall_time_s: float  # mean wall time of a base run


def reference(case: str, rows: dict[str, dict]) -> Reference:
    """The reference of ``case``: its rigid limit, and the base fills from finished runs (run
    ``reference.py`` first)."""
    import numpy as np

    ship = [rows[p.key] for p in default_points("reference", case, FILL_SEEDS[case])
            if p.key in rows and not rows[p.key].get("failed")]  # fmt: skip
    if len(ship) < 2:
        raise SystemExit(f"{case}: run validation/speed_accuracy/reference.py first")
    v_ship = np.array([r["velocity_norm"] for r in ship])
    spread = float(v_ship.std(ddof=1))
    rigid = rigid_limit(case)
    return Reference(case, rigid["velocity_norm"], rigid["stderr_norm"], spread,
                     float(v_ship.mean()), spread / math.sqrt(len(v_ship)),
                     float(np.mean([r["wall_time_s"] for r in ship])))  # fmt: skip


def table(points: list[Point], rows: dict[str, dict]) -> list[dict]:
    """Rows of a study: each setting (its fills averaged) with its error against the reference.

    A setting run with several seeds is one row: the mean over its fills, with ``fills`` and
    ``error_uncertainty`` = the fill-to-fill spread / sqrt(fills) combined with the reference's
    standard error (a run's own standard error misses the fill-to-fill part, see README).
    ``effect`` is the same against the base settings (the mean of their fills): what this
    one setting changes, whatever the error of the base settings themselves.
    """
    refs = {c: reference(c, rows) for c in {p.case for p in points}}
    groups: dict[tuple, list[Point]] = {}
    for p in points:
        groups.setdefault((p.case, p.study, p.label), []).append(p)
    out = []
    for (case, study, label), group in groups.items():
        ref = refs[case]
        runs = [rows[p.key] for p in group]
        base = {"case": case, "study": study, "label": label, "x": group[0].x,
                "fills": len(runs), "seed": " ".join(str(p.seed) for p in group),
                "reference": ref.velocity_norm, "fill_spread": ref.fill_spread}  # fmt: skip
        failed = [r for r in runs if r.get("failed")]
        if failed:
            out.append(base | {"velocity_norm": math.nan, "stderr": math.nan, "error": math.nan,
                               "relative_error": math.nan, "error_uncertainty": math.nan,
                               "acceptable": False, "effect": math.nan,
                               "relative_effect": math.nan, "effect_uncertainty": math.nan,
                               "effect_acceptable": False, "wall_time_s": math.nan,
                               "speedup": math.nan,
                               "failed": failed[0]["failed"].split(":")[0]})  # fmt: skip
            continue
        n = len(runs)
        v = sum(r["velocity_norm"] for r in runs) / n
        err = v - ref.velocity_norm
        spread = max(ref.fill_spread, max(r["stderr"] for r in runs))
        unc = math.hypot(spread / math.sqrt(n), ref.stderr)
        eff_unc = math.hypot(spread / math.sqrt(n), ref.shipped_stderr)
        wall = sum(r["wall_time_s"] for r in runs) / n
        r0 = runs[0]
        out.append(base | {
            "velocity_norm": v,
            "stderr": math.sqrt(sum(r["stderr"] ** 2 for r in runs)) / n,
            "error": err, "relative_error": err / ref.velocity_norm,
            "error_uncertainty": unc,
            "acceptable": abs(err) <= TOLERANCE * ref.velocity_norm and abs(err) <= 2.0 * unc,
            "effect": v - ref.shipped, "relative_effect": (v - ref.shipped) / ref.shipped,
            "effect_uncertainty": eff_unc,
            "effect_acceptable": abs(v - ref.shipped) <= TOLERANCE * ref.shipped
            and abs(v - ref.shipped) <= 2.0 * eff_unc,
            "wall_time_s": wall, "speedup": ref.wall_time_s / wall,
            "particle_steps": r0["particle_steps"], "spheres": r0["spheres"],
            "grains": r0["grains"], "timestep": r0["timestep"],
            "timestep_limit": r0["timestep_limit"],
            "settle_cycles": sum(r["settle_cycles"] for r in runs) / n,
            "load_1min": max(r["load_1min"] for r in runs), "git_commit": r0["git_commit"],
            "failed": "",
        })  # fmt: skip
    return out


def write_csv(name: str, rows: list[dict], script: str) -> Path:
    """``<name>.csv`` with the provenance header."""
    from dem import provenance

    path = HERE / f"{name}.csv"
    with open(path, "w", newline="") as fh:
        fh.write("\n".join(provenance.header_lines(script)) + "\n")
        fh.write(f"# reference: {REFERENCE}; base: {json.dumps(BASE)}, seeds {FILL_SEEDS}; "
                 f"acceptable: |error| <= {TOLERANCE:.0%} of it and "
                 "<= 2 x its uncertainty (fill-to-fill spread / sqrt(fills) and the "
                 "reference's)\n")  # fmt: skip
        fields = list(dict.fromkeys(k for r in rows for k in r))
        writer = csv.DictWriter(fh, fieldnames=fields, restval="")
        writer.writeheader()
        writer.writerows(rows)
    return path


def print_table(rows: list[dict]) -> None:
    """Each setting: velocity, error against the reference, effect against the base, cost."""
    print(f"{'case':13s} {'setting':28s} {'fills':>5s} {'v_norm':>7s} {'error %':>8s} {'+-':>5s} "
          f"{'effect %':>8s} {'+-':>5s} {'wall s':>7s} {'speedup':>7s}  ok")  # fmt: skip
    for r in rows:
        if r["failed"]:
            print(f"{r['case']:13s} {r['label']:28s} stopped by the guard: {r['failed']}")
            continue
        ok = "yes" if r["acceptable"] else "no"
        pm = 100 * r["error_uncertainty"] / r["reference"]
        eff = r.get("relative_effect", math.nan)
        eff_pm = 100 * r.get("effect_uncertainty", math.nan) / r["reference"]
        print(f"{r['case']:13s} {r['label']:28s} {r['fills']!s:>5s} {r['velocity_norm']:7.4f} "
              f"{100 * r['relative_error']:8.2f} {pm:5.2f} {100 * eff:8.2f} {eff_pm:5.2f} "
              f"{r['wall_time_s']:7.1f} {r['speedup']:7.2f}  {ok}")  # fmt: skip


def plot(rows: list[dict], path: Path, title: str) -> None:
    """Error (% of the reference) against wall time, one panel per case, the 2 % band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = [c for c in CASES if any(r["case"] == c for r in rows)]
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        sel = [r for r in rows if r["case"] == case]
        ref = sel[0]
        ax.axhspan(-100 * TOLERANCE, 100 * TOLERANCE, color="C2", alpha=0.12, label="2 %")
        spread = 200 * ref["fill_spread"] / ref["reference"]
        if math.isfinite(spread):
            ax.axhline(spread, color="0.5", lw=0.8, ls=":")
            ax.axhline(-spread, color="0.5", lw=0.8, ls=":", label="2 x fill-to-fill spread")
        ax.axhline(0.0, color="k", lw=0.8)
        ship_err = [r["relative_error"] for r in sel if r["label"] == "base"]
        if ship_err:
            ax.axhline(100 * ship_err[0], color="C1", lw=0.8, ls="--", label="base settings")
        stopped = 0
        for r in sel:
            if r["failed"]:
                ax.annotate(f"{r['label']}: stopped by the guard", (0.02, 0.95 - 0.05 * stopped),
                            xycoords="axes fraction", fontsize=7, color="C3")  # fmt: skip
                stopped += 1
                continue
            color = "C0" if r["acceptable"] else "C3"
            ax.errorbar(r["wall_time_s"], 100 * r["relative_error"],
                        yerr=100 * r["error_uncertainty"] / r["reference"], fmt="o",
                        color=color, ms=5, capsize=2)  # fmt: skip
            ax.annotate(r["label"], (r["wall_time_s"], 100 * r["relative_error"]),
                        fontsize=7, xytext=(4, 3), textcoords="offset points")  # fmt: skip
        ax.set_xscale("log")
        ax.set_xlabel("wall time of the run, s (1 thread beside 1 busy process)")
        ax.set_ylabel("error of v / (A omega cos phi), % of the reference")
        ax.set_title(f"{case}: reference {ref['reference']:.3f}", fontsize=10)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(name: str, points: list[Point], title: str, script: str) -> int:
    """Command line of a study: run what is missing, write the CSV and the chart."""
    parser = argparse.ArgumentParser(description=title)
    parser.add_argument("--fresh", action="store_true", help="rerun points already cached")
    parser.add_argument("--figures", action="store_true", help="only redraw from runs.jsonl")
    args = parser.parse_args()
    support = support_points({p.case for p in points})
    rows = cached() if args.figures else ensure(support + points, fresh=args.fresh)
    out = table(points, rows)
    write_csv(name, out, script)
    plot(out, HERE / f"{name}.png", title)
    print_table(out)
    print(f"wrote {name}.csv and {name}.png")
    return 0
