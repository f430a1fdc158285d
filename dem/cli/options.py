"""The command line's option types, ranges and small shared helpers (JSON output, --set)."""

import argparse
import math
from pathlib import Path
from typing import NoReturn

from dem.errors import InputError
from dem.quantities import QUANTITIES

EXIT_USAGE = 2

#: The quantity (:data:`dem.quantities.QUANTITIES`) of each numeric option: its range.
QUANTITY_OF = {
    "--throw-number": "throw_number",
    "--angle": "angle",
    "--friction": "friction",
    "--inclination": "inclination",
    "--frequency": "frequency",
    "--amplitude": "amplitude",
    "--peak-acceleration": "peak_acceleration",
    "--drive-velocity": "drive_velocity",
    "--eps-t": "restitution",
    "--eps-n": "restitution",
    "--inertia-factor": "inertia_factor",
    "--cycles": "cycles",
    "--threads": "threads",
    "--replicas": "replicas",
    "--workers": "workers",
    "--max-runs": "max_runs",
    "--tolerance": "tolerance",
}

#: Allowed values of each numeric option, used in error messages.
#: Help and "missing option" texts of the options, from the one table of quantities.
ALLOWED = {_option: QUANTITIES[_name].help for _option, _name in QUANTITY_OF.items()} | {
    "--eps-t": "tangential " + QUANTITIES["restitution"].help,
    "--eps-n": "normal " + QUANTITIES["restitution"].help,
}


def check_numbers(args) -> None:
    """Every numeric option given to this command against its range, before any work.

    An option out of range is an :class:`InputError` naming the option (``--frequency``), the
    value and the range, whether or not the command goes on to use it (an option the chosen
    ``--hold`` ignores is a typing error all the same). Options holding value lists
    (``dem pointmass sweep``) are checked value by value where they are parsed.
    """
    for option, name in QUANTITY_OF.items():
        value = getattr(args, option[2:].replace("-", "_"), None)
        if isinstance(value, int | float) and not isinstance(value, bool):
            QUANTITIES[name].check(value, option)


class Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit with status 2."""

    def error(self, message: str) -> NoReturn:  # noqa: D102
        prefix = "the following arguments are required: "
        if message.startswith(prefix):
            names = [n.strip() for n in message[len(prefix) :].split(",")]
            parts = [f"{n} ({ALLOWED[n]})" if n in ALLOWED else n for n in names]
            message = "missing option " + ", ".join(parts)
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def number(text: str) -> float:
    """A finite float option value (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"value {text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"value {text!r} is not a finite number")
    return value


def whole_from(minimum: int):
    """An argparse type: a whole number >= ``minimum``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"value {text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"value {value} must be >= {minimum}")
        return value

    return parse


WHOLE = whole_from(1)
WHOLE_FROM_0 = whole_from(0)


def option_name(key: str) -> str:
    """The option a key is given by on the command line (``--throw-number``)."""
    return "--" + key.replace("_", "-")


def print_json(obj) -> None:
    """Print ``obj`` as indented JSON (numpy values as plain numbers)."""
    from dem.io.files import json_text

    print(json_text(obj, indent=2, default=json_default))


def json_default(value):
    """JSON form of the numpy scalars and arrays the library returns."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot serialise {type(value).__name__}")


# --- dem pointmass ------------------------------------------------------------------------------


def parse_bounds(text: str | None, allowed: str) -> tuple[float, float] | None:
    """``--bounds LO:HI`` as two numbers, None where it is not given."""
    if not text:
        return None
    try:  # each a number ("10,20:30" took 10 and dropped 20)
        lo, hi = (float(p) for p in text.split(":"))
    except ValueError:
        raise InputError("--bounds", text, allowed) from None
    return lo, hi


def set_overrides(texts: list[str] | None) -> dict:
    """``--set table.key=value`` options as load_case overrides.

    One value per key: several values are a sweep (``dem sweep``).
    """
    from dem.studies.sweep import parse_set

    overrides: dict = {}
    for text in texts or ():
        key, values = parse_set(text)
        if len(values) != 1:
            many = text.partition("=")[2]
            raise InputError(f"--set {key}", many, "one value (several: dem sweep takes them)")
        if key in overrides:
            raise InputError("--set", key, "each key at most once")
        overrides[key] = values[0]
    return overrides
