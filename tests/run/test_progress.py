"""dem.run.progress.Status: a live line on a terminal, two lines in a log."""

import io
import time

from dem.run.progress import Status


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_start_and_an_end_line_only():
    out = io.StringIO()
    with Status("compiling", "compiled", stream=out, interval=0.01):
        time.sleep(0.05)
    lines = out.getvalue().splitlines()
    assert lines == ["dem: compiling ...", "dem: compiling: compiled in 0 s"]


def test_a_terminal_sees_the_elapsed_seconds_rewritten_in_place():
    out = _Tty()
    with Status("compiling", "compiled", stream=out, interval=0.01):
        time.sleep(0.1)
    text = out.getvalue()
    assert text.count("\rdem: compiling ... 0 s") >= 2  # rewritten, not appended
    assert text.endswith("dem: compiling: compiled in 0 s\n")


def test_an_error_inside_says_stopped_and_disabled_prints_nothing():
    out = io.StringIO()
    try:
        with Status("filling", stream=out):
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        pass
    assert "dem: filling: stopped in" in out.getvalue()
    quiet = io.StringIO()
    with Status("filling", stream=quiet, enabled=False):
        pass
    assert quiet.getvalue() == ""
