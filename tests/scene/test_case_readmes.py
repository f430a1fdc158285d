"""Every number a shipped case's README states about the case is its case.toml's.

The READMEs say what a case is in words; a README that says E = 5e7 Pa beside a case.toml that
says 5e8 (it happened) misleads the user who reads it first. Each pattern below reads one kind
of statement; the value must agree with the case to the digits the README gives.
"""

import math
import re
from pathlib import Path

import pytest

from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"
READMES = sorted(p for p in CASES.glob("*/README.md") if (p.parent / "case.toml").is_file())
NUMBER = r"([0-9]+(?:\.[0-9]+)?(?:e[+-]?[0-9]+)?)"

#: (pattern, the case's value it states, scale of the README's unit)
CLAIMS = [
    (rf"^{NUMBER} (?:screws|spheres)\b", lambda c: c.particles.count, 1.0),
    (rf"E = {NUMBER} Pa", lambda c: c.contact.youngs_modulus, 1.0),
    (rf"k = {NUMBER} N/m", lambda c: c.contact.stiffness, 1.0),
    (rf"\bmu = {NUMBER}", lambda c: c.material.friction, 1.0),
    (rf"\b{NUMBER} Hz\b", lambda c: c.drive.frequency, 1.0),
    (rf"phi = {NUMBER} deg", lambda c: c.drive.angle, 1.0),
    (rf"Gamma = {NUMBER}", lambda c: c.drive.throw_number, 1.0),
    (rf"\bA = {NUMBER} mm", lambda c: c.drive.amplitude, 1e-3),
    (rf"\br = {NUMBER} mm", lambda c: c.particles.radius, 1e-3),
    (rf"eps_n = {NUMBER}", lambda c: c.material.restitution_normal, 1.0),
    (rf"eps_t = {NUMBER}", lambda c: c.material.restitution_tangential, 1.0),
    (rf"{NUMBER} kg/m\^3", lambda c: c.material.density, 1.0),
    (rf"{NUMBER} m x [0-9.]+ m (?:periodic )?section", lambda c: c.trough.length, 1.0),
    (rf"[0-9.]+ m x {NUMBER} m (?:periodic )?section", lambda c: c.trough.width, 1.0),
    (rf"\b{NUMBER} kg/s fed", lambda c: c.feeder.feed_rate, 1.0),
]


def _agrees(text: str, value: float, scale: float) -> bool:
    """``value`` in the README's unit rounds to ``text`` at the digits ``text`` gives."""
    stated = float(text)
    mantissa = text.lower().split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(text.lower().split("e")[1]) if "e" in text.lower() else 0
    half_unit = 0.5 * 10.0 ** (exponent - decimals)
    return math.isclose(value / scale, stated, abs_tol=half_unit * (1 + 1e-9))


def test_there_are_case_readmes():
    assert len(READMES) >= 3


@pytest.mark.validation
@pytest.mark.parametrize("readme", READMES, ids=[p.parent.name for p in READMES])
def test_a_case_readme_states_its_case_tomls_numbers(readme):
    case = load_case(readme.parent)
    text = " ".join(readme.read_text(encoding="utf-8").split())  # one line: no wrap breaks
    text = re.sub(r"^# \S+ ", "", text)  # the title
    checked = 0
    for pattern, value_of, scale in CLAIMS:
        for found in re.finditer(pattern, text, flags=re.M):
            value = value_of(case)
            assert value is not None, f"{readme}: '{found.group(0)}' but the case has no such key"
            assert _agrees(found.group(1), value, scale), (
                f"{readme}: '{found.group(0)}', case.toml gives {value / scale:g}"
            )
            checked += 1
    assert checked >= 4, f"{readme}: too few numbers recognised to check ({checked})"


def test_the_check_catches_a_wrong_number():
    assert _agrees("5e8", 5.0e8, 1.0) and not _agrees("5e7", 5.0e8, 1.0)
    assert _agrees("3.06", 3.0613, 1.0) and not _agrees("3.1", 3.0613 - 0.1, 1.0)
    assert _agrees("0.294", 2.944e-4, 1e-3)
