"""Is the screws' fill-to-fill spread a fill's lasting state, or a slow fluctuation?

    .venv/bin/python validation/speed_accuracy/fill_spread.py   # about 3 min on 2 cores

Twenty-cycle runs of cases/screw-trough scatter from seed to seed by about 2.7 % of the bulk
velocity, more than each run's own (autocorrelation-corrected) standard error of about 0.7 %.
Here each of four fills runs 200 measured cycles (at dt = the stability limit, which the
time-step study found as accurate as the automatic step). If the spread were a lasting state
of each fill, the 200-cycle means would scatter as much as the 20-cycle ones; if it is a slow
fluctuation, the scatter of 20-cycle block means within one long run matches the
fill-to-fill spread, and the 200-cycle means scatter about sqrt(10) times less.

Writes fill_spread.csv (per-cycle velocities) and fill_spread.png (running means).
"""

import csv
import math
import sys
import tempfile
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from study import HERE, Point, load

from dem.physics import measure

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402

SEEDS = (1, 2, 3, 4)
CYCLES = 200
BLOCK = 20


def run(seed: int) -> list[float]:
    from dem.run import runner

    point = Point("fill_spread", "screw-trough", "long", "long", timestep_fraction=1.0, seed=seed)
    case = load(point)
    with tempfile.TemporaryDirectory() as tmp:
        summary = runner.run_case(case, Path(tmp) / "out", cycles=CYCLES, threads=1,
                                  progress=False, frames=False)  # fmt: skip
    scale = case.drive.velocity_scale
    tau = summary["cycle_autocorrelation_time"]
    print(f"seed {seed}: v_norm {summary['mean_velocity_norm']:.4f} +- "
          f"{summary['mean_velocity_norm_stderr']:.4f} (tau {tau:.1f})", flush=True)  # fmt: skip
    return [u / scale for u in summary["per_cycle_velocity"]]


def main() -> int:
    with Pool(2) as pool:
        series = pool.map(run, SEEDS)
    v = np.array(series)  # (seeds, cycles), normalised
    blocks = v[:, : CYCLES // BLOCK * BLOCK].reshape(len(SEEDS), -1, BLOCK).mean(axis=2)
    first = blocks[:, 0]
    full = v.mean(axis=1)
    within = float(np.std(blocks, axis=1, ddof=1).mean())
    stderr = [measure.correlated_stderr(s)[0] for s in v]
    print(f"20-cycle means (first block) across fills: std {np.std(first, ddof=1):.4f}")
    print(f"20-cycle block means within one run:       std {within:.4f} (mean over fills)")
    print(f"{CYCLES}-cycle means across fills:            std {np.std(full, ddof=1):.4f}; "
          f"expected if fluctuation only: {within / math.sqrt(CYCLES / BLOCK):.4f}")  # fmt: skip
    print(f"{CYCLES}-cycle correlated stderr of one run:     {np.mean(stderr):.4f}")
    with open(HERE / "fill_spread.csv", "w", newline="") as fh:
        header.write_csv_header(fh, __file__)
        w = csv.writer(fh)
        w.writerow(["cycle"] + [f"seed_{s}" for s in SEEDS])
        for k in range(v.shape[1]):
            w.writerow([k] + [f"{x:.6f}" for x in v[:, k]])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4))
    k = np.arange(1, v.shape[1] + 1)
    for s, row in zip(SEEDS, v, strict=True):
        ax.plot(k, np.cumsum(row) / k, label=f"seed {s}")
        ax.plot(np.arange(BLOCK, CYCLES + 1, BLOCK), blocks[SEEDS.index(s)], "o", ms=3,
                color=ax.lines[-1].get_color())  # fmt: skip
    ax.set_xlabel("measured cycles")
    ax.set_ylabel("v / (A omega cos phi): running mean (line), 20-cycle blocks (dots)")
    ax.set_title("cases/screw-trough, dt = stability limit: four fills", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "fill_spread.png", dpi=120)
    print("wrote fill_spread.csv and fill_spread.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
