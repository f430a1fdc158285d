"""A study's CSV tables: rows of dicts written with their header, and read back as numbers."""

from __future__ import annotations

import csv
from pathlib import Path


def write_rows(path: Path, rows: list[dict]) -> Path:
    """Write ``rows`` (dicts with the same keys) as CSV with a header line; returns ``path``."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return Path(path)


def read_rows(path: Path) -> list[dict]:
    """The rows of :func:`write_rows`: numbers as floats, True/False as booleans."""
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v)
            except ValueError:
                r[k] = {"True": True, "False": False}.get(v, v)
    return rows
