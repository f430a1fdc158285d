"""Errors that reach the user: bad input is named by key, value and allowed range."""


class InputError(ValueError):
    """A value given by the user is outside what the model allows.

    The message names where the value came from (a command-line option or a case-file key),
    the value, and what is allowed, so that one line tells the user what to change.
    """

    def __init__(self, key: str, value: object, allowed: str, source: str | None = None):
        self.key = key
        self.value = value
        self.allowed = allowed
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{key} = {value!r} is not allowed: {allowed}")

    def __reduce__(self):
        """Rebuilt from its fields, so that it crosses process boundaries (replicas, sweeps)."""
        return (type(self), (self.key, self.value, self.allowed, self.source))


class SimulationError(RuntimeError):
    """A run went unstable or cannot continue; the message says why and what to change."""


def one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning as the command line prints it, ``dem: warning: ...`` (no file, no line)."""
    return f"dem: warning: {message}\n"
