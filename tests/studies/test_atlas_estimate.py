"""The atlas used: the bulk's v_norm between an atlas's points, never outside them."""

import csv
import itertools
import json

import pytest
from small_case import run_cli

from dem.errors import InputError
from dem.run import bulk as atlas


def v(depth, mu, gamma, phi):
    """A smooth made-up bulk: linear in every axis, so interpolation is exact."""
    return 0.2 + 0.05 * depth + 0.3 * mu + 0.1 * gamma + 0.004 * phi


def write_atlas(path, skip=()):
    columns = ["shape", "particles.layers", "material.friction", "drive.throw_number",
               "drive.angle_deg", "mean_velocity_norm", "mean_velocity_norm_stderr",
               "status"]  # fmt: skip
    with path.open("w", newline="") as handle:
        w = csv.writer(handle)
        w.writerow(columns)
        for d, mu, g, phi in itertools.product((1.0, 2.0, 4.0), (0.35,), (1.8, 2.6, 3.5),
                                               (10.0, 25.0, 40.0)):  # fmt: skip
            if (d, g, phi) in skip:
                continue
            w.writerow(["sphere", d, mu, g, phi, v(d, mu, g, phi), 0.01, "done"])
        w.writerow(["sphere", 1.0, 0.35, 4.5, 10.0, "", "", "not run"])  # ignored
    return path


def test_an_estimate_between_points_is_their_multilinear_blend(tmp_path):
    rows = atlas.read_table(write_atlas(tmp_path / "atlas.csv"))
    e = atlas.estimate(rows, "sphere", depth=1.5, friction=0.35, throw_number=2.2, angle=30.0)
    assert e.velocity_norm == pytest.approx(v(1.5, 0.35, 2.2, 30.0))
    assert len(e.corners) == 8 and sum(c["weight"] for c in e.corners) == pytest.approx(1.0)
    assert e.interpolation == pytest.approx(0.0, abs=1e-12)  # linear: no curvature to miss
    # the corners' errors, weighted: at mid-cell 0.01 / sqrt(8) * ... (never more than 0.01)
    assert 0.0 < e.stderr <= 0.01
    on = atlas.estimate(rows, "sphere", depth=2.0, friction=0.35, throw_number=2.6, angle=25.0)
    assert on.velocity_norm == v(2.0, 0.35, 2.6, 25.0) and on.stderr == 0.01
    assert len(on.corners) == 1


def test_the_interpolation_error_follows_the_curvature_the_next_point_shows():
    """Three Gamma values on a parabola: linear interpolation misses (1/2) w (1 - w) h^2 f'',
    which the estimate states; with two values only, the change across the cell counts."""
    curve = {1.8: 0.5, 2.6: 0.8, 3.4: 0.7}  # f'' = (0.5 - 1.6 + 0.7) / 0.64 = -0.625
    rows = [{"shape": "screw", "particles.layers": 1.0, "material.friction": 0.35,
             "drive.throw_number": g, "drive.angle_deg": 25.0, "mean_velocity_norm": vn,
             "mean_velocity_norm_stderr": 0.0} for g, vn in curve.items()]  # fmt: skip
    e = atlas.estimate(rows, "screw", depth=1.0, friction=0.35, throw_number=2.2, angle=25.0)
    assert e.velocity_norm == pytest.approx(0.65)
    true = 0.5 + (0.8 - 0.5) * 0.5 + 0.5 * 0.25 * 0.64 * 0.625  # the parabola at 2.2
    assert e.interpolation == pytest.approx(abs(true - 0.65))
    two = [r for r in rows if r["drive.throw_number"] != 3.4]
    e2 = atlas.estimate(two, "screw", depth=1.0, friction=0.35, throw_number=2.2, angle=25.0)
    assert e2.interpolation == pytest.approx(0.25 * 0.3)


