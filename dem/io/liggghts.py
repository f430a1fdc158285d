"""Export a case as an equivalent LIGGGHTS-PUBLIC 3.8 input deck (DESIGN.md section 8).

The deck simulates the same periodic trough section in the trough's accelerating frame: the walls
stay still (``fix wall/gran`` primitives: floor z = 0, side walls y = +-width/2, x periodic; or
the case's triangle mesh, below) and every grain feels the effective gravity

    g_x(t) = -g sin(alpha) + A omega^2 sin(omega tau) cos(phi)
    g_y(t) = 0
    g_z(t) = -g cos(alpha) + A omega^2 sin(omega tau) sin(phi)

in m/s^2, with tau the time since the drive started. ``fix gravity`` takes a magnitude and a
direction; both are equal-style variables, |g(t)| and (g_x, 0, g_z).

Mesh troughs (``[trough] mesh``): the triangles the case reads (:func:`dem.scene.mesh.load_mesh`)
are
written next to the deck as the ASCII STL ``trough.stl`` (exact coordinates, m, trough frame)
and become one granular wall, ``fix trough all mesh/surface file trough.stl type 2`` and
``fix walls all wall/gran MODEL mesh n_meshes 1 meshes trough SETTINGS``, in place of the three
primitive walls (``curvature_tolerant yes`` is added only if a triangle has a corner angle below
LIGGGHTS's default curvature, 0.256 deg, which it would otherwise refuse). The mesh is not
moved: the drive is a translation, so in the trough's frame the walls stand still and the same
effective gravity is exact (DESIGN.md section 2); no ``fix move/mesh`` is needed. The box is
periodic over x in [0, length], which the mesh spans, and reaches
:data:`MESH_BOX_MARGIN` grain reaches beyond the mesh across y and below it. LIGGGHTS copies
the triangles across the periodic boundary itself (ghost elements); a sphere rolling across
x = 0 on the U pan keeps its speed and height to all printed digits (checked by hand with
LIGGGHTS 3.8). ``insert/pack`` checks new grains against each other (``overlapcheck``) and,
with ``all_in``, keeps spheres inside the region (clumps are inserted at random orientations
with their centres of mass in a region inset by their reach: :func:`_placement`), but not
against a mesh, so
the insertion block must itself clear the mesh: :func:`mesh_fill_block` takes the block over
the pan with the largest cross-section below the mesh's top whose sides and floor stay a
neighbour skin away from every triangle, and the column above it is as tall as the grains need
at the loose fill fraction.

Finite feeders (``[feeder]``, :mod:`dem.engine.feeder`): the box is closed across y and z and open
along x (``boundary f f f``) from a margin behind the back wall to the discharge edge x = L; a
sphere whose centre passes L leaves the box and LIGGGHTS deletes it (``thermo_modify lost
ignore``), as dem removes a grain whose centre of mass passes L. A clump goes as a whole in
LIGGGHTS, when its first member's centre passes L (``fix multisphere`` deletes a body that has
lost an atom: the balance's sphere count stays a multiple of the members), so it leaves earlier
than in dem, which waits for its centre of mass. The
back wall is ``wall/gran primitive xplane 0.0``, with a mesh too, as dem's fourth flat wall. The
fill is insert/pack in [reach, L - reach], as dem's. The feed is ``insert/rate/region``
(:func:`_feeder_lines`): one grain every m / feed_rate into the zone 0 < x < ``feed_length``,
at rest in the trough's frame (dem drops fed grains at rest in the laboratory, -s'(t) in the
trough's frame: at most A omega apart). ``balance.txt`` records the spheres in the box, the
grains fed and the initial charge; :func:`read_balance` and :func:`discharge_per_cycle` turn
them into grains discharged and the discharge rate per drive cycle.

Contact laws map one-to-one:

- ``hertz_mindlin`` -> ``model hertz tangential history`` with the same Young's modulus Y and
  Poisson ratio nu (one material for grains and walls), friction mu and normal restitution e.
  LIGGGHTS computes k_n = (4/3) Y* sqrt(R* d_n) and damping from
  beta = ln(e) / sqrt(ln(e)^2 + pi^2); it refuses e <= 0.05, so e is clamped to
  :data:`MIN_HERTZ_RESTITUTION` and the deck says so.
- ``linear`` -> ``model hooke/stiffness`` with ``absolute_damping on``: k_n (N/m),
  k_t = kappa k_n, and the damping coefficients (N s/m)

      gamma_n = 2 zeta sqrt(k_n m*),   zeta = -ln(e) / sqrt(ln(e)^2 + pi^2)   (1 for e = 0),

  with m* = m/2 for grain-grain (atom types 1-1) and m* = m for grain-wall contacts (1-2), so the
  restitution is exact for both and e = 0 needs no clamp; gamma_t = gamma_n as dem's
  ``tangential = "liggghts"`` uses it, or 2 zeta_t sqrt(k_t f_t m*) for ``"coulomb"``.

LIGGGHTS has one tangential convention, the spring capped at mu F_n with the dashpot added while
sticking: dem's ``tangential = "liggghts"``. A case with ``"coulomb"`` (dem's default) is written
with the same coefficients and a NOTE in the deck; use ``"liggghts"`` on both sides of a
comparison.

``limitForce`` is written out (on or off as ``[contact] limit_force``), and so is
``tangential_damping on`` (the LIGGGHTS default). Grains are atom type 1, walls type 2.

Grains: spheres are ``fix particletemplate/sphere`` integrated by ``fix nve/sphere`` (``nve``
with rotation locked). Screws and clumps are ``fix particletemplate/multisphere`` reading the
members from ``grain.multisphere`` (``x y z r`` in m, body frame: centre of mass at the origin,
principal axes, written by :func:`dem.scene.shapes.write_clump`), with the template's exact ``mass``
and diagonal ``inertia_tensor`` given (``use_volume``), so LIGGGHTS's Monte Carlo estimate only
sets its volume; ``fix multisphere`` integrates the rigid bodies (``tflag off off off`` locks
rotation) and needs ``atom_modify map array sort 0 0``. LIGGGHTS, like dem, takes the clump's
mass as the mass of a member in a contact. The mean x-velocity is then that of the bodies'
centres of mass (``compute multisphere property vcm``), not of the member spheres.

The deck runs three stages: fill (insert N grains at random in a loose column and let them fall
under static gravity until at rest), settle (drive on, ``settle_steps`` steps not measured) and
measure (``steps`` driven steps). Each stage is its own ``run`` command, so LIGGGHTS prints one
"Loop time of T on P procs for S steps" line per stage; the last one times the driven steps
alone. The mean x-velocity of all grains (``compute reduce ave vx``; equal masses, so the same as
the mass-weighted mean), averaged over windows of ``sample_steps`` steps, goes to ``vx_mean.txt``.
"""

