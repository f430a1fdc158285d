"""The finite feeder: back wall, discharge, feed, mass balance, ragged frames, checkpoints."""

import json
import math

import numpy as np
import pytest
from small_case import stop_mid_frame, write_case

from dem.engine import setup
from dem.errors import InputError
from dem.io import checkpoint as checkpoint_io
from dem.io.hdf5 import read_results
from dem.run.runner import run_case
from dem.scene.case import load_case

FEEDER = """
[trough]
length = 0.06
width = 0.02

[drive]
frequency = 60.0
angle = 25.0
throw_number = 1.8

[material]
density = 7800.0
friction = 0.35
# spheres free to roll keep rolling out over the discharge edge: the fill settled at rms
# 1.5e-3 m/s after 5 s under the impact-aware law, whose rigid stick does not damp rolling as
# the soft "coulomb" spring did (1.1e-3 m/s): rolling resistance, as a real pan's parts have
rolling_friction = 0.05

[contact]
model = "hertz_mindlin"
youngs_modulus = 5.0e7

[particles]
shape = "sphere"
count = 60
radius = 0.002

[run]
settle_cycles = 1
cycles = 5
seed = 3

[output]
frames_per_cycle = 4

[feeder]
feed_rate = 0.01
feed_length = 0.015
"""

SCREWS = """
[particles]
shape = "screw"
count = 12
length = 0.022
shank_radius = 0.0018
head_radius = 0.0036
mass = 0.0025
"""


def _case(tmp_path, text=FEEDER, **overrides):
    return load_case(write_case(tmp_path / "case", text), overrides=overrides or None)


@pytest.mark.validation
def test_feeder_keys_are_read_and_checked(tmp_path):
    case = _case(tmp_path)
    assert case.feeder.feed_rate == 0.01 and case.feeder.feed_length == 0.015
    assert _case(tmp_path, FEEDER.replace("feed_length = 0.015\n", "")).feeder.feed_length == (
        pytest.approx(0.015)  # a quarter of the trough
    )
    bad = [
        ("feed_rate = 0.01", "feed_rate = -1.0", "feeder.feed_rate", "[0, 1000] kg/s"),
        ("feed_length = 0.015", "feed_length = 0.1", "feeder.feed_length", "<= trough.length"),
        ("feed_length = 0.015", "feed_length = 0.002", "feeder.feed_length", "one grain's"),
        ("feed_rate = 0.01", "feed_rat = 0.01", "feeder.feed_rat", "did you mean 'feed_rate'"),
    ]
    for old, new, key, allowed in bad:
        with pytest.raises(InputError) as info:
            _case(tmp_path, FEEDER.replace(old, new))
        assert info.value.key == key and allowed in str(info.value)
    assert _case(tmp_path, FEEDER.split("[feeder]")[0]).feeder is None


@pytest.mark.validation
def test_back_wall_is_the_floor_turned_upright(tmp_path):
    """Without gravity a grain sent at 1 m/s at the back wall rebounds exactly as one sent at the
    floor (the same contact law, normal +x instead of +z), and never gets behind it."""
    case = _case(tmp_path)
    r = case.particles.radius
    at_wall = setup.from_grains(case, np.array([[0.002 + r, 0.0, 0.01]]),
                                velocities=np.array([[-1.0, 0.0, 0.0]]))  # fmt: skip
    at_floor = setup.from_grains(case, np.array([[0.03, 0.0, 0.002 + r]]), timestep=at_wall.dt,
                                 velocities=np.array([[0.0, 0.0, -1.0]]))  # fmt: skip
    assert at_wall.trough.finite and at_wall.trough.back == 0.0
    lowest = math.inf
    for sim in (at_wall, at_floor):
        sim.gravity = np.zeros(3)
    for _ in range(100):
        at_wall.run(10)
        at_floor.run(10)
        lowest = min(lowest, float(at_wall.spheres.x[0, 0]))
    assert lowest > 0.9 * r  # the overlap never passed a tenth of the radius
    rebound = at_wall.spheres.v[0, 0]
    # eps_n = 0 is a perfectly plastic contact (README "Contacts"): no rebound at either wall
    # (the critically damped dashpot before it returned 0.13 of the impact speed)
    assert abs(rebound) < 1e-6
    assert rebound == pytest.approx(at_floor.spheres.v[0, 2], rel=1e-12)
    assert at_wall.spheres.x[0, 0] == pytest.approx(at_floor.spheres.x[0, 2], rel=1e-12)


