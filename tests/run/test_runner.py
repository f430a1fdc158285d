"""dem run end to end: refusing to overwrite, signals, checkpoints and bit-identical resume."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, stop_mid_frame, write_case

from dem.errors import InputError
from dem.io.hdf5 import read_results
from dem.run.runner import run_case
from dem.scene.case import load_case


def _case_dir(tmp_path: Path, cycles: int = 6) -> Path:
    return write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", f"cycles = {cycles}"))


@pytest.mark.integration
def test_refuses_to_overwrite_an_earlier_run(tmp_path):
    case = load_case(_case_dir(tmp_path, cycles=1))
    out = tmp_path / "out"
    run_case(case, out, progress=False)
    before = (out / "summary.json").read_bytes()
    with pytest.raises(InputError) as info:
        run_case(case, out, progress=False)
    assert "--overwrite" in str(info.value) and "summary.json" in str(info.value)
    assert (out / "summary.json").read_bytes() == before  # nothing lost
    # --overwrite removes what dem wrote, by name: a user's file in frames/ stays
    (out / "frames" / "my_notes.txt").write_text("mine\n")
    stale = out / "frames" / "particles_000999.vtp"
    stale.write_bytes(b"old frame")
    run_case(case, out, progress=False, overwrite=True)
    assert (out / "frames" / "my_notes.txt").read_text() == "mine\n"
    assert not stale.exists()
    assert (out / "frames" / "particles_000000.vtp").is_file()
    with pytest.raises(InputError, match="--resume"):
        run_case(case, tmp_path / "empty", progress=False, resume=True)


def _start(case_dir: Path, out: Path) -> subprocess.Popen:
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    return subprocess.Popen(
        [sys.executable, "-m", "dem.cli", "run", str(case_dir), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _wait_for_frames(out: Path, frames: int, proc: subprocess.Popen, limit: float = 600.0):
    start = time.monotonic()
    while time.monotonic() - start < limit:
        if proc.poll() is not None:
            pytest.fail(f"run ended before the signal: {proc.stderr.read()}")
        try:
            if read_results(out / "results.h5")["frame_count"] >= frames:
                return
        except (OSError, KeyError, RuntimeError):
            # not there yet, or caught while the run is writing a record: HDF5 without SWMR
            # gives a reader in the middle of a write an inconsistent file (h5py raises
            # RuntimeError "addr overflow"); the checks that matter read after the run stopped
            pass
        time.sleep(0.05)
    pytest.fail("run did not reach the frame to interrupt in time")


@pytest.mark.integration
def test_interrupt_and_resume_is_bit_identical(tmp_path, monkeypatch):
    case_dir = _case_dir(tmp_path)
    case = load_case(case_dir)
    reference = run_case(case, tmp_path / "straight", progress=False, threads=1)

    out = tmp_path / "interrupted"
    proc = _start(case_dir, out)
    _wait_for_frames(out, 8, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "checkpoint written" in err and "--resume" in err
    assert "Traceback" not in err
    assert (out / "checkpoint.npz").exists() and not (out / "summary.json").exists()

    # other physics is refused by name, before anything in the folder changes
    saved = (out / "checkpoint.npz").read_bytes()
    h5 = (out / "results.h5").read_bytes()
    other = load_case(case_dir, overrides={"material.friction": 0.5})
    with pytest.raises(InputError, match=r"material.friction = 0.35 \(now 0.5\)"):
        run_case(other, out, progress=False, threads=1, resume=True)
    # a truncated checkpoint is refused with its cause, and kept
    (out / "checkpoint.npz").write_bytes(saved[: len(saved) // 2])
    with pytest.raises(InputError, match="a readable checkpoint"):
        run_case(case, out, progress=False, threads=1, resume=True)
    (out / "checkpoint.npz").write_bytes(saved)
    assert (out / "results.h5").read_bytes() == h5
    # a damaged results.h5 is refused before the fill (hardening round 4, item 10), naming the
    # file and --overwrite; the checkpoint and the file stay as they were
    from dem.engine import setup

    def no_fill(*args, **kwargs):
        raise AssertionError("the trough was filled before results.h5 was checked")

    for damaged in (h5[: len(h5) // 2], b"not HDF5 at all"):
        (out / "results.h5").write_bytes(damaged)
        monkeypatch.setattr(setup, "from_case", no_fill)
        with pytest.raises(InputError, match=r"results.h5.*--overwrite"):
            run_case(case, out, progress=False, threads=1, resume=True)
        monkeypatch.undo()
        assert (out / "results.h5").read_bytes() == damaged
        assert (out / "checkpoint.npz").read_bytes() == saved
    (out / "results.h5").write_bytes(h5)

    resumed = run_case(case, out, progress=False, threads=1, resume=True)
    assert resumed["per_cycle_velocity"] == reference["per_cycle_velocity"]
    assert resumed["steps"] == reference["steps"]
    a = read_results(tmp_path / "straight" / "results.h5")
    b = read_results(out / "results.h5")
    assert b["complete"] and b["frame_count"] == a["frame_count"]
    np.testing.assert_array_equal(a["frames"][-1]["positions"], b["frames"][-1]["positions"])
    np.testing.assert_array_equal(a["cycles"]["mean_velocity"], b["cycles"]["mean_velocity"])
    assert not (out / "checkpoint.npz").exists()
    pvd = (out / "particles.pvd").read_text()
    assert pvd.count('part="0"') == a["frame_count"]


@pytest.mark.integration
def test_results_of_a_killed_run_are_readable(tmp_path):
    # far more cycles than it runs before the kill: on a loaded machine a 6-cycle run finished
    # between its fifth frame and the second run's lock check
    case_dir = _case_dir(tmp_path, cycles=400)
    out = tmp_path / "killed"
    proc = _start(case_dir, out)
    _wait_for_frames(out, 5, proc)
    # the folder is locked while the run writes it: a second run is refused, nothing touched
    with pytest.raises(InputError, match="is writing it now") as info:
        run_case(load_case(case_dir), out, progress=False, overwrite=True)
    assert f"pid {proc.pid}" in str(info.value)
    assert (out / "results.h5").exists()
    proc.kill()  # SIGKILL: no handler runs
    proc.communicate(timeout=60)
    r = read_results(out / "results.h5")
    assert not r["complete"]
    assert r["frame_count"] >= 5
    last = r["frames"][r["frame_count"] - 1]
    assert np.all(np.isfinite(last["positions"])) and last["positions"].shape == (120, 3)
    assert json.loads(json.dumps(r["case"]))["particles"]["count"] == 120
    # a killed run leaves no stale lock (the kernel drops it with the process)
    from dem.run.output import lock_output

    lock_output(out).close()


@pytest.mark.integration
@pytest.mark.parametrize("lab_frame", [False, True])
def test_pvd_of_a_run_is_a_time_series_with_the_documented_arrays(tmp_path, lab_frame):
    import pyvista as pv

    case = load_case(_case_dir(tmp_path, cycles=1))
    out = tmp_path / "out"
    run_case(case, out, progress=False, lab_frame=lab_frame)
    reader = pv.get_reader(str(out / "particles.pvd"))
    times = reader.time_values
    per_cycle = case.output.frames_per_cycle
    assert len(times) == 1 + per_cycle * (case.run.settle_cycles + 1)
    assert np.all(np.diff(times) > 0)
    amplitude, omega = case.drive.amplitude, case.drive.omega
    for k in (1, len(times) - 1):
        reader.set_active_time_value(times[k])
        blocks = reader.read()
        particles, trough = blocks[0], blocks[1]
        assert particles.n_points == 120
        for name in ("radius", "velocity", "grain_id", "clump_id", "contact_count"):
            assert name in particles.point_data, name
        assert particles.point_data["contact_count"].sum() > 0
        floor_z = trough.points[:, 2].min()
        expected = amplitude * np.sin(omega * times[k]) * np.sin(np.radians(case.drive.angle))
        assert floor_z == pytest.approx(expected if lab_frame else 0.0, abs=1e-9)


@pytest.mark.integration
def test_summary_records_the_dem_version_and_commit(tmp_path):
    import dem
    from dem.provenance import git_commit

    case = load_case(_case_dir(tmp_path, cycles=1))
    run_case(case, tmp_path / "out", progress=False, frames=False)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["dem_version"] == dem.__version__
    commit = git_commit()  # None outside a git checkout; "+" marks edits to dem/ (may change)
    if commit is None:
        assert summary["git_commit"] is None
    else:
        assert summary["git_commit"].rstrip("+") == commit.rstrip("+")
    provenance = summary["provenance"]
    assert provenance["versions"]["dem"] == dem.__version__
    assert {"numpy", "numba", "python"} <= set(provenance["versions"])
    assert {"date", "host", "load_average"} <= set(provenance)


@pytest.mark.integration
def test_auto_settle_measures_after_the_detected_transient(tmp_path, monkeypatch, recwarn):
    from dem import config

    monkeypatch.setattr(config, "DEM_AUTO_SETTLE_MAX_CYCLES", 14)
    text = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    case = load_case(write_case(tmp_path / "case", text))
    assert case.run.settle_cycles is None
    summary = run_case(case, tmp_path / "out", cycles=2, frames=False, progress=False)
    settle = summary["settle_cycles"]
    assert summary["settle_cycles_auto"] is True
    assert config.DEM_AUTO_SETTLE_MIN_CYCLES <= settle <= 14
    measured = read_results(tmp_path / "out" / "results.h5")["cycles"]["measured"]
    assert list(measured) == [0] * settle + [1, 1]
    # either the transient test passed or the run said that it measured anyway
    drifting = [w for w in recwarn if "still drifts" in str(w.message)]
    assert summary["settle_transient_ended"] != bool(drifting)
    if settle < 14:
        assert summary["settle_transient_ended"]


@pytest.mark.integration
def test_auto_settle_cannot_go_into_a_liggghts_deck(tmp_path):
    from dem.io.liggghts import write_deck

    text = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    case = load_case(write_case(tmp_path / "case", text))
    with pytest.raises(InputError, match="run.settle_cycles"):
        write_deck(case, tmp_path / "deck", timestep=1e-6, steps=10)


@pytest.mark.validation
def test_guard_stops_an_unstable_run_before_a_non_finite_value_is_written(tmp_path, monkeypatch):
    # a time step 8 x the limit checked at load (2.4 x the critical step of one contact) blows
    # up within a few hundred steps; the load check is widened so that the run starts at all.
    # eps_n = 0.5: the plastic contact of eps_n = 0 caps each approach at what stops it within
    # a step and does not blow up at this step (a step the load check refuses to users)
    from dem import config
    from dem.errors import SimulationError
    from dem.scene.timestep import timestep_for

    case = load_case(_case_dir(tmp_path, cycles=4), {"material.restitution_normal": 0.5})
    limit = timestep_for(case).limit
    monkeypatch.setattr(config, "DEM_DT_STABILITY_FRACTION", 100.0)
    run = case.run.__class__(settle_cycles=0, cycles=4, timestep=8.0 * limit, seed=case.run.seed)
    case = dataclasses.replace(case, run=run)
    with pytest.raises(SimulationError) as info:
        run_case(case, tmp_path / "out", progress=False)
    message = str(info.value)
    assert "run.timestep" in message and "step" in message  # the cause and the fix
    assert not (tmp_path / "out" / "summary.json").exists()
    # stopped while settling (no output yet) or while driven (what was written is finite)
    if (tmp_path / "out" / "results.h5").exists():
        res = read_results(tmp_path / "out" / "results.h5")
        assert not res["complete"]
        frames = res["frames"]
        for i in range(len(frames)):
            for key in ("positions", "velocity"):
                assert np.isfinite(frames[i][key]).all()
        assert np.isfinite(res["cycles"]["mean_velocity"]).all()


class TypeText:
    """A numba type as a cache index pickles it: the compile check reads only its text."""

    def __init__(self, text):
        self.text = text

    def __str__(self):
        return self.text


def test_the_compile_check_tells_a_mesh_trough_variant_from_a_flat_one(tmp_path):
    """numba compiles the step kernel once per variant (mesh arrays or None as its last
    argument): a cache holding only one must not count as holding the other."""
    import pickle

    from dem.kernels import _holds_variant

    def index(*lasts):
        path = tmp_path / f"i{len(list(tmp_path.iterdir()))}.nbi"
        keys = {((TypeText("int64"), TypeText(last)), "target", "flags"): "x.nbc" for last in lasts}
        with open(path, "wb") as fh:
            pickle.dump("0.68.1", fh)
            fh.write(pickle.dumps((b"stamp", keys)))
        return path

    flat, meshed, both = (
        index("none"),
        index("MeshArrays(array(float64, 3d, C))"),
        index("none", "MeshArrays(array(float64, 3d, C))"),
    )
    assert _holds_variant(flat, mesh=False) and not _holds_variant(flat, mesh=True)
    assert _holds_variant(meshed, mesh=True) and not _holds_variant(meshed, mesh=False)
    assert _holds_variant(both, mesh=True) and _holds_variant(both, mesh=False)
    garbled = tmp_path / "garbled.nbi"
    garbled.write_bytes(b"not a pickle")
    assert _holds_variant(garbled, mesh=True)  # unreadable: assume compiled (nothing is lost)


@pytest.mark.integration
def test_a_first_run_says_it_compiles_and_its_trajectory_is_unchanged(tmp_path, monkeypatch,
                                                                     capsys):  # fmt: skip
    """The warm-up compiles on two separate grains: the run's own grains never see it."""
    from dem import kernels

    case = load_case(write_case(tmp_path / "case"))
    plain = run_case(case, tmp_path / "a", progress=False, frames=False)
    assert kernels.compiled(clumps=False)  # the cache now holds the sphere kernels
    monkeypatch.setattr(kernels, "compiled", lambda clumps=False, mesh=False: False)
    first = run_case(case, tmp_path / "b", progress=True, frames=False)
    err = capsys.readouterr().err
    assert "compiling the sphere step kernels" in err and ": compiled in" in err
    assert "resting the fill (drive off)" in err and "at rest below" in err  # the fill's bar
    assert first["per_cycle_velocity"] == plain["per_cycle_velocity"]