from __future__ import annotations

import math
import os
import platform
import re
import shutil
import subprocess
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dem import __version__
from dem.config import GRAVITY
from dem.errors import InputError
from dem.kernels.contacts import P_KT_RATIO, P_MASS_T, P_ZETA_T, damping_beta
from dem.physics.laws import NORMAL_LAWS, TANGENTIAL_LAWS, wall_params
from dem.scene.case import Case
from dem.scene.mesh import load_mesh
from dem.scene.resolved import Scene, resolve
from dem.scene.shapes import write_clump
from dem.scene.timestep import ContactLaw

#: LIGGGHTS version the decks are written for.
LIGGGHTS_VERSION = "LIGGGHTS-PUBLIC 3.8.0"
#: LIGGGHTS refuses coefficientRestitution <= 0.05; Hertz decks use at least this value.
MIN_HERTZ_RESTITUTION = 0.06
#: File name of the deck inside the output directory.
DECK_NAME = "in.dem"
#: File the deck writes the windowed mean x-velocity to (columns: step, mean vx in m/s).
VX_FILE = "vx_mean.txt"
#: The particle dump's files, one per output frame (``*`` is the step; trough frame, SI units).
DUMP_FILES = "dump*.liggghts"
#: File a finite feeder's deck writes its balance to (:func:`read_balance`).
BALANCE_FILE = "balance.txt"
#: Neighbour skin as a fraction of the sphere radius.
SKIN_FRACTION = 0.5
#: Solid volume fraction of the loose column the spheres are inserted into.
FILL_VOLUME_FRACTION = 0.2
#: The same for clumps: ``insert/pack`` (``all_in``) placed only 174 of 200 screws of
#: ``cases/screw-trough`` at 0.14 and all of them at 0.10 (and at 0.08 with random orientations).
FILL_VOLUME_FRACTION_CLUMPS = 0.08
#: A feeder's fill column is shorter (fill in [reach, L - reach]); its loose fraction is scaled.
FEEDER_FILL_SCALE = 0.6
#: File the clump template's members are written to, next to the deck.
CLUMP_FILE = "grain.multisphere"
#: Monte Carlo samples of ``particletemplate/multisphere`` (only its volume estimate uses them).
MULTISPHERE_NTRY = 1000000
#: File the trough mesh of a mesh case is written to, next to the deck (ASCII STL, m).
MESH_FILE = "trough.stl"
#: LIGGGHTS's default ``curvature`` of ``fix mesh/surface``, deg: a mesh with a smaller angle in
#: any triangle needs ``curvature_tolerant yes``.
MESH_DEFAULT_CURVATURE = 0.256235
#: Margin of the box around a mesh across y and below it, in grain reaches (radius or clump
#: bounding radius): every node lies strictly inside the box.
MESH_BOX_MARGIN = 2.0
#: Half-widths tried for the insertion block over a mesh pan.
MESH_FILL_TRIES = 256


#: ``Loop time of T on P procs for S steps with N atoms`` of a LIGGGHTS log: (T, P, S, N).
LOOP_RE = re.compile(
    r"Loop time of ([0-9.eE+-]+) on (\d+) procs.*?for (\d+) steps with (\d+) atoms"
)
#: The version banner of a LIGGGHTS log.
VERSION_RE = re.compile(r"LIGGGHTS \(Version ([^,]+)")


def machine_info() -> dict:
    """Cores, CPU model and platform: the machine a reference run was made on (provenance)."""
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cores": os.cpu_count(), "cpu": cpu, "platform": platform.platform()}


def damping_ratio(restitution: float) -> float:
    """Return the damping ratio zeta of a linear spring-dashpot with restitution e in [0, 1].

    zeta = -beta = -ln(e) / sqrt(ln(e)^2 + pi^2) (:func:`dem.kernels.contacts.damping_beta`, the
    kernels' value), from e = exp(-zeta pi / sqrt(1 - zeta^2)); e = 0 gives critical damping,
    zeta = 1.
    """
    return -damping_beta(restitution)


def _prime_at_least(n: int) -> int:
    """Smallest prime >= n (LIGGGHTS wants prime seeds above 10000)."""
    candidate = max(n, 10007)
    while any(candidate % d == 0 for d in range(2, math.isqrt(candidate) + 1)):
        candidate += 1
    return candidate


def _fmt(x: float) -> str:
    """Format a float exactly (shortest repr) for the deck."""
    return repr(float(x) + 0.0)  # + 0.0 turns -0.0 into 0.0


