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
    # the GPU kernels (cuda/) are compiled at run time, never cached: they stamp nothing here
    sources = sorted(p for p in here.rglob("*.py") if "cuda" not in p.relative_to(here).parts)
    sources.append(here.parent / "config.py")
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
        for path in list(here.rglob("*.nbi")) + list(here.rglob("*.nbc")):
            path.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:  # read-only install: numba then caches elsewhere or not at all
        pass


_drop_stale_cache()


def compiled(clumps: bool = False, mesh: bool = False) -> bool:
    """True if numba's on-disk cache holds the step kernel for this kind of scene.

    ``clumps``: the clump kernel (else the spheres'); ``mesh``: its variant for a mesh trough
    (a mesh trough passes the mesh arrays where a flat one passes None, so numba compiles each
    variant once, about a minute). A first run on a machine compiles the kernels and caches them
    next to their sources (or under NUMBA_CACHE_DIR); ``dem run`` says so before it starts, and
    ``dem plan`` counts the time.
    """
    name = "integrate.advance_clumps-*.nbi" if clumps else "integrate.advance-*.nbi"
    here = Path(__file__).resolve().parent
    places = [here / "__pycache__"]
    if numba.config.CACHE_DIR:  # numba then caches there only
        places = [Path(numba.config.CACHE_DIR)]
    indexes = [i for p in places if p.is_dir() for i in p.rglob(name)]
    return any(_holds_variant(i, mesh) for i in indexes)


def _holds_variant(index: Path, mesh: bool) -> bool:
    """Whether a numba cache index lists the step kernel with (or without) the mesh arrays.

    The index is numba's pickle (its version, then the source stamp and the overloads keyed by
    signature); the step kernel's last argument is ``MeshArrays`` or ``none``. An index this
    cannot read counts as holding every variant (the check only decides what is said and
    estimated, never what runs).
    """
    import pickle

    try:
        with open(index, "rb") as fh:
            pickle.load(fh)  # numba's version
            _stamp, overloads = pickle.loads(fh.read())
        lasts = [str(key[0][-1]) for key in overloads]
    except Exception:  # another numba's format: assume compiled
        return True
    return any(last.startswith("MeshArrays") == mesh for last in lasts)
