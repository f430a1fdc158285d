"""Kernel launches: the launch shapes in one place, and the step's arguments converted once.

The shapes: :data:`THREADS_PER_BLOCK` for every per-sphere and per-body kernel (:func:`blocks`),
the queue of step launches (:data:`MAX_CHUNK`), and the compact step's block and pass size
(:data:`COMPACT_BLOCK`, :data:`COMPACT_KEEP`, the rows of its shared arrays). Tuning knobs only:
none changes a bit of the results.

numba-cuda converts every argument of every launch in Python (an array is seven numbers, a tuple
of 24 floats 24 ctypes objects): for :func:`dem.kernels.cuda.step.step_kernel`'s 37 arguments
that cost about 0.55 ms a launch on an H200 host (measured: 1e4 and 1e5 spheres stepped at the
same 0.56-0.62 ms a step), more than the kernel itself below a million spheres. A
:class:`PreparedLaunch` converts the arguments once, as numba-cuda would (its own
``_Kernel._prepare_args``), keeps the converted list, and launches through the same
``cuda.core.launch`` call; a launch then only changes the scalars that change between steps.
The arrays must be the same objects at every launch: the caller prepares one launch per set of
buffers and prepares again after a rebuild replaces them.

The converted scalars are then handed to ``cuda.core.launch`` as Python floats and ints
(:func:`fast_arg`), not as numba's ctypes objects: cuda.core's ``ParamHolder`` takes a float as a
C double and an int as an intptr_t (8 bytes) in its first type checks, but a ctypes scalar only
after some thirty failed ``isinstance`` checks against numpy's and ctypes' types, about 0.6 us
each; the step's two parameter rows alone are 48 ctypes doubles. The driver receives the same
bytes (validation/performance/launch_args.py checks them and times the difference).

This uses numba-cuda internals (pinned at 0.30.4 by the ``cuda`` extra); where they differ,
:func:`prepare` returns None and the caller launches the ordinary way.
"""

from __future__ import annotations

import ctypes

#: Threads per block of every per-sphere and per-body kernel.
THREADS_PER_BLOCK = 128

#: The most step launches the GPU engine queues before it reads the rebuild trip
#: (:meth:`dem.engine.gpu.engine.GpuEngine.steps`).
MAX_CHUNK = 64

#: Threads per block of :func:`dem.kernels.cuda.compact.compact_step_kernel` (its shared arrays'
#: rows).
COMPACT_BLOCK = 128

#: Touching candidates a sphere lists in one pass of the compact step (its shared list's rows, a
#: column a thread: a warp's writes fall in different banks); a sphere with more takes further
#: passes.
COMPACT_KEEP = 16


def blocks(n: int) -> int:
    """Blocks of :data:`THREADS_PER_BLOCK` threads covering n items (at least one)."""
    return max(1, (n + THREADS_PER_BLOCK - 1) // THREADS_PER_BLOCK)


#: An intptr_t is 8 bytes: a Python int passes an int64 (cuda.core passes ints as intptr_t).
_INT64_AS_INT = ctypes.sizeof(ctypes.c_void_p) == 8


def fast_arg(value):
    """A converted kernel argument as cuda.core converts it fastest, the same bytes.

    A ctypes double becomes a Python float (a C double to cuda.core), a ctypes int64 a Python
    int (an intptr_t, the same 8 bytes on a 64-bit host); anything else is returned as it is.
    """
    if isinstance(value, ctypes.c_double):
        return float(value.value)
    if _INT64_AS_INT and isinstance(value, ctypes.c_int64):
        return int(value.value)
    return value


class PreparedLaunch:
    """One kernel with one set of arguments, launchable many times with new scalars."""

    def __init__(self, dispatcher, griddim, blockdim, args):
        from cuda.core import LaunchConfig
        from numba.cuda._compat import CUDA_CORE_GE_1_0

        cfg = dispatcher[griddim, blockdim]
        self.stream = cfg.stream
        argtypes = tuple(dispatcher.typeof_pyval(a) for a in args)
        kernel = dispatcher.compile(argtypes)
        self.positions = []
        self.kernelargs = []
        for t, v in zip(kernel.argument_types, args, strict=True):
            self.positions.append(len(self.kernelargs))
            kernel._prepare_args(t, v, self.stream, [], self.kernelargs)
        self.kernelargs = [fast_arg(a) for a in self.kernelargs]
        coop = "is_cooperative" if CUDA_CORE_GE_1_0 else "cooperative_launch"
        self.config = LaunchConfig(
            grid=cfg.griddim, block=cfg.blockdim, shmem_size=0, **{coop: False}
        )
        self.function = kernel._codelibrary.get_cufunc().kernel

    def set_float(self, index: int, value: float) -> None:
        """Argument ``index`` (a float64) takes ``value`` at the next launch."""
        self.kernelargs[self.positions[index]] = fast_arg(ctypes.c_double(value))

    def set_int(self, index: int, value: int) -> None:
        """Argument ``index`` (an int64) takes ``value`` at the next launch."""
        self.kernelargs[self.positions[index]] = fast_arg(ctypes.c_int64(value))

    def set_bool(self, index: int, value: bool) -> None:
        """Argument ``index`` (a boolean) takes ``value`` at the next launch."""
        self.kernelargs[self.positions[index]] = bool(value)

    def __call__(self) -> None:
        """Launch the kernel with the arguments as they stand.

        The driver copies them at the call: they may change before the launch runs.
        """
        from cuda.core import launch

        launch(self.stream, self.config, self.function, *self.kernelargs)


def prepare(dispatcher, griddim, blockdim, args) -> PreparedLaunch | None:
    """A :class:`PreparedLaunch`, or None where numba-cuda's internals are not as expected."""
    try:
        return PreparedLaunch(dispatcher, griddim, blockdim, args)
    except (ImportError, AttributeError, TypeError):
        return None
