"""Regenerate the paper's Figs. 2, 6, 7, 8 with the point-mass model, and check its claims.

Run from the repository root::

    .venv/bin/python validation/paper/make_figures.py            # full grids (about 10 s)
    .venv/bin/python validation/paper/make_figures.py --quick    # coarse grids (smoke test)

Writes into this folder (or ``--out DIR``): ``fig2_regimes``, ``fig6_throw_number``,
``fig7_friction``, ``fig8_throw_number`` as PNG + CSV, ``claims.json`` (every number quoted
in README.md) and ``claims.md`` (the README's tables). Each CSV starts with ``#`` comment lines
giving the dem version, the command, the date and the fixed inputs; read it with
``pandas.read_csv(path, comment="#")`` or, with numpy alone (whose ``names=True`` would take
the first comment line as the header), ``numpy.genfromtxt((line for line in open(path) if not
line.startswith("#")), delimiter=",", names=True, dtype=None, encoding=None)``.

Velocities are normalised by the drive velocity ``A omega cos(phi)``; the m/s panels use the
paper's 60 Hz. What is held fixed while the angle changes decides where the optimum lies
(README, The point-mass model): the throw number Gamma (the paper's Figs. 7-8), the
amplitude A, or the peak trough acceleration A omega^2 = K g. At a fixed frequency the last
two are the same hold (A = K g / omega^2); both are computed and reported, which checks that
identity. A fourth reading holds Gamma but measures the velocity in units of the drive
velocity amplitude, v / (A omega) = v_norm cos(phi) (``v_over_A_omega``; no frequency enters).

This file is the entry point; the work is in the modules beside it: fig2_regimes.py,
fig6_throw_number.py (claims a and b), optima.py and angle_figures.py (Figs. 7 and 8, claims c
and d), claims.py (verdicts, claims.md) and csv_output.py.
"""

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np
from angle_figures import FIG7, FIG8, fig7, fig8
from claims import markdown, verdicts
from fig2_regimes import FIG2, backward_upper_branch, fig2
from fig6_throw_number import FIG6, fig6, normal_landings

from dem import provenance
from dem.config import GRAVITY

HERE = Path(__file__).resolve().parent
# the figures' inputs and the tests' oracles, for tests/pointmass/test_validation_paper.py
__all__ = ["FIG2", "FIG6", "FIG7", "FIG8", "backward_upper_branch", "normal_landings", "run"]


def grids(quick: bool) -> dict:
    """Sample points of every figure; ``quick`` gives coarse grids for a smoke test."""
    if quick:
        return {
            "fig2_angle": np.linspace(1.0, 89.0, 12),
            "fig2_gamma": np.linspace(0.02, 3.0, 10),
            "fig6_gamma": np.round(np.arange(0.05, 7.0001, 0.25), 2),
            "angle": np.linspace(1.0, 89.0, 23),
            "optimum_points": 45,
            "merge_bisections": 2,
        }
    return {
        "fig2_angle": np.linspace(1.0, 89.0, 89),
        "fig2_gamma": np.linspace(0.01, 3.0, 300),
        "fig6_gamma": np.round(np.arange(0.01, 7.0001, 0.01), 2),
        "angle": np.linspace(1.0, 89.0, 353),
        "optimum_points": 321,
        "merge_bisections": 12,
    }


def provenance_meta(argv: list[str]) -> dict:
    """dem version, git commit, command, date, host, load and versions, for every output."""
    r = provenance.record()
    versions = r["versions"]
    return {
        "dem_version": versions["dem"],
        "git_commit": r["git_commit"] or "unknown",
        "command": shlex.join([sys.executable, *argv]),
        "date_utc": r["date"],
        "host": r["host"],
        "load_average": r["load_average"],
        "python": versions["python"],
        "numpy": versions["numpy"],
        "numba": versions["numba"],
        "gravity": GRAVITY,
    }


def to_jsonable(obj):
    """numpy scalars and arrays -> plain Python for json.dump."""
    if isinstance(obj, dict):
        return {k: to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def run(out: Path, quick: bool = False, argv: list[str] | None = None) -> dict:
    """Make every figure, CSV and the claims into ``out``; returns the claims dictionary."""
    out.mkdir(parents=True, exist_ok=True)
    meta = provenance_meta(argv if argv is not None else sys.argv)
    g = grids(quick)
    start = time.perf_counter()
    claims = {"provenance": meta, "quick": quick}
    claims["fig2"] = fig2(g, out, meta)
    claims.update(fig6(g, out, meta))
    claims["fig7"] = fig7(g, out, meta)
    claims["fig8"] = fig8(g, out, meta)
    claims["verdicts"] = verdicts(claims["fig7"], claims["fig8"])
    claims["seconds"] = time.perf_counter() - start
    claims = to_jsonable(claims)
    (out / "claims.json").write_text(json.dumps(claims, indent=1) + "\n")
    (out / "claims.md").write_text(markdown(claims))
    return claims


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="output folder (default: here)")
    parser.add_argument("--quick", action="store_true", help="coarse grids (smoke test)")
    args = parser.parse_args(argv[1:])
    claims = run(args.out, args.quick, argv)
    print(markdown(claims))
    print(f"claim (a): {json.dumps(claims['a'])}")
    for row in claims["b"]["per_eps_t"]:
        print(f"claim (b): {json.dumps(row)}")
    f2 = claims["fig2"]
    print(f"fig 2 agreement: {f2['agreeing']}/{f2['compared_outside_2pct_bands']}")
    print(f"done in {claims['seconds']:.1f} s -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
