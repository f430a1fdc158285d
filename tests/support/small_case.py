"""A small valid sphere case (case.toml text) shared by the command-line and runner tests."""

from pathlib import Path

SMALL_CASE = """
[trough]
length = 0.03
width = 0.02

[drive]
frequency = 60.0
angle = 25.0
amplitude = 0.0005

[material]
density = 7800.0
friction = 0.35

[contact]
model = "hertz_mindlin"
youngs_modulus = 5.0e7

[particles]
shape = "sphere"
count = 120
radius = 0.002

[run]
settle_cycles = 2
cycles = 6
seed = 3

[output]
frames_per_cycle = 3
"""


def write_case(directory: Path, text: str = SMALL_CASE) -> Path:
    """Write ``text`` as directory/case.toml (directory created); returns the directory."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "case.toml").write_text(text)
    return directory


def sigterm_at_check(monkeypatch, n: int) -> None:
    """Make the n-th instability check with the drive on send this process SIGTERM.

    The checks come every DEM_CHECK_INTERVAL steps (a feeder's exchange interval, if shorter),
    so a test can place the signal inside a frame. ``monkeypatch.undo()`` restores them.
    """
    import os
    import signal

    from dem.engine.simulation import Simulation

    original, calls = Simulation.check, {"n": 0}

    def check_then_signal(self):
        original(self)
        if self.drive_on:
            calls["n"] += 1
            if calls["n"] == n:
                os.kill(os.getpid(), signal.SIGTERM)

    monkeypatch.setattr(Simulation, "check", check_then_signal)


def stop_mid_frame(case, out: Path, monkeypatch, check: int, timestep: float) -> int:
    """Run ``case`` into ``out`` until SIGTERM at the ``check``-th instability check; assert the
    run stopped with a checkpoint inside a frame; return the driven steps done into that frame."""
    import numpy as np
    import pytest

    from dem.run.interrupts import RunInterrupted
    from dem.run.runner import run_case

    sigterm_at_check(monkeypatch, check)
    with pytest.raises(RunInterrupted) as info:
        run_case(case, out, progress=False, threads=1)
    monkeypatch.undo()
    assert info.value.checkpoint is not None
    steps_per_frame = round(1.0 / (case.drive.frequency * case.output.frames_per_cycle
                                   * timestep))  # fmt: skip
    state = np.load(out / "checkpoint.npz")
    step, drive_start = (int(v) for v in state["sim.counters"][:2])
    into = (step - drive_start) % steps_per_frame
    assert into != 0  # stopped mid-frame
    return into


def run_cli(capsys, *argv):
    """``dem`` with ``argv`` (any values, as strings): (exit status, stdout, stderr)."""
    from dem.cli import main

    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err
