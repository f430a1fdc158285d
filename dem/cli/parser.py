"""The ``dem`` argument parser: every command, option and help text."""

import argparse

from dem import __version__
from dem.cli import commands as c
from dem.cli.options import ALLOWED, WHOLE, WHOLE_FROM_0, Parser, number
from dem.config import DEM_EXPORT_SETTLE_CYCLES
from dem.quantities import QUANTITIES

#: ``--device`` choices: :data:`dem.scene.schema.DEVICES`, written out here because importing the
#: schema imports numba, which would slow every command's start (tests/engine/test_device.py
#: checks that the two agree).
DEVICES = ("cpu", "cuda")


def add_material(p: argparse.ArgumentParser, *, angle_required: bool = True) -> None:
    """The material options every point-mass command takes (mu, phi, alpha)."""
    if angle_required:
        p.add_argument("--angle", type=number, required=True, help=ALLOWED["--angle"])
    p.add_argument("--friction", type=number, required=True, help=ALLOWED["--friction"])
    p.add_argument("--inclination", type=number, default=0.0, help=ALLOWED["--inclination"])


def add_restitution(p: argparse.ArgumentParser) -> None:
    """The restitution options (eps_n, eps_t)."""
    p.add_argument("--eps-t", type=number, default=0.8, help=ALLOWED["--eps-t"])
    p.add_argument("--eps-n", type=number, default=0.0, help=ALLOWED["--eps-n"])
    add_impact(p)


def add_impact(p: argparse.ArgumentParser) -> None:
    """The impact-law options (Coulomb bound)."""
    p.add_argument(
        "--impact",
        choices=("paper", "coulomb"),
        default="paper",
        help="landing law: 'paper' (Eq. 12: v_t times eps_t) or 'coulomb' (that change capped "
        "at mu (1 + eps_n) v_n, as any friction contact: the DEM's reference)",
    )


def add_device(p: argparse.ArgumentParser) -> None:
    """The engine option of the commands that run or plan DEM (beside ``--threads``)."""
    p.add_argument(
        "--device", choices=DEVICES,
        help="engine: cpu (numba, the default) or cuda (numba.cuda on a GPU); overrides "
        "run.device",
    )  # fmt: skip


