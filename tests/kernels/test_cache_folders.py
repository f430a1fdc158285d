"""numba's cache of dem's kernels: a folder per source digest, so two versions never share one."""

import os
import subprocess
import sys
import time
from pathlib import Path

import numba

from dem import kernels


def test_the_kernels_cache_in_the_folder_of_their_sources_digest():
    """Importing dem.kernels pointed numba at __pycache__/dem-<digest> (or under
    NUMBA_CACHE_DIR): another source (a changed law, a changed config.py) is another folder."""
    folder = Path(numba.config.CACHE_DIR)
    assert folder.name == f"dem-{kernels.source_digest()[:16]}"
    assert kernels.cache_folder(folder.parent, "a" * 64) != folder


def test_a_process_of_another_version_caches_apart(tmp_path):
    """The crash this prevents: dem dropped the shared cache when its sources changed, and a
    process still running the old code wrote its kernels back under the new stamp. Two sources,
    two folders: a child process with NUMBA_CACHE_DIR set caches under it, in its digest's
    folder, and writes nothing into the other's."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    code = "import dem.kernels, numba; print(numba.config.CACHE_DIR)"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True).stdout.strip()  # fmt: skip
    assert Path(out) == kernels.cache_folder(tmp_path, kernels.source_digest())
    assert Path(out).is_dir()


def test_folders_of_other_sources_go_when_unused(tmp_path):
    keep = kernels.cache_folder(tmp_path, "1" * 64)
    old = kernels.cache_folder(tmp_path, "2" * 64)
    recent = kernels.cache_folder(tmp_path, "3" * 64)
    for folder in (keep, old, recent):
        (folder / "sub").mkdir(parents=True)
        (folder / "sub" / "k.nbi").write_bytes(b"x")
    week = time.time() - 8 * 86400
    os.utime(keep, (week, week))
    for path in (old, old / "sub" / "k.nbi"):
        os.utime(path, (week, week))
    (tmp_path / "unrelated").mkdir()
    removed = kernels.prune_cache_folders(tmp_path, keep, 7 * 86400)
    assert removed == [old]
    assert keep.is_dir() and recent.is_dir() and (tmp_path / "unrelated").is_dir()
