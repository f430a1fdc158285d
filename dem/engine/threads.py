"""A thread guard: a multi-thread run never falls far below one thread's speed on a shared machine.

numba's OpenMP threads wait for each other at the end of every parallel loop, twice a step. When
another process holds one of the cores, the thread that shares it arrives late at every barrier
and the whole run slows to a fraction of what one thread would do (measured on 2 cores beside a
busy process: 2 threads 0.2-0.4e7 particle-steps/s, 1 thread 1.6e7; validation/performance,
``threads_shared.py``). A process started with N threads can still run its loops on one
(``numba.set_num_threads``), and then runs at one thread's full speed.

:class:`ThreadGuard` times each chunk of steps (``DEM_CHECK_INTERVAL``) on the thread count it
chose. It starts on N threads, or on one where the cores busy now (the CPUs' idle time sampled
over a quarter of a second, :func:`busy_cores`) leave fewer than N free
(:func:`starting_threads`): the first two chunks on that choice (the first, which pays one-time
costs, is not timed), the third a short try (``DEM_THREAD_GUARD_TRY_STEPS``) of the other, then on
whichever was faster per step (the choice it keeps is re-timed every chunk, so it leaves a choice
that slows down at once). Since load comes and goes, it tries the other choice again after
``DEM_THREAD_GUARD_PERIOD`` chunks; each try that confirms the choice doubles the wait (up to 8
periods), and a try that confirms it and ran k times slower waits at least until such tries cost
``DEM_THREAD_GUARD_TRY_COST`` of the run (at most ``DEM_THREAD_GUARD_MAX_WAIT`` chunks); a try
that overturns it resets the wait. The trajectory and every reported value are the same on any
number of threads (the momentum sums are taken in fixed chunks), so the guard changes only the
wall time. The first move to one thread is noted in one line (``note``). Measured fill to
summary beside 0, 1 and 3 busy processes: validation/performance/threads_busy.py.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

import numba

from dem import config


def cpu_times() -> list[tuple[int, int]] | None:
    """(idle, total) jiffies of every CPU from /proc/stat, or None where there is none."""
    try:
        with open("/proc/stat", encoding="ascii") as handle:
            lines = handle.read().splitlines()
    except OSError:
        return None
    out = []
    for line in lines:
        name, *fields = line.split()
        if name.startswith("cpu") and name != "cpu":
            ticks = [int(x) for x in fields[:8]]  # user nice system idle iowait irq softirq steal
            out.append((ticks[3] + ticks[4], sum(ticks)))
    return out or None


def busy_cores(sample_s: float | None = None) -> float:
    """Cores busy now: the CPUs' busy time over ``sample_s``, summed over the CPUs.

    ``sample_s`` defaults to ``DEM_THREAD_GUARD_SAMPLE_S``; where /proc/stat is missing, the
    1-minute load average. Sampled, not averaged over a minute: the load average still holds a
    run that ended a minute
    ago (in a sweep, replicas or an atlas the run before this one), so a guard that read it started
    back-to-back runs on one thread on an idle machine. dem itself is waiting while it samples.
    """
    import time

    sample_s = config.DEM_THREAD_GUARD_SAMPLE_S if sample_s is None else sample_s
    before = cpu_times()
    if before is not None and sample_s > 0.0:
        time.sleep(sample_s)
        after = cpu_times()
        if after is not None and len(after) == len(before):
            busy = 0.0
            for (i0, t0), (i1, t1) in zip(before, after, strict=True):
                if t1 > t0:
                    busy += 1.0 - (i1 - i0) / (t1 - t0)
            return max(busy, 0.0)
    try:
        return max(os.getloadavg()[0], 0.0)
    except OSError:  # no load average on this platform
        return 0.0


def starting_threads(threads: int, cores: int | None = None, busy: float | None = None) -> int:
    """``threads``, or one where the cores busy now leave fewer than ``threads`` free.

    A core counts as free when less than half of it is busy (:func:`busy_cores`, sampled now).
    The guard corrects a wrong start within three chunks.
    """
    cores = int(cores or os.cpu_count() or 1)
    busy = busy_cores() if busy is None else float(busy)
    return threads if cores - busy >= threads - 0.5 else 1


class ThreadGuard:
    """Chooses, chunk by chunk, between ``threads`` and one thread by their measured speed.

    ``start``: the count of the first chunks (default ``threads``; the runner passes
    :func:`starting_threads`). ``note``: called with one line of text the first time the guard
    moves a run onto one thread (the runner prints it), and at the start if ``start`` is 1.
    """

    def __init__(self, threads: int, period: int | None = None, *, start: int | None = None,
                 note: Callable[[str], None] | None = None,
                 busy: float | None = None):  # fmt: skip
        self.threads = int(threads)
        self.busy_at_start = busy
        self.start = self.threads if start is None else int(start)
        if self.start not in (1, self.threads):
            raise ValueError(f"start must be 1 or {self.threads}, not {self.start}")
        self.period = int(period or config.DEM_THREAD_GUARD_PERIOD)
        self.chunks = 0
        self.seconds_per_step: dict[int, float] = {}
        self.steps = {self.threads: 0, 1: 0}
        self.wait = self.period  # chunks from one try of the other choice to the next
        self.next_try = 2  # the third chunk tries the other choice (the first is not timed)
        self._tried: int | None = None  # the choice a try interrupted
        self.note = note
        self._noted = False
        if self.start == 1 and self.threads > 1:
            busy = busy_cores() if busy is None else busy
            self._say(
                f"{busy:.1f} of {os.cpu_count()} cores busy now: starting on one thread, trying "
                f"{self.threads} now and then"
            )

    def _say(self, text: str) -> None:
        if self.note is not None and not self._noted:
            self.note(text)
        self._noted = True

    @property
    def trying(self) -> bool:
        """Whether the next chunk tries the choice that is not the best (a short chunk will do)."""
        return self.chunks == self.next_try

    @property
    def best(self) -> int:
        """The thread count that was faster per step (``start`` until both were measured)."""
        if len(self.seconds_per_step) < 2:
            return self.start
        return min(self.seconds_per_step, key=self.seconds_per_step.__getitem__)

    def choose(self) -> int:
        """Thread count for the next chunk (also set in numba)."""
        self._tried = None
        if self.chunks == 0:
            k = self.start
        elif self.chunks == self.next_try:
            self._tried = self.best
            k = 1 if self.best != 1 else self.threads  # try the other choice
        else:
            k = self.best
        numba.set_num_threads(k)
        return k

    def record(self, threads: int, steps: int, seconds: float) -> None:
        """Time of a chunk of ``steps`` steps run on ``threads``."""
        self.chunks += 1
        self.steps[threads] += steps
        # the first chunk pays once (cache loads, the inbox's first touch): not a fair time
        if self.chunks > 1 and steps >= config.DEM_THREAD_GUARD_MIN_STEPS and seconds > 0.0:
            self.seconds_per_step[threads] = seconds / steps
        if self.best == 1 and self.threads > 1:
            self._say(
                f"{self.threads} threads ran slower than one (another process on the cores?): "
                f"going on with one thread, trying {self.threads} now and then"
            )
        if self._tried is not None:
            held = self.best == self._tried
            self.wait = min(2 * self.wait, 8 * self.period) if held else self.period
            if held and len(self.seconds_per_step) == 2:
                # a try on the slow choice cost (slowdown - 1) x its steps: wait long enough
                # that tries cost at most DEM_THREAD_GUARD_TRY_COST of the run (beside busy
                # processes N threads can run 10-50x slower than one)
                slow = max(self.seconds_per_step.values()) / min(self.seconds_per_step.values())
                lost = (slow - 1.0) * steps / config.DEM_THREAD_GUARD_TRY_COST
                self.wait = max(self.wait, math.ceil(lost / config.DEM_CHECK_INTERVAL))
                self.wait = min(self.wait, config.DEM_THREAD_GUARD_MAX_WAIT)
            self.next_try = self.chunks + self.wait
            self._tried = None

    def restore(self) -> None:
        """Back to ``threads`` (the count the process asked for)."""
        numba.set_num_threads(self.threads)

    def as_dict(self) -> dict:
        """What the guard did, for summary.json."""
        total = sum(self.steps.values())
        return {
            "threads": self.threads,
            "started_on": self.start,
            "busy_cores_at_start": self.busy_at_start,
            "steps_on_one_thread": self.steps[1],
            "fraction_on_one_thread": self.steps[1] / total if total else 0.0,
            "seconds_per_step": {str(k): v for k, v in self.seconds_per_step.items()},
        }
