"""One function per ``dem`` command: check, call the library, print. No physics here."""

import sys
from pathlib import Path

from dem.cli.options import check_numbers, option_name, parse_bounds, print_json, set_overrides
from dem.errors import InputError
from dem.io.files import own_folder, refuse_links, replace_text
from dem.io.paths import output_folder, plot_path, writable_path

#: The options that set a case key (errors in their values name the option, not ``--set``).
ORIGINS = {
    "run.replicas": "--replicas",
    "run.device": "--device",
    "run.target_error": "--target-error",
}


def cmd_thresholds(args) -> int:
    """``dem pointmass thresholds``: the regime limits of a material and angle."""
    from dem.pointmass.answers import thresholds_answer

    check_numbers(args)
    result, lines = thresholds_answer(args.angle, args.friction, args.inclination)
    if args.json:
        print_json(result)
    else:
        print("\n".join(lines))
    return 0


def cmd_velocity(args) -> int:
    """``dem pointmass velocity``: the point mass's (or a rolling sphere's) velocity at a drive."""
    from dem import pointmass
    from dem.pointmass.answers import velocity_answer

    check_numbers(args)
    if args.grain == "rolling-sphere":
        from dem.pointmass import rolling
        from dem.pointmass.answers import rolling_answer

        drive = (args.throw_number, args.angle, args.friction, args.inclination, args.eps_t,
                 args.eps_n)  # fmt: skip
        impact = args.impact or "coulomb"
        k = rolling.SOLID_SPHERE if args.inertia_factor is None else args.inertia_factor
        r = rolling.velocity(*drive, k, landing=args.landing or "centre", impact=impact)
        pm = pointmass.velocity(*drive, impact=impact).velocity_norm
        result, lines = rolling_answer(r, args.frequency, pm)
    else:
        for option in ("--inertia-factor", "--landing"):
            value = getattr(args, option[2:].replace("-", "_"))
            if value is not None:
                raise InputError(option, value, "only with --grain rolling-sphere")
        v = pointmass.velocity(
            args.throw_number, args.angle, args.friction, args.inclination, args.eps_t,
            args.eps_n, impact=args.impact or "paper",
        )  # fmt: skip
        result, lines = velocity_answer(v, args.frequency)
    if args.bulk is not None or args.depth is not None or args.atlas is not None:
        bulk, more = bulk_answer(args)
        result["bulk"] = bulk
        lines += more
    if args.json:
        print_json(result)
    else:
        print("\n".join(lines))
    return 0


def bulk_answer(args) -> tuple[dict, list[str]]:
    """``--bulk``: the atlas's estimate of the bed on this drive, as JSON and as lines."""
    import dataclasses

    from dem import pointmass
    from dem.run import bulk as atlas

    if args.bulk is None:
        raise InputError("--bulk", None, "a grain shape (sphere, screw) with --depth and --atlas")
    if args.depth is None:
        raise InputError("--depth", None, "the bed's depth in grain layers, with --bulk")
    if args.grain != "point":
        raise InputError("--grain", args.grain, "point with --bulk (the atlas compares the bed "
                         "with the point mass)")  # fmt: skip
    path = args.atlas or atlas.default_table()
    if path is None:
        raise InputError("--bulk", args.bulk, "an atlas: the shipped one (dem/data/atlas) is not "
                         "computed yet (validation/atlas/README.md says how far it is); give "
                         "--atlas CSV, an atlas.csv of dem atlas")  # fmt: skip
    if args.atlas is None:  # the shipped atlas's material and trough
        for option, value in atlas.FIXED.items():
            given = getattr(args, option[2:].replace("-", "_"))
            if given != value:
                raise InputError(option, given, f"{value:g}, as the shipped atlas was run (give "
                                 "--atlas CSV of an atlas of your material)")  # fmt: skip
    rows = atlas.read_table(path)
    e = atlas.estimate(rows, args.bulk, depth=args.depth, friction=args.friction,
                       throw_number=args.throw_number, angle=args.angle,
                       source=str(path))  # fmt: skip
    bounded = pointmass.velocity(
        args.throw_number, args.angle, args.friction, args.inclination, args.eps_t, args.eps_n,
        impact="coulomb",
    ).velocity_norm  # fmt: skip
    ratio = e.velocity_norm / bounded if abs(bounded) > 1e-3 else None
    result = dataclasses.asdict(e) | {"pointmass_bounded_velocity_norm": bounded,
                                      "ratio_bounded": ratio}  # fmt: skip
    lines = [
        f"bulk (atlas)       v_norm {e.velocity_norm:.3f} +- {e.stderr:.2g} for a bed of "
        f"{args.bulk}s {args.depth:g} layers deep (interpolated between {len(e.corners)} "
        f"atlas points, +- {e.interpolation:.2g} of it from the interpolation; {path})",
    ]
    if ratio is not None:
        lines.append(f"bulk / point mass  {ratio:.3f} against the Coulomb-bounded point mass "
                     f"({bounded:.3f})")  # fmt: skip
    return result, lines


