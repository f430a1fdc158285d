"""A study's tables: CSV rows written with their header and read back as numbers; README tables."""

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


#: The markers between which a study's script writes its README's tables.
BEGIN, END = "<!-- tables: begin (run.py writes these) -->", "<!-- tables: end -->"


def write_readme_tables(path: Path, lines: list[str]) -> None:
    """Replace what lies between :data:`BEGIN` and :data:`END` in ``path`` by ``lines``.

    Nothing happens where the file or either marker is missing: a README that was edited by
    hand without them keeps its text.
    """
    path = Path(path)
    if not path.exists():
        return
    text = path.read_text()
    if BEGIN not in text or END not in text:
        return
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    path.write_text(head + BEGIN + "\n\n" + "\n".join(lines) + "\n\n" + END + tail)
