"""A typed reader of one TOML table, for the case file (:mod:`dem.scene.case`).

Each getter reads one key, checks its type and range, and raises
:class:`dem.errors.InputError` naming the dotted key (``drive.angle``), the value as written,
what is allowed and the file; an unknown key is refused with the closest known name. A table
read with its rows (:class:`Key`, the schema of :mod:`dem.scene.schema`) reads each key by name
(:meth:`Table.read`: type, range, default) and refuses the keys of a shape or law not chosen
(:meth:`Table.refuse_foreign`).
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dem.errors import InputError
from dem.quantities import QUANTITIES

#: Default meaning "the key must be given".
REQUIRED = object()
#: Owner of a key that every shape and law reads.
ALL = "all"
_ROW = object()  # Table.read's default: the row's
_NAME = re.compile(r"[A-Za-z0-9_-]{1,32}")


@dataclass(frozen=True)
class Derived:
    """A default the reader computes from other values (``how`` says from which)."""

    how: str


@dataclass(frozen=True)
class Key:
    """One key of a table: how it is read, its range, its default and who reads it.

    Attributes:
        name: Key name within its table (``angle``).
        kind: ``"number"`` (a float; an int is accepted), ``"whole"`` (an int), ``"boolean"``,
            ``"choice"`` (a string of ``choices``), ``"path"`` (a file relative to the case
            directory, read as optional: a reader that needs one says why it is missing),
            ``"numbers"`` (a non-empty array of numbers, each in ``quantity``'s range),
            ``"tables"`` (a non-empty array of tables, ``[[table.key]]``, read by the table's
            reader) or ``"name"`` (a short name: letters, digits, ``_`` and ``-``).
        quantity: Row of :data:`dem.quantities.QUANTITIES` giving the range of a number or
            whole number (None for the other kinds).
        default: The value when the key is absent: :data:`REQUIRED`, a value (None: unset), or
            a :class:`Derived` default, which the reader passes to :meth:`Table.read`.
        owners: :data:`ALL`, or the selector values under which the key is read: a shape
            (``"screw"``), a law (``"coulomb"``), or several that must all be chosen joined by
            ``+`` (``"liggghts+linear"``). Under any other choice the key is refused.
        choices: The strings a choice accepts, in the order errors list them.
        auto: True: the string ``"auto"`` is accepted too and read as None.

    """

    name: str
    kind: str
    quantity: str | None = None
    default: Any = REQUIRED
    owners: tuple[str, ...] = (ALL,)
    choices: tuple[str, ...] = ()
    auto: bool = False

    @property
    def numeric(self) -> bool:
        """Whether the key holds a number or a whole number."""
        return self.kind in ("number", "whole")

    def owned(self, chosen: tuple[str, ...]) -> bool:
        """Whether the key is read when the table's selectors have the values ``chosen``."""
        return any(o == ALL or set(o.split("+")) <= set(chosen) for o in self.owners)


def suggest(name: str, known: list[str] | tuple[str, ...]) -> str:
    """Return ' (did you mean 'x'?)' for the closest known name, or ''."""
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    close = close or [k for k in known if name and (k.startswith(name) or name.startswith(k))]
    return f" (did you mean {close[0]!r}?)" if close else ""


class Table:
    """One TOML table being read: typed getters that raise InputError with the dotted key."""

    def __init__(
        self,
        name: str,
        data: dict[str, Any],
        source: str,
        directory: Path,
        keys: tuple[Key, ...] = (),
    ):
        self.name = name
        self.data = data
        self.source = source
        self.directory = directory
        self.keys = {k.name: k for k in keys}

    def error(self, key: str, value: object, allowed: str) -> InputError:
        """An InputError for ``key`` of this table (not raised: the caller raises it)."""
        return InputError(f"{self.name}.{key}", value, allowed, source=self.source)

    def check_known(self, known: tuple[str, ...] | None = None) -> None:
        """Refuse keys that the table does not define (typos would otherwise be ignored).

        ``known``: the key names; None: those of the table's rows.
        """
        known = tuple(self.keys) if known is None else known
        for key, value in self.data.items():
            if key not in known:
                raise self.error(
                    key,
                    value,
                    f"a key of [{self.name}]: {', '.join(known)}{suggest(key, known)}",
                )

    def _get(self, key: str, default: Any) -> tuple[bool, Any]:
        if key in self.data:
            return True, self.data[key]
        if default is REQUIRED:
            raise InputError(
                f"{self.name}.{key}", None, "a value is required (the key is missing)", self.source
            )
        return False, default

    def number(
        self,
        key: str,
        default: Any = REQUIRED,
        check: Callable[[float], bool] | None = None,
        allowed: str = "a finite number",
    ) -> float | None:
        """Read a float (an int is accepted; a bool is not); ``check`` gives the range."""
        present, value = self._get(key, default)
        if not present:
            return value
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, value, f"a number: {allowed}")
        value = float(value)
        if not math.isfinite(value) or (check is not None and not check(value)):
            raise self.error(key, value, allowed)
        return value

    def quantity(self, key: str, default: Any = REQUIRED, name: str | None = None) -> float | None:
        """Read a number checked against :data:`dem.quantities.QUANTITIES` [``name`` or key]."""
        q = QUANTITIES[name or key]
        return self.number(key, default, q.accepts, q.allowed)

    def whole(self, key: str, default: Any = REQUIRED) -> int:
        """Read an integer checked against :data:`dem.quantities.QUANTITIES` [key]."""
        q = QUANTITIES[key]
        return self.integer(key, default, q.accepts, q.allowed)

    def integer(
        self,
        key: str,
        default: Any = REQUIRED,
        check: Callable[[int], bool] | None = None,
        allowed: str = "an integer",
    ) -> int:
        """Read an int (not a bool, not a float)."""
        present, value = self._get(key, default)
        if not present:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, value, f"an integer: {allowed}")
        if check is not None and not check(value):
            raise self.error(key, value, allowed)
        return value

    def numbers(self, key: str, quantity: str, default: Any = REQUIRED) -> tuple[float, ...]:
        """Read a non-empty array of numbers, each checked against ``QUANTITIES[quantity]``."""
        present, value = self._get(key, default)
        if not present:
            return value
        q = QUANTITIES[quantity]
        if not isinstance(value, list) or not value:
            raise self.error(key, value, f"a non-empty array of numbers, each {q.allowed}")
        for item in value:
            if isinstance(item, bool) or not isinstance(item, int | float):
                raise self.error(key, value, f"an array of numbers ({item!r} is not one)")
            item = float(item)
            if not math.isfinite(item) or not q.accepts(item):
                raise self.error(key, value, f"an array of numbers, each {q.allowed} "
                                 f"({item!r} is not)")  # fmt: skip
        return tuple(float(v) for v in value)

    def tables(self, key: str, default: Any = REQUIRED) -> tuple[dict, ...]:
        """Read a non-empty array of tables (``[[name.key]]`` in TOML), each a dict."""
        present, value = self._get(key, default)
        if not present:
            return value
        if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
            raise self.error(key, value, f"an array of tables, written [[{self.name}.{key}]]")
        return tuple(value)

    def name_text(self, key: str, default: Any = REQUIRED) -> str:
        """Read a short name: 1 to 32 letters, digits, ``_`` or ``-``."""
        present, value = self._get(key, default)
        if present and (not isinstance(value, str) or not _NAME.fullmatch(value)):
            raise self.error(key, value, "a name of 1 to 32 letters, digits, '_' or '-'")
        return value

    def boolean(self, key: str, default: Any = REQUIRED) -> bool:
        """Read a TOML boolean (true/false)."""
        present, value = self._get(key, default)
        if present and not isinstance(value, bool):
            raise self.error(key, value, "true or false")
        return value

    def choice(self, key: str, choices: tuple[str, ...], default: Any = REQUIRED) -> str:
        """Read a string out of ``choices``."""
        present, value = self._get(key, default)
        if present and (not isinstance(value, str) or value not in choices):
            hint = suggest(value, choices) if isinstance(value, str) else ""
            raise self.error(key, value, f"one of {', '.join(map(repr, choices))}{hint}")
        return value

    def path(self, key: str) -> Path | None:
        """Read an optional file path, relative to the case directory; the file must exist."""
        present, value = self._get(key, None)
        if not present:
            return None
        if not isinstance(value, str) or not value:
            raise self.error(key, value, "a file path relative to the case directory")
        if "\x00" in value:  # the system refuses it (Python raises ValueError)
            raise self.error(key, value, "a file path without NUL characters")
        try:
            resolved = (self.directory / value).resolve()
            found = resolved.is_file()
        except OSError as exc:  # a name too long, a loop of links
            raise self.error(
                key, value, f"a file path the system can open ({exc.strerror})"
            ) from None
        if not found:
            raise self.error(key, value, f"an existing file (no file at {resolved})")
        return resolved

    def read(self, name: str, default: Any = _ROW) -> Any:
        """Read the key ``name`` as its row says (kind, range, choices, ``"auto"``).

        ``default``: the value when the key is absent; left out, the row's (a :class:`Derived`
        default must be given here).
        """
        key = self.keys[name]
        if default is _ROW:
            default = key.default
            if isinstance(default, Derived):
                raise TypeError(f"{self.name}.{name}: its default is derived ({default.how})")
        if key.auto and self.data.get(name) == "auto":
            return None
        if key.kind in ("number", "whole", "numbers"):
            assert key.quantity is not None  # every number row names its quantity
            if key.kind == "numbers":
                return self.numbers(name, key.quantity, default)
            q = QUANTITIES[key.quantity]
            if key.kind == "number":
                return self.number(name, default, q.accepts, q.allowed)
            return self.integer(name, default, q.accepts, q.allowed)
        if key.kind == "boolean":
            return self.boolean(name, default)
        if key.kind == "choice":
            return self.choice(name, key.choices, default)
        if key.kind == "tables":
            return self.tables(name, default)
        if key.kind == "name":
            return self.name_text(name, default)
        return self.path(name)

    def refuse_foreign(self, chosen: tuple[str, ...], why: Callable[[str], str]) -> None:
        """Refuse a key given here that no owner among ``chosen`` reads.

        Owners are taken in the order the rows first name them, and each owner's keys in row
        order; ``why(owner)`` is the allowed text of the error for a key of ``owner``.
        """
        owners = dict.fromkeys(o for k in self.keys.values() for o in k.owners if o != ALL)
        for owner in owners:
            for key in self.keys.values():
                if owner in key.owners and key.name in self.data and not key.owned(chosen):
                    raise self.error(key.name, self.data[key.name], why(owner))
