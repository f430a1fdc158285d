"""numba kernels of the DEM: contact laws, neighbour lists, pair and wall forces, integration.

Importing this package

- selects the threading layer ``dem.config.DEM_THREADING_LAYER`` for numba's parallel loops,
  unless NUMBA_THREADING_LAYER is set or the layer is not installed, and OpenMP's wait policy
  ``dem.config.DEM_OMP_WAIT_POLICY`` (if not None) unless OMP_WAIT_POLICY is set;
- drops numba's on-disk cache of these kernels when any kernel source (or dem/config.py) changed
  since it was written. numba checks only the file that defines a function, not the files of the
  functions it inlines, so a kernel cached before an edit of a law it calls would otherwise run the
  old law (or crash on a changed signature).
"""

import hashlib
import importlib.util
import os
from pathlib import Path

import numba

from dem.config import DEM_OMP_WAIT_POLICY, DEM_THREADING_LAYER

_LAYER_MODULES = {"omp": "numba.np.ufunc.omppool", "tbb": "numba.np.ufunc.tbbpool"}

if DEM_OMP_WAIT_POLICY is not None:
    os.environ.setdefault("OMP_WAIT_POLICY", DEM_OMP_WAIT_POLICY)

if "NUMBA_THREADING_LAYER" not in os.environ:
    _module = _LAYER_MODULES.get(DEM_THREADING_LAYER)
    if _module is None or importlib.util.find_spec(_module) is not None:
        numba.config.THREADING_LAYER = DEM_THREADING_LAYER


def _drop_stale_cache() -> None:
    here = Path(__file__).resolve().parent
    sources = sorted(here.glob("*.py")) + [here.parent / "config.py"]
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()
    cache = here / "__pycache__"
    stamp = cache / "dem-kernels-source.sha256"
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for path in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
            path.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:  # read-only install: numba then caches elsewhere or not at all
        pass


_drop_stale_cache()


def compiled(clumps: bool = False) -> bool:
    """True if numba's on-disk cache holds the step kernel (of clumps if ``clumps``).

    A first run on a machine compiles the kernels (about a minute) and caches them next to their
    sources (or under NUMBA_CACHE_DIR); ``dem run`` says so before it starts.
    """
    name = "integrate.advance_clumps-*.nbi" if clumps else "integrate.advance-*.nbi"
    here = Path(__file__).resolve().parent
    places = [here / "__pycache__"]
    if numba.config.CACHE_DIR:
        places += list(Path(numba.config.CACHE_DIR).rglob("__pycache__")) + [
            Path(numba.config.CACHE_DIR)
        ]
    return any(any(p.rglob(name)) for p in places if p.is_dir())
