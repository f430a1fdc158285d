"""The default thread count against one thread, fill to summary, beside 0, 1 and 3 busy processes.

    .venv/bin/python validation/performance/threads_busy.py [--repeat 2] [--busy 0,1,3]
        [--cases sphere-bed,screw-trough] [--cycles N]

What a user on a shared workstation gets from ``dem run CASE`` (no ``--threads``: the default,
all cores, with the thread guard) against ``dem run CASE --threads 1``: the wall time of the
whole command, in a fresh process (import, cache load, fill, settle, settling and measured
cycles, summary), with ``--no-frames`` and one fill (``--replicas 1``: the shipped beds pool
three fills, which run as processes side by side, not as threads). Busy processes are Python
loops (``while True: pass``), started a second before the measured command and killed after it.
The configurations alternate (default, one thread, default, ...) within each busy level and
case, so slow drifts of the machine's load fall on both; the 1-minute load average is recorded
before each command.

Both commands must report the same per-cycle velocity to the last bit (the guard changes only the
wall time); the script stops if they do not. Writes threads_busy.json and threads_busy.csv (one
row per command) and prints, per case and busy level, the median of one thread's wall time over
the default's (the default's speed as a fraction of one thread's; >= 0.95 is the requirement).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CONFIGS = {"default": [], "1 thread": ["--threads", "1"]}


def run(case: str, extra: list[str], out: Path, cycles: int | None) -> tuple[float, dict]:
    """Wall time of one ``dem run`` and its summary."""
    if out.exists():
        shutil.rmtree(out)
    dem = str(Path(sys.executable).with_name("dem"))
    # one fill: the shipped beds pool three (run.replicas), which run as processes, not threads
    cmd = [dem, "run", str(ROOT / "cases" / case), "--out", str(out), "--no-frames",
           "--replicas", "1", *extra]  # fmt: skip
    if cycles is not None:
        cmd += ["--cycles", str(cycles)]
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    return wall, json.loads((out / "summary.json").read_text())


def _slowdown(seconds_per_step: dict) -> float:
    """Seconds per step on N threads over one, as the guard last timed them (NaN if untimed)."""
    one = seconds_per_step.get("1")
    many = [v for k, v in seconds_per_step.items() if k != "1"]
    return many[0] / one if one and many else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--busy", default="0,1,3", help="busy processes beside the run")
    parser.add_argument("--cases", default="sphere-bed,screw-trough")
    parser.add_argument("--cycles", type=int, help="measured cycles (default: the case's)")
    args = parser.parse_args()
    scratch = HERE / "scratch" / "threads_busy"
    scratch.mkdir(parents=True, exist_ok=True)
    cases = args.cases.split(",")
    levels = [int(b) for b in args.busy.split(",")]
    for case in cases:  # compile once, untimed, so that no measured command pays for it
        run(case, ["--threads", "1"], scratch / "warm", 1)
    rows = []
    for case in cases:
        for busy in levels:
            hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                    for _ in range(busy)]  # fmt: skip
            time.sleep(1.0 if busy else 0.0)
            try:
                for rep in range(args.repeat):
                    velocities = {}
                    order = list(CONFIGS) if rep % 2 == 0 else list(CONFIGS)[::-1]
                    for name in order:
                        load = os.getloadavg()[0]
                        wall, s = run(case, CONFIGS[name], scratch / "run", args.cycles)
                        guard = s.get("thread_guard") or {}
                        velocities[name] = s["per_cycle_velocity"]
                        rows.append({
                            "case": case, "busy_processes": busy, "repeat": rep,
                            "config": name, "threads": s["threads"],
                            "wall_time_s": round(wall, 2),
                            "fraction_on_one_thread": round(
                                guard.get("fraction_on_one_thread", 0.0), 3),
                            "slowdown_n_threads_over_1": round(
                                _slowdown(guard.get("seconds_per_step", {})), 2),
                            "settle_wall_s": round(s["settle_wall_time_s"], 2),
                            "cycles_wall_s": round(s["wall_time_s"], 2),
                            "load_1min_before": round(load, 2),
                            "velocity_m_per_s": s["mean_velocity"],
                        })  # fmt: skip
                        print(f"{case:13s} busy {busy}  {name:9s} {wall:7.1f} s  "
                              f"one-thread share {rows[-1]['fraction_on_one_thread']:.2f}  "
                              f"(load {load:.2f})", flush=True)  # fmt: skip
                    if velocities["default"] != velocities["1 thread"]:
                        raise SystemExit(f"{case}: the default and one thread report different "
                                         "per-cycle velocities")  # fmt: skip
            finally:
                for h in hogs:
                    h.kill()
                    h.wait()
    table = []
    print(f"\n{'case':13s} {'busy':>4s} {'1 thread (s)':>13s} {'default (s)':>12s} "
          f"{'default speed / 1 thread':>25s}")  # fmt: skip
    for case in cases:
        for busy in levels:
            sel = [r for r in rows if r["case"] == case and r["busy_processes"] == busy]
            one = [r["wall_time_s"] for r in sel if r["config"] == "1 thread"]
            dflt = [r["wall_time_s"] for r in sel if r["config"] == "default"]
            ratios = [a / b for a, b in zip(one, dflt, strict=True)]
            table.append({"case": case, "busy_processes": busy,
                          "one_thread_s": statistics.median(one),
                          "default_s": statistics.median(dflt),
                          "ratio_median": statistics.median(ratios),
                          "ratio_min": min(ratios), "ratio_max": max(ratios)})  # fmt: skip
            t = table[-1]
            print(
                f"{case:13s} {busy:4d} {t['one_thread_s']:13.1f} {t['default_s']:12.1f} "
                f"{t['ratio_median']:12.2f} ({t['ratio_min']:.2f}-{t['ratio_max']:.2f})"
            )
    from dem import provenance

    with open(HERE / "threads_busy.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    (HERE / "threads_busy.json").write_text(json.dumps(
        {"provenance": provenance.record(), "command": " ".join(sys.argv),
         "cycles": args.cycles, "table": table}, indent=1) + "\n")  # fmt: skip
    print("wrote threads_busy.json, threads_busy.csv")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
