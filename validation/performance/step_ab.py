"""Two checkouts' step on one settled, driven bed, interleaved: what did a kernel change buy?

    .venv/bin/python validation/performance/step_ab.py --old /tmp/old [--new .] [--rounds 3]
        [--case cases/sphere-bed]

``--old`` is a checkout (``git worktree add --detach /tmp/old COMMIT``). Each round runs one
fresh process per checkout, alternating which goes first, each on one thread (numba's cache in
``NUMBA_CACHE_DIR``, so a checkout compiles once). A process loads the state that
``profile_step.py`` prepares for the case (settled and driven two cycles: the bed's contacts as
a run has them, not a fill's falling grains), steps 200 times, then times, as thread CPU time
(the machine's other work does not count), the best of five loops of 1000 calls of

- ``pairs_us``: the one-thread pair loop (``pair_forces_serial``);
- ``walls_us``: the per-sphere walls (``forces_kick`` with the pairs gathered, no kick);
- ``whole_us``: ``Simulation.run``, best of three 1000-step calls.

Prints one JSON line per process and the medians per checkout. Measure with the machine quiet.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

JOB = r"""
import json, os, sys, time
sys.path.insert(0, sys.argv[3])
import numba
from pathlib import Path
import dem
from dem.scene.case import load_case
from dem.engine import setup
from dem.kernels import integrate as I
from dem.kernels.forces import pair_forces_serial
from threads_shared import load

sim = setup.from_case(load_case(sys.argv[1]))
load(sim, Path(sys.argv[2]))
sim.run(200)
s, nb, geom = sim.spheres, sim.pairs, sim.geom
steps = 1000


@numba.njit
def loop_pairs(k, model, p, x, v, om, rad, mass, pi, pj, n_pairs, hist, length, dt, n, f, t):
    for _ in range(k):
        pair_forces_serial(model, p, x, v, om, rad, mass, pi, pj, n_pairs, hist, length, dt, n,
                           0.0, 0.0, -9.81, f, t)


@numba.njit
def loop_walls(k, n, model, p, sph, nb, geom, rotation, mesh):
    s = 0.0
    for _ in range(k):
        s += I.forces_kick(n, model, p, sph, nb, 0.5 * geom.width, geom.back, geom.dt, 0.0, 0.0,
                           -9.81, rotation, False, False, True, mesh)
    return s


def best(fn, args, reps=5):
    fn(2, *args)
    b = 1e9
    for _ in range(reps):
        t0 = time.thread_time()
        fn(steps, *args)
        b = min(b, time.thread_time() - t0)
    return 1e6 * b / steps


hist, walls = nb.hist.copy(), s.wall_hist.copy()
out = {"dem": os.path.dirname(dem.__file__), "pairs": int(nb.n_pairs)}
out["pairs_us"] = best(loop_pairs, (sim.law.model_id, sim.law.params, s.x, s.v, s.omega,
                                    s.radius, s.mass, nb.pair_i, nb.pair_j, nb.n_pairs, nb.hist,
                                    geom.length, geom.dt, s.n, s.force, s.torque))
out["walls_us"] = best(loop_walls, (s.n, sim.law.model_id, sim.law.params, s.as_layout(),
                                    nb.as_layout(), geom, sim.rotation, sim.mesh_layout()))
nb.hist[:] = hist
s.wall_hist[:] = walls
sim.run(steps)
w = 1e9
for _ in range(3):
    t0 = time.thread_time()
    sim.run(steps)
    w = min(w, time.thread_time() - t0)
out["whole_us"] = 1e6 * w / steps
out["load_1min"] = os.getloadavg()[0]
print(json.dumps(out))
"""


def run_one(checkout: Path, case: Path, state: Path) -> dict:
    env = os.environ | {"PYTHONPATH": str(checkout), "NUMBA_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", JOB, str(case), str(state), str(HERE)],
                          cwd="/", env=env, capture_output=True, text=True)  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"the job failed in {checkout}:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=ROOT)
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "sphere-bed")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    from threads_shared import prepare

    case = args.case.resolve()
    state = HERE / "scratch" / f"profile_{case.name}.npz"
    state.parent.mkdir(exist_ok=True)
    if not state.exists():
        prepare(str(case), state)
    rows: dict[str, list[dict]] = {"old": [], "new": []}
    for r in range(args.rounds):
        order = [("old", args.old), ("new", args.new)]
        for name, checkout in order if r % 2 == 0 else order[::-1]:
            row = run_one(checkout.resolve(), case, state)
            rows[name].append(row)
            print(name, json.dumps(row), flush=True)
    for key in ("pairs_us", "walls_us", "whole_us"):
        old = statistics.median(r[key] for r in rows["old"])
        new = statistics.median(r[key] for r in rows["new"])
        print(f"{key}: old {old:.1f}, new {new:.1f} (new / old {new / old:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
