"""A checkpoint handed back with ``dem run --resume`` is validated in full before it is used.

A tampered file that is still a valid zip used to give a KeyError traceback (a missing key), a
segmentation fault in the pair loop (pair indices beyond the spheres) or a NaN summary (a loop
record beyond the run's end). Now each is refused in one line naming what is wrong, exit 2,
and the interrupted run's folder is left as it was, so a good checkpoint can still be put back.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, sigterm_at_check, write_case

from dem.cli import main
from dem.io import checkpoint
from dem.scene.case import load_case

TEXT = SMALL_CASE.replace("cycles = 6", "cycles = 2").replace("settle_cycles = 2",
                                                              "settle_cycles = 1")  # fmt: skip


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """An interrupted run of a small case with its checkpoint (cycle 2 of 3, mid-run)."""
    from dem.run.interrupts import RunInterrupted
    from dem.run.runner import run_case

    root = tmp_path_factory.mktemp("interrupted")
    case_dir = write_case(root / "case", TEXT)
    with pytest.MonkeyPatch.context() as mp:
        sigterm_at_check(mp, 12)
        with pytest.raises(RunInterrupted):
            run_case(load_case(case_dir), root / "out", progress=False, threads=1)
    assert (root / "out" / "checkpoint.npz").exists()
    return case_dir, root / "out"


def _copy(interrupted, tmp_path) -> tuple[Path, Path]:
    case_dir, out = interrupted
    shutil.copytree(out, tmp_path / "out")
    return case_dir, tmp_path / "out"


def _tamper(out: Path, change) -> None:
    """Rewrite out/checkpoint.npz with ``change(state, loop)`` applied (a valid zip still)."""
    path = out / "checkpoint.npz"
    with np.load(path) as data:
        state = {k: data[k] for k in data.files}
    loop = json.loads(str(state.pop(checkpoint.LOOP_KEY)))
    change(state, loop)
    state.setdefault(checkpoint.LOOP_KEY, np.array(json.dumps(loop)))  # unless set by change
    np.savez(path, **state)


def _snapshot(out: Path) -> dict:
    return {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def _resume(case_dir, out, capsys) -> tuple[int, str]:
    try:
        code = main(["run", str(case_dir), "--out", str(out), "--resume", "--threads", "1"])
    except SystemExit as exc:
        code = exc.code
    _, err = capsys.readouterr()
    return code, err


def _lines(err: str) -> list[str]:
    """stderr less the runner's progress line: it fills the trough before it reads the
    checkpoint (dem/run/runner.py; its owner is asked to read and compare it before the fill)."""
    return [line for line in err.splitlines() if not line.startswith("dem: filling")]


def _child(case_dir, out) -> tuple[int, str]:
    """dem run --resume in a child process: a file the pair loop would read out of bounds
    with crashes that process only (a segmentation fault before validation)."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, "-m", "dem.cli", "run", str(case_dir), "--out", str(out), "--resume"],
        capture_output=True, text=True, env=env, timeout=600,
    )  # fmt: skip
    return proc.returncode, proc.stderr


def _refused(interrupted, tmp_path, capsys, change, *words, child=False) -> None:
    case_dir, out = _copy(interrupted, tmp_path)
    _tamper(out, change)
    before = _snapshot(out)
    code, err = _child(case_dir, out) if child else _resume(case_dir, out, capsys)
    assert code == 2, err
    assert len(_lines(err)) == 1 and "Traceback" not in err, err
    assert "--resume" in err and "checkpoint.npz" in err, err
    for word in words:
        assert word in err, err
    assert _snapshot(out) == before  # nothing lost: the folder is as it was


def _set(key, index, value):
    def change(s, lp):
        s[key][index] = value

    return change


# --- the cases ------------------------------------------------------------------------


@pytest.mark.integration
def test_a_missing_key_is_named(interrupted, tmp_path, capsys):
    _refused(interrupted, tmp_path, capsys, lambda s, lp: s.pop("sph.v"), "lacks sph.v")


@pytest.mark.integration
def test_a_wrong_shape_is_named(interrupted, tmp_path, capsys):
    def change(s, lp):
        s["sph.radius"] = s["sph.radius"][:-1]

    _refused(interrupted, tmp_path, capsys, change, "sph.radius", "(119,)", "(120,)")


@pytest.mark.integration
def test_pair_indices_beyond_the_spheres_are_refused_not_a_segfault(interrupted, tmp_path, capsys):
    """Before the fix the pair loop read far out of bounds: a segmentation fault (-11)."""
    change = _set("nb.pair_j", 0, 10**9)
    _refused(interrupted, tmp_path, capsys, change, "nb.pair_j holds 1000000000", child=True)


@pytest.mark.integration
def test_a_loop_record_beyond_the_run_is_refused_not_a_nan_summary(interrupted, tmp_path, capsys):
    def change(s, lp):
        lp["cycle"] = lp["h5_cycles"] = 9

    _refused(interrupted, tmp_path, capsys, change, "cycle = 9", "beyond the run's end")


