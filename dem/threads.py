"""A thread guard: a multi-thread run never falls far below one thread's speed on a shared machine.

numba's OpenMP threads wait for each other at the end of every parallel loop, twice a step. When
another process holds one of the cores, the thread that shares it arrives late at every barrier
and the whole run slows to a fraction of what one thread would do (measured on 2 cores beside a
busy process: 2 threads 0.2-0.4e7 particle-steps/s, 1 thread 1.6e7; validation/performance,
``threads_shared.py``). A process started with N threads can still run its loops on one
(``numba.set_num_threads``), and then runs at one thread's full speed.

:class:`ThreadGuard` times each chunk of steps (``DEM_CHECK_INTERVAL``) on the thread count it
chose: the first two chunks on N threads (the first, which pays one-time costs, is not timed),
the third on one, then on whichever was faster per step
(the choice it keeps is re-timed every chunk, so it leaves a choice that slows down at once).
Since load comes and goes, it tries the other choice again after ``DEM_THREAD_GUARD_PERIOD``
chunks; each try that confirms the choice doubles the wait (up to 8 periods), a try that
overturns it resets the wait. The trajectory and every reported value are the same on any number
of threads (the momentum sums are taken in fixed chunks), so the guard changes only the wall
time. Its cost is one chunk in 8 to one in 64 run on the slower choice (one in 8 throughout cost
the idle sphere bed a tenth of its two-thread rate: validation/performance/README.md).
"""

from __future__ import annotations

import numba

from dem import config


class ThreadGuard:
    """Chooses, chunk by chunk, between ``threads`` and one thread by their measured speed."""

    def __init__(self, threads: int, period: int | None = None):
        self.threads = int(threads)
        self.period = int(period or config.DEM_THREAD_GUARD_PERIOD)
        self.chunks = 0
        self.seconds_per_step: dict[int, float] = {}
        self.steps = {self.threads: 0, 1: 0}
        self.wait = self.period  # chunks from one try of the other choice to the next
        self.next_try = 2  # the third chunk tries one thread (the first is not timed)
        self._tried: int | None = None  # the choice a try interrupted

    @property
    def best(self) -> int:
        """The thread count that was faster per step (``threads`` until both were measured)."""
        if len(self.seconds_per_step) < 2:
            return self.threads
        return min(self.seconds_per_step, key=self.seconds_per_step.get)

    def choose(self) -> int:
        """Thread count for the next chunk (also set in numba)."""
        self._tried = None
        if self.chunks == 0:
            k = self.threads
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
        if self._tried is not None:
            held = self.best == self._tried
            self.wait = min(2 * self.wait, 8 * self.period) if held else self.period
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
            "steps_on_one_thread": self.steps[1],
            "fraction_on_one_thread": self.steps[1] / total if total else 0.0,
            "seconds_per_step": {str(k): v for k, v in self.seconds_per_step.items()},
        }
