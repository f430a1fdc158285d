"""Every shipped case runs end to end through ``dem run`` (the integration tier).

Each case keeps its trough, drive, material, contact and grain; only the count is cut to a few
grains and the run to one settling and one measured cycle, so the tier takes seconds. The run
must write a finite summary, a complete results.h5 (with the clumps' orientations for screws)
and the ParaView collection.
"""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from dem.io.files import json_text
from dem.io.hdf5 import read_results
from dem.run.runner import run_case
from dem.scene.case import load_case

pytestmark = pytest.mark.integration

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
SHIPPED = sorted(p.parent for p in CASES_DIR.glob("*/case.toml"))
GRAINS = 20


@pytest.mark.parametrize("directory", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_case_runs(tmp_path, directory):
    case = load_case(directory)
    count = min(case.particles.count, GRAINS)
    case = dataclasses.replace(
        case,
        particles=dataclasses.replace(case.particles, count=count),
        run=dataclasses.replace(case.run, settle_cycles=1),
    )
    summary = run_case(case, tmp_path, cycles=1, progress=False)
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    # the file is strict JSON: what has no number (one cycle's standard error) is null there
    assert on_disk == json.loads(json_text(summary))
    grains = count
    if case.feeder is not None:  # grains spill, leave and are fed: the balance holds instead
        f = on_disk["feeder"]
        grains = f["grains_in_trough"]
        assert f["grains_inserted"] == grains + f["grains_discharged"]
    assert on_disk["grains"] == grains and math.isfinite(on_disk["mean_velocity"])
    results = read_results(tmp_path / "results.h5")
    assert results["complete"]
    assert results["frame_count"] == 1 + 2 * case.output.frames_per_cycle
    last = results["frames"][-1]
    assert np.all(np.isfinite(last["positions"]))
    if case.particles.shape == "sphere":
        assert last["orientation"] is None
    else:
        assert last["orientation"].shape == (grains, 4)
        np.testing.assert_allclose(np.linalg.norm(last["orientation"], axis=1), 1.0, atol=1e-9)
    assert (tmp_path / "particles.pvd").is_file()
    assert 'name="spheres"' in (tmp_path / "particles.pvd").read_text()
    if case.particles.shape != "sphere":
        assert 'name="grains"' in (tmp_path / "particles.pvd").read_text()
    assert len((tmp_path / "cycles.csv").read_text().splitlines()) == 1 + 1  # header, 1 cycle
