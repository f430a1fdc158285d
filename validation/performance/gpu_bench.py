"""The GPU engine's speed against the CPU engine's, and the bed's velocity on both (issue 29).

Three jobs, meant to run together on a machine with a GPU and many cores (``run_device.sh``
starts them), each writing one JSON:

``--gpu``   sphere-steps/s of the GPU engine at several sizes (``--sizes``), the sphere-bed
            case's material, law, step and drive, on a wider and longer periodic section of the
            same depth: a bed of N spheres on a loose cubic lattice (spacing 2.05 r, jittered),
            driven from the start, so contacts, tangential springs, walls and the drive are all
            in the timing. Each size: a warm-up call, then a timed call of many steps (the copy of
            the state back to the host at its end included). With the registers and local memory
            (spills) of every kernel, and a roofline estimate (bytes a sphere-step must move
            against the memory bandwidth).
``--cpu``   the CPU engine on the same lattices at 1, 4 and 16 threads (``--threads``).
``--bed``   the sphere-bed case itself (1500 spheres): filled and settled on the CPU, then the
            same state measured ``--cycles`` cycles on the CPU and on the GPU: the conveying
            velocity of each with its standard error.
``--clumps`` clump-steps/s of the screw-trough case's screws (8-sphere rigid clumps) on a
            lattice of ``--clump-sizes`` screws, ``--device`` cuda or cpu (at each of
            ``--threads``), the case's law, step and drive.

Usage: python validation/performance/gpu_bench.py --gpu --out gpu.json [--sizes 1e4 1e5]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pickle
import platform
import sys
import time
import traceback
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

CASE = ROOT / "cases" / "sphere-bed"
SCREWS = ROOT / "cases" / "screw-trough"
#: The lattice's depth in layers (the sphere-bed case: 1500 spheres of r = 2 mm on 0.10 x 0.04 m
#: are about 7 layers) and its width in spheres.
LAYERS = 7
ACROSS = 48


def load_loadavg() -> list[float]:
    return [round(v, 2) for v in os.getloadavg()]


def lattice_sim(n: int, device: str, seed: int = 1, mesh: bool = False):
    """The sphere-bed case's spheres on a jittered cubic lattice of about n spheres.

    With ``mesh`` the floor and side walls are triangles (:func:`box_mesh`), the lattice the same.
    """
    from dem.engine.setup import from_grains
    from dem.scene.case import load_case

    r = 0.002
    a = 2.0 * r * (1.0 - 1.0e-3)  # touching, 4 um overlaps: the bed's contacts from the start
    rows = max(1, round(n / (ACROSS * LAYERS)))
    width = ACROSS * a
    length = rows * a
    sets = {"trough.length": length, "trough.width": width}
    if mesh:
        sets["trough.mesh"] = str(box_mesh(length, width, (LAYERS + 2) * a))
    case = load_case(CASE, sets)
    i, j, k = np.meshgrid(np.arange(rows), np.arange(ACROSS), np.arange(LAYERS), indexing="ij")
    rng = np.random.default_rng(seed)
    x = np.column_stack(
        [(i.ravel() + 0.5) * a, (j.ravel() + 0.5) * a - width / 2, 0.5 * a + k.ravel() * a]
    )
    x[:, :2] += rng.uniform(-1e-4 * r, 1e-4 * r, (x.shape[0], 2))
    sim = from_grains(case, x, timestep=4.0e-6)
    sim.device = device
    sim.start_drive()
    return sim


def box_mesh(length: float, width: float, height: float) -> Path:
    """The flat trough's floor and side walls as triangles, 1 cm long along x, in an STL file."""
    import tempfile

    import meshio

    from dem.scene.mesh import extrude

    h = 0.5 * width
    profile = [[-h, height], [-h, 0.0], [h, 0.0], [h, height]]
    path = Path(tempfile.mkdtemp(prefix="dem_bench_")) / "box.stl"
    meshio.write(path, extrude(profile, length, max(1, round(length / 0.01))), binary=True)
    return path


