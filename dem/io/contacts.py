"""The contacts of a frame as files read them: kinds, and the trough's loads summed from them.

numpy only (the VTK and HDF5 writers, and readers, import it without numba). The rows are those
of :meth:`dem.engine.simulation.Simulation.contact_snapshot`: ``kind``, ``i``, ``j``, ``point``,
``normal``, ``normal_force``, ``tangential_force``, ``overlap``.
"""

from __future__ import annotations

import numpy as np

#: ``kind`` of a contact row, by index (:mod:`dem.kernels.snapshot`'s PAIR ... BACK): a pair, or
#: a sphere on the floor, a side wall (y < 0, y > 0), the back wall.
CONTACT_KINDS = ("pair", "floor", "side wall y-", "side wall y+", "back wall")
PAIR, FLOOR, WALL_LOW_Y, WALL_HIGH_Y, BACK = range(5)
#: The rows of a contact snapshot, as files store them.
CONTACT_ROW_NAMES = ("kind", "i", "j", "point", "normal", "normal_force", "tangential_force",
                     "overlap")  # fmt: skip


#: Names of :func:`wall_loads`' entries, in the order results.h5 and the VTK field data list them.
WALL_LOAD_NAMES = (
    "floor_normal_force", "side_wall_normal_force", "back_wall_normal_force",
    "floor_force_on_grains", "wall_force_on_grains",
)  # fmt: skip


def wall_loads(snapshot: dict) -> dict:
    """The trough's loads at one instant, summed over a contact snapshot's rows.

    (:meth:`dem.engine.simulation.Simulation.contact_snapshot`; ``kind`` indexes
    :data:`CONTACT_KINDS`.)

    ``floor_normal_force``, ``side_wall_normal_force`` (both side walls),
    ``back_wall_normal_force``: the sums of F_n (N, positive pushes the grain off the wall), shape
    (); the grains press on the wall with as much. ``floor_force_on_grains`` and
    ``wall_force_on_grains``: the total force (normal plus tangential) of the floor, and of every
    wall, on the grains, (3,) N in the trough frame (x along the trough, z normal to the floor): the
    floor's x component is the friction that conveys the bed. Averaged over a steady cycle the walls
    carry the bed's weight: the mean of ``wall_force_on_grains`` is minus the weight vector m g in
    the trough frame (the drive's inertial force averages to zero over a cycle, and the grains'
    momentum returns).
    """
    kind = np.asarray(snapshot["kind"])
    fn = np.asarray(snapshot["normal_force"], dtype=np.float64)
    total = fn[:, None] * np.asarray(snapshot["normal"], dtype=np.float64) + np.asarray(
        snapshot["tangential_force"], dtype=np.float64
    )
    side = (kind == WALL_LOW_Y) | (kind == WALL_HIGH_Y)
    return {
        "floor_normal_force": np.float64(fn[kind == FLOOR].sum()),
        "side_wall_normal_force": np.float64(fn[side].sum()),
        "back_wall_normal_force": np.float64(fn[kind == BACK].sum()),
        "floor_force_on_grains": total[kind == FLOOR].sum(axis=0).reshape(3),
        "wall_force_on_grains": total[kind != PAIR].sum(axis=0).reshape(3),
    }
