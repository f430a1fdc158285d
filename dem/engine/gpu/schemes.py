"""The GPU engine's step schemes: the plain step, and the compact step with its trial (opt-in).

Two step kernels give the same bits for spheres between flat walls: the plain one
(:func:`dem.kernels.cuda.step.step_kernel`, a thread a sphere, its contacts in its own loops) and
the compact one (:func:`dem.kernels.cuda.compact.compact_step_kernel`: a block gathers its
touching contacts first, so a warp's threads run the contact law together). No GPU has timed the
compact step yet, so the plain step is the default (:attr:`StepSchemes.compact` False). True runs
the compact step; None opts in to a trial: a scene of :attr:`StepSchemes.tune_min` or more
spheres runs its first chunks alternately with each, times them by the host's clock (the
queueing and the wait for the chunk, per launch; each kernel's first chunk, its compile,
untimed) and keeps the faster (:attr:`StepSchemes.tuned`). The trial's chunks are the run's own
steps, so it costs only the slower kernel's share of a few chunks and changes no result.
"""

from __future__ import annotations

import time
from typing import Any

from dem.kernels.cuda.launch import COMPACT_BLOCK, COMPACT_KEEP

#: With :attr:`StepSchemes.compact` None (the trial), scenes of at least this many spheres (flat
#: walls) time the plain and the compact step on their own first chunks and keep the faster;
#: smaller scenes are bound by the host's launches.
TUNE_MIN_SPHERES = 20_000
#: The trial times each step over at least this many chunks and launches (after an untimed
#: first chunk: its compile), the two alternating chunk by chunk so that a passing load on the
#: host falls on both.
TUNE_CHUNKS = 3
TUNE_LAUNCHES = 24
#: Launches after a decision before the trial runs again (the scene may have changed).
TUNE_EVERY = 20_000


