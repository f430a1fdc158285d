"""The figures of validation/plots: dem's plots as a user gets them, from real runs.

    .venv/bin/python validation/plots/make.py      # about a minute on 2 cores, kernels cached

- ``sweep.png``: ``dem sweep`` of a small sphere bed (60 spheres of r = 2 mm, 0.03 m x 0.02 m
  section, 60 Hz, A = 0.5 mm held, 1 settling and 4 measured cycles a point) over
  drive.angle = 15, 25, 35 deg and material.friction = 0.3, 0.6: the velocity in m/s and
  normalised, the point mass dashed.
- ``comparison.png``: ``dem report`` of three of its points (mu = 0.3).
- ``velocity_per_cycle.png``: ``dem report`` of one point (phi = 25 deg, mu = 0.3).
- ``optimum_screw_trough.png``: ``dem optimum``'s figure redrawn
(:func:`dem.studies.optimum.replot`)
  from the recorded search of validation/optimum/screw-trough/optimum.json: the plateau band,
  the runs, the point mass of the same drive.

Scratch output goes to validation/plots/scratch (git-ignored).
"""

import shutil
from pathlib import Path

from dem.studies.optimum import replot
from dem.studies.report import make_report
from dem.studies.sweep import run_sweep

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SCRATCH = HERE / "scratch"

CASE = """
[trough]
length = 0.03
width = 0.02

[drive]
frequency = 60.0
angle = 25.0
amplitude = 0.0005

[material]
density = 7800.0
friction = 0.35

[contact]
model = "hertz_mindlin"
youngs_modulus = 5.0e7

[particles]
shape = "sphere"
count = 60
radius = 0.002

[run]
settle_cycles = 1
cycles = 4
seed = 3

[output]
frames_per_cycle = 3
"""


def main() -> None:
    case = SCRATCH / "case"
    case.mkdir(parents=True, exist_ok=True)
    (case / "case.toml").write_text(CASE)
    sweep = SCRATCH / "sweep"
    run_sweep(case, [("drive.angle", [15.0, 25.0, 35.0]), ("material.friction", [0.3, 0.6])],
              sweep, workers=2, progress=False)  # fmt: skip
    shutil.copy(sweep / "sweep.png", HERE / "sweep.png")
    points = [sweep / f"{i:03d}_drive.angle={a}_material.friction=0.3"
              for i, a in ((0, 15), (2, 25), (4, 35))]  # fmt: skip
    make_report(points, SCRATCH / "comparison")
    shutil.copy(SCRATCH / "comparison" / "comparison.png", HERE / "comparison.png")
    make_report([points[1]], SCRATCH / "one")
    shutil.copy(SCRATCH / "one" / "velocity_per_cycle.png", HERE / "velocity_per_cycle.png")
    opt = SCRATCH / "optimum"
    opt.mkdir(exist_ok=True)
    shutil.copy(ROOT / "validation" / "optimum" / "screw-trough" / "optimum.json", opt)
    replot(opt)  # its case_dir, cases/screw-trough, is relative to the repository root
    shutil.copy(opt / "optimum.png", HERE / "optimum_screw_trough.png")
    for name in ("sweep", "comparison", "velocity_per_cycle", "optimum_screw_trough"):
        print(f"wrote {HERE / name}.png")


if __name__ == "__main__":
    main()
