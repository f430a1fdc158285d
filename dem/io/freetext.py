r"""Free text in files other programs read: a name stays inside its line and cannot add a command.

dem writes names and paths it did not choose (a case folder's name, ``--out``, a mesh or
template file's name, the run a settle count came from) into files that LIGGGHTS, LAMMPS,
ParaView or a shell read: the decks' comments, the title lines of LAMMPS data and molecule
files, a clump template's header, the reports. A newline in such a name would end the comment
and make the rest of the name a live command (``shell ...`` in a deck runs a program). Every
line of those files goes through :func:`input_line`, every fragment of text shown to a person
through :func:`free_text`:

- control characters (Unicode Cc: C0, DEL, C1 with NEL), format characters (Cf: the bidi
  overrides that make a line read differently from what it is) and the line and paragraph
  separators (Zl, Zp: U+2028, U+2029) are written as visible escapes, ``\x0a``, ``\u2028``;
- in a line of a LAMMPS or LIGGGHTS input, a last printable ``&`` (both join the next line to
  it, before comments are stripped, so a comment ending in ``&`` would swallow the next command)
  and a triple quote (LAMMPS reads on to the next one) are escaped as well.

Nothing else changes, so a name without such characters is written as it is.
"""

from __future__ import annotations

import unicodedata
from collections.abc import Iterable

#: Unicode categories of the characters :func:`free_text` writes as escapes.
ESCAPED_CATEGORIES = frozenset({"Cc", "Cf", "Zl", "Zp"})


def _escape(ch: str) -> str:
    code = ord(ch)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def free_text(value: object) -> str:
    """``str(value)`` on one line: every control, format or separator character escaped."""
    text = str(value)
    if text.isascii() and text.isprintable():  # the usual case, at once
        return text
    return "".join(
        _escape(ch) if unicodedata.category(ch) in ESCAPED_CATEGORIES else ch for ch in text
    )


def input_line(line: str) -> str:
    r"""One line of a LAMMPS or LIGGGHTS input file, data file or template, made inert.

    :func:`free_text`, and the two ways LAMMPS's reader joins lines: a triple quote and a last
    printable ``&`` become ``\x22\x22\x22`` and ``\x26``.
    """
    text = free_text(line).replace('"""', "\\x22\\x22\\x22")
    body = text.rstrip()
    if body.endswith("&"):
        text = body[:-1] + "\\x26"
    return text


def input_text(lines: Iterable[str]) -> str:
    """The text of an input file from its lines (:func:`input_line` each), newline-terminated."""
    return "".join(input_line(line) + "\n" for line in lines)


def shown_text(text: str) -> str:
    """A person's text of many lines (a report): each line :func:`free_text`, the newlines kept."""
    return "\n".join(free_text(line) for line in text.split("\n"))
