"""The atlas's figures and checks, from whatever points are finished (the atlas's item 6).

    .venv/bin/python validation/atlas/figures.py            # from run*/ (or dem/data/atlas)

Writes into this folder:

- ``maps.png``: the bulk over the Coulomb-bounded point mass over (phi, Gamma), a panel per shape
  and depth (mu 0.35);
- ``optimum.png``: the best vibration angle per Gamma of the bulk against the point mass's,
  per shape, depth and friction, from a parabola through the best angle run and its neighbours
  (the point mass on a fine angle grid);
- ``paper_drive.png``: v_norm against Gamma at phi 25 deg, mu 0.35 per depth and shape beside
  both point masses: does the bed show the point mass's fall at Gamma 4.5?
- ``holdout.png`` and the coverage of the estimates (dem.run.bulk) at the held-out points: how
  many lie within their stated 1 and 2 errors;
- ``refill.png`` and the coverage of a point's error bar by a refill (the same points, fills
  seeded afresh);
- ``summary.json``: the numbers behind every figure, the tables read and the cost so far.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

SHIPPED = ROOT / "dem" / "data" / "atlas"
TABLES = {"atlas": "run", "holdout": "run-holdout", "refill": "run-refill",
          "paper_drive": "run-paper"}  # fmt: skip


def scan(folder: Path) -> list[dict]:
    """The finished points of a running atlas, from their folders (its table comes at the end).

    The columns that ``dem atlas`` tabulates and these figures read: the point's keys (as the
    table names them), v_norm with its pooled error, the bounded point mass and the ratio.
    """
    out = []
    for record in sorted((folder / "points").glob("*/*/atlas_point.json")):
        try:
            rec = json.loads(record.read_text())
            s = json.loads((record.parent / "summary.json").read_text())
        except (OSError, ValueError):
            continue
        if not rec.get("finished"):
            continue
        keys = {("drive.angle_deg" if k == "drive.angle" else k): v
                for k, v in rec["overrides"].items()}  # fmt: skip
        bounded = s.get("pointmass_bounded_velocity_norm")
        v = s["mean_velocity_norm"]
        out.append({"shape": rec["shape"], **keys, "mean_velocity_norm": v,
                    "mean_velocity_norm_stderr": s["mean_velocity_norm_stderr"],
                    "pointmass_bounded_velocity_norm": bounded,
                    "ratio_bounded": v / bounded if bounded and abs(bounded) > 1e-3 else None,
                    "cpu_s": s.get("wall_time_s"), "status": "done"})  # fmt: skip
    return out


def read(name: str) -> list[dict]:
    """The finished points of a table: its run folder's points, else the shipped table."""
    live = scan(HERE / TABLES[name])
    if live:
        return live
    for path in (SHIPPED / f"{name}.csv",):
        if path.is_file():
            with path.open(newline="") as handle:
                rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
            out = []
            for r in rows:
                if r.get("status") != "done":
                    continue
                out.append({k: _num(v) for k, v in r.items()})
            return out
    return []


def _num(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return text


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def maps(rows: list[dict]) -> dict:
    plt = _plt()
    panels = sorted({(r["shape"], r["particles.layers"]) for r in rows
                     if r["material.friction"] == 0.35})  # fmt: skip
    if not panels:
        return {}
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels), 3.4), squeeze=False)
    out = {}
    for ax, (shape, layers) in zip(axes[0], panels, strict=True):
        sel = [r for r in rows if r["shape"] == shape and r["particles.layers"] == layers
               and r["material.friction"] == 0.35
               and isinstance(r["ratio_bounded"], float)]  # fmt: skip
        sc = ax.scatter([r["drive.angle_deg"] for r in sel],
                        [r["drive.throw_number"] for r in sel],
                        c=[r["ratio_bounded"] for r in sel], cmap="coolwarm", vmin=0.4,
                        vmax=1.6, s=120, edgecolors="k")  # fmt: skip
        for r in sel:
            where = (r["drive.angle_deg"], r["drive.throw_number"])
            ax.annotate(f"{r['ratio_bounded']:.2f}", where, fontsize=6, ha="center",
                        va="center")  # fmt: skip
        ax.set_title(f"{shape}s, {layers:g} layers", fontsize=9)
        ax.set_xlabel("phi (deg)")
        ax.set_ylabel("Gamma")
        ax.grid(alpha=0.3)
        out[f"{shape} {layers:g}"] = len(sel)
    fig.colorbar(sc, ax=axes[0].tolist(), label="bulk / bounded point mass")
    fig.savefig(HERE / "maps.png", dpi=110)
    plt.close(fig)
    return {"panels": out}


