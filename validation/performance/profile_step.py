"""Where a step's time goes: each kernel of the step loop timed alone, on 1 and 2 threads.

    .venv/bin/python validation/performance/profile_step.py [--case cases/sphere-bed] [--steps 2000]

The case is settled and driven for two cycles (one state, prepared once). Then, for each thread
count, in a fresh process (OpenMP reads its thread count once):

- ``advance``: the whole step loop (what ``dem run`` times), ``--steps`` steps;
- each part of a step alone, called ``--steps`` times from a compiled loop (no Python dispatch):
  the displacement check, the pair loop, the per-sphere (or per-body) gather and kick, and a
  neighbour build; builds per step are counted in the ``advance`` run. One thread takes the
  serial path as ``dem run`` does (pairs added to the spheres directly; "gather" is then the
  walls and the kick alone).

The parts' sum (build time weighted by builds per step) against the whole step shows what the
parallel regions' start and end (fork, barrier) cost. Writes profile_CASE.json and prints the
table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from threads_shared import prepare  # the same settled, driven state

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

WORKER = r"""
import json, sys, time
import numba
import numpy as np
from pathlib import Path
from dem.scene.case import load_case
from dem.engine import setup
from threads_shared import load
from dem.kernels import integrate as I
from dem.kernels.forces import pair_forces, pair_forces_serial
from dem.kernels.neighbours import max_displacement_sq

steps = int(sys.argv[1])
sim = setup.from_case(load_case(sys.argv[2]))
load(sim, Path(sys.argv[3]))
sim.run(200)


@numba.njit
def loop_disp(k, x, x_ref, n, length):
    s = 0.0
    for _ in range(k):
        s += max_displacement_sq(x, x_ref, n, length)
    return s


@numba.njit
def loop_pairs(k, model, p, sph, nb, n_pairs, geom, serial):
    for _ in range(k):
        if serial:
            pair_forces_serial(model, p, sph.x, sph.v, sph.omega, sph.radius, sph.mass,
                               nb.pair_i, nb.pair_j, n_pairs, nb.hist, geom.length, geom.dt,
                               sph.x.shape[0], 0.0, 0.0, -9.81, sph.force, sph.torque)
        else:
            pair_forces(model, p, sph.x, sph.v, sph.omega, sph.radius, sph.mass, nb.pair_i,
                        nb.pair_j, n_pairs, nb.hist, geom.length, geom.dt, nb.part_slot, nb.inbox)


@numba.njit
def loop_gather(k, n, model, p, sph, nb, geom, rotation, serial, mesh):
    s = 0.0
    for _ in range(k):
        s += I.forces_kick(n, model, p, sph, nb, 0.5 * geom.width, geom.back, geom.dt, 0.0, 0.0,
                           -9.81, rotation, True, True, serial, mesh)
    return s


@numba.njit
def loop_gather_bodies(k, model, p, sph, nb, geom, rotation, bod, serial, mesh):
    s = 0.0
    for _ in range(k):
        s += I.bodies_forces_kick(model, p, sph, nb, 0.5 * geom.width, geom.back, geom.dt, 0.0,
                                  0.0, -9.81, rotation, True, bod, geom.length, serial, mesh)
    return s


@numba.njit
def loop_build(k, n, sph, body, nb, counters, geom):
    for _ in range(k):
        nb.x_ref[0, 0] = np.inf
        I.build(n, sph, body, nb, counters, geom)


def timed(fn, *args, repeat=3):
    fn(2, *args)  # compile
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(steps, *args)
        best = min(best, time.perf_counter() - t0)
    return best / steps


import copy
s, nb, geom = sim.spheres, sim.pairs, sim.geom
n, model, p = s.n, sim.law.model_id, sim.law.params
builds0 = nb.builds
t0 = time.perf_counter()
sim.run(steps)
whole = (time.perf_counter() - t0) / steps
builds = (nb.builds - builds0) / steps
base = copy.deepcopy((sim.spheres, sim.pairs, sim.bodies))
res = {"threads": numba.get_num_threads(), "spheres": n, "pairs": nb.n_pairs,
       "whole_step_s": whole, "builds_per_step": builds}