def cmd_sweep(args) -> int:
    """``dem pointmass sweep``: the point-mass velocity over a range, as a table and plot."""
    from dem.pointmass.sweep import parse_values, sweep, write_csv

    values = {
        key: parse_values(getattr(args, key), option_name(key))
        for key in ("throw_number", "angle", "friction", "inclination", "eps_t", "eps_n")
    }
    if args.out:
        writable_path("--out", args.out, folder=False)
        refuse_links(Path(args.out).parent, [Path(args.out).name])
    result = sweep(**values, impact=args.impact)
    if args.out:
        import io

        text = io.StringIO()
        write_csv(result, text)
        replace_text(Path(args.out), text.getvalue())
        print(f"wrote {len(result['velocity_norm'])} rows to {args.out}", file=sys.stderr)
    else:
        write_csv(result, sys.stdout)
    return 0


def cmd_optimum(args) -> int:
    """``dem pointmass optimum``: the best vibration angle or throw number."""
    from dem.pointmass.answers import optimum_lines
    from dem.pointmass.sweep import optimum

    check_numbers(args)
    bounds = parse_bounds(args.bounds, "LOW:HIGH, two numbers")
    plot = plot_path("--plot", args.plot, "optimum.png") if args.plot else None
    held = ("friction", "angle", "throw_number", "amplitude", "peak_acceleration",
            "drive_velocity", "frequency", "inclination", "eps_t", "eps_n", "impact")  # fmt: skip
    o = optimum(args.over, args.hold, bounds=bounds, **{k: getattr(args, k) for k in held})
    if plot is not None:
        from dem.studies.plots import optimum_figure

        optimum_figure(o, plot)
        print(f"wrote {plot}", file=sys.stderr)
    if args.json:
        print_json(o.as_dict(with_curve=args.curve))
    else:
        print("\n".join(optimum_lines(o, args.over, args.hold)))
    return 0


def cmd_run(args) -> int:
    """``dem run``: one case, its summary printed and written."""
    from dem.run.interrupts import RunInterrupted
    from dem.run.replicas import run_replicas
    from dem.scene.case import load_case
    from dem.studies.answers import run_summary_lines

    overrides = set_overrides(args.set)
    if args.replicas is not None:
        overrides["run.replicas"] = args.replicas
    if args.device is not None:
        overrides["run.device"] = args.device
    if args.target_error is not None:
        overrides["run.target_error"] = args.target_error
    case = load_case(args.case_dir, overrides, ORIGINS)
    out = output_folder("--out", args.out, case.directory / "output")
    try:
        summary = run_replicas(
            case, out, cycles=args.cycles, threads=args.threads, progress=True,
            overwrite=args.overwrite, resume=args.resume, frames=not args.no_frames,
            lab_frame=args.lab_frame, all_replicas=args.all_replicas,
        )  # fmt: skip
    except RunInterrupted as stop:
        print(f"dem: stopped by {stop}", file=sys.stderr)
        if stop.checkpoint is not None:
            print(f"dem: continue with: {resume_command(args, case, out)}", file=sys.stderr)
        return 128 + stop.signum
    if args.json:
        print_json(summary)
        print(f"wrote {out / 'summary.json'}", file=sys.stderr)
        return 0
    print("\n".join(run_summary_lines(summary)))
    print(f"wrote {out / 'summary.json'}")
    return 0


