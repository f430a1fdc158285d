"""What a run of a case will cost: memory, start-up, compile, fill, frames and steps.

The figures :func:`dem.run.plan.plan` adds up into a wall time, and the state's memory:

- memory: the state's arrays allocated as a run allocates them (zeros, so nothing is touched),
  with the pair list at its starting capacity (and, on several threads, the parallel pair
  loop's inbox);
- wall time: start-up, the compile where numba's cache lacks this kind of scene, the fill, the
  frames, and particle-steps (spheres x steps: the drive-off settle, the settling cycles and the
  measured cycles) over a rate: the rate the last run of this case measured on this machine
  (``CASE_DIR/output/summary.json``), else the rate of the shipped cases of this grain kind on
  the project's idle 2-core VM (``RATE_1THREAD``; checked against every shipped case by
  validation/performance/plan_check.py).
"""

from __future__ import annotations

import json
import math

import numpy as np

from dem import config
from dem.scene.resolved import resolve

#: Cost of a step apart from its particles, s (cases/single-sphere: 1.64e6 steps of one sphere in
#: 7.1 s, plan_check.py); it dominates only for a few grains.
STEP_OVERHEAD_S = 4.0e-6
#: Particle-steps per second on one thread where no run of the case has measured it: the
#: shipped cases on the project's idle 2-core VM (2026-11-26, plan_check.py: sphere-bed 9.3e6 on
#: 2 threads; screw-trough 1.4e7 sphere-steps/s) ...
RATE_1THREAD = {"sphere": 5.5e6, "clump": 8.2e6}
#: ... times this on a mesh trough (u-trough 4.3e6, v-trough 6.2e6 against the flat 1.4e7).
MESH_RATE_FACTOR = 0.4
#: Settling cycles an automatic settle ("auto") takes, as the shipped beds took them under the
#: default law (sphere-bed 10; screw-trough 6, u-trough 8, v-trough 6).
AUTO_SETTLE_CYCLES = {"sphere": 10, "clump": 7}
#: Start-up of ``dem run`` (imports, loading the cached kernels, the point mass, summary), s.
#: The figures below were measured on the project's 2-core VM (validation/performance,
#: plan_check.py and its README); another machine scales them all alike, roughly.
STARTUP_S = 3.0
#: Compiling the step kernels where numba's cache holds none yet for this kind of scene (a
#: fresh clone, or the first mesh trough), s: with an empty NUMBA_CACHE_DIR, the whole run's
#: extra time: 56 s (sphere-bed) and 61 s (screw-trough), of which the step kernels 46 and 53.
COMPILE_S = {"sphere": 56.0, "clump": 61.0}
#: Building the scene and placing its grains, s: this much ... (in a run, after the compile
#: check has loaded the kernels: 0.14 s for 1500 spheres, 0.07-0.28 s for 150-200 screws)
FILL_S = {"sphere": 0.05, "clump": 0.05}
#: ... and this much per grain (random sequential placement).
FILL_S_PER_GRAIN = {"sphere": 6e-5, "clump": 1e-3}
#: A frame (VTK files and the results.h5 rows): this much, s (a clump's frame has a grains
#: file too: sphere-bed 12 ms, screw-trough 16 ms, the feeder 22 ms a frame) ...
FRAME_S = {"sphere": 0.008, "clump": 0.012}
#: ... and this much per sphere (1500 spheres 12 ms, 15000 spheres 54 ms a frame).
FRAME_S_PER_SPHERE = 3.0e-6


def format_size(n: float) -> str:
    """A byte count in B, kB, MB or GB, 3 significant digits."""
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.3g} {unit}"
        n /= 1000.0
    return f"{n:.3g} GB"


def format_duration(s: float) -> str:
    """A duration in seconds as s, min, h, days or years, readable at a glance."""
    if s < 10:
        return f"{s:.2g} s"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 4 * 86400:
        return f"{s / 3600:.1f} h"
    if s < 2 * 365.25 * 86400:
        return f"{s / 86400:.0f} days"
    return f"{s / (365.25 * 86400):.3g} years"


