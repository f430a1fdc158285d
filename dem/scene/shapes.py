"""Grain templates: rigid clumps of spheres and the mass properties of their union.

A template is what every grain of one kind shares: the member spheres in the body frame, the
mass and the principal moments of inertia. Three constructors build one: :func:`sphere`,
:func:`screw` (a head sphere plus a row of overlapping shank spheres) and :func:`clump_from_file`
(lines ``x y z r``, the layout of a LIGGGHTS ``.multisphere`` template); :func:`clump` takes
arrays.

Mass properties are those of the UNION of the spheres (overlaps counted once), uniform density
rho:

    V = int_U dV,   c = (1/V) int_U x dV,   I = rho int_U (|r|^2 Id - r r^T) dV,  r = x - c.

:func:`union_properties` computes them by one of three methods, chosen automatically:

* ``"disjoint"``: no two spheres overlap (touching allowed). Exact: sums of sphere values,
  I_sphere = (2/5) m R^2 Id moved by the parallel-axis theorem.
* ``"axial"``: all centres on one line (a sphere, a screw). The union is a solid of revolution
  whose radius profile is rho(t)^2 = max(0, max_i R_i^2 - (t - t_i)^2) along the axis t. The
  pieces between breakpoints (sphere ends t_i +- R_i and profile crossings) are polynomials of
  degree <= 4 in t, integrated exactly by 3-point Gauss-Legendre:

      V = pi int rho^2 dt,  int t dV = pi int t rho^2 dt,  int t^2 dV = pi int t^2 rho^2 dt,
      int u^2 dV = int v^2 dV = (pi/4) int rho^4 dt  (u, v across the axis).

* ``"grid"``: any other overlapping clump. Lines parallel to x through the nodes of a square
  grid (spacing h) covering the (y, z) silhouette; along each line the union of the sphere chords
  is merged exactly and int 1, x, x^2 dx over it are exact, so only the 2-D rule in (y, z)
  carries error. The grid is shifted by a uniformly random offset in [0, h)^2, which makes each
  estimate unbiased (a randomised lattice rule); the mean of ``GRID_SHIFTS`` independent shifts
  (fixed seed: deterministic) is returned and the error bound is ``GRID_SIGMAS`` standard errors
  of that mean: for V a two-sided confidence of about 99.5 % (Student t, 7 degrees of freedom);
  the bounds on |c| and on the Frobenius norm of I pool 3 and 6 components and are safer still.
  h is halved from ``GRID_START_CELLS`` cells across until the bounds of V (relative), c
  (relative to the largest extent) and I (Frobenius, relative) are below ``rtol``; at
  ``GRID_MAX_CELLS`` it stops and returns the larger bound it reached.
  Measured (tests and checks): errors between 0.01 and 0.65 of the bound; rtol = 1e-4 takes
  0.3 to 5 s for clumps of 2 to 9 spheres, rtol = 1e-3 under 0.3 s.
  An unshifted grid is not used: its error is not monotone in h (silhouettes aligned with grid
  lines), so successive differences can understate it.

The exact methods report rounding-level bounds (``EXACT_RTOL`` times the value).
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

#: Relative error bound reported for the exact methods (rounding only).
EXACT_RTOL = 1e-12
#: Default relative tolerance of the grid method (volume, centre of mass / extent, inertia).
GRID_RTOL = 1e-4
#: Grid method: cells across the larger (y, z) extent on the first level, and the most allowed.
GRID_START_CELLS = 64
GRID_MAX_CELLS = 1024
#: Grid method: independent random grid offsets per level, their seed, and the bound in standard
#: errors of their mean (4 standard errors: about 99.5 % two-sided for 8 shifts, Student t).
GRID_SHIFTS = 8
GRID_SEED = 20240521
GRID_SIGMAS = 4.0
#: Grid method: at most this many (line, sphere) entries are held in memory at once.
_GRID_CHUNK = 2_000_000

# 3-point Gauss-Legendre on [-1, 1]: exact for polynomials of degree <= 5.
_GL_X = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
_GL_W = np.array([5.0, 8.0, 5.0]) / 9.0


@dataclass(frozen=True)
class UnionProperties:
    """Geometric mass properties of a union of spheres (unit density).

    Attributes:
        volume: V, m^3.
        com: Centre of the union, (3,), m.
        inertia: Inertia tensor per unit density about ``com``, int (|r|^2 Id - r r^T) dV, (3, 3),
            m^5.
        volume_error: Bound on |V - V_true|, m^3.
        com_error: Bound on |com - com_true| (Euclidean), m.
        inertia_error: Bound on the Frobenius norm of the inertia error, m^5; by Weyl's
            inequality it bounds the error of each principal moment too.
        method: ``"disjoint"``, ``"axial"`` or ``"grid"``.

    """

    volume: float
    com: np.ndarray
    inertia: np.ndarray
    volume_error: float
    com_error: float
    inertia_error: float
    method: str


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
        _check_positive("density", density, "kg/m^3")
        rel_density = 0.0
    eigenvalues, axes = np.linalg.eigh(props.inertia)
    for col in range(2):  # largest component of each axis positive, then right-handed
        if axes[np.argmax(np.abs(axes[:, col])), col] < 0.0:
            axes[:, col] = -axes[:, col]
    axes[:, 2] = np.cross(axes[:, 0], axes[:, 1])
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


def write_clump(path: str | Path, template: Template, *, frame: str = "body") -> None:
    """Write a template's spheres as ``x y z r`` lines (m, full precision).

    The file reads back with :func:`clump_from_file` and in LIGGGHTS
    ``particletemplate/multisphere`` (scale 1).

    Args:
        path: Output file.
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
    Path(path).write_text("\n".join(lines) + "\n", encoding="ascii")