def resume_command(args, case, out: Path) -> str:
    """The ``dem run`` line that resumes this run: every option a resume must repeat.

    The folder, the ``--set`` keys, the measured cycles (a resume is refused with others) and
    the frames setting (``--no-frames``, ``--lab-frame``), and the threads and device if they
    were given.
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
    if args.device is not None:
        parts += ["--device", args.device]
    if args.replicas is not None:
        parts += ["--replicas", str(args.replicas)]
    if args.target_error is not None:
        parts += ["--target-error", repr(args.target_error)]
    if args.all_replicas:
        parts.append("--all-replicas")
    return shlex.join(parts)


def cmd_plan(args) -> int:
    """``dem plan``: cost, memory and expected error of a case before it runs."""
    from dem.engine.device import check_device
    from dem.run.plan import plan
    from dem.scene.case import load_case

    overrides = set_overrides(args.set)
    if args.device is not None:
        overrides["run.device"] = args.device
    case = load_case(args.case_dir, overrides, ORIGINS)
    check_device(case.run.device, case)
    if args.suggest:
        from dem.run.plan import suggest

        done = suggest(args.case_dir, args.suggest, overrides, threads=args.threads,
                       cycles=args.cycles)  # fmt: skip
        if args.json:
            before, after = done.before.as_dict(), done.after.as_dict()
            print_json({"path": str(done.path), "changes": done.changes, "before": before,
                         "after": after})  # fmt: skip
        else:
            print(done.text())
        return 0
    result = plan(case, threads=args.threads, cycles=args.cycles)
    if args.json:
        print_json(result.as_dict())
    else:
        print(result.text())
    return 0


def cmd_dem_sweep(args) -> int:
    """``dem sweep``: runs of one case over the values of its keys."""
    from dem.studies.sweep import parse_set, run_sweep

    check_numbers(args)
    sets = [parse_set(text) for text in args.set]
    out = output_folder("--out", args.out, Path(args.case_dir) / "sweep")
    result = run_sweep(
        args.case_dir, sets, out, scheduler=args.scheduler, workers=args.workers,
        threads=args.threads or 1, cycles=args.cycles, frames=args.frames, device=args.device,
    )  # fmt: skip
    if args.json:
        print_json(result)
    else:
        failed = len(result["failed"])
        print(f"{result['points']} points: {result['done']} done "
              f"({result['skipped']} from an earlier run), {failed} failed")  # fmt: skip
        print(f"wrote {result['csv']}, sweep.h5 and sweep.png")
    for name, error in result["failed"].items():
        print(f"dem: sweep point {name} failed: {error}", file=sys.stderr)
    return 1 if result["failed"] else 0


def cmd_dem_atlas(args) -> int:
    """``dem atlas``: bulk runs over a grid file, each to a target error, into one table."""
    from dem.studies.atlas import run_atlas

    check_numbers(args)
    grid = Path(args.grid)
    out = output_folder("--out", args.out, grid.with_suffix(""))
    result = run_atlas(grid, out, workers=args.workers, scheduler=args.scheduler,
                       threads=args.threads, device=args.device, rerun_stale=args.rerun_stale,
                       dry_run=args.dry_run)  # fmt: skip
    if args.json:
        print_json(result)
    elif not args.dry_run:
        print(f"{result['points']} points: {result['done']} finished, {len(result['failed'])} "
              f"failed; wrote {result['csv']}, atlas.h5 and atlas.png")  # fmt: skip
    for name, error in result.get("failed", {}).items():
        print(f"dem: atlas point {name} failed: {error}", file=sys.stderr)
    if result.get("stopped"):
        return 128 + int(result["stopped"])
    return 1 if result.get("failed") else 0


def cmd_dem_optimum(args) -> int:
    """``dem optimum``: the DEM's best angle or throw number around the point mass's."""
    from dem.studies.optimum import bulk_optimum

    check_numbers(args)
    bounds = parse_bounds(args.bounds, "LO:HI, two numbers")
    out = output_folder("--out", args.out, Path(args.case_dir) / "optimum")
    result = bulk_optimum(
        args.case_dir, args.over, args.hold, out, bounds=bounds, tolerance=args.tolerance,
        max_runs=args.max_runs, scheduler=args.scheduler, workers=args.workers,
        cycles=args.cycles, overrides=set_overrides(args.set),
    )  # fmt: skip
    if args.json:
        print_json(result)
    else:
        b, p = result["bulk"], result["pointmass"]
        where = (f"{b['x']:.4g}, flat within the noise over {b['bracket'][0]:.4g}-"
                 f"{b['bracket'][1]:.4g}" if b["flat"]
                 else f"{b['x']:.4g} +- {b['uncertainty']:.2g}")  # fmt: skip
        print(f"bulk optimum {args.over} = {where} "
              f"({result['objective']} {b['value']:.4g}; {b['reason']}; "
              f"{len(result['samples'])} runs)")  # fmt: skip
        if b["at_bound"]:
            print(f"dem: warning: the bulk optimum lies at the {b['at_bound']} bound of the "
                  f"search ({result['bounds'][0]:g}:{result['bounds'][1]:g}): the best may lie "
                  "beyond it; widen --bounds", file=sys.stderr)  # fmt: skip
        print(f"point-mass optimum {args.over} = {p['value']:.4g} "
              f"(90 % plateau {p['plateau_90'][0]:.3g}-{p['plateau_90'][1]:.3g})")  # fmt: skip
        print(f"wrote {out / 'optimum.json'}, optimum.csv and optimum.png")
    return 0


def cmd_report(args) -> int:
    """``dem report``: a finished run's figures and comparison with the point mass."""
    from dem.studies.report import make_report

    for out in args.out_dirs:
        if not (Path(out) / "summary.json").is_file():
            raise InputError("OUT", out, "a run output folder holding summary.json")
    dest = writable_path("--out", args.dest, folder=True) if args.dest else None
    paths = make_report([Path(p) for p in args.out_dirs], dest, atlas=args.atlas)
    if args.json:
        print_json({"written": [str(p) for p in paths]})
        return 0
    for path in paths:
        print(f"wrote {path}")
    return 0


