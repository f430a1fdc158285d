"""The pre-flight check of ``run.device``: whether the chosen engine can run this case here.

``device = "cpu"`` (the default) runs everywhere. ``device = "cuda"`` needs numba's CUDA target
to work on this machine: a GPU and its driver with numba-cuda (``pip install -e '.[cuda]'``), or
numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, set before numba is imported; slow, for
tests). The GPU engine steps spheres and rigid clumps between flat walls or in a trough mesh
(U and V pans, CAD troughs) in a periodic section, under the drive and every contact law; it
does not have the finite feeder yet, and a case that asks for one with ``device = "cuda"`` is
refused here, naming the key that asks for it. :func:`check_device` runs at the door of
``dem run``, ``dem plan`` and ``dem sweep``, before anything is filled or written; its errors
are :class:`dem.errors.InputError`, which the command line ends with exit status 2.
"""

from __future__ import annotations

from dem.errors import InputError

#: What a refusal tells the user to do instead.
USE_CPU = 'set run.device = "cpu" (--device cpu)'
#: How the GPU extra is installed (pyproject.toml's ``cuda`` extra).
INSTALL = "pip install -e '.[cuda]'"


def check_device(device: str, scene) -> None:
    """Refuse a run on ``device`` that this machine or the engine cannot do, before any work.

    Args:
        device: ``"cpu"`` or ``"cuda"`` (``run.device`` after ``--device``).
        scene: The case to run: a :class:`dem.scene.resolved.Scene` or a
            :class:`dem.scene.case.Case`.

    Raises:
        InputError: for ``"cuda"``: naming ``feeder`` (a finite trough) in the case file,
            which the GPU engine does not have yet; or naming
            ``run.device`` when numba's CUDA cannot run here (numba-cuda missing, or no GPU or
            driver: numba's reason is quoted).
            For a device other than ``"cpu"`` and ``"cuda"``, naming ``run.device``.

    """
    if device == "cpu":
        return
    if device != "cuda":
        raise InputError("run.device", device, "one of 'cpu', 'cuda'")
    case = getattr(scene, "case", scene)
    _check_features(case)
    _check_cuda()


def _check_features(case) -> None:
    """Refuse the features the GPU engine lacks, each by the key that asks for it."""
    source = str(case.source)
    gpu = 'under run.device = "cuda"'
    if case.feeder is not None:
        raise InputError(
            "feeder", {"feed_rate": case.feeder.feed_rate, "feed_length": case.feeder.feed_length},
            f"no [feeder] table {gpu}: the GPU engine runs periodic sections only so far (no "
            f"finite feeder); remove the table, or {USE_CPU}", source,
        )  # fmt: skip


def _check_cuda() -> None:
    """Refuse when numba's CUDA target cannot run here, saying what is missing."""
    try:
        from numba import cuda
    except ImportError as exc:  # a numba without its bundled CUDA target, and no numba-cuda
        raise InputError(
            "run.device", "cuda", f"a machine where numba's CUDA target imports: numba.cuda is "
            f"missing ({exc}); install numba-cuda ({INSTALL}), or {USE_CPU}",
        ) from None  # fmt: skip
    if cuda.is_available():  # a GPU with its driver, or the simulator (NUMBA_ENABLE_CUDASIM=1)
        return
    reason = _numba_reason(cuda)
    if not _numba_cuda_installed():
        raise InputError(
            "run.device", "cuda", f"a machine where numba's CUDA target finds a GPU: numba-cuda "
            f"is not installed ({INSTALL} installs it), and numba's own CUDA target finds no "
            f"GPU ({reason}); install it, or {USE_CPU}",
        )  # fmt: skip
    raise InputError(
        "run.device", "cuda", f"a machine where numba's CUDA target finds a GPU: no CUDA GPU or "
        f"driver found ({reason}); {USE_CPU}",
    )  # fmt: skip


def _numba_reason(cuda) -> str:
    """Why numba's CUDA target is unavailable, in numba's words where it gives them (one line)."""
    error = getattr(cuda, "cuda_error", lambda: None)()
    if error:
        return " ".join(str(error).split()).rstrip(":. ")
    try:
        from numba.cuda.cudadrv import nvvm

        if not nvvm.is_available():
            return "the driver works but libNVVM (the CUDA compiler library) is not found"
    except Exception:  # an older or newer numba without this module: no reason to give
        pass
    return "numba gives no reason (no CUDA device visible?)"


def _numba_cuda_installed() -> bool:
    """Whether the numba-cuda distribution (the maintained CUDA target) is installed."""
    from importlib import metadata

    try:
        metadata.version("numba-cuda")
    except metadata.PackageNotFoundError:
        return False
    return True
