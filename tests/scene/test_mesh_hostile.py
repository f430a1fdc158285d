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

SCREW_CASE = (
    SMALL_CASE.replace("density = 7800.0\n", "")
    .replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "screw"\ncount = 10\nlength = 0.022\nshank_radius = 0.0018\nhead_radius = 0.0036\n'
        "mass = 0.0025\nmax_bumpiness = {b}",
    )
    .replace("length = 0.03", "length = 0.08")
)


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


@pytest.mark.validation
def test_the_smallest_bumpiness_named_is_accepted(tmp_path, capsys):
    """The bound in the message is rounded up: the value it names loads (at most 1000 spheres)."""
    import re

    from dem.quantities import MAX_GRAIN_SPHERES
    from dem.scene.case import load_case

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
    text = (
        SMALL_CASE.replace("density = 7800.0\n", "")
        .replace(
            'shape = "sphere"\ncount = 120\nradius = 0.002',
            'shape = "clump"\ncount = 2\ntemplate = "big.spheres"\nmass = 0.0025',
        )
        .replace("length = 0.03", "length = 2.0")
    )
    code, err = _dem(["plan", str(write_case(tmp_path / "case", text))], capsys)
    _refused(code, err, "big.spheres", "1001", "at most 1000 member spheres")


# --- trough.mesh: every reader failure is dem's own line naming the key and the file -------------

LENGTH, WIDTH, WALL = 0.03, 0.02, 0.012  # SMALL_CASE's trough


def _box(path, binary: bool) -> bytes:
    """Floor and side walls of SMALL_CASE's trough as 6 triangles; returns the file's bytes."""
    import meshio

    from dem.scene.mesh import extrude

    h = 0.5 * WIDTH
    mesh = extrude([[-h, WALL], [-h, 0.0], [h, 0.0], [h, WALL]], LENGTH)
    if path.suffix == ".stl":
        meshio.write(path, mesh, binary=binary)
    else:
        meshio.write(path, mesh)
    return path.read_bytes()


def _mesh_case(tmp_path, name: str, content: bytes):
    """SMALL_CASE with ``trough.mesh`` = a file ``name`` holding ``content``."""
    case_dir = tmp_path / "case"
    case_dir.mkdir(exist_ok=True)
    (case_dir / name).write_bytes(content)
    text = SMALL_CASE.replace("width = 0.02", f'width = 0.02\nmesh = "{name}"')
    return write_case(case_dir, text)


@pytest.mark.validation
def test_the_box_meshes_load_in_every_format(tmp_path, capsys):
    """The base of the variants below: valid files of each kind pass the door."""
    for name, binary in [("b.stl", True), ("a.stl", False), ("m.obj", False)]:
        content = _box(tmp_path / name, binary)
        code, err = _dem(["plan", str(_mesh_case(tmp_path, name, content))], capsys)
        assert code == 0, err


def test_a_truncated_binary_stl_is_refused_with_both_sizes(tmp_path, capsys):
    """A binary STL cut short used to load with a wall triangle silently dropped (or fail in a
    decoding error): grains fell through and the run failed 79 s later advising a smaller time
    step. Now the size is checked against the header's triangle count."""
    content = _box(tmp_path / "b.stl", binary=True)
    assert len(content) == 84 + 6 * 50
    for cut in (1, 30, 50):
        code, err = _dem(["plan", str(_mesh_case(tmp_path, "t.stl", content[:-cut]))], capsys)
        _refused(code, err, "trough.mesh", "t.stl", "384 bytes", f"has {384 - cut} bytes")


def test_a_malformed_ascii_stl_is_refused_with_the_key_and_line(tmp_path, capsys):
    """A malformed ASCII STL made meshio print its own error and exit 1 (or load garbage):
    now dem's one line names trough.mesh, the file and the line."""
    text = _box(tmp_path / "a.stl", binary=False).decode()
    cut = text[: text.index("endloop")]  # the file ends inside the first facet
    for bad, where in [
        (text.replace("vertex", "vortex", 1), "line 4"),
        (text.replace("endloop", "", 1), "line 8"),
        (text.replace("vertex 0.0", "vertex 0.0 1.0", 1), "line 4"),
        (text.replace("0.012", "0.0x12", 1), "line 4"),
        (cut, "ends where"),
        ("solid\nendsolid\n", "at least one triangle"),
        ("", "neither an ASCII STL"),
    ]:
        code, err = _dem(["plan", str(_mesh_case(tmp_path, "m.stl", bad.encode()))], capsys)
        _refused(code, err, "trough.mesh", "m.stl", where)