#: Above twice this many grains the memory is extrapolated from this many and twice as many
#: (every array is proportional to the count): a plan of 1e9 grains allocates nothing large.
MEMORY_SAMPLE_GRAINS = 2000


def memory_bytes(case, spheres: int, grains: int, threads: int = 1) -> int:
    """Bytes of the state a run allocates: spheres, clumps and the pair list (at its start).

    ``case``: a :class:`dem.scene.resolved.Scene`, or a case resolved here. Several threads add the
    parallel pair loop's inbox (:meth:`dem.engine.state.PairList.ensure_inbox`). Measured by
    allocating
    the arrays (zeros: no page is touched) up to 2 :data:`MEMORY_SAMPLE_GRAINS` grains, and
    extrapolated linearly beyond.
    """
    scene = resolve(case)
    g1 = MEMORY_SAMPLE_GRAINS
    if grains <= 2 * g1:
        return _allocated_bytes(scene, spheres, grains, threads)
    per = spheres // grains
    m1 = _allocated_bytes(scene, g1 * per, g1, threads)
    m2 = _allocated_bytes(scene, 2 * g1 * per, 2 * g1, threads)
    return int(m1 + (m2 - m1) * (grains - g1) / g1)


def _allocated_bytes(scene, spheres: int, grains: int, threads: int) -> int:
    """The bytes of the state's arrays, allocated for ``grains`` grains of ``spheres``."""
    from dem.engine.state import Bodies, PairList, Spheres

    case = scene.case
    width = scene.law.history_width
    total = 0
    if not case.particles.clumps:
        s = Spheres.create(np.zeros((spheres, 3)), case.particles.radius, case.material.density)
        arrays: list[Spheres | Bodies | PairList] = [s]
    else:
        q = np.zeros((grains, 4))
        q[:, 0] = 1.0
        b, s = Bodies.create(scene.grain, np.zeros((grains, 3)), q)
        arrays = [s, b]
    s.set_history_width(width)
    if case.trough.mesh is not None:
        s.use_mesh()  # the mesh contact slots (the triangles themselves are not counted)
    pairs = PairList.for_spheres(spheres, width)
    if threads > 1:
        pairs.ensure_inbox()
    arrays.append(pairs)
    seen = set()
    for obj in arrays:
        for value in vars(obj).values():
            if isinstance(value, np.ndarray) and id(value) not in seen:
                seen.add(id(value))
                total += value.nbytes
    return total


def settle_steps(case, dt: float) -> int:
    """Steps of the drive-off settle: twice the fall time from the top of the fill box."""
    from dem.scene import fill

    fall = math.sqrt(2.0 * fill.box_height(case) / config.GRAVITY)
    return int(min(2.0 * fall, config.DEM_SETTLE_MAX_TIME) / dt)


def rate(case, threads: int, data: dict | None) -> tuple[float, str]:
    """Particle-steps per second and where the figure comes from."""
    last = case.directory / "output" / "summary.json"
    if last.is_file():
        try:
            s = json.loads(last.read_text())
            measured, used = float(s["particle_steps_per_s"]), int(s["threads"])
            if s.get("spheres") and measured > 0:
                return _scale(measured, used, threads), f"measured by the last run, {last}"
        except (ValueError, KeyError, TypeError):
            pass  # an older or partial summary: fall back to the study
    kind = case.particles.kind
    one = RATE_1THREAD[kind] * (MESH_RATE_FACTOR if case.trough.mesh is not None else 1.0)
    where = ", a mesh trough" if case.trough.mesh is not None else ""
    return _scale(one, 1, threads), f"the rate of the shipped {kind} cases{where} on a 2-core VM"


def _scale(rate_used: float, used: int, threads: int) -> float:
    """Threads scale at about 0.7 of ideal each beyond the first (a shared 2-core machine)."""

    def speed(n: int) -> float:
        return 1.0 + 0.7 * (max(n, 1) - 1)

    return rate_used * speed(threads) / speed(used)


def physical_memory() -> int | None:
    """Physical memory of this machine in bytes, or None where the OS does not say."""
    try:
        import os

        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None
