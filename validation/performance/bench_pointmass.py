"""Speed of the event-driven point-mass model, and its speed-up over brute-force time stepping.

Run from the repository root (about 1-2 minutes on 2 cores; nothing is asserted)::

    .venv/bin/python validation/performance/bench_pointmass.py [--repeats 7] [--target 1e-3]

1. The paper's Fig. 7 sweep (Gamma = 1.8, mu in {0.25, 0.35, 0.60}, 161 angles from 1 to
   89 deg: 483 points) through :func:`dem.pointmass.sweep.sweep`, timed after a warm-up call
   that compiles the kernels: best and median of ``--repeats`` runs.
2. The brute-force twin of the tests (``tests/oracles/naive_pointmass.py``: fixed-step Moreau time
   stepping, first order in the step) on the same 483 points, against the event-driven result
   (exact to about 1e-9). Step counts per cycle run up a geometric ladder; the coarsest count
   from which on the maximum absolute error in v / (A omega cos phi) stays within ``--target``
   is timed (warm, best of 3), and the speed-up is its time over the event-driven time.
   Each brute-force run skips 1.5 times the cycles the model needed to close its orbit plus
   100, then averages 48 cycles (as in tests/pointmass/test_pointmass.py).
3. The brute force's error at the tests' 8000 steps per cycle, on the Fig. 7 sweep and on the
   tests' own grid (``tests/pointmass/test_pointmass.py::_grid``, periodic points).

Prints a table and writes ``validation/performance/pointmass.json``.
"""

import argparse
import importlib.util
import json
import os
import platform
import shlex
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np

from dem import provenance
from dem.pointmass import velocities
from dem.pointmass.sweep import sweep

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent.parent / "tests"


def from_tests(name: str):
    """The module tests/FOLDER/NAME.py, loaded by its path (tests/ is not a package)."""
    if name not in sys.modules:
        path = next(TESTS.rglob(f"{name}.py"))
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


brute = from_tests("naive_pointmass").brute  # the tests' independent twin
_grid = from_tests("test_pointmass")._grid  # the grid the brute-force test uses

FIG7_ANGLES = np.linspace(1.0, 89.0, 161)
FIG7_FRICTIONS = (0.25, 0.35, 0.60)
FIG7_THROW_NUMBER = 1.8
MEASURED_CYCLES = 48
TEST_STEPS = 8000
LADDER = np.unique(np.round(500 * 2.0 ** (np.arange(0, 13) / 3.0)).astype(int))  # 500..8000


def fig7_sweep():
    """The timed call: one Fig. 7 sweep (3 mu x 161 angles)."""
    return sweep(FIG7_THROW_NUMBER, FIG7_ANGLES, FIG7_FRICTIONS)


def timed(func, repeats):
    """Seconds of ``repeats`` calls of func (after the caller's warm-up)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return times


def params_of(result):
    """Rows (Gamma, phi, mu, alpha, eps_t, eps_n) of a sweep result, as the brute force takes."""
    keys = ("throw_number", "angle", "friction", "inclination", "eps_t", "eps_n")
    return np.column_stack([result[k] for k in keys])


def transient_of(cycles):
    """Cycles the brute force skips: 1.5 times the model's, plus 100 (as in the tests)."""
    return (1.5 * np.asarray(cycles)).astype(int) + 100


def machine():
    """Cores, threads, load, versions and commit."""
    versions = provenance.package_versions()
    return {
        "cpu_count": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "processor": platform.processor() or platform.machine(),
        "python": versions["python"],
        "numpy": versions["numpy"],
        "numba": versions["numba"],
        "dem_version": versions["dem"],
        "git_commit": provenance.git_commit(),
        "load_average": provenance.load_average(),
    }