# --- mass properties of a union of spheres ------------------------------------------------------


def union_properties(
    centres, radii, *, method: str = "auto", rtol: float = GRID_RTOL
) -> UnionProperties:
    """Volume, centre and inertia per unit density of the union of spheres.

    Args:
        centres: (k, 3), m.
        radii: (k,), m.
        method: ``"auto"`` (``"disjoint"`` if no two spheres overlap, else ``"axial"`` if the
            centres are collinear, else ``"grid"``) or one of those names to force it.
        rtol: Grid method: stop when successive changes of V (relative), com (relative to the
            largest extent) and I (Frobenius, relative to |I|) are all below rtol.

    Returns:
        :class:`UnionProperties`, with error bounds as described in the module docstring.

    """
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    r = np.asarray(radii, dtype=np.float64).reshape(-1)
    if method == "auto":
        if _disjoint(c, r):
            method = "disjoint"
        elif _collinear(c, r):
            method = "axial"
        else:
            method = "grid"
    if method == "disjoint":
        if not _disjoint(c, r):
            raise InputError("method", method, "'disjoint' only for spheres that do not overlap")
        return _exact(*_moments_disjoint(c, r), "disjoint")
    if method == "axial":
        if not _collinear(c, r):
            raise InputError("method", method, "'axial' only for collinear centres")
        return _exact(*_moments_axial(c, r), "axial")
    if method == "grid":
        return _grid(c, r, rtol)
    raise InputError("method", method, "'auto', 'disjoint', 'axial' or 'grid'")


def _disjoint(c: np.ndarray, r: np.ndarray) -> bool:
    d = np.linalg.norm(c[:, None, :] - c[None, :, :], axis=2)
    overlap = d < (r[:, None] + r[None, :]) * (1.0 - 1e-12)
    np.fill_diagonal(overlap, False)
    return not overlap.any()


