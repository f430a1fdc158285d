"""Do two checkouts of dem compute the same numbers?  Bit for bit, over every contact law.

A refactor that claims to "change no number" is checked here: each configuration (a shipped
case with keys overridden: every normal law x every tangential law, rolling resistance,
``limit_force``, the wall lever arm, spheres and screws, flat walls, a U-pan mesh and the
finite feeder) is filled, settled and driven for a few hundred steps in a fresh process per
checkout, and the SHA-256 of the positions, velocities, spins and contact histories is
compared. Any difference in any bit is reported.

    .venv/bin/python validation/performance/same_numbers.py --old /tmp/old --new .

``--old`` is a checkout (``git worktree add --detach /tmp/old <commit>``); each process runs
with ``PYTHONPATH`` set to its checkout. One thread, so that the sums are ordered the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

#: The screw cases as they were when the bits were recorded (shipped at 2e9 Pa, 4e-6 s since).
SCREWS_THEN = {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}
#: (name, case folder, overrides); small counts so that the whole matrix runs in minutes. The
#: sphere beds are the LIGGGHTS-parity bed, cases/sphere-bed as it was shipped until 2026-11-26.
CONFIGS = [
    ("sphere-hertz-impact", "validation/liggghts-bulk/sphere-bed-5e7", {"particles.count": 120}),
    (
        "sphere-hertz-coulomb",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {"particles.count": 120, "contact.tangential": "coulomb"},
    ),
    (
        "sphere-hertz-liggghts",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {"particles.count": 120, "contact.tangential": "liggghts"},
    ),
    (
        "sphere-hertz-impact-roll-limit",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {
            "particles.count": 120,
            "material.rolling_friction": 0.05,
            "contact.limit_force": True,
            "contact.wall_lever_arm": "midpoint",
        },
    ),
    (
        "sphere-linear-impact",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {
            "particles.count": 120,
            "contact.model": "linear",
            "contact.youngs_modulus": None,
            "contact.stiffness": 4000.0,
        },
    ),
    (
        "sphere-linear-coulomb",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {
            "particles.count": 120,
            "contact.model": "linear",
            "contact.youngs_modulus": None,
            "contact.stiffness": 4000.0,
            "contact.tangential": "coulomb",
        },
    ),
    (
        "sphere-linear-liggghts",
        "validation/liggghts-bulk/sphere-bed-5e7",
        {
            "particles.count": 120,
            "contact.model": "linear",
            "contact.youngs_modulus": None,
            "contact.stiffness": 4000.0,
            "contact.tangential": "liggghts",
        },
    ),
    ("screw-impact", "cases/screw-trough", {**SCREWS_THEN, "particles.count": 24}),
    (
        "screw-coulomb",
        "cases/screw-trough",
        {**SCREWS_THEN, "particles.count": 24, "contact.tangential": "coulomb"},
    ),
    ("single-sphere", "cases/single-sphere", {}),
    ("u-trough", "cases/u-trough", {**SCREWS_THEN, "particles.count": 40}),
    ("feeder", "cases/feeder", SCREWS_THEN),
    # the shipped cases as shipped (2e9 Pa, 4e-6 s), fewer grains
    ("shipped-sphere-bed", "cases/sphere-bed", {"particles.count": 120}),
    ("shipped-screw-trough", "cases/screw-trough", {"particles.count": 24}),
    ("shipped-u-trough", "cases/u-trough", {"particles.count": 40}),
    ("shipped-v-trough", "cases/v-trough", {"particles.count": 40}),
    ("shipped-feeder", "cases/feeder", {}),
]

JOB = r"""
import hashlib, json, sys
import numba
import numpy as np
try:  # the layer folders (issue 27); before them the modules sat at dem/'s top level
    from dem.scene.case import load_case
    from dem.engine import setup
except ImportError:
    from dem.case import load_case
    from dem import setup
numba.set_num_threads(1)
name, folder, overrides, steps = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4])
case = load_case(folder, overrides)
sim = setup.from_case(case)
sim.run(steps)
sim.start_drive()
sim.run(steps)
s = sim.spheres
digest = hashlib.sha256()
arrays = [s.x, s.v, s.omega]
if sim.bodies is not None:
    arrays += [sim.bodies.x, sim.bodies.v, sim.bodies.q]
for a in arrays:
    digest.update(np.ascontiguousarray(a).tobytes())
arrays = [s.wall_hist, s.mesh_hist, sim.pairs.hist[: sim.pairs.counters[0]]]
for a in arrays:
    digest.update(np.ascontiguousarray(a).tobytes())
print(json.dumps({"sha256": digest.hexdigest(), "spheres": int(s.n),
                  "x0": float(s.x[0, 0]), "vmean": float(np.mean(s.v[:, 0]))}))
"""


def run_one(checkout: Path, folder: str, overrides: dict, steps: int) -> dict:
    """One configuration in a fresh process of ``checkout``; its JSON line as a dict."""
    env = os.environ | {"PYTHONPATH": str(checkout), "NUMBA_NUM_THREADS": "1"}
    done = subprocess.run(
        [sys.executable, "-c", JOB, "x", str(checkout / folder), json.dumps(overrides),
         str(steps)],
        cwd=checkout, env=env, capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{folder} {overrides} failed in {checkout}:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=Path("."))
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    rows, same = [], True
    for name, folder, overrides in CONFIGS:
        old = run_one(args.old.resolve(), folder, overrides, args.steps)
        new = run_one(args.new.resolve(), folder, overrides, args.steps)
        equal = old["sha256"] == new["sha256"]
        same &= equal
        rows.append({"name": name, "equal": equal, "old": old, "new": new})
        print(
            f"{name:32s} {'same' if equal else 'DIFFERENT'}  {old['sha256'][:12]} "
            f"{new['sha256'][:12]}",
            flush=True,
        )
    if args.out:
        args.out.write_text(json.dumps({"steps": args.steps, "rows": rows}, indent=1) + "\n")
    raise SystemExit(0 if same else 1)


if __name__ == "__main__":
    main()
