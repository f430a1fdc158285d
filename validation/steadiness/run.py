"""Can one run tell that its bed is still moving? Trend tests on short correlated series.

The hardening check found auto-settled bed runs whose per-cycle velocity rose by about 6 of their
own standard errors over their 30 measured cycles, with nothing in the summary saying so. Before
a run reports "not steady", this study measures what a test on the run's own series can do:
synthetic per-cycle series of the length a run measures (20 and 30 cycles), AR(1) noise of the
lag-1 correlations the shipped beds show (0, 0.5, 0.8; measure.py: "up to +0.8"), with and
without a linear drift of k times the run's own standard error of the mean (k = 6, 10, 20), and
three tests at |z| > 3:

- ``halves``: the second half's mean against the first's, each half's autocorrelated error
  (:func:`dem.physics.measure.correlated_stderr`);
- ``whole``: the same difference against the whole series' autocorrelated spread;
- ``trend``: the least-squares slope over the run against its error, the residuals' spread
  and autocorrelation time.

    .venv/bin/python validation/steadiness/run.py     # ~1 min, writes results.json
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from dem.physics import measure  # noqa: E402
from validation._lib.header import results_header  # noqa: E402

Z = 3.0
RUNS = 1000


def ar1(rng, n: int, rho: float) -> np.ndarray:
    """A stationary AR(1) series of unit innovations."""
    x = np.empty(n)
    x[0] = rng.normal(0.0, 1.0 / math.sqrt(1.0 - rho * rho))
    for t in range(1, n):
        x[t] = rho * x[t - 1] + rng.normal()
    return x


def halves(u: np.ndarray) -> float:
    n = u.size
    a, b = u[: n // 2], u[n - n // 2 :]
    se = math.hypot(measure.correlated_stderr(a)[0], measure.correlated_stderr(b)[0])
    return float((b.mean() - a.mean()) / se)


def whole(u: np.ndarray) -> float:
    n = u.size
    a, b = u[: n // 2], u[n - n // 2 :]
    tau = measure.integrated_autocorrelation_time(u)
    se_half = float(np.std(u, ddof=1)) * math.sqrt(2.0 * tau / (n // 2))
    return float((b.mean() - a.mean()) / (math.sqrt(2.0) * se_half))


def trend(u: np.ndarray) -> float:
    n = u.size
    t = np.arange(n) - (n - 1) / 2.0
    slope = float(np.dot(t, u - u.mean()) / np.dot(t, t))
    res = u - u.mean() - slope * t
    tau = measure.integrated_autocorrelation_time(res)
    se = float(np.std(res, ddof=2)) * math.sqrt(2.0 * tau / float(np.dot(t, t)))
    return slope / se


TESTS = {"halves": halves, "whole": whole, "trend": trend}


def main() -> None:
    rng = np.random.default_rng(46)
    rows = []
    for n in (20, 30):
        for rho in (0.0, 0.5, 0.8):
            sd = 1.0 / math.sqrt(1.0 - rho * rho)
            se_run = sd * math.sqrt((1.0 + rho) / (1.0 - rho) / n)  # the mean's true error
            for k in (0, 6, 10, 20):
                series = [ar1(rng, n, rho) + np.linspace(0.0, k * se_run, n) for _ in range(RUNS)]
                row = {"cycles": n, "lag1": rho, "drift_in_run_stderr": k}
                for name, test in TESTS.items():
                    row[name] = float(np.mean([abs(test(u)) > Z for u in series]))
                rows.append(row)
                print(json.dumps(row), flush=True)
    doc = results_header("validation/steadiness/run.py", dated=True)
    doc |= {"z": Z, "runs": RUNS, "flagged_fraction": rows}
    (HERE / "results.json").write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
