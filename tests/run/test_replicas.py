"""Replicas (dem.run.replicas): N fills of one case, pooled; reproducible, refusing, resumable."""

import json
import math

import numpy as np
import pytest
from small_case import SMALL_CASE, run_cli, write_case

from dem.errors import InputError
from dem.physics import measure
from dem.run import replicas
from dem.run.runner import run_case
from dem.scene.case import load_case

TINY = SMALL_CASE.replace("count = 120", "count = 40").replace("cycles = 6", "cycles = 3")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    return write_case(tmp_path_factory.mktemp("replicas") / "case", TINY)


@pytest.fixture(scope="module")
def pooled_run(tiny, tmp_path_factory):
    case = load_case(tiny, {"run.replicas": 3})
    out = tmp_path_factory.mktemp("pooled") / "out"
    return case, out, replicas.run_replicas(case, out, threads=2, progress=False)


def test_replica_k_is_the_case_seeded_seed_plus_k(tiny):
    case = load_case(tiny, {"run.replicas": 4})
    assert [replicas.replica_case(case, k).run.seed for k in range(4)] == [3, 4, 5, 6]
    assert all(replicas.replica_case(case, k).run.replicas == 1 for k in range(4))


@pytest.mark.integration
def test_the_pool_is_dem_measure_pooled_of_the_replicas_own_runs(pooled_run):
    case, out, summary = pooled_run
    per = summary["per_replica"]
    assert [r["seed"] for r in per] == [3, 4, 5]
    own = [json.loads((out / "replicas" / str(k) / "summary.json").read_text()) for k in range(3)]
    assert [o["mean_velocity"] for o in own] == [r["mean_velocity"] for r in per]
    p = measure.pooled([o["mean_velocity"] for o in own], [o["mean_velocity_stderr"] for o in own])
    assert summary["mean_velocity"] == p.mean
    assert summary["mean_velocity_stderr"] == p.stderr
    assert summary["mean_velocity_ci95"] == p.half_width
    assert summary["replicas"] == 3 and "fill-to-fill spread included" in summary["error_bar"]
    # the fills differ: three seeds, three values
    assert len({r["mean_velocity"] for r in per}) == 3
    assert json.loads((out / "summary.json").read_text())["mean_velocity"] == p.mean
    # frames and results.h5 of replica 0 only
    assert (out / "results.h5").is_file() and (out / "particles.pvd").is_file()
    assert not (out / "replicas" / "1" / "results.h5").exists()
    assert not (out / "replicas" / "1" / "frames").exists()


@pytest.mark.integration
def test_replica_zero_is_the_single_run_bit_for_bit(pooled_run, tmp_path):
    case, _, summary = pooled_run
    single = run_case(replicas.replica_case(case, 0), tmp_path / "one", threads=1, progress=False)
    assert single["mean_velocity"] == summary["per_replica"][0]["mean_velocity"]
    assert "excludes the fill-to-fill spread" in single["error_bar"]


@pytest.mark.integration
def test_a_replicated_run_is_reproducible(pooled_run, tmp_path):
    case, _, summary = pooled_run
    again = replicas.run_replicas(case, tmp_path / "again", threads=1, progress=False)
    assert again["per_replica"] == [
        dict(r, wall_time_s=a["wall_time_s"])
        for r, a in zip(summary["per_replica"], again["per_replica"], strict=True)
    ]
    assert again["mean_velocity"] == summary["mean_velocity"]


def test_an_earlier_run_is_refused_before_any_replica_starts(pooled_run):
    case, out, _ = pooled_run
    before = (out / "summary.json").read_bytes()
    with pytest.raises(InputError, match="--out"):
        replicas.run_replicas(case, out, threads=2, progress=False)
    assert (out / "summary.json").read_bytes() == before


@pytest.mark.integration
def test_resume_reruns_only_what_is_missing(pooled_run, tmp_path):
    case, out, summary = pooled_run
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    (copy / "replicas" / "2" / "summary.json").unlink()
    resumed = replicas.run_replicas(case, copy, threads=2, resume=True, progress=False)
    assert resumed["per_replica"][:2] == summary["per_replica"][:2]
    assert resumed["per_replica"][2]["mean_velocity"] == summary["per_replica"][2]["mean_velocity"]


def test_pool_summaries_pools_the_feeder_and_flow(pooled_run):
    _, _, summary = pooled_run
    assert summary["mass_flow_rate"] > 0 and math.isfinite(summary["mass_flow_rate_stderr"])
    ratio = summary["mass_flow_rate"] / summary["mean_velocity"]
    first = summary["per_replica"][0]
    assert ratio == pytest.approx(first["mass_flow_rate"] / first["mean_velocity"], rel=1e-9)


def test_replicas_key_and_option_are_checked_at_the_door(tiny, capsys):
    with pytest.raises(InputError, match="run.replicas"):
        load_case(tiny, {"run.replicas": 0})
    code, _, err = run_cli(capsys, "run", str(tiny), "--replicas", "0")
    assert code == 2 and "--replicas" in err
    with pytest.raises(InputError, match="seed"):
        load_case(tiny, {"run.seed": 2**63 - 2, "run.replicas": 3})
    np.testing.assert_equal(load_case(tiny, {"run.replicas": 2}).run.replicas, 2)