def _vertex(xs, ys) -> float | None:
    """The best x: a parabola through the best point and its neighbours (the best x at an end)."""
    k = max(range(len(ys)), key=ys.__getitem__)
    if k == 0 or k == len(ys) - 1:
        return xs[k]
    (x0, x1, x2), (y0, y1, y2) = xs[k - 1 : k + 2], ys[k - 1 : k + 2]
    denom = (x0 - x1) * (x0 - x2) * (x1 - x2)
    a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denom
    b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denom
    return -b / (2 * a) if a < 0 else xs[k]


def optimum(rows: list[dict]) -> dict:
    from dem import pointmass

    plt = _plt()
    groups: dict = {}
    for r in rows:
        key = (r["shape"], r["particles.layers"], r["material.friction"], r["drive.throw_number"])
        groups.setdefault(key, []).append(r)
    result = []
    for (shape, layers, mu, gamma), sel in sorted(groups.items()):
        sel = sorted(sel, key=lambda r: r["drive.angle_deg"])
        if len(sel) < 3:
            continue
        xs = [r["drive.angle_deg"] for r in sel]
        bulk = _vertex(xs, [r["mean_velocity_norm"] for r in sel])
        fine = [10.0 + 0.5 * k for k in range(101)]
        pm = [pointmass.velocity(gamma, a, mu, 0.0, 0.8, 0.0, impact="coulomb").velocity_norm
              for a in fine]  # fmt: skip
        result.append({"shape": shape, "layers": layers, "friction": mu, "throw_number": gamma,
                       "bulk_optimum_deg": bulk, "pointmass_optimum_deg": _vertex(fine, pm),
                       "angles_run": xs})  # fmt: skip
    if result:
        fig, ax = plt.subplots(figsize=(6, 4.2))
        for i, (shape, layers, mu) in enumerate(sorted({(r["shape"], r["layers"], r["friction"])
                                                        for r in result})):  # fmt: skip
            sel = [
                r for r in result if (r["shape"], r["layers"], r["friction"]) == (shape, layers, mu)
            ]
            ax.plot([r["throw_number"] for r in sel], [r["bulk_optimum_deg"] for r in sel], "o-",
                    color=f"C{i}", label=f"{shape}s {layers:g} layers mu {mu:g}")  # fmt: skip
            ax.plot([r["throw_number"] for r in sel], [r["pointmass_optimum_deg"] for r in sel],
                    "--", color=f"C{i}", lw=0.8)  # fmt: skip
        ax.set_xlabel("Gamma")
        ax.set_ylabel("best vibration angle (deg); dashed: point mass")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(HERE / "optimum.png", dpi=110)
        plt.close(fig)
    return {"optimum": result}


def paper_drive(rows: list[dict]) -> dict:
    from dem import pointmass

    if not rows:
        return {}
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    gammas = [1.05 + 0.02 * k for k in range(200)]
    for ax, shape in zip(axes, ("sphere", "screw"), strict=True):
        for i, layers in enumerate(sorted({r["particles.layers"] for r in rows})):
            sel = sorted((r for r in rows if r["shape"] == shape
                          and r["particles.layers"] == layers),
                         key=lambda r: r["drive.throw_number"])  # fmt: skip
            if sel:
                ax.errorbar([r["drive.throw_number"] for r in sel],
                            [r["mean_velocity_norm"] for r in sel],
                            yerr=[r["mean_velocity_norm_stderr"] for r in sel], fmt="o-",
                            color=f"C{i}", capsize=2, label=f"{layers:g} layers")  # fmt: skip
        for impact, style in (("coulomb", "k--"), ("paper", "k:")):
            ax.plot(
                gammas,
                [
                    pointmass.velocity(g, 25.0, 0.35, 0.0, 0.8, 0.0, impact=impact).velocity_norm
                    for g in gammas
                ],
                style,
                lw=0.8,
                label=f"point mass ({'bounded' if impact == 'coulomb' else 'Eq. 12'})",
            )
        ax.set_title(f"{shape}s, phi 25 deg, mu 0.35", fontsize=9)
        ax.set_xlabel("Gamma")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("v / (A omega cos phi)")
    fig.tight_layout()
    fig.savefig(HERE / "paper_drive.png", dpi=110)
    plt.close(fig)
    return {"paper_drive_points": len(rows)}


