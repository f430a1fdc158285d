"""The instability checks name the measured cause, and large but stable overlaps finish.

Issue item 15: every stop names what was measured (overlap, speed, a grain leaving the trough,
a bed running away downhill): which grain, where and when, and only the fixes that address it.
Issue item 16: an overlap above the accuracy bound (DEM_OVERLAP_WARN_FRACTION) but stable runs
to the end with a warning and its record (max_overlap_fraction, where, when, the stiffness that
would bring it under the bound) in summary.json; a stop is kept for true instability: beyond the
hard bound DEM_MAX_OVERLAP_FRACTION, an overlap growing at consecutive checks, non-finite values,
speeds no drive explains.
"""

import json
import math

import numpy as np
import pytest

from dem import config
from dem.config import GRAVITY
from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import Spheres
from dem.errors import SimulationError
from dem.kernels import contact
from dem.run.runner import run_case
from dem.scene.case import load_case
from dem.scene.mesh import extrude, load_mesh
from dem.scene.trough import Trough

RADIUS, DENSITY = 2.0e-3, 7800.0
MASS = DENSITY * 4 / 3 * math.pi * RADIUS**3
LENGTH, WIDTH = 0.02, 0.02


def _linear(kn=1.0e5, e=0.0, mu=0.35):
    return ContactLaw(
        "linear",
        contact.make_params(
            model="linear",
            stiffness=kn,
            restitution=e,
            friction=mu,
            tangential_stiffness_ratio=2 / 7,
        ),
    )


def _sim(positions, *, kn=1.0e5, e=0.0, inclination=0.0, mesh=None, **kwargs):
    spheres = Spheres.create(np.asarray(positions, dtype=float), RADIUS, DENSITY)
    dt = contact.linear_collision_time(kn, MASS, -1.0 if e == 0.0 else 0.0) / 50
    trough = Trough(LENGTH, WIDTH, inclination=math.radians(inclination))
    return Simulation(spheres, trough, _linear(kn=kn, e=e), dt, mesh=mesh, **kwargs)


def _stop(sim, steps=None) -> str:
    with pytest.raises(SimulationError) as info:
        if steps is None:
            sim.check()
        else:
            sim.run(steps)
    return str(info.value)


def test_thresholds_are_ordered():
    """The accuracy bound warns, the hard bound (five times it) stops."""
    assert 0.0 < config.DEM_OVERLAP_WARN_FRACTION < config.DEM_MAX_OVERLAP_FRACTION < 1.0
    assert config.DEM_OVERLAP_GROWTH_CHECKS >= 2 and config.DEM_OVERLAP_GROWTH_FACTOR > 1.0


# --- item 16: large but stable overlaps finish, with their record -----------------------------


@pytest.mark.parametrize("fraction", [0.107, 0.3])
def test_a_stable_overlap_above_the_accuracy_bound_finishes_with_its_record(fraction):
    """A block resting on the floor on a spring soft enough for a static overlap of 0.107
    radii (the LIGGGHTS-parity screw bed's seed that dem stopped) or 0.3: no stop now."""
    kn = MASS * GRAVITY / (fraction * RADIUS)
    sim = _sim([[0.01, 0.0, RADIUS * (1 - fraction)]], kn=kn, rotation=False)
    sim.run(3 * config.DEM_CHECK_INTERVAL)  # stopped at the first check before
    record = sim.overlap_summary()
    assert record["fraction"] == pytest.approx(fraction, rel=1e-3)
    assert record["grain"] == 0 and record["against"] == "floor"
    assert record["step"] == config.DEM_CHECK_INTERVAL and record["phase"] == "drive off"
    assert record["time_s"] == pytest.approx(config.DEM_CHECK_INTERVAL * sim.dt)
    assert record["position_m"][2] == pytest.approx(0.0, abs=1e-9)  # on the floor
    expected = kn * (fraction / config.DEM_OVERLAP_WARN_FRACTION) ** 2
    assert record["stiffer"] == {"contact.stiffness": pytest.approx(expected)}
    (warning,) = sim.overlap_warnings()
    assert f"{fraction:.3g} radii" in warning and "grain 0" in warning and "floor" in warning
    assert "contact.stiffness" in warning and f"{expected:.3g}" in warning


def test_no_warning_below_the_accuracy_bound():
    kn = MASS * GRAVITY / (0.05 * RADIUS)
    sim = _sim([[0.01, 0.0, RADIUS * 0.95]], kn=kn, rotation=False)
    sim.run(2 * config.DEM_CHECK_INTERVAL)
    assert sim.overlap_summary()["fraction"] == pytest.approx(0.05, rel=1e-3)
    assert sim.overlap_warnings() == []


def test_hertz_suggests_a_youngs_modulus():
    params = contact.make_params(
        model="hertz_mindlin", youngs_modulus=5e7, poisson_ratio=0.3, restitution=0.0, friction=0.35
    )
    law = ContactLaw("hertz_mindlin", params)
    spheres = Spheres.create(np.array([[0.01, 0.0, 0.8 * RADIUS]]), RADIUS, DENSITY)
    sim = Simulation(spheres, Trough(LENGTH, WIDTH), law, 1e-6)
    sim.check()
    assert sim.overlap_summary()["stiffer"] == {
        "contact.youngs_modulus": pytest.approx(5e7 * 2.0**2.5)
    }