res["displacement_s"] = timed(loop_disp, s.x, nb.x_ref, n, geom.length)
serial = numba.get_num_threads() == 1  # as the CPU engine chooses
res["pair_forces_s"] = timed(loop_pairs, model, p, s.as_layout(), nb.as_layout(), nb.n_pairs,
                             geom, serial)
if sim.bodies is None:
    res["gather_kick_s"] = timed(loop_gather, n, model, p, s.as_layout(), nb.as_layout(), geom,
                                 sim.rotation, serial, sim.mesh_layout())
else:
    res["gather_kick_s"] = timed(loop_gather_bodies, model, p, s.as_layout(), nb.as_layout(),
                                 geom, sim.rotation, sim.bodies.as_layout(), serial,
                                 sim.mesh_layout())
sim.spheres, sim.pairs, sim.bodies = base
s, nb = sim.spheres, sim.pairs
res["build_s"] = timed(loop_build, n, s.as_layout(), s.body, nb.as_layout(), nb.counters, geom,
                       repeat=1)
print(json.dumps(res))
"""


def measure(threads: int, steps: int, case: str, state: Path) -> dict:
    env = os.environ | {"NUMBA_NUM_THREADS": str(threads), "PYTHONPATH": str(HERE)}
    out = subprocess.run([sys.executable, "-c", WORKER, str(steps), case, str(state)],
                         env=env, capture_output=True, text=True)  # fmt: skip
    if out.returncode != 0:
        raise SystemExit(f"the worker failed:\n{out.stderr[-3000:]}")
    row = json.loads(out.stdout.strip().splitlines()[-1])
    row["load_1min"] = round(os.getloadavg()[0], 2)
    return row


def table(rows: list[dict]) -> str:
    """Microseconds per step of each part, best over repeats, per thread count."""
    parts = ["displacement_s", "pair_forces_s", "gather_kick_s", "build_s"]
    lines = [f"{'threads':>7s} {'whole':>8s} {'disp':>7s} {'pairs':>7s} {'gather':>7s} "
             f"{'build':>8s} {'b/step':>7s} {'sum':>8s} {'rest':>7s}"]  # fmt: skip
    for threads in sorted({r["threads"] for r in rows}):
        mine = [r for r in rows if r["threads"] == threads]
        best = {k: min(r[k] for r in mine) for k in ["whole_step_s", *parts]}
        per_step_build = best["build_s"] * mine[0]["builds_per_step"]
        total = best["displacement_s"] + best["pair_forces_s"] + best["gather_kick_s"]
        total += per_step_build
        us = {k: 1e6 * v for k, v in best.items()}
        lines.append(
            f"{threads:7d} {us['whole_step_s']:8.1f} {us['displacement_s']:7.1f} "
            f"{us['pair_forces_s']:7.1f} {us['gather_kick_s']:7.1f} {us['build_s']:8.1f} "
            f"{mine[0]['builds_per_step']:7.3f} {1e6 * total:8.1f} "
            f"{us['whole_step_s'] - 1e6 * total:7.1f}"
        )
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--case", default=str(ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
    )
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--threads", default="1,2")
    args = parser.parse_args()
    name = Path(args.case).name
    state = HERE / "scratch" / f"profile_{name}.npz"
    state.parent.mkdir(exist_ok=True)
    if not state.exists():
        prepare(args.case, state)
    rows = []
    for _ in range(args.repeat):
        for threads in [int(t) for t in args.threads.split(",")]:
            row = measure(threads, args.steps, args.case, state)
            rows.append(row)
            print(json.dumps(row), flush=True)
    print(f"\n{name}: microseconds per step ({rows[0]['spheres']} spheres, "
          f"{rows[0]['pairs']} pairs)")  # fmt: skip
    print(table(rows))
    from dem import provenance

    (HERE / f"profile_{name}.json").write_text(json.dumps(
        {"provenance": provenance.record(), "case": args.case, "steps": args.steps,
         "rows": rows}, indent=1) + "\n")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