class StepSchemes:
    """Which step kernel a call runs, and the opt-in trial of the plain and compact steps.

    A mixin of :class:`dem.engine.gpu.engine.GpuEngine` (``self.step`` the step kernels'
    module, ``self.mesh``, ``self.n``).
    """

    #: The step kernels' module (:mod:`dem.kernels.cuda.step`), set by the engine.
    step: Any
    #: Spheres on the device.
    n: int
    #: The trough mesh's device arrays (:class:`dem.engine.gpu.buffers.Buffers`), None: flat.
    mesh: tuple | None
    #: The steps a call may run, by ``compact`` (set by :meth:`_choose`).
    _options: dict[bool | None, tuple]

    def init_schemes(self) -> None:
        """The knobs at their defaults: the plain step, no trial."""
        #: The step that gathers each block's touching candidates before the contact law
        #: (:func:`dem.kernels.cuda.compact.compact_step_kernel`, the same bits), listing at
        #: most ``compact_keep`` a sphere a pass (1 to ``COMPACT_KEEP``). False (the default):
        #: the plain step; True: the compact step; None: the trial, where the scene has
        #: ``tune_min`` spheres or more and flat walls (the plain step below).
        self.compact: bool | None = False
        self.compact_keep = COMPACT_KEEP
        self.tune_min = TUNE_MIN_SPHERES
        #: The last trial's outcome: {"chose": "plain" | "compact", "us_per_step": {"plain":
        #: mean, "compact": mean}, "trials": trials so far} (None: no trial, or none decided).
        self.tuned: dict[str, Any] | None = None
        #: The trial under way: seconds, launches and chunks of each step (None: none).
        self._trial: dict[str, dict[bool, Any]] | None = None
        self._since_trial = 0  # launches since the last decision
        #: The step kernel and its launch of the chunk (:meth:`_choose`; None before).
        self._chosen: tuple | None = None
        self._clock = time.perf_counter

    def forget_trial(self) -> None:
        """Time the steps anew (another scene)."""
        self._trial = self.tuned = None

    def _step_kernel(self, compact: bool | None = None) -> tuple:
        """The step kernel ``compact`` and the trough's mesh choose.

        ``compact`` None: :attr:`compact`'s (None there: the plain step). Returns (kernel,
        threads, block, its leading arguments, its trailing arguments), the block None for the
        default :attr:`threads`. The compact step's module is imported (and compiled) only here.
        """
        compact = bool(self.compact) if compact is None else compact
        if self.mesh is not None:
            if compact:
                raise ValueError(
                    f"compact = {self.compact} in a trough mesh: the GPU's mesh step has one "
                    "thread a sphere (compact = False)"
                )
            return self.step.mesh_step_kernel, self.n, None, (), self.mesh
        if compact:
            from dem.kernels.cuda.compact import compact_step_kernel

            keep = self.compact_keep
            if not 1 <= keep <= COMPACT_KEEP:
                raise ValueError(f"compact_keep = {keep}: 1 to {COMPACT_KEEP}")
            return compact_step_kernel, self.n, COMPACT_BLOCK, (int(keep),), ()
        return self.step.step_kernel, self.n, None, (), ()

    def _choose(self) -> None:
        """Take up :attr:`compact` and the mesh for this call's steps.

        Once a call, not once a step: :meth:`_step` runs for every step. Where the plain and
        the compact step are timed against each other (:attr:`compact` None), both are made
        ready: the trial's chunks alternate (:meth:`_pick`), the others run the faster.
        """
        trial = (
            self.compact is None and self.mesh is None and self.n >= self.tune_min
        )  # fmt: skip
        if not trial:
            self._trial, self.tuned = None, None
        elif self._trial is None and self.tuned is None:
            self._start_trial()
        options = (False, True) if trial else (None,)
        self._options = {}
        for compact in options:
            step, n, block, lead, trail = self._step_kernel(compact)
            scheme = (compact,) + lead + tuple(id(a) for a in trail)
            self._options[compact] = (step, n, block, lead, trail, scheme)
        faster = self.tuned is not None and self.tuned["chose"] == "compact"
        self._chosen = self._options[faster if trial else None]

    def _start_trial(self) -> None:
        self._trial = {"seconds": {False: 0.0, True: 0.0}, "launches": {False: 0, True: 0},
                       "chunks": {False: 0, True: 0}}  # fmt: skip

    def _pick(self) -> bool | None:
        """The step of the next chunk in a trial (the one with fewer chunks run), else None."""
        if self._trial is None:
            return None  # nothing to time
        pick = min((False, True), key=self._trial["chunks"].__getitem__)
        self._chosen = self._options[pick]
        return pick

    def _timed(self, compact, seconds: float, launches: int) -> None:
        """Take one chunk's time into the trial; decide once each step has its timings.

        A step's first chunk in a trial is not counted (it compiles); the chunks after count
        with all their launches, those queued after a rebuild's trip included (they cost each
        step the same). :data:`TUNE_EVERY` launches after a decision the trial runs again (the
        scene changes: a fill settles, the drive starts).
        """
        t = self._trial
        if t is None:
            self._since_trial += launches
            if self.tuned is not None and self._since_trial >= TUNE_EVERY:
                self._start_trial()
            return
        if t["chunks"][compact]:
            t["seconds"][compact] += seconds
            t["launches"][compact] += launches
        t["chunks"][compact] += 1
        if any(t["chunks"][c] <= TUNE_CHUNKS or t["launches"][c] < TUNE_LAUNCHES
               for c in (False, True)):  # fmt: skip
            return
        us = {("compact" if c else "plain"): 1e6 * t["seconds"][c] / t["launches"][c]
              for c in (False, True)}  # fmt: skip
        chose = "compact" if us["compact"] < us["plain"] else "plain"
        trials = 1 if self.tuned is None else self.tuned["trials"] + 1
        self.tuned = {"chose": chose, "us_per_step": us, "trials": trials}
        self._trial, self._since_trial = None, 0
        self._chosen = self._options[chose == "compact"]

    def step_scheme(self) -> dict:
        """The step kernel of the run (None before a call), and the last trial's timings.

        After a trial, the kernel it chose (a later trial's chunks alternate meanwhile).
        """
        chosen = self._chosen
        if self.tuned is not None:
            chosen = self._options[self.tuned["chose"] == "compact"]
        out = {"kernel": None if chosen is None else chosen[0].py_func.__name__}
        if self.tuned is not None:
            out["trial_us_per_step"] = self.tuned["us_per_step"]
            out["trials"] = self.tuned["trials"]
        return out
