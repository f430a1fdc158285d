"""The feed and the balance of a finite feeder's deck (``[feeder]``, :mod:`dem.engine.feeder`).

The box is closed across y and z and open along x (``boundary f f f``) from a margin behind the
back wall to the discharge edge x = L (:func:`dem.io.liggghts.geometry.layout`); a sphere whose
centre passes L leaves the box and LIGGGHTS deletes it (``thermo_modify lost ignore``), as dem
removes a grain whose centre of mass passes L. A clump goes as a whole in LIGGGHTS, when its
first member's centre passes L (``fix multisphere`` deletes a body that has lost an atom: the
balance's sphere count stays a multiple of the members), so it leaves earlier than in dem,
which waits for its centre of mass. The back wall is ``wall/gran primitive xplane 0.0``, with a
mesh too, as dem's fourth flat wall. The fill is insert/pack in [reach, L - reach], as dem's.
The feed is ``insert/rate/region`` (:func:`feeder_lines`): one grain every m / feed_rate into
the zone 0 < x < ``feed_length``, at rest in the trough's frame (dem drops fed grains at rest in
the laboratory, -s'(t) in the trough's frame: at most A omega apart). ``balance.txt`` records
the spheres in the box, the grains fed and the initial charge;
:func:`dem.io.liggghts.readers.read_balance` and
:func:`dem.io.liggghts.readers.discharge_per_cycle` turn them into grains discharged and the
discharge rate per drive cycle.
"""

from __future__ import annotations

from dem.io.liggghts.geometry import placement
from dem.io.liggghts.text import fmt
from dem.scene.resolved import Scene

#: File a finite feeder's deck writes its balance to
#: (:func:`dem.io.liggghts.readers.read_balance`).
BALANCE_FILE = "balance.txt"


def feeder_lines(
    scene: Scene,
    timestep: float,
    fill_y: tuple[float, float],
    fill_z0: float,
    fill_height: float,
    members: int,
    *,
    s_feed: int,
    sample_steps: int,
    drive_start: int,
) -> tuple[list[str], list[str]]:
    """The feed and the balance output of a finite feeder's deck, and the header lines on them.

    The feed is ``insert/rate/region`` of ``feed_rate`` kg/s into the zone 0 < x <
    ``feed_length`` over the fill block's y range, from the fill block's bottom up as high as
    the loose fill column, one grain every m / feed_rate (at least every
    :data:`dem.engine.feeder.EXCHANGE_FRACTION` of a drive period, as dem exchanges), the first one
    m / feed_rate after the drive starts (as dem, which feeds a grain once a whole one is owed;
    LIGGGHTS would insert one at once), at rest in the trough's frame. :data:`BALANCE_FILE`
    gets, every ``sample_steps``, the drive time tau (s), the spheres in the box (a grain of k
    members counts k), the grains fed so far and the initial charge in spheres: grains
    discharged = charge + fed - in the box, per
    :func:`dem.io.liggghts.readers.read_balance`.
    """
    from dem.engine.feeder import EXCHANGE_FRACTION

    case = scene.case
    f, d = case.feeder, case.drive
    assert f is not None  # written only for a case with a [feeder]
    # one grain per insertion, as dem feeds a grain whenever a whole one is owed (checked
    # every EXCHANGE_FRACTION of a period): LIGGGHTS's massrate rounds a fraction of a grain
    # per insertion down and feeds 10 % short (measured on cases/feeder, every 1/16 cycle)
    exchange = max(1, round(EXCHANGE_FRACTION / (d.frequency * timestep)))
    grain = scene.grain_mass
    every = max(exchange, round(grain / (f.feed_rate * timestep))) if f.feed_rate > 0 else 0
    keywords = placement(case)
    p = case.particles
    if not p.clumps:  # all_in keeps the sphere in the zone
        x0, x1 = 0.0, f.feed_length
    else:  # the zone holds centres of mass (placement), as dem's feed does
        reach = p.grain.bounding_radius
        x0, x1 = reach, max(f.feed_length - reach, reach + 1e-6)
    lines = [
        "# finite feeder: grains fed at the back; a sphere past x = L is deleted (lost)",
        "variable charge equal ${natoms0}",
    ]
    fed = "0"
    if f.feed_rate > 0.0:
        lines += [
            f"region feedzone block {fmt(x0)} {fmt(x1)} {fmt(fill_y[0])} "
            f"{fmt(fill_y[1])} {fmt(fill_z0)} {fmt(fill_z0 + fill_height)} units box",
            f"fix feed all insert/rate/region seed {s_feed} distributiontemplate pdd "
            f"nparticles INF massrate {fmt(f.feed_rate)} insert_every {every} "
            f"start {drive_start + every} "
            f"overlapcheck yes{keywords} vel constant 0.0 0.0 0.0 region feedzone",
        ]
        fed = "$(f_feed[1])"
    lines += [
        f'fix balance all print {sample_steps} "$(v_tau) $(atoms) {fed} ${{charge}}" '
        f'file {BALANCE_FILE} screen no title "# tau (s), spheres in the box, grains fed, '
        f'initial charge (spheres); {members} spheres a grain"',
    ]
    note = [
        "# finite feeder: back wall x = 0 (primitive, also with a mesh), open discharge edge",
        f"#   x = L (a sphere past it leaves the box and is deleted); feed {f.feed_rate} kg/s "
        f"into 0 < x < {f.feed_length} m at rest in the trough frame (dem: at rest in the lab);",
        f"#   {BALANCE_FILE}: tau, spheres in the box, grains fed, initial charge. A clump is",
        "#   deleted whole when its first member passes the edge (dem removes the grain when",
        "#   its centre of mass passes it)",
    ]
    return lines, note
