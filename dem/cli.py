"""The ``dem`` command: parses arguments, calls the library, prints. No physics here.

Every error the user can fix ends with exit status 2 and one line naming the option (or case
key), the value and what is allowed; nothing is computed before the inputs are checked.
"""

import argparse
import math
import os
import sys
import warnings
from pathlib import Path

from dem import __version__
from dem.config import DEM_EXPORT_SETTLE_CYCLES
from dem.errors import InputError, SimulationError
from dem.io.files import replace_file, replace_text
from dem.quantities import QUANTITIES

EXIT_USAGE = 2

#: The quantity (:data:`dem.quantities.QUANTITIES`) of each numeric option: its range.
_QUANTITY_OF = {
    "--throw-number": "throw_number",
    "--angle": "angle",
    "--friction": "friction",
    "--inclination": "inclination",
    "--frequency": "frequency",
    "--amplitude": "amplitude",
    "--peak-acceleration": "peak_acceleration",
    "--drive-velocity": "drive_velocity",
    "--eps-t": "restitution",
    "--eps-n": "restitution",
    "--cycles": "cycles",
    "--threads": "threads",
    "--replicas": "replicas",
    "--workers": "workers",
    "--max-runs": "max_runs",
    "--tolerance": "tolerance",
}

#: Allowed values of each numeric option, used in error messages.
#: Help and "missing option" texts of the options, from the one table of quantities.
_ALLOWED = {_option: QUANTITIES[_name].help for _option, _name in _QUANTITY_OF.items()} | {
    "--eps-t": "tangential " + QUANTITIES["restitution"].help,
    "--eps-n": "normal " + QUANTITIES["restitution"].help,
}


def _check_numbers(args) -> None:
    """Every numeric option given to this command against its range, before any work.

    An option out of range is an :class:`InputError` naming the option (``--frequency``), the
    value and the range, whether or not the command goes on to use it (an option the chosen
    ``--hold`` ignores is a typing error all the same). Options holding value lists
    (``dem pointmass sweep``) are checked value by value where they are parsed.
    """
    for option, name in _QUANTITY_OF.items():
        value = getattr(args, option[2:].replace("-", "_"), None)
        if isinstance(value, int | float) and not isinstance(value, bool):
            QUANTITIES[name].check(value, option)


def _plot_path(text: str, default_name: str) -> Path:
    """The path ``--plot`` names, refused by option before any work if it cannot be one.

    A .png file name (any case) is taken as it is; an existing folder gets ``default_name``
    inside it; anything else is refused, since matplotlib would write it with .png added.
    """
    path = Path(text)
    if path.is_dir():
        path = path / default_name
    elif path.suffix.lower() != ".png":
        raise InputError("--plot", text, f"a .png file name, or an existing folder to write "
                         f"{default_name} in")  # fmt: skip
    return _writable_path("--plot", path, folder=False)


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit with status 2."""

    def error(self, message: str) -> None:  # noqa: D102
        prefix = "the following arguments are required: "
        if message.startswith(prefix):
            names = [n.strip() for n in message[len(prefix) :].split(",")]
            parts = [f"{n} ({_ALLOWED[n]})" if n in _ALLOWED else n for n in names]
            message = "missing option " + ", ".join(parts)
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _format_warning(message, category, filename, lineno, line=None) -> str:
    """One line per warning, as the command line's errors are: ``dem: warning: ...``."""
    return f"dem: warning: {message}\n"


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"value {text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"value {text!r} is not a finite number")
    return value