def test_beyond_the_hard_bound_the_run_stops_naming_the_contact():
    sim = _sim([[0.01, 0.0, 0.4 * RADIUS]])
    message = _stop(sim)
    assert message.startswith("overlap of 0.6 radii")
    assert "grain 0" in message and "floor" in message and "t = 0 s" in message
    assert "DEM_MAX_OVERLAP_FRACTION" in message and "contact.stiffness" in message
    assert "timestep" not in message  # a soft contact: a shorter step would not help


def _pair(sim, overlap):
    """Place sphere 1 beside sphere 0 (mid-air, at rest) with ``overlap`` radii between them."""
    sim.spheres.x[1] = sim.spheres.x[0] + [(2.0 - overlap) * RADIUS, 0.0, 0.0]
    sim.spheres.v[:] = 0.0
    sim.compute_forces()  # the pair list, as a step builds it


def test_an_overlap_growing_at_consecutive_checks_stops_the_run():
    sim = _sim([[0.005, 0.0, 0.005], [0.009, 0.0, 0.005]])
    factor, first = 1.01 * config.DEM_OVERLAP_GROWTH_FACTOR, 0.11
    for k in range(config.DEM_OVERLAP_GROWTH_CHECKS):
        _pair(sim, first * factor**k)
        sim.check()
    _pair(sim, first * factor**config.DEM_OVERLAP_GROWTH_CHECKS)
    message = _stop(sim)
    assert "grew" in message and "grain 0" in message and "grain 1" in message
    assert "timestep" in message


def test_overlaps_that_come_and_go_do_not_stop_the_run():
    """Impacts give a different worst overlap at each check, large or small: no growth."""
    sim = _sim([[0.005, 0.0, 0.005], [0.009, 0.0, 0.005]])
    for overlap in (0.12, 0.3, 0.15, 0.35, 0.2, 0.45, 0.12, 0.2, 0.32, 0.13):
        _pair(sim, overlap)
        sim.check()
    assert sim.overlap_summary()["fraction"] == pytest.approx(0.45)


# --- item 15: each stop names its measured cause ------------------------------------------------


def test_a_bed_sliding_down_a_steep_trough_is_named_as_such():
    """60 deg at mu = 0.35: the block accelerates downhill; it used to be reported as an
    unstable integration, with a smaller time step as the fix."""
    sim = _sim([[0.01, 0.0, RADIUS - MASS * GRAVITY * 0.5 / 1e5]], inclination=60.0,
               rotation=False, reference_speed=0.05)  # fmt: skip
    message = _stop(sim, 200_000)
    assert "downhill" in message and "60 deg" in message and "trough.inclination" in message
    assert "timestep" not in message and "grain 0" in message


def test_a_grain_through_a_mesh_floor_is_named_leaving_the_trough(tmp_path):
    """A soft contact lets a fast grain through the thin mesh floor; it fell until it outran
    the speed check (0.75 s later), reported as an unstable integration."""
    import meshio

    h = 0.5 * WIDTH
    path = tmp_path / "box.stl"
    meshio.write(path, extrude([[-h, 0.01], [-h, 0.0], [h, 0.0], [h, 0.01]], LENGTH),
                 binary=False)  # fmt: skip
    mesh = load_mesh(path, length=LENGTH)
    sim = _sim([[0.01, 0.0, 0.003]], kn=1e3, e=1.0, mesh=mesh)
    sim.spheres.v[0, 2] = -5.0
    message = _stop(sim, 50_000)
    assert "grain 0 left the trough" in message and "below the trough" in message
    assert "t = " in message and "(x, y, z)" in message and "contact.stiffness" in message


def test_a_centre_past_a_flat_side_wall_is_named_leaving_the_trough():
    sim = _sim([[0.01, 0.5 * WIDTH + 0.5 * RADIUS, 0.005]])
    message = _stop(sim)
    assert "side wall y = +width/2" in message and "leaving the trough" in message
    assert "grain 0" in message


def test_a_grain_far_above_the_trough_stops_the_run():
    sim = _sim([[0.01, 0.0, 0.005]])
    sim.spheres.x[0, 2] = 50.0
    message = _stop(sim)
    assert "grain 0" in message and "far above the trough" in message and "timestep" in message


def test_non_finite_values_name_the_grain():
    sim = _sim([[0.005, 0.0, 0.005], [0.012, 0.0, 0.005]])
    sim.spheres.v[1, 0] = math.nan
    message = _stop(sim)
    assert "non-finite" in message and "grain 1" in message and "timestep" in message


