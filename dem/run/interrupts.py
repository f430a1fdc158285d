"""Signals during a run: SIGINT and SIGTERM stop it cleanly, SIGXFSZ becomes an error.

Before the drive starts (compiling, filling, settling) there is nothing worth resuming: a
signal stops the run at once with :class:`RunInterrupted` and no checkpoint (:class:`StopNow`).
Once the drive runs, a signal is only recorded (:class:`SignalFlag`); the run loop checks the
flag between chunks, writes a checkpoint and then raises :class:`RunInterrupted`, or, after the
last cycle, finishes its summary first. SIGXFSZ is ignored while the run writes, so a file size
limit ends the run with an ordinary write error instead of a core dump.
"""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import Any, Self

#: What signal.signal takes and returns: a handler, SIG_DFL, SIG_IGN, or None (not set from Python).
_Handler = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None


class RunInterrupted(Exception):
    """SIGINT/SIGTERM arrived; a checkpoint was written. ``signum`` says which."""

    def __init__(self, signum: int, checkpoint: Path | None, cycle: int, phase: str = ""):
        self.signum = signum
        self.checkpoint = checkpoint
        self.cycle = cycle
        name = signal.Signals(signum).name
        if checkpoint is None:
            super().__init__(
                f"{name} while {phase}, before the drive started: no checkpoint (nothing worth "
                "resuming: a new run fills again)"
            )
        else:
            super().__init__(f"{name} at cycle {cycle}; checkpoint written to {checkpoint}")


class SignalFlag:
    """Record SIGINT/SIGTERM instead of dying, so the loop can checkpoint between chunks."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._old: dict[int, _Handler] = {}

    def __enter__(self) -> Self:
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._old[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread: signals stay as they are
                pass
        return self

    def _handle(self, signum, frame) -> None:
        self.signum = signum

    def is_set(self) -> bool:
        """Whether a signal has arrived."""
        return self.signum is not None

    def __exit__(self, *exc) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)


class StopNow(SignalFlag):
    """SIGINT/SIGTERM before the drive starts: stop at once, no checkpoint.

    While compiling, filling and settling a signal raises :class:`RunInterrupted` without a
    checkpoint; ``phase`` names what was going on. Python runs the handler between bytecodes,
    so a signal that arrives inside one compiled kernel call is honoured when the call returns
    (settling calls them in 5 ms chunks).
    """

    def __init__(self) -> None:
        super().__init__()
        self.phase = "compiling"

    def _handle(self, signum, frame) -> None:
        raise RunInterrupted(signum, None, 0, self.phase)


@contextmanager
def file_size_limit_as_error() -> Iterator[None]:
    """Ignore SIGXFSZ while the ``with`` block runs; the handler it replaced comes back after.

    Its default action kills the process with a core dump at the file size limit (``ulimit
    -f``); ignored, the write fails with EFBIG and the run ends in one line, exit 1, like a full
    disk. Python's own start-up ignores it already; a program embedding dem may not. Where the
    handler cannot be set (no SIGXFSZ, or not the main thread) signals stay as they are.
    """
    old = None
    if hasattr(signal, "SIGXFSZ"):
        try:
            old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        except ValueError:  # not the main thread: signals stay as they are
            old = None
    try:
        yield
    finally:
        if old is not None:
            signal.signal(signal.SIGXFSZ, old)