def _whole_from(minimum: int):
    """An argparse type: a whole number >= ``minimum``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"value {text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"value {value} must be >= {minimum}")
        return value

    return parse


_whole = _whole_from(1)
_whole0 = _whole_from(0)


def _option_name(key: str) -> str:
    return "--" + key.replace("_", "-")


#: Longest file name and path the guards accept (Linux NAME_MAX and PATH_MAX).
NAME_MAX, PATH_MAX = 255, 4096


def _writable_path(key: str, path: str | Path, *, folder: bool) -> Path:
    """``path`` as an output file (``folder`` False) or folder, refused before any work.

    Refused with the key and the cause: a file where a folder is wanted or the reverse, a name
    or path longer than the system allows, or a nearest existing folder that is not writable.
    A file's parent folder must exist (dem does not create it); a folder is created later.
    """
    path = Path(path)
    if len(str(path.absolute())) >= PATH_MAX or any(len(part) > NAME_MAX for part in path.parts):
        raise InputError(key, str(path), f"a path the system allows (names <= {NAME_MAX} "
                         f"characters, paths < {PATH_MAX})")  # fmt: skip
    if path.exists() and path.is_dir() != folder:
        what = "a folder (this is a file)" if folder else "a file name (this is a folder)"
        raise InputError(key, str(path), what)
    parent = path if folder else path.parent
    if not folder and not parent.absolute().is_dir():
        raise InputError(key, str(path), f"a file in an existing folder ({parent} does not exist)")
    base = parent.absolute()
    while not base.exists():
        base = base.parent
    if not base.is_dir():
        raise InputError(key, str(path), f"a path under a folder ({base} is a file)")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(key, str(path), f"a writable place ({base} is not writable)")
    return path


def _print_json(obj) -> None:
    from dem.io.files import json_text

    print(json_text(obj, indent=2, default=_json_default))


def _json_default(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot serialise {type(value).__name__}")


# --- dem pointmass ------------------------------------------------------------------------------


def _add_material(p: argparse.ArgumentParser, *, angle_required: bool = True) -> None:
    if angle_required:
        p.add_argument("--angle", type=_number, required=True, help=_ALLOWED["--angle"])
    p.add_argument("--friction", type=_number, required=True, help=_ALLOWED["--friction"])
    p.add_argument("--inclination", type=_number, default=0.0, help=_ALLOWED["--inclination"])


def _add_restitution(p: argparse.ArgumentParser) -> None:
    p.add_argument("--eps-t", type=_number, default=0.8, help=_ALLOWED["--eps-t"])
    p.add_argument("--eps-n", type=_number, default=0.0, help=_ALLOWED["--eps-n"])
    _add_impact(p)


def _add_impact(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--impact",
        choices=("paper", "coulomb"),
        default="paper",
        help="landing law: 'paper' (Eq. 12: v_t times eps_t) or 'coulomb' (that change capped "
        "at mu (1 + eps_n) v_n, as any friction contact: the DEM's reference)",
    )


def _cmd_thresholds(args) -> int:
    from dem import pointmass

    _check_numbers(args)
    t = pointmass.thresholds(args.angle, args.friction, args.inclination)
    result = {
        "angle": args.angle,
        "friction": args.friction,
        "inclination": args.inclination,
        "forward_sliding": t.forward_sliding,
        "backward_sliding": t.backward_sliding,
        "flight": t.flight,
    }
    if args.json:
        _print_json(result)
    else:
        back = "never" if t.backward_sliding is None else f"{t.backward_sliding:.4f}"
        print(f"forward sliding  Gamma > {t.forward_sliding:.4f}   (Eq. 1)")
        print(f"backward sliding Gamma > {back}   (Eq. 2)")
        print(f"flight           Gamma >= {t.flight:.4f}   (Eq. 4)")
    return 0


def _cmd_velocity(args) -> int:
    from dem import pointmass

    _check_numbers(args)
    r = pointmass.velocity(
        args.throw_number, args.angle, args.friction, args.inclination, args.eps_t, args.eps_n,
        impact=args.impact,
    )  # fmt: skip
    result = r.as_dict()
    if args.frequency is not None:
        result["frequency"] = args.frequency
        result["velocity"] = r.velocity(args.frequency)
        result["amplitude"] = pointmass.amplitude_from_throw_number(
            r.throw_number, r.angle, r.inclination, args.frequency
        )
    if args.json:
        _print_json(result)
        return 0
    print(f"velocity_norm  {r.velocity_norm:.6f}   (v / (A omega cos phi))")
    if args.frequency is not None:
        print(f"velocity       {result['velocity']:.6g} m/s at {args.frequency:g} Hz")
    print(f"regime         {r.regime}")
    print(f"impact         {r.impact}")
    if r.periodic:
        print(f"periodic       yes, period {r.period} cycle(s), settled after {r.cycles}")
    else:
        print(
            f"periodic       no: mean over starting phases, spread {r.spread:.3g} "
            f"(range {r.velocity_min:.4f} .. {r.velocity_max:.4f})"
        )
    print(
        f"phases         stick {r.stick:.3f}  forward {r.slide_forward:.3f}  "
        f"backward {r.slide_backward:.3f}  flight {r.flight:.3f} (fractions of a cycle)"
    )
    return 0


def _cmd_sweep(args) -> int:
    from dem.pointmass.sweep import parse_values, sweep, write_csv

    values = {
        key: parse_values(getattr(args, key), _option_name(key))
        for key in ("throw_number", "angle", "friction", "inclination", "eps_t", "eps_n")
    }
    if args.out:
        _writable_path("--out", args.out, folder=False)
    result = sweep(**values, impact=args.impact)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as stream:
            write_csv(result, stream)
        print(f"wrote {len(result['velocity_norm'])} rows to {args.out}", file=sys.stderr)
    else:
        write_csv(result, sys.stdout)
    return 0


def _cmd_optimum(args) -> int:
    from dem.pointmass.sweep import optimum

    _check_numbers(args)
    bounds = None
    if args.bounds:
        try:  # each a number ("10,20:30" took 10 and dropped 20)
            lo, hi = (float(p) for p in args.bounds.split(":"))
        except ValueError:
            raise InputError("--bounds", args.bounds, "LOW:HIGH, two numbers") from None
        bounds = (lo, hi)
    plot = _plot_path(args.plot, "optimum.png") if args.plot else None
    o = optimum(
        args.over,
        args.hold,
        friction=args.friction,
        angle=args.angle,
        throw_number=args.throw_number,
        amplitude=args.amplitude,
        peak_acceleration=args.peak_acceleration,
        drive_velocity=args.drive_velocity,
        frequency=args.frequency,
        inclination=args.inclination,
        eps_t=args.eps_t,
        eps_n=args.eps_n,
        bounds=bounds,
        impact=args.impact,
    )
    if plot is not None:
        from dem.studies.plots import optimum_figure

        optimum_figure(o, plot)
        print(f"wrote {plot}", file=sys.stderr)
    if args.json:
        _print_json(o.as_dict(with_curve=args.curve))
        return 0
    unit = "deg" if args.over == "angle" else ""
    held = ", ".join(
        f"{k} = {v:g}" if isinstance(v, int | float) else f"{k} = {v}" for k, v in o.held.items()
    )
    print(f"optimum {args.over}: {o.value:.3f} {unit}  (holding {args.hold}; {held})")
    print(f"maximises      {o.objective}")
    print(f"velocity       {o.velocity:.5g} m/s   velocity_norm {o.velocity_norm:.5f}")
    print(
        f"drive          Gamma {o.throw_number:.4g}, phi {o.angle:.3g} deg, "
        f"A {o.amplitude * 1e3:.4g} mm, f {o.frequency:.4g} Hz"
    )
    print(f"regime         {o.regime}")
    print(f"within 90%     {o.plateau[0]:.3g} .. {o.plateau[1]:.3g} {unit}")
    return 0


def _pointmass_parser(sub) -> None:
    pm = sub.add_parser("pointmass", help="the paper's point-mass model")
    pms = pm.add_subparsers(dest="pm_command", required=True, parser_class=_Parser)

    p = pms.add_parser("thresholds", help="throw numbers where sliding and flight begin")
    _add_material(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_thresholds)

    p = pms.add_parser("velocity", help="mean conveying velocity of the steady motion")
    p.add_argument("--throw-number", type=_number, required=True, help=_ALLOWED["--throw-number"])
    _add_material(p)
    _add_restitution(p)
    p.add_argument("--frequency", type=_number,
                   help="also give the velocity in m/s at this drive frequency f, Hz; "
                   + QUANTITIES["frequency"].allowed)  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_velocity)

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
    _add_impact(p)
    p.add_argument("--out", help="CSV file (default: standard output)")
    p.set_defaults(func=_cmd_sweep)

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
    p.add_argument("--angle", type=_number, help=_ALLOWED["--angle"] + " (over throw_number)")
    _add_material(p, angle_required=False)
    _add_restitution(p)
    p.add_argument("--throw-number", type=_number, help=_ALLOWED["--throw-number"])
    p.add_argument("--amplitude", type=_number, help=_ALLOWED["--amplitude"])
    p.add_argument("--peak-acceleration", type=_number, help=_ALLOWED["--peak-acceleration"])
    p.add_argument("--drive-velocity", type=_number, help=_ALLOWED["--drive-velocity"])
    p.add_argument("--frequency", type=_number, default=60.0, help=_ALLOWED["--frequency"])
    p.add_argument("--bounds", help="LOW:HIGH of the scanned variable")
    p.add_argument("--plot", help="write a PNG of the scanned curve: a .png file name, or an "
                   "existing folder to write optimum.png in")  # fmt: skip
    p.add_argument("--curve", action="store_true", help="include the scanned curve in --json")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_optimum)


# --- dem run / export ---------------------------------------------------------------------------


def _cmd_run(args) -> int:
    from dem.run.replicas import run_replicas
    from dem.run.runner import RunInterrupted
    from dem.scene.case import load_case

    overrides = _set_overrides(args.set)
    if args.replicas is not None:
        overrides["run.replicas"] = args.replicas
    case = load_case(args.case_dir, overrides)
    out = _writable_path("--out", args.out or case.directory / "output", folder=True)
    try:
        summary = run_replicas(
            case, out, cycles=args.cycles, threads=args.threads, progress=True,
            overwrite=args.overwrite, resume=args.resume, frames=not args.no_frames,
            lab_frame=args.lab_frame, all_replicas=args.all_replicas,
        )  # fmt: skip
    except RunInterrupted as stop:
        print(f"dem: stopped by {stop}", file=sys.stderr)
        if stop.checkpoint is not None:
            print(f"dem: continue with: {_resume_command(args, case, out)}", file=sys.stderr)
        return 128 + stop.signum
    _print_summary(summary)
    print(f"wrote {out / 'summary.json'}")
    return 0


def _print_summary(s: dict) -> None:
    """The answer of a run, each value with its unit and the digits its error allows."""
    from dem.physics.measure import with_error
    from dem.studies.report import feeder_lines

    def line(label: str, text: str) -> None:
        print(f"{label:<18s} {text}")

    line("mean velocity", with_error(s["mean_velocity"], s["mean_velocity_stderr"], "m/s"))
    line("normalised", with_error(s["mean_velocity_norm"], s["mean_velocity_norm_stderr"])
         + "  (v / A omega cos phi)")  # fmt: skip
    if s.get("replicas", 1) > 1:
        line("error bar", f"{s['replicas']} fills pooled, fill-to-fill spread included (95 %: "
             f"+- {s['mean_velocity_ci95']:.2g} m/s; spread between fills "
             f"{s['replica_spread']:.2g} m/s)")  # fmt: skip
    else:
        line("error bar", "this run only: it excludes the fill-to-fill spread (pool fills "
             "with --replicas N)")  # fmt: skip
    paper, bounded = s.get("pointmass_velocity_norm"), s.get("pointmass_bounded_velocity_norm")
    if paper is not None:
        text = f"{paper:.3f} (paper's model)"
        if bounded is not None and abs(bounded - paper) > 5e-4:
            text += f", {bounded:.3f} (Coulomb-bounded, the DEM's reference)"
        line("point mass", text + " in v_norm")
    flow = with_error(s["mass_flow_rate"], s.get("mass_flow_rate_stderr")
                      or abs(s["mass_flow_rate"] * s["mean_velocity_stderr"]
                             / (s["mean_velocity"] or float("nan"))), "kg/s")  # fmt: skip
    line("mass flow", f"{flow} through the section ({s['mass_flow_rate_per_width']:.3g} kg/s "
         "per m of width)")  # fmt: skip
    for text in feeder_lines(s.get("feeder")):  # the discharge: a feeder's answer
        print(text)
    stiff = s.get("stiffness")
    if stiff:
        sign = "<=" if stiff["converged"] else ">"
        ratio = f"(omega / omega_bed)^2 = {stiff['compliance']:.2g} {sign} "
        ratio += f"{stiff['compliance_limit']:.2g}"
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


def _resume_command(args, case, out: Path) -> str:
    """The ``dem run`` line that resumes this run: every option a resume must repeat.

    The folder, the ``--set`` keys, the measured cycles (a resume is refused with others) and
    the frames setting (``--no-frames``, ``--lab-frame``), and the threads if they were given.
    """
    import shlex

    parts = ["dem", "run", str(args.case_dir), "--out", str(out), "--resume"]
    for text in args.set or ():
        parts += ["--set", text]
    parts += ["--cycles", str(args.cycles if args.cycles is not None else case.run.cycles)]
    if args.no_frames:
        parts.append("--no-frames")
    if args.lab_frame:
        parts.append("--lab-frame")
    if args.threads is not None:
        parts += ["--threads", str(args.threads)]
    if args.replicas is not None:
        parts += ["--replicas", str(args.replicas)]
    if args.all_replicas:
        parts.append("--all-replicas")
    return shlex.join(parts)


def _set_overrides(texts: list[str] | None) -> dict:
    """``--set table.key=value`` options as load_case overrides.

    One value per key: several values are a sweep (``dem sweep``).
    """
    from dem.studies.sweep import parse_set

    overrides: dict = {}
    for text in texts or ():
        key, values = parse_set(text)
        if len(values) != 1:
            many = text.partition("=")[2]
            raise InputError(f"--set {key}", many, "one value (several: dem sweep takes them)")
        if key in overrides:
            raise InputError("--set", key, "each key at most once")
        overrides[key] = values[0]
    return overrides


def _cmd_plan(args) -> int:
    from dem.run.plan import plan
    from dem.scene.case import load_case

    overrides = _set_overrides(args.set)
    if args.suggest:
        from dem.run.plan import suggest

        done = suggest(args.case_dir, args.suggest, overrides, threads=args.threads,
                       cycles=args.cycles)  # fmt: skip
        if args.json:
            before, after = done.before.as_dict(), done.after.as_dict()
            _print_json({"path": str(done.path), "changes": done.changes, "before": before,
                         "after": after})  # fmt: skip
        else:
            print(done.text())
        return 0
    case = load_case(args.case_dir, overrides)
    result = plan(case, threads=args.threads, cycles=args.cycles)
    if args.json:
        _print_json(result.as_dict())
    else:
        print(result.text())
    return 0


def _cmd_dem_sweep(args) -> int:
    from dem.studies.sweep import parse_set, run_sweep

    _check_numbers(args)
    sets = [parse_set(text) for text in args.set]
    out = _writable_path("--out", args.out or Path(args.case_dir) / "sweep", folder=True)
    result = run_sweep(
        args.case_dir, sets, out, scheduler=args.scheduler, workers=args.workers,
        threads=args.threads or 1, cycles=args.cycles, frames=args.frames,
    )  # fmt: skip
    if args.json:
        _print_json(result)
    else:
        failed = len(result["failed"])
        print(f"{result['points']} points: {result['done']} done "
              f"({result['skipped']} from an earlier run), {failed} failed")  # fmt: skip
        print(f"wrote {result['csv']}, sweep.h5 and sweep.png")
    for name, error in result["failed"].items():
        print(f"dem: sweep point {name} failed: {error}", file=sys.stderr)
    return 1 if result["failed"] else 0


def _cmd_dem_optimum(args) -> int:
    from dem.studies.optimum import bulk_optimum

    _check_numbers(args)
    bounds = None
    if args.bounds:
        try:
            lo, hi = (float(v) for v in args.bounds.split(":"))
        except ValueError:
            raise InputError("--bounds", args.bounds, "LO:HI, two numbers") from None
        bounds = (lo, hi)
    out = _writable_path("--out", args.out or Path(args.case_dir) / "optimum", folder=True)
    result = bulk_optimum(
        args.case_dir, args.over, args.hold, out, bounds=bounds, tolerance=args.tolerance,
        max_runs=args.max_runs, scheduler=args.scheduler, workers=args.workers,
        cycles=args.cycles,
    )  # fmt: skip
    if args.json:
        _print_json(result)
    else:
        b, p = result["bulk"], result["pointmass"]
        print(f"bulk optimum {args.over} = {b['x']:.4g} +- {b['uncertainty']:.2g} "
              f"({result['objective']} {b['value']:.4g}; {b['reason']}; "
              f"{len(result['samples'])} runs)")  # fmt: skip
        print(f"point-mass optimum {args.over} = {p['value']:.4g} "
              f"(90 % plateau {p['plateau_90'][0]:.3g}-{p['plateau_90'][1]:.3g})")  # fmt: skip
        print(f"wrote {out / 'optimum.json'}, optimum.csv and optimum.png")
    return 0


def _cmd_report(args) -> int:
    from dem.studies.report import make_report

    for out in args.out_dirs:
        if not (Path(out) / "summary.json").is_file():
            raise InputError("OUT", out, "a run output folder holding summary.json")
    dest = _writable_path("--out", args.dest, folder=True) if args.dest else None
    paths = make_report([Path(p) for p in args.out_dirs], dest)
    for path in paths:
        print(f"wrote {path}")
    return 0


def _cmd_export_liggghts(args) -> int:
    from dem.io.liggghts import CLUMP_FILE, DECK_NAME, MESH_FILE, write_deck
    from dem.scene.case import load_case
    from dem.scene.resolved import resolve

    case = load_case(args.case_dir)
    # dem's own time step (explicit or automatic, checked against the stability limit), so
    # the deck integrates with the step a dem run of this case would take
    try:
        scene = resolve(case, timestep=args.timestep)
    except InputError as exc:
        if args.timestep is None:
            raise
        raise InputError("--timestep", args.timestep, exc.allowed) from None  # not the case's
    timestep = scene.step.dt
    steps = int(round(case.run.cycles / case.drive.frequency / timestep))
    settle, settle_note = _export_settle_cycles(args, case)
    settle_steps = round(settle / (case.drive.frequency * timestep))
    out = _writable_path("OUT_DIR", args.out_dir, folder=True)
    written = [n for n in (DECK_NAME, CLUMP_FILE, MESH_FILE) if (out / n).exists()]
    if written and not args.overwrite:
        raise InputError(
            "OUT_DIR", str(out), f"a folder without a deck: it holds {', '.join(written)}, "
            "which the export would replace (pass --overwrite to replace them)",
        )  # fmt: skip
    path = write_deck(
        scene, Path(args.out_dir), timestep=timestep, steps=steps, settle_steps=settle_steps,
        settle_note=settle_note, dump=not args.no_dump,
    )  # fmt: skip
    print(f"wrote {path} (dt = {timestep:.4g} s, {settle} settling and {case.run.cycles} measured "
          f"cycles, {steps} measured steps)")  # fmt: skip
    if settle_note:
        print(f"settle: {settle_note}")
    return 0


def _export_settle_cycles(args, case) -> tuple[int, str | None]:
    """Driven cycles before measuring in an exported deck, and a note where the case said "auto".

    ``--settle-cycles``, else the case's number; for "auto" the number an earlier ``dem run`` of
    this case detected (``--from-run``, else CASE_DIR/output), else
    :data:`dem.config.DEM_EXPORT_SETTLE_CYCLES`.
    """
    import json

    if args.settle_cycles is not None:
        return args.settle_cycles, None
    if case.run.settle_cycles is not None:
        return case.run.settle_cycles, None
    run_dir = Path(args.from_run) if args.from_run else case.directory / "output"
    path = run_dir / "summary.json"
    if path.is_file():
        try:
            s = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            s = None
        if isinstance(s, dict) and s.get("case") == case.name and s.get("settle_cycles_auto"):
            n = int(s["settle_cycles"])
            return n, (f'run.settle_cycles = "auto": {n} cycles, the transient dem run detected '
                       f"in {path}")  # fmt: skip
        if args.from_run:
            why = 'run.settle_cycles = "auto" (its summary.json says otherwise)'
            raise InputError("--from-run", str(run_dir), f"a dem run of {case.name} with {why}")
    elif args.from_run:
        raise InputError("--from-run", str(run_dir), "a finished dem run's folder (summary.json)")
    return DEM_EXPORT_SETTLE_CYCLES, (
        f'run.settle_cycles = "auto": {DEM_EXPORT_SETTLE_CYCLES} cycles, dem\'s default for a deck '
        "(no earlier dem run of the case reports its transient; the shipped cases' were 6-12 "
        "cycles); --settle-cycles N or --from-run RUN_DIR to choose"
    )


def _cmd_calibrate(args) -> int:
    import datetime

    from dem.physics.laws import TANGENTIAL_LAWS
    from dem.scene.case import CASE_FILE, load_case, set_contact_keys
    from dem.studies.calibrate import calibrate
    from dem.studies.plots import calibration_figure

    case = load_case(args.case_dir)
    plot = _plot_path(args.plot, "calibration.png") if args.plot else None
    source = case.directory / CASE_FILE
    print(
        f"dem calibrate {case.name}: eps_t target {case.wall_material.restitution_tangential:g}, "
        f"virtual impacts of one grain over the point mass's landings",
        file=sys.stderr,
    )

    import time

    trail = case.directory / "output" / "calibration_evaluations.csv"
    trail.parent.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    tried: list[tuple[float, float]] = []
    with open(trail, "w", encoding="utf-8") as fh:
        fh.write("evaluation,tangential_stiffness_ratio,mean_eps_t,target_eps_t\n")

    def progress(kappa, eps, done, total):
        """Each evaluation: count, ETA, and a row of the trail kept if the search is stopped."""
        tried.append((kappa, eps))
        with open(trail, "a", encoding="utf-8") as fh:
            fh.write(
                f"{done},{kappa:.6g},{eps:.6g},{case.wall_material.restitution_tangential:g}\n"
            )
        spent = time.perf_counter() - started
        eta = spent / done * max(total - done, 0)
        print(f"  [{done:2d}/{total}] k_t / k_n = {kappa:<10.4g} mean eps_t = {eps:.4f}   "
              f"{spent:.0f} s, at most {eta:.0f} s to go", file=sys.stderr)  # fmt: skip

    try:
        cal = calibrate(case, progress=progress)
    except KeyboardInterrupt:
        target = case.wall_material.restitution_tangential
        best = min(tried, key=lambda t: abs(t[1] - target), default=None)
        text = "" if best is None else (f"; the closest so far: k_t / k_n = {best[0]:.4g} "
                                        f"(mean eps_t {best[1]:.4f} for {target:g})")  # fmt: skip
        print(f"dem calibrate: stopped after {len(tried)} evaluations, case.toml unchanged; "
              f"every evaluation is in {trail}{text}", file=sys.stderr)  # fmt: skip
        return 130
    theta = cal.impacts[:, 0]
    print(f"impacts          {len(theta)}, incidence {theta.min():.1f}-{theta.max():.1f} deg")
    print("  incidence  speed   target  eps_t   residual")
    for (inc, speed), target, eps, bound in zip(
        cal.impacts, cal.targets, cal.after, cal.bounded, strict=True
    ):
        mark = "  friction-bound (Coulomb caps eps_t here)" if bound else ""
        print(f"  {inc:6.1f} deg {speed:5.3f}   {target:.4f}  {eps:.4f}  {eps - target:+.4f}{mark}")
    strict_fail = args.strict and not cal.reachable
    if not cal.fitted:
        print(
            f"nothing to fit     {TANGENTIAL_LAWS[case.contact.tangential].calibration}; "
            f"weighted rms residual {cal.deviation:.4f}"
        )
    else:
        print(
            f"before           mean eps_t = {cal.before.mean():.4f}, weighted rms deviation "
            f"{cal.deviation_before:.4f}"
        )
        print(f"after            k_t / k_n = {cal.kappa:.6g}, zeta_t = {cal.zeta_t:g}")
        spread = f"{cal.eps_t:.4f} +- {cal.eps_t_spread:.4f}"
        print(f"                 eps_t = {spread}, eps_n = {cal.eps_n:.4f}")
        print(f"                 weighted rms deviation {cal.deviation:.4f} (the fit minimises it)")
    print(f"residual         {cal.residual:+.4f} (mean eps_t - mean reachable target)")
    if not cal.reachable:
        print(
            f"dem calibrate: {'no k_t / k_n brings' if cal.fitted else 'the law does not bring'} "
            f"every impact within 0.02 of its target (worst {cal.worst:.4f}); "
            + ("the closest fit is written. " if cal.fitted and not args.dry_run else "")
            + ("--strict: exit 1" if args.strict else "use --strict to fail on this"),
            file=sys.stderr,
        )
    if plot is None:
        plot = case.directory / "output" / "calibration.png"
        plot.parent.mkdir(parents=True, exist_ok=True)
    calibration_figure(cal, case.wall_material.friction, plot)
    print(f"wrote {plot}")
    if not cal.fitted:
        print("case.toml unchanged: nothing to calibrate")
        return 1 if strict_fail else 0
    if args.dry_run:
        print("dry run: case.toml unchanged")
        return 1 if strict_fail else 0
    stamp = datetime.date.today().isoformat()
    text = set_contact_keys(
        source,
        {
            "tangential_stiffness_ratio": float(f"{cal.kappa:.6g}"),
            "tangential_damping_ratio": cal.zeta_t,
        },
        f"dem calibrate {stamp}: eps_t {cal.eps_t:.3f} for {cal.target:g} at Gamma "
        f"{case.drive.throw_number:.6g}, phi {case.drive.angle:g} deg, mu "
        f"{case.wall_material.friction:g}, alpha {case.trough.inclination:g} deg",
    )
    original = source.with_name(CASE_FILE + ".orig")
    if not original.exists():
        replace_text(original, source.read_text(encoding="utf-8"))
        print(f"kept the previous file as {original}")

    def write_checked(tmp):
        tmp.write_text(text, encoding="utf-8")
        load_case(tmp)  # never replace a case with one that does not load

    replace_file(source, write_checked)
    print(f"wrote {source} ([contact] tangential_stiffness_ratio, tangential_damping_ratio)")
    return 1 if strict_fail else 0


def build_parser() -> argparse.ArgumentParser:
    """The full ``dem`` argument parser."""
    parser = _Parser(
        prog="dem",
        description="Granular material on vibratory conveyors: point-mass model and DEM.",
    )
    parser.add_argument("--version", action="version", version=f"dem {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _pointmass_parser(sub)

    p = sub.add_parser("run", help="run a case directory (DEM)")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument("--out", help="output directory (default CASE_DIR/output)")
    p.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. drive.angle=30 (repeatable; recorded in "
        "summary.json)",
    )  # fmt: skip
    p.add_argument("--cycles", type=_whole, help="measured cycles (overrides run.cycles)")
    p.add_argument("--threads", type=_whole, help="numba threads (default: all cores)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--overwrite", action="store_true", help="replace an earlier run in --out")
    mode.add_argument("--resume", action="store_true", help="continue an interrupted run")
    p.add_argument("--no-frames", action="store_true", help="write no VTK/HDF5 particle frames")
    p.add_argument(
        "--lab-frame", action="store_true", help="VTK frames in the lab frame (trough shakes)"
    )
    p.add_argument(
        "--replicas", type=_whole, help="independent fills pooled (overrides run.replicas)"
    )
    p.add_argument(
        "--all-replicas", action="store_true",
        help="keep every replica's frames and results.h5 (default: replica 0's only)",
    )  # fmt: skip
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser(
        "plan", help="cost, memory, expected error and advice for a case, without running it"
    )
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument(
        "--set", action="append", metavar="TABLE.KEY=VALUE",
        help="a case key set over case.toml, e.g. drive.angle=30 (repeatable)",
    )  # fmt: skip
    p.add_argument("--cycles", type=_whole, help="measured cycles (overrides run.cycles)")
    p.add_argument("--threads", type=_whole, help="numba threads (default: all cores)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--suggest", metavar="OUT_DIR",
        help="write the case the advice recommends (every advice with a value applied) into "
        "OUT_DIR, a new folder",
    )  # fmt: skip
    p.set_defaults(func=_cmd_plan)

    p = sub.add_parser("sweep", help="run a grid of cases on Dask and gather one table")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument(
        "--set", action="append", required=True, metavar="TABLE.KEY=VALUES",
        help="swept key: a value, a comma list or start:stop:step (stop included); repeat the "
        "option for a grid",
    )  # fmt: skip
    p.add_argument("--out", help="sweep folder (default CASE_DIR/sweep), one folder per point")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: local)")
    p.add_argument("--workers", type=_whole, help="local workers (default: one per core)")
    p.add_argument("--threads", type=_whole, help="numba threads per point (default 1)")
    p.add_argument("--cycles", type=_whole, help="measured cycles (overrides run.cycles)")
    p.add_argument("--frames", action="store_true", help="write VTK/HDF5 frames for every point")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_dem_sweep)

    p = sub.add_parser("optimum", help="the bulk optimum angle (or throw number) of a case")
    p.add_argument("case_dir", help="directory holding case.toml")
    p.add_argument("--over", required=True, choices=("drive.angle", "drive.throw_number"))
    p.add_argument("--hold", default="throw_number", help="held fixed: throw_number or "
                   "amplitude over drive.angle; frequency over drive.throw_number")  # fmt: skip
    p.add_argument("--bounds", help="LO:HI of the search (default 10:60 deg, Gamma 0.5:4)")
    p.add_argument("--tolerance", type=_number, help="bracket half-width to stop at "
                   "(default 1 deg, Gamma 0.05); " + QUANTITIES["tolerance"].allowed)  # fmt: skip
    runs = "most DEM runs (default 20); " + QUANTITIES["max_runs"].allowed
    p.add_argument("--max-runs", type=_whole, default=20, help=runs)
    p.add_argument("--out", help="output folder (default CASE_DIR/optimum)")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: local)")
    p.add_argument("--workers", type=_whole, help="local workers (default: one per core)")
    p.add_argument("--cycles", type=_whole, help="measured cycles per run (overrides run.cycles)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_dem_optimum)

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
    p.set_defaults(func=_cmd_calibrate)

    p = sub.add_parser("report", help="figures and a summary of one or more finished runs")
    p.add_argument("out_dirs", nargs="+", help="run output folders (holding summary.json)")
    p.add_argument(
        "--out",
        "--dest",
        dest="dest",
        help="where to write the report (default OUT/report); --dest is an alias",
    )
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("export", help="export a case to another code")
    es = p.add_subparsers(dest="export_command", required=True, parser_class=_Parser)
    e = es.add_parser("liggghts", help="write an equivalent LIGGGHTS-PUBLIC 3.8 deck")
    e.add_argument("case_dir")
    e.add_argument("out_dir")
    e.add_argument("--timestep", type=_number, help="dt in s (default: dem's for this case)")
    e.add_argument(
        "--settle-cycles", type=_whole0,
        help="driven cycles before measuring (default: the case's; for \"auto\" what an earlier "
        f"dem run detected, else {DEM_EXPORT_SETTLE_CYCLES})",
    )  # fmt: skip
    e.add_argument("--from-run", metavar="RUN_DIR",
                   help='the dem run whose detected settling an "auto" case takes '
                   "(default CASE_DIR/output)")  # fmt: skip
    e.add_argument(
        "--no-dump",
        action="store_true",
        help="no particle dump (default: output.frames_per_cycle a cycle)",
    )
    e.add_argument(
        "--overwrite", action="store_true",
        help="replace a deck already in OUT_DIR (in.dem, grain.multisphere, trough.stl)",
    )  # fmt: skip
    e.set_defaults(func=_cmd_export_liggghts)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``dem`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    warnings.formatwarning = _format_warning
    try:
        return args.func(args)
    except InputError as err:
        where = f"{err.source}: " if err.source else ""
        # a positional argument (its metavar, upper case) is named as it is, not as an option
        # and a case key (table.key) as itself, not as an option that does not exist
        plain = err.source or err.key.startswith("--") or err.key.isupper() or "." in err.key
        key = err.key if plain else _option_name(err.key)
        if err.value is None:
            print(f"dem: error: {where}missing {key}: {err.allowed}", file=sys.stderr)
        else:
            print(f"dem: error: {where}{key} = {err.value!r}: {err.allowed}", file=sys.stderr)
        return EXIT_USAGE
    except SimulationError as err:
        print(f"dem: simulation stopped: {err}", file=sys.stderr)
        return 1
    except OSError as err:  # disk full, permission, a vanished folder: one line, no traceback
        where = err.filename or "an output file"
        cause = err.strerror or str(err) or type(err).__name__
        print(f"dem: error: cannot write or read {where}: {cause}; what was written before it "
              "stays readable (results.h5 up to its last cycle)", file=sys.stderr)  # fmt: skip
        return 1
    except KeyboardInterrupt:
        print("dem: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
