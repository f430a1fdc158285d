"""Readers of what a LIGGGHTS run of a deck writes: the feeder's balance and the log's lines.

A finite feeder's deck writes :data:`dem.io.liggghts.feeder.BALANCE_FILE`; :func:`read_balance`
reads it and :func:`discharge_per_cycle` turns it into the discharge rate per drive cycle. A
LIGGGHTS log prints its version in a banner (:func:`liggghts_version`) and one ``Loop time``
line per ``run`` command (:func:`loop_times`); a deck from
:func:`dem.io.liggghts.deck.write_deck` runs three, the last timing the measured steps alone.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

#: ``Loop time of T on P procs for S steps with N atoms`` of a LIGGGHTS log: (T, P, S, N).
LOOP_RE = re.compile(
    r"Loop time of ([0-9.eE+-]+) on (\d+) procs.*?for (\d+) steps with (\d+) atoms"
)
#: The version banner of a LIGGGHTS log.
VERSION_RE = re.compile(r"LIGGGHTS \(Version ([^,]+)")


class Balance(NamedTuple):
    """A finite feeder's balance from a LIGGGHTS run (:func:`read_balance`).

    Attributes:
        tau: Drive time of each line, s.
        in_trough: Grains in the box (spheres / members; a clump half past the edge counts
            by the fraction of its members left).
        fed: Grains fed so far.
        discharged: Grains discharged so far, charge + fed - in_trough.
        charge: The initial charge, grains.

    """

    tau: np.ndarray
    in_trough: np.ndarray
    fed: np.ndarray
    discharged: np.ndarray
    charge: float


def read_balance(path: str | Path, members: int) -> Balance:
    """Read the balance file of a feeder deck; ``members`` spheres make a grain.

    The file is :data:`dem.io.liggghts.feeder.BALANCE_FILE` of the run's directory.
    """
    data = np.loadtxt(path, comments="#", ndmin=2)
    if data.shape[0] == 0 or data.shape[1] != 4:
        raise ValueError(f"{path}: no balance lines (tau, spheres, fed, charge)")
    tau, spheres, fed, charge = data.T
    in_trough = spheres / members
    c = float(charge[0]) / members
    return Balance(tau, in_trough, fed, c + fed - in_trough, c)


def discharge_per_cycle(balance: Balance, period: float, start: float, grain_mass: float):
    """Discharge rate per whole drive cycle from ``start`` (s), kg/s, and mean grains held.

    Cycle k covers [start + k T, start + (k+1) T); the discharged count is interpolated
    linearly to the cycle bounds (lines come every sample window).
    """
    end = float(balance.tau[-1])
    cycles = int(math.floor((end - start) / period + 1e-9))
    bounds = start + period * np.arange(cycles + 1)
    out = np.interp(bounds, balance.tau, balance.discharged)
    rates = np.diff(out) * grain_mass / period
    held = np.interp(bounds, balance.tau, balance.in_trough)
    return rates, float(np.mean(held))


class LoopTime(NamedTuple):
    """One ``Loop time of T on P procs for S steps with N atoms`` line of a LIGGGHTS log.

    Attributes:
        seconds: T, wall time of that ``run`` command's step loop, s.
        procs: P, MPI ranks.
        steps: S, time steps of that ``run``.
        atoms: N, spheres at its end (clump members under ``fix multisphere``).

    """

    seconds: float
    procs: int
    steps: int
    atoms: int


def liggghts_version(stdout: str) -> str | None:
    """The version in the banner ``LIGGGHTS (Version V, ...)`` of a log, or None."""
    found = VERSION_RE.search(stdout)
    return found.group(1) if found else None


def loop_times(stdout: str) -> list[LoopTime]:
    """Every ``Loop time of T on P procs for S steps with N atoms`` line of a log, in order."""
    return [LoopTime(float(t), int(p), int(s), int(n)) for t, p, s, n in LOOP_RE.findall(stdout)]
