"""Paths, the results file and small helpers shared by the parts of this study."""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib.pair import fresh_copy  # noqa: E402, F401 (the parts import it from here)

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


def fmt(x) -> str:
    """A float exactly (shortest repr), also for numpy scalars."""
    return repr(float(x))


def rel(path: Path) -> str:
    """A path relative to the repository root, as results.json records it."""
    return str(Path(path).resolve().relative_to(ROOT))