def pointmass_parser(sub) -> None:
    """The ``dem pointmass`` commands and their options."""
    pm = sub.add_parser("pointmass", help="the paper's point-mass model")
    pms = pm.add_subparsers(dest="pm_command", required=True, parser_class=Parser)

    p = pms.add_parser("thresholds", help="throw numbers where sliding and flight begin")
    add_material(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_thresholds)

    p = pms.add_parser("velocity", help="mean conveying velocity of the steady motion")
    p.add_argument("--throw-number", type=number, required=True, help=ALLOWED["--throw-number"])
    add_material(p)
    add_restitution(p)
    p.add_argument("--frequency", type=number,
                   help="also give the velocity in m/s at this drive frequency f, Hz; "
                   + QUANTITIES["frequency"].allowed)  # fmt: skip
    p.add_argument(
        "--grain",
        choices=("point", "rolling-sphere"),
        default="point",
        help="point: the paper's point mass (default); rolling-sphere: a round grain "
        "free to roll, the reference of spheres whose rotation is free "
        "(dem.pointmass.rolling; its landings Coulomb-bounded unless --impact paper)",
    )
    p.add_argument(
        "--inertia-factor",
        type=number,
        help="rolling-sphere: I / (m r^2), default 0.4 (a solid sphere); "
        + QUANTITIES["inertia_factor"].allowed,
    )
    p.add_argument(
        "--landing",
        choices=("centre", "contact"),
        help="rolling-sphere: eps_t of the centre's velocity, never past rolling "
        "(centre, the default: the DEM's law) or of the contact point's slip",
    )
    p.add_argument("--bulk", metavar="SHAPE", help="also the atlas's estimate of a bed of "
                   "these grains (sphere, screw) on this drive: dem atlas's table, interpolated, "
                   "never extrapolated")  # fmt: skip
    p.add_argument("--depth", type=number, metavar="LAYERS",
                   help="--bulk: the bed's depth in grain layers (particles.layers)")  # fmt: skip
    p.add_argument("--atlas", metavar="CSV", help="--bulk: an atlas.csv of dem atlas (default: "
                   "the shipped one, dem/data/atlas)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_velocity, impact=None)  # --impact's default depends on --grain

    p = pms.add_parser(
        "sweep",
        help="velocities over a grid (CSV)",
        description="Each option takes a value, a comma list, or start:stop:step; the CSV "
        "has one row per combination.",
    )
    p.add_argument("--throw-number", required=True, help="Gamma values")
    p.add_argument("--angle", required=True, help="phi values, degrees")
    p.add_argument("--friction", required=True, help="mu values")
    p.add_argument("--inclination", default="0", help="alpha values, degrees")
    p.add_argument("--eps-t", default="0.8", help="eps_t values")
    p.add_argument("--eps-n", default="0", help="eps_n values")
    add_impact(p)
    p.add_argument("--out", help="CSV file (default: standard output)")
    p.set_defaults(func=c.cmd_sweep)

    p = pms.add_parser(
        "optimum",
        help="optimum vibration angle or throw number, stating what is held fixed",
        description="--over angle --hold throw_number|amplitude|acceleration, or "
        "--over throw_number --hold frequency|amplitude|drive_velocity.",
    )
    p.add_argument("--over", choices=("angle", "throw_number"), required=True)
    p.add_argument(
        "--hold",
        required=True,
        choices=("throw_number", "amplitude", "acceleration", "frequency", "drive_velocity"),
    )
    p.add_argument("--angle", type=number, help=ALLOWED["--angle"] + " (over throw_number)")
    add_material(p, angle_required=False)
    add_restitution(p)
    p.add_argument("--throw-number", type=number, help=ALLOWED["--throw-number"])
    p.add_argument("--amplitude", type=number, help=ALLOWED["--amplitude"])
    p.add_argument("--peak-acceleration", type=number, help=ALLOWED["--peak-acceleration"])
    p.add_argument("--drive-velocity", type=number, help=ALLOWED["--drive-velocity"])
    p.add_argument("--frequency", type=number, default=60.0, help=ALLOWED["--frequency"])
    p.add_argument("--bounds", help="LOW:HIGH of the scanned variable")
    p.add_argument("--plot", help="write a PNG of the scanned curve: a .png file name, or an "
                   "existing folder to write optimum.png in")  # fmt: skip
    p.add_argument("--curve", action="store_true", help="include the scanned curve in --json")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_optimum)


