import csv
import json

import numpy as np
import pytest

from dem.io.hdf5 import ResultsWriter
from dem.studies.report import make_report, running_statistics

PNG = b"\x89PNG\r\n\x1a\n"


def _summary(angle=25.0, norm=0.31, stderr=0.004, pm=0.42):
    scale = 0.0005 * 2 * np.pi * 60 * np.cos(np.radians(angle))
    return {
        "case": "spheres",
        "mean_velocity": norm * scale,
        "mean_velocity_stderr": stderr * scale,
        "mean_velocity_norm": norm,
        "mean_velocity_norm_stderr": stderr,
        "mass_flow_rate": 0.0123,
        "mass_flow_rate_per_width": 0.3,
        "amplitude": 0.0005,
        "throw_number": 1.8,
        "frequency": 60.0,
        "angle": angle,
        "inclination": 0.0,
        "friction": 0.35,
        "contact_model": "hertz_mindlin",
        "grains": 60,
        "spheres": 60,
        "total_mass": 0.02,
        "timestep": 5e-6,
        "steps": 40000,
        "settle_cycles": 2,
        "cycles": 6,
        "per_cycle_velocity": [norm * scale] * 6,
        "wall_time_s": 3.0,
        "particle_steps_per_s": 8e5,
        "threads": 1,
        "pointmass_velocity_norm": pm,
    }


def _run_folder(path, angle=25.0, with_h5=True, pm=0.42):
    path.mkdir(parents=True)
    s = _summary(angle=angle, pm=pm)
    (path / "summary.json").write_text(json.dumps(s))
    if with_h5:
        rng = np.random.default_rng(0)
        case = {"trough": {"length": 0.05, "width": 0.02}, "drive": {"angle": angle}}
        w = ResultsWriter(path / "results.h5", case=case, versions={}, seed=1, timestep=5e-6)
        n = 60
        for k in range(8):
            v = s["mean_velocity"] * (1 + 0.1 * rng.standard_normal()) if k >= 2 else 0.001
            w.append_cycle(cycle=k, time=k / 60.0, mean_velocity=v)
            pos = np.column_stack(
                [
                    rng.uniform(0, 0.05, n),
                    rng.uniform(-0.008, 0.008, n),
                    rng.uniform(0.002, 0.01, n),
                ]
            )
            w.append_frame(k / 60.0, pos, rng.normal(0.01, 0.01, (n, 3)), np.full(n, 0.002))
        w.close()
    return path


def _is_png(p):
    return p.read_bytes()[:8] == PNG and p.stat().st_size > 5000


def test_running_statistics_match_direct_formula():
    v = np.random.default_rng(3).normal(0.02, 0.003, 12)
    mean, err = running_statistics(v)
    assert np.isnan(err[0])
    for k in range(1, 13):
        assert np.isclose(mean[k - 1], v[:k].mean())
        if k > 1:
            assert np.isclose(err[k - 1], v[:k].std(ddof=1) / np.sqrt(k))


@pytest.mark.integration
def test_single_run_report(tmp_path):
    out = _run_folder(tmp_path / "run")
    files = make_report([out])
    names = {p.name for p in files}
    assert names == {
        "velocity_per_cycle.png",
        "pointmass_comparison.png",
        "bed_snapshot.png",
        "report.txt",
    }
    for p in files:
        assert p.parent == out / "report" and p.is_file()
        if p.suffix == ".png":
            assert _is_png(p), p
    text = (out / "report" / "report.txt").read_text()
    text.encode("ascii")
    assert "0.31 +- 0.004" in text  # normalised velocity and its standard error
    assert "0.42" in text and "0.738" in text  # point mass and DEM / point mass = 0.31 / 0.42
    assert "8 frames, complete" in text
    assert "results.h5 /cycles (8 cycles)" in text