@pytest.mark.validation
def test_a_grain_over_the_edge_is_removed_and_counted(tmp_path):
    case = _case(tmp_path, **{"feeder.feed_rate": 0.0})
    r = case.particles.radius
    length = case.trough.length
    sim = setup.from_grains(
        case, np.array([[length - 0.001, 0.0, r], [0.02, 0.0, r]]),
        velocities=np.array([[0.3, 0.0, 0.0], [0.0, 0.0, 0.0]]),
    )  # fmt: skip
    sim.start_drive()
    kept_id = sim.grain_id[1]
    sim.run(4 * sim.feeder.interval)
    f = sim.feeder
    assert (f.inserted, sim.n_grains, f.discharged) == (2, 1, 1)
    assert f.discharged_mass == pytest.approx(f.grain_mass)
    assert sim.grain_id.tolist() == [kept_id]
    assert sim.spheres.x[0, 0] < length


@pytest.mark.validation
def test_mass_balance_holds_in_every_frame_and_the_feed_rate_is_met(tmp_path):
    case = _case(tmp_path)
    summary = run_case(case, tmp_path / "out", progress=False)
    r = read_results(tmp_path / "out" / "results.h5")
    assert r["format_version"] == 3
    f = summary["feeder"]
    assert f["grains_discharged"] > 0 and f["grains_inserted"] > case.particles.count // 2
    for i in range(r["frame_count"]):
        frame = r["frames"][i]
        assert frame["grains_inserted"] == frame["grains_in_trough"] + frame["grains_discharged"]
        assert frame["mass_inserted"] == pytest.approx(
            frame["mass_in_trough"] + frame["mass_discharged"], rel=1e-12
        )
        assert frame["positions"].shape == (frame["grains_in_trough"], 3)
        assert np.all(frame["positions"][:, 0] < case.trough.length + 0.01)
        assert len(set(frame["grain_id"].tolist())) == frame["grains_in_trough"]
    # fed grains get new lasting ids, never one the fill gave (spilled grains' included)
    fed_ids = set(r["frames"][-1]["grain_id"].tolist()) - set(r["frames"][0]["grain_id"].tolist())
    assert fed_ids and min(fed_ids) >= case.particles.count
    # the feed delivers feed_rate, up to a grain, from the drive's start (frame 0)
    first, last = r["frames"][0], r["frames"][-1]
    assert first["time"] == 0.0 and first["grains_discharged"] == 0
    fed = int(last["grains_inserted"] - first["grains_inserted"])
    owed = case.feeder.feed_rate * last["time"] / _grain_mass(case)
    assert fed + f["feed_backlog"] == int(owed) or abs(fed + f["feed_backlog"] - owed) <= 1
    assert fed > 0
    cycles = r["cycles"]
    # the per-cycle discharge rate is the discharged mass over the period
    np.testing.assert_allclose(cycles["discharge_rate"] * (1 / 60.0), cycles["discharged_mass"])
    measured = cycles["measured"] == 1
    assert f["discharge_rate"] == pytest.approx(np.mean(cycles["discharge_rate"][measured]))
    assert summary["grains"] == f["grains_in_trough"]
    # VTK frames hold the grains present in each frame
    pvd = (tmp_path / "out" / "particles.pvd").read_text()
    assert pvd.count('part="0"') == r["frame_count"]


def _grain_mass(case):
    return case.material.density * 4 / 3 * math.pi * case.particles.radius**3


