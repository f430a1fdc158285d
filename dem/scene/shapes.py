"""Grain templates: rigid clumps of spheres, built from a shape or read from a file.

A template is what every grain of one kind shares: the member spheres in the body frame, the
mass and the principal moments of inertia. Three constructors build one: :func:`sphere`,
:func:`screw` (a head sphere plus a row of overlapping shank spheres) and :func:`clump_from_file`
(lines ``x y z r``, the layout of a LIGGGHTS ``.multisphere`` template); :func:`clump` takes
arrays.

A template's mass properties are those of the UNION of its spheres (overlaps counted once),
uniform density: :func:`dem.physics.mass.union_properties` computes them (its module docstring
gives the three methods and their error bounds).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dem import quantities
from dem.config import DEM_CONTACT_MASS_MARGIN
from dem.errors import InputError
from dem.physics.mass import GRID_RTOL, principal_axes, union_properties


@dataclass(frozen=True, eq=False)
class Template:
    """A rigid grain: member spheres in the body frame and its mass properties.

    Body frame: origin at the centre of mass, axes along the principal axes, moments ascending.
    A point p of the input frame (the frame the spheres were given in) is at
    ``axes.T @ (p - com_input)`` in the body frame, and back: ``com_input + axes @ q``.

    Attributes:
        name: Label (``"sphere"``, ``"screw"`` or the file's stem).
        centres: Member sphere centres in the body frame, (k, 3), m.
        radii: Member sphere radii, (k,), m.
        mass: m = rho V, kg.
        moments: Principal moments of inertia, ascending, (3,), kg m^2.
        density: rho, kg/m^3.
        volume: Union volume V (overlaps counted once), m^3.
        com_input: Centre of mass in the input frame, (3,), m.
        axes: Principal axes as columns, in the input frame, (3, 3), orthonormal, det = +1;
            where two moments are (nearly) equal any orthonormal pair in their plane is valid.
        volume_error: Bound on the volume error, m^3 (see :func:`union_properties`).
        com_error: Bound on the centre-of-mass error, m.
        inertia_error: Bound on the error of each principal moment, kg m^2.
        method: How the union was integrated: ``"disjoint"``, ``"axial"`` or ``"grid"``.

    """

    name: str
    centres: np.ndarray
    radii: np.ndarray
    mass: float
    moments: np.ndarray
    density: float
    volume: float
    com_input: np.ndarray
    axes: np.ndarray
    volume_error: float = 0.0
    com_error: float = 0.0
    inertia_error: float = 0.0
    method: str = "disjoint"

    def __post_init__(self):
        for key in ("centres", "radii", "moments", "com_input", "axes"):
            value = np.array(getattr(self, key), dtype=np.float64)
            value.flags.writeable = False
            object.__setattr__(self, key, value)

    @property
    def count(self) -> int:
        """Number of member spheres k."""
        return len(self.radii)

    @property
    def bounding_radius(self) -> float:
        """max_i (|c_i| + R_i) about the centre of mass, m."""
        return float(np.max(np.linalg.norm(self.centres, axis=1) + self.radii))

    def contact_mass(self, samples: int = 400) -> float:
        """Smallest effective mass of the rigid clump at any point of its surface, kg.

        A force along the unit vector d at the body-frame point r (from the centre of mass)
        accelerates that point as if it had the mass 1 / (d . K(r) d), with
        K(r) = 1/M + [r]x^T I^-1 [r]x (I = diag(moments), [r]x the cross-product matrix). The
        smallest mass over all directions is 1 / lambda_max(K(r)); it is taken over the member
        surfaces r = c_s + R_s u at ``samples`` Fibonacci directions u per member and lowered by
        ``DEM_CONTACT_MASS_MARGIN`` for the points between the samples (lambda_max(K(r)) is
        convex in r, so its maximum over a member ball lies on the sampled surface). A sphere
        gives 2/7 M (the rolling sphere's tangential mass); a screw about 6 times more than the
        crude bound 1 / (1/M + |d_max|^2 / I_min), which pairs the longest lever with the
        smallest moment.
        """
        k = np.arange(samples) + 0.5
        polar = np.arccos(1.0 - 2.0 * k / samples)
        azimuth = np.pi * (1.0 + 5.0**0.5) * k
        u = np.stack(
            [np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], 1
        )
        r = (self.centres[:, None, :] + self.radii[:, None, None] * u[None]).reshape(-1, 3)
        cross = np.zeros((len(r), 3, 3))
        cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -r[:, 2], r[:, 1], -r[:, 0]
        cross -= np.transpose(cross, (0, 2, 1))
        k_matrix = np.eye(3) / self.mass + np.einsum(
            "nji,j,njk->nik", cross, 1.0 / self.moments, cross
        )
        worst = float(np.max(np.linalg.eigvalsh(k_matrix)[:, -1]))
        return (1.0 - DEM_CONTACT_MASS_MARGIN) / worst

    def input_centres(self) -> np.ndarray:
        """Member centres in the input frame, com_input + axes @ c_i, (k, 3), m."""
        return self.com_input + self.centres @ self.axes.T

    def inertia_tensor(self, frame: str = "body") -> np.ndarray:
        """Inertia tensor about the centre of mass, (3, 3), kg m^2.

        ``frame="body"`` gives diag(moments); ``"input"`` gives axes @ diag(moments) @ axes.T.
        """
        if frame == "body":
            return np.diag(self.moments)
        if frame == "input":
            return self.axes @ np.diag(self.moments) @ self.axes.T
        raise InputError("frame", frame, "'body' or 'input'")


# --- constructors -----------------------------------------------------------------------------


def sphere(radius: float, density: float) -> Template:
    """One sphere: V = 4/3 pi R^3, m = rho V, moments (2/5) m R^2 (exact).

    Args:
        radius: R, m.
        density: rho, kg/m^3.

    """
    _check_positive("radius", radius, "m")
    return clump([[0.0, 0.0, 0.0]], [radius], density=density, name="sphere")


def screw(
    length: float,
    shank_radius: float,
    head_radius: float,
    *,
    mass: float | None = None,
    density: float | None = None,
    max_bumpiness: float = 0.25,
) -> Template:
    """A screw: a head sphere plus a row of overlapping shank spheres along +x.

    Input frame: the head sphere (radius R_h) is centred at the origin. Shank spheres (radius
    r_s <= R_h) are centred at x_j = j s, j = 0..n, from the head centre to the tip sphere at
    x_n = L - R_h - r_s, so the grain spans exactly ``length`` L from the back of the head
    (x = -R_h) to the tip (x = x_n + r_s). Shank spheres that lie wholly inside the head
    (x_j + r_s <= R_h) are left out: they change neither the union nor the contacts.

    Spacing rule: the valley between neighbouring shank spheres has depth
    r_s - sqrt(r_s^2 - (s/2)^2) <= b r_s with b = ``max_bumpiness``, i.e.

        s <= s_max = 2 r_s sqrt(b (2 - b)),   n = ceil((L - R_h - r_s) / s_max),  s = x_n / n,

    the fewest spheres that keep the rule; the union's radius never dips below (1 - b) r_s along
    the shank (0 <= x <= x_n). b = 0.25 gives s = 1.32 r_s at most.

    Args:
        length: Overall length L (back of head to tip), m; L >= R_h + r_s.
        shank_radius: r_s, m.
        head_radius: R_h, m; R_h >= r_s.
        mass: Target mass, kg; the density is then m / V_union (the paper: about 2.5 g).
        density: rho, kg/m^3; give exactly one of mass and density.
        max_bumpiness: b, 0 < b <= 1 (1: touching shank spheres); a b that would need more
            than ``quantities.MAX_GRAIN_SPHERES`` member spheres is refused, naming the
            smallest b this screw allows.

    """
    _check_positive("length", length, "m")
    _check_positive("shank_radius", shank_radius, "m")
    _check_positive("head_radius", head_radius, "m")
    if shank_radius > head_radius:
        raise InputError("shank_radius", shank_radius, f"<= head_radius = {head_radius} (m)")
    if length < head_radius + shank_radius:
        raise InputError(
            "length", length, f">= head_radius + shank_radius = {head_radius + shank_radius} (m)"
        )
    if not 0.0 < max_bumpiness <= 1.0:
        raise InputError("max_bumpiness", max_bumpiness, "0 < b <= 1 (fraction of shank_radius)")
    spacing, count = screw_spacing(length, shank_radius, head_radius, max_bumpiness)
    if count + 2 > quantities.MAX_GRAIN_SPHERES:  # checked before any array is made
        _refuse_resolution(length, shank_radius, head_radius, max_bumpiness)
    x = spacing * np.arange(count + 1)
    x = x[x + shank_radius > head_radius]  # spheres wholly inside the head add nothing
    centres = np.zeros((len(x) + 1, 3))
    centres[1:, 0] = x
    radii = np.concatenate([[head_radius], np.full(len(x), shank_radius)])
    return clump(centres, radii, mass=mass, density=density, name="screw")


def _refuse_resolution(
    length: float, shank_radius: float, head_radius: float, max_bumpiness: float
) -> None:
    """InputError: the screw would need more than ``MAX_GRAIN_SPHERES`` member spheres.

    With n_max = MAX_GRAIN_SPHERES - 2 gaps (the head and n + 1 shank spheres), the rule of
    :func:`screw` holds with n <= n_max for s_max >= span / n_max, i.e. b (2 - b) >= q^2 with
    q = span / (2 r_s n_max): b >= 1 - sqrt(1 - q^2) (written q^2 / (1 + sqrt(1 - q^2)), exact
    for small q). The bound is shown rounded up, so the value it names is accepted.
    """
    cap = quantities.MAX_GRAIN_SPHERES
    span = length - head_radius - shank_radius
    q = span / (2.0 * shank_radius * (cap - 2))
    if q >= 1.0:  # even touching shank spheres (b = 1) are too many: the screw is too slender
        longest = head_radius + shank_radius + 2.0 * shank_radius * (cap - 2)
        raise InputError(
            "length", length,
            f"<= {longest:.6g} m for shank_radius = {shank_radius:g} m: a screw has at most "
            f"{cap} member spheres, at max_bumpiness = 1 (touching shank spheres)",
        )  # fmt: skip
    lowest = q * q / (1.0 + math.sqrt(1.0 - q * q))
    digits = 2 - math.floor(math.log10(lowest))  # three significant digits, rounded up
    shown = math.ceil(lowest * 10.0**digits) / 10.0**digits
    s_max = 2.0 * shank_radius * math.sqrt(max_bumpiness * (2.0 - max_bumpiness))
    raise InputError(
        "max_bumpiness", max_bumpiness,
        f"{shown:.3g} <= b <= 1 for this screw: a grain has at most {cap} member spheres, "
        f"b = {max_bumpiness:g} would make about {span / s_max + 2.0:.3g} (smaller b: more "
        "spheres)",
    )  # fmt: skip


def screw_spacing(
    length: float, shank_radius: float, head_radius: float, max_bumpiness: float
) -> tuple[float, int]:
    """Shank spacing s and number of gaps n of :func:`screw` (its docstring has the rule).

    Returns:
        (s, n): s = x_n / n in m (0 when x_n = 0), n >= 0 gaps between n + 1 shank centres.

    """
    span = length - head_radius - shank_radius
    s_max = 2.0 * shank_radius * math.sqrt(max_bumpiness * (2.0 - max_bumpiness))
    count = math.ceil(span / s_max * (1.0 - 1e-12)) if span > 0.0 else 0
    return (span / count if count else 0.0), count


def clump(
    centres,
    radii,
    *,
    mass: float | None = None,
    density: float | None = None,
    name: str = "clump",
    rtol: float = GRID_RTOL,
) -> Template:
    """Template of the union of spheres given in any frame.

    Args:
        centres: Sphere centres, (k, 3), m.
        radii: Sphere radii, (k,), m, all > 0.
        mass: Target mass, kg (density = mass / V); give exactly one of mass and density.
        density: rho, kg/m^3.
        name: Label.
        rtol: Tolerance of the grid method (see :func:`union_properties`).

    Returns:
        The template; centres are moved to the body frame (centre of mass, principal axes).

    """
    centres = np.atleast_2d(np.asarray(centres, dtype=np.float64))
    radii = np.atleast_1d(np.asarray(radii, dtype=np.float64))
    if centres.ndim != 2 or centres.shape[1] != 3:
        raise InputError("centres", centres.shape, "an array of shape (k, 3) (m)")
    if radii.ndim != 1 or len(radii) == 0 or len(radii) != len(centres):
        raise InputError("radii", len(radii), f"one radius per centre ({len(centres)} centres)")
    if not (np.all(np.isfinite(centres)) and np.all(np.isfinite(radii)) and np.all(radii > 0)):
        raise InputError("radii", radii.tolist(), "finite centres and radii > 0 (m)")
    if (mass is None) == (density is None):
        raise InputError("mass, density", (mass, density), "exactly one of the two given")
    if len(radii) > quantities.MAX_GRAIN_SPHERES:  # before the pairwise checks below
        raise InputError(
            "spheres", len(radii),
            f"at most {quantities.MAX_GRAIN_SPHERES} member spheres per grain",
        )  # fmt: skip
    gaps = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2)
    same = np.argwhere(np.triu(gaps <= 1e-9 * radii.max(), k=1))
    if len(same):
        i, j = (int(k) for k in same[0])
        raise InputError(
            f"spheres {i + 1} and {j + 1}", centres[i].tolist(),
            "distinct member spheres (these two have the same centre: a sphere listed twice)",
        )  # fmt: skip
    props = union_properties(centres, radii, rtol=rtol)
    if mass is not None:
        _check_positive("mass", mass, "kg")
        density = mass / props.volume
        rel_density = props.volume_error / props.volume  # rho = m / V carries V's error
    else:
        assert density is not None  # exactly one of the two (checked above)
        _check_positive("density", density, "kg/m^3")
        rel_density = 0.0
    eigenvalues, axes = principal_axes(props.inertia)
    moments = density * eigenvalues
    return Template(
        name=name,
        centres=(centres - props.com) @ axes,
        radii=radii,
        mass=density * props.volume,
        moments=moments,
        density=float(density),
        volume=props.volume,
        com_input=props.com,
        axes=axes,
        volume_error=props.volume_error,
        com_error=props.com_error,
        inertia_error=density * props.inertia_error + rel_density * float(np.max(moments)),
        method=props.method,
    )


def clump_from_file(
    path: str | Path, *, density: float | None = None, mass: float | None = None, scale: float = 1.0
) -> Template:
    """Read a clump template: one sphere per line, ``x y z r`` in metres.

    ``#`` starts a comment; blank lines are skipped. A LIGGGHTS ``.multisphere`` file has the same
    layout; its ``scale`` multiplies centres and radii here as there.

    Args:
        path: The file.
        density: rho, kg/m^3; give exactly one of density and mass.
        mass: Target mass, kg.
        scale: Length factor > 0 applied to x, y, z and r.

    Raises:
        InputError: A line without four numbers, a non-finite value, a radius <= 0, or no sphere
            at all; the message names the file, the line number, the value and what is allowed.

    """
    path = Path(path)
    _check_positive("scale", scale, "")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError("template", str(path), f"a readable text file ({exc})") from exc
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        content = line.split("#", 1)[0].strip()
        if not content:
            continue
        fields = content.split()
        try:
            values = [float(v) for v in fields]
        except ValueError:
            values = []
        if len(values) != 4 or not all(math.isfinite(v) for v in values):
            raise InputError(
                f"line {number}", content, "four finite numbers 'x y z r' (m)", source=str(path)
            )
        if not quantities.QUANTITIES["radius"].accepts(values[3] * scale):
            raise InputError(
                f"line {number}: r", values[3], quantities.QUANTITIES["radius"].allowed,
                source=str(path),
            )  # fmt: skip
        rows.append(values)
    if not rows:
        raise InputError("spheres", 0, "at least one line 'x y z r' (m)", source=str(path))
    data = scale * np.array(rows)
    try:
        return clump(data[:, :3], data[:, 3], mass=mass, density=density, name=path.stem)
    except InputError as exc:
        if exc.key in ("mass", "density", "mass, density"):  # the caller's, not the file's
            raise
        raise InputError(exc.key, exc.value, exc.allowed, source=str(path)) from None


def clump_lines(template: Template, *, frame: str = "body") -> list[str]:
    """A template's spheres as ``x y z r`` lines (m, full precision) after a ``#`` header.

    Written by :func:`dem.io.liggghts.write_clump`; the file reads back with
    :func:`clump_from_file` and in LIGGGHTS ``particletemplate/multisphere`` (scale 1).

    Args:
        template: The template.
        frame: ``"body"`` (centre of mass, principal axes) or ``"input"``.

    """
    if frame not in ("body", "input"):
        raise InputError("frame", frame, "'body' or 'input'")
    centres = template.centres if frame == "body" else template.input_centres()
    lines = [f"# {template.name}: {template.count} spheres, x y z r (m), {frame} frame"]
    lines += [
        " ".join(repr(float(v)) for v in (*c, r))
        for c, r in zip(centres, template.radii, strict=True)
    ]
    return lines


def _check_positive(key: str, value, unit: str) -> None:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0.0):
        raise InputError(key, value, f"> 0 ({unit})" if unit else "> 0")