@pytest.mark.integration
def test_the_plan_warning_is_one_line_once_not_once_a_replica(tiny, tmp_path, capfd):
    """Issue 48, item 5: the stiffness warning came as a Python warning with a file path, once
    per replica (the replicas' processes warned each, in Python's format)."""
    from dem.cli import main

    code = main(["run", str(tiny), "--out", str(tmp_path / "out"), "--replicas", "2",
                 "--threads", "2", "--no-frames"])  # fmt: skip
    err = capfd.readouterr().err
    assert code == 0, err
    warned = [line for line in err.splitlines() if "warning" in line.lower()]
    assert warned, err  # this soft small bed is warned about
    assert all(line.startswith("dem: warning: ") for line in warned), warned
    assert ".py:" not in err
    plan_lines = [line for line in warned if "dem plan" in line]
    assert len(plan_lines) == 1, plan_lines


# --- a target error instead of a fill count (the atlas issue, item 2) --------------------------


def test_fills_for_follows_one_over_sqrt_fills():
    assert replicas.fills_for(3, 0.02, 0.01, 12) == 12  # 3 (2)^2
    assert replicas.fills_for(3, 0.011, 0.01, 12) == 4  # at least one more
    assert replicas.fills_for(3, 0.02, 0.01, 8) == 8  # never past max_replicas
    assert replicas.fills_for(3, math.nan, 0.01, 8) == 4


def test_the_goal_is_relative_with_a_floor_near_a_threshold():
    assert replicas.target_gap({"mean_velocity_norm_stderr": 0.01,
                                "mean_velocity_norm": 0.5}, 0.02) == (0.01, 0.01)  # fmt: skip
    error, goal = replicas.target_gap({"mean_velocity_norm_stderr": 0.001,
                                       "mean_velocity_norm": -0.01}, 0.02)  # fmt: skip
    assert goal == pytest.approx(0.002)  # 2 % of 0.1, not of 0.01


def test_a_target_error_starts_with_three_fills_and_is_checked_at_the_door(tiny):
    case = load_case(tiny, {"run.target_error": 0.05})
    assert case.run.replicas == 3 and case.run.max_replicas == 12
    with pytest.raises(InputError, match=r"run\.replicas.*>= 3 with run\.target_error"):
        load_case(tiny, {"run.target_error": 0.05, "run.replicas": 2})
    with pytest.raises(InputError, match=r"run\.max_replicas.*>= run\.replicas \(4\)"):
        load_case(tiny, {"run.target_error": 0.05, "run.replicas": 4, "run.max_replicas": 3})
    with pytest.raises(InputError, match=r"run\.target_error.*\[1e-4, 0\.5\]"):
        load_case(tiny, {"run.target_error": 2.0})


@pytest.mark.integration
def test_a_run_with_a_target_error_pools_fills_until_it_reaches_it(tiny, tmp_path):
    """A loose target stops at the first three fills; a tight one adds fills up to the cap and
    says it was not reached; both pool exactly the fills they name."""
    loose = load_case(tiny, {"run.target_error": 0.5})
    s = replicas.run_replicas(loose, tmp_path / "loose", threads=2, progress=False, frames=False)
    assert s["replicas"] == 3 and s["target"]["reached"]
    assert s["mean_velocity_norm_stderr"] <= 0.5 * max(abs(s["mean_velocity_norm"]), 0.1)
    tight = load_case(tiny, {"run.target_error": 1e-4, "run.max_replicas": 5})
    s = replicas.run_replicas(tight, tmp_path / "tight", threads=2, progress=False, frames=False)
    assert s["replicas"] == 5 and not s["target"]["reached"]
    assert "NOT REACHED" in s["target"]["what"] and "run.max_replicas = 5" in s["target"]["what"]
    assert [r["seed"] for r in s["per_replica"]] == [3, 4, 5, 6, 7]
    assert [step["fills"] for step in s["target"]["steps"]] == [3, 5]
    own = [json.loads((tmp_path / "tight" / "replicas" / str(k) / "summary.json").read_text())
           for k in range(5)]  # fmt: skip
    p = measure.pooled([o["mean_velocity"] for o in own], [o["mean_velocity_stderr"] for o in own])
    assert s["mean_velocity"] == p.mean


def test_a_done_line_clears_a_progress_bars_open_line_on_a_terminal(monkeypatch):
    import io
    import sys

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    term, pipe = Terminal(), io.StringIO()
    monkeypatch.setattr(sys, "stderr", term)
    replicas.say("dem: replica 1 done")
    monkeypatch.setattr(sys, "stderr", pipe)
    replicas.say("dem: replica 2 done")
    assert term.getvalue() == "\r\x1b[Kdem: replica 1 done\n"
    assert pipe.getvalue() == "dem: replica 2 done\n"


@pytest.mark.integration
def test_a_worker_that_ignores_sigterm_is_killed_after_the_grace(monkeypatch):
    """Stopping the replicas never waits on a worker for ever (an atlas's stop hung on one)."""
    import multiprocessing
    import signal
    import time
    from concurrent.futures import ProcessPoolExecutor

    from dem.run import replicas

    monkeypatch.setattr(replicas, "STOP_GRACE_S", 0.5)
    pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
    busy = "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(60)"
    pool.submit(exec, busy)
    while not pool._processes:
        time.sleep(0.05)
    time.sleep(2.0)  # the worker has started the job and ignores SIGTERM
    processes = list(pool._processes.values())
    t0 = time.monotonic()
    replicas._stop_workers(pool)
    assert time.monotonic() - t0 < 10.0
    assert not any(p.is_alive() for p in processes)
    assert processes[0].exitcode == -signal.SIGKILL
