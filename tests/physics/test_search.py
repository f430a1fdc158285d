"""dem.physics.search: the golden-section search against the known optimum and its cost."""

import math

import pytest

from dem.physics.search import golden_evaluations, golden_section


def test_a_minimum_is_found_to_the_tolerance_with_the_counted_evaluations():
    calls = []

    def f(x):
        calls.append(x)
        return (x - 0.3) ** 2

    x, fx = golden_section(f, -1.0, 2.0, tol=1e-6)
    assert abs(x - 0.3) < 1e-6 and fx == f(x)
    assert len(calls) - 1 == golden_evaluations(3.0, 1e-6)


def test_a_maximum_after_a_fixed_number_of_narrowings():
    x, fx = golden_section(math.sin, 0.0, 3.0, iterations=40, maximize=True)
    assert x == pytest.approx(math.pi / 2, abs=1e-7) and fx == pytest.approx(1.0, abs=1e-14)


def test_it_takes_a_tolerance_or_a_count_not_both():
    with pytest.raises(ValueError, match="one of them"):
        golden_section(math.sin, 0.0, 1.0, tol=1e-3, iterations=3)