@pytest.mark.parametrize("face", ["4 7 9", "4 7 -1", "4 7 0", "4 7 -9"])
def test_an_obj_face_naming_a_missing_vertex_is_refused(tmp_path, capsys, face):
    """9 of 8 vertices was an IndexError traceback; 0 and -1 (numpy wraps negative indices)
    loaded a triangle from the wrong corner without a word."""
    text = _box(tmp_path / "m.obj", binary=False).decode().replace("f 4 7 8", f"f {face}")
    code, err = _dem(["plan", str(_mesh_case(tmp_path, "m.obj", text.encode()))], capsys)
    _refused(code, err, "trough.mesh", "m.obj", "faces that name existing vertices")


@pytest.mark.parametrize(
    "name, content",
    [
        ("m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n"),
        ("m.obj", b"v 0 0 zero\nf 1 2 3\n"),
        ("m.ply", b"ply\nformat nonsense\nend_header\n"),
        ("m.vtk", b"\x00\x01garbage"),
        ("m.xyz", b"0 0 0\n"),
        ("m.obj", b"v 0 0 0\n"),
    ],
    ids=["obj-face-word", "obj-vertex-word", "ply-header", "vtk-bytes", "unknown-format",
         "no-faces"],
)  # fmt: skip
def test_any_file_meshio_cannot_use_is_one_line_naming_the_key(tmp_path, capsys, name, content):
    code, err = _dem(["plan", str(_mesh_case(tmp_path, name, content))], capsys)
    _refused(code, err, "trough.mesh", name)
    out, _ = capsys.readouterr()
    assert out == ""  # meshio's own printing is kept off the terminal


def _binary(triangles) -> bytes:
    import numpy as np

    from dem.scene.mesh import _STL_DTYPE

    records = np.zeros(len(triangles), dtype=_STL_DTYPE)
    records["facet"] = triangles
    return b"\0" * 80 + np.uint32(len(triangles)).tobytes() + records.tobytes()


@pytest.mark.parametrize(
    "variant", ["huge-count", "padded", "nan-corner", "solid-header-truncated", "huge-corner"]
)
def test_other_corrupt_binary_stls_are_refused(tmp_path, capsys, variant):
    import numpy as np

    from dem.scene.mesh import read_stl

    good = _box(tmp_path / "b.stl", binary=True)
    tri = read_stl(tmp_path / "b.stl")
    content = {
        "huge-count": good[:80] + np.uint32(2**32 - 1).tobytes() + good[84:],
        "padded": good + b"\0" * 50,
        "nan-corner": _binary(np.where(tri == tri.max(), np.nan, tri)),
        "solid-header-truncated": b"solid dem" + good[9:-50],
        "huge-corner": _binary(np.where(tri == tri.max(), 1e38, tri)),
    }[variant]
    code, err = _dem(["plan", str(_mesh_case(tmp_path, "m.stl", content))], capsys)
    _refused(code, err, "trough.mesh", "m.stl")


def test_an_unreadable_mesh_is_an_io_fault_in_one_line(tmp_path, capsys, monkeypatch):
    """A read that fails (a disk error, no permission) is an I/O fault: exit 1, one line."""
    import errno
    from pathlib import Path

    case_dir = _mesh_case(tmp_path, "m.stl", _box(tmp_path / "b.stl", binary=True))
    read_bytes = Path.read_bytes

    def failing(self):
        if self.suffix == ".stl":
            raise OSError(errno.EIO, "Input/output error", str(self))
        return read_bytes(self)

    monkeypatch.setattr(Path, "read_bytes", failing)
    code, err = _dem(["plan", str(case_dir)], capsys)
    assert code == 1 and err.count("\n") == 1 and "m.stl" in err, err
    assert "Traceback" not in err


def test_a_refused_mesh_in_a_resumable_folder_loses_nothing(tmp_path, capsys):
    """dem run refuses the case at load: the earlier run's folder is left as it was."""
    content = _box(tmp_path / "b.stl", binary=True)
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("{}\n")
    case_dir = _mesh_case(tmp_path, "t.stl", content[:-10])
    code, err = _dem(["run", str(case_dir), "--out", str(out), "--overwrite"], capsys)
    _refused(code, err, "trough.mesh")
    assert [p.name for p in out.iterdir()] == ["summary.json"]
    assert (out / "summary.json").read_text() == "{}\n"
