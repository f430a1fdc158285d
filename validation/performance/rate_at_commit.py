"""The sphere bed's step rate at any commit, interleaved with others: where did the speed go?

    .venv/bin/python validation/performance/rate_at_commit.py 7798172 HEAD --rounds 3

Each commit gets a detached worktree under ``--work`` (default /tmp/dem-rate) and its own
numba cache there (compiled once). Each round runs every commit once, alternating the order, in
a fresh process on one thread: ``run_case`` on the benchmark's sphere deck as that commit has it
(validation/liggghts-bulk/sphere-bed-5e7, or cases/sphere-bed before that folder existed: the
same 1500 spheres at 5e7 Pa), the "liggghts" law (which every commit has), dt 5e-6 s, one settle
cycle and six measured, one fill; the rate is the summary's particle_steps_per_s.

Measured 2026-11-28 (2-core VM, nothing else running, load 0.9-1.0): 7798172 (2026-11-23)
6.9-8.9e6 particle-steps/s against 4.4-5.1e6 at b6ab922, three rounds. Single runs scatter by
up to 40 % on this VM (bcb4815: 8.6 once, 5.2-6.2 three times), which defeated a bisect on one
run per commit: take three rounds a commit. count_instructions.py then located the slowdown by
instruction counts, which the noise does not touch (the contact history's reset, 314b1fd).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

JOB = r"""
import dataclasses, json, os, sys
try:
    from dem.scene.case import load_case
    from dem.run.runner import run_case
except ImportError:  # before the layer folders
    from dem.case import load_case
    from dem.runner import run_case
case = load_case(sys.argv[1]).with_tangential("liggghts")
kw = dict(timestep=5e-6, settle_cycles=1, cycles=6)
if "replicas" in {f.name for f in dataclasses.fields(case.run)}:
    kw["replicas"] = 1
case = dataclasses.replace(case, run=dataclasses.replace(case.run, **kw))
run_case(case, sys.argv[2], cycles=6, threads=1, progress=False, overwrite=True, frames=False)
s = json.load(open(os.path.join(sys.argv[2], "summary.json")))
print(json.dumps({"rate": s["particle_steps_per_s"], "load": os.getloadavg()[0]}))
"""


def checkout(commit: str, work: Path) -> Path:
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", commit],
                         capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    tree = work / sha
    if not tree.exists():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), sha],
                       check=True, capture_output=True)  # fmt: skip
    return tree


def rate(tree: Path) -> dict:
    deck = tree / "validation" / "liggghts-bulk" / "sphere-bed-5e7"
    if not deck.exists():
        deck = tree / "cases" / "sphere-bed"
    env = os.environ | {"PYTHONPATH": str(tree), "NUMBA_NUM_THREADS": "1",
                        "NUMBA_CACHE_DIR": str(tree.parent / f"cache-{tree.name}")}  # fmt: skip
    out = tree.parent / f"out-{tree.name}"
    done = subprocess.run([sys.executable, "-c", JOB, str(deck), str(out)],
                          cwd="/", env=env, capture_output=True, text=True)  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{tree.name} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("commits", nargs="+")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--work", type=Path, default=Path("/tmp/dem-rate"))
    args = parser.parse_args(argv)
    args.work.mkdir(parents=True, exist_ok=True)
    trees = [checkout(c, args.work) for c in args.commits]
    rates: dict[str, list[float]] = {t.name: [] for t in trees}
    for r in range(args.rounds):
        for tree in trees if r % 2 == 0 else trees[::-1]:
            row = rate(tree)
            rates[tree.name].append(row["rate"])
            print(f"round {r + 1}: {tree.name} {row['rate']:.3g} (load {row['load']:.2f})",
                  flush=True)  # fmt: skip
    for name, values in rates.items():
        print(
            f"{name}: median {statistics.median(values):.3g}, {min(values):.3g}-{max(values):.3g}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
