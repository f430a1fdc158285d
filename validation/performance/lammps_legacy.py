"""A ``pair granular`` deck turned into one for LAMMPS's legacy pair ``gran/hertz/history``.

The legacy pair is LAMMPS's fastest granular pair (about twice ``pair granular`` on the sphere
bed), so bench_bulk.py times it beside ``pair granular``. It is a cost benchmark: the legacy deck
does the same work per contact (a Hertz spring and dashpot, a tangential spring with history, a
Coulomb cap), not the same physics as dem's law.

LAMMPS's legacy Hertz contact (pair_gran_hertz_history.cpp, fix_wall_gran.cpp), with
a = sqrt(delta R*) (``polyhertz``) and m* the pair's reduced mass (a wall's: the grain's):

    F_n = a (Kn delta - m* gamma_n v_n),   F_t = -a (Kt s + m* gamma_t v_t),   |F_t| <= xmu |F_n|

``pair_style gran/hertz/history Kn Kt gamma_n gamma_t xmu dampflag`` and
``fix ID all wall/gran hertz/history Kn Kt gamma_n gamma_t xmu dampflag wallstyle args``; in
SI units Kn and Kt are Pa, gamma_n and gamma_t 1/(s m) (LAMMPS docs, pair_style gran and
fix wall/gran). From dem's law (:class:`dem.physics.contact.ContactLaw`, "coulomb", the law the
granular deck expresses: :mod:`dem.io.lammps.contact`), per interaction (grain-grain for the
pair, grain-wall for the walls):

- Kn = 4/3 Y*: dem's Hertz spring 4/3 Y* sqrt(R*) delta^(3/2), exactly;
- Kt = C_kt: dem's k_t = C_kt a, the number the granular deck writes after ``mindlin``;
- gamma_n: dem's dashpot is C_dn sqrt(a m*) (C_dn = -2 sqrt(5/6) beta sqrt(2 Y*)), so it grows
  as delta^(1/4); the legacy one, a m* gamma_n, as delta^(1/2). They agree at one overlap only:
  gamma_n = C_dn / sqrt(a0 m*), with a0 = sqrt(R* delta0) at delta0 the resting overlap of one
  grain under its own weight m g on that contact (on a grain: R* = R/2, m* = m/2; on a flat
  wall: R* = R, m* = m);
- gamma_t = x gamma_n, x = C_dt / C_dn, the ratio the granular deck writes after ``mindlin k``;
- xmu = mu; dampflag 1 (the tangential dashpot on); ``limit_damping`` kept where the granular
  deck has it.

The legacy reset of the spring at the cap and its spring rotation are LAMMPS's, not dem's.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dem import config
from dem.physics.contact import ContactLaw

#: The deck's file name (:data:`dem.io.lammps.deck.DECK_NAME`).
DECK_NAME = "in.lammps"
#: A granular run's files (:mod:`dem.io.lammps.launcher`), not copied into the legacy deck.
RUN_FILES = ("log.lammps", "vx_mean.txt", "summary.json")
#: The legacy pair and wall model.
LEGACY_PAIR = "gran/hertz/history"
LEGACY_WALL = "hertz/history"
#: The walls ``fix wall/gran`` takes (``fix wall/gran/region`` takes ``region ID``).
WALL_STYLES = ("xplane", "yplane", "zplane", "zcylinder", "region")
#: Relative agreement required between the granular deck's Kt, x, mu and the law's.
MATCH = 1e-9


class LegacyDeckError(ValueError):
    """A deck or a law the legacy mapping cannot take; the message names the value."""


@dataclass(frozen=True)
class LegacyConstants:
    """The legacy constants of one interaction, SI units.

    Attributes:
        kn: Kn = 4/3 Y*, Pa.
        kt: Kt = C_kt, Pa.
        gamma_n: 1/(s m), dem's normal dashpot at ``delta0``.
        gamma_t: gamma_n times the granular deck's tangential dashpot ratio x, 1/(s m).
        xmu: mu.
        limit_damping: True where the law keeps F_n >= 0 (dem's limit_force).
        delta0: The resting overlap gamma_n is matched at, m.
        ratio: x = C_dt / C_dn.

    """

    kn: float
    kt: float
    gamma_n: float
    gamma_t: float
    xmu: float
    limit_damping: bool
    delta0: float
    ratio: float

    def words(self) -> str:
        """``Kn Kt gamma_n gamma_t xmu 1`` (and ``limit_damping``)."""
        out = (
            f"{self.kn:.17g} {self.kt:.17g} {self.gamma_n:.17g} {self.gamma_t:.17g} "
            f"{self.xmu:.17g} 1"
        )
        return out + (" limit_damping" if self.limit_damping else "")


def legacy_constants(
    law: ContactLaw, mass: float, radius: float, *, wall: bool = False,
    gravity: float = config.GRAVITY,
) -> LegacyConstants:  # fmt: skip
    """The legacy constants of the law's grain-grain (or grain-wall) contacts.

    Args:
        law: dem's law under "coulomb" (the granular deck's).
        mass: m, the grain's mass, kg.
        radius: R, the grain's (largest member) sphere radius, m.
        wall: True: the grain-wall interaction (R* = R, m* = m), else R* = R/2, m* = m/2.
        gravity: g, m/s^2 (dem.config.GRAVITY).

    Raises:
        LegacyDeckError: A law that is not Hertz ("hertz_mindlin"), or a non-positive mass or
            radius.

    """
    if law.model != "hertz_mindlin":
        raise LegacyDeckError(
            f"contact.model = {law.model!r}: the legacy mapping is written for "
            f"'hertz_mindlin' (pair_style {LEGACY_PAIR})"
        )
    if not (mass > 0.0 and radius > 0.0):
        raise LegacyDeckError(f"mass {mass!r} kg and radius {radius!r} m must both be > 0")
    interaction = law.grain_wall if wall else law.grain_grain
    k = law.kernel_coefficients(wall)
    y_star = interaction.normal.y_star
    kn = 4.0 / 3.0 * y_star
    r_eff, m_eff = (radius, mass) if wall else (0.5 * radius, 0.5 * mass)
    # the resting overlap of one grain under its own weight: m g = 4/3 Y* sqrt(R*) delta0^(3/2)
    delta0 = (mass * gravity / (kn * math.sqrt(r_eff))) ** (2.0 / 3.0)
    a0 = math.sqrt(r_eff * delta0)
    c_dn, c_dt = k.normal_damping, k.tangential_damping
    # legacy a0 m* gamma_n = dem's C_dn sqrt(a0 m*) at delta0 (delta^(1/2) against delta^(1/4))
    gamma_n = c_dn / math.sqrt(a0 * m_eff)
    ratio = c_dt / c_dn if c_dn > 0.0 else 0.0
    return LegacyConstants(
        kn=kn,
        kt=k.tangential_stiffness,
        gamma_n=gamma_n,
        gamma_t=ratio * gamma_n,
        xmu=interaction.friction,
        limit_damping=interaction.limit_force,
        delta0=delta0,
        ratio=ratio,
    )


def _mindlin(words: list[str], where: str) -> tuple[float, float, float]:
    """(k, x, mu) after ``mindlin`` in a granular model's words."""
    if "mindlin" not in words or len(words) < words.index("mindlin") + 4:
        raise LegacyDeckError(
            f"{where}: no 'tangential mindlin k x mu' in {' '.join(words)!r} (the legacy "
            "mapping takes a hertz/material deck of dem.io.lammps)"
        )
    i = words.index("mindlin")
    return float(words[i + 1]), float(words[i + 2]), float(words[i + 3])


