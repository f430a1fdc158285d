"""The progress record of a run: where its loop stands, what it has measured, where its writers are.

One :class:`Progress` travels through a run. The loop advances ``cycle`` and ``chunk`` (a chunk
is one frame's worth of steps), :func:`close_cycle` adds each cycle's mean velocity to the
settling or the measured series (and with ``run.settle_cycles = "auto"`` decides when settling
ends), and each writer of :mod:`dem.run.writers` keeps its own position here (``vtk_entries``,
``h5_frames``, ``h5_cycles``). A checkpoint stores the record as the JSON object ``loop.json``
(:mod:`dem.io.checkpoint`, whose ``LOOP_KEYS`` check it); :meth:`Progress.to_checkpoint` and
:meth:`Progress.from_checkpoint` convert at that boundary, key for key, so checkpoints written
before this record existed still resume.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field

from dem import config
from dem.physics import drive, measure

#: Keys a checkpoint holds only once they have a value (older checkpoints lack some of them).
_OPTIONAL = ("compile_wall_time_s", "fill_wall_time_s", "frames", "lab_frame", "settle_detected",
             "discharge_per_cycle", "hold_up_per_cycle", "feeder", "max_overlap",
             "extended_cycles", "per_cycle_types")  # fmt: skip


@dataclass
class Progress:
    """Where a run stands; its fields are the keys of a checkpoint's ``loop.json``.

    Counters: ``cycle`` (cycles done, settling ones included), ``chunk`` (frames done in the
    current cycle), ``steps`` (driven steps). ``settle_cycles`` is None while "auto" settling has
    not ended; then ``total_cycles`` is None too. Times are wall-clock seconds, except
    ``settle_time_s`` (simulated time the fill took to come to rest, s).
    """

    #: The case as :func:`dem.run.summary.fingerprint` records it.
    case: dict
    #: Mass a finite feeder had discharged at the end of the last cycle, kg.
    discharged_mark: float = 0.0
    cycle: int = 0
    chunk: int = 0
    total_cycles: int | None = None
    settle_cycles: int | None = None
    #: Measured cycles (the run's, plus any the steadiness test added: ``extended_cycles``).
    cycles: int = 1
    #: Mean x-velocity of each "auto" settling cycle so far, m/s.
    settle_series: list = field(default_factory=list)
    steps: int = 0
    wall_time_s: float = 0.0
    settle_time_s: float = 0.0
    settle_wall_time_s: float = 0.0
    compile_wall_time_s: float | None = None
    fill_wall_time_s: float | None = None
    frames_wall_time_s: float = 0.0
    #: Mean x-velocity of each measured cycle, m/s.
    per_cycle: list = field(default_factory=list)
    #: (time, particles file, trough file) of each VTK frame written.
    vtk_entries: list = field(default_factory=list)
    h5_cycles: int = 0
    h5_frames: int = 0
    #: Whether the run writes frames, and in the lab frame (None: a checkpoint without them).
    frames: bool | None = None
    lab_frame: bool | None = None
    #: "auto" settling: whether the transient was seen to end (False: the cap ended it).
    settle_detected: bool | None = None
    #: A finite feeder: discharge rate (kg/s) and mass in the trough (kg) per measured cycle.
    discharge_per_cycle: list | None = None
    hold_up_per_cycle: list | None = None
    #: A finite feeder's counters and generator, as the last checkpoint saved them.
    feeder: dict | None = None
    #: The deepest overlap so far (:meth:`dem.engine.simulation.Simulation.overlap_summary`).
    max_overlap: dict | None = None
    #: Measured cycles added because the measured series was not steady (:func:`close_cycle`).
    extended_cycles: int | None = None
    #: Grain types (``particles.types``): the mass-weighted mean x-velocity of each type in each
    #: measured cycle, m/s (the cycle edge's positions are ``Simulation.type_mark``).
    per_cycle_types: list | None = None
    #: Keys of a checkpoint that no field above names, written back unchanged.
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_checkpoint(cls, loop: dict) -> Progress:
        """The record of a checkpoint's ``loop.json`` (validated by :mod:`dem.io.checkpoint`)."""
        names = {f.name for f in dataclasses.fields(cls)} - {"extra"}
        known = {k: v for k, v in loop.items() if k in names}
        return cls(**known, extra={k: v for k, v in loop.items() if k not in names})

    def to_checkpoint(self) -> dict:
        """The record as ``loop.json`` holds it: every key, less optional ones without a value."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "extra" or (f.name in _OPTIONAL and value is None):
                continue
            out[f.name] = value
        return out | self.extra

    @property
    def measuring(self) -> bool:
        """True once the cycles about to run are measured ones (settling is over)."""
        return self.settle_cycles is not None and self.cycle >= self.settle_cycles

    @property
    def finished(self) -> bool:
        """True once every cycle has run."""
        total = self.total_cycles  # set with settle_cycles
        return self.settle_cycles is not None and total is not None and self.cycle >= total


@dataclass(frozen=True)
class CycleRow:
    """One cycle's row of results.h5's ``/cycles`` (:meth:`dem.run.writers.Writer.cycle`).

    ``time``: drive time at the cycle's end, s; ``mean_velocity``: mass-weighted mean
    x-velocity over the cycle, m/s; ``kinetic_energy``: J, at the cycle's end, as ``contacts``;
    ``feeder``: a finite feeder's discharge and balance over the cycle (empty without one);
    ``types``: each grain type's mean x-velocity over the cycle, m/s, as
    ``mean_velocity_<type>`` (empty for one type).
    """

    cycle: int
    time: float
    mean_velocity: float
    kinetic_energy: float
    contacts: int
    measured: bool
    feeder: dict
    types: dict = field(default_factory=dict)

    def stats(self) -> dict:
        """The row as :meth:`dem.io.hdf5.ResultsWriter.append_cycle` takes it, key for key."""
        return {"cycle": self.cycle, "time": self.time, "mean_velocity": self.mean_velocity,
                "kinetic_energy": self.kinetic_energy, "contacts": self.contacts,
                "measured": int(self.measured), **self.feeder, **self.types}  # fmt: skip


def _type_velocities(sim, case, progress: Progress, measured: bool) -> dict:
    """Each grain type's mean x-velocity over the cycle now closing (``particles.types``).

    From the grains' displacements since the last cycle's edge
    (:func:`dem.physics.measure.group_velocities`, over the steps the cycle took); the edge is
    ``sim.type_mark``, an array of the simulation (so a checkpoint's arrays, not its JSON
    record, carry it: O(n) binary). Returns results.h5's columns, ``mean_velocity_<type>``; {}
    for one type.
    """
    kind = sim.grain_type
    if kind is None or sim.type_mark is None:
        return {}
    types = case.particles.types
    x = sim.spheres.x[:, 0]
    velocities = measure.group_velocities(
        sim.type_mark, x, sim.spheres.mass, kind, len(types),
        sim.stats[1] * sim.dt, sim.trough.length,
    )  # fmt: skip
    sim.type_mark = x.copy()
    if measured:
        if progress.per_cycle_types is None:
            progress.per_cycle_types = []
        progress.per_cycle_types.append(velocities)
    return {f"mean_velocity_{t.name}": v for t, v in zip(types, velocities, strict=True)}


def friction_floor(case) -> int:
    """Settling cycles the floor's friction needs at least.

    ``DEM_FRICTION_RELAX_FACTOR`` times the cycles it takes to remove the drive's start-up
    velocity from a grain (:func:`dem.physics.drive.friction_relaxation_cycles`); 10^9 for a
    frictionless floor.
    """
    relax = drive.friction_relaxation_cycles(
        case.drive.velocity_scale, case.drive.frequency, case.wall_material.friction,
        case.trough.inclination,
    )  # fmt: skip
    return math.ceil(min(config.DEM_FRICTION_RELAX_FACTOR * relax, 1e9))


def settle_floor(case) -> int:
    """Fewest settling cycles of ``settle_cycles = "auto"``.

    The transient test's minimum (``DEM_AUTO_SETTLE_MIN_CYCLES``), or the friction's
    (:func:`friction_floor`), whichever is more.
    """
    return max(config.DEM_AUTO_SETTLE_MIN_CYCLES, friction_floor(case))


def drifts(case, t: measure.Trend) -> bool:
    """Whether a measured series' trend ``t`` says the run is not steady.

    Its z beyond ``DEM_STEADY_Z``, and a fitted change beyond the settle's tolerance
    (``DEM_AUTO_SETTLE_TOLERANCE`` of A omega cos phi): a single grain on its periodic orbit
    repeats its cycles to rounding, whose z says nothing.
    """
    small = abs(t.change) <= config.DEM_AUTO_SETTLE_TOLERANCE * case.drive.velocity_scale
    return abs(t.z) > config.DEM_STEADY_Z and not small


def steadiness(case, progress: Progress) -> dict:
    """How steady the measured series was: summary.json's ``steadiness``.

    The least-squares trend of the measured per-cycle velocities against its autocorrelated
    error (:func:`dem.physics.measure.trend`): ``trend_z``, the fitted change over the measured
    cycles in v / (A omega cos phi) (``change_norm``), ``steady`` (not :func:`drifts`), the
    cycles added to reach it (``extended_cycles``) and what it means.
    """
    t = measure.trend(progress.per_cycle)
    steady = not drifts(case, t)
    extended = progress.extended_cycles or 0
    if steady:
        what = f"no trend beyond {config.DEM_STEADY_Z:g} standard errors over the measured cycles"
        if extended:
            what += f", after {extended} cycles more than run.cycles"
    elif case.run.settle_cycles is None:
        what = (f"still drifting after {extended} cycles more than run.cycles: the bed changes "
                "over longer times than the run; measure more cycles (run.cycles) or pool "
                "fills (run.replicas)")  # fmt: skip
    else:
        what = ("drifting: the measured cycles include the start-up; settle longer "
                '(run.settle_cycles, or "auto", which waits for a steady series)')  # fmt: skip
    scale = case.drive.velocity_scale
    return {
        "steady": steady,
        "trend_z": t.z,
        "change_norm": t.change / scale,
        "threshold_z": config.DEM_STEADY_Z,
        "extended_cycles": extended,
        "what": what,
    }


def extend_if_unsteady(case, progress: Progress) -> int:
    """At the last measured cycle: measure ``run.cycles`` more if the series is not steady.

    Only with ``run.settle_cycles = "auto"`` (a fixed settle is the user's choice, and the
    summary says when it was too short), at most ``DEM_STEADY_MAX_EXTENSIONS`` times. The longer
    series dilutes what remains of a transient and gives the autocorrelation time more cycles
    to be measured on. Returns the cycles added (0: none).
    """
    if case.run.settle_cycles is not None or case.feeder is not None:
        return 0
    extended = progress.extended_cycles or 0
    base = progress.cycles - extended
    if extended >= config.DEM_STEADY_MAX_EXTENSIONS * base:
        return 0
    if not drifts(case, measure.trend(progress.per_cycle)):
        return 0
    assert progress.total_cycles is not None  # measuring: settling has ended
    progress.cycles += base
    progress.total_cycles += base
    progress.extended_cycles = extended + base
    return base


def close_cycle(sim, case, progress: Progress) -> CycleRow:
    """Close a cycle: its mass-weighted mean x-velocity from the step loop's momentum sums.

    With ``run.settle_cycles = "auto"`` a settling cycle also tests the settling velocities so
    far for the end of the transient (:func:`dem.physics.measure.steady`, with the trend test);
    the first cycle after it is measured. At ``DEM_AUTO_SETTLE_MAX_CYCLES`` the run measures
    anyway and says so. The last measured cycle tests the measured series and may add cycles
    (:func:`extend_if_unsteady`). Then
    the sums are zeroed and ``progress`` moves to the next cycle; the row returned is the closed
    cycle's.
    """
    velocity = sim.cycle_velocity()
    settle = progress.settle_cycles
    measured = settle is not None and progress.cycle >= settle
    types = _type_velocities(sim, case, progress, measured)
    if measured:
        progress.per_cycle.append(velocity)
        if progress.cycle + 1 == progress.total_cycles:
            extend_if_unsteady(case, progress)
    elif settle is None:
        series = progress.settle_series
        series.append(velocity)
        scale = case.drive.velocity_scale
        done = (
            measure.steady(
                series,
                settle_floor(case),
                config.DEM_AUTO_SETTLE_TOLERANCE * scale,
                config.DEM_AUTO_SETTLE_TREND_Z,
            )  # fmt: skip
            and len(series) >= case.drive.ramp_cycles
        )  # the start-up ramp is no steady state
        if done or len(series) >= config.DEM_AUTO_SETTLE_MAX_CYCLES:
            progress.settle_cycles = progress.cycle + 1
            progress.total_cycles = progress.settle_cycles + progress.cycles
            progress.settle_detected = bool(done)
            if not done:
                warnings.warn(
                    f"{case.name}: the per-cycle velocity still drifts after "
                    f"{len(series)} settling cycles (DEM_AUTO_SETTLE_MAX_CYCLES); measuring anyway",
                    stacklevel=2,
                )
    feeder = {}
    if sim.feeder is not None:
        f = sim.feeder
        mass = f.discharged_mass - progress.discharged_mark
        progress.discharged_mark = f.discharged_mass
        feeder = {
            "discharged_mass": mass,
            "discharge_rate": mass / sim.trough.period,
            "mass_in_trough": sim.total_mass,
            "grains_in_trough": sim.n_grains,
            "grains_inserted": f.inserted,
            "grains_discharged": f.discharged,
            "feed_backlog": f.backlog,
        }
        if measured:
            if progress.discharge_per_cycle is None:
                progress.discharge_per_cycle = []
            if progress.hold_up_per_cycle is None:
                progress.hold_up_per_cycle = []
            progress.discharge_per_cycle.append(mass / sim.trough.period)
            progress.hold_up_per_cycle.append(sim.total_mass)
    row = CycleRow(
        cycle=progress.cycle,
        time=sim.drive_time,
        mean_velocity=velocity,
        kinetic_energy=sim.kinetic_energy(),
        contacts=int(sim.contact_counts().sum()),
        measured=measured,
        feeder=feeder,
        types=types,
    )
    sim.stats[:] = 0.0
    progress.cycle += 1
    progress.chunk = 0
    return row