# --- dem run / export ---------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """The full ``dem`` argument parser."""
    parser = Parser(
        prog="dem",
        description="Granular material on vibratory conveyors: point-mass model and DEM.",
    )
    parser.add_argument("--version", action="version", version=f"dem {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    pointmass_parser(sub)

    p = sub.add_parser("run", help="run a case directory (DEM)")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument("--out", help="output directory (default CASE_DIR/output)")
    p.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. drive.angle=30 (repeatable; recorded in "
        "summary.json)",
    )  # fmt: skip
    p.add_argument("--cycles", type=WHOLE, help="measured cycles (overrides run.cycles)")
    p.add_argument("--threads", type=WHOLE, help="numba threads (default: all cores)")
    add_device(p)
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--overwrite", action="store_true", help="replace an earlier run in --out")
    mode.add_argument("--resume", action="store_true", help="continue an interrupted run")
    p.add_argument("--no-frames", action="store_true", help="write no VTK/HDF5 particle frames")
    p.add_argument(
        "--lab-frame", action="store_true", help="VTK frames in the lab frame (trough shakes)"
    )
    p.add_argument(
        "--replicas", type=WHOLE, help="independent fills pooled (overrides run.replicas)"
    )
    p.add_argument(
        "--all-replicas", action="store_true",
        help="keep every replica's frames and results.h5 (default: replica 0's only)",
    )  # fmt: skip
    p.add_argument(
        "--target-error", type=number, metavar="FRACTION",
        help="pool fills until the standard error is this fraction of |v_norm| (overrides "
        "run.target_error), e.g. 0.02",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print summary.json's object")
    p.set_defaults(func=c.cmd_run)

    p = sub.add_parser(
        "plan", help="cost, memory, expected error and advice for a case, without running it"
    )
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. drive.angle=30 (repeatable)",
    )  # fmt: skip
    p.add_argument("--cycles", type=WHOLE, help="measured cycles (overrides run.cycles)")
    p.add_argument("--threads", type=WHOLE, help="numba threads (default: all cores)")
    add_device(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--suggest", metavar="OUT_DIR",
        help="write the case the advice recommends (every advice with a value applied) into "
        "OUT_DIR, a new folder",
    )  # fmt: skip
    p.set_defaults(func=c.cmd_plan)

    p = sub.add_parser("sweep", help="run a grid of cases on Dask and gather one table")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument(
        "--set", action="append", required=True, metavar="TABLE.KEY=VALUES",
        help="swept key: a value, a comma list or start:stop:step (stop included); repeat the "
        "option for a grid",
    )  # fmt: skip
    p.add_argument("--out", help="sweep folder (default CASE_DIR/sweep), one folder per point")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: local)")
    p.add_argument("--workers", type=WHOLE, help="local workers (default: one per core)")
    p.add_argument("--threads", type=WHOLE, help="numba threads per point (default 1)")
    add_device(p)
    p.add_argument("--cycles", type=WHOLE, help="measured cycles (overrides run.cycles)")
    p.add_argument("--frames", action="store_true", help="write VTK/HDF5 frames for every point")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_dem_sweep)

    p = sub.add_parser(
        "atlas", help="the bulk against the point mass over a grid file, resumable, each point "
        "to a target error",
    )  # fmt: skip
    p.add_argument("grid", metavar="GRID", help="grid file (TOML): [atlas] and [[grid]] blocks")
    p.add_argument("--out", help="atlas folder (default: beside GRID, named after it)")
    p.add_argument("--workers", type=WHOLE, help="points at once on a local Dask cluster "
                   "(default 1: one point at a time, its fills on the cores)")  # fmt: skip
    p.add_argument("--scheduler", help="address of a running dask scheduler")
    p.add_argument("--threads", type=WHOLE, help="cores one point's fills share (default: all)")
    add_device(p)
    p.add_argument("--rerun-stale", action="store_true", help="move points run with another "
                   "case or settings to OUT/stale/ and run them again")  # fmt: skip
    p.add_argument("--dry-run", action="store_true", help="count the points and stop")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_dem_atlas)

    p = sub.add_parser("optimum", help="the bulk optimum angle (or throw number) of a case")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument("--over", required=True, choices=("drive.angle", "drive.throw_number"))
    p.add_argument("--hold", default="throw_number", help="held fixed: throw_number or "
                   "amplitude over drive.angle; frequency over drive.throw_number")  # fmt: skip
    p.add_argument("--bounds", help="LO:HI of the search (default 10:60 deg, Gamma 0.5:4)")
    p.add_argument("--tolerance", type=number, help="bracket half-width to stop at "
                   "(default 1 deg, Gamma 0.05); " + QUANTITIES["tolerance"].allowed)  # fmt: skip
    runs = "most DEM runs (default 20); " + QUANTITIES["max_runs"].allowed
    p.add_argument("--max-runs", type=WHOLE, default=20, help=runs)
    p.add_argument("--out", help="output folder (default CASE_DIR/optimum)")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: local)")
    p.add_argument("--workers", type=WHOLE, help="local workers (default: one per core)")
    p.add_argument("--cycles", type=WHOLE, help="measured cycles per run (overrides run.cycles)")
    p.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml at every run, e.g. material.friction=0.5 "
        "(repeatable; not the --over key)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=c.cmd_dem_optimum)

    p = sub.add_parser(
        "calibrate", help="fit the tangential contact to eps_t by virtual impacts (writes case)"
    )
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument("--dry-run", action="store_true", help="print and plot, change nothing")
    p.add_argument(
        "--plot",
        help="eps_t figure: a .png file name, or an existing folder to "
        "write calibration.png in (default CASE_DIR/output/calibration.png)",
    )
    p.add_argument(
        "--strict",
        action="store_true",
        help="exit 1 when an impact stays more than 0.02 from its reachable target "
        "(default: write the closest fit and exit 0)",
    )
    p.add_argument("--json", action="store_true", help="print the fit as one JSON object")
    p.set_defaults(func=c.cmd_calibrate)

    p = sub.add_parser("report", help="figures and a summary of one or more finished runs")
    p.add_argument("out_dirs", nargs="+", help="run output folders (holding summary.json)")
    p.add_argument(
        "--out",
        "--dest",
        dest="dest",
        help="where to write the report (default OUT/report); --dest is an alias",
    )
    p.add_argument("--atlas", metavar="CSV",
                   help="an atlas.csv of dem atlas to draw the run's drive on (default: the "
                   "shipped atlas, where there is one)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print the files written as JSON")
    p.set_defaults(func=c.cmd_report)

    p = sub.add_parser("export", help="export a case to another code")
    es = p.add_subparsers(dest="export_command", required=True, parser_class=Parser)
    e = es.add_parser("liggghts", help="write an equivalent LIGGGHTS-PUBLIC 3.8 deck")
    e.add_argument("case_dir")
    e.add_argument("out_dir")
    e.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. drive.angle=30 (repeatable)",
    )  # fmt: skip
    _deck_options(e)
    e.add_argument(
        "--no-dump",
        action="store_true",
        help="no particle dump (default: output.frames_per_cycle a cycle)",
    )
    e.add_argument(
        "--overwrite", action="store_true",
        help="replace a deck already in OUT_DIR (in.dem, grain.multisphere, trough.stl)",
    )  # fmt: skip
    e.add_argument("--run", action="store_true", help="run the deck in LIGGGHTS (on PATH) and "
                   "write OUT_DIR/summary.json as dem run reports one")  # fmt: skip
    e.add_argument("--json", action="store_true", help="print the deck (and with --run the "
                   "run's summary) as one JSON object")  # fmt: skip
    e.set_defaults(func=c.cmd_export_liggghts)

    e = es.add_parser("lammps", help="write a LAMMPS deck (pair granular) and optionally run it")
    e.add_argument("case_dir")
    e.add_argument("out_dir")
    e.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. contact.tangential=coulomb (repeatable)",
    )  # fmt: skip
    _deck_options(e)
    e.add_argument("--overwrite", action="store_true",
                   help="replace a deck already in OUT_DIR (in.lammps, data.fill)")  # fmt: skip
    e.add_argument("--run", action="store_true",
                   help="run the deck in LAMMPS and write OUT_DIR/summary.json")  # fmt: skip
    e.add_argument("--ranks", type=WHOLE, default=1, help="MPI ranks for --run (default 1)")
    e.add_argument("--json", action="store_true", help="print the deck (and with --run the "
                   "run's summary) as one JSON object")  # fmt: skip
    e.add_argument(
        "--fill", choices=("dem", "lammps"), default="dem",
        help="who fills the trough: dem (settled here, data.fill; default) or lammps (the deck "
        "pours and settles its own with fix pour)",
    )  # fmt: skip
    e.set_defaults(func=c.cmd_export_lammps)
    return parser


def _deck_options(e) -> None:
    """The step and settling options every exported deck takes."""
    e.add_argument("--timestep", type=number, help="dt in s (default: dem's for this case)")
    e.add_argument(
        "--settle-cycles", type=WHOLE_FROM_0,
        help="driven cycles before measuring (default: the case's; for \"auto\" what an earlier "
        f"dem run detected, else {DEM_EXPORT_SETTLE_CYCLES})",
    )  # fmt: skip
    e.add_argument("--from-run", metavar="RUN_DIR",
                   help='the dem run whose detected settling an "auto" case takes '
                   "(default CASE_DIR/output)")  # fmt: skip