def _contact_block(scene: Scene, sphere_mass: float) -> tuple[list[str], str, str]:
    """Return the property/global lines, the model string and the model settings."""
    case = scene.case
    lines = [
        "# grains are atom type 1, walls type 2; each matrix below is (1-1 1-2 2-1 2-2): "
        "grain-grain the material, grain-wall [wall] (the material's where it gives nothing)",
    ]
    row = TANGENTIAL_LAWS[case.contact.tangential]
    if row.liggghts_as != row.name:
        note = row.liggghts_note
        if case.contact.model != "linear" and row.name == "coulomb":
            note += ", with Mindlin's k_t = 8 G* sqrt(R* d)"
        lines.append("# NOTE: " + note)
        if row.name != "coulomb":  # "coulomb" keeps its own k_t / k_n and zeta_t (below)
            case = case.with_tangential(row.liggghts_as)
    contact, material, wall = case.contact, case.material, case.wall_material
    limit = "on" if contact.limit_force else "off"

    def pair(grains: float, walls: float) -> str:
        return " ".join(_fmt(x) for x in (grains, walls, walls, walls))

    mu = pair(material.friction, wall.friction)
    if contact.wall_lever_arm == "surface":
        lines.append(
            "# NOTE: the case's wall contacts act at r - delta (contact.wall_lever_arm = "
            "'surface'); LIGGGHTS's walls at r - delta/2, as dem's wall_lever_arm = 'midpoint'"
        )
    lines += [
        f"fix m_mu all property/global coefficientFriction peratomtypepair 2 {mu}",
    ]
    if contact.model == "hertz_mindlin":
        es = []
        for e_case in (material.restitution_normal, wall.restitution_normal):
            e = max(e_case, MIN_HERTZ_RESTITUTION)
            if e != e_case and e_case not in es:
                lines.append(
                    f"# NOTE: restitution_normal = {e_case} in the case; LIGGGHTS refuses "
                    f"e <= 0.05, so e = {e} is used here (use the same value on both sides of a "
                    "comparison)"
                )  # fmt: skip
            es.append(e)
        y, nu = _fmt(contact.youngs_modulus), _fmt(contact.poisson_ratio)
        lines += [
            f"fix m_Y all property/global youngsModulus peratomtype {y} {y}",
            f"fix m_nu all property/global poissonsRatio peratomtype {nu} {nu}",
            f"fix m_e all property/global coefficientRestitution peratomtypepair 2 {pair(*es)}",
        ]
        model = NORMAL_LAWS[contact.model].liggghts
        settings = f"limitForce {limit} tangential_damping on"
    else:
        # the scene's law, or the law of the case switched to "liggghts" above (its own)
        law = scene.law if case is scene.case else ContactLaw.from_case(case)
        kn = contact.stiffness
        rows = (law.params, wall_params(law.params))  # grain-grain, grain-wall
        kts = [rows[0][P_KT_RATIO] * kn] + [rows[1][P_KT_RATIO] * kn] * 3
        zetas = [damping_ratio(material.restitution_normal)]
        zetas += [damping_ratio(wall.restitution_normal)] * 3
        # m* = m/2 grain-grain (1-1), m for grain-wall (1-2 and 2-1); type 2-2 never meets
        meff = (0.5 * sphere_mass, sphere_mass, sphere_mass, sphere_mass)
        gn = [2.0 * z * math.sqrt(kn * m) for z, m in zip(zetas, meff, strict=True)]
        if contact.tangential == "liggghts":
            gt, gt_text = gn, "gamma_t = gamma_n (as dem's liggghts convention)"
        else:
            gt = [
                2.0 * row[P_ZETA_T] * math.sqrt(kt * row[P_MASS_T] * m)
                for row, kt, m in zip((rows[0],) + (rows[1],) * 3, kts, meff, strict=True)
            ]
            gt_text = (f"gamma_t = 2 zeta_t sqrt(k_t f_t m*), zeta_t = {rows[0][P_ZETA_T]:.6g}, "
                       f"f_t = {rows[0][P_MASS_T]:.6g}")  # fmt: skip
        lines += [
            f"# linear spring-dashpot: zeta = {zetas[0]:.6g} (grain-wall {zetas[1]:.6g}) from e = "
            f"{material.restitution_normal} (wall {wall.restitution_normal}), "
            "gamma_n = 2 zeta sqrt(k m*), m* = m/2 (1-1) or m (1-2); " + gt_text,
            f"fix m_kn all property/global kn peratomtypepair 2 {' '.join([_fmt(kn)] * 4)}",
            "fix m_kt all property/global kt peratomtypepair 2 " + " ".join(map(_fmt, kts)),
            "fix m_gn all property/global gamman_abs peratomtypepair 2 " + " ".join(map(_fmt, gn)),
            "fix m_gt all property/global gammat_abs peratomtypepair 2 " + " ".join(map(_fmt, gt)),
        ]
        model = NORMAL_LAWS[contact.model].liggghts
        settings = f"absolute_damping on limitForce {limit} tangential_damping on"
    if material.rolling_friction > 0.0 or wall.rolling_friction > 0.0:
        mr = pair(material.rolling_friction, wall.rolling_friction)
        lines.append(
            f"fix m_mur all property/global coefficientRollingFriction peratomtypepair 2 {mr}"
        )
        model += " rolling_friction cdt"
    return lines, model, settings


# --- mesh troughs -------------------------------------------------------------------------------


def write_stl(path: str | Path, tri: np.ndarray, name: str = "trough") -> Path:
    """Write triangles as an ASCII STL file (LIGGGHTS 3.8 reads ASCII STL only).

    Args:
        path: The file.
        tri: Corners, (T, 3, 3), m; each triangle keeps its winding a -> b -> c, and its facet
            normal is (b - a) x (c - a) / |...|.
        name: The solid's name.

    Coordinates are written exactly (shortest repr), so the file reads back to the same bits.

    """
    tri = np.asarray(tri, dtype=np.float64).reshape(-1, 3, 3)
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(cross, axis=1, keepdims=True)
    normals = cross / np.where(length > 0.0, length, 1.0)
    lines = [f"solid {name}"]
    for corners, normal in zip(tri, normals, strict=True):
        lines.append("facet normal " + " ".join(map(_fmt, normal)))
        lines.append(" outer loop")
        lines += ["  vertex " + " ".join(map(_fmt, v)) for v in corners]
        lines += [" endloop", "endfacet"]
    lines.append(f"endsolid {name}")
    out = Path(path)
    out.write_text("\n".join(lines) + "\n")
    return out


