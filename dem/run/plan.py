"""``dem plan``: what a case will cost and how accurate it will be, before any grain moves.

:func:`plan` reads a case and, without filling or stepping it, works out the grains and spheres,
the time step and its stability limit, steps per cycle, the memory of the state, an estimate of
the wall time, the error to expect from these settings, and advice: settings stiffer or finer
than the answer needs, a section too short for the grain, too few or too many cycles, and which
rung of the model ladder (point mass, one grain, bed) already answers the question.
:func:`suggest` (``dem plan --suggest``) writes the case with that advice applied.

Where the numbers come from: memory and wall time, :mod:`dem.run.cost`; the expected error and
the study's advice, :mod:`dem.run.accuracy`; the bed's compliance, :mod:`dem.run.stiffness`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from dem import config
from dem.physics import drive
from dem.run import accuracy, cost, record, stiffness
from dem.run.advice import Advice
from dem.run.cost import format_duration, format_size, physical_memory
from dem.scene.resolved import resolve


class PlanWarning(UserWarning):
    """A case asks for far more (or less) than its answer needs (``dem run`` warns at start)."""


@dataclass
class Plan:
    """The plan of a case (all SI; ``as_dict`` is what summary.json's ``plan`` holds)."""

    case: str
    grains: int
    spheres_per_grain: int
    spheres: int
    timestep: float
    timestep_auto: float
    timestep_limit: float
    steps_per_cycle: float
    settle_cycles: int
    settle_cycles_auto: bool
    cycles: int
    steps: int
    particle_steps: float
    memory_bytes: int
    threads: int
    particle_steps_per_s: float
    rate_source: str
    wall_time_s: float
    compile_s: float
    fill_s: float
    frames: int
    frames_s: float
    expected_error: float
    error_parts: dict[str, float]
    error_source: str
    advice: list[Advice] = field(default_factory=list)
    #: Fills pooled (run.replicas): the wall time counts them all, the expected error their pool.
    replicas: int = 1

    def as_dict(self) -> dict:
        """Plain data for JSON."""
        return asdict(self)

    def warnings(self) -> list[Advice]:
        """The advice a run warns about at start."""
        return [a for a in self.advice if a.level == "warn"]

    def text(self) -> str:
        """The plan as ``dem plan`` prints it."""
        lines = [
            f"case {self.case}",
            f"  grains            {self.grains} x {self.spheres_per_grain} sphere(s) = "
            f"{self.spheres} spheres",
            f"  time step         {self.timestep:.3g} s = {self.timestep / self.timestep_limit:.3g}"
            f" x stability limit {self.timestep_limit:.3g} s (automatic {self.timestep_auto:.3g})",
            f"  steps per cycle   {_count(self.steps_per_cycle)}",
            f"  cycles            {self.settle_cycles} settling"
            f"{' (auto: estimated)' if self.settle_cycles_auto else ''} + {self.cycles} measured,"
            f" {self.steps:.3g} steps in all",
            f"  memory            {format_size(self.memory_bytes)} "
            f"({self.memory_bytes / self.spheres:.0f} B per sphere)",
            f"  wall time         about {format_duration(self.wall_time_s)} "
            f"on {self.threads} thread(s)"
            + (f" for {self.replicas} fills" if self.replicas > 1 else "")
            + (
                f": compiling {format_duration(self.compile_s)} "
                "(no numba cache yet, once per machine),"
                if self.compile_s
                else ":"
            )
            + f" filling {format_duration(self.fill_s)}, {self.frames} frames "
            f"{format_duration(self.frames_s)}, steps at "
            f"{self.particle_steps_per_s:.2g} particle-steps/s ({self.rate_source})",
            f"  expected error    {100 * self.expected_error:.1f} % of the bulk velocity ("
            + ", ".join(f"{k} {100 * v:.1f} %" for k, v in self.error_parts.items())
            + f"; {self.error_source})"
            if math.isfinite(self.expected_error)
            else f"  expected error    not estimated: {self.error_source}",
        ]
        if self.advice:
            lines.append("advice:")
            lines += [f"  [{a.level}] {a.key}: {a.text}" for a in self.advice]
        return "\n".join(lines)


def plan(
    case, *, threads: int | None = None, cycles: int | None = None, frames: bool = True
) -> Plan:
    """The plan of a :class:`~dem.scene.resolved.Scene`, or of a case resolved here.

    No fill, no dynamics. ``frames``: the run writes its VTK and HDF5 frames (``dem run
    --no-frames`` does not).
    """
    scene = resolve(case)
    case = scene.case
    data_all = accuracy.study_data()
    kind = accuracy.study_kind(case)
    data = data_all["cases"][kind] if data_all else None
    threads = config.default_threads() if threads is None else int(threads)
    cycles = case.run.cycles if cycles is None else int(cycles)
    pt = case.particles
    per_grain = pt.spheres_per_grain
    grains = pt.count
    spheres = grains * per_grain
    step = scene.step
    per_cycle = drive.steps_per_cycle(case.drive.frequency, step.dt)
    auto_settle = case.run.settle_cycles is None
    if not auto_settle:
        settle = case.run.settle_cycles
    elif grains > 1:
        settle = cost.AUTO_SETTLE_CYCLES[pt.kind]
    else:
        settle = config.DEM_AUTO_SETTLE_MIN_CYCLES
    floor = record.settle_floor(case)
    if auto_settle:
        settle = max(settle, floor)
    steps = int(cost.settle_steps(case, step.dt) + (settle + cycles) * per_cycle)
    particle_steps = float(spheres) * steps
    speed, source = cost.rate(case, threads, data)
    if case.run.device == "cuda":
        source += "; the CPU engine's rate: a run on the GPU is not estimated"
    from dem import kernels

    shape = pt.kind
    cached = kernels.compiled(clumps=shape == "clump", mesh=case.trough.mesh is not None)
    compile_s = 0.0 if cached else cost.COMPILE_S[shape]
    fill_s = cost.FILL_S[shape] + grains * cost.FILL_S_PER_GRAIN[shape]
    n_frames = 1 + (settle + cycles) * case.output.frames_per_cycle if frames else 0
    frames_s = n_frames * (cost.FRAME_S[shape] + spheres * cost.FRAME_S_PER_SPHERE)
    startup = cost.STARTUP_S
    advice: list[Advice] = []
    away = accuracy.unmeasured(case, data, kind) if data else []
    if data and grains > 1:
        away += accuracy.bed_and_contact_away(scene, data, kind)
    parts: dict[str, float]
    if data and away:
        expected, parts = math.nan, {}
        measure = (
            f"dem run {case.directory} compares one grain with its reference (summary.json's "
            "reference names it: the Coulomb-bounded point mass, or the rolling sphere for a "
            "sphere free to roll)"
            if grains == 1
            else f"dem sweep {case.directory} --set contact.youngs_modulus=A,B,C (and "
            "run.timestep, trough.length, run.seed) measures it"
        )
        error_source = f"not measured under this case's {'; '.join(away)}: {measure}"
        text = ("the speed-accuracy study measured other conditions: none of its error figures "
                "or advice on stiffness, step and section is claimed for this case")  # fmt: skip
        advice.append(Advice("note", away[0].split(" =")[0], text))
    elif data and grains > 1:
        expected, parts, error_source = accuracy.expected_error(scene, data, kind, cycles, advice)
    elif data:  # one grain: the bed study says nothing of its error; the ladder does
        expected, parts = math.nan, {}
        error_source = ("one grain: compare it with the point mass (validation/single-grain, "
                        "validation/single-screw), or a sphere free to roll with the rolling "
                        "sphere (validation/rolling-sphere)")  # fmt: skip
        accuracy.advise_ladder(case, data, kind, advice)
    else:
        expected, parts = math.nan, {}
        error_source = "no study data: dem/data/speed_accuracy.json is missing"
    if grains > 1:
        atlas_advice(case, advice)
    relax_advice(case, record.friction_floor(case), advice)
    if getattr(case, "feeder", None) is not None:
        text = (
            "a finite feeder's grain count changes as grains are fed and discharged: cost "
            "and memory here are those of the initial charge (particles.count)"
        )
        advice.append(Advice("note", "feeder", text))
    stiff = stiffness.advice(scene)  # the bed's lowest mode against the drive (bulk study)
    if stiff is not None:  # one warning per key: this one, which names this bed's own value
        advice = [a for a in advice if not (a.key == stiff.key and a.level == "warn")]
        advice.append(stiff)
    calibrated = accuracy.calibration_advice(case)
    if calibrated is not None:
        advice.append(calibrated)
    # replicas (dem.run.replicas): min(N, threads) processes at once, the threads shared among
    # them (a process's rate taken as its share of the threads' rate), N of them in batches;
    # frames are replica 0's
    replicas = max(1, int(case.run.replicas))
    workers = min(replicas, threads)
    batches = math.ceil(replicas / workers)
    mem = cost.memory_bytes(scene, spheres, grains, threads)
    total = physical_memory()
    if total and mem > 0.5 * total:
        advice.append(Advice("warn", "particles.count", f"the state needs {format_size(mem)}, "
                             f"over half of this machine's {format_size(total)}"))  # fmt: skip
    return Plan(
        case=case.name, grains=grains, spheres_per_grain=per_grain, spheres=spheres,
        timestep=step.dt, timestep_auto=step.auto, timestep_limit=step.limit,
        steps_per_cycle=per_cycle, settle_cycles=settle, settle_cycles_auto=auto_settle,
        cycles=cycles, steps=steps, particle_steps=particle_steps, memory_bytes=mem,
        threads=threads, particle_steps_per_s=speed, rate_source=source,
        wall_time_s=startup + compile_s + frames_s + batches * (
            fill_s + workers * particle_steps / speed + steps * cost.STEP_OVERHEAD_S),
        replicas=replicas,
        compile_s=compile_s, fill_s=fill_s, frames=n_frames, frames_s=frames_s,
        expected_error=expected, error_parts=parts,
        error_source=error_source, advice=advice,
    )  # fmt: skip


# --- dem plan --suggest ----------------------------------------------------------------------

#: Rounds of apply-and-plan again before ``suggest`` gives up on advice that keeps moving.
SUGGEST_ROUNDS = 4


@dataclass
class Suggestion:
    """What :func:`suggest` wrote: the keys it set and the plans before and after."""

    path: Path
    changes: dict[str, Any]
    before: Plan
    after: Plan

    def text(self) -> str:
        """The suggestion as ``dem plan --suggest`` prints it."""
        if not self.changes:
            return f"no advice names a value to set: wrote {self.path} as it was"
        b, a = self.before, self.after
        lines = [f"wrote {self.path}, with:"]
        lines += [f"  {key} = {value!r}" for key, value in self.changes.items()]
        lines.append(
            f"wall time about {format_duration(a.wall_time_s)} "
            f"(was {format_duration(b.wall_time_s)}, "
            f"{a.wall_time_s / b.wall_time_s:.2g}x)"
        )
        if math.isfinite(a.expected_error) or math.isfinite(b.expected_error):
            lines.append(
                f"expected error {100 * a.expected_error:.1f} % (was "
                f"{100 * b.expected_error:.1f} %)"
            )
        return "\n".join(lines)


def relax_advice(case, floor: int, advice: list[Advice]) -> None:
    """Warn where the settle is shorter than the floor's friction needs (:func:`settle_floor`).

    An explicit ``run.settle_cycles`` below it, or an automatic settle that would have to wait
    longer than ``DEM_AUTO_SETTLE_MAX_CYCLES``: the run would measure the start-up velocity.
    """
    key = "wall.friction" if "friction" in case.wall.given else "material.friction"
    mu = case.wall_material.friction
    why = (
        f"{key} = {mu:g} takes at least {floor / config.DEM_FRICTION_RELAX_FACTOR:.3g} drive "
        "cycles to take the start-up velocity out of a grain (the drive starts at full speed)"
    )
    given = case.run.settle_cycles
    if given is not None and given < floor:
        advice.append(
            Advice(
                "warn",
                "run.settle_cycles",
                f"{why}: settle for {floor} cycles "
                "at least, or the run measures the start-up, not transport",
                floor,
            )
        )
    elif given is None and floor > config.DEM_AUTO_SETTLE_MAX_CYCLES:
        advice.append(
            Advice(
                "warn",
                key,
                f"{why}: more than the automatic settle waits "
                f"({config.DEM_AUTO_SETTLE_MAX_CYCLES} cycles); set "
                f"run.settle_cycles = {floor}, or check that {key} is right",
            )
        )


def _count(n: float) -> str:
    """A count in digits, or as 1.67e+13 where the digits would be a wall of them."""
    return f"{n:.0f}" if n < 1e9 else f"{n:.3g}"


def suggest(
    case_dir: str | Path,
    out_dir: str | Path,
    overrides: dict | None = None,
    *,
    threads: int | None = None,
    cycles: int | None = None,
) -> Suggestion:
    """Write the case the plan recommends into ``out_dir``: every advice with a value applied.

    The advice of the case (with ``overrides``, as ``--set``) is applied, the result planned
    again, and so on until no advice names a new value (at most ``SUGGEST_ROUNDS`` rounds); advice
    that moves a key back to an earlier value is an error, not a suggestion. ``out_dir`` gets
    the case folder's files (not its outputs) and a case.toml with the changed keys, each with a
    comment; a relative ``trough.mesh`` is rewritten to reach the same file. The written case is
    loaded and planned before this returns. ``out_dir`` must not hold a case.toml already.
    """
    import datetime
    import os
    import shutil

    from dem.errors import InputError
    from dem.io.files import refuse_links, replace_file, replace_text
    from dem.scene.case import CASE_FILE, load_case
    from dem.scene.tomledit import set_case_keys

    case_dir = Path(case_dir).expanduser().resolve()
    source = case_dir / CASE_FILE if case_dir.is_dir() else case_dir
    case_dir = source.parent
    out = Path(out_dir).expanduser().resolve()
    # the case's own files (grain meshes...) go beside it: plain files only, never a link (a
    # received case folder may hold one to a file of its receiver's), never through one
    copied = [item for item in case_dir.iterdir()
              if item.name not in (CASE_FILE, "README.md") and not item.is_symlink()
              and item.is_file()]  # fmt: skip
    refuse_links(out, [CASE_FILE, *(item.name for item in copied)], "--suggest")
    if os.path.lexists(out / CASE_FILE):
        raise InputError("--suggest", str(out), "a folder without a case.toml (none is replaced)")
    if out == case_dir or case_dir in out.parents:
        raise InputError("--suggest", str(out), "a folder outside the case folder")
    overrides = dict(overrides or {})
    case = load_case(source, overrides)
    before = plan(case, threads=threads, cycles=cycles)
    changes: dict[str, Any] = dict(overrides)
    seen: dict[str, list] = {}
    current, current_case = before, case
    for _ in range(SUGGEST_ROUNDS):
        todo: dict[str, Any] = {
            a.key: a.value
            for a in current.advice
            if a.value is not None and changes.get(a.key) != a.value
        }
        if not todo:
            break
        for key, value in todo.items():
            if value in seen.get(key, []):
                raise InputError(
                    key, value, "advice that settles: applied together, the plan's advice "
                    f"moves {key} back and forth ({', '.join(map(repr, seen[key]))}); set it "
                    "with --set and plan again",
                )  # fmt: skip
            seen.setdefault(key, []).append(value)
        stiffer = {"contact.youngs_modulus", "contact.stiffness"} & set(todo)
        if stiffer and ("run.timestep" in todo or current_case.run.timestep is not None):
            # a step set by hand, or advised at the old stiffness, keeps its fraction of the
            # stability limit, which moves with the stiffness (the automatic step follows by
            # itself)
            step = todo.get("run.timestep", current.timestep)
            automatic = load_case(source, changes | todo | {"run.timestep": None})
            limit = resolve(automatic).step.limit
            todo["run.timestep"] = accuracy.round_down(step / current.timestep_limit * limit)
        changes.update(todo)
        current_case = load_case(source, changes)
        current = plan(current_case, threads=threads, cycles=cycles)
    else:
        raise InputError("--suggest", str(source), "advice that settles within "
                         f"{SUGGEST_ROUNDS} rounds: {changes}")  # fmt: skip
    mesh = case.trough.mesh
    if mesh is not None and "trough.mesh" not in changes:
        changes["trough.mesh"] = os.path.relpath(mesh, out)
    out.mkdir(parents=True, exist_ok=True)
    for item in copied:  # not the README: it describes the case as it was
        if not os.path.lexists(out / item.name):
            replace_file(out / item.name, functools.partial(shutil.copy2, item), key="--suggest")
    stamp = datetime.date.today().isoformat()
    as_filed = load_case(source) if overrides else case  # "was": the file's value, not --set's
    was = {k: _case_value(as_filed, k) for k in changes}
    text_lines = set_case_keys(source, changes, f"dem plan --suggest {stamp}").splitlines()
    for i, line in enumerate(text_lines):  # each changed key's comment says what it was
        for key, old in was.items():
            name = key.rpartition(".")[2]
            if line.startswith(f"{name} = ") and line.endswith(f"# dem plan --suggest {stamp}"):
                text_lines[i] = f"{line}, was {old}"
    # the file's own header and comments describe the case it came from: say so above them
    changed = ", ".join(sorted(changes))
    text_lines = [
        f"# dem plan --suggest {stamp}: the case {source.parent.name} with its advice applied,",
        f"# {changed}. The comments below are that case's (each changed key keeps its old line",
        "# as '# was: ...'): where they describe the old values, the values are the new ones.",
        *text_lines,
    ]
    replace_text(out / CASE_FILE, "\n".join(text_lines) + "\n", key="--suggest")
    after = plan(load_case(out), threads=threads, cycles=cycles)
    return Suggestion(out / CASE_FILE, {k: v for k, v in changes.items()}, before, after)


def atlas_advice(case, advice: list) -> None:
    """A note from the atlas: whether the point mass answers this bed (:mod:`dem.run.bulk`)."""
    from dem.run import bulk

    said = bulk.point_mass_answers(case)
    if said is None:
        return
    if said["answers"] is None:
        advice.append(Advice("note", "particles.layers", f"the atlas does not describe this "
                             f"bed: {said['why']}"))  # fmt: skip
        return
    share = f"{said['ratio']:.3f} +- {said['ratio_stderr']:.2g} of the Coulomb-bounded point mass"
    if said["answers"]:
        text = (f"by the atlas this bed of {said['layers']:.2g} layers conveys at {share}: "
                f"within the {100 * said['accuracy']:g} % asked, the point mass answers "
                "(dem pointmass velocity) without this run")  # fmt: skip
    else:
        text = (f"by the atlas this bed of {said['layers']:.2g} layers conveys at {share}: "
                f"more than the {100 * said['accuracy']:g} % asked from the point mass, so the "
                "DEM run is needed")  # fmt: skip
    advice.append(Advice("note", "particles.layers", text))


def _case_value(case, dotted: str) -> str:
    """The case's value of ``table.key`` as text (``automatic`` for an automatic step)."""
    obj = case
    for part in dotted.split("."):
        obj = getattr(obj, part, None)
    if dotted == "run.timestep" and obj is None:
        return "automatic"
    if isinstance(obj, Path):
        return str(obj)
    return "unset" if obj is None else repr(obj)
