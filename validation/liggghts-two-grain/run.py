"""dem's ``liggghts`` tangential law against LIGGGHTS-PUBLIC 3.8 itself, on Chung and Ooi's test 8.

    nice -n 10 .venv/bin/python validation/liggghts-two-grain/run.py           # all, ~100 s
    nice -n 10 .venv/bin/python validation/liggghts-two-grain/run.py --short   # psi_1 0.5, 12
    .venv/bin/python validation/liggghts-two-grain/run.py --report-only        # the tables again

validation/contact-benchmarks finds that dem's ``contact.tangential = "liggghts"`` law misses
its own continuous-time design in test 8 (two spheres, Al alloy r = 10 mm below, Mg alloy
r = 5 mm above, 1 m/s relative normal speed, mu = 0.1, e = 0.5) by up to 0.20 (Hertz) and 0.97
(linear) in psi_2, and says that this is LIGGGHTS's own behaviour at the same time step. This
script runs the same collisions in LIGGGHTS and sets the three side by side.

Per law (:data:`LAWS`: Hertz and linear normal laws, ``tangential = "liggghts"``,
``limit_force`` off and on) and per oblique point of test 8 (psi_1 of the benchmark's full list,
or its short one), at dem's automatic step dt and at dt/2:

- **dem**: the benchmark's own collision (``benchmarks._oblique_setups(8, ...)``, its case keys
  ``benchmarks._case_keys``, :func:`collide.pair_collision`: gravity and drive off, the spheres
  touching after 2.5 steps of free flight);
- **LIGGGHTS**: a deck (:func:`deck_lines`) with the same two atoms (``create_atoms single``,
  ``set atom ... diameter ... density``, ``velocity ... set``), the material and law words of
  :func:`dem.io.liggghts.contact.contact_block` (the mapping ``dem export liggghts`` ships: for
  Hertz ``youngsModulus``, ``poissonsRatio``, ``coefficientRestitution``,
  ``coefficientFriction`` and ``model hertz tangential history``; for linear ``model
  hooke/stiffness`` with ``kn``, ``kt``, ``gamman_abs``, ``gammat_abs``, ``absolute_damping on``,
  its m* set to the pair's), ``limitForce on|off``, ``fix nve/sphere``, the same dt and the same
  number of steps; ``dump custom`` of every step (x, v, omega, f to 17 digits);
- **design**: the law's own equations in continuous time (:func:`analytic.law_reference`, as the
  benchmark takes it, at 20000 steps a contact).

Both runs are read by the same function, :func:`collide.measure`: psi_2 = kappa u2 / (mu v_n),
u2 the slip of the contact point after the collision with the full radii; the normalised spin
change of the upper sphere Omega = kappa r_1 dw_1 / (mu v_n) (m_1 / m*); the restitution e; and
the largest |F_t| / (mu F_n) over the loaded steps (``coulomb_excess`` + 1).
Written: results.json (every run, the decks' hashes, LIGGGHTS's version and command), the
example decks in decks/ and README.md's tables.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
BENCH = ROOT / "validation" / "contact-benchmarks"
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(BENCH))

import analytic  # noqa: E402
import benchmarks  # noqa: E402
import collide  # noqa: E402

from dem import provenance  # noqa: E402
from dem.io.liggghts.contact import contact_block  # noqa: E402
from dem.io.liggghts.launcher import find_liggghts, run_liggghts  # noqa: E402
from validation._lib import tables  # noqa: E402

SCRIPT = "validation/liggghts-two-grain/run.py"
TEST = 8
LAWS = [benchmarks.Law(normal, "liggghts", limit)
        for normal in ("hertz_mindlin", "linear") for limit in (False, True)]  # fmt: skip
#: The dt factors: dem's automatic step and its half.
FACTORS = (1, 2)
#: Steps of the continuous-time reference per contact (the benchmark's full run).
REFERENCE_STEPS = 20_000
DECK = "in.liggghts"
DUMP = "dump.txt"
#: The columns of the dump, in order.
COLUMNS = ("id", "x", "y", "z", "vx", "vy", "vz", "omegax", "omegay", "omegaz", "fx", "fy",
           "fz", "radius", "mass")  # fmt: skip
#: Example decks kept in decks/: (law name, psi_1, dt factor).
KEEP = {("hertz/liggghts", 8.0, 1), ("hertz/liggghts/limit", 8.0, 1),
        ("linear/liggghts", 16.0, 1), ("linear/liggghts/limit", 16.0, 1)}  # fmt: skip


def setup(is_short: bool):
    """Test 8 as the benchmark builds it: (contact, grains, points, initial velocities).

    The velocities (v_x, v_z) of sphere 0 (below) and 1 (above) per point, in the centre-of-mass
    frame, are those of ``benchmarks._oblique_setups``'s ``slid`` (checked against dem's record
    by :func:`compare_start`).
    """
    c, kind, grains, points = benchmarks._oblique_setups(TEST, is_short)
    assert kind == "pair"
    r0, r1 = 0.010, 0.005
    rho0, rho1 = benchmarks.MATERIALS["al_alloy"][2], benchmarks.MATERIALS["mg_alloy"][2]
    m0, m1 = rho0 * 4 / 3 * math.pi * r0**3, rho1 * 4 / 3 * math.pi * r1**3
    f0, f1 = m1 / (m0 + m1), m0 / (m0 + m1)
    unit = c.friction * 1.0 / c.kappa
    velocities = []
    for _, psi, vn, _ in points:
        vt = psi * unit
        velocities.append(((-f0 * vt, f0 * vn), (f1 * vt, -f1 * vn)))
    spheres = {"radii": (r0, r1), "densities": (rho0, rho1), "masses": (m0, m1)}
    return c, spheres, points, velocities


def initial_state(spheres: dict, v0, v1, dt: float):
    """Centres and velocities (2, 3) as :func:`collide.pair_collision` places them."""
    r0, r1 = spheres["radii"]
    vel = np.array([[v0[0], 0.0, v0[1]], [v1[0], 0.0, v1[1]]])
    touch = np.array([collide.PAIR_CENTRE - [0.0, 0.0, r0], collide.PAIR_CENTRE + [0.0, 0.0, r1]])
    return touch - vel * collide.START_STEPS * dt, vel


def _g(x) -> str:
    """A float to the last bit."""
    return f"{float(x):.17g}"


def deck_lines(scene, c, spheres: dict, x0, v0, dt: float, steps: int, title: str) -> list[str]:
    """The LIGGGHTS deck of one collision: dem's mapped material and law, two atoms, a dump.

    The material block is :func:`dem.io.liggghts.contact.contact_block`'s (atom type 1 the
    grains; type 2, the walls, has no atom here). Its linear damping takes m* = m/2 of a sphere
    of mass m: it is given m = 2 m* of the pair, so gamma_n = 2 zeta sqrt(k_n m*) as dem's.
    """
    material, model, settings = contact_block(scene, 2.0 * c.m_eff)
    lines = [
        f"# {title}",
        "# written by validation/liggghts-two-grain/run.py; run: liggghts -in " + DECK,
        "atom_style granular",
        "atom_modify map array",
        "boundary f f f",
        "newton off",
        "communicate single vel yes",
        "units si",
    ]
    if scene.case.contact.youngs_modulus is not None and scene.case.contact.youngs_modulus > 1e9:
        lines.append("hard_particles yes")
    centre = collide.PAIR_CENTRE
    lines += [
        f"region domain block {_g(centre[0] - 0.05)} {_g(centre[0] + 0.05)} -0.05 0.05 "
        f"{_g(centre[2] - 0.05)} {_g(centre[2] + 0.05)} units box",
        "create_box 2 domain",
        "neighbor 0.001 bin",
        "neigh_modify delay 0",
        *material,
        f"pair_style gran {model} {settings}",
        "pair_coeff * *",
        f"timestep {_g(dt)}",
        "fix integr all nve/sphere",
    ]
    for i, (x, v) in enumerate(zip(x0, v0, strict=True)):
        r, rho = spheres["radii"][i], spheres["densities"][i]
        lines += [
            f"create_atoms 1 single {_g(x[0])} {_g(x[1])} {_g(x[2])} units box",
            f"set atom {i + 1} diameter {_g(2.0 * r)}",
            f"set atom {i + 1} density {_g(rho)}",
            f"group g{i + 1} id {i + 1}",
            f"velocity g{i + 1} set {_g(v[0])} {_g(v[1])} {_g(v[2])} units box",
        ]
    form = " ".join(["%d"] + ["%.17g"] * (len(COLUMNS) - 1))
    lines += [
        f"dump d all custom 1 {DUMP} {' '.join(COLUMNS)}",
        f'dump_modify d sort id format "{form}"',
        "thermo_style custom step atoms ke",
        f"thermo {steps}",
        f"run {steps}",
    ]
    return lines


def read_dump(path: Path) -> dict:
    """The dump's frames as :func:`collide.step_through`'s arrays (x, v, omega, f) and radius,
    mass of the first frame."""
    frames, block = [], None
    lines = path.read_text().splitlines()
    k = 0
    while k < len(lines):
        if lines[k].startswith("ITEM: NUMBER OF ATOMS"):
            n = int(lines[k + 1])
        elif lines[k].startswith("ITEM: ATOMS"):
            block = np.array(
                [[float(w) for w in line.split()] for line in lines[k + 1 : k + 1 + n]]
            )
            frames.append(block[np.argsort(block[:, 0])])
            k += n
        k += 1
    a = np.array(frames)
    return {"x": a[:, :, 1:4], "v": a[:, :, 4:7], "omega": a[:, :, 7:10], "f": a[:, :, 10:13],
            "radius": a[0, :, 13], "mass": a[0, :, 14]}  # fmt: skip


def run_liggghts_collision(scene, c, spheres, v0, v1, dt, steps, title, work: Path) -> dict:
    """One collision in LIGGGHTS (:func:`deck_lines`): the recorded arrays, the deck, the log."""
    x0, vel = initial_state(spheres, v0, v1, dt)
    work.mkdir(parents=True, exist_ok=True)
    text = "\n".join(deck_lines(scene, c, spheres, x0, vel, dt, steps, title)) + "\n"
    (work / DECK).write_text(text)
    done = run_liggghts(work, DECK)
    h = read_dump(work / DUMP)
    return {"h": h, "deck": text, "version": done.version, "stdout": done.stdout}


def normalised(m: dict, c) -> dict:
    """psi_2, Omega, e and max |F_t| / (mu F_n) of one :func:`collide.measure` result."""
    vn = m["vn_in"]
    upper = 1
    return {
        "psi_in": analytic.normalise(m["u_in"], c.kappa, c.friction, vn),
        "psi_out": analytic.normalise(m["u_out"], c.kappa, c.friction, vn),
        "spin_out_norm": analytic.normalise(
            m["radii"][upper] * (m["spin_out"][upper] - m["spin_in"][upper]),
            c.kappa, c.friction, vn) * m["masses"][upper] / c.m_eff,
        "restitution": m["restitution"],
        "max_ft_over_mu_fn": m["coulomb_excess"] + 1.0,
        "after": m["after"],
        "contact_steps": m["contact_steps"],
        "vn_in": vn,
        "u_in": m["u_in"],
        "dt_s": m["dt_s"],
        "peak_force_n": m["peak_force_n"],
    }  # fmt: skip


def design(scene, c, psis, law) -> dict:
    """The law's continuous-time answer at each psi_1 (the benchmark's reference)."""
    vns = np.ones(len(psis))
    ref = analytic.law_reference(
        benchmarks.law_constants(scene, "pair"), np.asarray(psis) * c.friction * vns / c.kappa,
        vns, c.m_eff, c.r_eff, steps=REFERENCE_STEPS)  # fmt: skip
    return {
        "psi_out": [analytic.normalise(float(u), c.kappa, c.friction, 1.0) for u in ref["u_out"]],
        "spin_out_norm": [
            analytic.normalise(2.5 * float(j) / c.m_eff, c.kappa, c.friction, 1.0)
            for j in ref["impulse_t"]
        ],  # fmt: skip
        "restitution": [float(e) for e in ref["restitution"]],
    }


def collide_point(law, scene, c, spheres, point, velocities, factor: int, work: Path,
                  dt0: float | None = None) -> dict:  # fmt: skip
    """One point of test 8 at dt = dt0 / ``factor`` (dt0 None: dem's automatic step) in dem and
    in LIGGGHTS: a results row without the design (:func:`normalised` of each code)."""
    label, psi, _vn, run = point
    v0, v1 = velocities
    dem_m = run(scene, None if dt0 is None else dt0 / factor)
    dt = dem_m["dt_s"]
    steps = len(dem_m["history"]["t_s"]) - 1
    title = (f"test {TEST}, {law.name}, {label}, dt = {dt:.6g} s "
             f"(dem's automatic step / {factor}), {steps} steps")  # fmt: skip
    lig = run_liggghts_collision(scene, c, spheres, v0, v1, dt, steps, title, work)
    h = lig["h"]
    lig_m = collide.measure(h, "pair", dt, h["radius"], h["mass"], c.friction)
    a, b = normalised(dem_m, c), normalised(lig_m, c)
    return {
        "law": law.name, "psi_in": psi, "dt_factor": factor, "dt_s": dt, "steps": steps,
        "deck": lig["deck"], "liggghts_version": lig["version"],
        "deck_sha256": hashlib.sha256(lig["deck"].encode()).hexdigest(),
        "dem": a, "liggghts": b,
        "start": {"radii_dem": dem_m["radii"], "radii_liggghts": lig_m["radii"],
                  "masses_dem": dem_m["masses"], "masses_liggghts": lig_m["masses"],
                  "du_in": b["u_in"] - a["u_in"], "dvn_in": b["vn_in"] - a["vn_in"]},
        "liggghts_force_at_end": float(np.max(np.abs(h["f"][-1]))),
    }  # fmt: skip


def law_scene(law, c, spheres):
    """The benchmark's scene of ``law`` for test 8 (its case keys, the upper sphere's grain)."""
    return collide.scene_for(benchmarks._case_keys(law, c, spheres["radii"][1],
                                                   spheres["densities"][1]))  # fmt: skip


def one_point(law_name: str, psi: float, work: Path, factor: int = 1) -> dict:
    """:func:`collide_point` of one law (by name, :data:`LAWS`) and psi_1 of the full list."""
    law = next(x for x in LAWS if x.name == law_name)
    c, spheres, points, velocities = setup(False)
    k = next(i for i, p in enumerate(points) if p[1] == psi)
    scene = law_scene(law, c, spheres)
    dt0 = None
    if factor != 1:
        dt0 = points[k][3](scene, None)["dt_s"]
    return collide_point(law, scene, c, spheres, points[k], velocities[k], factor, work, dt0)


def run_all(is_short: bool, work_root: Path) -> dict:
    """Every law, point and dt in dem and in LIGGGHTS; the rows of results.json."""
    c, spheres, points, velocities = setup(is_short)
    rows, version = [], None
    decks = HERE / "decks"
    for law in LAWS:
        scene = law_scene(law, c, spheres)
        ref = design(scene, c, [p for _, p, _, _ in points], law)
        for k, (point, vel) in enumerate(zip(points, velocities, strict=True)):
            dt0 = None
            for factor in FACTORS:
                psi = point[1]
                work = work_root / f"{law.name.replace('/', '-')}-psi{psi:g}-dt{factor}"
                row = collide_point(law, scene, c, spheres, point, vel, factor, work, dt0)
                dt0 = dt0 or row["dt_s"]
                deck = row.pop("deck")
                version = version or row.pop("liggghts_version")
                row.pop("liggghts_version", None)
                if (law.name, psi, factor) in KEEP:
                    decks.mkdir(exist_ok=True)
                    (decks / f"{law.name.replace('/', '-')}-psi{psi:g}.in").write_text(deck)
                row["design"] = {key: ref[key][k] for key in ref}
                rows.append(row)
                a, b = row["dem"], row["liggghts"]
                print(json.dumps({"law": law.name, "psi": psi, "dt/": factor,
                                  "psi2": [a["psi_out"], b["psi_out"], row["design"]["psi_out"]],
                                  "ft": [a["max_ft_over_mu_fn"], b["max_ft_over_mu_fn"]]}),
                      flush=True)  # fmt: skip
    return {"rows": rows, "liggghts_version": version}


def _json_safe(value):
    if isinstance(value, dict):
        return {key: _json_safe(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.floating, np.integer)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _pairs(results: dict):
    """(row at dt, row at dt/2) per law and point."""
    rows = results["rows"]
    for row in rows:
        if row["dt_factor"] == 1:
            half = next(r for r in rows if (r["law"], r["psi_in"], r["dt_factor"])
                        == (row["law"], row["psi_in"], 2))  # fmt: skip
            yield row, half


def summary(results: dict) -> dict:
    """Per law: the largest |dem - LIGGGHTS| and |X - design| of psi_2, Omega and e, at dt and
    dt/2, and the largest |F_t| / (mu F_n) of each code."""
    out = {}
    for law in dict.fromkeys(r["law"] for r in results["rows"]):
        s = {}
        for factor in FACTORS:
            rows = [r for r in results["rows"] if r["law"] == law and r["dt_factor"] == factor]
            for q in ("psi_out", "spin_out_norm", "restitution"):
                s[f"{q}/dem-liggghts/dt{factor}"] = max(
                    abs(r["dem"][q] - r["liggghts"][q]) for r in rows
                )
                for code in ("dem", "liggghts"):
                    worst = max(
                        rows, key=lambda r, q=q, code=code: abs(r[code][q] - r["design"][q])
                    )
                    s[f"{q}/{code}-design/dt{factor}"] = worst[code][q] - worst["design"][q]
                    s[f"{q}/{code}-design/dt{factor}/psi"] = worst["psi_in"]
            for code in ("dem", "liggghts"):
                s[f"max_ft/{code}/dt{factor}"] = max(r[code]["max_ft_over_mu_fn"] for r in rows)
        out[law] = s
    return out


def report(results: dict) -> list[str]:
    """README's tables (markdown) from results.json."""
    out = [
        f"Measured {results['date']} with dem at commit {results['git_commit']}, "
        f"LIGGGHTS {results['liggghts_version']} (`{results['liggghts_command']}`), "
        f"mode {results['mode']}.",
        "",
        "Per law and psi_1 at dem's step dt (dt/2 in the next table): psi_2 of dem, LIGGGHTS and "
        "the law's continuous-time design; dem - LIGGGHTS (psi_2, Omega, e); each code's miss of "
        "the design; the largest |F_t| / (mu F_n) of dem and LIGGGHTS.",
        "",
        "| law | psi_1 | psi_2 dem | psi_2 LIGGGHTS | psi_2 design | d psi_2 (dem - L) | "
        "dem - design | L - design | Omega dem | Omega L | Omega design | d Omega | e dem | e L "
        "| e design | d e | max Ft/muFn dem | L |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row, _ in _pairs(results):
        a, b, d = row["dem"], row["liggghts"], row["design"]
        out.append(
            f"| {row['law']} | {row['psi_in']:g} | {a['psi_out']:.5f} | {b['psi_out']:.5f} | "
            f"{d['psi_out']:.5f} | {a['psi_out'] - b['psi_out']:+.1e} | "
            f"{a['psi_out'] - d['psi_out']:+.4f} | {b['psi_out'] - d['psi_out']:+.4f} | "
            f"{a['spin_out_norm']:.4f} | {b['spin_out_norm']:.4f} | {d['spin_out_norm']:.4f} | "
            f"{a['spin_out_norm'] - b['spin_out_norm']:+.1e} | {a['restitution']:.5f} | "
            f"{b['restitution']:.5f} | {d['restitution']:.5f} | "
            f"{a['restitution'] - b['restitution']:+.1e} | {a['max_ft_over_mu_fn']:.3g} | "
            f"{b['max_ft_over_mu_fn']:.3g} |"
        )
    out += [
        "",
        "The step halved: psi_2's miss of the design at dt and dt/2 in each code (a first-order "
        "error halves), and dem - LIGGGHTS at dt/2:",
        "",
        "| law | psi_1 | dem - design (dt) | dem - design (dt/2) | L - design (dt) | "
        "L - design (dt/2) | d psi_2 (dt/2) | d Omega (dt/2) | d e (dt/2) | max Ft/muFn dem, L "
        "(dt/2) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row, half in _pairs(results):
        d = row["design"]["psi_out"]
        a2, b2 = half["dem"], half["liggghts"]
        out.append(
            f"| {row['law']} | {row['psi_in']:g} | {row['dem']['psi_out'] - d:+.4f} | "
            f"{a2['psi_out'] - d:+.4f} | {row['liggghts']['psi_out'] - d:+.4f} | "
            f"{b2['psi_out'] - d:+.4f} | {a2['psi_out'] - b2['psi_out']:+.1e} | "
            f"{a2['spin_out_norm'] - b2['spin_out_norm']:+.1e} | "
            f"{a2['restitution'] - b2['restitution']:+.1e} | "
            f"{a2['max_ft_over_mu_fn']:.3g}, {b2['max_ft_over_mu_fn']:.3g} |"
        )
    out += [
        "",
        "Per law, the largest over the points (dem - LIGGGHTS: largest |difference|; X - design: "
        "the signed miss of largest size, at psi_1 in brackets):",
        "",
        "| law | dt | max abs d psi_2 | max abs d Omega | max abs d e | dem - design psi_2 | "
        "L - design psi_2 | max Ft/muFn dem | L |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for law, s in results["summary"].items():
        for factor in FACTORS:
            t = f"/dt{factor}"
            out.append(
                f"| {law} | dt/{factor} | {s['psi_out/dem-liggghts' + t]:.1e} | "
                f"{s['spin_out_norm/dem-liggghts' + t]:.1e} | "
                f"{s['restitution/dem-liggghts' + t]:.1e} | "
                f"{s['psi_out/dem-design' + t]:+.4f} ({s['psi_out/dem-design' + t + '/psi']:g}) | "
                f"{s['psi_out/liggghts-design' + t]:+.4f} "
                f"({s['psi_out/liggghts-design' + t + '/psi']:g}) | "
                f"{s['max_ft/dem' + t]:.3g} | {s['max_ft/liggghts' + t]:.3g} |"
            )
    return out


def write_readme_tables(results: dict) -> None:
    """Replace the tables between the markers in README.md (if it has them)."""
    tables.write_readme_tables(HERE / "README.md", report(results))


def liggghts_unavailable() -> str | None:
    """Why LIGGGHTS cannot be run here, or None."""
    if find_liggghts() is None:
        return "liggghts is not on PATH (apt-get install -y liggghts: LIGGGHTS-PUBLIC 3.8)"
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--short", action="store_true", help="psi_1 = 0.5 and 12 only")
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args(argv)
    path = HERE / "results.json"
    if args.report_only:
        results = json.loads(path.read_text())
    else:
        why = liggghts_unavailable()
        if why:
            print(why, file=sys.stderr)
            return 2
        with tempfile.TemporaryDirectory() as tmp:
            data = run_all(args.short, Path(tmp))
        record = provenance.record()
        results = {
            "command": " ".join([SCRIPT, *(sys.argv[1:] if argv is None else argv)]),
            "date": record["date"], "git_commit": record["git_commit"],
            "mode": "short" if args.short else "full",
            "liggghts_version": data["liggghts_version"],
            "liggghts_command": f"{find_liggghts()} -in {DECK} (in each run's directory)",
            "test": TEST, "laws": [law.name for law in LAWS],
            "definitions": {
                "psi_out": "kappa u2 / (mu v_n), u2 the contact point's slip after, full radii "
                           "(collide.measure, analytic.normalise)",
                "spin_out_norm": "kappa r_1 (w_1 - w_1,in) / (mu v_n) m_1 / m*, upper sphere",
                "restitution": "-(v_r . n)_after / (v_r . n)_before",
                "max_ft_over_mu_fn": "max over loaded steps of |F_t| / (mu F_n)",
                "design": "analytic.law_reference (continuous time) at "
                          f"{REFERENCE_STEPS} steps a contact",
            },
            "rows": data["rows"],
            "provenance": record,
        }  # fmt: skip
        results["summary"] = summary(results)
        path.write_text(json.dumps(_json_safe(results), indent=1, allow_nan=False) + "\n")
    print("\n".join(report(results)))
    write_readme_tables(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