def strip_top(tri: np.ndarray, y0: float, y1: float) -> float:
    """Highest z of the triangles' parts with y0 <= y <= y1 (any x), m; -inf where none is.

    The triangles (T, 3, 3) are clipped to the slab; z is linear on a triangle, so its highest
    point in the slab is a corner inside it or a point where an edge crosses y = y0 or y = y1.
    """
    y, z = tri[..., 1], tri[..., 2]
    inside = (y >= y0) & (y <= y1)
    top = float(np.max(np.where(inside, z, -np.inf), initial=-np.inf))
    for i, j in ((0, 1), (1, 2), (2, 0)):
        yi, yj, zi, zj = y[:, i], y[:, j], z[:, i], z[:, j]
        for s in (y0, y1):
            crosses = (yi - s) * (yj - s) < 0.0  # never where yi == yj
            t = np.divide(s - yi, yj - yi, out=np.zeros_like(yi), where=crosses)
            top = max(top, float(np.max(np.where(crosses, zi + t * (zj - zi), -np.inf))))
    return top


def mesh_fill_block(tri: np.ndarray, clearance: float) -> tuple[float, float, float]:
    """The insertion block over a mesh pan: (y0, y1, z0), m; it runs over all x and up from z0.

    The block is centred on the mesh's extent across y. For each half-width h (a fraction
    k / :data:`MESH_FILL_TRIES` of the mesh's half-width) its bottom z0 is ``clearance`` above
    the highest point of the mesh within ``clearance`` of the block's sides (:func:`strip_top`),
    so no triangle comes closer than ``clearance`` to the block, anywhere along x; the walls of
    the pan rule out wide blocks. Of these, the block with the largest cross-section below the
    mesh's top, 2 h (z_top - z0), is taken: the widest column that still reaches down into the
    pan. Widths are rounded down and z0 up to 1e-6 m.

    Raises:
        ValueError: No block fits (a pan closed at the top, or with a gap in its floor).

    """
    lo, hi = tri.min(axis=(0, 1)), tri.max(axis=(0, 1))
    y_mid, half = 0.5 * (lo[1] + hi[1]), 0.5 * (hi[1] - lo[1])
    best, best_area = None, 0.0
    for k in range(1, MESH_FILL_TRIES):
        h = math.floor(half * k / MESH_FILL_TRIES * 1e6) / 1e6
        below = strip_top(tri, y_mid - h - clearance, y_mid + h + clearance)
        z0 = math.ceil((below + clearance) * 1e6) / 1e6 if math.isfinite(below) else math.nan
        if h > 0.0 and below >= lo[2] and z0 < hi[2] and 2.0 * h * (hi[2] - z0) > best_area:
            best, best_area = (y_mid - h, y_mid + h, z0), 2.0 * h * (hi[2] - z0)
    if best is None:
        raise ValueError(
            "no block over the pan clears the mesh (is the pan open at the top, with no gap in "
            "its floor?)"
        )
    return best


def min_angle_deg(tri: np.ndarray) -> float:
    """Smallest corner angle of any triangle (T, 3, 3), degrees (LIGGGHTS checks it)."""
    smallest = 180.0
    for i in range(3):
        a = tri[:, (i + 1) % 3] - tri[:, i]
        b = tri[:, (i + 2) % 3] - tri[:, i]
        cos = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        smallest = min(smallest, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).min()))
    return smallest


def _drive_variables(d, gx0: float, gz0: float) -> list[str]:
    """Equal-style variables gx, gz: gravity minus the trough's acceleration s''(tau).

    The paper's drive: drive = A w^2 sin(w tau), gx = gx0 + drive cos(phi), gz likewise (as
    before). A second component and a start-up ramp follow :class:`dem.physics.drive.Motion` term
    for
    term: each component k adds A_k w^2 [c_s sin(w tau + psi_k) + c_c cos(w tau + psi_k)] e_k
    with c_s = r - r''/w^2, c_c = -2 r'/w of the smootherstep r(u), u = min(tau / T, 1)
    (written with comparisons: LIGGGHTS's min() is a special function of computes)
    (r' = r'' = 0 once u = 1, so the same expressions hold after the ramp).
    """
    w = d.omega
    phi = math.radians(d.angle)
    if d.second_amplitude == 0.0 and d.ramp_cycles == 0.0:
        peak = d.amplitude * w**2
        return [
            f"variable drive equal {_fmt(peak)}*sin({_fmt(w)}*v_tau)",
            f"variable gx equal {_fmt(gx0)}+v_drive*{_fmt(math.cos(phi))}",
            f"variable gz equal {_fmt(gz0)}+v_drive*{_fmt(math.sin(phi))}",
        ]
    lines = []
    if d.ramp_cycles > 0.0:
        ramp = d.ramp_cycles / d.frequency
        lines += [
            f"variable u equal (v_tau<{_fmt(ramp)})*v_tau/{_fmt(ramp)}+(v_tau>={_fmt(ramp)})",
            "variable r0 equal v_u*v_u*v_u*(10.0-15.0*v_u+6.0*v_u*v_u)",
            f"variable r1 equal 30.0*v_u*v_u*(1.0-v_u)*(1.0-v_u)/{_fmt(ramp)}",
            f"variable r2 equal 60.0*v_u*(1.0-v_u)*(1.0-2.0*v_u)/{_fmt(ramp * ramp)}",
            f"variable cs equal v_r0-v_r2/{_fmt(w * w)}",
            f"variable cc equal -2.0*v_r1/{_fmt(w)}",
        ]
        cs, cc = "v_cs", "v_cc"
    else:
        cs, cc = "1.0", "0.0"
    comps = [(d.amplitude, phi, 0.0)]
    if d.second_amplitude > 0.0:
        comps.append(
            (d.second_amplitude, math.radians(d.second_angle), math.radians(d.second_phase))
        )
    names = []
    for k, (a, ang, psi) in enumerate(comps, start=1):
        arg = f"{_fmt(w)}*v_tau+{_fmt(psi)}"
        lines.append(f"variable drive{k} equal {_fmt(a * w**2)}*({cs}*sin({arg})+{cc}*cos({arg}))")
        names.append((f"v_drive{k}", ang))
    gx = "+".join(f"{n}*{_fmt(math.cos(ang))}" for n, ang in names)
    gz = "+".join(f"{n}*{_fmt(math.sin(ang))}" for n, ang in names)
    return lines + [
        f"variable gx equal {_fmt(gx0)}+{gx}",
        f"variable gz equal {_fmt(gz0)}+{gz}",
    ]


