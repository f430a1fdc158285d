"""LIGGGHTS-PUBLIC 3.8: a case exported as an equivalent deck, LIGGGHTS run on it, its output read.

:mod:`~dem.io.liggghts.deck` writes the deck block by block (:func:`write_deck`), with the walls
and insertion block of :mod:`~dem.io.liggghts.geometry`, the contact law of
:mod:`~dem.io.liggghts.contact`, the drive of :mod:`~dem.io.liggghts.drive` and a feeder's
feed of :mod:`~dem.io.liggghts.feeder`; :mod:`~dem.io.liggghts.export` chooses the step and the
settling as ``dem export liggghts`` does; :mod:`~dem.io.liggghts.launcher` runs LIGGGHTS and
:mod:`~dem.io.liggghts.readers` reads what it writes. The names below are the public ones.
"""

from dem.io.liggghts.contact import MIN_HERTZ_RESTITUTION, damping_ratio
from dem.io.liggghts.deck import (
    CLUMP_FILE,
    DECK_NAME,
    DUMP_FILES,
    VX_FILE,
    write_clump,
    write_deck,
)
from dem.io.liggghts.feeder import BALANCE_FILE
from dem.io.liggghts.geometry import MESH_FILE, mesh_fill_block, min_angle_deg, strip_top, write_stl
from dem.io.liggghts.launcher import (
    LIGGGHTS_INSTALL,
    LIGGGHTS_STDOUT,
    LiggghtsError,
    LiggghtsRun,
    find_liggghts,
    machine_info,
    run_liggghts,
)
from dem.io.liggghts.readers import (
    Balance,
    LoopTime,
    discharge_per_cycle,
    liggghts_version,
    loop_times,
    read_balance,
)

__all__ = [
    "BALANCE_FILE",
    "CLUMP_FILE",
    "DECK_NAME",
    "DUMP_FILES",
    "LIGGGHTS_INSTALL",
    "LIGGGHTS_STDOUT",
    "MESH_FILE",
    "MIN_HERTZ_RESTITUTION",
    "VX_FILE",
    "Balance",
    "LiggghtsError",
    "LiggghtsRun",
    "LoopTime",
    "damping_ratio",
    "discharge_per_cycle",
    "find_liggghts",
    "liggghts_version",
    "loop_times",
    "machine_info",
    "mesh_fill_block",
    "min_angle_deg",
    "read_balance",
    "run_liggghts",
    "strip_top",
    "write_clump",
    "write_deck",
    "write_stl",
]