def test_no_extrapolation_and_no_missing_corner(tmp_path):
    rows = atlas.read_table(write_atlas(tmp_path / "atlas.csv", skip={(2.0, 2.6, 25.0)}))
    with pytest.raises(InputError, match=r"--angle.*10 to 40.*no extrapolation"):
        atlas.estimate(rows, "sphere", depth=2.0, friction=0.35, throw_number=2.0, angle=60.0)
    with pytest.raises(InputError, match=r"--depth.*1 to 4"):
        atlas.estimate(rows, "sphere", depth=5.0, friction=0.35, throw_number=2.0, angle=20.0)
    with pytest.raises(InputError, match=r"--friction.*0\.35 to 0\.35"):
        atlas.estimate(rows, "sphere", depth=2.0, friction=0.5, throw_number=2.0, angle=20.0)
    with pytest.raises(InputError, match=r"none at layers 2, friction 0\.35, throw_number 2\.6"):
        atlas.estimate(rows, "sphere", depth=2.0, friction=0.35, throw_number=2.2, angle=30.0)
    with pytest.raises(InputError, match=r"--bulk.*a shape of the atlas: sphere"):
        atlas.estimate(rows, "screw", depth=2.0, friction=0.35, throw_number=2.2, angle=20.0)


def test_pointmass_velocity_prints_the_atlass_bulk(tmp_path, capsys):
    path = write_atlas(tmp_path / "atlas.csv")
    code, out, err = run_cli(capsys, "pointmass", "velocity", "--throw-number", "2.2", "--angle",
                             "30", "--friction", "0.35", "--bulk", "sphere", "--depth", "1.5",
                             "--atlas", path, "--json")  # fmt: skip
    assert code == 0, err
    bulk = json.loads(out)["bulk"]
    assert bulk["velocity_norm"] == pytest.approx(v(1.5, 0.35, 2.2, 30.0))
    assert bulk["ratio_bounded"] == pytest.approx(
        bulk["velocity_norm"] / bulk["pointmass_bounded_velocity_norm"])  # fmt: skip
    code, _, err = run_cli(
        capsys,
        "pointmass",
        "velocity",
        "--throw-number",
        "2.2",
        "--angle",
        "30",
        "--friction",
        "0.35",
        "--bulk",
        "sphere",
        "--atlas",
        path,
    )
    assert code == 2 and "--depth" in err


def test_plan_says_from_the_atlas_whether_the_point_mass_answers(tmp_path, monkeypatch):
    """A synthetic atlas around the shipped sphere bed's drive: a bulk at the bounded point mass
    answers within 3 %; one 20 % below it does not. No atlas: no note."""
    from pathlib import Path

    from dem import pointmass
    from dem.run import bulk
    from dem.run.plan import plan
    from dem.scene.case import load_case

    case = load_case(Path(__file__).resolve().parents[2] / "cases" / "sphere-bed",
                     {"particles.layers": 2.0})  # fmt: skip
    d = case.drive
    pm = pointmass.velocity(d.throw_number, 25.0, 0.35, 0.0, 0.8, 0.0, impact="coulomb")
    notes = []
    for factor in (1.0, 0.8):
        path = tmp_path / f"atlas{factor}.csv"
        with path.open("w", newline="") as handle:
            w = csv.writer(handle)
            w.writerow(["shape", "particles.layers", "material.friction", "drive.throw_number",
                        "drive.angle_deg", "mean_velocity_norm", "mean_velocity_norm_stderr",
                        "status"])  # fmt: skip
            for layers in (1.0, 4.0):
                w.writerow(["sphere", layers, 0.35, d.throw_number, 25.0,
                            factor * pm.velocity_norm, 0.002, "done"])  # fmt: skip
        monkeypatch.setattr(bulk, "default_table", lambda path=path: path)
        said = bulk.point_mass_answers(case)
        assert said["ratio"] == pytest.approx(factor)
        notes.append([a.text for a in plan(case).advice if "by the atlas" in a.text])
    assert "the point mass answers" in notes[0][0] and "DEM run is needed" in notes[1][0]
    monkeypatch.setattr(bulk, "default_table", lambda: None)
    assert bulk.point_mass_answers(case) is None
    assert not [a for a in plan(case).advice if "atlas" in a.text]
