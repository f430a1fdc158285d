"""Figures that answer: axes with quantity and unit, titles that say what is held, nothing cut."""

import re

import numpy as np
import pytest

from dem.studies import plots

UNIT = re.compile(r"\([^()]+\)$")  # "... (deg)", "... (m/s)", "(-)" for a dimensionless number


@pytest.fixture
def figures(monkeypatch):
    """Every figure dem.studies.plots.save writes, kept open for inspection after it was written."""
    kept = []
    real = plots.save

    def keep(fig, path):
        kept.append(fig)
        return real(fig, path)

    monkeypatch.setattr(plots, "save", keep)
    return kept


def _check(fig, *, forbidden=("budget of evaluations", "points", "point mass bed")):
    """Every labelled axis names its unit; titles hold none of ``forbidden``; nothing is cut."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # written and closed: drawn again as it was laid out
    canvas.draw()
    renderer = canvas.get_renderer()
    box = fig.bbox
    texts = [fig._suptitle] if fig._suptitle is not None else []
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            assert UNIT.search(ax.get_ylabel() or ax.get_xlabel()), ax.get_ylabel()
            continue
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label:
                assert UNIT.search(label), f"no unit in the axis label {label!r}"
        shared = ax.get_shared_x_axes().get_siblings(ax)  # stacked panels: the lowest says it
        assert any(a.get_xlabel() for a in shared) and ax.get_ylabel(), "an axis without label"
        texts += [ax.title, ax.xaxis.label, ax.yaxis.label]
        if ax.get_legend() is not None:
            texts.append(ax.get_legend())
    titles = " ".join(t.get_text() for t in texts if hasattr(t, "get_text"))
    for word in forbidden:
        assert word not in titles, f"{word!r} in a title: {titles!r}"
    for t in texts:
        if hasattr(t, "get_text") and not t.get_text():
            continue
        e = t.get_window_extent(renderer)
        inside = e.x0 >= box.x0 - 1 and e.x1 <= box.x1 + 1 and e.y0 >= box.y0 - 1
        assert inside and e.y1 <= box.y1 + 1, f"cut off at the figure's edge: {t}"
    return titles


def test_axis_label_and_held_text():
    assert plots.axis_label("drive.angle") == "vibration angle phi (deg)"
    assert plots.axis_label("throw_number") == "throw number Gamma (-)"
    assert plots.axis_label("contact.youngs_modulus") == "Young's modulus E (Pa)"
    assert plots.axis_label("particles.max_bumpiness") == "particles.max_bumpiness (-)"
    text = plots.held_text({"throw_number": 1.8, "frequency": 60.0, "amplitude": 5e-4,
                            "impact": "paper"})  # fmt: skip
    assert text.replace(plots.NBSP, " ") == "Gamma = 1.8, f = 60 Hz, A = 0.5 mm, landing law paper"


@pytest.mark.integration
def test_pointmass_optimum_figures(tmp_path, figures):
    from dem.pointmass.sweep import optimum

    plots.optimum_figure(optimum("angle", "amplitude", friction=0.35, amplitude=5e-4,
                                 frequency=60.0, points=41), tmp_path / "a.png")  # fmt: skip
    plots.optimum_figure(optimum("throw_number", "drive_velocity", friction=0.35, angle=25.0,
                                 drive_velocity=0.2, points=41), tmp_path / "g.png")  # fmt: skip
    a = _check(figures[0]).replace(plots.NBSP, " ")
    assert "fixed A = 0.5 mm" in a and "mu = 0.35" in a
    assert figures[0].axes[0].get_xlabel() == "vibration angle phi (deg)"
    assert figures[0].axes[0].get_ylabel() == "conveying velocity v (m/s)"
    g = _check(figures[1]).replace(plots.NBSP, " ")
    assert "fixed A omega = 0.2 m/s" in g and "phi = 25 deg" in g
    assert figures[1].axes[0].get_xlabel() == "throw number Gamma (-)"


@pytest.mark.integration
def test_run_figures(tmp_path, figures):
    c = np.arange(10)
    v = 0.05 + 0.001 * np.sin(c)
    plots.velocity_cycles_figure(c, v, v, np.full(10, 1e-3), tmp_path / "v.png",
                                 measured=c >= 3, title="case: phi = 25 deg")  # fmt: skip
    plots.discharge_figure(c / 60.0, np.full(10, 0.05), np.full(10, 0.1), tmp_path / "d.png",
                           steady=0.05, steady_err=0.002, feed_rate=0.05,
                           title="feeder")  # fmt: skip
    long = "a-long-run-folder-name_drive.angle=25_material.friction=0.35"
    plots.pointmass_comparison_figure([long, long + "_2", long + "_3"], [0.8, 0.9, 0.85],
                                      [0.01, 0.01, 0.01], [0.7, 0.95, 0.9], tmp_path / "c.png",
                                      title="DEM and point mass at f = 60 Hz")  # fmt: skip
    plots.pointmass_comparison_figure([15.0, 25.0, 35.0], [0.8, 0.9, 0.85], [0.01] * 3,
                                      [0.7, 0.95, 0.9], tmp_path / "n.png",
                                      xlabel=plots.axis_label("angle"))  # fmt: skip
    rng = np.random.default_rng(0)
    pos = np.column_stack([rng.uniform(0, 0.1, 40), rng.uniform(-0.02, 0.02, 40),
                           rng.uniform(0, 0.01, 40)])  # fmt: skip
    plots.bed_snapshot_figure(pos, np.full(40, 0.002), rng.normal(0, 0.01, 40), 0.1, 0.04,
                              tmp_path / "b.png", title="bed: last frame")  # fmt: skip
    for fig in figures:
        _check(fig)
    assert figures[2].axes[0].get_xlabel() == "run (output folder)"


def _rows():
    rows = []
    for i, (angle, mu) in enumerate([(15.0, 0.3), (25.0, 0.3), (15.0, 0.6), (25.0, 0.6)]):
        rows.append({"point": f"{i:03d}", "drive.angle": angle, "material.friction": mu,
                     "mean_velocity": 0.1 + 0.001 * i, "mean_velocity_stderr": 0.002,
                     "mean_velocity_norm": 0.6 + 0.01 * i, "mean_velocity_norm_stderr": 0.01,
                     "pointmass_velocity_norm": 0.7, "velocity_scale": 0.17, "status": "done",
                     "error": ""})  # fmt: skip
    return rows


@pytest.mark.integration
def test_sweep_figure_shows_m_s_and_v_norm(tmp_path, figures):
    from dem.studies.sweep import plot

    plot(_rows(), tmp_path / "s.png", ["drive.angle", "material.friction"],
         held={"drive.amplitude": 5e-4, "drive.frequency": 60.0})  # fmt: skip
    fig = figures[0]
    title = _check(fig).replace(plots.NBSP, " ")
    assert [ax.get_ylabel() for ax in fig.axes] == [plots.VELOCITY_LABEL, plots.NORM_LABEL]
    assert all(ax.get_xlabel() == "vibration angle phi (deg)" for ax in fig.axes)
    assert "held: A = 0.5 mm, f = 60 Hz" in title
    legend = [t.get_text().replace(plots.NBSP, " ") for t in fig.axes[0].get_legend().texts]
    assert "DEM, mu = 0.3" in legend and "point mass, mu = 0.6" in legend
    # the point mass in m/s is its v_norm times the velocity scale
    dashed = [line for line in fig.axes[0].lines if line.get_linestyle() == "--"][0]
    assert np.allclose(dashed.get_ydata(), 0.7 * 0.17)
    # one swept key: no "point mass bed"
    plot(_rows()[:2], tmp_path / "one.png", ["drive.angle"])
    _check(figures[1])
    legend = [t.get_text() for t in figures[1].axes[0].get_legend().texts]
    assert sorted(legend) == ["DEM", "point mass"]


def _search(peak: bool):
    from dem.studies.optimum import maximize_noisy

    rng = np.random.default_rng(3)

    def evaluate(batch):
        if peak:
            return [(0.9 - 4e-4 * (x - 31.0) ** 2 + 0.005 * rng.standard_normal(), 0.005)
                    for x, _ in batch]  # fmt: skip
        return [(0.5 + 0.01 * rng.standard_normal(), 0.01) for _ in batch]

    return maximize_noisy(evaluate, 10.0, 60.0, tolerance=1.0, max_evaluations=20)


@pytest.mark.integration
def test_bulk_optimum_figure_has_a_plateau_band_and_no_stop_reason(tmp_path, figures):
    from dem.pointmass.sweep import optimum
    from dem.studies.optimum import _plot, plateau

    pm = optimum("angle", "throw_number", friction=0.35, throw_number=1.8, frequency=60.0,
                 bounds=(10.0, 60.0), points=41)  # fmt: skip
    for peak in (True, False):
        result = _search(peak)
        _plot(tmp_path / f"o{peak}.png", result, pm, "drive.angle", "velocity_norm", "case")
        fig = figures[-1]
        title = _check(fig, forbidden=("budget", "flat within", "points", "bracket")).replace(
            plots.NBSP, " "
        )
        assert "fixed Gamma = 1.8" in title and "mu = 0.35" in title
        ax = fig.axes[0]
        assert ax.get_xlabel() == "vibration angle phi (deg)"
        band = plateau(result)
        lo, hi = band["range"]
        assert lo <= result.x <= hi or band["parabola"] is not None
        spans = [p for p in ax.patches if p.get_label().startswith("plateau")]
        assert len(spans) == 1
        x0 = spans[0].get_x()
        assert np.isclose(x0, lo) and np.isclose(x0 + spans[0].get_width(), hi)
        if peak:  # x_v +- sqrt(s / |c2|) of the fitted parabola: c2 about -4e-4, s 0.005
            assert band["parabola"] is not None
            c2, c1, _ = band["parabola"]
            assert -1.2e-3 < c2 < -1.3e-4  # one noisy top: within a factor of 3
            assert lo < -c1 / (2 * c2) < hi and 25.0 < -c1 / (2 * c2) < 37.0
            assert hi - lo == pytest.approx(2 * np.sqrt(0.005 / -c2), rel=1e-6)
        else:  # level within one combined standard error: most of the range
            assert band["parabola"] is None and hi - lo > 20.0