def test_a_speed_no_drive_explains_names_the_grain_and_only_the_time_step():
    sim = _sim([[0.005, 0.0, 0.005], [0.012, 0.0, 0.005]])
    sim.spheres.v[1, 1] = 100.0
    message = _stop(sim)
    assert "grain 1" in message and "100 m/s" in message and "(x, y, z)" in message
    assert "timestep" in message
    assert "throw_number" not in message and "stiffer" not in message  # they do not fix it


def test_the_overlap_record_samples_the_same_steps_however_short_the_chunks(monkeypatch):
    """A busy machine shortens ``run``'s chunks (DEM_STOP_LATENCY_S, the thread guard's tries);
    the checks, and so the overlap record, stay on every DEM_CHECK_INTERVAL-th step of a call
    and its last. Here chunks of one step against whole ones: the same checks, the same record."""
    monkeypatch.setattr(config, "DEM_CHECK_INTERVAL", 50)
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(0, LENGTH, 6), rng.uniform(-0.002, 0.002, 6),
                         RADIUS + 0.004 * np.arange(6)])  # fmt: skip
    records, checked = [], []
    for latency in (1.0, 1e-12):
        monkeypatch.setattr(config, "DEM_STOP_LATENCY_S", latency)
        sim = _sim(x)
        sim.spheres.v[:, 2] = -0.3  # falling onto the floor and onto each other
        steps, check = [], sim.check
        monkeypatch.setattr(sim, "check", lambda s=sim, steps=steps, check=check: (
            steps.append(s.step_index), check()))  # fmt: skip
        sim.run(437, stop=lambda: False)
        sim.run(100, stop=lambda: False)
        checked.append(steps)
        records.append(repr(sim._max_overlap))
        assert sim._max_overlap["fraction"] > 0.0
    assert checked[0] == checked[1] == [50 * k for k in range(1, 9)] + [437, 487, 537]
    assert records[0] == records[1]


# --- the runner writes the record -------------------------------------------------------------


@pytest.mark.validation
def test_summary_holds_the_overlap_record_and_the_warning(tmp_path, monkeypatch):
    """Bound lowered below the single sphere's resting overlap: the run finishes and says so."""
    case = load_case("cases/single-sphere", overrides={"run.settle_cycles": 1, "run.cycles": 2})
    monkeypatch.setattr(config, "DEM_OVERLAP_WARN_FRACTION", 1e-12)
    with pytest.warns(UserWarning, match="overlap"):
        summary = run_case(case, tmp_path / "out", progress=False, frames=False)
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert on_disk["max_overlap_fraction"] == summary["max_overlap_fraction"] > 0.0
    assert on_disk["max_overlap"]["grain"] == 0 and on_disk["max_overlap"]["against"] == "floor"
    assert len(on_disk["warnings"]) == 1 and "contact.stiffness" in on_disk["warnings"][0]
    monkeypatch.undo()
    summary = run_case(case, tmp_path / "again", progress=False, frames=False)
    # the deepest overlap is the dent of the fill's landing, which a perfectly plastic contact
    # (eps_n = 0) keeps: 3.0e-5 of the radius, the same from the fill's rest to 60 cycles on
    # (the elastic resting overlap under the weight would be 1.3e-7)
    assert summary["warnings"] == [] and summary["max_overlap_fraction"] < 1e-4


@pytest.mark.validation
def test_a_resumed_run_reports_the_overlap_of_the_whole_run(tmp_path, monkeypatch):
    """The record travels in the checkpoint: a run stopped mid-frame and resumed reports the
    deepest overlap of both parts (the fill's landing, before the stop, included), as the
    uninterrupted run does; a tampered record is a bad --resume file."""
    import zipfile

    from small_case import SMALL_CASE, stop_mid_frame, write_case

    from dem.errors import InputError

    text = SMALL_CASE.replace("frames_per_cycle = 3", "frames_per_cycle = 1")
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 6", "cycles = 3")))
    straight = run_case(case, tmp_path / "straight", progress=False, threads=1)
    out = tmp_path / "interrupted"
    stop_mid_frame(case, out, monkeypatch, 7, straight["timestep"])
    with np.load(out / "checkpoint.npz") as state:
        loop = json.loads(str(state["loop.json"]))
    assert loop["max_overlap"]["fraction"] > 0.0
    # a copy with a tampered record is refused, naming --resume
    bad = tmp_path / "bad"
    import shutil

    shutil.copytree(out, bad)
    loop_bad = dict(loop, max_overlap={"fraction": "deep"})
    with np.load(out / "checkpoint.npz") as state:
        arrays = {k: state[k] for k in state.files}
    arrays["loop.json"] = np.array(json.dumps(loop_bad))
    np.savez(bad / "checkpoint.npz", **arrays)
    assert zipfile.is_zipfile(bad / "checkpoint.npz")
    with pytest.raises(InputError, match="--resume"):
        run_case(case, bad, progress=False, threads=1, resume=True)
    resumed = run_case(case, out, progress=False, threads=1, resume=True)
    assert resumed["max_overlap"] == straight["max_overlap"]
    assert resumed["max_overlap"]["fraction"] >= loop["max_overlap"]["fraction"]