def _placement(case: Case) -> str:
    """The insert fixes' placement keywords: spheres ``all_in yes``, clumps ``all_in no``.

    Clumps get ``orientation random`` in a region inset by their reach (:func:`write_deck`).

    LIGGGHTS 3.8's insert fixes default to the template's orientation (``quat_random_`` is false
    in ``FixInsert``): without ``orientation random`` every screw starts with its axis along x,
    and such a bed conveyed 8 % faster than dem's randomly oriented one
    (validation/liggghts-screws, part D). Their ``all_in`` keeps a sphere of the template's
    bounding radius inside the region, but about the point where the clump's centre of mass is
    then put (``ParticleToInsertMultisphere::check_near_set_x_v_omega``), not about the
    bounding sphere's centre: a rotated screw's tip reached past the side walls and 2 of 200
    screws were deleted at once. The inset region holds the centre of mass instead, so every
    member stays inside at any orientation.
    """
    if case.particles.shape == "sphere":
        return " all_in yes"
    return " all_in no orientation random"


def _feeder_lines(
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
    discharged = charge + fed - in the box, per :func:`read_balance`.
    """
    from dem.engine.feeder import EXCHANGE_FRACTION

    case = scene.case
    f, d = case.feeder, case.drive
    # one grain per insertion, as dem feeds a grain whenever a whole one is owed (checked
    # every EXCHANGE_FRACTION of a period): LIGGGHTS's massrate rounds a fraction of a grain
    # per insertion down and feeds 10 % short (measured on cases/feeder, every 1/16 cycle)
    exchange = max(1, round(EXCHANGE_FRACTION / (d.frequency * timestep)))
    grain = scene.grain_mass
    every = max(exchange, round(grain / (f.feed_rate * timestep))) if f.feed_rate > 0 else 0
    placement = _placement(case)
    p = case.particles
    if p.shape == "sphere":  # all_in keeps the sphere in the zone
        x0, x1 = 0.0, f.feed_length
    else:  # the zone holds centres of mass (_placement), as dem's feed does
        reach = p.grain.bounding_radius
        x0, x1 = reach, max(f.feed_length - reach, reach + 1e-6)
    lines = [
        "# finite feeder: grains fed at the back; a sphere past x = L is deleted (lost)",
        "variable charge equal ${natoms0}",
    ]
    fed = "0"
    if f.feed_rate > 0.0:
        lines += [
            f"region feedzone block {_fmt(x0)} {_fmt(x1)} {_fmt(fill_y[0])} "
            f"{_fmt(fill_y[1])} {_fmt(fill_z0)} {_fmt(fill_z0 + fill_height)} units box",
            f"fix feed all insert/rate/region seed {s_feed} distributiontemplate pdd "
            f"nparticles INF massrate {_fmt(f.feed_rate)} insert_every {every} "
            f"start {drive_start + every} "
            f"overlapcheck yes{placement} vel constant 0.0 0.0 0.0 region feedzone",
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


def write_deck(
    case: Case | Scene,
    out_dir: str | Path,
    *,
    timestep: float,
    steps: int,
    settle_steps: int | None = None,
    fill_time: float | None = None,
    sample_steps: int | None = None,
    thermo_every: int | None = None,
    settle_note: str | None = None,
    dump: bool = True,
) -> Path:
    """Write ``out_dir/in.dem``, a LIGGGHTS deck equivalent to a case.

    Args:
        case: A validated case (spheres, screws or clumps), or its
        :class:`dem.scene.resolved.Scene`.
        out_dir: Directory for the deck (created; a clump case also gets ``grain.multisphere``,
            a mesh case ``trough.stl``); LIGGGHTS is run inside it.
        timestep: dt, s.
        steps: Driven steps that are measured (the last ``run``).
        settle_steps: Driven steps before measuring; default ``run.settle_cycles`` drive cycles.
        fill_time: Time, s, for the inserted grains to fall and come to rest under static
            gravity; default sqrt(2 H / g) + 0.1 s for an insertion column of height H.
        sample_steps: Window of the mean x-velocity written to ``vx_mean.txt``; default one
            output frame, 1 / (frequency * frames_per_cycle) s.
        thermo_every: Steps between thermo lines; default one drive cycle.
        settle_note: Where the settle count came from (a comment in the deck), when the case
            says "auto" and the caller chose it.
        dump: Write a particle dump (``dump*.liggghts``, LIGGGHTS's ``custom`` text: id, type,
            x y z, vx vy vz, radius) every output frame, ``output.frames_per_cycle`` per drive
            cycle, from the drive's start: what dem run writes as VTK frames.

    Returns:
        Path of the deck.

    Raises:
        InputError: A clump case without its template, a mesh no insertion block fits in,
            or timestep/steps not positive.

    """
    scene = case if isinstance(case, Scene) else None
    case = case.case if scene is not None else case
    source = str(case.source)
    p, t, d = case.particles, case.trough, case.drive
    if p.shape != "sphere" and p.grain is None:
        raise InputError(
            "particles.shape", p.shape, "a case read by dem.scene.case.load_case", source
        )
    if not timestep > 0.0:
        raise InputError("timestep", timestep, "> 0 (s)")
    if steps < 1:
        raise InputError("steps", steps, ">= 1")
    if scene is None:  # the deck's step is ``timestep``: the scene's own is not checked here
        scene = resolve(case, check_limit=False)

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    n = p.count
    seed = case.run.seed
    s_template = _prime_at_least(15485863 + 1000 * seed)
    s_dist = _prime_at_least(32452843 + 1000 * seed)
    s_insert = _prime_at_least(49979687 + 1000 * seed)
    if p.shape == "sphere":
        r_max = r_min = p.radius
        grain_volume = 4.0 / 3.0 * math.pi * p.radius**3
        grain_mass = case.material.density * grain_volume
        members = 1
        what = f"{n} spheres r = {p.radius} m"
        grain_lines = [
            f"fix pts all particletemplate/sphere {s_template} atom_type 1 "
            f"density constant {_fmt(case.material.density)} radius constant {_fmt(p.radius)}"
        ]
        integrator = [f"fix integr all {'nve/sphere' if p.rotation else 'nve'}"]
        velocity = ["compute vxm all reduce ave vx"]
    else:
        g = scene.grain
        r_max, r_min = float(max(g.radii)), float(min(g.radii))
        grain_volume, grain_mass, members = g.volume, g.mass, g.count
        what = f"{n} {p.shape}s of {members} spheres, m = {g.mass:.6g} kg"
        write_clump(out / CLUMP_FILE, g, frame="body")
        i1, i2, i3 = (_fmt(m) for m in g.moments)
        grain_lines = [
            f"# {CLUMP_FILE}: members x y z r (m) in the body frame (centre of mass at the origin,",
            "# principal axes); mass and inertia tensor exact from dem.scene.shapes,"
            " Monte Carlo volume",
            f"fix pts all particletemplate/multisphere {s_template} atom_type 1 "
            f"density constant {_fmt(g.density)} nspheres {members} ntry {MULTISPHERE_NTRY} "
            f"spheres file {CLUMP_FILE} scale 1.0 type 1 mass {_fmt(g.mass)} "
            f"inertia_tensor {i1} 0.0 0.0 {i2} 0.0 {i3} use_volume"
            + ("" if p.rotation else " tflag off off off"),
        ]
        integrator = ["fix integr all multisphere"]
        velocity = [
            "compute vcm all multisphere property vcm",
            "compute vxm all reduce ave c_vcm[1]",
        ]
    steps_per_cycle = 1.0 / (d.frequency * timestep)
    if settle_steps is None:
        if case.run.settle_cycles is None:
            raise InputError(
                "run.settle_cycles",
                "auto",
                "a whole number of cycles for a LIGGGHTS deck (the deck cannot detect the end of "
                "the transient; use the number a dem run of the case reported in summary.json)",
                source=str(case.source),
            )
        settle_steps = round(case.run.settle_cycles * steps_per_cycle)
    frame_steps = max(1, round(steps_per_cycle / case.output.frames_per_cycle))
    if sample_steps is None:
        sample_steps = frame_steps
    if thermo_every is None:
        thermo_every = max(1, round(steps_per_cycle))

    material_lines, model, settings = _contact_block(scene, grain_mass)
    placement = _placement(case)

    # loose insertion column and a box tall enough that thrown grains never leave it
    if p.shape == "sphere":
        fill_fraction, fill_min = FILL_VOLUME_FRACTION, 4.0 * r_max
    else:
        fill_fraction, fill_min = FILL_VOLUME_FRACTION_CLUMPS, 2.5 * p.grain.bounding_radius
    if t.mesh is None:  # flat floor z = 0 and side walls y = +-width/2; the column spans the box
        half_w = 0.5 * t.width
        box_y, box_z0 = (-half_w, half_w), 0.0
        fill_y, fill_z0, bottom = box_y, 0.0, 0.0
        mesh_top, wall_note = 0.0, []
    else:  # the column stands in the pan (mesh_fill_block); the box holds the mesh
        tri = load_mesh(t.mesh, length=t.length, source=source).tri
        write_stl(out / MESH_FILE, tri)
        try:
            fill_block = mesh_fill_block(tri, SKIN_FRACTION * r_min)
        except ValueError as exc:
            raise InputError(
                "trough.mesh", str(t.mesh), f"a pan grains fit in ({exc})", source
            ) from None
        lo, hi = tri.min(axis=(0, 1)), tri.max(axis=(0, 1))
        margin = MESH_BOX_MARGIN * (p.radius if p.shape == "sphere" else p.grain.bounding_radius)
        box_y, box_z0 = (float(lo[1] - margin), float(hi[1] + margin)), float(lo[2] - margin)
        fill_y, fill_z0, bottom = fill_block[:2], fill_block[2], float(lo[2])
        mesh_top = float(hi[2] + margin)
        wall_note = [
            f"# walls: {MESH_FILE}, the {len(tri)} triangles of {t.mesh.name} (m, trough frame),",
            "#   standing still: the drive translates the trough, so in its frame the walls do",
            "#   not move (no move/mesh; DESIGN.md section 2). The insertion block lies inside the",
            "#   pan, clear of the mesh: insert/pack does not check grains against a mesh",
        ]
    feeder = case.feeder
    reach = p.radius if p.shape == "sphere" else p.grain.bounding_radius
    if p.shape != "sphere":  # the region holds centres of mass (_placement)
        fill_y, fill_z0 = (fill_y[0] + reach, fill_y[1] - reach), fill_z0 + reach
    # a feeder fills [reach, L - reach] as dem does (dem.engine.setup), clear of the back wall and
    # edge
    fill_x = (0.0, t.length) if feeder is None else (reach, t.length - reach)
    fill_width = fill_y[1] - fill_y[0]
    if fill_width <= 0.0:
        raise InputError(
            "trough.width" if t.mesh is None else "trough.mesh",
            t.width if t.mesh is None else str(t.mesh),
            f"room across y for a grain's reach of {reach:g} m either side of its centre of "
            "mass (LIGGGHTS's insertion region)",
            source,
        )
    fill_length = fill_x[1] - fill_x[0]
    if feeder is not None:  # insert/pack placed 43 of cases/feeder's 50 screws at 0.08
        fill_fraction *= FEEDER_FILL_SCALE
    fill_height = max(n * grain_volume / (fill_fraction * fill_length * fill_width), fill_min)
    top = max(fill_z0 + 3.0 * fill_height + 20.0 * r_max, mesh_top)
    if fill_time is None:
        fill_time = math.sqrt(2.0 * (fill_z0 + fill_height - bottom) / GRAVITY) + 0.1
    fill_steps = max(1, round(fill_time / timestep))
    if t.mesh is None:
        wall_lines = [
            f"fix floor all wall/gran {model} primitive type 2 zplane 0.0 {settings}",
            f"fix side_lo all wall/gran {model} primitive type 2 yplane {_fmt(-half_w)} {settings}",
            f"fix side_hi all wall/gran {model} primitive type 2 yplane {_fmt(half_w)} {settings}",
        ]
    else:
        # LIGGGHTS refuses a triangle with a corner angle below the curvature unless told
        tolerant = min_angle_deg(tri) < MESH_DEFAULT_CURVATURE
        wall_lines = [
            f"fix trough all mesh/surface file {MESH_FILE} type 2"
            + (" curvature_tolerant yes" if tolerant else ""),
            f"fix walls all wall/gran {model} mesh n_meshes 1 meshes trough {settings}",
        ]

    if feeder is None:
        box_x, boundary = (0.0, t.length), "boundary p f f"
        feeder_lines, feed_lines, lost, balance_note = [], [], "", []
    else:
        # open x: a sphere whose centre passes x = L leaves the box and is deleted (lost atoms
        # ignored); the back wall is the plane x = 0, as dem's
        box_x, boundary = (-MESH_BOX_MARGIN * reach, t.length), "boundary f f f"
        lost = " lost ignore"
        feeder_lines = [
            f"fix back all wall/gran {model} primitive type 2 xplane 0.0 {settings}",
        ]
        feed_lines, balance_note = _feeder_lines(
            scene, timestep, fill_y, fill_z0, fill_height, members, s_feed=_prime_at_least(
                67867967 + 1000 * seed), sample_steps=sample_steps, drive_start=fill_steps,
        )  # fmt: skip
        wall_lines += feeder_lines
    alpha = math.radians(t.inclination)
    gx0, gz0 = -GRAVITY * math.sin(alpha), -GRAVITY * math.cos(alpha)
    g0 = math.hypot(gx0, gz0)
    drive_start = fill_steps

    # LIGGGHTS refuses E > 1e9 Pa in SI units unless told the grains are hard on purpose
    youngs = case.contact.youngs_modulus if case.contact.model == "hertz_mindlin" else None
    hard = (["hard_particles yes  # E > 1e9 Pa: LIGGGHTS 3.8 refuses it in SI units otherwise"]
            if youngs is not None and youngs > 1.0e9 else [])  # fmt: skip
    lines = [
        f"# LIGGGHTS deck exported by dem {__version__} (dem export liggghts)",
        f"# case {case.name}: {what}, {case.contact.model}, "
        f"f = {d.frequency} Hz, phi = {d.angle} deg, A = {d.amplitude:.6g} m, "
        f"Gamma = {d.throw_number:.6g}, alpha = {t.inclination} deg",
        f"# made for {LIGGGHTS_VERSION} (Debian package 'liggghts')",
        f"# run:  cd {out.name} && liggghts -in {DECK_NAME}",
        f"#   or: cd {out.name} && mpirun -np 2 liggghts -in {DECK_NAME}",
        f"# stages: fill {fill_steps} steps (static gravity), settle {settle_steps} driven steps, "
        f"measure {steps} driven steps; dt = {timestep} s",
        f"# output: {VX_FILE} (step, mean vx in m/s averaged over {sample_steps} steps), "
        "log.liggghts"
        + (
            f", {DUMP_FILES} (every {frame_steps} steps: "
            f"{case.output.frames_per_cycle} a cycle, from the drive's start)"
            if dump
            else ""
        ),
        *([f"# settle: {settle_note}"] if settle_note else []),
        "# frame: the trough's accelerating frame; walls still, effective gravity",
        "#   g(t) = (-g sin(alpha) + A w^2 sin(w tau) cos(phi), 0, "
        "-g cos(alpha) + A w^2 sin(w tau) sin(phi))",
        *wall_note,
        *balance_note,
        "",
        "atom_style granular",
        "atom_modify map array" + ("" if p.shape == "sphere" else " sort 0 0"),
        boundary,
        "newton off",
        "communicate single vel yes",
        "processors * 1 1  # split x only: the bed is uniform across y and z",
        "units si",
        *hard,
        "",
        f"region domain block {_fmt(box_x[0])} {_fmt(box_x[1])} {_fmt(box_y[0])} {_fmt(box_y[1])} "
        f"{_fmt(box_z0)} {_fmt(top)} units box",
        "create_box 2 domain",
        f"neighbor {_fmt(SKIN_FRACTION * r_min)} bin",
        "neigh_modify delay 0",
        "",
        *material_lines,
        "",
        f"pair_style gran {model} {settings}",
        "pair_coeff * *",
        f"timestep {_fmt(timestep)}",
        "",
        *wall_lines,
        "",
        f"fix grav all gravity {_fmt(g0)} vector {_fmt(gx0 / g0)} 0.0 {_fmt(gz0 / g0)}",
        "",
        *grain_lines,
        f"fix pdd all particledistribution/discrete {s_dist} 1 pts 1.0",
        f"region fill block {_fmt(fill_x[0])} {_fmt(fill_x[1])} "
        f"{_fmt(fill_y[0])} {_fmt(fill_y[1])} "
        f"{_fmt(fill_z0)} {_fmt(fill_z0 + fill_height)} units box",
        f"fix ins all insert/pack seed {s_insert} distributiontemplate pdd "
        "maxattempt 1000 vel constant 0.0 0.0 0.0 insert_every once "
        f"overlapcheck yes{placement} particles_in_region {n} region fill",
        *integrator,
        "",
        *velocity,
        "thermo_style custom step atoms ke c_vxm",
        f"thermo {thermo_every}",
        "thermo_modify norm no" + lost,
        "",
        "# --- fill: insert and let the grains come to rest under static gravity",
        f"run {fill_steps}",
        "variable ninserted equal f_ins[1]",
        f'if "${{ninserted}} < {n}" then '
        f'"print \'ERROR: only ${{ninserted}} of {n} grains inserted\'" "quit"',
        "unfix ins",
        "variable natoms0 equal atoms",
        "",
        "# --- drive: effective gravity in the accelerating frame",
        f"variable tau equal (step-{drive_start})*{_fmt(timestep)}",
        *_drive_variables(d, gx0, gz0),
        "variable gmag equal sqrt(v_gx*v_gx+v_gz*v_gz)",
        "unfix grav",
        "fix grav all gravity v_gmag vector v_gx 0.0 v_gz",
        f"fix vxout all ave/time 1 {sample_steps} {sample_steps} c_vxm file {VX_FILE}",
        *(
            [f"dump frames all custom {frame_steps} {DUMP_FILES} id type x y z vx vy vz radius"]
            if dump
            else []
        ),
        *feed_lines,
        "",
        "# --- settle: driven, not measured",
        f"run {settle_steps}" if settle_steps > 0 else "# (no settle steps)",
        "",
        "# --- measure: driven; the last 'Loop time' line times these steps alone",
        f"run {steps}",
        "",
    ]
    deck = out / DECK_NAME
    deck.write_text("\n".join(lines))
    return deck


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
    """Read :data:`BALANCE_FILE` of a feeder deck; ``members`` spheres make a grain."""
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


# --- running LIGGGHTS -------------------------------------------------------------------------
# The launcher the validation studies share (validation/liggghts-bulk, liggghts-screws and
# performance/bench_bulk.py).

#: How to install LIGGGHTS where it is missing (Debian/Ubuntu package, LIGGGHTS-PUBLIC 3.8).
LIGGGHTS_INSTALL = "apt-get install -y liggghts"
#: File inside the run directory that :func:`run_liggghts` writes LIGGGHTS's stdout and stderr to.
LIGGGHTS_STDOUT = "stdout.txt"
#: Characters of stdout and of stderr quoted when a run fails.
FAILURE_TAIL = 2000


class LiggghtsError(RuntimeError):
    """LIGGGHTS is not on PATH, or a run of it failed; the message says which, and how to fix."""


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


class LiggghtsRun(NamedTuple):
    """A finished LIGGGHTS run (:func:`run_liggghts`).

    Attributes:
        stdout: LIGGGHTS's standard output.
        wall_s: Wall time of the whole process (start-up, every ``run``, the output), s.
        loop_times: The ``Loop time`` lines, one per ``run`` command of the deck, in order; the
            last one of a deck from :func:`write_deck` times the measured driven steps alone.
        version: The version in the log banner, e.g. "LIGGGHTS-PUBLIC 3.8.0" (None if absent).

    """

    stdout: str
    wall_s: float
    loop_times: list[LoopTime]
    version: str | None


def find_liggghts() -> str | None:
    """Path of the ``liggghts`` executable on PATH, or None if there is none."""
    return shutil.which("liggghts")


def liggghts_version(stdout: str) -> str | None:
    """The version in the banner ``LIGGGHTS (Version V, ...)`` of a log, or None."""
    found = VERSION_RE.search(stdout)
    return found.group(1) if found else None


def loop_times(stdout: str) -> list[LoopTime]:
    """Every ``Loop time of T on P procs for S steps with N atoms`` line of a log, in order."""
    return [LoopTime(float(t), int(p), int(s), int(n)) for t, p, s, n in LOOP_RE.findall(stdout)]


def run_liggghts(
    work_dir: str | os.PathLike,
    deck_name: str = DECK_NAME,
    *,
    log_name: str = LIGGGHTS_STDOUT,
    prefix: tuple[str, ...] | list[str] = (),
    min_loops: int = 1,
) -> LiggghtsRun:
    """Run ``liggghts -in deck_name`` in ``work_dir`` and wait for it.

    The deck's relative paths (``grain.multisphere``, ``vx_mean.txt``) are taken from and
    written to ``work_dir``; LIGGGHTS's stdout and stderr go to ``work_dir / log_name`` as well.

    Args:
        work_dir: The run directory (a copy of a deck directory from :func:`write_deck`).
        deck_name: The input deck inside it.
        log_name: File for LIGGGHTS's stdout followed by its stderr.
        prefix: Words before the executable, e.g. ``("mpirun", "-np", "2")``.
        min_loops: Fewer ``Loop time`` lines than this count as a failed run (a deck from
            :func:`write_deck` prints one per stage).

    Raises:
        LiggghtsError: ``liggghts`` is not on PATH (the message says how to install it), or it
            exited non-zero or printed too few ``Loop time`` lines (the message quotes the last
            :data:`FAILURE_TAIL` characters of its stdout and stderr).

    """
    exe = find_liggghts()
    if exe is None:
        raise LiggghtsError(f"liggghts is not on PATH ({LIGGGHTS_INSTALL})")
    work = Path(work_dir)
    command = [*prefix, exe, "-in", deck_name]
    t0 = time.perf_counter()
    # errors="replace": LIGGGHTS can print raw bytes (a clump template's name, a garbled error
    # line) that are not UTF-8; its message must still reach the user
    done = subprocess.run(command, cwd=work, capture_output=True, text=True, errors="replace")
    wall = time.perf_counter() - t0
    (work / log_name).write_text(done.stdout + done.stderr)
    loops = loop_times(done.stdout)
    if done.returncode != 0 or len(loops) < min_loops:
        raise LiggghtsError(
            f"LIGGGHTS failed ({' '.join(command)} in {work}: exit status {done.returncode}, "
            f"{len(loops)} 'Loop time' lines, {min_loops} expected); the end of its output:\n"
            f"{done.stdout[-FAILURE_TAIL:]}{done.stderr[-FAILURE_TAIL:]}"
        )
    return LiggghtsRun(done.stdout, wall, loops, liggghts_version(done.stdout))