@pytest.mark.validation
def test_removing_a_grain_that_touches_nothing_changes_nothing_else(tmp_path):
    """replace_grains keeps the others' state and contact history: a bed with one extra grain
    far from it, removed after a while, moves bit for bit as the bed without it."""
    case = _case(tmp_path, **{"feeder.feed_rate": 0.0})
    a = setup.from_case(case)
    a.settle()
    far = np.array([[case.trough.length - 0.004, 0.0, 0.03]])
    grains = np.vstack([a.spheres.x, far])
    b = setup.from_grains(case, grains, timestep=a.dt)
    c = setup.from_grains(case, a.spheres.x.copy(), timestep=a.dt)
    for sim in (b, c):
        sim.spheres.v[: a.spheres.n] = a.spheres.v
        sim.start_drive()
    b.run(300)
    c.run(300)
    b.replace_grains(np.arange(b.n_grains) < c.n_grains)
    b.run(700)
    c.run(700)
    np.testing.assert_array_equal(b.spheres.x, c.spheres.x)
    np.testing.assert_array_equal(b.spheres.v, c.spheres.v)


@pytest.mark.validation
def test_a_checkpoint_of_a_feeder_resumes_bit_for_bit(tmp_path):
    case = _case(tmp_path)
    a = setup.from_case(case)
    a.settle()
    a.start_drive()
    steps = int(round(1.0 / 60.0 / a.dt))
    a.run(steps)
    state = {k: np.array(v, copy=True) for k, v in checkpoint_io.state_dict(a).items()}
    feeder_state = json.loads(json.dumps(a.feeder.state()))
    b = setup.from_case(case)
    checkpoint_io.load_state(b, state)
    b.feeder.restore(feeder_state)
    a.run(2 * steps)
    b.run(2 * steps)
    assert a.feeder.inserted > case.particles.count - 20 and a.feeder.state() == b.feeder.state()
    np.testing.assert_array_equal(a.spheres.x, b.spheres.x)
    np.testing.assert_array_equal(a.grain_id, b.grain_id)


@pytest.mark.validation
def test_screws_are_fed_and_discharged_as_rigid_bodies(tmp_path):
    text = (
        FEEDER.split("[particles]")[0].replace("density = 7800.0\n", "")
        + SCREWS
        + "[run]"
        + FEEDER.split("[run]")[1]
    )
    text = text.replace("length = 0.06", "length = 0.09").replace("width = 0.02", "width = 0.03")
    text = text.replace("feed_rate = 0.01", "feed_rate = 0.15").replace(
        "feed_length = 0.015", "feed_length = 0.03"
    )
    case = _case(tmp_path, text, **{"run.cycles": 3, "drive.throw_number": 2.5})
    summary = run_case(case, tmp_path / "out", progress=False, frames=True)
    f = summary["feeder"]
    assert f["grains_inserted"] > case.particles.count
    r = read_results(tmp_path / "out" / "results.h5")
    last = r["frames"][-1]
    members = 8
    assert last["positions"].shape[0] == members * last["grains_in_trough"]
    assert last["orientation"].shape == (last["grains_in_trough"], 4)
    # each screw's members sit at the template's distances from its first member
    idx = last["grain_index"]
    for g in range(last["grains_in_trough"]):
        pts = last["positions"][idx == g]
        assert pts.shape[0] == members
        assert np.max(np.linalg.norm(pts - pts.mean(axis=0), axis=1)) < 0.02