def cmd_export_liggghts(args) -> int:
    """``dem export liggghts``: the case as a LIGGGHTS deck (``--run``: run it and summarise)."""
    from dem.io.liggghts.export import (
        DECK_FILES,
        RUN_FILES,
        dem_run_line,
        export_deck,
        plan_export,
    )
    from dem.io.liggghts.launcher import (
        LIGGGHTS_INSTALL,
        LIGGGHTS_STDOUT,
        LiggghtsError,
        find_liggghts,
        run_liggghts,
        summarize_run,
    )
    from dem.scene.case import load_case

    case = load_case(args.case_dir, set_overrides(args.set))
    plan = plan_export(case, timestep=args.timestep, settle_cycles=args.settle_cycles,
                       from_run=args.from_run)  # fmt: skip
    out = writable_path("OUT_DIR", args.out_dir, folder=True)
    refuse_links(out, (*DECK_FILES, *RUN_FILES), "OUT_DIR")  # before LIGGGHTS is looked for
    if args.run and find_liggghts() is None:  # say it now, not after the deck
        print(f"dem: liggghts is not on PATH ({LIGGGHTS_INSTALL})", file=sys.stderr)
        return 2
    path = export_deck(plan, out, dump=not args.no_dump, overwrite=args.overwrite,
                       every_step=args.run)  # fmt: skip
    say = sys.stderr if args.json else sys.stdout  # with --json stdout holds the object alone
    print(f"wrote {path} (dt = {plan.timestep:.4g} s, {plan.settle_cycles} settling and "
          f"{case.run.cycles} measured cycles, {plan.steps} measured steps)", file=say)  # fmt: skip
    if plan.settle_note:
        print(f"settle: {plan.settle_note}", file=say)
    if case.run.replicas > 1:  # a deck is one fill
        from dem.run.replicas import fill_keys

        print(f"replicas: the deck is one fill (run.seed {case.run.seed}); "
              f"{fill_keys(case.run)} is not written: run it with other seeds (--set "
              "run.seed=N) and pool them", file=say)  # fmt: skip
    recipe = dem_run_line(plan, args.set)
    print(f"the same bed in dem: {recipe}", file=say)
    deck = {"deck": str(path), "timestep": plan.timestep, "settle_cycles": plan.settle_cycles,
            "cycles": case.run.cycles, "steps": plan.steps, "dem_run": recipe}  # fmt: skip
    if not args.run:
        if args.json:
            print_json(deck)
        return 0
    print(f"dem: running LIGGGHTS in {out} (fill, {plan.settle_cycles} settling and "
          f"{case.run.cycles} measured cycles; it prints nothing until it ends)",
          file=sys.stderr, flush=True)  # fmt: skip
    try:
        run = run_liggghts(out, min_loops=3 if plan.settle_steps > 0 else 2)
        s = summarize_run(plan, out, run)
    except LiggghtsError as exc:
        print(f"dem: {str(exc).splitlines()[0]} (the end of its output: {out / LIGGGHTS_STDOUT})",
              file=sys.stderr)  # fmt: skip
        return 1
    if args.json:
        print_json(deck | {"summary": s})
        return 0
    print(engine_line(s["engine_version"] or "LIGGGHTS", s, out))
    return 0


