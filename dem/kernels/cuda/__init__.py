"""GPU kernels on numba.cuda: the CPU engine's physics, one thread per sphere.

The contact law is not copied: the kernels call :func:`dem.kernels.contact.contact_core` and the
scalar helpers beside it (lever arms, wall gaps, the periodic image) as device functions,
compiled from the same source as the CPU engine's. The parameter rows reach them as tuples of
floats.

numba.cuda is imported only by the kernel modules (:mod:`dem.kernels.cuda.forces`), which
nothing in dem imports: importing dem, or this package, needs no CUDA. Without a GPU, numba's
CUDA simulator runs the kernels (``NUMBA_ENABLE_CUDASIM=1``, set before numba.cuda is first
imported).
"""

import numpy as _np

# numba-cuda 0.30.4 (pinned: its successors drop the simulator the tests run in) types arrays
# through ``np.row_stack``, which numpy 2.5 removed: the kernels then fail to compile on a GPU
# (seen on an H200 with numpy 2.5.2). ``row_stack`` was an alias of ``vstack``; put it back.
if not hasattr(_np, "row_stack"):
    _np.row_stack = _np.vstack
