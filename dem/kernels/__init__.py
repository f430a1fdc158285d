"""numba kernels of the DEM: contact laws, neighbour lists, pair and wall forces, integration.

Importing this package

- selects the threading layer ``dem.config.DEM_THREADING_LAYER`` for numba's parallel loops,
  unless NUMBA_THREADING_LAYER is set or the layer is not installed, and OpenMP's wait policy
  ``dem.config.DEM_OMP_WAIT_POLICY`` (if not None) unless OMP_WAIT_POLICY is set;
- points numba's on-disk cache at a folder of its own for these sources: ``__pycache__`` (or
  NUMBA_CACHE_DIR) ``/dem-<digest>``, the digest of every kernel source and dem/config.py. numba
  checks only the file that defines a function, not the files of the functions it inlines, so a
  kernel cached before an edit of a law it calls would otherwise run the old law (or crash on a
  changed signature). A folder per digest keeps processes of two versions apart: dem used to drop
  the shared cache when the sources changed, and a process still running the old code (a sweep's
  or an atlas's worker) could then write its kernels back under the new stamp, which the next
  process loaded and crashed on (a segfault in the neighbour build, seen once here). Folders of
  other digests unused for ``DEM_CACHE_KEEP_S`` are removed.
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


def source_digest() -> str:
    """The sha256 of every kernel source and dem/config.py, in a fixed order.

    cuda/ aside: the GPU kernels are compiled at run time, never cached.
    """
    here = Path(__file__).resolve().parent
    sources = sorted(p for p in here.rglob("*.py") if "cuda" not in p.relative_to(here).parts)
    sources.append(here.parent / "config.py")
    return hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()


def cache_folder(base: Path, digest: str) -> Path:
    """The cache folder of the sources with ``digest`` under ``base``."""
    return Path(base) / f"dem-{digest[:16]}"


def prune_cache_folders(base: Path, keep: Path, older_than_s: float) -> list[Path]:
    """Remove the ``dem-*`` folders under ``base`` but ``keep`` unused for ``older_than_s``.

    "Unused": the newest modification time of the folder and its index files. Returns those
    removed. A process of that version still running recompiles what it no longer finds.
    """
    import shutil
    import time

    removed = []
    now = time.time()
    for folder in Path(base).glob("dem-*"):
        if folder == keep or not folder.is_dir():
            continue
        try:
            newest = max([folder.stat().st_mtime] + [p.stat().st_mtime
                                                     for p in folder.rglob("*.nbi")])  # fmt: skip
        except OSError:
            continue
        if now - newest > older_than_s:
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


def _use_own_cache() -> None:
    from dem.config import DEM_CACHE_KEEP_S

    base = Path(numba.config.CACHE_DIR or Path(__file__).resolve().parent / "__pycache__")
    folder = cache_folder(base, source_digest())
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".writable"
        probe.touch()
    except OSError:  # a read-only install: numba then caches where it can, or not at all
        return
    numba.config.CACHE_DIR = str(folder)
    try:
        prune_cache_folders(base, folder, DEM_CACHE_KEEP_S)
    except OSError:
        pass


_use_own_cache()


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
