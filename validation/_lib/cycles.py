"""Drive cycles in steps: where each cycle ends, and a per-step series binned into cycles.

dem counts cycle c as the driven steps round(c P / dt) + 1 ... round((c + 1) P / dt), with
P = 1 / f the drive period and dt the time step (``dem.run.runner``,
``dem.engine.simulation.measure_cycles``). A reference run that samples every step (LIGGGHTS's
``vx_mean.txt`` at ``sample_steps = 1``) is binned into exactly these cycles, so that both codes
average over the same steps.
"""

from __future__ import annotations

import math

import numpy as np


def steps_per_cycle(case) -> float:
    """Time steps per drive period, P / dt (not rounded)."""
    return (1.0 / case.drive.frequency) / case.run.timestep


def cycle_edges(case, n_cycles: int) -> list[int]:
    """Driven-step index ending each cycle, round(c P / dt) for c = 0 .. n_cycles."""
    period = 1.0 / case.drive.frequency
    return [int(round(c * period / case.run.timestep)) for c in range(n_cycles + 1)]


def cycle_means(steps, values, edges, cycles, *, strict: bool = True, source: str = "") -> list:
    """Mean of ``values`` over the steps of each cycle in ``cycles``: (edges[k], edges[k + 1]].

    Args:
        steps: Driven-step index of each sample (0 when the drive starts), (n,).
        values: The samples, (n,).
        edges: :func:`cycle_edges`.
        cycles: The cycle indices k to average.
        strict: Every step of a cycle must have exactly one sample (SystemExit otherwise);
            if False, a cycle without samples gives nan.
        source: The file the samples came from, for the error message.

    """
    out = []
    for k in cycles:
        inside = (steps > edges[k]) & (steps <= edges[k + 1])
        if strict:
            expected = edges[k + 1] - edges[k]
            if inside.sum() != expected:
                raise SystemExit(f"cycle {k}: {inside.sum()} samples in {source}, not {expected}")
            out.append(float(values[inside].mean()))
        else:
            out.append(float(values[inside].mean()) if inside.any() else math.nan)
    return out


def drive_steps(data: np.ndarray, drive_start: int) -> tuple[np.ndarray, np.ndarray]:
    """A (step, value) table's driven-step indices (step - drive_start) and values."""
    return data[:, 0].astype(np.int64) - drive_start, data[:, 1]
