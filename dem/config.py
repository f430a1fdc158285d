"""One place for numerical settings: numba flags, tolerances and safety factors.

Kernels import their decorator options from here, so the choice of ``fastmath`` or caching is
made once. ``fastmath`` stays off: the point-mass events are roots found to near machine
precision, and reassociation would make results depend on the compiler's mood.
"""

import os

#: Options for every ``numba.njit`` in the package. ``cache=True`` writes compiled code next to
#: the sources (``__pycache__``) so a second run does not recompile.
NUMBA_OPTIONS = {"cache": True, "fastmath": False, "nogil": True}

#: Options for kernels that run a ``prange`` loop.
NUMBA_PARALLEL_OPTIONS = {**NUMBA_OPTIONS, "parallel": True}

#: Standard gravity, m/s^2 (DESIGN.md section 2).
GRAVITY = 9.81

# --- point-mass model -------------------------------------------------------------------------
#: Relative tolerance on the Poincare section state (u, w, z) for calling an orbit periodic.
PM_PERIODIC_TOL = 1e-9
#: Longest period of an orbit that is searched for, in drive cycles.
PM_MAX_ORBIT_PERIOD = 64
#: Cycles integrated before an orbit that has not closed is declared non-periodic.
PM_MAX_CYCLES = 3000
#: Cycles averaged for the mean velocity of a non-periodic motion.
PM_AVERAGE_CYCLES = 1000
#: Starting phases used to report the spread of a non-periodic motion.
PM_SPREAD_STARTS = 8
#: A bounce slower than this (normal velocity in units of A omega sin phi) ends the bouncing:
#: the remaining bounces of the geometric series are shorter than about 1e-8 of a cycle.
PM_BOUNCE_SETTLE = 1e-9
#: Hard limit on phase changes within one cycle; more means a bug or a pathological input.
PM_MAX_EVENTS_PER_CYCLE = 100_000


def default_threads() -> int:
    """Threads for numba parallel loops: NUMBA_NUM_THREADS if set, else all cores."""
    value = os.environ.get("NUMBA_NUM_THREADS")
    return int(value) if value else (os.cpu_count() or 1)
