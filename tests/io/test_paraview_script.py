"""The ParaView script shipped with dem (dem/data/paraview/open_run.py)."""

import importlib.util
import shutil
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

from dem.io.vtk import VTKSeriesWriter, paraview_script

ROOT = Path(__file__).resolve().parents[2]


def _module():
    spec = importlib.util.spec_from_file_location("open_run", paraview_script())
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # paraview is imported inside its functions only
    return module


def test_the_script_is_package_data_and_compiles():
    path = paraview_script()
    assert path.is_file() and path.parent == ROOT / "dem" / "data" / "paraview"
    compile(path.read_text(), str(path), "exec")
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "data/paraview/*.py" in data["tool"]["setuptools"]["package-data"]["dem"]


def test_block_names_and_the_glyph_scale(tmp_path):
    w = VTKSeriesWriter(tmp_path, 0.1, 0.04, 0.0)
    n = 3
    w.write_frame(0.0, np.full((n, 3), 0.01), np.full(n, 1e-3), np.zeros((n, 3)), np.arange(n),
                  np.arange(n), np.zeros(n, int))  # fmt: skip
    w.close()
    module = _module()
    assert module.block_names(str(tmp_path / "particles.pvd")) == {0: "spheres", 1: "trough"}
    assert module.glyph_scale_factor() == 2.0  # ParaView's glyph sphere has radius 0.5


CHECK = """
import sys
sys.path.insert(0, {folder!r})
import open_run
p = open_run.pipeline({out!r})
p["glyph"].UpdatePipeline(p["times"][p["frame"]])
print("BOUNDS", *p["glyph"].GetDataInformation().GetBounds())
print("NAMES", *sorted(p["names"].values()))
"""


@pytest.mark.integration
@pytest.mark.skipif(shutil.which("pvpython") is None, reason="ParaView's pvpython not on PATH")
def test_pvpython_draws_each_sphere_with_its_diameter(tmp_path):
    """The script's pipeline in ParaView itself: glyphs reach x +- r of each sphere."""
    pos = np.array([[0.02, -0.01, 0.003], [0.05, 0.0, 0.004], [0.08, 0.012, 0.006]])
    radius = np.array([0.003, 0.002, 0.004])
    w = VTKSeriesWriter(tmp_path / "out", 0.1, 0.04, 0.0)
    for t in (0.0, 0.01):
        w.write_frame(t, pos, radius, np.zeros((3, 3)), np.arange(3), np.arange(3),
                      np.zeros(3, int), drive_velocity=np.array([0.1, 0.0, 0.05]))  # fmt: skip
    w.close()
    script = tmp_path / "check.py"
    script.write_text(CHECK.format(folder=str(paraview_script().parent), out=str(tmp_path / "out")))
    done = subprocess.run(["pvpython", str(script)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = {line.split()[0]: line.split()[1:] for line in done.stdout.splitlines() if line}
    bounds = np.array([float(v) for v in lines["BOUNDS"]])
    expected = np.ravel([(np.min(pos[:, i] - radius), np.max(pos[:, i] + radius))
                         for i in range(3)])  # fmt: skip
    assert np.allclose(bounds, expected, atol=0.02 * radius.max())  # a faceted sphere
    assert lines["NAMES"] == ["spheres", "trough"]


CONTACTS = """
import sys
sys.path.insert(0, {folder!r})
import open_run
p = open_run.pipeline({out!r})
p["forces"].UpdatePipeline(p["times"][p["frame"]])
print("CONTACTS", p["contacts"].GetDataInformation().GetNumberOfPoints())
print("BOUNDS", *p["forces"].GetDataInformation().GetBounds())
print("NAMES", *sorted(p["names"].values()))
"""


@pytest.mark.integration
@pytest.mark.skipif(shutil.which("pvpython") is None, reason="ParaView's pvpython not on PATH")
def test_pvpython_draws_each_contact_force_as_an_arrow_of_its_size(tmp_path):
    """A frame with contacts (output.contacts): one arrow per contact, along its normal force,
    the largest 3 r long: here a floor contact pushing up with 2 N and a pair with 1 N."""
    pos = np.array([[0.05, 0.0, 0.002], [0.05, 0.0, 0.006]])
    radius = np.full(2, 0.002)
    snap = {"kind": np.array([1, 0]), "i": np.array([0, 1]), "j": np.array([-1, 0]),
            "point": np.array([[0.05, 0.0, 0.0], [0.05, 0.0, 0.004]]),
            "normal": np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]),
            "normal_force": np.array([2.0, 1.0]), "tangential_force": np.zeros((2, 3)),
            "overlap": np.array([1e-6, 1e-6])}  # fmt: skip
    w = VTKSeriesWriter(tmp_path / "out", 0.1, 0.04, 0.0)
    w.write_frame(0.0, pos, radius, np.zeros((2, 3)), np.arange(2), np.arange(2),
                  np.array([2, 1]), contacts=snap)  # fmt: skip
    w.close()
    script = tmp_path / "check.py"
    script.write_text(
        CONTACTS.format(folder=str(paraview_script().parent), out=str(tmp_path / "out"))
    )
    done = subprocess.run(["pvpython", str(script)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = {line.split()[0]: line.split()[1:] for line in done.stdout.splitlines() if line}
    assert lines["CONTACTS"] == ["2"] and lines["NAMES"] == ["contacts", "spheres", "trough"]
    bounds = np.array([float(v) for v in lines["BOUNDS"]])
    # the floor's arrow from z = 0 up 3 r = 6 mm, the pair's from 4 mm up 3 mm
    assert bounds[4] == pytest.approx(0.0, abs=1e-4) and bounds[5] == pytest.approx(0.007, abs=2e-4)
