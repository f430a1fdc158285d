"""A mesh trough in dem and in LIGGGHTS-PUBLIC 3.8: the U pan of cases/u-trough, both codes.

Regenerates results.json, velocity.png and decks/<run>/ (in.dem, trough.stl, ...) here (the
runs of the README: see its Provenance):

    nice -n 10 .venv/bin/python validation/liggghts-mesh/run.py                  # U pan, seed 1
    nice -n 10 .venv/bin/python validation/liggghts-mesh/run.py --cases spheres --seed 2
    nice -n 10 .venv/bin/python validation/liggghts-mesh/run.py --cases screws --seed 1 \
        --mesh-curvature 5 --skip-dem     # LIGGGHTS with 'curvature 5 curvature_tolerant yes'
    .venv/bin/python validation/liggghts-mesh/run.py --report-only   # pooled seeds + figure

Cases (``--cases``), each built by ``dem.scene.case.load_case(case, overrides=...)``:

- ``spheres``: the U pan of cases/u-trough (a half cylinder of radius 30 mm with 20 mm walls,
  100 triangles) with 2400 spheres of r = 2 mm instead of the screws: the mesh contact alone;
- ``screws``: cases/u-trough's 150 screws (8 spheres each);
- ``flat-spheres`` / ``box-spheres``: the spheres on a flat floor between side walls 60 mm
  apart, as the kernel's (LIGGGHTS's primitive) walls or as 48 triangles;
- ``flat-screws`` / ``box-screws``: cases/screw-trough (200 screws) the same two ways.

A run with ``--seed N`` (N > 1) is stored as ``<case>-seedN``; seeds of one case are pooled.

Both codes use the same conventions: ``contact.tangential = "liggghts"`` (LIGGGHTS's tangential
law, Mindlin k_t from G), ``material.restitution_normal = 0.06`` (LIGGGHTS refuses e <= 0.05),
the same explicit time step, 10 driven settle cycles and 20 measured cycles at 60 Hz, seed.
The method is that of validation/liggghts-bulk/run.py:

- LIGGGHTS: ``dem.io.liggghts.write_deck(case, decks/<case>, timestep=dt, steps=..,
  settle_steps=.., sample_steps=1)``, run on one rank in a copy under scratch/ with one line
  added, ``write_dump all custom final.atoms id type x y z radius``, so that the final member
  spheres can be checked against the mesh (dem.scene.mesh's closest-point kernels): all inside the
  pan and not through it. vx_mean.txt (the mean x-velocity of every step: of the spheres, or of
  the screws' centres of mass) is binned into exactly the drive cycles dem uses.
- dem: ``dem.run.runner.run_case(case, scratch/dem/<case>, cycles=20, threads=1, progress=False,
  overwrite=True, frames=False)``; per-cycle mass-weighted mean x-velocities from its summary.
- both: v = mean of the per-cycle means, se = the correlated standard error of the per-cycle
  means (``dem.physics.measure.correlated_stderr``: a bed's successive cycles are not
  independent, so std(ddof=1) / sqrt(cycles) would understate it; runs recorded before
  2026-12 give LIGGGHTS's se as std(ddof=1) / sqrt(cycles)); dem - LIGGGHTS in % of LIGGGHTS
  and in combined standard errors sqrt(se_dem^2 + se_L^2).

The run of both codes is validation/_lib/pair.py's.

One code at a time (dem on one thread, LIGGGHTS on one rank). Not part of the test suite.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

import numpy as np

from dem import provenance
from dem.io.liggghts import DECK_NAME, MESH_FILE
from dem.scene.case import load_case
from dem.scene.mesh import extrude, load_mesh

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header, pair, replicas  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CASES = ROOT / "cases"

RESTITUTION = 0.06
SPHERE_RADIUS = 0.002  # m
SPHERE_COUNT = 2400  # about 25 mm deep in the 30 mm pan at a packing fraction of 0.6
SPHERE_TIMESTEP = 5e-6  # s: 0.59 of dem's stability limit for these spheres (8.5e-6 s)
BOX_WALL = 0.06  # m, walls of the box mesh (validation/mesh: taller than the bed climbs)
FINAL_DUMP = "final.atoms"
#: Overlap of a final member sphere with the mesh beyond which it counts as through it, m
#: (LIGGGHTS dumps 6 significant digits; resting overlaps are below 1e-5 m here).
OVERLAP_TOLERANCE = 5e-5

COMMON = {
    "contact.tangential": "liggghts",
    "contact.tangential_stiffness_ratio": None,  # Hertz under "liggghts" takes Mindlin's k_t
    "contact.tangential_damping_ratio": None,
    "material.restitution_normal": RESTITUTION,
    "contact.youngs_modulus": 5.0e8,  # the screw cases as shipped when this was measured
}


def box_mesh(path: Path, length: float, width: float, wall: float) -> Path:
    """Floor z = 0 and side walls y = +-width/2 (height ``wall``) as 48 triangles, 8 along x."""
    import meshio

    h = 0.5 * width
    profile = [[-h, wall], [-h, 0.0], [h, 0.0], [h, wall]]
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, extrude(profile, length, 8), binary=False)
    return path


def make_case(name: str, args):
    """The case ``name`` with the comparison settings (one overrides dict per case)."""
    run = {
        "run.settle_cycles": args.settle_cycles,
        "run.cycles": args.cycles,
        "run.seed": args.seed,
    }
    if name in ("spheres", "flat-spheres", "box-spheres"):
        overrides = {
            **COMMON,
            **run,
            "particles.shape": "sphere",
            "particles.radius": SPHERE_RADIUS,
            "particles.count": SPHERE_COUNT,
            "particles.length": None,
            "particles.shank_radius": None,
            "particles.head_radius": None,
            "particles.mass": None,
            "material.density": 7800.0,  # steel; the screws' mass set theirs
            "run.timestep": SPHERE_TIMESTEP,
        }
        if name == "flat-spheres":  # the kernel's flat floor and side walls, 60 mm apart
            overrides["trough.mesh"] = None
        elif name == "box-spheres":  # the same floor and walls as triangles
            box = box_mesh(Path(args.scratch) / "box_trough.stl", 0.12, 0.06, BOX_WALL)
            overrides["trough.mesh"] = str(box)
        return load_case(CASES / "u-trough", overrides=overrides), overrides
    source = {"screws": "u-trough", "flat-screws": "screw-trough", "box-screws": "screw-trough"}
    # the screws keep the case's own time step, 8e-6 s (cases/u-trough and screw-trough)
    overrides = {**COMMON, **run, "run.timestep": 8.0e-6}
    if name == "box-screws":  # screw-trough's floor and walls as triangles
        box = box_mesh(Path(args.scratch) / "box_trough.stl", 0.12, 0.06, BOX_WALL)
        overrides["trough.mesh"] = str(box)
    return load_case(CASES / source[name], overrides=overrides), overrides


def inside_check(case, work: Path) -> dict:
    """The final member spheres of a LIGGGHTS run against the mesh (or the flat walls)."""
    data = np.loadtxt(work / FINAL_DUMP, skiprows=9)
    x, r = data[:, 2:5], data[:, 5]
    top = x[:, 2] + r
    out = {
        "spheres": int(len(x)),
        "bed_top_p95_m": float(np.percentile(top, 95)),
        "bed_top_max_m": float(top.max()),
    }
    if case.trough.mesh is None:
        half = 0.5 * case.trough.width
        overlap = np.maximum.reduce([r - x[:, 2], r - (half - x[:, 1]), r - (half + x[:, 1])])
        outside = int(np.sum(overlap > OVERLAP_TOLERANCE))
        out.update(outside=outside, max_overlap_m=float(overlap.max()))
        return out
    mesh = load_mesh(work / MESH_FILE, length=case.trough.length)
    lo, hi = mesh.tri.min(axis=(0, 1)), mesh.tri.max(axis=(0, 1))
    mesh.index(float(np.max(hi - lo)))  # every point within the index's reach
    side, gap = mesh.sides(x), mesh.gaps(x)
    overlap = r - gap
    through = (side <= 0.0) | (overlap > OVERLAP_TOLERANCE)
    out.update(outside=int(through.sum()), max_overlap_m=float(overlap.max()))
    return out


# --------------------------------------------------------------------------- the pair
def deck_edit(args):
    """The edit of the copied deck (validation/_lib/pair.py's ``edit``) and the list of changes
    it records: a final dump of the member spheres, and the mesh curvature option if asked."""
    changes = [f"appended: write_dump all custom {FINAL_DUMP} id type x y z radius"]

    def edit(deck: Path) -> None:
        with open(deck, "a") as f:
            f.write(f"write_dump all custom {FINAL_DUMP} id type x y z radius\n")
        if args.mesh_curvature is not None:
            # facets meeting at less than this angle count as one surface: LIGGGHTS then carries
            # the tangential spring across their edge (as dem does up to 45 deg) and drops the
            # edge contacts between them; the option refuses thin triangles unless tolerant
            text = deck.read_text()
            line = f"fix trough all mesh/surface file {MESH_FILE} type 2"
            extra = f" curvature {args.mesh_curvature:g} curvature_tolerant yes"
            if line + "\n" not in text:
                raise SystemExit(f"no '{line}' line in the deck")
            deck.write_text(text.replace(line + "\n", line + extra + "\n"))
            changes.append(f"'{line}' + '{extra}'")

    return edit, changes


def run_both(name: str, case, args) -> tuple[pair.Pair, list[str]]:
    """LIGGGHTS (unless --skip-liggghts), then dem (unless --skip-dem), on one case."""
    edit, changes = deck_edit(args)
    both = pair.run_pair(
        case,
        deck_dir=HERE / "decks" / name.split("-curvature")[0],  # the variant runs the same deck
        work=Path(args.scratch) / "liggghts" / name,
        dem_out=Path(args.scratch) / "dem" / name,
        skip_reference=args.skip_liggghts,
        skip_dem=args.skip_dem,
        min_loops=3,
        edit=edit,
        fresh_deck=True,
    )
    return both, changes


def liggghts_entry(name: str, case, lig: pair.ReferenceRun, changes: list[str]) -> dict:
    """results.json's LIGGGHTS half of a case: the per-cycle means and the final-state check."""
    run, work = lig.run, lig.work
    mean, se = replicas.series_mean(lig.per_cycle)
    check = inside_check(case, work)
    print(
        f"  LIGGGHTS {name}: v = {mean:.5f} +- {se:.5f} m/s ({run.wall_s:.0f} s); "
        f"{check['outside']} of {check['spheres']} spheres outside the walls"
    )
    return {
        "version": run.version,
        "deck": str(lig.deck.relative_to(ROOT)),
        "command": f"cd {work.relative_to(ROOT)} && liggghts -in {DECK_NAME}",
        "deck_changed": changes,
        "mean_velocity": mean,
        "mean_velocity_stderr": se,
        "per_cycle_velocity": lig.per_cycle,
        "settle_cycle_velocity": lig.settle_cycle,
        "drive_start_step": lig.drive_start,
        "atoms": run.loop_times[-1].atoms,
        "final_state": check,
        "loop_times_s": [x.seconds for x in run.loop_times],
        "loop_steps": [x.steps for x in run.loop_times],
        "wall_time_s": run.wall_s,
    }


def dem_entry(name: str, case, dem: pair.DemRun) -> dict:
    """results.json's dem half of a case: the numbers of run_case's summary."""
    summary, out, wall = dem.summary, dem.out, dem.wall_s
    print(
        f"  dem      {name}: v = {summary['mean_velocity']:.5f} +- "
        f"{summary['mean_velocity_stderr']:.5f} m/s ({wall:.0f} s)"
    )
    return {
        "command": (
            f"dem.run.runner.run_case(case, {out.relative_to(ROOT)}, cycles={case.run.cycles}, "
            "threads=1, progress=False, overwrite=True, frames=False)"
        ),
        "mean_velocity": summary["mean_velocity"],
        "mean_velocity_stderr": summary["mean_velocity_stderr"],
        "per_cycle_velocity": summary["per_cycle_velocity"],
        "timestep": summary["timestep"],
        "timestep_limit": summary["timestep_limit"],
        "settle_time_s": summary["settle_time_s"],
        "settle_wall_time_s": summary["settle_wall_time_s"],
        "driven_wall_time_s": summary["wall_time_s"],
        "steps": summary["steps"],
        "particle_steps_per_s": summary.get("particle_steps_per_s"),
        "wall_time_s": wall,
    }


# --------------------------------------------------------------------------- report
def compare(entry: dict, dem: dict | None = None) -> None:
    """entry["difference"]: dem - LIGGGHTS (dem: the entry's own, or the one given)."""
    dem, lig = dem or entry.get("dem", {}), entry.get("liggghts", {})
    if "mean_velocity" in dem and "mean_velocity" in lig:
        entry["difference"] = replicas.difference(
            dem["mean_velocity"], dem["mean_velocity_stderr"],
            lig["mean_velocity"], lig["mean_velocity_stderr"],
        )  # fmt: skip


def refresh(results: dict) -> None:
    """Recompute every entry's difference (a variant's against its base case's dem run)."""
    for entry in results["cases"].values():
        base = results["cases"].get(entry.get("dem_of", ""), {})
        compare(entry, base.get("dem"))


def pooled(results: dict) -> dict:
    """Per kind of case with two or more seeds: each code's mean over the seeds, its seed se.

    The per-cycle se covers only the cycle-to-cycle noise of one fill; re-filling moves a
    result by more (validation/liggghts-bulk), so the seed-to-seed se, std(ddof=1)/sqrt(seeds)
    of the per-seed means, is the yardstick for a pooled difference. Also sets the flat-trough
    screw difference of validation/liggghts-screws (seeds 1-3, E = 5e7 Pa) beside them.
    """
    kinds: dict[str, list[dict]] = {}
    for name, entry in results["cases"].items():
        if "dem_of" in entry:
            continue
        kinds.setdefault(re.sub(r"-seed\d+", "", name), []).append(entry)
    out = {}
    for kind, entries in kinds.items():
        done = [e for e in entries if "difference" in e]
        if len(done) < 2:
            continue
        row = {"seeds": sorted(e["seed"] for e in done)}
        for key in ("dem", "liggghts"):
            v = np.array([e[key]["mean_velocity"] for e in done])
            row[f"{key}_mean"] = float(v.mean())
            row[f"{key}_seed_stderr"] = replicas.replica_stderr(v)
        diff = row["dem_mean"] - row["liggghts_mean"]
        sigma = math.hypot(row["dem_seed_stderr"], row["liggghts_seed_stderr"])
        row["percent_of_liggghts"] = 100.0 * diff / row["liggghts_mean"]
        row["sigma_seed"] = diff / sigma
        out[kind] = row
    flat = ROOT / "validation" / "liggghts-screws" / "results.json"
    if flat.exists():
        ref = json.loads(flat.read_text())["bulk"]
        out["reference_flat_screws_liggghts_screws"] = {
            "source": "validation/liggghts-screws/results.json (bulk.seeds_pooled, seeds 1-3, "
            "200 screws, E = 5e7 Pa, 5 + 10 cycles)",
            **ref["seeds_pooled"],
        }
    return out


def plot(results: dict) -> None:
    """velocity.png: per-cycle series of the two U-pan cases (seed 1); dem - LIGGGHTS of all."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = results["cases"]
    fig = plt.figure(figsize=(10.0, 7.5))
    grid = fig.add_gridspec(2, 2, height_ratios=[1.0, 1.2])
    for col, name in enumerate(("spheres", "screws")):
        ax = fig.add_subplot(grid[0, col])
        entry = cases.get(name, {})
        s = entry.get("settle_cycles", 0)
        for key, label, color, marker in (
            ("dem", "dem", "C0", "o"),
            ("liggghts", "LIGGGHTS 3.8", "C1", "s"),
        ):
            half = entry.get(key, {})
            if "per_cycle_velocity" not in half:
                continue
            u = np.asarray(half["per_cycle_velocity"])
            ax.plot(s + np.arange(u.size) + 0.5, u, marker=marker, ms=3, lw=0.8, color=color,
                    label=f"{label}: {half['mean_velocity']:.4f} +- "
                    f"{half['mean_velocity_stderr']:.4f}")  # fmt: skip
            m, e = half["mean_velocity"], half["mean_velocity_stderr"]
            ax.axhspan(m - e, m + e, color=color, alpha=0.2)
            if "settle_cycle_velocity" in half:
                v = np.asarray(half["settle_cycle_velocity"])
                ax.plot(np.arange(v.size) + 0.5, v, marker=marker, ms=3, lw=0.8, color=color,
                        alpha=0.35)  # fmt: skip
        ax.axvline(s, color="k", lw=0.6, ls=":")
        ax.set_title(entry.get("title", name) + ", seed 1", fontsize=8)
        ax.set_xlabel("drive cycle (LIGGGHTS settle cycles faint)", fontsize=8)
        ax.set_ylabel("mean vx (m/s)", fontsize=8)
        ax.legend(fontsize=7, loc="upper right")
        ax.grid(alpha=0.3)
    ax = fig.add_subplot(grid[1, :])

    def order(name: str) -> tuple:
        kind = re.sub(r"-seed\d+|-curvature.*", "", name)
        return (NAMES.index(kind), "-curvature" in name, cases[name]["seed"])

    names = sorted((n for n in cases if "difference" in cases[n]), key=order)
    y = np.arange(len(names))[::-1]
    for yi, name in zip(y, names, strict=True):
        d, lig = cases[name]["difference"], cases[name]["liggghts"]["mean_velocity"]
        ax.errorbar(d["percent_of_liggghts"], yi, xerr=100.0 * d["combined_stderr"] / lig,
                    fmt="D", color="C2", capsize=3)  # fmt: skip
    labels = [cases[n]["title"] for n in names]
    for kind, row in results.get("pooled", {}).items():
        if "percent_of_liggghts" not in row:
            continue
        sigma = math.hypot(row["dem_seed_stderr"], row["liggghts_seed_stderr"])
        y = np.append(y, -1 - len([lb for lb in labels if lb.startswith("pooled")]))
        ax.errorbar(row["percent_of_liggghts"], y[-1], xerr=100.0 * sigma / row["liggghts_mean"],
                    fmt="D", mfc="none", color="C3", capsize=3)  # fmt: skip
        labels.append(f"pooled {kind}, seeds {row['seeds']} (seed-to-seed se)")
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=7)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("(dem - LIGGGHTS) / LIGGGHTS (%), bars: combined standard error", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(HERE / "velocity.png", dpi=120)


NAMES = ("spheres", "screws", "flat-spheres", "box-spheres", "flat-screws", "box-screws")
TITLES = {
    "spheres": f"U pan, {SPHERE_COUNT} spheres r = {SPHERE_RADIUS * 1e3:g} mm",
    "flat-spheres": f"flat floor and walls, {SPHERE_COUNT} spheres",
    "box-spheres": f"the flat floor and walls as 48 triangles, {SPHERE_COUNT} spheres",
    "screws": "U pan, 150 screws (cases/u-trough)",
    "flat-screws": "flat floor and walls, 200 screws (cases/screw-trough)",
    "box-screws": "the flat floor and walls as 48 triangles, 200 screws",
}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="+", default=["spheres", "screws"],
                        choices=NAMES)  # fmt: skip
    parser.add_argument("--settle-cycles", type=int, default=10)
    parser.add_argument("--cycles", type=int, default=20, help="measured drive cycles")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--mesh-curvature",
        type=float,
        default=None,
        help="deg: LIGGGHTS runs with 'curvature DEG curvature_tolerant yes' on the mesh "
        "(results under <case>-curvatureDEG; use with --skip-dem)",
    )
    parser.add_argument("--skip-liggghts", action="store_true")
    parser.add_argument("--skip-dem", action="store_true")
    parser.add_argument("--results", default=str(HERE / "results.json"))
    parser.add_argument("--scratch", default=str(HERE / "scratch"), help="run folders go here")
    parser.add_argument("--report-only", action="store_true", help="rewrite velocity.png only")
    args = parser.parse_args(argv)
    args.scratch = str(Path(args.scratch).resolve())
    path = Path(args.results)
    results = json.loads(path.read_text()) if path.exists() else {}
    if args.report_only:
        refresh(results)
        results["pooled"] = pooled(results)
        path.write_text(json.dumps(results, indent=2) + "\n")
        plot(results)
        return
    invocation = header.invocation("validation/liggghts-mesh/run.py", argv)
    # "script": the last invocation; each run records its own
    results.update(header.results_header("validation/liggghts-mesh/run.py", argv))
    results.setdefault("cases", {})
    for kind in args.cases:
        name = kind if args.seed == 1 else f"{kind}-seed{args.seed}"
        if args.mesh_curvature is not None:
            name += f"-curvature{args.mesh_curvature:g}"
        case, overrides = make_case(kind, args)
        print(f"{name}: dt = {case.run.timestep:g} s, Gamma = {case.drive.throw_number:.3f}")
        entry = results["cases"].get(name, {})
        entry.update(
            {
                "title": TITLES[kind]
                + ("" if args.seed == 1 else f", seed {args.seed}")
                + ("" if args.mesh_curvature is None else ", LIGGGHTS mesh curvature "
                   f"{args.mesh_curvature:g} deg"),
                "case": str(case.directory.relative_to(ROOT)),
                "walls": "flat floor and side walls (primitives)" if case.trough.mesh is None
                else f"mesh {case.trough.mesh.name}",
                "overrides": overrides,
                "timestep": case.run.timestep,
                "settle_cycles": case.run.settle_cycles,
                "cycles": case.run.cycles,
                "seed": case.run.seed,
                "velocity_scale": case.drive.amplitude * case.drive.omega
                * math.cos(math.radians(case.drive.angle)),
            }
        )  # fmt: skip
        both, changes = run_both(name, case, args)
        lig, dem = both.reference, both.dem
        if isinstance(lig, str):  # liggghts is not on PATH
            entry["liggghts"] = {**header.stamp(invocation=invocation), "skipped": lig}
        elif lig is not None:  # dated at its start
            half = liggghts_entry(name, case, lig, changes)
            entry["liggghts"] = {"date": lig.date, "invocation": invocation, **half}
        if dem is not None:
            stamp = {"date": dem.date, "invocation": invocation}
            stamp["git_commit"] = provenance.git_commit()  # None for an exported tree
            stamp["dem_package"] = str(Path(provenance.__file__).resolve().parent)
            entry["dem"] = {**stamp, **dem_entry(name, case, dem)}
        base = results["cases"].get(name.split("-curvature")[0], {})
        if "dem" not in entry and "dem" in base:  # a LIGGGHTS variant against dem's run
            entry["dem_of"] = name.split("-curvature")[0]
            compare(entry, base["dem"])
        else:
            compare(entry)
        if "difference" in entry:
            d = entry["difference"]
            print(f"  dem - L = {d['percent_of_liggghts']:+.2f} % ({d['sigma']:+.2f} sigma)")
        results["cases"][name] = entry
        path.write_text(json.dumps(results, indent=2) + "\n")  # after each case
    refresh(results)
    results["pooled"] = pooled(results)
    path.write_text(json.dumps(results, indent=2) + "\n")
    plot(results)
    print(f"wrote {path}, velocity.png")


if __name__ == "__main__":
    main()