def main(argv=None):
    """Run the benchmark, print the table, write pointmass.json."""
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7, help="timed runs of the sweep")
    parser.add_argument("--target", type=float, default=1e-3, help="max abs error in v_norm")
    parser.add_argument("--out", type=Path, default=HERE / "pointmass.json")
    args = parser.parse_args(argv[1:])

    # 1. event-driven sweep
    start = time.perf_counter()
    reference = fig7_sweep()  # compiles (or loads the numba cache)
    first_call = time.perf_counter() - start
    sweep_times = timed(fig7_sweep, args.repeats)
    n_points = reference["velocity_norm"].size
    exact = reference["velocity_norm"]
    params = params_of(reference)
    transient = transient_of(reference["cycles"])
    t_event = min(sweep_times)

    # 2. brute force: error against step count
    brute(params[:2], steps=50, transient=transient[:2], measured=2)  # compile
    ladder = []
    for steps in LADDER:
        start = time.perf_counter()
        approx = brute(params, steps=int(steps), transient=transient, measured=MEASURED_CYCLES)
        seconds = time.perf_counter() - start
        error = np.abs(approx - exact)
        worst = int(np.argmax(error))
        ladder.append(
            {
                "steps_per_cycle": int(steps),
                "max_abs_error": float(error.max()),
                "median_abs_error": float(np.median(error)),
                "worst_angle": float(params[worst, 1]),
                "worst_friction": float(params[worst, 2]),
                "seconds": seconds,
            }
        )
        print(
            f"  brute force {steps:5d} steps/cycle: max |err| {error.max():.2e}, "
            f"median {np.median(error):.1e}, {seconds:.2f} s",
            flush=True,
        )
    ok = [row["max_abs_error"] <= args.target for row in ladder]
    coarsest = None
    for i in range(len(ladder)):
        if all(ok[i:]):
            coarsest = ladder[i]
            break
    speedup = None
    if coarsest is not None:
        steps = coarsest["steps_per_cycle"]
        brute_times = timed(
            lambda: brute(params, steps=steps, transient=transient, measured=MEASURED_CYCLES), 3
        )
        coarsest = {**coarsest, "seconds_best_of_3": min(brute_times)}
        speedup = min(brute_times) / t_event

    # 3. the tests' step count
    at_test = next(row for row in ladder if row["steps_per_cycle"] == TEST_STEPS)
    grid = _grid()
    model = velocities(*grid.T)
    periodic = model["periodic"]
    start = time.perf_counter()
    ref_grid = brute(
        grid[periodic],
        steps=TEST_STEPS,
        transient=transient_of(model["cycles"][periodic]),
        measured=MEASURED_CYCLES,
    )
    grid_seconds = time.perf_counter() - start
    grid_error = np.abs(ref_grid - model["velocity_norm"][periodic])
    worst = int(np.argmax(grid_error))

    report = {
        "date_utc": provenance.utc_now(),
        "command": shlex.join([sys.executable, *argv]),
        "machine": machine(),
        "fig7_sweep": {
            "points": n_points,
            "throw_number": FIG7_THROW_NUMBER,
            "frictions": list(FIG7_FRICTIONS),
            "angles": [float(FIG7_ANGLES[0]), float(FIG7_ANGLES[-1]), len(FIG7_ANGLES)],
            "first_call_seconds": first_call,
            "seconds_best": t_event,
            "seconds_median": statistics.median(sweep_times),
            "seconds_all": sweep_times,
            "points_per_second": n_points / t_event,
            "model_cycles_median": float(np.median(reference["cycles"])),
            "model_cycles_max": int(reference["cycles"].max()),
        },
        "brute_force": {
            "target_max_abs_error": args.target,
            "measured_cycles": MEASURED_CYCLES,
            "transient": "1.5 x model cycles + 100",
            "ladder": ladder,
            "coarsest_meeting_target": coarsest,
            "speedup_at_equal_accuracy": speedup,
            "at_test_steps_fig7": at_test,
            "test_grid": {
                "steps_per_cycle": TEST_STEPS,
                "points_compared": int(periodic.sum()),
                "points_total": int(periodic.size),
                "max_abs_error": float(grid_error.max()),
                "median_abs_error": float(np.median(grid_error)),
                "worst_point": grid[periodic][worst].tolist(),
                "seconds": grid_seconds,
            },
        },
    }
    args.out.write_text(json.dumps(report, indent=1) + "\n")

    s = report["fig7_sweep"]
    print()
    print(f"machine: {report['machine']['cpu_count']} cores, {s['points']} points")
    print("| quantity | value |")
    print("|---|---|")
    print(f"| Fig. 7 sweep, first call (compile or cache load) | {s['first_call_seconds']:.3f} s |")
    print(f"| Fig. 7 sweep, best of {args.repeats} | {s['seconds_best'] * 1e3:.1f} ms |")
    print(f"| Fig. 7 sweep, median | {s['seconds_median'] * 1e3:.1f} ms |")
    if coarsest is not None:
        print(
            f"| brute force, coarsest steps/cycle with max err <= {args.target:g} "
            f"| {coarsest['steps_per_cycle']} (max err {coarsest['max_abs_error']:.2e}) |"
        )
        print(f"| brute force time there, best of 3 | {coarsest['seconds_best_of_3']:.2f} s |")
        print(f"| speed-up at equal accuracy | {speedup:.0f}x |")
    else:
        print(f"| brute force | target {args.target:g} not met up to {LADDER[-1]} steps |")
    print(f"| brute force at {TEST_STEPS} steps, Fig. 7 max err | {at_test['max_abs_error']:.2e} |")
    g = report["brute_force"]["test_grid"]
    print(
        f"| brute force at {TEST_STEPS} steps, test grid max err "
        f"({g['points_compared']}/{g['points_total']} periodic points) "
        f"| {g['max_abs_error']:.2e} at {g['worst_point']} |"
    )
    print(f"written {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
