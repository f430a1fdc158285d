"""The door's contract as data: hostile values for every key end in exit 2, one line, nothing.

Every numeric key of every case table gets the values a hostile but realistic user types:
non-finite numbers, 1e300 and -1e300 (which used to pass the range checks and overflow deep in
a run), a string, a boolean and a table. ``dem run`` must exit 2 with one line on stderr that
names the key, print no traceback, and write nothing (no output folder). A new key is covered
by adding it to :data:`KEYS`.

A link planted in the output folder under a name dem writes (the lock, ``frames``, results.h5,
...) is hostile input too: refused the same way, and nothing written, truncated or deleted
through it (:data:`PLANTED`).
"""

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main

#: (table.key, a valid case text it is set in): numeric keys of the case file.
SPHERE_KEYS = [
    "trough.length", "trough.width", "trough.inclination",
    "drive.frequency", "drive.angle", "drive.amplitude", "drive.second_amplitude",
    "drive.second_angle", "drive.second_phase", "drive.ramp_cycles",
    "material.density", "material.friction", "material.restitution_normal",
    "material.restitution_tangential", "material.rolling_friction",
    "wall.friction", "wall.restitution_normal", "wall.restitution_tangential",
    "wall.rolling_friction",
    "contact.youngs_modulus", "contact.poisson_ratio", "contact.tangential_stiffness_ratio",
    "contact.tangential_damping_ratio",
    "particles.count", "particles.radius",
    "run.cycles", "run.settle_cycles", "run.timestep", "run.seed",
    "output.frames_per_cycle",
    "feeder.feed_rate", "feeder.feed_length",
]  # fmt: skip
SCREW_KEYS = [
    "particles.length", "particles.shank_radius", "particles.head_radius", "particles.mass",
    "particles.max_bumpiness",
]  # fmt: skip
SCREW_CASE = (
    SMALL_CASE.replace("density = 7800.0\n", "")
    .replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "screw"\ncount = 10\nlength = 0.022\nshank_radius = 0.0018\nhead_radius = 0.0036\n'
        "mass = 0.0025",
    )
    .replace("length = 0.03", "length = 0.08")
)
HOSTILE = {
    "nan": "nan",
    "inf": "inf",
    "-inf": "-inf",
    "huge": "1e300",
    "-huge": "-1e300",
    "text": '"lots"',
    "bool": "true",
    "table": "{ a = 1 }",
}
KEYS = [(k, SMALL_CASE) for k in SPHERE_KEYS] + [(k, SCREW_CASE) for k in SCREW_KEYS]


def _set(text: str, key: str, value: str) -> str:
    """The case text with ``table.key = value`` (the key replaced, or added to its table)."""
    table, name = key.split(".")
    lines, out, in_table, done = text.splitlines(), [], False, False
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("["):
            if in_table and not done:
                out.append(f"{name} = {value}")
                done = True
            in_table = stripped == f"[{table}]"
        if in_table and stripped.split("=")[0].strip() == name:
            out.append(f"{name} = {value}")
            done = True
            continue
        out.append(line)
    if not done:
        out += ([] if in_table else ["", f"[{table}]"]) + [f"{name} = {value}"]
    return "\n".join(out) + "\n"


def test_the_screw_case_of_the_table_is_valid_and_set_replaces_keys(tmp_path, capsys):
    """The table's base cases load, and _set writes the hostile value where the key lives."""
    from dem.scene.case import load_case

    assert load_case(write_case(tmp_path / "s", SCREW_CASE)).particles.shape == "screw"
    text = _set(SMALL_CASE, "material.friction", "nan")
    assert "friction = nan" in text and "friction = 0.35" not in text
    case = load_case(write_case(tmp_path / "f", _set(SMALL_CASE, "feeder.feed_rate", "0.01")))
    assert case.feeder.feed_rate == 0.01


