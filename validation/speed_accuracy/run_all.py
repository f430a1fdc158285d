"""Every speed-accuracy study in one go: all runs in one pool (about 25 min on 2 cores), then
each study's CSV and chart, the ladder, and ``dem/data/speed_accuracy.json``: the summary that
``dem plan`` reads (errors of each setting, the cheapest acceptable settings, rates).

    .venv/bin/python validation/speed_accuracy/run_all.py [--figures]
"""

import sys

import contact_model
import ladder
import numpy as np
import reference
import resolution
import section
import skin
import stiffness
import timestep
from study import (
    BASE,
    CASES,
    FILL_SEEDS,
    HERE,
    REFERENCE,
    ROOT,
    TOLERANCE,
    cached,
    default_points,
    ensure,
    load,
    plot,
    print_table,
    rigid_limit,
    table,
    write_csv,
)
from study import (
    reference as reference_of,
)

from dem import provenance
from dem.run import accuracy

STUDIES = (reference, timestep, contact_model, skin, section, resolution)


def main() -> int:
    if "--figures" not in sys.argv:
        ensure([p for m in STUDIES for p in m.POINTS] + ladder.POINTS)
    rows = cached()
    for m in STUDIES:
        name = m.__name__
        out = table(m.POINTS, rows)
        write_csv(name, out, m.__file__)
        plot(out, HERE / f"{name}.png", (m.__doc__ or name).splitlines()[0])
        print(f"\n== {name}")
        print_table(out)
    stiffness.main()
    sys.argv = [sys.argv[0], "--figures"]
    ladder.main()
    data = plan_data(rows)
    path = ROOT / "dem" / "data" / "speed_accuracy.json"
    accuracy.write_study_data(path, data)
    for case, d in data["cases"].items():
        print(f"{case}: cheapest acceptable {d['cheapest']}")
    print(f"wrote {path.relative_to(ROOT)}")
    return 0


def _effects(rows: list[dict], x_of, shipped_x) -> tuple[list[list[float]], dict]:
    """``[[x, relative effect], ...]`` with the base setting at 0, and each x's verdict:
    "ok" (acceptable), "bad" (off by more than the tolerance and by more than twice its
    uncertainty) or "open" (neither: a single noisy fill that settles nothing)."""
    sel = [r for r in rows if r["label"] != "base" and not r["failed"]]
    series = [[float(x_of(r)), r["relative_effect"]] for r in sel] + [[float(shipped_x), 0.0]]
    verdict = {float(x_of(r)): _verdict(r, "effect") for r in sel} | {float(shipped_x): "ok"}
    return series, verdict


def _verdict(r: dict, kind: str) -> str:
    if r["failed"]:
        return "bad"
    if r["acceptable" if kind == "error" else "effect_acceptable"]:
        return "ok"
    e, u = abs(r[kind]), r[f"{kind}_uncertainty"]
    base = r["reference"] if kind == "error" else r["velocity_norm"] - r["effect"]
    return "bad" if e > TOLERANCE * base and e > 2.0 * u else "open"


def _stiffness_verdict(r: dict) -> str:
    """A sweep point against the rigid limit: "ok" within the tolerance and resolved (its
    uncertainty under half the tolerance), "bad" beyond it by more than two uncertainties
    (the rule ``dem`` warns by, validation/bulk-convergence), else "open"."""
    e, u = abs(r["relative_error"]), r["error_uncertainty"] / r["reference"]
    if e - 2.0 * u > TOLERANCE:
        return "bad"
    return "ok" if e <= TOLERANCE and u <= TOLERANCE / 2 else "open"


def _walk(verdict: dict, start: float, *, upward: bool) -> float:
    """From ``start`` towards the cheap side: the farthest "ok" setting before a "bad" one."""
    xs = sorted(x for x in verdict if (x >= start if upward else x <= start))
    if not upward:
        xs = xs[::-1]
    best = start
    for x in xs:
        if verdict[x] == "bad":
            break
        if verdict[x] == "ok":
            best = x
    return best


