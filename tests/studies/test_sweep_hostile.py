"""``dem sweep`` and ``dem optimum`` at the door: grid size, scheduler, reuse of finished points.

Each bad input ends with exit 2 and one line naming the option (or the point and the keys that
differ), before anything runs, and nothing already in the sweep folder is lost.
"""

import json
import socket
import time

import pytest
from small_case import SMALL_CASE, write_case
from small_case import run_cli as run

from dem.run.output import SUMMARY

pytest.importorskip("distributed")

#: 30 spheres, one settling cycle: a point takes well under a second.
TINY = SMALL_CASE.replace("count = 120", "count = 30").replace(
    "settle_cycles = 2", "settle_cycles = 1"
)


def one_line(err: str) -> bool:
    return err.count("\n") == 1 and "Traceback" not in err


def closed_port() -> int:
    """A local TCP port where nothing listens."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize(
    "sets, size",
    [
        (["drive.angle=10:60:0.001", "material.friction=0.1:0.9:0.1"], "50001 x 9"),
        (["run.seed=0:10000:1"], "10001"),
    ],
)
def test_a_grid_over_the_limit_is_refused_at_once(capsys, tmp_path, sets, size):
    """A grid of 450,009 points loaded a case per point for minutes and then ran them all;
    more than 10,000 points is refused before a single case is loaded."""
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    argv = ["sweep", case, "--out", out]
    for s in sets:
        argv += ["--set", s]
    start = time.perf_counter()
    code, _, err = run(capsys, *argv)
    assert time.perf_counter() - start < 5.0
    assert code == 2 and one_line(err), err
    assert "--set" in err and "at most 10000 points" in err and size in err, err
    assert not out.exists()


@pytest.mark.integration
@pytest.mark.parametrize("command", ["sweep", "optimum"])
def test_an_unreachable_scheduler_is_named_not_called_a_file_error(capsys, tmp_path, command):
    import dask

    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    address = f"tcp://127.0.0.1:{closed_port()}"
    argv = [command, case, "--out", out, "--scheduler", address]
    argv += ["--set", "drive.angle=20"] if command == "sweep" else ["--over", "drive.angle"]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        code, _, err = run(capsys, *argv)
    assert code == 2 and one_line(err), err
    assert "--scheduler" in err and address in err and "cannot write or read" not in err, err
    assert not out.exists()


def test_a_malformed_scheduler_address_is_refused_by_option(capsys, tmp_path):
    case = write_case(tmp_path / "case", TINY)
    code, _, err = run(capsys, "sweep", case, "--set", "drive.angle=20", "--out",
                       tmp_path / "out", "--scheduler", "not an address:::")  # fmt: skip
    assert code == 2 and one_line(err) and "--scheduler" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "extra, option",
    [
        (["--threads", "5000"], "--threads"),
        (["--cycles", "100000000"], "--cycles"),
        (["--workers", "100000"], "--workers"),
    ],
)
def test_sweep_options_out_of_range_are_refused(capsys, tmp_path, extra, option):
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    code, _, err = run(capsys, "sweep", case, "--set", "drive.angle=20", "--out", out, *extra)
    assert code == 2 and one_line(err), err
    assert f"{option} = " in err and extra[1] in err and "[1, " in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    "extra, needles",
    [
        (["--bounds", "10:95"], ["--bounds", "95", "(0, 90)"]),
        (["--bounds", "10:nan"], ["--bounds", "nan"]),
        (["--bounds", "40:20"], ["--bounds", "below"]),
        (["--bounds", "10"], ["--bounds", "LO:HI"]),
        (["--tolerance", "-1"], ["--tolerance = -1.0"]),
        (["--tolerance", "0"], ["--tolerance = 0.0"]),
        (["--max-runs", "2"], ["--max-runs = 2", "[5, 10000]"]),
        (["--max-runs", "100000"], ["--max-runs = 100000"]),
        (["--cycles", "100000000"], ["--cycles = 100000000"]),
        (["--workers", "100000"], ["--workers = 100000"]),
    ],
)
def test_optimum_options_out_of_range_are_named_not_the_case_file(capsys, tmp_path, extra,
                                                                  needles):  # fmt: skip
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    code, _, err = run(capsys, "optimum", case, "--over", "drive.angle", "--out", out, *extra)
    assert code == 2 and one_line(err), err
    assert "case.toml" not in err, err
    for needle in needles:
        assert needle in err, err
    assert not out.exists()


def sweep(capsys, case, out, *extra):
    return run(capsys, "sweep", case, "--set", "drive.angle=20", "--out", out, "--workers", "1",
               "--json", *extra)  # fmt: skip


@pytest.mark.integration
def test_a_finished_point_is_reused_only_for_the_same_case_and_options(capsys, tmp_path):
    """A finished point of another --cycles or another case was reported as the new result
    (exit 0); now the sweep refuses, naming the point and each key that differs, and leaves the
    finished point as it was. The same case and options still reuse it."""
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    code, _, err = sweep(capsys, case, out, "--cycles", "2")
    assert code == 0, err
    summary = out / "000_drive.angle=20" / SUMMARY
    before = summary.read_bytes()

    code, _, err = sweep(capsys, case, out, "--cycles", "3")
    assert code == 2 and one_line(err), err
    assert "000_drive.angle=20" in err and "cycles = 2 (now 3)" in err, err
    assert summary.read_bytes() == before

    other = write_case(tmp_path / "other", TINY.replace("friction = 0.35", "friction = 0.5"))
    code, _, err = sweep(capsys, other, out, "--cycles", "2")
    assert code == 2 and one_line(err), err
    assert "material.friction = 0.35 (now 0.5)" in err and "cycles" not in err, err
    assert summary.read_bytes() == before

    code, out_text, err = sweep(capsys, case, out, "--cycles", "2")
    assert code == 0, err
    assert json.loads(out_text)["skipped"] == 1 and summary.read_bytes() == before


def test_a_finished_point_without_a_record_is_not_taken_as_this_sweeps(capsys, tmp_path):
    """A summary.json with no record of its case (copied in, or an older dem) could be of any
    case: refused, not reported as this sweep's result, and left in place."""
    case = write_case(tmp_path / "case", TINY)
    point = tmp_path / "out" / "000_drive.angle=20"
    point.mkdir(parents=True)
    (point / SUMMARY).write_text(json.dumps({"mean_velocity": 1.0, "cycles": 6}))
    code, _, err = sweep(capsys, case, tmp_path / "out")
    assert code == 2 and one_line(err), err
    assert "000_drive.angle=20" in err and "record" in err, err
    assert json.loads((point / SUMMARY).read_text())["mean_velocity"] == 1.0
    assert not (tmp_path / "out" / "sweep.csv").exists()


@pytest.mark.integration
@pytest.mark.parametrize("text", ["", '{"mean_velocity": 0.0', "[1, 2]"])
def test_a_corrupt_summary_of_a_finished_point_is_named(capsys, tmp_path, text):
    """A truncated or list-valued summary.json of a finished point was a traceback when the
    sweep gathered it; now it is named before anything runs."""
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    code, _, err = sweep(capsys, case, out, "--cycles", "2")
    assert code == 0, err
    summary = out / "000_drive.angle=20" / SUMMARY
    summary.write_text(text)
    code, _, err = sweep(capsys, case, out, "--cycles", "2")
    assert code == 2 and one_line(err), err
    assert str(summary) in err, err
    assert summary.read_text() == text
