"""A finite feeder: a trough with a closed back end, a discharge edge and a feed.

A linear feeder is a trough of length L with a back wall at x = 0 and an open end at x = L
where the product falls into a hopper. ``[feeder]`` in a case turns the periodic section into
one (README, A DEM run):

- **Back wall**: the plane x = 0 (inward normal +x), a fourth flat wall of the kernel with the
  same contact law as the floor (:func:`dem.kernels.forces.wall_forces`); with a trough mesh it
  closes the pan as well.
- **Discharge**: a grain whose centre of mass has passed x = L has left the trough: it is removed
  and its mass counted as discharged, at its drive time. The floor (or the mesh) ends at the
  edge, so the grain is counted when it tips over the lip, not when it lands in the hopper.
- **Feed**: ``feed_rate`` (kg/s) of grains inserted at the back, as a hopper outlet would drop
  them: at random in the feed zone 0 < x < ``feed_length``, across the trough, at the height of
  the grains already there (within half a grain's bounding radius, above the floor) where they
  touch none, at rest in the laboratory (velocity -s'(t) in the trough frame). Grains owed but
  without room (the trough backs up to the hopper) wait and are counted as a backlog. Without a
  feed rate the initial charge (``particles.count``) is emptied by the drive.

The kernels stay periodic, over a domain of length L + gap (:func:`domain_gap`): the gap is
empty (grains are removed once past L) and wide enough that no grain near the back wall and no
grain at the edge can see each other through the periodic image. Grains are exchanged at most
every :data:`EXCHANGE_FRACTION` of a drive period (:attr:`Feeder.interval`), and only when one
leaves or arrives, each exchange O(n) (:meth:`dem.engine.simulation.Simulation.replace_grains`).

Conservation: grains inserted (the initial charge plus the feed) = grains in the trough +
grains discharged, at every moment (:meth:`Feeder.balance`); ``dem run`` stores the three in
every frame of results.h5.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from dem.engine.state import Bodies, Spheres

#: Grains are exchanged at most every this fraction of a drive period.
EXCHANGE_FRACTION = 1.0 / 16.0
#: Tries to place one fed grain before it waits for the next exchange.
FEED_TRIES = 40
#: Fed grains start at rest in the laboratory (velocity -s'(t) in the trough's frame), as a
#: hopper drops them. False starts them at rest in the trough's frame, as LIGGGHTS's
#: ``insert/rate/region ... vel constant 0 0 0`` does in the accelerating frame of an exported
#: deck: validation/liggghts-feeder sets it to measure what the convention changes.
FEED_AT_LAB_REST = True


def domain_gap(bound: float, r_max: float, skin: float, travel: float) -> float:
    """Empty length behind the discharge edge, m.

    A grain at the back wall reaches x >= -overlap, a grain still counted at the edge (centre
    of mass up to L plus what it travels between two exchanges) reaches L + travel + ``bound``.
    Through the periodic image they must stay further apart than the pair cutoff
    2 ``r_max`` + ``skin``: gap = 2 (``bound`` + 2 ``r_max`` + ``skin``) + ``travel``, with
    ``bound`` the grain's bounding radius.
    """
    return 2.0 * (bound + 2.0 * r_max + skin) + travel


@dataclass
class Feeder:
    """State and bookkeeping of a finite feeder (see the module docstring).

    Attributes:
        discharge: x of the discharge edge L, m.
        width: Trough width (the flat walls' y extent), m; for a mesh the mesh's y extent.
        feed_rate: Mass fed per second, kg/s (0: none).
        feed_length: Length of the feed zone at the back, m.
        grain_mass: Mass of one grain, kg.
        bound: Bounding radius of a grain about its centre of mass, m.
        interval: Steps between exchanges.
        make: Callable (positions (k, 3), orientations (k, 4) or None) -> (Spheres, Bodies or
            None): new grains at rest.
        random: Generator of the feed positions and orientations (seeded from the case).
        floor: Lowest z of the trough, m (0 for the flat floor, the mesh's bottom otherwise).
        inside: Callable (points (k, 3), clearance) -> bool (k,): inside a mesh pan (None:
            flat walls).
        inserted, discharged: Grains so far (the initial charge counts as inserted).
        inserted_mass, discharged_mass: Their mass, kg.
        owed: Grains due by the feed rate and not yet placed (fractional).
        next_id: The id the next fed grain gets (after every id the fill gave, spilled ones
            included: an id is never reused).
        events: Discharges as (drive time s, mass kg), cleared by :meth:`take_events`.

    """

    discharge: float
    width: float
    feed_rate: float
    feed_length: float
    grain_mass: float
    bound: float
    interval: int
    make: Callable[[np.ndarray, np.ndarray | None], tuple[Spheres, Bodies | None]]
    random: np.random.Generator
    floor: float = 0.0
    inside: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
    inserted: int = 0
    discharged: int = 0
    inserted_mass: float = 0.0
    discharged_mass: float = 0.0
    owed: float = 0.0
    next_id: int = 0
    last_time: float = 0.0
    started: bool = False
    spilled: int = 0
    events: list = field(default_factory=list)

    def start(self, sim) -> None:
        """Count the grains in the trough as the initial charge (the drive starts now)."""
        self.started = True
        self.inserted = sim.n_grains
        self.inserted_mass = sim.total_mass
        self.last_time = 0.0

    @property
    def backlog(self) -> int:
        """Whole grains owed by the feed that found no room yet."""
        return int(self.owed)

    def balance(self, sim) -> tuple[int, int, int]:
        """(inserted, in the trough, discharged): the first is the sum of the others."""
        return self.inserted, sim.n_grains, self.discharged

    def exchange(self, sim) -> None:
        """Remove the grains past the discharge edge, then feed the grains now due.

        Before the drive starts (the fill settling) grains that flow over the edge are removed
        too, as ``spilled``: the initial charge is what the trough holds when the drive starts.
        """
        centres = sim.spheres.x if sim.bodies is None else sim.bodies.x
        leaving = centres[:, 0] > self.discharge
        if not self.started:
            if leaving.any():
                self.spilled += int(leaving.sum())
                sim.replace_grains(~leaving)
            return
        t = sim.drive_time
        self.owed += self.feed_rate * max(t - self.last_time, 0.0) / self.grain_mass
        self.last_time = t
        due = int(self.owed)
        if not leaving.any() and due == 0:
            return
        gone = int(leaving.sum())
        if gone:
            self.discharged += gone
            mass = gone * self.grain_mass
            self.discharged_mass += mass
            self.events.append((t, mass))
        new_spheres = new_bodies = None
        ids = None
        if due:
            positions, quats = self._place(sim, due, ~leaving)
            k = positions.shape[0]
            if k:
                new_spheres, new_bodies = self.make(positions, quats)
                lab_rest = -sim.trough.velocity(t) if FEED_AT_LAB_REST else np.zeros(3)
                if new_bodies is None:
                    new_spheres.v[:] = lab_rest
                else:
                    new_bodies.v[:] = lab_rest
                    new_bodies.place(new_spheres)
                ids = np.arange(self.next_id, self.next_id + k, dtype=np.int64)
                self.next_id += k
                self.inserted += k
                self.inserted_mass += k * self.grain_mass
                self.owed -= k
        if gone or new_spheres is not None:
            sim.replace_grains(~leaving, new_spheres, new_bodies, ids)

    def _place(self, sim, count: int, kept: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Up to ``count`` free poses in the feed zone, at the height of the grains there."""
        from dem.scene.fill import random_orientations

        s = sim.spheres
        b = self.bound
        member_kept = kept if sim.bodies is None else kept[s.body]
        near = member_kept & (s.x[:, 0] < self.feed_length + 2.0 * b)
        xs, rs = s.x[near], s.radius[near]
        top = float(np.max(xs[:, 2] + rs)) if xs.shape[0] else self.floor
        top = max(top, self.floor)
        clumps = sim.bodies is not None
        placed: list[np.ndarray] = []
        quats: list[np.ndarray] = []
        members_x: list[np.ndarray] = [xs]
        members_r: list[np.ndarray] = [rs]
        half = 0.5 * self.width
        x_hi = max(self.feed_length - b, b + 1e-12)
        for _ in range(count):
            for _try in range(FEED_TRIES):
                centre = np.array([
                    self.random.uniform(b, x_hi),
                    self.random.uniform(-half + b, half - b) if half > b else 0.0,
                    max(top + self.random.uniform(-0.5, 0.5) * b, self.floor + b),
                ])  # fmt: skip
                q = None
                if clumps:
                    q = random_orientations(1, self.random)
                    trial_s, _ = self.make(centre[None, :], q)
                    px, pr = trial_s.x, trial_s.radius
                else:
                    px, pr = centre[None, :], np.array([b])
                if np.any(px[:, 2] - pr < self.floor):
                    continue
                if self.inside is not None and not np.all(self.inside(px, pr)):
                    continue
                if not _clear(px, pr, np.concatenate(members_x), np.concatenate(members_r)):
                    continue
                placed.append(centre)
                if clumps:
                    assert q is not None, "drawn above for clumps"
                    quats.append(q[0])
                members_x.append(px)
                members_r.append(pr)
                break
        if not placed:
            return np.zeros((0, 3)), None
        return np.array(placed), (np.array(quats) if clumps else None)

    def take_events(self) -> list[tuple[float, float]]:
        """The discharges since the last call, (drive time s, mass kg), and forget them."""
        out, self.events = self.events, []
        return out

    def state(self) -> dict:
        """The counters and the generator's state, JSON-serialisable (for a checkpoint)."""
        return {
            "inserted": self.inserted, "discharged": self.discharged,
            "inserted_mass": self.inserted_mass, "discharged_mass": self.discharged_mass,
            "owed": self.owed, "next_id": self.next_id, "last_time": self.last_time,
            "started": self.started, "spilled": self.spilled,
            "random": self.random.bit_generator.state,
        }  # fmt: skip

    def restore(self, state: dict) -> None:
        """Undo :meth:`state`."""
        for key in ("inserted", "discharged", "inserted_mass", "discharged_mass", "owed",
                    "next_id", "last_time", "started", "spilled"):  # fmt: skip
            setattr(self, key, type(getattr(self, key))(state[key]))
        self.random.bit_generator.state = state["random"]


def _clear(px, pr, x, r) -> bool:
    """Whether spheres (px, pr) overlap none of the spheres (x, r) (brute force)."""
    if x.shape[0] == 0:
        return True
    d = px[:, None, :] - x[None, :, :]
    dist2 = np.einsum("ijk,ijk->ij", d, d)
    return bool(np.all(dist2 >= (pr[:, None] + r[None, :]) ** 2))


def grain_factory(case):
    """``make(positions, orientations)`` -> new grains at rest of the case's grain."""
    pt, mat = case.particles, case.material

    def make(positions, quats):
        positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        if not pt.clumps:
            return Spheres.create(positions, pt.radius, mat.density), None
        bodies, spheres = Bodies.create(pt.grain, positions, quats)
        return spheres, bodies

    return make


def grain_mass(case) -> float:
    """Mass of one grain of the case, kg (:attr:`dem.scene.resolved.Scene.grain_mass`)."""
    from dem.scene.resolved import resolve

    return resolve(case).grain_mass
