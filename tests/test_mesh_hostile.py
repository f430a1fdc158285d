"""Hostile geometry at the door: trough mesh files and grain resolutions dem cannot use.

Each bad input ends in exit 2 with one line that names the case key (``trough.mesh``,
``particles.max_bumpiness``), the value and what is allowed, before any computation, with no
traceback and no output folder. (A mesh file that cannot be read at all, an I/O fault, ends in
exit 1 with one line naming the file.)
"""

import time

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main

SCREW_CASE = SMALL_CASE.replace(
    'shape = "sphere"\ncount = 120\nradius = 0.002',
    'shape = "screw"\ncount = 10\nlength = 0.022\nshank_radius = 0.0018\nhead_radius = 0.0036\n'
    "mass = 0.0025\nmax_bumpiness = {b}",
).replace("length = 0.03", "length = 0.08")


def _dem(args, capsys) -> tuple[int, str]:
    try:
        code = main(args)
    except SystemExit as exc:
        code = exc.code
    _, err = capsys.readouterr()
    return code, err


def _refused(code: int, err: str, *words: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err


# --- particles.max_bumpiness: the member-sphere count it sets is bounded at case load ----------


@pytest.mark.parametrize("command", ["plan", "run"])
def test_a_tiny_max_bumpiness_is_refused_at_load_not_by_a_memory_error(tmp_path, capsys, command):
    """b = 1e-12 asked for 3 million shank spheres and a 184 TiB pairwise array: a MemoryError
    traceback in dem plan and dem run. Now the case load names the key and the smallest b."""
    case_dir = write_case(tmp_path / "case", SCREW_CASE.format(b="1e-12"))
    out = tmp_path / "out"
    args = [command, str(case_dir)] + (["--out", str(out)] if command == "run" else [])
    t0 = time.monotonic()
    code, err = _dem(args, capsys)
    _refused(code, err, "particles.max_bumpiness", "1e-12", "<= b <= 1", "1000 member spheres")
    assert time.monotonic() - t0 < 10.0
    assert not out.exists()


@pytest.mark.parametrize("b", ["5e-324", "1e-300", "1e-6", "1.0e-5"])
def test_other_tiny_bumpiness_values_are_refused_too(tmp_path, capsys, b):
    case_dir = write_case(tmp_path / "case", SCREW_CASE.format(b=b))
    code, err = _dem(["plan", str(case_dir)], capsys)
    _refused(code, err, "particles.max_bumpiness", "<= b <= 1")


def test_the_smallest_bumpiness_named_is_accepted(tmp_path, capsys):
    """The bound in the message is rounded up: the value it names loads (at most 1000 spheres)."""
    import re

    from dem.case import load_case
    from dem.quantities import MAX_GRAIN_SPHERES

    case_dir = write_case(tmp_path / "case", SCREW_CASE.format(b="1e-9"))
    code, err = _dem(["plan", str(case_dir)], capsys)
    shown = re.search(r": ([0-9.e+-]+) <= b <= 1", err).group(1)
    grain = load_case(write_case(tmp_path / "ok", SCREW_CASE.format(b=shown))).particles.grain
    assert MAX_GRAIN_SPHERES // 2 < grain.count <= MAX_GRAIN_SPHERES


def test_a_screw_too_slender_for_any_bumpiness_names_its_length(tmp_path, capsys):
    text = SCREW_CASE.format(b="1.0").replace("length = 0.022", "length = 10.0")
    code, err = _dem(["plan", str(write_case(tmp_path / "case", text))], capsys)
    _refused(code, err, "particles.length", "1000 member spheres")


def test_a_clump_template_of_too_many_spheres_names_the_file(tmp_path, capsys):
    template = tmp_path / "case" / "big.spheres"
    template.parent.mkdir()
    template.write_text("".join(f"{0.001 * k} 0 0 0.0006\n" for k in range(1001)))
    text = SMALL_CASE.replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "clump"\ncount = 2\ntemplate = "big.spheres"\nmass = 0.0025',
    ).replace("length = 0.03", "length = 2.0")
    code, err = _dem(["plan", str(write_case(tmp_path / "case", text))], capsys)
    _refused(code, err, "big.spheres", "1001", "at most 1000 member spheres")