def screw_lattice_sim(n: int, device: str, seed: int = 1):
    """The screw-trough case's screws on a jittered lattice of about n, lying along the axes."""
    from dem.engine.setup import from_grains
    from dem.scene.case import load_case

    case = load_case(SCREWS)
    one = from_grains(case, [[0.05, 0.0, 0.01]])
    x = one.spheres.x - one.bodies.x[0]
    r = one.spheres.radius[:, None]
    lo, hi = (x - r).min(axis=0), (x + r).max(axis=0)
    a = (hi - lo) * (1.0 - 1.0e-3)  # boxes touching: contacts from the start
    across = int(case.trough.width * 2 / a[1])
    rows = max(2, round(n / (across * LAYERS)))  # a period of 2 screws at least
    length, width = rows * a[0], across * a[1]
    case = load_case(SCREWS, {"trough.length": length, "trough.width": width})
    i, j, k = np.meshgrid(np.arange(rows), np.arange(across), np.arange(LAYERS), indexing="ij")
    rng = np.random.default_rng(seed)
    centre = np.column_stack(
        [(i.ravel() + 0.5) * a[0], (j.ravel() + 0.5) * a[1] - width / 2, k.ravel() * a[2]]
    ) - lo - 0.5 * a + np.array([0.0, 0.0, 0.5 * a[2]])  # fmt: skip
    centre[:, :2] += rng.uniform(-0.002, 0.002, (centre.shape[0], 2)) * a[:2]
    sim = from_grains(case, centre, timestep=case.run.timestep)
    sim.device = device
    sim.start_drive()
    return sim


STEPS = {"plain": False, "compact": True, "auto": None}  # GpuEngine.compact


def _scheme(sim, args) -> None:
    """The step scheme the command line asks for (--step) on ``sim``'s GPU engine."""
    engine = sim.engine
    engine.compact = STEPS[args.step]


def _trial_done(advance, engine, steps: int = 64, calls: int = 40) -> None:
    """Advance until the engine's trial of the plain and compact steps has decided (if any).

    So that a timed window runs the chosen step alone; ``advance(steps)`` steps the scene.
    """
    for _ in range(calls):
        if engine._trial is None or engine.tuned is not None:
            return
        advance(steps)


def clumps_job(args) -> dict:
    """Clump-steps/s of screw lattices on ``args.device`` (CPU: at each thread count)."""
    import numba

    out = {"device": args.device, "sizes": [], "loadavg_start": load_loadavg()}
    for n in args.clump_sizes:
        n = int(float(n))
        threads = args.threads if args.device == "cpu" else [None]
        try:
            sim = screw_lattice_sim(n, args.device)
            if args.device == "cuda":
                _scheme(sim, args)
            if args.device == "cpu":
                numba.set_num_threads(max(threads))
            sim.advance(200)  # compile, upload, the lattice starts to shake
            if args.device == "cuda":
                _trial_done(sim.advance, sim.engine)
            for t in threads:
                if t is not None:
                    numba.set_num_threads(t)
                sim.advance(5)
                steps = int(max(50, min(4000, args.work / 8 / sim.bodies.n * (t or 50))))
                t0 = time.perf_counter()
                sim.advance(steps)
                wall = time.perf_counter() - t0
                row = {"screws": sim.bodies.n, "spheres": sim.spheres.n, "threads": t,
                       "steps": steps, "wall_s": round(wall, 3),
                       "clump_steps_per_s": sim.bodies.n * steps / wall,
                       "contacts": int(sim.contact_counts().sum()),
                       "finite": bool(np.all(np.isfinite(sim.bodies.x))),
                       "loadavg": load_loadavg()}  # fmt: skip
                if args.device == "cuda":
                    eng = sim.engine
                    row.update(builds=eng.builds, skipped_launches=eng.skipped, chunk=eng.chunk,
                               step=eng.step_scheme())  # fmt: skip
                print(f"{args.device} {sim.bodies.n} screws x{t}: "
                      f"{row['clump_steps_per_s']:.3g} clump-steps/s", flush=True)  # fmt: skip
                out["sizes"].append(row)
            del sim
        except Exception:  # noqa: BLE001  (the next size may still run)
            out["sizes"].append({"screws_asked": n, "error": traceback.format_exc()})
            print(out["sizes"][-1]["error"], flush=True)
        Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def _first(value) -> int:
    """One figure of numba-cuda's per-signature dict (or the figure itself)."""
    return int(next(iter(value.values())) if isinstance(value, dict) else value)


