"""Paths, the results file and small helpers shared by the parts of this study."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CASE = ROOT / "cases" / "screw-trough"
#: The case's keys as they were when this study was measured (shipped at 2e9 Pa, 4e-6 s since
#: 2026-11-26).
AS_MEASURED = {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}
SCRATCH = HERE / "scratch"
DECKS = HERE / "decks"
RESULTS = HERE / "results.json"


def write_results(results: dict) -> None:
    """results.json, rewritten after every run so that an interrupted study keeps its runs."""
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")


def fresh_copy(deck_dir: Path, work: Path) -> None:
    """A clean copy of a deck directory to run LIGGGHTS in (scratch/ is git-ignored)."""
    if work.exists():
        shutil.rmtree(work)
    shutil.copytree(deck_dir, work)


def fmt(x) -> str:
    """A float exactly (shortest repr), also for numpy scalars."""
    return repr(float(x))


def rel(path: Path) -> str:
    """A path relative to the repository root, as results.json records it."""
    return str(Path(path).resolve().relative_to(ROOT))