def _axis(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean of the centres and the unit direction of their best-fit line (x if none)."""
    p0 = c.mean(axis=0)
    if len(c) == 1:
        return p0, np.array([1.0, 0.0, 0.0])
    _, s, vt = np.linalg.svd(c - p0)
    return p0, (vt[0] if s[0] > 0.0 else np.array([1.0, 0.0, 0.0]))


def _collinear(c: np.ndarray, r: np.ndarray) -> bool:
    p0, d = _axis(c)
    rel = c - p0
    off = rel - np.outer(rel @ d, d)
    return bool(np.max(np.linalg.norm(off, axis=1)) <= 1e-12 * (np.max(np.abs(rel)) + r.max()))


def _moments_disjoint(c: np.ndarray, r: np.ndarray):
    """Raw moments of separate spheres.

    V_i = 4/3 pi R_i^3, int x dV = V_i c_i, int x x^T dV = V_i (c_i c_i^T + R_i^2/5 Id).
    """
    v = 4.0 / 3.0 * math.pi * r**3
    second = np.einsum("i,ia,ib->ab", v, c, c) + np.sum(v * r**2 / 5.0) * np.eye(3)
    return v.sum(), v @ c, second


def _moments_axial(c: np.ndarray, r: np.ndarray):
    """Raw moments of a union of spheres with collinear centres (solid of revolution)."""
    p0, d = _axis(c)
    t = (c - p0) @ d
    lo, hi = t - r, t + r
    breaks = [lo, hi]
    i, j = np.triu_indices(len(r), 1)
    apart = t[i] != t[j]
    i, j = i[apart], j[apart]
    # R_i^2 - (x - t_i)^2 = R_j^2 - (x - t_j)^2
    #   =>  x = (R_i^2 - R_j^2 + t_j^2 - t_i^2) / (2 (t_j - t_i))
    cross = (r[i] ** 2 - r[j] ** 2 + t[j] ** 2 - t[i] ** 2) / (2.0 * (t[j] - t[i]))
    breaks.append(cross[(cross > lo.min()) & (cross < hi.max())])
    b = np.unique(np.concatenate(breaks))
    a, e = b[:-1], b[1:]
    mid = 0.5 * (a + e)
    q_mid = r[None, :] ** 2 - (mid[:, None] - t[None, :]) ** 2
    owner = np.argmax(q_mid, axis=1)
    keep = q_mid[np.arange(len(mid)), owner] > 0.0
    a, e, owner = a[keep], e[keep], owner[keep]
    x = 0.5 * (a + e)[:, None] + 0.5 * (e - a)[:, None] * _GL_X[None, :]
    w = 0.5 * (e - a)[:, None] * _GL_W[None, :]
    rho2 = r[owner][:, None] ** 2 - (x - t[owner][:, None]) ** 2
    vol = math.pi * np.sum(w * rho2)
    m1 = math.pi * np.sum(w * x * rho2)  # int t dV
    m2 = math.pi * np.sum(w * x * x * rho2)  # int t^2 dV
    m_perp = 0.25 * math.pi * np.sum(w * rho2 * rho2)  # int u^2 dV = int v^2 dV
    first = vol * p0 + m1 * d
    dd = np.outer(d, d)
    second = (
        vol * np.outer(p0, p0)
        + m1 * (np.outer(p0, d) + np.outer(d, p0))
        + m2 * dd
        + m_perp * (np.eye(3) - dd)
    )
    return vol, first, second


def _central(vol: float, first: np.ndarray, second: np.ndarray):
    """Centre and inertia per unit density from raw moments about the origin."""
    com = first / vol
    s = second - vol * np.outer(com, com)  # int r r^T dV about the centre
    return com, np.trace(s) * np.eye(3) - s


def _exact(vol: float, first: np.ndarray, second: np.ndarray, method: str) -> UnionProperties:
    com, inertia = _central(vol, first, second)
    size = math.sqrt(np.trace(inertia) / vol)  # a length of the order of the grain's radius
    return UnionProperties(
        volume=float(vol),
        com=com,
        inertia=0.5 * (inertia + inertia.T),
        volume_error=EXACT_RTOL * vol,
        com_error=EXACT_RTOL * (size + float(np.max(np.abs(com)))),
        inertia_error=EXACT_RTOL * float(np.linalg.norm(inertia)),
        method=method,
    )


def _grid_level(c: np.ndarray, r: np.ndarray, cells: int, offset: np.ndarray):
    """Raw moments (about the origin) by exact chords along x on a shifted (y, z) grid.

    Lines pass through (y, z) = lo - h + (i + offset) h, i = 0 .. n + 1, with h the larger
    (y, z) extent over ``cells`` and offset in [0, 1)^2: the grid covers the silhouette for every
    offset, so with a uniformly random offset the estimate is unbiased.
    """
    lo, hi = (c[:, 1:] - r[:, None]).min(axis=0), (c[:, 1:] + r[:, None]).max(axis=0)
    h = float(np.max(hi - lo)) / cells
    ny, nz = (np.ceil((hi - lo) / h).astype(int) + 2).tolist()
    y = lo[0] + h * (np.arange(ny) - 1.0 + offset[0])
    z = lo[1] + h * (np.arange(nz) - 1.0 + offset[1])
    floor = (c[:, 0] - r).min() - 1.0  # empty chords sit here with zero length
    k = len(r)
    sums = np.zeros(10)  # V, Sx, Sy, Sz, Sxx, Syy, Szz, Sxy, Sxz, Syz
    rows = max(1, _GRID_CHUNK // (k * nz))
    for start in range(0, ny, rows):
        yy, zz = np.meshgrid(y[start : start + rows], z, indexing="ij")
        yy, zz = yy.ravel(), zz.ravel()
        d2 = (yy[:, None] - c[None, :, 1]) ** 2 + (zz[:, None] - c[None, :, 2]) ** 2
        half = np.sqrt(np.maximum(r[None, :] ** 2 - d2, 0.0))
        hit = d2 < r[None, :] ** 2
        a = np.where(hit, c[None, :, 0] - half, floor)
        b = np.where(hit, c[None, :, 0] + half, floor)
        order = np.argsort(a, axis=1)
        a, b = np.take_along_axis(a, order, 1), np.take_along_axis(b, order, 1)
        reach = np.maximum.accumulate(b, axis=1)  # right end of the union of chords so far
        before = np.concatenate([np.full((len(a), 1), floor), reach[:, :-1]], axis=1)
        lo, hi = np.maximum(a, before), np.maximum(b, before)  # new part of each chord
        l0 = np.sum(hi - lo, axis=1)
        l1 = np.sum(hi**2 - lo**2, axis=1) / 2.0
        l2 = np.sum(hi**3 - lo**3, axis=1) / 3.0
        sums += [
            l0.sum(), l1.sum(), yy @ l0, zz @ l0, l2.sum(), (yy * yy) @ l0, (zz * zz) @ l0,
            yy @ l1, zz @ l1, (yy * zz) @ l0,
        ]  # fmt: skip
    sums *= h * h
    v, sx, sy, sz, sxx, syy, szz, sxy, sxz, syz = sums
    second = np.array([[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]])
    return v, np.array([sx, sy, sz]), second


def _grid(c: np.ndarray, r: np.ndarray, rtol: float) -> UnionProperties:
    shift = 0.5 * ((c - r[:, None]).min(axis=0) + (c + r[:, None]).max(axis=0))
    extent = float(np.max((c + r[:, None]).max(axis=0) - (c - r[:, None]).min(axis=0)))
    offsets = np.random.default_rng(GRID_SEED).random((GRID_SHIFTS, 2))
    cells = GRID_START_CELLS
    while True:
        vols, coms, inertias = [], [], []
        for offset in offsets:
            vol, first, second = _grid_level(c - shift, r, cells, offset)
            com, inertia = _central(vol, first, second)
            vols.append(vol)
            coms.append(com)
            inertias.append(inertia)
        # the shifted estimates are independent and unbiased: bound = GRID_SIGMAS standard errors
        vols, coms, inertias = np.array(vols), np.array(coms), np.array(inertias)
        vol, com, inertia = vols.mean(), coms.mean(axis=0), inertias.mean(axis=0)
        scale = GRID_SIGMAS / math.sqrt(GRID_SHIFTS * (GRID_SHIFTS - 1))
        errors = (
            scale * math.sqrt(np.sum((vols - vol) ** 2)),
            scale * math.sqrt(np.sum((coms - com) ** 2)),
            scale * math.sqrt(np.sum((inertias - inertia) ** 2)),
        )
        rel = (errors[0] / vol, errors[1] / extent, errors[2] / np.linalg.norm(inertia))
        if max(rel) <= rtol or 2 * cells > GRID_MAX_CELLS:
            break
        cells *= 2
    return UnionProperties(
        volume=float(vol),
        com=com + shift,
        inertia=0.5 * (inertia + inertia.T),
        volume_error=errors[0],
        com_error=errors[1],
        inertia_error=errors[2],
        method="grid",
    )


def _check_positive(key: str, value, unit: str) -> None:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0.0):
        raise InputError(key, value, f"> 0 ({unit})" if unit else "> 0")
