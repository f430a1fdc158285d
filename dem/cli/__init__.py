"""The ``dem`` command: parses arguments, calls the library, prints. No physics here.

Every error the user can fix ends with exit status 2 and one line naming the option (or case
key), the value and what is allowed; nothing is computed before the inputs are checked.
"""

import sys
import warnings

from dem.cli.options import EXIT_USAGE, option_name
from dem.cli.parser import build_parser
from dem.errors import InputError, SimulationError, one_line_warning

#: What an interrupted write leaves behind, by command (the files are replaced whole or not).
KEPT = {
    "run": "what was written before it stays readable (results.h5 up to its last cycle; "
    "--resume continues from the last checkpoint)",
    "sweep": "every finished point's folder stays as it is, and a rerun skips them",
    "optimum": "every finished run's folder stays as it is",
    "atlas": "every finished point's folder stays as it is, and a rerun skips them",
}


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``dem`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    warnings.formatwarning = one_line_warning
    try:
        return args.func(args)
    except InputError as err:
        where = f"{err.source}: " if err.source else ""
        # a positional argument (its metavar, upper case) is named as it is, not as an option
        # and a case key (table.key) as itself, not as an option that does not exist
        plain = err.source or err.key.startswith("--") or err.key.isupper() or "." in err.key
        key = err.key if plain else option_name(err.key)
        if err.value is None:
            print(f"dem: error: {where}missing {key}: {err.allowed}", file=sys.stderr)
        else:
            print(f"dem: error: {where}{key} = {err.value!r}: {err.allowed}", file=sys.stderr)
        return EXIT_USAGE
    except SimulationError as err:
        print(f"dem: simulation stopped: {err}", file=sys.stderr)
        return 1
    except OSError as err:  # disk full, permission, a vanished folder: one line, no traceback
        where = err.filename or "an output file"
        cause = err.strerror or str(err) or type(err).__name__
        kept = KEPT.get(args.command, "what was written before it stays as it was")
        print(f"dem: error: cannot write or read {where}: {cause}; {kept}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("dem: interrupted", file=sys.stderr)
        return 130
