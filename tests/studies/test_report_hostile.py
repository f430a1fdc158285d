"""``dem report`` on corrupt inputs: a summary.json cut short (the runner may be killed while
writing it), of the wrong shape or with mistyped values, and a results.h5 that is no readable
results file. Each is exit 2 and one line naming the file and what is wrong, before any report
file is written."""

import json

import h5py
import pytest
from small_case import run_cli as run
from test_report import _run_folder, _summary

GOOD = json.dumps(_summary())


def _with(**changes) -> str:
    return json.dumps(_summary() | changes)


@pytest.mark.parametrize(
    "text, needle",
    [
        (GOOD[: len(GOOD) // 2], "not valid JSON"),
        ("", "not valid JSON"),
        (b"\xff\xfe\x00{", "not valid JSON"),
        ("[1, 2]", "a JSON object"),
        ("null", "a JSON object"),
        ('"summary"', "a JSON object"),
        (_with(settle_cycles="x"), "settle_cycles"),
        (_with(settle_cycles=-3), "settle_cycles"),
        (_with(settle_cycles=1.5), "settle_cycles"),
        (_with(per_cycle_velocity="abc"), "per_cycle_velocity"),
        (_with(per_cycle_velocity=[0.1, "a"]), "per_cycle_velocity"),
        (_with(feeder=5), "feeder"),
        (_with(feeder={"discharge_rate": "fast"}), "feeder.discharge_rate"),
        (_with(case=[1]), "case"),
        (_with(contact_model=3), "contact_model"),
        (_with(mean_velocity="0.01"), "mean_velocity"),
        (_with(angle=True), "angle"),
        (_with(grains={"n": 3}), "grains"),
    ],
)
def test_a_corrupt_summary_is_named_in_one_line(capsys, tmp_path, text, needle):
    out = _run_folder(tmp_path / "run", with_h5=False)
    path = out / "summary.json"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    code, stdout, err = run(capsys, "report", out)
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert str(path) in err and needle in err, err
    assert not (out / "report").exists() and stdout == ""


def _corrupt_h5(path, how):
    if how == "garbage":
        path.write_bytes(b"not an hdf5 file" * 64)
    elif how == "truncated":
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 3])
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "foreign":
        path.unlink()
        with h5py.File(path, "w") as f:
            f["x"] = [1, 2, 3]
    elif how == "no_cycles":
        with h5py.File(path, "a") as f:
            del f["cycles"]
    elif how == "text_cycles":
        with h5py.File(path, "a") as f:
            del f["cycles/mean_velocity"]
            f["cycles/mean_velocity"] = ["a", "b"]
    elif how == "bad_frames":
        with h5py.File(path, "a") as f:
            del f["frames/positions"]
            f["frames/positions"] = [[1.0, 2.0]] * 8


@pytest.mark.parametrize(
    "how",
    ["garbage", "truncated", "empty", "foreign", "no_cycles", "text_cycles", "bad_frames"],
)
def test_a_corrupt_results_h5_is_named_in_one_line(capsys, tmp_path, how):
    out = _run_folder(tmp_path / "run")
    path = out / "results.h5"
    _corrupt_h5(path, how)
    code, stdout, err = run(capsys, "report", out)
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert str(path) in err and "results.h5" in err, err
    assert "cannot write or read" not in err  # a corrupt input, not a failing disk
    assert not (out / "report").exists() and stdout == ""


def test_one_corrupt_run_among_several_writes_no_report(capsys, tmp_path):
    """Every input is read and checked before the first report file is written."""
    good = _run_folder(tmp_path / "a", with_h5=False)
    bad = _run_folder(tmp_path / "b", with_h5=False)
    (bad / "summary.json").write_text("[]")
    code, _, err = run(capsys, "report", good, bad, "--dest", tmp_path / "rep")
    assert code == 2 and str(bad / "summary.json") in err, err
    assert not (tmp_path / "rep").exists()