def plan_data(rows: dict) -> dict:
    """The study reduced to what ``dem plan`` needs, per grain kind.

    ``stiffness``: the error against the rigid limit at each Young's modulus
    (validation/bulk-convergence's sweep); ``timestep``, ``section_*``, ``resolution``,
    ``contact_model``: the effect of each setting against the base settings (0 there).
    ``cheapest``: walking from the stiffest point (stiffness) or the base value (the others)
    towards the cheap side, the last setting still acceptable. ``conditions``: the drive,
    material and tangential law every figure was measured under.
    """
    out = {"provenance": provenance.record(), "tolerance": TOLERANCE,
           "base": BASE, "reference": {"source": REFERENCE,
                         "seeds": {k: list(v) for k, v in FILL_SEEDS.items()}},
           "cases": {}}  # fmt: skip
    for case in CASES:
        ref = reference_of(case, rows)
        ship = [rows[p.key] for p in default_points("x", case, FILL_SEEDS[case])]
        shipped_err = (ref.shipped - ref.velocity_norm) / ref.velocity_norm
        c = load(default_points("x", case)[0])  # the case at the study's base settings
        d_, m_ = c.drive, c.material
        conditions = {"tangential": c.contact.tangential, "throw_number": d_.throw_number,
                      "angle": d_.angle, "friction": m_.friction,
                      "inclination": c.trough.inclination,
                      "restitution_tangential": m_.restitution_tangential,
                      "restitution_normal": m_.restitution_normal}  # fmt: skip
        g_len = accuracy.grain_length(c)
        v_ref = ref.velocity_norm
        stderr = float(np.mean([r["stderr"] for r in ship])) / v_ref
        d = {
            "conditions": conditions,
            "reference": v_ref,
            "fill_spread": ref.fill_spread / v_ref,
            "base_error": shipped_err,
            "base_stderr": stderr,
            "base_cycles": int(ship[0]["cycles"]),
            "settle_cycles": float(np.mean([r["settle_cycles"] for r in ship])),
            "particle_steps_per_s_1thread": float(
                np.mean([r["particle_steps"] / r["wall_time_s"] for r in ship])
            ),
        }
        # the stiffness sweep (dt = 0.5 of the limit) against the rigid limit
        st = [r for r in stiffness.rows() if r["case"] == case]
        d["stiffness"] = [[r["x"], r["relative_error"]] for r in st]
        ok = {r["x"]: _stiffness_verdict(r) for r in st}
        rigid = rigid_limit(case)
        d["reference_uncertainty"] = rigid["stderr_norm"] / rigid["velocity_norm"]
        e_ok = _walk(ok, max(ok), upward=False)

        ts = [r for r in table(timestep.POINTS, rows) if r["case"] == case]
        auto = float(np.mean([r["timestep"] / r["timestep_limit"] for r in ship]))
        d["timestep"], ok = _effects(ts, lambda r: r["x"], auto)
        # the stiffness sweep ran at this step: plan adds the step's effect against it
        d["stiffness_timestep_fraction"] = stiffness.SWEEP_TIMESTEP_FRACTION
        f_ok = _walk(ok, auto, upward=True)

        cm = [r for r in table(contact_model.POINTS, rows) if r["case"] == case]
        d["contact_model"] = {"hertz_mindlin impact": 0.0} | {
            r["x"].replace("hertz", "hertz_mindlin"): r["relative_effect"]
            for r in cm if r["label"] != "base" and not r["failed"]
        }  # fmt: skip

        sec = [r for r in table(section.POINTS, rows) if r["case"] == case]
        cheapest_section = {}
        for axis, size in (("length", c.trough.length), ("width", c.trough.width)):
            sel = [r for r in sec if str(r["x"]).startswith(axis) or r["label"] == "base"]
            grains = {r["x"]: size * float(r["x"].split("x")[-1]) / g_len
                      for r in sel if r["label"] != "base"}  # fmt: skip
            d[f"section_{axis}"], ok = _effects(sel, lambda r, g=grains: g[r["x"]], size / g_len)
            cheapest_section[axis] = _walk(ok, size / g_len, upward=False)
        if case == "screw-trough":
            res = table(resolution.POINTS, rows)
            per = c.particles.grain.count
            d["resolution"], ok = _effects(res, lambda r: r["x"], per)
            res_ok = _walk(ok, per, upward=False)
        lad = {r["label"]: r for r in ladder.pointmass_rows(rows) + table(ladder.POINTS, rows)
               if r["case"] == case}  # fmt: skip
        pm, one = lad["point mass"]["velocity_norm"], lad["one grain"]["velocity_norm"]
        d["ladder"] = {
            "point mass": (pm - v_ref) / v_ref,
            "one grain": (one - v_ref) / v_ref,
            "one grain vs point mass": (one - pm) / pm,
            "point mass wall_time_s": lad["point mass"]["wall_time_s"],
            "one grain wall_time_s": lad["one grain"]["wall_time_s"],
        }
        d["cheapest"] = {
            "youngs_modulus": e_ok, "timestep_fraction": f_ok,
            "section_length_grains": cheapest_section["length"],
            "section_width_grains": cheapest_section["width"],
        }  # fmt: skip
        if case == "screw-trough":
            d["cheapest"]["spheres_per_grain"] = res_ok
        out["cases"][case] = d
    return out


if __name__ == "__main__":
    raise SystemExit(main())