def holdout(atlas_rows: list[dict], held: list[dict]) -> dict:
    """Each held-out point against the atlas's estimate there: within 1 and 2 errors?"""
    from dem.errors import InputError
    from dem.run import bulk

    table = [{"shape": r["shape"]} | {c: r[c] for c, _ in bulk.AXES}
             | {"mean_velocity_norm": r["mean_velocity_norm"],
                "mean_velocity_norm_stderr": r["mean_velocity_norm_stderr"]}
             for r in atlas_rows]  # fmt: skip
    out = []
    for r in held:
        try:
            e = bulk.estimate(
                table,
                r["shape"],
                depth=r["particles.layers"],
                friction=r["material.friction"],
                throw_number=r["drive.throw_number"],
                angle=r["drive.angle_deg"],
            )
        except InputError as exc:
            out.append({"point": _where(r), "refused": f"{exc.key}: {exc.allowed}"})
            continue
        sigma = math.hypot(e.stderr, r["mean_velocity_norm_stderr"])
        z = (r["mean_velocity_norm"] - e.velocity_norm) / sigma if sigma > 0 else math.inf
        out.append({"point": _where(r), "measured": r["mean_velocity_norm"],
                    "estimate": e.velocity_norm, "stated": e.stderr, "z": z})  # fmt: skip
    judged = [o for o in out if "z" in o]
    return {"holdout": out, "within_1": sum(abs(o["z"]) <= 1 for o in judged),
            "within_2": sum(abs(o["z"]) <= 2 for o in judged), "judged": len(judged)}  # fmt: skip


def refill(atlas_rows: list[dict], again: list[dict]) -> dict:
    """Each refilled point against the atlas's own: within 1 and 2 combined errors?"""
    index = {(r["shape"], *(r[c] for c in ("particles.layers", "material.friction",
                                           "drive.throw_number", "drive.angle_deg"))): r
             for r in atlas_rows}  # fmt: skip
    out = []
    for r in again:
        key = (r["shape"], r["particles.layers"], r["material.friction"],
               r["drive.throw_number"], r["drive.angle_deg"])  # fmt: skip
        first = index.get(key)
        if first is None:
            continue
        sigma = math.hypot(first["mean_velocity_norm_stderr"], r["mean_velocity_norm_stderr"])
        z = (r["mean_velocity_norm"] - first["mean_velocity_norm"]) / sigma
        out.append({"point": _where(r), "first": first["mean_velocity_norm"],
                    "refill": r["mean_velocity_norm"], "z": z})  # fmt: skip
    return {"refill": out, "within_1": sum(abs(o["z"]) <= 1 for o in out),
            "within_2": sum(abs(o["z"]) <= 2 for o in out), "judged": len(out)}  # fmt: skip


def _where(r: dict) -> str:
    return (f"{r['shape']} {r['particles.layers']:g} layers, mu {r['material.friction']:g}, "
            f"Gamma {r['drive.throw_number']:g}, phi {r['drive.angle_deg']:g}")  # fmt: skip


def main() -> int:
    atlas_rows = read("atlas")
    report = {"points": {name: len(read(name)) for name in TABLES}}
    report |= maps(atlas_rows)
    report |= optimum(atlas_rows)
    report |= paper_drive(read("paper_drive"))
    report["holdout_check"] = holdout(atlas_rows, read("holdout"))
    report["refill_check"] = refill(atlas_rows, read("refill"))
    report["cpu_hours_so_far"] = sum(float(r.get("cpu_s") or 0) for name in TABLES
                                     for r in read(name)) / 3600.0  # fmt: skip
    (HERE / "summary.json").write_text(json.dumps(report, indent=1, default=str) + "\n")
    print(json.dumps({k: v for k, v in report.items() if k in ("points", "cpu_hours_so_far")}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
