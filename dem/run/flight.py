"""The grains in flight by phase of the drive: what the bed does, beside what it conveys.

With ``output.flight_phases = K`` a run, after its measured cycles, runs
:data:`dem.config.DEM_FLIGHT_CYCLES` more cycles in K chunks each and at the end of every chunk
counts the grains that touch nothing (no neighbour, no wall: every member sphere of a clump
free). The summary's ``flight`` gives, per phase bin (its end, in degrees of the drive from its
start at phase 0), the fraction of grains in flight averaged over those cycles. A point mass in
the hopping regime is in flight between its take-off and landing phases; a bed is partly in
flight where its grains collide among themselves or the bed leaves the floor as a block.

These cycles come after the measurement, so the measured velocity and its error are those of a
run without them (bit for bit); they cost DEM_FLIGHT_CYCLES / (settle + measured) of the run.
"""

from __future__ import annotations

import numpy as np

from dem import config
from dem.physics.drive import cycle_edge


def in_flight(sim) -> float:
    """The fraction of grains touching nothing now (:meth:`Simulation.contact_counts`)."""
    counts = sim.contact_counts()
    per_grain = np.bincount(sim.spheres.body, weights=counts, minlength=sim.n_grains)
    return float(np.mean(per_grain[: sim.n_grains] == 0))


def by_phase(sim, case) -> dict | None:
    """Run the sampling cycles and return the summary's ``flight`` (None when not asked)."""
    phases = case.output.flight_phases
    if not phases:
        return None
    cycles = config.DEM_FLIGHT_CYCLES
    period = sim.trough.period
    start = (sim.step_index - sim.drive_start_step) * sim.dt / period  # whole cycles so far
    first = round(start)
    sums = np.zeros(phases)
    for c in range(cycles):
        for k in range(phases):
            end = cycle_edge(sim.drive_start_step, first + c + (k + 1) / phases, period, sim.dt)
            sim.run(end - sim.step_index)
            sums[k] += in_flight(sim)
    return {
        "phase_deg": [360.0 * (k + 1) / phases for k in range(phases)],
        "fraction": [float(x) for x in sums / cycles],
        "cycles": cycles,
        "what": f"fraction of grains touching nothing at the end of each of {phases} phase "
        f"bins, averaged over {cycles} cycles run after the measured ones",
    }


def not_sampled(case, why: str) -> dict | None:
    """The summary's ``flight`` where a run cannot take the sampling cycles (None if not asked)."""
    if not case.output.flight_phases:
        return None
    return {"phase_deg": None, "fraction": None, "cycles": 0, "what": f"not sampled: {why}"}