@pytest.mark.integration
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_settling_stops_at_once_with_a_message(tmp_path, sig):
    """Before the drive starts there is nothing worth a checkpoint: the run stops within about
    a second, says so in one line, and exits 128 + signal, without a traceback or a checkpoint."""
    bouncy = SMALL_CASE.replace("friction = 0.35", "friction = 0.35\nrestitution_normal = 0.9")
    case_dir = write_case(tmp_path / "case", bouncy.replace("count = 120", "count = 400"))
    out = tmp_path / "out"
    proc = _start(case_dir, out)
    while "settling" not in (line := proc.stderr.readline()):
        assert line, "the run ended before it settled"
    t0 = time.monotonic()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 5.0
    assert proc.returncode == 128 + sig, err
    assert "before the drive started" in err and "settling" in err
    assert "Traceback" not in err and "--resume" not in err
    assert not (out / "checkpoint.npz").exists()


@pytest.mark.integration
def test_a_full_disk_ends_in_one_line_and_a_readable_results_file(tmp_path, monkeypatch, capsys):
    """ENOSPC while a run writes its cycles: exit 1, one line naming the cause, no traceback,
    and results.h5 holds the cycles written before (the writer flushes each record)."""
    import errno

    from dem.cli import main
    from dem.io.hdf5 import ResultsWriter

    calls = {"n": 0}
    original = ResultsWriter.append_cycle

    def full_after_two(self, **kwargs):
        calls["n"] += 1
        if calls["n"] > 2:
            raise OSError(errno.ENOSPC, "No space left on device", str(self.path))
        return original(self, **kwargs)

    monkeypatch.setattr(ResultsWriter, "append_cycle", full_after_two)
    case_dir = _case_dir(tmp_path, cycles=2)
    out = tmp_path / "out"
    code = main(["run", str(case_dir), "--out", str(out), "--threads", "1"])
    err = capsys.readouterr().err
    assert code == 1
    assert "No space left on device" in err and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("dem: error: cannot write")
    r = read_results(out / "results.h5")
    assert len(r["cycles"]["mean_velocity"]) == 2


