"""The door's contract as data: hostile values for every key end in exit 2, one line, nothing.

Every numeric key of every case table (each numeric row of the schema,
:data:`dem.scene.schema.SCHEMA`) gets the values a hostile but realistic user types: non-finite
numbers, 1e300 and -1e300 (which used to pass the range checks and overflow deep in a run), a
string, a boolean and a table. ``dem run`` must exit 2 with one line on stderr that names the
key, print no traceback, and write nothing (no output folder). Each key is set in a valid case
of a shape and law that read it (:data:`BASES`, by the row's first owner), so the value meets
the key's own checks, not the refusal of a foreign key. A new key is covered by its row in the
schema.

A link planted in the output folder under a name dem writes (the lock, ``frames``, results.h5,
...) is hostile input too: refused the same way, and nothing written, truncated or deleted
through it (:data:`PLANTED`).
"""

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.scene.schema import SCHEMA
from dem.scene.tomltable import ALL

SCREW_CASE = (
    SMALL_CASE.replace("density = 7800.0\n", "")
    .replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "screw"\ncount = 10\nlength = 0.022\nshank_radius = 0.0018\nhead_radius = 0.0036\n'
        "mass = 0.0025",
    )
    .replace("length = 0.03", "length = 0.08")
)
#: A clump of two spheres (its template file, :data:`TEMPLATE`, written beside the case).
CLUMP_CASE = (
    SMALL_CASE.replace("density = 7800.0\n", "")
    .replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "clump"\ncount = 10\ntemplate = "grain.txt"\nmass = 0.0005',
    )
    .replace("length = 0.03", "length = 0.06")
)
TEMPLATE = "0.0 0.0 0.0 0.002\n0.002 0.0 0.0 0.002\n"
LINEAR_CASE = SMALL_CASE.replace(
    'model = "hertz_mindlin"\nyoungs_modulus = 5.0e7', 'model = "linear"\nstiffness = 2000.0'
)
#: Spheres of a size distribution (the owners of its keys).
_SIZES = {
    "uniform": "radius_min = 0.0018\nradius_max = 0.0022",
    "normal": "radius = 0.002\nradius_std = 0.0002\nradius_min = 0.0016\nradius_max = 0.0024",
    "lognormal": "radius = 0.002\nradius_log_std = 0.1\nradius_min = 0.0016\nradius_max = 0.0024",
    "discrete": "radii = [0.0018, 0.0022]\nradius_fractions = [0.5, 0.5]",
}
SIZE_CASES = {
    name: SMALL_CASE.replace("radius = 0.002", f'radius_distribution = "{name}"\n{keys}')
    for name, keys in _SIZES.items()
}
#: A valid case in which each owner's keys are read ("all": every case).
BASES = {
    ALL: SMALL_CASE,
    "sphere": SMALL_CASE,
    "screw": SCREW_CASE,
    "clump": CLUMP_CASE,
    "hertz_mindlin": SMALL_CASE,
    "linear": LINEAR_CASE,
    "coulomb": SMALL_CASE.replace("[contact]", '[contact]\ntangential = "coulomb"'),
    "liggghts+linear": LINEAR_CASE.replace("[contact]", '[contact]\ntangential = "liggghts"'),
    **SIZE_CASES,
}
#: Keys read only beside others: the keys set with them (drive.amplitude removed: exactly one
#: of it and throw_number; the second component's angle and phase need its amplitude).
BESIDE = {
    "drive.throw_number": {"drive.amplitude": None},
    "drive.second_angle": {"drive.second_amplitude": "0.0002"},
    "drive.second_phase": {"drive.second_amplitude": "0.0002", "drive.second_angle": "60.0"},
}
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
#: (table.key, the owner whose base case it is set in): every numeric key of the case file.
KEYS = [
    (f"{table}.{k.name}", k.owners[0]) for table, keys in SCHEMA.items() for k in keys if k.numeric
]


def _set(text: str, key: str, value: str | None) -> str:
    """The case text with ``table.key = value`` (the key replaced, or added to its table; None:
    the key removed)."""
    table, name = key.split(".")
    lines, out, in_table, done = text.splitlines(), [], False, value is None
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("["):
            if in_table and not done:
                out.append(f"{name} = {value}")
                done = True
            in_table = stripped == f"[{table}]"
        if in_table and stripped.split("=")[0].strip() == name:
            if value is not None:
                out.append(f"{name} = {value}")
            done = True
            continue
        out.append(line)
    if not done:
        out += ([] if in_table else ["", f"[{table}]"]) + [f"{name} = {value}"]
    return "\n".join(out) + "\n"


def _case(directory, key: str, value: str, owner: str):
    """Write the base case of ``owner`` with ``key = value`` (and its :data:`BESIDE` keys)."""
    text = BASES[owner]
    for other, other_value in BESIDE.get(key, {}).items():
        text = _set(text, other, other_value)
    write_case(directory, _set(text, key, value))
    if owner == "clump":
        (directory / "grain.txt").write_text(TEMPLATE)
    return directory


@pytest.mark.validation
def test_every_owner_has_a_base_case_that_loads_and_reads_its_keys(tmp_path):
    """Each base case loads and chooses its owner's shape and laws; _set replaces, adds and
    removes keys where they live."""
    from dem.scene.case import load_case

    owners = {o for keys in SCHEMA.values() for k in keys for o in k.owners}
    assert owners <= set(BASES), owners - set(BASES)
    for owner in BASES:
        case = load_case(_case(tmp_path / owner, "run.seed", "3", owner))
        chosen = {case.particles.shape, case.contact.model, case.contact.tangential}
        chosen |= {t.size.distribution for t in case.particles.types}
        assert owner == ALL or set(owner.split("+")) <= chosen, owner
    drive = load_case(_case(tmp_path / "second", "drive.second_phase", "30.0", ALL)).drive
    assert (drive.second_amplitude, drive.second_angle, drive.second_phase) == (2e-4, 60.0, 30.0)
    drive = load_case(_case(tmp_path / "gamma", "drive.throw_number", "2.0", ALL)).drive
    assert drive.given == "throw_number"
    text = _set(SMALL_CASE, "material.friction", "nan")
    assert "friction = nan" in text and "friction = 0.35" not in text
    assert "friction" not in _set(SMALL_CASE, "material.friction", None)
    case = load_case(write_case(tmp_path / "f", _set(SMALL_CASE, "feeder.feed_rate", "0.01")))
    assert case.feeder.feed_rate == 0.01


@pytest.mark.parametrize("label", list(HOSTILE))
@pytest.mark.parametrize("key, owner", KEYS, ids=[k for k, _ in KEYS])
def test_hostile_value_is_refused_with_one_line_and_nothing_written(
    tmp_path, capsys, key, owner, label
):
    case_dir = _case(tmp_path / "case", key, HOSTILE[label], owner)
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


@pytest.mark.validation
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
@pytest.mark.validation
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