def kernel_resources() -> dict:
    """Registers and local memory (spills) per thread of every compiled GPU kernel."""
    from dem.kernels.cuda import bodies, forces, neighbours, step

    out = {}
    for mod in (forces, neighbours, step, bodies):
        for name in dir(mod):
            k = getattr(mod, name)
            if not name.endswith("_kernel") or not hasattr(k, "overloads"):
                continue
            if not k.overloads:
                continue
            key = f"{mod.__name__.rsplit('.', 1)[-1]}.{name}"
            try:
                out[key] = {
                    "registers": _first(k.get_regs_per_thread()),
                    "local_bytes": _first(k.get_local_mem_per_thread()),
                }
            except Exception as exc:  # noqa: BLE001  (a report, not a check)
                out[key] = {"error": repr(exc)}
    return out


def prepared_vs_ordinary(n: int = 10000, steps: int = 300) -> dict:
    """The same lattice stepped with prepared launches and with numba-cuda's ordinary ones."""
    sims = [lattice_sim(n, "cuda") for _ in range(2)]
    for sim in sims:
        sim.advance(20)
    sims[1].engine.fast = False
    walls = []
    for sim in sims:
        t0 = time.perf_counter()
        sim.advance(steps)
        walls.append(time.perf_counter() - t0)
    a, b = (sim.spheres for sim in sims)
    same = all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("x", "v", "omega", "force"))
    out = {"spheres": sims[0].spheres.n, "steps": steps, "used": sims[0].engine.fast,
           "same_bits": bool(same), "prepared_s_per_step": walls[0] / steps,
           "ordinary_s_per_step": walls[1] / steps}  # fmt: skip
    print(f"prepared launch: {out}", flush=True)
    return out