@pytest.mark.integration
def test_a_run_refused_inside_leaves_no_empty_output_folder(tmp_path):
    """An error raised after the folder was locked (here a fill that cannot come to rest, while
    settling) leaves no folder behind that was not there before."""
    from dem.errors import SimulationError

    bad = SMALL_CASE.replace("friction = 0.35", "friction = 0.35\nrestitution_normal = 0.95")
    case = load_case(write_case(tmp_path / "case", bad))
    out = tmp_path / "out"
    import dem.config as config

    old = config.DEM_SETTLE_MAX_TIME
    config.DEM_SETTLE_MAX_TIME = 0.002  # the fill cannot rest in 2 ms
    try:
        with pytest.raises(SimulationError, match="did not come to rest"):
            run_case(case, out, progress=False, threads=1, frames=False)
    finally:
        config.DEM_SETTLE_MAX_TIME = old
    assert not out.exists()


@pytest.mark.integration
def test_a_signal_mid_frame_is_honoured_within_a_check_interval_and_resumes_bit_for_bit(
    tmp_path, monkeypatch
):
    """A slow frame no longer hides a signal: the loop asks after every DEM_CHECK_INTERVAL
    steps, checkpoints mid-frame, and the resumed run is bit-identical to an uninterrupted one."""
    from dem import config

    text = SMALL_CASE.replace("frames_per_cycle = 3", "frames_per_cycle = 1")
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 6", "cycles = 3")))
    reference = run_case(case, tmp_path / "straight", progress=False, threads=1)

    out = tmp_path / "interrupted"
    # 5 checks a frame of 2457 steps: the 7th is inside the 2nd
    into = stop_mid_frame(case, out, monkeypatch, 7, reference["timestep"])
    assert into % config.DEM_CHECK_INTERVAL == 0
    resumed = run_case(case, out, progress=False, threads=1, resume=True)
    assert resumed["per_cycle_velocity"] == reference["per_cycle_velocity"]
    assert resumed["steps"] == reference["steps"]
    a = read_results(tmp_path / "straight" / "results.h5")
    b = read_results(out / "results.h5")
    np.testing.assert_array_equal(a["frames"][-1]["positions"], b["frames"][-1]["positions"])