def test_report_without_results_h5_skips_snapshot(tmp_path):
    out = _run_folder(tmp_path / "run", with_h5=False, pm=None)
    files = make_report([out], dest=tmp_path / "rep")
    names = {p.name for p in files}
    assert "bed_snapshot.png" not in names and "velocity_per_cycle.png" in names
    text = (tmp_path / "rep" / "report.txt").read_text()
    assert "summary.json (6 cycles)" in text and "bed_snapshot.png skipped" in text


@pytest.mark.integration
def test_comparison_across_runs(tmp_path):
    outs = [_run_folder(tmp_path / f"phi{a}", angle=a) for a in (15.0, 25.0, 35.0)]
    files = make_report(outs, dest=tmp_path / "cmp")
    names = [p.relative_to(tmp_path / "cmp").as_posix() for p in files]
    assert {"comparison.csv", "comparison.txt", "comparison.png"} <= set(names)
    assert "phi25.0/report.txt" in names and "phi35.0/bed_snapshot.png" in names
    with (tmp_path / "cmp" / "comparison.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["run"] for r in rows] == ["phi15.0", "phi25.0", "phi35.0"]
    assert [float(r["angle_deg"]) for r in rows] == [15.0, 25.0, 35.0]
    assert np.isclose(float(rows[1]["dem_over_pointmass"]), 0.31 / 0.42, rtol=1e-5)
    assert "mean_velocity_m_s" in rows[0] and "mass_flow_rate_kg_s" in rows[0]
    table = np.genfromtxt(tmp_path / "cmp" / "comparison.csv", delimiter=",", names=True,
                          dtype=None, encoding="utf-8")  # fmt: skip
    assert list(table["angle_deg"]) == [15.0, 25.0, 35.0]
    side = json.loads((tmp_path / "cmp" / "comparison.json").read_text())
    assert side["columns"]["mean_velocity_m_s"]["unit"] == "m/s" and side["provenance"]
    table = (tmp_path / "cmp" / "comparison.txt").read_text().splitlines()
    assert len(table) == 4 and "dem/pm" in table[0]
    # issue 48, item 6: the material and incline, and how many fills each error pools
    assert all(word in table[0].split() for word in ("mu", "alpha", "fills"))
    assert [int(r["replicas"]) for r in rows] == [1, 1, 1]
    assert _is_png(tmp_path / "cmp" / "comparison.png")


def test_missing_summary_is_named(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="summary.json"):
        make_report([tmp_path / "empty"])


@pytest.mark.integration
def test_report_shows_the_bounded_point_mass_where_it_differs(tmp_path):
    out = _run_folder(tmp_path / "run", with_h5=False)
    s = json.loads((out / "summary.json").read_text())
    (out / "summary.json").write_text(json.dumps({**s, "pointmass_bounded_velocity_norm": 0.55}))
    make_report([out])
    text = (out / "report" / "report.txt").read_text()
    assert "bounded p. mass 0.55" in text and "Coulomb" in text
    (out / "summary.json").write_text(json.dumps({**s, "pointmass_bounded_velocity_norm": 0.42}))
    make_report([out])
    assert "bounded p. mass" not in (out / "report" / "report.txt").read_text()


def test_report_text_names_which_error_bar_it_shows():
    """Issue 48, item 6: a 3-fill pool was labelled "+-1 standard error of the per-cycle means"."""
    from dem.studies.report import _error_label

    assert "3 fills pooled" in _error_label({"replicas": 3})
    one = _error_label({"replicas": 1})
    assert "this run's per-cycle means" in one and "leaves out the fill-to-fill" in one


def test_a_pooled_runs_per_cycle_figure_draws_every_fill_and_the_pooled_band(tmp_path, monkeypatch):
    """Replica 0's series alone hid the fill-to-fill spread the pooled error includes."""
    from dem.studies import plots

    run = tmp_path / "run"
    _run_folder(run, with_h5=False)
    s = json.loads((run / "summary.json").read_text())
    s |= {"replicas": 3, "seed": 1, "mean_velocity_stderr": 0.002}
    (run / "summary.json").write_text(json.dumps(s))
    for k, v in ((1, 0.05), (2, 0.06)):
        own = dict(s, seed=1 + k, replicas=1, per_cycle_velocity=[v] * 6)
        (run / "replicas" / str(k)).mkdir(parents=True)
        (run / "replicas" / str(k) / "summary.json").write_text(json.dumps(own))
    seen = {}
    original = plots.velocity_cycles_figure

    def spy(*args, **kwargs):
        seen.update(kwargs)
        return original(*args, **kwargs)

    monkeypatch.setattr(plots, "velocity_cycles_figure", spy)
    make_report([run], tmp_path / "report")
    assert [(seed, list(v)) for seed, _, v in seen["replicas"]] == [(2, [0.05] * 6),
                                                                   (3, [0.06] * 6)]  # fmt: skip
    assert seen["pooled"] == (s["mean_velocity"], 0.002)
    assert _is_png(tmp_path / "report" / "velocity_per_cycle.png")


def _atlas_csv(path):
    cols = ["shape", "status", "drive.angle_deg", "drive.throw_number", "material.friction",
            "particles.layers", "mean_velocity_norm", "mean_velocity_norm_stderr",
            "pointmass_bounded_velocity_norm"]  # fmt: skip
    rows = [["sphere", "done", 10, 1.8, 0.35, 2, 0.9, 0.02, 0.8],
            ["sphere", "done", 40, 1.8, 0.35, 2, 0.5, 0.01, 0.6],
            ["sphere", "done", 25, 1.0, 0.35, 1, 0.4, 0.01, 0.5],
            ["screw", "done", 25, 1.8, 0.35, 2, 0.7, 0.01, 0.6],
            ["sphere", "running", 25, 2.6, 0.35, 2, "", "", ""]]  # fmt: skip
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows([cols, *rows])
    return path


@pytest.mark.integration
def test_a_report_draws_the_run_on_the_atlas_map(tmp_path, monkeypatch):
    """dem report puts the run's drive (phi, Gamma) on the atlas's map of its shape at the
    atlas's nearest depth and friction, beside the points there (bulk / bounded point mass);
    without an atlas it says why in report.txt; an unreadable one is refused naming --atlas
    before anything is written."""
    import matplotlib

    from dem.errors import InputError
    from dem.studies import plots

    out = tmp_path / "run"
    _run_folder(out)
    summary = json.loads((out / "summary.json").read_text())
    summary |= {"bed": {"layers": 1.8}, "pointmass_bounded_velocity_norm": 0.4}
    (out / "summary.json").write_text(json.dumps(summary))
    drawn = {}
    original = plots.atlas_point_figure

    def spy(points, case_point, path, *, title=""):
        drawn.update(points=points, case_point=case_point, title=title)
        return original(points, case_point, path, title=title)

    monkeypatch.setattr(plots, "atlas_point_figure", spy)
    files = make_report([out], dest=tmp_path / "rep", atlas=_atlas_csv(tmp_path / "atlas.csv"))
    assert _is_png(tmp_path / "rep" / "atlas_point.png") and len(files) == 5
    # the two sphere points at 2 layers (the bed's 1.8 is nearest 2), ratios 0.9/0.8 and 0.5/0.6
    assert sorted(p[:3] for p in drawn["points"]) == [
        (10.0, 1.8, 0.9 / 0.8),
        (40.0, 1.8, 0.5 / 0.6),
    ]
    assert drawn["case_point"][:3] == (25.0, 1.8, 0.31 / 0.4)
    assert "spheres, 2 layers" in drawn["title"]
    assert matplotlib.get_backend().lower() == "agg"
    monkeypatch.undo()
    make_report([out], dest=tmp_path / "bare")
    assert "atlas_point.png skipped: no atlas" in (tmp_path / "bare" / "report.txt").read_text()
    (tmp_path / "bad.csv").write_text("not,an\natlas,csv\n")
    with pytest.raises(InputError, match="--atlas"):
        make_report([out], dest=tmp_path / "none", atlas=tmp_path / "bad.csv")
    assert not (tmp_path / "none").exists()
