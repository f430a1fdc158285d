"""CPU kernel functions compiled a second time, from their own source, as CUDA device functions.

The CPU's per-grain functions that take arrays (a body's kick and drift, its members' placement,
a mesh's contacts) cannot be called from a CUDA kernel in numba's CUDA simulator, which runs
the kernels as Python and cannot pass arrays into CPU-compiled code. :func:`device` compiles
such a function's Python source as a CUDA device function instead, with the array-taking
functions it calls bound to their device versions; the scalar ones (the contact law's core, the
free rotation, the periodic image) it calls as they are. So there is one definition of each: in
the simulator the device version runs the CPU's operations in its order (the same bits), on a
GPU numba-cuda compiles the same code.
"""

from __future__ import annotations

import types

from numba import cuda


def device(function, **names):
    """``function`` (a CPU kernel function or its Python source) as a CUDA device function.

    The names in ``names`` (the array-taking functions it calls) are bound to the given device
    functions instead of the CPU's; everything else it refers to is as in its own module.
    """
    py = getattr(function, "py_func", function)
    scope = dict(py.__globals__)
    scope.update(names)
    source = types.FunctionType(py.__code__, scope, py.__name__, py.__defaults__, py.__closure__)
    source.__doc__ = py.__doc__
    return cuda.jit(device=True)(source)
