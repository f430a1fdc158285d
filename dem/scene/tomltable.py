"""A typed reader of one TOML table, for the case file (:mod:`dem.scene.case`).

Each getter reads one key, checks its type and range, and raises
:class:`dem.errors.InputError` naming the dotted key (``drive.angle``), the value as written,
what is allowed and the file; an unknown key is refused with the closest known name.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from dem.errors import InputError
from dem.quantities import QUANTITIES

#: Default meaning "the key must be given".
REQUIRED = object()


def suggest(name: str, known: list[str] | tuple[str, ...]) -> str:
    """Return ' (did you mean 'x'?)' for the closest known name, or ''."""
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    close = close or [k for k in known if name and (k.startswith(name) or name.startswith(k))]
    return f" (did you mean {close[0]!r}?)" if close else ""


class Table:
    """One TOML table being read: typed getters that raise InputError with the dotted key."""

    def __init__(self, name: str, data: dict[str, Any], source: str, directory: Path):
        self.name = name
        self.data = data
        self.source = source
        self.directory = directory

    def error(self, key: str, value: object, allowed: str) -> InputError:
        """An InputError for ``key`` of this table (not raised: the caller raises it)."""
        return InputError(f"{self.name}.{key}", value, allowed, source=self.source)

    def check_known(self, known: tuple[str, ...]) -> None:
        """Refuse keys that the table does not define (typos would otherwise be ignored)."""
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
        resolved = (self.directory / value).resolve()
        if not resolved.is_file():
            raise self.error(key, value, f"an existing file (no file at {resolved})")
        return resolved
