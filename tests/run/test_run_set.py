"""dem run / dem plan --set: one case key over case.toml, checked as if written, recorded."""

import json

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main


def _case_dir(tmp_path):
    return write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", "cycles = 1"))


@pytest.mark.integration
def test_run_set_changes_the_case_and_summary_json_records_it(tmp_path):
    case_dir = _case_dir(tmp_path)
    before = (case_dir / "case.toml").read_bytes()
    out = tmp_path / "out"
    code = main(["run", str(case_dir), "--out", str(out), "--threads", "1", "--no-frames",
                 "--set", "drive.angle=30", "--set", "material.friction=0.4"])  # fmt: skip
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["overrides"] == {"drive.angle": 30.0, "material.friction": 0.4}
    assert s["angle"] == 30.0 and s["friction"] == 0.4
    assert (case_dir / "case.toml").read_bytes() == before  # the user's file is untouched


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ("drive.angle=10,20", "one value"),
        ("drive.angle", "table.key=values"),
        ("drive.angle=95", "drive.angle"),  # out of range: the case reader's own message
        ("drive.colour=3", "colour"),  # an unknown key
    ],
)
def test_plan_set_refuses_bad_values_before_anything_runs(tmp_path, capsys, option, message):
    case_dir = _case_dir(tmp_path)
    code = main(["plan", str(case_dir), "--set", option])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not (case_dir / "output").exists()


@pytest.mark.integration
def test_plan_set_is_the_edited_case(tmp_path, capsys):
    case_dir = _case_dir(tmp_path)
    assert main(["plan", str(case_dir), "--json", "--set", "run.cycles=40"]) == 0
    long = json.loads(capsys.readouterr().out)
    assert main(["plan", str(case_dir), "--json"]) == 0
    short = json.loads(capsys.readouterr().out)
    assert long["steps"] > short["steps"]