@pytest.mark.validation
def test_a_feeder_in_a_u_pan_keeps_every_grain_inside_the_mesh(tmp_path):
    """Mesh pan, back wall and feed together: every sphere of every frame lies on the grains'
    side of the U mesh, clear of it, in front of the back wall, and the balance holds."""
    from pathlib import Path

    from dem.scene.fill import inside_mesh
    from dem.scene.mesh import load_mesh

    stl = Path(__file__).resolve().parents[2] / "cases" / "geometry" / "u_trough.stl"
    text = FEEDER.replace(
        "length = 0.06\nwidth = 0.02", f'length = 0.12\nwidth = 0.06\nmesh = "{stl}"'
    )
    text = text.replace("feed_rate = 0.01", "feed_rate = 0.05").replace(
        "feed_length = 0.015", "feed_length = 0.03"
    )
    # without rolling resistance the spheres along the pan's bottom keep rolling out over the
    # open edge one by one and the fill never comes to rest (the settle error says so)
    case = _case(tmp_path, text, **{"run.cycles": 2, "material.rolling_friction": 0.05})
    summary = run_case(case, tmp_path / "out", progress=False)
    mesh = load_mesh(stl, length=0.12)
    r = read_results(tmp_path / "out" / "results.h5")
    for i in range(r["frame_count"]):
        frame = r["frames"][i]
        x = frame["positions"]
        on_pan = x[:, 0] < 0.12
        assert np.all(inside_mesh(mesh, x[on_pan], 0.5 * case.particles.radius))
        assert np.all(x[:, 0] > 0.5 * case.particles.radius)
        assert frame["grains_inserted"] == frame["grains_in_trough"] + frame["grains_discharged"]
    assert summary["feeder"]["grains_inserted"] > r["frames"][0]["grains_inserted"]


@pytest.mark.validation
def test_a_feeder_run_stopped_by_sigterm_resumes_bit_for_bit(tmp_path):
    """dem run on a feeder, SIGTERM mid-run, --resume: the same per-cycle velocities and
    discharge, the same grains inserted, the same last frame (ragged results.h5 trimmed)."""
    import signal

    from test_runner import _start, _wait_for_frames

    case_dir = write_case(tmp_path / "case", FEEDER.replace("cycles = 5", "cycles = 10"))
    case = load_case(case_dir)
    straight = run_case(case, tmp_path / "straight", progress=False, threads=1)
    out = tmp_path / "stopped"
    proc = _start(case_dir, out)
    _wait_for_frames(out, 10, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM, err
    resumed = run_case(case, out, progress=False, threads=1, resume=True)
    assert resumed["per_cycle_velocity"] == straight["per_cycle_velocity"]
    for key in ("discharge_rate_per_cycle", "grains_inserted", "grains_discharged"):
        assert resumed["feeder"][key] == straight["feeder"][key]
    a = read_results(tmp_path / "straight" / "results.h5")
    b = read_results(out / "results.h5")
    assert b["frame_count"] == a["frame_count"]
    np.testing.assert_array_equal(a["frames"][-1]["positions"], b["frames"][-1]["positions"])
    np.testing.assert_array_equal(a["frames"][-1]["grain_id"], b["frames"][-1]["grain_id"])


@pytest.mark.validation
def test_a_signal_mid_frame_stops_a_feeder_there_and_it_resumes_bit_for_bit(tmp_path, monkeypatch):
    """A feeder honours SIGTERM after any exchange chunk, not only at a frame's end: the
    checkpoint lies inside a frame, and the resumed run feeds, discharges and conveys exactly
    as an uninterrupted one (its chunks, and so its exchanges, fall on the same steps)."""

    text = FEEDER.replace("frames_per_cycle = 4", "frames_per_cycle = 1")
    case = load_case(write_case(tmp_path / "case", text.replace("cycles = 5", "cycles = 3")))
    reference = run_case(case, tmp_path / "straight", progress=False, threads=1)
    out = tmp_path / "interrupted"
    # 16 exchange chunks a frame: the 23rd check is inside the second frame
    stop_mid_frame(case, out, monkeypatch, 23, reference["timestep"])
    resumed = run_case(case, out, progress=False, threads=1, resume=True)
    assert resumed["per_cycle_velocity"] == reference["per_cycle_velocity"]
    assert resumed["steps"] == reference["steps"]
    for key in ("discharge_rate_per_cycle", "grains_inserted", "grains_discharged"):
        assert resumed["feeder"][key] == reference["feeder"][key]
    a = read_results(tmp_path / "straight" / "results.h5")
    b = read_results(out / "results.h5")
    np.testing.assert_array_equal(a["frames"][-1]["positions"], b["frames"][-1]["positions"])
    np.testing.assert_array_equal(a["frames"][-1]["grain_id"], b["frames"][-1]["grain_id"])
