"""The bulk from an atlas: v_norm between the points ``dem atlas`` ran, never outside them.

An atlas (:mod:`dem.studies.atlas`; the shipped one in ``dem/data/atlas/atlas.csv``) holds the
bulk's v_norm with its pooled error over grain shape, depth, friction, throw number and angle.
:func:`estimate` interpolates it multilinearly at a drive it may not have run, with an error
that includes the interpolation's; ``dem pointmass velocity --bulk`` prints it and ``dem plan``
says from it whether the point mass answers a case. Cost: reading the table, O(points); an
estimate, O(points) to index and 2^4 corners.
"""

from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

from dem.errors import InputError

#: The axes an estimate interpolates over: the atlas.csv column and the option that names it.
AXES = (
    ("particles.layers", "--depth"),
    ("material.friction", "--friction"),
    ("drive.throw_number", "--throw-number"),
    ("drive.angle_deg", "--angle"),
)
#: What the shipped atlas holds fixed: a query must match (restitutions, incline).
FIXED = {"--eps-t": 0.8, "--eps-n": 0.0, "--inclination": 0.0}


@dataclass(frozen=True)
class Estimate:
    """The atlas's bulk v_norm at a drive it may not have run, and how sure it is.

    Attributes:
        shape: The grain shape ("sphere", "screw").
        query: The drive and depth asked for, by option.
        velocity_norm: The bulk's v / (A omega cos phi), interpolated.
        stderr: Its standard error: the corner points' pooled errors, weighted, and the
            interpolation's own (:func:`estimate`), in quadrature.
        interpolation: The interpolation's part of ``stderr``.
        corners: The atlas points it interpolated between, with their weights.
        source: The atlas.csv it read.

    """

    shape: str
    query: dict
    velocity_norm: float
    stderr: float
    interpolation: float
    corners: list
    source: str


def default_table() -> Path | None:
    """The shipped atlas, ``dem/data/atlas/atlas.csv``, or None before it is computed."""
    from importlib import resources

    path = Path(str(resources.files("dem").joinpath("data", "atlas", "atlas.csv")))
    return path if path.is_file() else None


def read_table(path: str | Path, key: str = "--atlas") -> list[dict]:
    """The finished points of an atlas.csv, numbers as floats; refused naming ``key``."""
    path = Path(path)
    try:
        with path.open(encoding="utf-8", newline="") as handle:
            rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(key, str(path), f"a readable atlas.csv of dem atlas ({exc})") from None
    need = ["shape", "status", "mean_velocity_norm", "mean_velocity_norm_stderr",
            *(c for c, _ in AXES)]  # fmt: skip
    missing = [c for c in need if rows and c not in rows[0]]
    if not rows or missing:
        raise InputError(key, str(path), "an atlas.csv of dem atlas over particles.layers, "
                         "material.friction, drive.throw_number and drive.angle (it lacks "
                         f"{', '.join(missing) or 'rows'})")  # fmt: skip
    out = []
    for r in rows:
        if r["status"] != "done":
            continue
        try:
            row = {"shape": r["shape"]} | {c: float(r[c]) for c in need[2:]}
        except ValueError:
            continue
        try:  # the report's map draws the ratio where the table has it
            row["pointmass_bounded_velocity_norm"] = float(r["pointmass_bounded_velocity_norm"])
        except (KeyError, TypeError, ValueError):
            row["pointmass_bounded_velocity_norm"] = math.nan
        out.append(row)
    return out


def _interpolation_error(own, index, brackets, a: int, x: float) -> float:
    """Linear interpolation's error along axis ``a``: (1/2) w (1 - w) h^2 |f''|.

    f'' is the second divided difference through the bracket and the atlas's next value
    beyond it on this axis, at each of the other axes' corners (the largest); where the axis
    has no third value, or a point is missing, w (1 - w) |f(hi) - f(lo)|: the change across the
    bracket taken as all curvature.
    """
    column = AXES[a][0]
    (lo, _), (hi, w) = brackets[a][1]
    values = sorted({r[column] for r in own})
    i = values.index(lo)
    third = values[i - 1] if i >= 1 else (values[i + 2] if i + 2 < len(values) else None)
    others = [b if k != a else [(lo, 0.0)] for k, (_, b) in enumerate(brackets)]
    worst = 0.0
    for combo in itertools.product(*others):
        key = [v for v, _ in combo]

        def f(value, key=key):
            point = index.get(tuple(key[:a] + [value] + key[a + 1 :]))
            return None if point is None else point["mean_velocity_norm"]

        f_lo, f_hi = f(lo), f(hi)
        f_3 = None if third is None else f(third)
        if f_lo is None or f_hi is None:
            continue
        if f_3 is None:
            worst = max(worst, w * (1.0 - w) * abs(f_hi - f_lo))
            continue
        p, q, t = lo, hi, third
        second = 2.0 * (f_lo / ((p - q) * (p - t)) + f_hi / ((q - p) * (q - t))
                        + f_3 / ((t - p) * (t - q)))  # fmt: skip
        worst = max(worst, 0.5 * w * (1.0 - w) * (hi - lo) ** 2 * abs(second))
    return worst