def gpu_job(args) -> dict:
    import numba
    from numba import cuda

    out = {"device": "numba's CUDA simulator"}
    total = 0
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        dev = cuda.get_current_device()
        total = cuda.current_context().get_memory_info()[1]
        out = {
            "device": dev.name.decode() if isinstance(dev.name, bytes) else str(dev.name),
            "compute_capability": list(dev.compute_capability),
            "memory_GiB": round(total / 2**30, 1),
        }
    out.update({
        "mesh": args.mesh,
        "numba": numba.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
        "loadavg_start": load_loadavg(),
        "sizes": [],
    })  # fmt: skip
    try:
        import numba_cuda

        out["numba_cuda"] = numba_cuda.__version__
    except ImportError:
        out["numba_cuda"] = "bundled"
    try:
        out["prepared_launch"] = prepared_vs_ordinary()
    except Exception:  # noqa: BLE001
        out["prepared_launch"] = {"error": traceback.format_exc()}
        print(out["prepared_launch"]["error"], flush=True)
    for n in args.sizes:
        n = int(float(n))
        row = {"spheres_asked": n}
        try:
            t0 = time.perf_counter()
            sim = lattice_sim(n, "cuda", mesh=args.mesh)
            _scheme(sim, args)
            row["spheres"] = sim.spheres.n
            row["setup_s"] = round(time.perf_counter() - t0, 2)
            t0 = time.perf_counter()
            sim.advance(20)  # compile (first size), upload, first build
            row["first_call_s"] = round(time.perf_counter() - t0, 2)
            sim.advance(200)  # the bed starts to sit
            steps = int(max(200, min(4000, args.work / sim.spheres.n)))
            eng = sim.engine
            _trial_done(sim.advance, eng)
            builds = eng.builds
            cuda.synchronize()
            t0 = time.perf_counter()
            eng.steps(sim, steps, sim.step_index - sim.drive_start_step, sim.drive_array())
            cuda.synchronize()
            wall = time.perf_counter() - t0
            sim.step_index += steps
            t0 = time.perf_counter()
            eng.download(sim)
            row["download_s"] = round(time.perf_counter() - t0, 3)
            t0 = time.perf_counter()
            eng.steps(sim, 1, sim.step_index - sim.drive_start_step, sim.drive_array())
            cuda.synchronize()
            row["one_step_call_s"] = round(time.perf_counter() - t0, 5)
            sim.step_index += 1
            counts = eng.count[0].copy_to_host()
            k = sim.pairs.n_pairs
            x = sim.spheres.x
            pi, pj = sim.pairs.pair_i[:k], sim.pairs.pair_j[:k]
            d = x[pi] - x[pj]
            d[:, 0] -= sim.trough.length * np.round(d[:, 0] / sim.trough.length)
            touching = int(np.sum(np.linalg.norm(d, axis=1) < 2 * 0.002))
            width = eng.width
            pairs_per = float(np.mean(counts))
            # bytes a sphere-step must move (each array read or written once, partners' state
            # from cache): own state and constants, the new state, force and torque, px, the
            # wall rows, the slot and reverse indices, the history of its own pairs (read and
            # written)
            bytes_per = (
                72 + 32 + 72 + 48 + 16 + 2 * 4 * width * 8 + 4 * (eng.slots + eng.rev.shape[0]
                // eng.n) + 2 * pairs_per * width * 8
            )  # fmt: skip
            row.update(
                steps=steps, wall_s=round(wall, 3),
                sphere_steps_per_s=sim.spheres.n * steps / wall,
                builds=eng.builds - builds, pairs_per_sphere=pairs_per,
                contacts_per_sphere=2 * touching / sim.spheres.n, slots=eng.slots,
                history_width=width, bytes_per_sphere_step=bytes_per, step=eng.step_scheme(),
                max_abs_v=float(np.max(np.abs(sim.spheres.v))),
                finite=bool(np.all(np.isfinite(sim.spheres.x))),
                gpu_memory_used_GiB=round(
                    (total - cuda.current_context().get_memory_info()[0]) / 2**30, 2
                ) if total else None,
                loadavg=load_loadavg(),
            )  # fmt: skip
            rate = row["sphere_steps_per_s"]
            print(f"GPU {sim.spheres.n}: {rate:.3g} sphere-steps/s", flush=True)
            del sim, eng
        except Exception:  # noqa: BLE001  (the next size may still run)
            row["error"] = traceback.format_exc()
            print(row["error"], flush=True)
        out["sizes"].append(row)
        Path(args.out).write_text(json.dumps(out, indent=1))
    for regs in args.max_registers:
        # the step kernel compiled with fewer registers (more threads resident), at one size
        import types as pytypes

        from dem.kernels.cuda import step

        row = {"spheres_asked": int(float(args.sizes[-2])), "max_registers": regs}
        try:
            sim = lattice_sim(row["spheres_asked"], "cuda")
            sim.advance(20)
            eng = sim.engine
            alt = cuda.jit(max_registers=regs)(step.step_kernel.py_func)
            eng.step = pytypes.SimpleNamespace(
                step_kernel=alt, kick_drift_kernel=step.kick_drift_kernel
            )
            eng._prepared.clear()
            t0 = time.perf_counter()
            sim.advance(200)
            row["compile_and_200_steps_s"] = round(time.perf_counter() - t0, 2)
            steps = int(max(200, min(4000, args.work / sim.spheres.n)))
            cuda.synchronize()
            t0 = time.perf_counter()
            eng.steps(sim, steps, sim.step_index - sim.drive_start_step, sim.drive_array())
            cuda.synchronize()
            wall = time.perf_counter() - t0
            row.update(steps=steps, wall_s=round(wall, 3),
                       sphere_steps_per_s=sim.spheres.n * steps / wall,
                       registers=_first(alt.get_regs_per_thread()),
                       local_bytes=_first(alt.get_local_mem_per_thread()))  # fmt: skip
            print(f"GPU max_registers={regs}: {row['sphere_steps_per_s']:.3g}", flush=True)
            del sim, eng
        except Exception:  # noqa: BLE001
            row["error"] = traceback.format_exc()
            print(row["error"], flush=True)
        out.setdefault("register_variants", []).append(row)
        Path(args.out).write_text(json.dumps(out, indent=1))
    try:
        out["kernels"] = kernel_resources()
    except Exception:  # noqa: BLE001
        out["kernels_error"] = traceback.format_exc()
    Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def cpu_job(args) -> dict:
    import numba

    out = {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
           "numba": numba.__version__, "mesh": args.mesh, "sizes": []}  # fmt: skip
    for n in args.sizes:
        n = int(float(n))
        sim = lattice_sim(n, "cpu", mesh=args.mesh)
        numba.set_num_threads(max(args.threads))
        sim.advance(220)
        for threads in args.threads:
            numba.set_num_threads(threads)
            sim.advance(5)
            steps = int(max(10, min(2000, args.work / 10 / sim.spheres.n * threads)))
            t0 = time.perf_counter()
            sim.advance(steps)
            wall = time.perf_counter() - t0
            row = {"spheres": sim.spheres.n, "threads": threads, "steps": steps,
                   "wall_s": round(wall, 3), "sphere_steps_per_s": sim.spheres.n * steps / wall,
                   "loadavg": load_loadavg()}  # fmt: skip
            print(f"CPU {sim.spheres.n} x{threads}: {row['sphere_steps_per_s']:.3g}", flush=True)
            out["sizes"].append(row)
            Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def bed_state(path: Path, threads: int) -> None:
    """The sphere-bed case filled, settled and driven for 3 cycles on the CPU, pickled."""
    import numba

    from dem.engine.setup import from_case
    from dem.engine.simulation import measure_cycles
    from dem.scene.case import load_case

    numba.set_num_threads(threads)
    sim = from_case(load_case(CASE))
    sim.settle()
    measure_cycles(sim, 3)
    path.write_bytes(pickle.dumps(sim))


def bed_job(args) -> dict:
    import numba

    from dem.engine.simulation import measure_cycles

    numba.set_num_threads(max(args.threads))
    sim = pickle.loads(Path(args.state).read_bytes())
    sim.device = args.device
    t0 = time.perf_counter()
    v = measure_cycles(sim, args.cycles)
    wall = time.perf_counter() - t0
    se = float(np.std(v, ddof=1) / math.sqrt(len(v)))
    out = {"device": args.device, "cycles": args.cycles, "velocity_m_s": float(np.mean(v)),
           "standard_error_m_s": se, "per_cycle": v.tolist(), "wall_s": round(wall, 2),
           "spheres": sim.spheres.n, "dt": sim.dt, "loadavg": load_loadavg()}  # fmt: skip
    print(f"bed on {args.device}: {out['velocity_m_s']:.5f} +- {se:.5f} m/s", flush=True)
    Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def _replicas(blob: bytes, reps: int) -> list:
    """``reps`` copies of the pickled bed, each but the first with velocities nudged by 1e-9 m/s."""
    rng = np.random.default_rng(reps)
    sims = []
    for r in range(reps):
        sim = pickle.loads(blob)
        if r:  # a replica: the same bed, velocities nudged (chaos does the rest)
            sim.spheres.v += rng.normal(0.0, 1e-9, sim.spheres.v.shape)
        sims.append(sim)
    return sims


def _time_batch(
    blob: bytes, reps: int, cycles: int, threads=None, max_registers=None,
    compact: bool | None = False,
) -> dict:  # fmt: skip
    """One batch of ``reps`` replicas timed over ``cycles`` drive cycles (a row of the JSON).

    ``threads``: threads per block of the step launches; ``max_registers``: the step kernels
    compiled with at most this many registers (None: the defaults; the plain step and the
    compact one); ``compact``: the step that gathers the touching candidates first
    (:attr:`dem.engine.gpu.schemes.StepSchemes.compact`; None: the engine's trial against the
    plain step, before the timed cycles).
    """
    import types as pytypes

    from numba import cuda

    from dem.engine.gpu.replicas import GpuReplicas
    from dem.kernels.cuda import compact as compact_module
    from dem.kernels.cuda import step

    sims = _replicas(blob, reps)
    t0 = time.perf_counter()
    batch = GpuReplicas(sims)
    setup = time.perf_counter() - t0
    eng = batch.engine
    if threads is not None:
        eng.threads = threads
    eng.compact = compact
    if max_registers is not None:
        capped = cuda.jit(max_registers=max_registers)
        eng.step = pytypes.SimpleNamespace(
            step_kernel=capped(step.step_kernel.py_func), mesh_step_kernel=step.mesh_step_kernel,
            kick_drift_kernel=step.kick_drift_kernel,
        )  # fmt: skip
        # the engine imports the compact step where it runs it: the capped one is bound there
        compact_module.compact_step_kernel = capped(compact_module.compact_step_kernel.py_func)
    kernel, _, block, _, _ = eng._step_kernel()
    eng._prepared.clear()
    batch.advance(10)  # compile, upload, first build
    _trial_done(batch.advance, eng)
    host0, wait0 = eng.host_s, eng.wait_s
    t0 = time.perf_counter()
    v = batch.measure(cycles)
    wall = time.perf_counter() - t0
    means = v.mean(axis=0)
    n_steps = int(round(cycles * batch.sim.trough.period / batch.sim.dt))
    row = {"replicas": reps, "spheres": int(batch.sim.spheres.n), "cycles": cycles,
           "threads_per_block": block or eng.threads, "max_registers": max_registers,
           "compact": compact, "step": eng.step_scheme(),
           "wall_s": round(wall, 2), "setup_s": round(setup, 2),
           "host_queueing_s": round(eng.host_s - host0, 3),
           "host_waiting_s": round(eng.wait_s - wait0, 3),
           "us_per_step": 1e6 * wall / n_steps,
           "replica_means_m_s": means.tolist(), "ensemble_mean_m_s": float(means.mean()),
           "ensemble_standard_error_m_s": float(means.std(ddof=1) / np.sqrt(reps))
           if reps > 1 else None, "builds": eng.builds, "chunk": eng.chunk,
           "loadavg": load_loadavg()}  # fmt: skip
    try:
        row["registers"] = _first(kernel.get_regs_per_thread())
        row["local_bytes"] = _first(kernel.get_local_mem_per_thread())
    except Exception:  # noqa: BLE001  (a report, not a result)
        pass
    row["sphere_steps_per_s"] = batch.sim.spheres.n * n_steps / wall
    scheme = {True: "compact", None: "auto"}.get(compact, "plain")
    if compact is None:
        scheme += f" ({eng.step_scheme()})"
    print(f"batch {reps} x {cycles} cycles, {scheme}, {block or eng.threads} threads/block, "
          f"registers {row.get('registers')}: {wall:.2f} s ({row['us_per_step']:.0f} us a step; "
          f"host queueing {row['host_queueing_s']:.2f} s, waiting {row['host_waiting_s']:.2f} s), "
          f"v = {row['ensemble_mean_m_s']:.6f}", flush=True)  # fmt: skip
    return row


def batch_job(args) -> dict:
    """R replicas of the pickled bed in one GPU job (dem.engine.gpu.replicas), timed."""
    blob = Path(args.state).read_bytes()
    out = {"runs": [], "loadavg_start": load_loadavg()}
    for reps, cycles in zip(args.batch, args.batch_cycles, strict=True):
        out["runs"].append(_time_batch(blob, reps, cycles))
        Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def variants_job(args) -> dict:
    """The batch's launch variants (threads per block, register caps), each a short run.

    Then one replica alone (the host's cost of a step, the kernel being tiny) and the fastest
    variant over the full --batch-cycles.
    """
    blob = Path(args.state).read_bytes()
    reps, cycles = args.batch[0], args.variant_cycles
    out = {"variants": [], "loadavg_start": load_loadavg()}
    for spec in args.batch_variants:
        compact = {"c": True, "a": None}.get(spec[-1], False)
        threads, _, regs = spec.rstrip("ca").partition(":")
        try:
            row = _time_batch(
                blob, reps, cycles, int(threads), int(regs) if regs else None, compact
            )  # fmt: skip
        except Exception:  # noqa: BLE001  (the next variant may still run)
            row = {"variant": spec, "error": traceback.format_exc()}
            print(row["error"], flush=True)
        out["variants"].append(row)
        Path(args.out).write_text(json.dumps(out, indent=1))
    try:
        out["one_replica"] = _time_batch(blob, 1, cycles)
    except Exception:  # noqa: BLE001
        out["one_replica_error"] = traceback.format_exc()
    Path(args.out).write_text(json.dumps(out, indent=1))
    timed = [r for r in out["variants"] if "wall_s" in r]
    if timed and args.batch_cycles:
        best = min(timed, key=lambda r: r["wall_s"])
        out["best_full"] = _time_batch(
            blob, reps, args.batch_cycles[0], best["threads_per_block"], best["max_registers"],
            best["compact"],
        )  # fmt: skip
        Path(args.out).write_text(json.dumps(out, indent=1))
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--gpu", action="store_true")
    p.add_argument("--cpu", action="store_true")
    p.add_argument("--clumps", action="store_true", help="screw lattices on --device")
    p.add_argument("--clump-sizes", nargs="+", default=["1e4", "1e5"])
    p.add_argument("--bed-state", metavar="PKL", help="fill and settle the sphere-bed, pickle it")
    p.add_argument("--bed", action="store_true", help="measure the pickled bed (--state)")
    p.add_argument("--state", default="/tmp/bed.pkl")
    p.add_argument("--device", default="cuda", choices=["cpu", "cuda"])
    p.add_argument("--sizes", nargs="+", default=["1e4", "1e5", "1e6", "4e6"])
    p.add_argument("--threads", nargs="+", type=int, default=[1, 4, 16])
    p.add_argument("--work", type=float, default=2e9, help="sphere-steps a timed GPU call")
    p.add_argument("--cycles", type=int, default=20)
    p.add_argument(
        "--batch",
        nargs="*",
        type=int,
        default=[],
        help="replica counts: the pickled bed (--state) R times in one GPU job",
    )
    p.add_argument(
        "--batch-cycles",
        nargs="*",
        type=int,
        default=[],
        help="cycles measured for each --batch count",
    )
    p.add_argument("--batch-variants", nargs="*", default=[], metavar="T[:R][c|a]",
                   help="time the first --batch count with T threads per block (the step "
                   "kernel capped at R registers, c: the compact step, a: the engine's trial of "
                   "the plain and compact steps) "
                   "for --variant-cycles each")  # fmt: skip
    p.add_argument(
        "--step",
        choices=list(STEPS),
        default="plain",
        help="the step kernel (--gpu and --clumps on cuda): plain (the default), compact "
        "(touching candidates gathered first) or auto (the engine times both on the first chunks)",
    )
    p.add_argument(
        "--mesh",
        action="store_true",
        help="--gpu and --cpu lattices in a trough of triangles (the flat walls as a mesh)",
    )
    p.add_argument("--variant-cycles", type=int, default=5)
    p.add_argument("--max-registers", nargs="*", type=int, default=[],
                   help="also time the step kernel compiled with at most this many registers, "
                   "at the second-largest size")  # fmt: skip
    p.add_argument("--out", default="gpu_bench.json")
    args = p.parse_args()
    if args.gpu:
        gpu_job(args)
    if args.cpu:
        cpu_job(args)
    if args.bed_state:
        bed_state(Path(args.bed_state), max(args.threads))
    if args.bed:
        bed_job(args)
    if args.batch_variants:
        variants_job(args)
    elif args.batch:
        batch_job(args)
    if args.clumps:
        clumps_job(args)


if __name__ == "__main__":
    main()
