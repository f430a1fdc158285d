"""Progress for work whose length is not counted in cycles: a status line with elapsed time.

A terminal (stderr is a TTY) sees the line rewritten every second, ``dem: compiling ... 23 s``;
a log file or a pipe gets the line once when the work starts and once when it ends, so logs
stay short. The cycles of a run have their own bars (tqdm, :mod:`dem.run.runner`).
"""

import sys
import threading
import time


class Status:
    """A context manager that shows ``message`` with the seconds elapsed until it exits.

    Args:
        message: What is being done (printed after ``dem: ``).
        done: The words after the message when it ends (``"compiled"`` gives
            ``dem: <message>: compiled in 42 s``).
        enabled: False shows nothing (``progress=False`` of the callers).
        stream: Where to write (default stderr).
        interval: Seconds between rewrites of the line on a terminal.

    """

    def __init__(self, message: str, done: str = "done", *, enabled: bool = True,
                 stream=None, interval: float = 1.0):  # fmt: skip
        self.message, self.done, self.enabled = message, done, enabled
        self.stream = sys.stderr if stream is None else stream
        self.interval = interval
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.elapsed = 0.0

    def _tty(self) -> bool:
        isatty = getattr(self.stream, "isatty", None)
        return bool(isatty and isatty())

    def _tick(self) -> None:
        while not self._stop.wait(self.interval):
            seconds = time.perf_counter() - self._t0
            self.stream.write(f"\rdem: {self.message} ... {seconds:.0f} s")
            self.stream.flush()

    def __enter__(self) -> "Status":
        self._t0 = time.perf_counter()
        if not self.enabled:
            return self
        self.stream.write(f"dem: {self.message} ...")
        if self._tty():
            self.stream.flush()
            self._thread = threading.Thread(target=self._tick, daemon=True)
            self._thread.start()
        else:
            self.stream.write("\n")
            self.stream.flush()
        return self

    def __exit__(self, kind, value, tb) -> None:
        self.elapsed = time.perf_counter() - self._t0
        if not self.enabled:
            return
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self.stream.write("\r")
        end = self.done if kind is None else "stopped"
        self.stream.write(f"dem: {self.message}: {end} in {self.elapsed:.0f} s\n")
        self.stream.flush()
