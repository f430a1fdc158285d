"""``dem export liggghts --run``: the deck run in LIGGGHTS and summarised as dem run reports."""

import json
import shutil

import numpy as np
import pytest
from small_case import SMALL_CASE, run_cli, write_case

from dem.io.liggghts.export import dem_run_line, export_deck, plan_export
from dem.io.liggghts.launcher import LiggghtsError, LiggghtsRun, summarize_run
from dem.io.liggghts.readers import LoopTime
from dem.physics import drive
from dem.scene.case import load_case


def _deck(tmp_path):
    case = load_case(write_case(tmp_path / "case", SMALL_CASE))
    plan = plan_export(case)
    export_deck(plan, tmp_path / "deck", dump=False, every_step=True)
    return case, plan, tmp_path / "deck"


def test_the_summary_cuts_every_steps_velocity_into_dems_cycles(tmp_path):
    """A synthetic vx_mean.txt (one row a step from the drive's start) gives each cycle's own
    mean; one that stops early is refused in one line."""
    case, plan, deck = _deck(tmp_path)
    text = (deck / "in.dem").read_text()
    assert "fix vxout all ave/time 1 1 1 c_vxm" in text  # every step
    start = int(text.split("variable tau equal (step-")[1].split(")")[0])
    period, dt = plan.scene.trough.period, plan.timestep
    total = plan.settle_cycles + case.run.cycles
    last = drive.cycle_edge(start, total, period, dt)
    steps = np.arange(start + 1, last + 1)
    cycle = np.floor((steps - start - 0.5) * dt / period).astype(int)  # the cycle of each step
    (deck / "vx_mean.txt").write_text("# step vx\n" + "".join(
        f"{s} {0.01 * c}\n" for s, c in zip(steps, cycle, strict=True)))  # fmt: skip
    run = LiggghtsRun("", 1.0, [LoopTime(1.0, 1, 100, 120)], "LIGGGHTS-PUBLIC 3.8.0")
    s = summarize_run(plan, deck, run)
    expected = [0.01 * c for c in range(plan.settle_cycles, total)]
    assert np.allclose(s["per_cycle_velocity"], expected)
    assert s["engine"] == "liggghts" and s["cycles"] == case.run.cycles
    assert json.loads((deck / "summary.json").read_text())["mean_velocity"] == s["mean_velocity"]
    rows = (deck / "vx_mean.txt").read_text().splitlines()
    (deck / "vx_mean.txt").write_text("\n".join(rows[:-5]) + "\n")
    with pytest.raises(LiggghtsError, match="the run ended early"):
        summarize_run(plan, deck, run)


def test_the_export_names_the_matching_dem_run(tmp_path):
    case, plan, _ = _deck(tmp_path)
    line = dem_run_line(plan, ["drive.angle=30"])
    assert line.startswith(f"dem run {case.directory} --set drive.angle=30")
    assert f"run.timestep={plan.timestep!r}" in line and "--replicas 1" in line
    assert f"run.settle_cycles={plan.settle_cycles}" in line


@pytest.mark.integration
@pytest.mark.skipif(shutil.which("liggghts") is None, reason="liggghts is not on PATH")
def test_export_liggghts_run_writes_a_summary_and_prints_json(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", "cycles = 2"))
    code, out, err = run_cli(capsys, "export", "liggghts", case_dir, tmp_path / "deck", "--run",
                             "--no-dump", "--json")  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    s = result["summary"]
    assert s["engine_version"].startswith("LIGGGHTS") and len(s["per_cycle_velocity"]) == 2
    assert 0.0 < s["mean_velocity_norm"] < 1.5 and result["dem_run"].startswith("dem run")