# --- variants -----------------------------------------------------------------------------------


def _loop(key, value):
    def change(s, lp):
        if value is KeyError:
            lp.pop(key)
        else:
            lp[key] = value

    return change


VARIANTS = {
    "nan-velocity": (_set("sph.v", (3, 1), np.nan), "sph.v holds non-finite"),
    "negative-radius": (_set("sph.radius", 5, -0.002), "sph.radius holds values <= 0"),
    "float-pairs": (lambda s, lp: s.update({"nb.pair_i": s["nb.pair_i"] * 1.0}), "nb.pair_i is"),
    "negative-pair": (_set("nb.pair_i", 0, -1), "nb.pair_i holds -1"),
    "pair-count": (_set("nb.counters", 0, 10**6), "nb.counters"),
    "pair-index": (_set("nb.part_slot", 0, 10**6), "nb.part_start, nb.part_slot"),
    "sizes": (_set("nb.sizes", 1, 10**12), "nb.pair_i is"),
    "unsorted-pairs": (
        lambda s, lp: s.update({"nb.pair_j": s["nb.pair_j"][::-1].copy()}),
        "nb.pair_i, nb.pair_j",
    ),
    "body-index": (_set("sph.body", 0, 999), "sph.body holds 999"),
    "drive-off": (_set("sim.counters", 2, 0), "sim.counters"),
    "dt-shape": (lambda s, lp: s.update({"sim.dt": np.array([1e-5])}), "sim.dt"),
    "stats-nan": (_set("sim.stats", 0, np.inf), "sim.stats"),
    "steps": (_loop("steps", 5), "steps = 5 disagrees"),
    "cycle-behind": (_loop("cycle", 0), "per_cycle"),
    "loop-key": (_loop("per_cycle", KeyError), "lacks 'per_cycle'"),
    "loop-type": (_loop("cycles", "2"), "cycles = '2'"),
    "loop-nan": (_loop("per_cycle", [float("nan")]), "per_cycle holds"),
    "total": (_loop("total_cycles", 30), "total_cycles = 30"),
    "chunk": (_loop("chunk", 7), "chunk = 7"),
    "vtk-entry": (
        lambda s, lp: lp["vtk_entries"].__setitem__(0, [0.0, "../../x.vtp", "trough.vtp"]),
        "vtk_entries",
    ),
    "loop-not-json": (
        lambda s, lp: s.update({checkpoint.LOOP_KEY: np.array("{not json")}),
        "loop.json is not JSON",
    ),
    "no-loop": (lambda s, lp: s.update({checkpoint.LOOP_KEY: np.array("[]")}), "an object"),
    "case-record": (_loop("case", "friction"), "case = 'friction'"),
}


@pytest.mark.integration
@pytest.mark.parametrize("variant", list(VARIANTS))
def test_other_tampered_checkpoints_are_refused_in_one_line(interrupted, tmp_path, capsys, variant):
    change, words = VARIANTS[variant]
    _refused(interrupted, tmp_path, capsys, change, words)


@pytest.mark.integration
def test_a_checkpoint_from_another_case_is_still_refused_by_its_keys(interrupted, tmp_path, capsys):
    """Validation does not hide the case comparison: other physics is named by key."""
    case_dir, out = _copy(interrupted, tmp_path)
    other = write_case(tmp_path / "other", TEXT.replace("friction = 0.35", "friction = 0.5"))
    code, err = _resume(other, out, capsys)
    assert code == 2 and "material.friction = 0.35 (now 0.5)" in err, err


@pytest.mark.integration
def test_the_untouched_checkpoint_passes_and_resumes(interrupted, tmp_path, capsys):
    case_dir, out = _copy(interrupted, tmp_path)
    state, loop = checkpoint.read(out / "checkpoint.npz")
    checkpoint.validate(state)
    code, err = _resume(case_dir, out, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["per_cycle_velocity"]) == 2
    assert np.isfinite(summary["mean_velocity"])


@pytest.mark.integration
def test_a_checkpoint_of_another_tangential_law_is_refused(interrupted, tmp_path, capsys):
    """The history width is the law's: "impact" keeps 5 floats a contact, "coulomb" 3. A
    checkpoint cut to 3 columns is a valid file of another law, refused against this case."""

    def change(s, lp):
        for key in ("nb.hist", "nb.scratch_hist", "sph.wall_hist", "sph.mesh_hist"):
            s[key] = np.ascontiguousarray(s[key][:, :3])

    _refused(interrupted, tmp_path, capsys, change, "3 floats of contact history", "'impact'")


@pytest.mark.integration
def test_a_history_width_of_no_law_is_refused(interrupted, tmp_path, capsys):
    def change(s, lp):
        s["nb.hist"] = np.zeros((s["nb.hist"].shape[0], 4))

    _refused(interrupted, tmp_path, capsys, change, "nb.hist", "history width")