def _check(where: str, deck: tuple[float, float, float], c: LegacyConstants) -> None:
    """Refuse a deck whose Kt, x, mu are not the law's: the deck is of another case."""
    for name, written, ours in zip(("k", "x", "mu"), deck, (c.kt, c.ratio, c.xmu), strict=True):
        if not math.isclose(written, ours, rel_tol=MATCH, abs_tol=1e-300):
            raise LegacyDeckError(
                f"{where}: mindlin {name} = {written!r} in the deck, {ours!r} from the case's "
                "law: the deck was exported from another case or law"
            )


def convert_text(text: str, pair: LegacyConstants, wall: LegacyConstants) -> str:
    """The legacy deck's text of a granular deck's ``text``; every other line as it was.

    ``pair_style granular`` and ``pair_coeff * * hertz/material ...`` become
    ``pair_style gran/hertz/history <pair words>`` and ``pair_coeff * *``; each
    ``fix NAME GROUP wall/gran[/region] granular hertz/material ... WALLSTYLE ARGS`` becomes
    ``fix NAME GROUP wall/gran[/region] hertz/history <wall words> WALLSTYLE ARGS``. A comment
    heading the deck names the mapping and says it is cost-equivalent, not the same physics.

    Raises:
        LegacyDeckError: No ``pair_style granular``, a granular ``pair_coeff`` or wall line
            not of dem's form, or its Kt, x, mu not those of the law.

    """
    lines = text.splitlines()
    code = [line.split("#", 1)[0].split() for line in lines]
    if not any(words == ["pair_style", "granular"] for words in code):
        raise LegacyDeckError(
            "no 'pair_style granular' line in the deck: the legacy mapping takes a deck "
            "exported by dem.io.lammps (dem export lammps)"
        )
    out = []
    pairs = walls = 0
    for line, words in zip(lines, code, strict=True):
        if words == ["pair_style", "granular"]:
            out.append(f"pair_style {LEGACY_PAIR} {pair.words()}")
        elif words[:3] == ["pair_coeff", "*", "*"] and len(words) > 3:
            if words[3] != "hertz/material":
                raise LegacyDeckError(
                    f"pair_coeff model {words[3]!r}: the legacy mapping takes 'hertz/material'"
                )
            _check("pair_coeff", _mindlin(words, "pair_coeff"), pair)
            out.append("pair_coeff * *")
            pairs += 1
        elif len(words) > 4 and words[0] == "fix" and words[3].startswith("wall/gran"):
            if words[4] != "granular":
                out.append(line)
                continue
            style = next((i for i, w in enumerate(words) if w in WALL_STYLES), None)
            if style is None or len(words) < 6 or words[5] != "hertz/material":
                raise LegacyDeckError(
                    f"fix {words[1]}: {line.strip()!r} is not 'granular hertz/material ... "
                    f"WALLSTYLE ARGS' with WALLSTYLE one of {', '.join(WALL_STYLES)}"
                )
            _check(f"fix {words[1]}", _mindlin(words[5:style], f"fix {words[1]}"), wall)
            head = " ".join(words[:4])
            out.append(f"{head} {LEGACY_WALL} {wall.words()} {' '.join(words[style:])}")
            walls += 1
        else:
            out.append(line)
    if pairs != 1:
        raise LegacyDeckError(f"{pairs} 'pair_coeff * * hertz/material' lines; the deck needs 1")
    header = [
        f"# LEGACY DECK, cost-equivalent, NOT the same physics: pair_style granular replaced by "
        f"{LEGACY_PAIR} and {walls} wall/gran granular wall(s) by {LEGACY_WALL}",
        "#   (validation/performance/lammps_legacy.py): Kn = 4/3 Y*, Kt = C_kt (mindlin k), "
        "gamma_n = dem's normal dashpot at the resting overlap of one grain under gravity,",
        "#   gamma_t = x gamma_n (the granular deck's tangential dashpot ratio), xmu = mu; the "
        "legacy dashpot scales as delta^(1/2), dem's Hertz dashpot as delta^(1/4)",
        f"#   grain-grain: Kn {pair.kn:.6g} Pa, Kt {pair.kt:.6g} Pa, gamma_n {pair.gamma_n:.6g} "
        f"1/(s m) at delta0 {pair.delta0:.4g} m, gamma_t {pair.gamma_t:.6g}, xmu {pair.xmu:g}",
        f"#   grain-wall: Kn {wall.kn:.6g} Pa, Kt {wall.kt:.6g} Pa, gamma_n {wall.gamma_n:.6g} "
        f"1/(s m) at delta0 {wall.delta0:.4g} m, gamma_t {wall.gamma_t:.6g}, xmu {wall.xmu:g}",
        "#   the comments below are the pair granular deck's, as exported; its mapping is not "
        "this deck's",
    ]
    return "\n".join(header + out) + "\n"


