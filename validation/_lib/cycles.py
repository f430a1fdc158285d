"""Drive cycles in steps: where each cycle ends, and a per-step series binned into cycles.

dem counts cycle c as the driven steps round(c P / dt) + 1 ... round((c + 1) P / dt), with
P = 2 pi / omega the trough's drive period and dt the time step (``dem.run.runner``,
``dem.engine.simulation.measure_cycles``). A reference run that samples every step (LIGGGHTS's
``vx_mean.txt`` at ``sample_steps = 1``) is binned into exactly these cycles, so that both codes
average over the same steps.
"""

from __future__ import annotations

import math

import numpy as np

from dem.physics import drive
from dem.scene.trough import Trough


def steps_per_cycle(case) -> float:
    """Time steps per drive period, 1 / (f dt), not rounded (``drive.steps_per_cycle``)."""
    return drive.steps_per_cycle(case.drive.frequency, case.run.timestep)


def cycle_edges(case, n_cycles: int) -> list[int]:
    """Driven-step index ending each cycle c = 0 .. n_cycles, as dem's run counts them.

    :func:`dem.physics.drive.cycle_edge` with the trough's period 2 pi / omega, the period the
    runner and :func:`dem.engine.simulation.measure_cycles` use.
    """
    period = Trough.from_case(case).period
    return [drive.cycle_edge(0, c, period, case.run.timestep) for c in range(n_cycles + 1)]


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
