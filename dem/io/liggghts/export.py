"""The deck ``dem export liggghts`` writes: dem's own time step and the case's cycles.

:func:`plan_export` takes the step a dem run of the case would take (explicit or automatic,
checked against the stability limit), the case's measured cycles, and the settling cycles
(:func:`export_settle_cycles`: the caller's, the case's, or for ``settle_cycles = "auto"`` the
transient an earlier dem run detected); :func:`export_deck` writes the deck
(:func:`dem.io.liggghts.deck.write_deck`) where no earlier deck would be replaced unasked.
Errors name the command line's options (``--timestep``, ``--from-run``, ``OUT_DIR``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import NamedTuple

from dem.config import DEM_EXPORT_SETTLE_CYCLES
from dem.errors import InputError
from dem.io.files import refuse_links
from dem.io.liggghts.deck import CLUMP_FILE, DECK_NAME, VX_FILE, write_deck
from dem.io.liggghts.geometry import MESH_FILE
from dem.io.liggghts.launcher import LIGGGHTS_STDOUT, SUMMARY_NAME
from dem.io.paths import refuse_replacing
from dem.physics import drive
from dem.scene.case import Case
from dem.scene.resolved import Scene, resolve

#: The files ``dem export liggghts`` writes into its folder.
DECK_FILES = (DECK_NAME, CLUMP_FILE, MESH_FILE)
#: What ``--run`` writes beside the deck: LIGGGHTS's output, the velocities and the summary.
RUN_FILES = (LIGGGHTS_STDOUT, VX_FILE, SUMMARY_NAME)


class ExportPlan(NamedTuple):
    """What an exported deck runs (:func:`plan_export`).

    Attributes:
        scene: The resolved case, with dem's time step.
        timestep: dt, s.
        steps: Measured driven steps: the case's ``run.cycles``.
        settle_cycles: Driven cycles before measuring.
        settle_steps: The same in steps.
        settle_note: Where ``settle_cycles`` came from, when the case says "auto"; else None.

    """

    scene: Scene
    timestep: float
    steps: int
    settle_cycles: int
    settle_steps: int
    settle_note: str | None


def plan_export(
    case: Case,
    *,
    timestep: float | None = None,
    settle_cycles: int | None = None,
    from_run: str | os.PathLike | None = None,
) -> ExportPlan:
    """The step, measured steps and settling of ``case``'s deck, checked before anything is written.

    Args:
        case: A case read by :func:`dem.scene.case.load_case`.
        timestep: dt, s, instead of the case's; checked against the stability limit.
        settle_cycles: Driven cycles before measuring, instead of the case's.
        from_run: The dem run whose detected settling an "auto" case takes (default
            CASE_DIR/output).

    Raises:
        InputError: ``timestep`` beyond the stability limit (``--timestep``), or ``from_run``
            not a finished dem run of this case with ``settle_cycles = "auto"``.

    """
    # dem's own time step (explicit or automatic, checked against the stability limit), so
    # the deck integrates with the step a dem run of this case would take
    try:
        scene = resolve(case, timestep=timestep)
    except InputError as exc:
        if timestep is None:
            raise
        raise InputError("--timestep", timestep, exc.allowed) from None  # not the case's
    dt = scene.step.dt
    settle, settle_note = export_settle_cycles(case, settle_cycles, from_run)
    # dem's cycle edges (drive.cycle_edge), as the launchers cut the deck's output by them:
    # rounding each stage on its own made 83,333 + 83,333 steps of 166,667 (issue 48, item 1)
    period = 1.0 / case.drive.frequency
    settle_steps = drive.cycle_edge(0, settle, period, dt)
    steps = drive.cycle_edge(0, settle + case.run.cycles, period, dt) - settle_steps
    return ExportPlan(scene, dt, steps, settle, settle_steps, settle_note)


def export_settle_cycles(
    case: Case, settle_cycles: int | None = None, from_run: str | os.PathLike | None = None
) -> tuple[int, str | None]:
    """Driven cycles before measuring in an exported deck, and a note where the case said "auto".

    ``settle_cycles``, else the case's number; for "auto" the number an earlier ``dem run`` of
    this case detected (``from_run``, else CASE_DIR/output), else
    :data:`dem.config.DEM_EXPORT_SETTLE_CYCLES`.
    """
    if settle_cycles is not None:
        return settle_cycles, None
    if case.run.settle_cycles is not None:
        return case.run.settle_cycles, None
    run_dir = Path(from_run) if from_run else case.directory / "output"
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
        if from_run:
            why = 'run.settle_cycles = "auto" (its summary.json says otherwise)'
            raise InputError("--from-run", str(run_dir), f"a dem run of {case.name} with {why}")
    elif from_run:
        raise InputError("--from-run", str(run_dir), "a finished dem run's folder (summary.json)")
    return DEM_EXPORT_SETTLE_CYCLES, (
        f'run.settle_cycles = "auto": {DEM_EXPORT_SETTLE_CYCLES} cycles, dem\'s default for a deck '
        "(no earlier dem run of the case reports its transient; the shipped cases' were 6-12 "
        "cycles); --settle-cycles N or --from-run RUN_DIR to choose"
    )


def export_deck(
    plan: ExportPlan, out_dir: str | os.PathLike, *, dump: bool = True, overwrite: bool = False,
    every_step: bool = False,
) -> Path:  # fmt: skip
    """Write the deck of ``plan`` into ``out_dir`` and return its path.

    Args:
        plan: From :func:`plan_export`.
        out_dir: The deck's folder (created).
        dump: Write a particle dump every output frame.
        overwrite: Replace a deck already there (``in.dem``, ``grain.multisphere``,
            ``trough.stl``); without it such a folder is refused (``OUT_DIR``).
        every_step: Write the mean x-velocity of every step (the run's summary cuts it into
            dem's cycles, :func:`dem.io.liggghts.launcher.summarize_run`), not of every frame.

    """
    out = Path(out_dir)
    refuse_links(out, DECK_FILES, "OUT_DIR")
    if not overwrite:
        refuse_replacing("OUT_DIR", out, DECK_FILES)
    return write_deck(
        plan.scene, out, timestep=plan.timestep, steps=plan.steps,
        settle_steps=plan.settle_steps, settle_note=plan.settle_note, dump=dump,
        sample_steps=1 if every_step else None,
    )  # fmt: skip


def dem_run_line(plan: ExportPlan, sets: list[str] | None = None) -> str:
    """The ``dem run`` command that runs the same bed as the deck: its step and settle cycles.

    The case folder, the export's ``--set`` keys, and ``run.timestep`` and ``run.settle_cycles``
    as the deck has them (the deck is one fill: ``run.replicas = 1``).
    """
    import shlex

    case = plan.scene.case
    parts = ["dem", "run", str(case.directory)]
    for text in sets or ():
        parts += ["--set", text]
    parts += ["--set", f"run.timestep={plan.timestep!r}",
              "--set", f"run.settle_cycles={plan.settle_cycles}", "--replicas", "1"]  # fmt: skip
    return shlex.join(parts)
