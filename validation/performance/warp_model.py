"""How often a warp meets the contact law in each GPU step scheme, counted on a real bed's pairs.

Nsight Compute found the GPU step kernel latency- and divergence-bound on the 100-replica bed
(`ncu_step_kernel_h200.txt`: 9.3 of 32 threads active). This script counts, on the CPU, from
the settled sphere-bed's pair list and wall gaps, the times a warp runs the contact law in a step
and how many of its threads run it usefully, for each scheme of :mod:`dem.kernels.cuda.step`:

- ``plain`` (:func:`step_kernel`): a thread a sphere walks its reverse slots, its own slots and
  the walls in three loops, each with its own call site of the law; a warp runs the law at slot
  s of a loop when any of its 32 spheres' slot s touches.
- ``lanes L`` (:func:`lanes_step_kernel`): L threads a sphere, candidates dealt round-robin, one
  call site; a block's rounds are set by its most loaded sphere.
- ``compact`` (:func:`compact_step_kernel`): a block lists its touching candidates and runs the
  law one contact a thread: ceil(touching / 32) runs a warp's worth of spheres.

It is a count, not a timing: the law is most of a step's instructions, so the ratio of the
counts bounds what each scheme can gain; the GPU measurement (run_device_schemes.sh) says what it
does gain. The bed state is ``gpu_bench.py --bed-state PKL``'s (filled here if missing).

Usage: python validation/performance/warp_model.py [--state /tmp/bed.pkl] [--out JSON]
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))
sys.path.insert(0, str(HERE))

WARP = 32
BLOCK = 128


def candidates(sim) -> list[np.ndarray]:
    """Each sphere's candidates' touching flags in the kernels' order, and each one's loop.

    Returns a list of (m, 2) int arrays: column 0 touching (0/1), column 1 the loop (0 reverse
    slots, 1 own slots, 2 walls).
    """
    from dem.kernels.forces import N_WALLS

    pairs, x, r = sim.pairs, sim.spheres.x, sim.spheres.radius
    n, k = sim.spheres.n, sim.pairs.n_pairs
    pi, pj = pairs.pair_i[:k], pairs.pair_j[:k]
    length, width = sim.geom.length, sim.geom.width
    d = x[pi] - x[pj]
    d[:, 0] -= length * np.round(d[:, 0] / length)
    touch = (np.sum(d * d, axis=1) < (r[pi] + r[pj]) ** 2).astype(int)
    gaps = np.stack([x[:, 2], x[:, 1] + width / 2, width / 2 - x[:, 1], x[:, 0] - sim.geom.back], 1)
    walls = (r[:, None] - gaps > 0).astype(int)
    assert walls.shape[1] == N_WALLS
    upper = np.lexsort((pi, pj))  # sphere j's reverse slots: by j, then a
    lower = np.lexsort((pj, pi))  # sphere i's own slots: by i, then b
    rev = np.split(touch[upper], np.searchsorted(pj[upper], np.arange(1, n)))
    own = np.split(touch[lower], np.searchsorted(pi[lower], np.arange(1, n)))
    out = []
    for i in range(n):
        flags = np.concatenate([rev[i], own[i], walls[i]])
        loops = np.repeat([0, 1, 2], [len(rev[i]), len(own[i]), N_WALLS])
        out.append(np.stack([flags, loops], 1))
    return out


def plain(cands) -> tuple[int, int]:
    """(law runs, useful thread runs) of :func:`step_kernel`, summed over the warps."""
    runs = useful = 0
    for s in range(0, len(cands), WARP):
        warp = cands[s : s + WARP]
        for loop in range(3):
            lists = [c[c[:, 1] == loop, 0] for c in warp]
            most = max(len(f) for f in lists)
            for slot in range(most):
                hits = sum(int(f[slot]) for f in lists if slot < len(f))
                runs += hits > 0
                useful += hits
    return runs, useful


def lanes(cands, count: int) -> tuple[int, int]:
    """(law runs, useful thread runs) of :func:`lanes_step_kernel` with ``count`` lanes."""
    runs = useful = 0
    per_block, per_warp = BLOCK // count, WARP // count
    for s in range(0, len(cands), per_block):
        block = cands[s : s + per_block]
        rounds = max(-(-len(c) // count) for c in block)
        for w in range(0, len(block), per_warp):
            warp = block[w : w + per_warp]
            for r in range(rounds):
                hits = sum(int(c[e, 0]) for c in warp for e in range(r * count, (r + 1) * count)
                           if e < len(c))  # fmt: skip
                runs += hits > 0
                useful += hits
    return runs, useful


def compact(cands) -> tuple[int, int]:
    """(law runs, useful thread runs) of :func:`compact_step_kernel`."""
    runs = useful = 0
    for s in range(0, len(cands), BLOCK):
        items = sum(int(c[:, 0].sum()) for c in cands[s : s + BLOCK])
        runs += -(-items // WARP)
        useful += items
    return runs, useful


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--state", default="/tmp/bed.pkl", help="gpu_bench.py --bed-state's pickle")
    p.add_argument("--out", default=str(HERE / "warp_model_sphere-bed.json"))
    args = p.parse_args()
    state = Path(args.state)
    if not state.exists():
        from gpu_bench import bed_state

        print(f"filling and settling the sphere-bed into {state} ...", flush=True)
        bed_state(state, 2)
    sim = pickle.loads(state.read_bytes())
    cands = candidates(sim)
    n = len(cands)
    touching = sum(int(c[:, 0].sum()) for c in cands)
    schemes = {"plain": plain(cands)}
    for count in (2, 4, 8):
        schemes[f"lanes {count}"] = lanes(cands, count)
    schemes["compact"] = compact(cands)
    rows = {}
    for name, (runs, useful) in schemes.items():
        rows[name] = {
            "law_runs_per_32_spheres": round(WARP * runs / n, 2),
            "useful_threads_per_run": round(useful / runs, 1),
        }
        print(f"{name:8s}: the law {rows[name]['law_runs_per_32_spheres']:6.2f} times a warp's "
              f"worth of spheres, {rows[name]['useful_threads_per_run']:4.1f} of 32 threads "
              f"useful", flush=True)  # fmt: skip
    out = {
        "what": "issue 29: contact-law runs a warp's worth of spheres (32) in one step of each "
        "GPU step scheme, counted from the settled, driven sphere-bed's pair list and wall gaps "
        "(a count on the CPU, not a timing)",
        "command": "python validation/performance/warp_model.py --state BED.pkl",
        "spheres": n,
        "candidates_per_sphere": round(sum(len(c) for c in cands) / n, 2),
        "touching_per_sphere": round(touching / n, 2),
        "schemes": rows,
    }
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
