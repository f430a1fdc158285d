"""Editing a case file's text in place: set ``table.key`` values, keep everything else.

``dem plan --suggest`` writes the advised case and ``dem calibrate`` writes the fitted
``[contact]`` keys back into ``case.toml`` through :func:`set_case_keys`: the lines of the keys
set are replaced (or added after their table's header, with a comment saying who set them), and
the rest of the file, its comments and its order, is kept. Reading and checking a case is
:mod:`dem.scene.case`'s job; this module only writes text.
"""

from __future__ import annotations

import re
from pathlib import Path


def set_contact_keys(path: Path, values: dict[str, float], comment: str) -> str:
    """Return the text of the case file ``path`` with ``values`` set in its [contact] table.

    As :func:`set_case_keys` with every key in [contact].
    """
    return set_case_keys(path, {f"contact.{k}": v for k, v in values.items()}, comment)


def set_case_keys(path: Path, values: dict[str, object], comment: str) -> str:
    """Return the text of the case file ``path`` with ``values`` ({"table.key": value}) set.

    A key already in its table is set where it stands, with ``comment``, and its old line
    follows as a comment (``# was: key = old  # its comment``), so that its unit and the
    comment lines that continue it stay in place; a new key follows the table's header. The
    rest of the file (comments, order) is kept. A missing table is appended. Values are written
    as TOML: numbers, strings and booleans.
    """
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    any_header = re.compile(r"^\s*\[")
    tables: dict[str, dict[str, object]] = {}
    for dotted, value in values.items():
        table, _, key = dotted.rpartition(".")
        tables.setdefault(table, {})[key] = value
    for table, keys in tables.items():
        header = re.compile(r"^\s*\[\s*" + re.escape(table) + r"\s*\]\s*(#.*)?$")
        new = [f"{key} = {_toml_value(value)}  # {comment}" for key, value in keys.items()]
        start = next((i for i, line in enumerate(lines) if header.match(line)), None)
        if start is None:
            lines = [*lines, "", f"[{table}]", *new]
            continue
        end = next(
            (i for i in range(start + 1, len(lines)) if any_header.match(lines[i])), len(lines)
        )
        own = re.compile(r"^\s*(" + "|".join(map(re.escape, keys)) + r")\s*=")
        body, placed = [], set()
        for line in lines[start + 1 : end]:
            match = own.match(line)
            if match is None:
                body.append(line)
                continue
            key = match.group(1)
            body += [f"{key} = {_toml_value(keys[key])}  # {comment}", f"# was: {line.strip()}"]
            placed.add(key)
        added = [line for key, line in zip(keys, new, strict=True) if key not in placed]
        lines = [*lines[: start + 1], *added, *body, *lines[end:]]
    return "\n".join(lines) + "\n"


def _toml_value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return toml_string(value)
    return repr(value)


#: TOML's short escapes in a basic string.
_SHORT_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
                  "\r": "\\r"}  # fmt: skip


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string that reads back to the same text.

    Quote and backslash escaped, and every control character TOML forbids raw (U+0000-U+001F,
    U+007F) as an escape, so a value cannot end its line and start another key; other
    characters are written as UTF-8 (JSON's surrogate-pair escapes are not TOML).
    """
    out = []
    for ch in text:
        if ch in _SHORT_ESCAPES:
            out.append(_SHORT_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'
