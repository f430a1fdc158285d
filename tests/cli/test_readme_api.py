"""The README's Python example runs as written (from a folder holding the shipped cases)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _example() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("### From Python", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.integration
def test_the_readme_python_example_runs_and_agrees_with_the_point_mass(tmp_path, monkeypatch,
                                                                       capsys):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    exec(compile(_example(), "README.md", "exec"), {})
    out = capsys.readouterr().out
    dem, pm = re.search(r"DEM (\S+) \+- \S+, point mass (\S+)", out).groups()
    assert float(dem) == pytest.approx(float(pm), abs=0.03)  # the sliding block is the point mass
    assert (tmp_path / "runs" / "api" / "summary.json").is_file()
    assert "per-cycle mean velocity" in out
