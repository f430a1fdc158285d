"""The instability checks of the step loop, and the record of the deepest overlap.

:class:`InstabilityChecks` is the part of :class:`dem.engine.simulation.Simulation` that
:meth:`~InstabilityChecks.check` runs every ``DEM_CHECK_INTERVAL`` steps: it raises
:class:`dem.errors.SimulationError` on non-finite values, a speed no drive and gravity explain (or
a bed running away downhill), an overlap beyond ``DEM_MAX_OVERLAP_FRACTION`` of the radius or
growing at consecutive checks, and a grain whose centre left the trough, naming the measured
cause, the grain, where and when, and the fix. It also keeps the running maximum overlap that
summary.json reports (:meth:`~InstabilityChecks.overlap_summary`); one above
``DEM_OVERLAP_WARN_FRACTION`` is a warning, not a stop. The methods read the simulation's
state (``spheres``, ``pairs``, ``trough``, ``mesh``, ``law``, ``dt``, ``time``, ``drive_on``)
and keep their records in ``_max_overlap`` and ``_growth``, which ``Simulation.__init__`` sets.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from dem import config
from dem.errors import SimulationError
from dem.scene.trough import WALLS

if TYPE_CHECKING:
    from dem.engine.door import Engine
    from dem.engine.state import Bodies, Spheres
    from dem.scene.mesh import TriangleMesh
    from dem.scene.timestep import ContactLaw
    from dem.scene.trough import Trough


class InstabilityChecks:
    """The instability checks and overlap record of a :class:`~dem.engine.simulation.Simulation`.

    A mixin: it holds no state of its own; the simulation's attributes are what it checks.
    The annotations below name them for the type checker (``Simulation.__init__`` sets them).
    """

    spheres: Spheres
    bodies: Bodies | None
    trough: Trough
    mesh: TriangleMesh | None
    law: ContactLaw
    dt: float
    timestep_limit: float
    rotation: bool
    drive_on: bool
    step_index: int
    reference_speed: float
    gravity: np.ndarray
    grain_id: np.ndarray
    #: The deepest overlap seen at the checks (:meth:`overlap_summary`'s record).
    _max_overlap: dict[str, Any]
    #: (contact, its fractions at consecutive checks) above the accuracy bound, or None.
    _growth: tuple[str, list[float]] | None
    #: A trough mesh's bounding box (lowest corner, highest corner), m; None: flat walls.
    _mesh_box: tuple[np.ndarray, np.ndarray] | None
    #: The height above which a grain is far above the trough, m.
    _ceiling: float

    if TYPE_CHECKING:  # the simulation's, declared for the type checker only

        @property
        def engine(self) -> Engine:
            """:attr:`dem.engine.simulation.Simulation.engine`."""

        @property
        def time(self) -> float:
            """:attr:`dem.engine.simulation.Simulation.time`."""

        def wall_gaps(self, x: np.ndarray) -> np.ndarray:
            """:meth:`dem.engine.simulation.Simulation.wall_gaps`."""

        def mean_velocity_x(self) -> float:
            """:meth:`dem.engine.simulation.Simulation.mean_velocity_x`."""

    def max_overlap_fraction(self) -> float:
        """Largest overlap over the smaller radius, pairs and walls (0 if nothing touches)."""
        return self._deepest()[0]

    def _deepest(self) -> tuple[float, int, str, np.ndarray]:
        """The deepest overlap now: (fraction of the smaller radius, sphere, what, point).

        ``what`` is ``"grain K"`` or a wall's name, ``point`` the contact point (3,), m (against
        a trough mesh, the grain's centre); (0, -1, "", nan) if nothing touches. O(spheres + pairs).
        """
        s = self.spheres
        r = s.radius
        worst, sphere, other, point = 0.0, -1, "", np.full(3, np.nan)
        i, j = self.engine.deepest_pair()  # on a GPU found there: no pair list to copy
        if i.shape[0]:
            d = self.trough.minimum_image(s.x[i] - s.x[j])
            dist = np.sqrt(np.einsum("ij,ij->i", d, d))
            frac = (r[i] + r[j] - dist) / np.minimum(r[i], r[j])
            m = int(np.argmax(frac))
            if frac[m] > worst:
                a, b = int(i[m]), int(j[m])
                worst, sphere = float(frac[m]), a
                other = f"grain {self.grain_id[s.body[b]]}"
                point = s.x[b] + d[m] * r[b] / (r[a] + r[b])
        gaps = self.wall_gaps(s.x)
        frac = (r - gaps) / r
        w, m = map(int, np.unravel_index(int(np.argmax(frac)), frac.shape))
        if frac[w, m] > worst:
            worst, sphere, other, point = float(frac[w, m]), int(m), self._wall_name(int(w)), s.x[m]
            if self.mesh is None or w == 1:  # a flat wall: the point on it (a mesh: the centre)
                point = s.x[m] - np.array(WALLS[3 if self.mesh is not None else w][1]) * gaps[w, m]
        return worst, sphere, other, np.array(point, dtype=np.float64)

    def _wall_name(self, row: int) -> str:
        """The wall of row ``row`` of :meth:`wall_gaps`."""
        if self.mesh is None:
            return WALLS[row][0]
        return "trough mesh" if row == 0 else WALLS[3][0]

    def _grain(self, sphere: int) -> int:
        """Lasting id of the grain that owns ``sphere``."""
        return int(self.grain_id[self.spheres.body[sphere]])

    def _when(self) -> str:
        phase = "drive on" if self.drive_on else "drive off"
        return f"at t = {self.time:.6g} s (step {self.step_index}, {phase}, dt = {self.dt:.3g} s)"

    def _step_fix(self) -> str:
        """The fix for an integration out of its stable range: a shorter step, and where dt is."""
        limit = self.timestep_limit
        where = f"dt = {self.dt:.3g} s"
        if math.isfinite(limit) and limit > 0.0:
            where += f", {self.dt / limit:.2g} of the stability limit {limit:.3g} s"
        return f"use a smaller run.timestep ({where}), or 'auto'"

    def _stiffer(self, fraction: float) -> tuple[str, float]:
        """The contact key and value that bring ``fraction`` radii to DEM_OVERLAP_WARN_FRACTION.

        Impacts scale the overlap as k^(-1/2) (linear) and E^(-2/5) (Hertz), a resting load as
        k^-1 and E^(-2/3): the impact exponent suffices for both.
        """
        ratio = max(fraction / config.DEM_OVERLAP_WARN_FRACTION, 1.0)
        return self.law.stiffer(ratio)

    @staticmethod
    def _at(x) -> str:
        return "(x, y, z) = ({:.4g}, {:.4g}, {:.4g}) mm".format(*(1e3 * np.asarray(x)))

    def overlap_summary(self) -> dict:
        """The running maximum overlap, sampled at every check, as summary.json holds it.

        fraction (of the smaller radius), grain and what it touched (``against``), the contact
        point position_m, time_s and step, phase (drive on or off), and ``stiffer``: the contact
        key and value that would bring it down to ``DEM_OVERLAP_WARN_FRACTION``.
        """
        rec = dict(self._max_overlap)
        key, value = self._stiffer(rec["fraction"])
        rec["stiffer"] = {key: value}
        return rec

    def restore_overlap(self, record) -> None:
        """Take back a record of :meth:`overlap_summary` (a resumed run); None: keep this one.

        Raises SimulationError naming what is wrong with it.
        """
        if record is None:
            return
        try:
            rec: dict[str, Any] = {
                "fraction": float(record["fraction"]),
                "grain": int(record["grain"]),
                "against": str(record["against"]),
                "position_m": [float(v) for v in record["position_m"]],
                "time_s": float(record["time_s"]),
                "step": int(record["step"]),
                "phase": str(record["phase"]),
            }
        except (TypeError, KeyError, ValueError) as exc:
            raise SimulationError(f"max_overlap record {record!r}: {exc!r}") from None
        if not (math.isfinite(rec["fraction"]) and rec["fraction"] >= 0.0):
            raise SimulationError(f"max_overlap fraction {rec['fraction']!r}: finite, >= 0")
        if len(rec["position_m"]) != 3:
            raise SimulationError(f"max_overlap position {rec['position_m']!r}: three numbers")
        self._max_overlap = rec

    def overlap_warnings(self) -> list[str]:
        """One line if the largest overlap exceeded ``DEM_OVERLAP_WARN_FRACTION``, else none."""
        rec = self._max_overlap
        bound = config.DEM_OVERLAP_WARN_FRACTION
        if not rec["fraction"] > bound:
            return []
        key, value = self._stiffer(rec["fraction"])
        return [
            f"largest overlap {rec['fraction']:.3g} radii, grain {rec['grain']} against "
            f"{rec['against']} at {self._at(rec['position_m'])}, t = {rec['time_s']:.6g} s "
            f"({rec['phase']}), above the accuracy bound {bound:g} (DEM_OVERLAP_WARN_FRACTION, "
            f"sampled every {config.DEM_CHECK_INTERVAL} steps): the result may depend on the "
            f"contact stiffness; {key} = {value:.3g} would bring it under (a stiffer contact "
            "needs a shorter run.timestep; 'auto' follows it)"
        ]

    def check(self) -> None:
        """Raise SimulationError naming the measured cause if the run cannot go on.

        In order: non-finite values; a speed no drive explains (energy the step loop made),
        or a bed running away downhill; an overlap beyond ``DEM_MAX_OVERLAP_FRACTION`` or growing
        at consecutive checks; a grain whose centre left the trough (below the floor, through a
        wall, far above). An overlap above ``DEM_OVERLAP_WARN_FRACTION`` is recorded
        (:meth:`overlap_summary`), not fatal. O(spheres + pairs).
        """
        s = self.spheres
        when = self._when()
        bad = ~(np.isfinite(s.x).all(axis=1) & np.isfinite(s.v).all(axis=1)
                & np.isfinite(s.omega).all(axis=1))  # fmt: skip
        if bad.any():
            i = int(np.argmax(bad))
            raise SimulationError(
                f"non-finite positions or velocities {when}: grain {self._grain(i)} first (of "
                f"{int(bad.sum())} spheres): the integration blew up; {self._step_fix()}"
            )
        self._check_speed(when)
        self._check_overlap(when)
        self._check_inside(when)

    def _check_speed(self, when: str) -> None:
        s = self.spheres
        speed2 = np.einsum("ij,ij->i", s.v, s.v)
        i = int(np.argmax(speed2))
        speed = math.sqrt(float(speed2[i]))
        bound = config.DEM_MAX_SPEED_FACTOR * self.reference_speed
        if speed <= bound:
            return
        mean = self.mean_velocity_x()
        incline = math.degrees(math.atan2(-self.gravity[0], -self.gravity[2]))
        if abs(incline) > 1e-9 and mean * self.gravity[0] > 0.0 and abs(mean) > 0.5 * bound:
            rolling = self.law.rolling_friction == 0.0 and self.rotation and self.bodies is None
            raise SimulationError(
                f"the grains run away downhill {when}: mean velocity {mean:.3g} m/s along the "
                f"trough (grain {self._grain(i)} at {speed:.3g} m/s), more than {bound:.3g} m/s "
                f"that the drive explains, on a trough inclined {incline:.3g} deg: friction does "
                "not hold them and no steady conveying exists; lower trough.inclination"
                + (", or give material.rolling_friction (spheres roll down any slope without it)"
                   if rolling else ", or raise material.friction")
            )  # fmt: skip
        raise SimulationError(
            f"grain {self._grain(i)} moves at {speed:.3g} m/s {when} at {self._at(s.x[i])}, "
            f"more than the {bound:.3g} m/s that drive and gravity can explain: energy the step "
            f"loop made, the integration is unstable; {self._step_fix()}"
        )

    def _check_overlap(self, when: str) -> None:
        fraction, i, other, point = self._deepest()
        if fraction > self._max_overlap["fraction"]:
            self._max_overlap = {
                "fraction": fraction,
                "grain": self._grain(i),
                "against": other,
                "position_m": [float(v) for v in point],
                "time_s": self.time,
                "step": self.step_index,
                "phase": "drive on" if self.drive_on else "drive off",
            }
        what = f"grain {self._grain(i) if i >= 0 else -1} against {other}"
        if fraction > config.DEM_MAX_OVERLAP_FRACTION:
            key, value = self._stiffer(fraction)
            past = ""
            if fraction > 1.0 and not other.startswith("grain"):
                past = f" (its centre is past the {other}: the grain is leaving the trough)"
            raise SimulationError(
                f"overlap of {fraction:.3g} radii, {what}{past}, at {self._at(point)} {when}, "
                f"beyond {config.DEM_MAX_OVERLAP_FRACTION} (DEM_MAX_OVERLAP_FRACTION): the "
                f"contact is too soft for this load or impact; a stiffer contact, {key} = "
                f"{value:.3g}, or a smaller drive.throw_number (softer impacts)"
            )
        # growth: the same contact the deepest, above the accuracy bound, deeper at each check
        last = self._growth
        if fraction <= config.DEM_OVERLAP_WARN_FRACTION:
            self._growth = None
            return
        if (
            last is not None
            and last[0] == what
            and fraction >= (config.DEM_OVERLAP_GROWTH_FACTOR * last[1][-1])
        ):
            self._growth = (what, [*last[1], fraction])
        else:
            self._growth = (what, [fraction])
        series = self._growth[1]
        if len(series) > config.DEM_OVERLAP_GROWTH_CHECKS:
            raise SimulationError(
                f"overlap of {what} grew at {len(series) - 1} checks in a row ("
                + ", ".join(f"{f:.3g}" for f in series)
                + f" radii, every {config.DEM_CHECK_INTERVAL} steps) to {self._at(point)} {when}: "
                "driven ever deeper, not bouncing (DEM_OVERLAP_GROWTH_CHECKS, "
                f"DEM_OVERLAP_GROWTH_FACTOR): the integration is unstable; {self._step_fix()}"
            )

    def _check_inside(self, when: str) -> None:
        """A grain whose centre left the trough: below it, through a wall, far above it."""
        s = self.spheres
        x = s.x
        tests = []
        if self.mesh is None:
            half = 0.5 * self.trough.width
            tests += [
                (x[:, 2] < 0.0, "below the floor z = 0"),
                (x[:, 1] < -half, "through the side wall y = -width/2"),
                (x[:, 1] > half, "through the side wall y = +width/2"),
            ]
        else:
            assert self._mesh_box is not None, "Simulation.__init__ sets it with the mesh"
            lo, hi = self._mesh_box
            side = self.mesh.sides(x)
            behind = side < -0.5 * self.mesh.gaps(x)  # nan (far from the mesh): False
            tests += [
                (x[:, 2] < lo[2], "below the trough mesh"),
                ((x[:, 1] < lo[1]) | (x[:, 1] > hi[1]), "beyond the side of the trough mesh"),
                (behind, "through the trough mesh, behind its wall"),
            ]
        tests.append((x[:, 0] < self.trough.back, "through the back wall x = 0"))
        for out, where in tests:
            if out.any():
                i = int(np.argmax(out))
                key, value = self._stiffer(1.0)
                speed = float(np.linalg.norm(s.v[i]))
                per_step = speed * self.dt / float(s.radius[i])
                jump = ""
                if per_step > 0.5:  # it may have crossed the wall within a step or two
                    jump = f"; it moves {per_step:.2g} radii a step: {self._step_fix()}"
                raise SimulationError(
                    f"grain {self._grain(i)} left the trough {where}: its centre is at "
                    f"{self._at(x[i])} {when}, moving at {speed:.3g} m/s ({int(out.sum())} "
                    "spheres outside): a wall holds a grain only while the overlap stays below "
                    "one radius, and this contact is too soft for its impacts; a stiffer "
                    f"contact (at least {key} = {value:.3g}, which keeps an impact that went a "
                    "radius deep within the accuracy bound) or a smaller drive.throw_number" + jump
                )
        high = x[:, 2] > self._ceiling
        if high.any():
            i = int(np.argmax(x[:, 2]))
            raise SimulationError(
                f"grain {self._grain(i)} is far above the trough, {x[i, 2]:.3g} m above the "
                f"floor at {self._at(x[i])} {when}: higher than drive and gravity can throw it "
                f"(the ceiling is {self._ceiling:.3g} m): energy the step loop made, the "
                f"integration is unstable; {self._step_fix()}"
            )
