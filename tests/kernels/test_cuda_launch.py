"""The prepared launch's argument conversion (dem/kernels/cuda/launch.py), without a GPU.

The bytes cuda.core lays out for the driver are compared in the cuda extra's venv by
validation/performance/launch_args.py (CI's sm_90 step); here the conversion's own rules.
"""

import ctypes

import pytest

from dem.kernels.cuda.launch import fast_arg


@pytest.mark.parametrize("value", [0.0, -1.5e-300, 1.0 / 3.0, float("inf")])
def test_a_ctypes_double_becomes_the_same_python_float(value):
    out = fast_arg(ctypes.c_double(value))
    assert type(out) is float and out == value


@pytest.mark.parametrize("value", [0, -(1 << 62), (1 << 62) + 7])
def test_a_ctypes_int64_becomes_the_same_python_int(value):
    out = fast_arg(ctypes.c_int64(value))
    assert type(out) is int and out == value


@pytest.mark.parametrize(
    "value", [ctypes.c_int32(3), ctypes.c_float(0.5), ctypes.c_uint16(2), True, 12345]
)
def test_other_arguments_pass_unchanged(value):
    """Narrower ctypes keep their width; numba's bools and array fields are Python already."""
    assert fast_arg(value) is value
