"""A run's steadiness: the settle's trend test, the measured series' test, and the extension."""

from types import SimpleNamespace

import numpy as np
import pytest
from small_case import SMALL_CASE, stop_mid_frame, write_case

from dem import config
from dem.io.hdf5 import read_results
from dem.run.record import Progress, drifts, extend_if_unsteady, steadiness
from dem.run.runner import run_case
from dem.scene.case import load_case


def _case(settle=None, scale=1.0, feeder=None):
    return SimpleNamespace(run=SimpleNamespace(settle_cycles=settle), feeder=feeder,
                           drive=SimpleNamespace(velocity_scale=scale))  # fmt: skip


def _progress(per_cycle, cycles=None):
    n = len(per_cycle)
    return Progress(case={}, cycle=10 + n, settle_cycles=10, cycles=cycles or n,
                    total_cycles=10 + (cycles or n), per_cycle=list(per_cycle))  # fmt: skip


def test_a_rising_series_is_extended_twice_at_most_and_a_flat_one_never():
    rng = np.random.default_rng(3)
    rising = list(0.5 + 0.002 * np.arange(20) + 0.001 * rng.normal(size=20))
    p = _progress(rising)
    assert extend_if_unsteady(_case(), p) == 20
    assert (p.cycles, p.total_cycles, p.extended_cycles) == (40, 50, 20)
    p.per_cycle += list(0.54 + 0.002 * np.arange(20))
    assert extend_if_unsteady(_case(), p) == 20
    p.per_cycle += list(0.58 + 0.002 * np.arange(20))
    assert extend_if_unsteady(_case(), p) == 0  # two extensions: the run ends and says so
    s = steadiness(_case(), p)
    assert not s["steady"] and s["extended_cycles"] == 40 and "still drifting" in s["what"]
    assert s["change_norm"] == pytest.approx(0.002 * 59, rel=0.05)

    flat = _progress(list(0.5 + 0.001 * rng.normal(size=20)))
    assert extend_if_unsteady(_case(), flat) == 0
    assert steadiness(_case(), flat)["steady"]
    # a fixed settle is the user's: not extended, but the summary says the series drifts
    fixed = _progress(rising)
    assert extend_if_unsteady(_case(settle=10), fixed) == 0
    assert "settle longer" in steadiness(_case(settle=10), fixed)["what"]


def test_a_single_grain_repeating_its_orbit_to_rounding_is_steady():
    """Its z can be anything (rounding against rounding); its change is nothing."""
    orbit = 0.6835 + 1e-13 * np.arange(30)
    t_case = _case(scale=0.05)
    from dem.physics import measure

    t = measure.trend(orbit)
    assert not drifts(t_case, t)
    assert extend_if_unsteady(t_case, _progress(list(orbit))) == 0


@pytest.mark.integration
def test_an_unsteady_run_measures_more_says_so_and_resumes_bit_for_bit(tmp_path, monkeypatch):
    monkeypatch.setattr(config, "DEM_STEADY_Z", -1.0)  # every measured series "drifts"
    monkeypatch.setattr(config, "DEM_AUTO_SETTLE_MAX_CYCLES", 8)
    text = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    text = text.replace("frames_per_cycle = 3", "frames_per_cycle = 1")
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 6", "cycles = 4")))
    ref = run_case(case, tmp_path / "straight", progress=False, threads=1)
    settle = ref["settle_cycles"]
    assert ref["cycles"] == 12 and len(ref["per_cycle_velocity"]) == 12
    st = ref["steadiness"]
    assert st["extended_cycles"] == 8 and not st["steady"] and "still drifting" in st["what"]
    measured = read_results(tmp_path / "straight" / "results.h5")["cycles"]["measured"]
    assert list(measured) == [0] * settle + [1] * 12
    csv_rows = (tmp_path / "straight" / "cycles.csv").read_text().strip().splitlines()
    assert len([r for r in csv_rows if not r.startswith("#")]) == 1 + 12
    assert np.mean(ref["per_cycle_velocity"]) == pytest.approx(ref["mean_velocity"], rel=1e-12)

    # stopped inside the first extension, resumed: the same run to the last bit
    steps_per_cycle = ref["steps"] / (settle + 12)
    check = int((settle + 6.5) * steps_per_cycle / config.DEM_CHECK_INTERVAL) + 1
    stop_mid_frame(case, tmp_path / "cut", monkeypatch, check, ref["timestep"])
    monkeypatch.setattr(config, "DEM_STEADY_Z", -1.0)  # stop_mid_frame undid the patches
    monkeypatch.setattr(config, "DEM_AUTO_SETTLE_MAX_CYCLES", 8)
    resumed = run_case(case, tmp_path / "cut", progress=False, threads=1, resume=True)
    assert resumed["per_cycle_velocity"] == ref["per_cycle_velocity"]
    assert resumed["steadiness"] == ref["steadiness"]


@pytest.mark.integration
def test_the_steadiness_study_replays_the_settle_dem_run_takes(tmp_path):
    """validation/steadiness/beds.py judges settle rules on series recorded from cycle 0; its
    replay of the default rule must end the settle where `dem run` does, and what follows must
    be the very cycles `dem run` measured."""
    import importlib.util
    from pathlib import Path

    from dem.run.record import settle_floor

    path = Path(__file__).resolve().parents[2] / "validation" / "steadiness" / "beds.py"
    spec = importlib.util.spec_from_file_location("beds", path)
    beds = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(beds)

    text = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 6", "cycles = 3")))
    auto = run_case(case, tmp_path / "auto", progress=False, threads=1, frames=False)
    settle = auto["settle_cycles"]
    beds.MEASURED = 3
    recorded = load_case(tmp_path / "case", {"run.settle_cycles": 0, "run.cycles": settle + 3})
    with pytest.warns(UserWarning):  # an explicit settle below the friction floor: warned
        every = run_case(recorded, tmp_path / "all", progress=False, threads=1, frames=False)
    series = np.array(every["per_cycle_velocity"]) / case.drive.velocity_scale
    assert beds.replay_settle(series, settle_floor(case), "mser+trend", 2.0) == settle
    assert every["per_cycle_velocity"][settle : settle + 3] == auto["per_cycle_velocity"][:3]


@pytest.mark.integration
def test_a_run_stopped_while_its_automatic_settle_goes_on_resumes_bit_for_bit(
    tmp_path, monkeypatch
):
    """The checkpoint of an "auto" settle has no total yet: reading it used to compute the
    old-format default anyway (None - int), so such a run could not be resumed."""
    text = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    text = text.replace("frames_per_cycle = 3", "frames_per_cycle = 1")
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 6", "cycles = 3")))
    ref = run_case(case, tmp_path / "straight", progress=False, threads=1)
    steps_per_cycle = ref["steps"] / (ref["settle_cycles"] + 3)
    check = int(2.5 * steps_per_cycle / config.DEM_CHECK_INTERVAL) + 1  # the settle's 3rd cycle
    stop_mid_frame(case, tmp_path / "cut", monkeypatch, check, ref["timestep"])
    resumed = run_case(case, tmp_path / "cut", progress=False, threads=1, resume=True)
    assert resumed["settle_cycles"] == ref["settle_cycles"]
    assert resumed["per_cycle_velocity"] == ref["per_cycle_velocity"]