@pytest.mark.parametrize("label", list(HOSTILE))
@pytest.mark.parametrize("key, base", KEYS, ids=[k for k, _ in KEYS])
def test_hostile_value_is_refused_with_one_line_and_nothing_written(
    tmp_path, capsys, key, base, label
):
    case_dir = write_case(tmp_path / "case", _set(base, key, HOSTILE[label]))
    out = tmp_path / "out"
    try:
        code = main(["run", str(case_dir), "--out", str(out)])
    except SystemExit as exc:
        code = exc.code
    _, err = capsys.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1, err
    assert "Traceback" not in err
    assert key in err, err
    assert not out.exists()


def test_a_count_whose_state_exceeds_the_machine_is_refused_before_anything(tmp_path, capsys):
    """count = 1e9 used to reserve 23 GB and start a fill that never ended: now the memory
    estimate (dem plan's, extrapolated without allocating) refuses it at once."""
    import time

    case_dir = write_case(tmp_path / "case", _set(SMALL_CASE, "particles.count", "1000000000"))
    out = tmp_path / "out"
    t0 = time.monotonic()
    code = main(["run", str(case_dir), "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1, err
    assert "particles.count" in err and "fits this machine" in err
    assert time.monotonic() - t0 < 30.0
    assert not out.exists()


#: Links planted in the output folder under names dem writes, as (name, what the link points
#: to, options). Before: the lock link's target was truncated and overwritten (a dangling one
#: created), ``--overwrite`` deleted the user's particles_*.vtp through a linked frames/, and
#: summary.json and results.h5 were written through their links.
PLANTED = [
    (".dem-run.lock", "file", []),
    (".dem-run.lock", "nothing", []),
    ("frames", "folder", ["--overwrite"]),
    ("frames", "folder", []),
    ("frames", "nothing", []),
    ("summary.json", "nothing", []),
    ("results.h5", "nothing", []),
    ("results.h5", "file", ["--overwrite"]),
    ("particles.pvd", "nothing", []),
    ("checkpoint.npz", "file", ["--resume"]),
]  # fmt: skip


def _snapshot(path):
    """What is at ``path``: None, a file's bytes, or a folder's {name: bytes}."""
    if path.is_dir():
        return {p.name: p.read_bytes() for p in path.iterdir()}
    return path.read_bytes() if path.exists() else None


@pytest.mark.parametrize("name, target, options", PLANTED,
                         ids=[f"{n}-{t}{''.join(o)}" for n, t, o in PLANTED])  # fmt: skip
def test_a_planted_link_is_refused_and_nothing_is_written_or_deleted_through_it(
    tmp_path, capsys, name, target, options
):
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", "cycles = 1"))
    mine = tmp_path / "mine"
    mine.mkdir()
    aim = mine / f"the_{name.strip('.')}"
    if target == "file":
        aim.write_bytes(b"precious\n")
    elif target == "folder":
        aim.mkdir()
        (aim / "particles_000000.vtp").write_bytes(b"my own frame\n")
        (aim / "notes.txt").write_bytes(b"mine\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / name).symlink_to(aim, target_is_directory=target == "folder")
    before = _snapshot(aim)
    code = main(["run", str(case_dir), "--out", str(out), "--threads", "1", *options])
    _, err = capsys.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert str(out / name) in err and "link" in err, err
    assert _snapshot(aim) == before  # the target: not written, truncated, made or emptied
    assert (out / name).is_symlink()  # the link itself stays: dem did not make it


def test_a_planted_link_at_a_temporary_name_is_replaced_not_written_through(tmp_path):
    """summary.json, the collection and the frames are written to NAME.tmp and renamed: a link
    planted at NAME.tmp is removed and the file made afresh, its target untouched."""
    from dem.io.files import replace_text

    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    (tmp_path / "summary.json.tmp").symlink_to(victim)
    replace_text(tmp_path / "summary.json", "{}\n")
    assert victim.read_text() == "precious\n"
    assert (tmp_path / "summary.json").read_text() == "{}\n"
    assert not (tmp_path / "summary.json").is_symlink()
    assert not (tmp_path / "summary.json.tmp").exists()