def estimate(rows: list[dict], shape: str, *, depth: float, friction: float,
             throw_number: float, angle: float, source: str = "") -> Estimate:  # fmt: skip
    """The bulk's v_norm at a drive and depth, multilinear between the atlas's points.

    Each axis (depth in layers, friction, Gamma, phi) is bracketed by the atlas's two nearest
    values of this shape (one where the query sits on a value); outside an axis's range the
    estimate is refused, naming the option and the range, and so is a query whose corners the
    atlas did not all run. The error is the weighted corners' pooled errors in quadrature with
    the interpolation's along each bracketed axis (:func:`_interpolation_error`: from the
    curvature the atlas's next point shows; none at a point run), which the held-out points of
    validation/atlas check.
    """
    own = [r for r in rows if r["shape"] == shape]
    if not own:
        shapes = sorted({r["shape"] for r in rows})
        raise InputError("--bulk", shape, f"a shape of the atlas: {', '.join(shapes)}")
    query = {"--depth": depth, "--friction": friction, "--throw-number": throw_number,
             "--angle": angle}  # fmt: skip
    brackets = []
    for column, option in AXES:
        values = sorted({r[column] for r in own})
        x = query[option]
        if not values[0] - 1e-9 <= x <= values[-1] + 1e-9:
            run = ", ".join(f"{v:g}" for v in values)
            raise InputError(option, x, f"within the atlas's {column.split('.')[-1]} range for "
                             f"{shape}s, {values[0]:g} to {values[-1]:g} (values run: {run}): "
                             "no extrapolation")  # fmt: skip
        hit = [v for v in values if abs(v - x) <= 1e-9]
        if hit:
            brackets.append((column, [(hit[0], 1.0)]))
            continue
        lo = max(v for v in values if v < x)
        hi = min(v for v in values if v > x)
        w = (x - lo) / (hi - lo)
        brackets.append((column, [(lo, 1.0 - w), (hi, w)]))
    index = {tuple(r[c] for c, _ in AXES): r for r in own}
    value, variance, corners = 0.0, 0.0, []
    for combo in itertools.product(*(b for _, b in brackets)):
        key = tuple(v for v, _ in combo)
        weight = math.prod(w for _, w in combo)
        r = index.get(key)
        if r is None:
            where = ", ".join(f"{c.split('.')[-1]} {v:g}" for (c, _), v in zip(AXES, key,
                                                                          strict=True))  # fmt: skip
            raise InputError("--bulk", shape, f"an atlas point at every corner around this "
                             f"query; it has none at {where}: run it (dem atlas), or ask "
                             "at a drive the atlas ran around")  # fmt: skip
        value += weight * r["mean_velocity_norm"]
        variance += (weight * r["mean_velocity_norm_stderr"]) ** 2
        corners.append({"point": dict(zip([c for c, _ in AXES], key, strict=True)),
                        "weight": weight, "velocity_norm": r["mean_velocity_norm"]})  # fmt: skip
    interpolation = 0.0
    for a, (_, bracket) in enumerate(brackets):
        if len(bracket) == 1:
            continue
        axis_error = _interpolation_error(own, index, brackets, a, query[AXES[a][1]])
        interpolation = math.hypot(interpolation, axis_error)
    stderr = math.sqrt(variance + interpolation**2)
    return Estimate(shape, query, value, stderr, interpolation, corners, source)


#: What a case asks of the point mass where it gives no run.target_error: 3 %, the atlas's own.
DEFAULT_ACCURACY = 0.03


def point_mass_answers(case, table: str | Path | None = None) -> dict | None:
    """Whether the point mass answers ``case``'s bed within its accuracy, by the atlas.

    The atlas's estimate of this bed (shape, depth in layers, friction, Gamma, phi) against
    the Coulomb-bounded point mass on the case's drive: ``answers`` where |ratio - 1| plus its
    error is within ``run.target_error`` (else :data:`DEFAULT_ACCURACY`). None without an
    atlas (``table`` or the shipped one) or for a case it does not describe (a mesh trough, a
    feeder, a two-component drive, another material or incline than the shipped atlas's), with
    ``why`` where the atlas is there but refuses (out of its range).
    """
    from dem import pointmass
    from dem.scene import depth

    shipped = table is None
    table = default_table() if table is None else Path(table)
    d, m, t = case.drive, case.wall_material, case.trough
    if table is None or t.mesh is not None or case.feeder is not None or not d.is_single:
        return None
    if shipped and (m.restitution_tangential, m.restitution_normal, t.inclination) != tuple(
        FIXED.values()
    ):  # fmt: skip
        return None
    layers = depth.bed(case.particles, case.material.density, t.length, t.width)["layers"]
    try:
        e = estimate(read_table(table), case.particles.shape, depth=layers, friction=m.friction,
                     throw_number=d.throw_number, angle=d.angle, source=str(table))  # fmt: skip
    except InputError as exc:
        return {"answers": None, "why": f"{exc.key} = {exc.value!r}: {exc.allowed}"}
    bounded = pointmass.velocity(d.throw_number, d.angle, m.friction, t.inclination,
                                 m.restitution_tangential, m.restitution_normal,
                                 impact="coulomb").velocity_norm  # fmt: skip
    if abs(bounded) < 1e-3:
        return {"answers": None, "why": "the point mass rests here: no ratio"}
    ratio, ratio_err = e.velocity_norm / bounded, e.stderr / abs(bounded)
    need = case.run.target_error or DEFAULT_ACCURACY
    return {"answers": abs(ratio - 1.0) + ratio_err <= need, "ratio": ratio,
            "ratio_stderr": ratio_err, "accuracy": need, "layers": layers,
            "bulk_velocity_norm": e.velocity_norm, "bounded_velocity_norm": bounded,
            "source": str(table)}  # fmt: skip