def grain_mass_radius(scene) -> tuple[float, float]:
    """(m, R) of the grain of a :class:`dem.scene.resolved.Scene`: its mass and largest sphere."""
    return float(scene.grain_mass), float(np.max(scene.grain.radii))


def constants_for(scene) -> tuple[LegacyConstants, LegacyConstants]:
    """(grain-grain, grain-wall) legacy constants of a scene under "coulomb" (the deck's law)."""
    law = scene.law
    if law.tangential != "coulomb":
        raise LegacyDeckError(
            f'contact.tangential = "{law.tangential}": the legacy mapping takes the law of the '
            'granular deck, "coulomb" (case.with_tangential("coulomb"))'
        )
    mass, radius = grain_mass_radius(scene)
    return legacy_constants(law, mass, radius), legacy_constants(law, mass, radius, wall=True)


def write_legacy_deck(granular_dir, legacy_dir, scene) -> Path:
    """Copy the granular deck folder to ``legacy_dir`` and convert its in.lammps; its path.

    ``scene``: the :class:`dem.scene.resolved.Scene` the granular deck was exported from
    (``plan_lammps(...).scene``), under "coulomb". The folder is replaced if it exists; the run
    files of a granular run (log, velocity) are not copied.
    """
    src, dst = Path(granular_dir), Path(legacy_dir)
    text = (src / DECK_NAME).read_text()
    converted = convert_text(text, *constants_for(scene))
    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns(*RUN_FILES))
    path = dst / DECK_NAME
    path.write_text(converted)
    return path