def cmd_export_lammps(args) -> int:
    """``dem export lammps``: the case as a LAMMPS deck from dem's settled fill (``--run``: run)."""
    from dem.io.lammps.export import DECK_FILES, RUN_FILES, export_lammps, plan_lammps
    from dem.io.lammps.launcher import LammpsError, LammpsMissing, run_lammps, summarize_run
    from dem.scene.case import load_case

    case = load_case(args.case_dir, set_overrides(args.set))
    plan = plan_lammps(case, timestep=args.timestep, settle_cycles=args.settle_cycles,
                       from_run=args.from_run)  # fmt: skip
    out = writable_path("OUT_DIR", args.out_dir, folder=True)
    refuse_links(out, (*DECK_FILES, *RUN_FILES), "OUT_DIR")  # before LAMMPS is looked for
    if args.run:  # say it now, not after the fill
        try:
            from dem.io.lammps.launcher import find_lammps

            find_lammps()
        except LammpsMissing as exc:
            print(f"dem: {exc}", file=sys.stderr)
            return 2
    path = export_lammps(plan, out, overwrite=args.overwrite, fill=args.fill)
    deck = {"deck": str(path), "timestep": plan.timestep, "settle_cycles": plan.settle_cycles,
            "cycles": case.run.cycles, "steps": plan.steps}  # fmt: skip
    print(f"wrote {path} (dt = {plan.timestep:.4g} s, {plan.settle_cycles} settling and "
          f"{case.run.cycles} measured cycles, {plan.steps} measured steps)",
          file=sys.stderr if args.json else sys.stdout)  # fmt: skip
    if plan.settle_note:
        print(f"settle: {plan.settle_note}")
    if case.run.replicas > 1:  # a deck is one fill
        from dem.run.replicas import fill_keys

        print(f"replicas: the deck is one fill (run.seed {case.run.seed}); "
              f"{fill_keys(case.run)} is not written: run it with other seeds (--set "
              "run.seed=N) and pool them")  # fmt: skip
    if not args.run:
        if args.json:
            print_json(deck)
        return 0
    print(f"dem: running LAMMPS on {args.ranks} rank(s) in {out}", file=sys.stderr)
    try:
        log, wall = run_lammps(out, ranks=args.ranks, progress=True,
                               total_steps=plan.settle_steps + plan.steps)  # fmt: skip
        s = summarize_run(plan, out, log, wall, args.ranks)  # a finished run's errors too
    except LammpsError as exc:
        print(f"dem: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print_json(deck | {"summary": s})
        return 0
    print(engine_line(f"LAMMPS {s['engine_version']}", s, out, ranks=args.ranks))
    return 0


def engine_line(name: str, s: dict, out: Path, ranks: int | None = None) -> str:
    """The result of another engine's run of an exported deck, in one line (its summary ``s``)."""
    err = s["mean_velocity_stderr"]
    err_text = "" if err is None else f" +- {err:.3g}"
    rate = s["particle_steps_per_s"]
    on = "" if ranks is None else f" on {ranks} rank(s)"
    rate_text = "" if rate is None else f"; {rate:.3g} particle-steps/s{on}"
    return (f"{name}: mean velocity {s['mean_velocity']:.4g}{err_text} m/s (v_norm "
            f"{s['mean_velocity_norm']:.4g}) over {s['cycles']} cycles{rate_text}; "
            f"{out / 'summary.json'}")  # fmt: skip


def cmd_calibrate(args) -> int:
    """``dem calibrate``: fit the tangential spring to eps_t, and write it back."""
    import time

    from dem.scene.case import CASE_FILE, load_case
    from dem.studies.answers import calibration_lines
    from dem.studies.calibrate import (
        EVALUATIONS_FILE,
        EvaluationTrail,
        calibrate,
        write_calibration,
    )
    from dem.studies.plots import calibration_figure

    case = load_case(args.case_dir)
    plot = plot_path("--plot", args.plot, "calibration.png") if args.plot else None
    # every name calibrate writes in the case folder, checked for links before the first impact
    names = ["output", f"output/{EVALUATIONS_FILE}"] + ([] if plot else ["output/calibration.png"])
    if not args.dry_run:
        names += [CASE_FILE, CASE_FILE + ".orig"]
    refuse_links(case.directory, names, "CASE_DIR")
    print(
        f"dem calibrate {case.name}: eps_t target {case.wall_material.restitution_tangential:g}, "
        f"virtual impacts of one grain over the point mass's landings",
        file=sys.stderr,
    )
    trail = EvaluationTrail(case)
    started = time.perf_counter()

    def progress(kappa, eps, done, total):
        """Each evaluation: count, ETA, and a row of the trail kept if the search is stopped."""
        trail.record(kappa, eps, done)
        spent = time.perf_counter() - started
        eta = spent / done * max(total - done, 0)
        print(f"  [{done:2d}/{total}] k_t / k_n = {kappa:<10.4g} mean eps_t = {eps:.4f}   "
              f"{spent:.0f} s, at most {eta:.0f} s to go", file=sys.stderr)  # fmt: skip

    try:
        cal = calibrate(case, progress=progress)
    except KeyboardInterrupt:
        best = trail.closest()
        text = ""
        if best is not None:
            text = (f"; the closest so far: k_t / k_n = {best[0]:.4g} "
                    f"(mean eps_t {best[1]:.4f} for {trail.target:g})")  # fmt: skip
        print(f"dem calibrate: stopped after {len(trail.tried)} evaluations, case.toml unchanged; "
              f"every evaluation is in {trail.path}{text}", file=sys.stderr)  # fmt: skip
        return 130
    out = sys.stderr if args.json else sys.stdout  # with --json stdout holds the object alone
    print("\n".join(calibration_lines(case, cal)), file=out)
    strict_fail = args.strict and not cal.reachable
    if not cal.reachable:
        print(
            f"dem calibrate: {'no k_t / k_n brings' if cal.fitted else 'the law does not bring'} "
            f"every impact within 0.02 of its target (worst {cal.worst:.4f}); "
            + ("the closest fit is written. " if cal.fitted and not args.dry_run else "")
            + ("--strict: exit 1" if args.strict else "use --strict to fail on this"),
            file=sys.stderr,
        )
    if plot is None:
        plot = own_folder(case.directory / "output", "CASE_DIR") / "calibration.png"
    calibration_figure(cal, case.wall_material.friction, plot)
    print(f"wrote {plot}", file=out)
    source = None
    if not cal.fitted:
        print("case.toml unchanged: nothing to calibrate", file=out)
    elif args.dry_run:
        print("dry run: case.toml unchanged", file=out)
    else:
        source = write_calibration(case, cal, lambda kept: print(f"kept the previous file as "
                                                                  f"{kept}", file=out))  # fmt: skip
        print(f"wrote {source} ([contact] tangential_stiffness_ratio, tangential_damping_ratio)",
              file=out)  # fmt: skip
    if args.json:
        import dataclasses

        print_json({"calibration": dataclasses.asdict(cal), "plot": str(plot),
                    "case_written": None if source is None else str(source)})  # fmt: skip
    return 1 if strict_fail else 0