@pytest.mark.integration
def test_a_run_that_would_take_years_is_refused_at_load_with_the_figure(tmp_path, capsys):
    """The steps are estimated from the case alone (dem plan's estimate): 1e7 cycles of the
    stiffest contact allowed would take years, so dem run refuses it, naming the steps and the
    time, before anything is written."""
    from dem.cli import main

    text = SMALL_CASE.replace("cycles = 6", "cycles = 10000000")
    case_dir = write_case(tmp_path / "case", text.replace("youngs_modulus = 5.0e7",
                                                          "youngs_modulus = 1.0e13"))  # fmt: skip
    out = tmp_path / "out"
    code = main(["run", str(case_dir), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "run.cycles = 10000000" in err and "steps" in err and "years" in err
    assert not out.exists()


@pytest.mark.integration
def test_a_slow_scene_asks_for_a_stop_every_stop_latency_not_500_steps(tmp_path, monkeypatch):
    """When 500 steps take long (a million spheres take about a minute), ``run`` shortens its
    chunks to DEM_STOP_LATENCY_S of wall time from the last chunk's speed, so a signal is still
    honoured within about that (issue 15: "within about a second in every phase")."""
    from dem import config
    from dem.engine import setup
    from dem.engine.simulation import Simulation

    case = load_case(write_case(tmp_path / "case", SMALL_CASE))
    sim = setup.from_case(case)
    per_step = 0.002  # s: 500 steps would take a second

    def slow_advance(self, n):
        time.sleep(per_step * n)
        self.step_index += n

    monkeypatch.setattr(Simulation, "advance", slow_advance)
    monkeypatch.setattr(Simulation, "check", lambda self: None)
    monkeypatch.setattr(config, "DEM_STOP_LATENCY_S", 0.05)
    asked = []

    def stop():
        asked.append(time.perf_counter())
        return False

    done = sim.run(1200, stop=stop)
    assert done == 1200
    gaps = np.diff(asked)
    assert len(asked) > 10 and gaps.max() < 0.05 * 3  # after the first, full-length chunk
