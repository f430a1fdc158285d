"""LIGGGHTS deck export: the deck carries the case's numbers (parsing only; no liggghts needed)."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import dem
from dem.config import GRAVITY
from dem.engine.simulation import ContactLaw
from dem.errors import InputError
from dem.io.liggghts import (
    LIGGGHTS_INSTALL,
    MESH_FILE,
    damping_ratio,
    find_liggghts,
    mesh_fill_block,
    run_liggghts,
    strip_top,
    write_deck,
)
from dem.kernels import contact
from dem.scene import shapes
from dem.scene.case import load_case
from dem.scene.mesh import extrude, load_mesh

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"


def parse(deck: Path) -> dict[str, list[list[str]]]:
    """Map the first word of every command line to the list of its argument lists."""
    commands: dict[str, list[list[str]]] = {}
    for line in deck.read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words:
            commands.setdefault(words[0], []).append(words[1:])
    return commands


def fix(commands, fix_id):
    [args] = [a for a in commands["fix"] if a[0] == fix_id]
    return args


def variable(commands, name):
    [args] = [a for a in commands["variable"] if a[0] == name and a[1] == "equal"]
    return args[2]


def evaluate(expression: str, **values: float) -> float:
    """Evaluate a LIGGGHTS equal-style expression with v_NAME substituted."""
    for name, value in values.items():
        expression = expression.replace(f"v_{name}", repr(value))
    assert "v_" not in expression
    return float(eval(expression, {"sin": math.sin, "sqrt": math.sqrt}))


@pytest.fixture
def bed_deck(tmp_path):
    case = load_case(CASES_DIR / "sphere-bed")
    deck = write_deck(case, tmp_path / "deck", timestep=5e-6, steps=1234, settle_steps=567)
    return case, deck, parse(deck)


@pytest.mark.integration
def test_sphere_bed_material_numbers(bed_deck):
    case, deck, c = bed_deck
    assert fix(c, "m_Y")[3:5] == ["youngsModulus", "peratomtype"]
    assert [float(x) for x in fix(c, "m_Y")[5:]] == [case.contact.youngs_modulus] * 2
    assert [float(x) for x in fix(c, "m_nu")[5:]] == [case.contact.poisson_ratio] * 2
    assert [float(x) for x in fix(c, "m_mu")[6:]] == [case.material.friction] * 4
    # e = 0 in the case; LIGGGHTS refuses e <= 0.05, so the deck clamps to 0.06 and says so
    assert case.material.restitution_normal == 0.0
    assert fix(c, "m_e")[3] == "coefficientRestitution"
    assert [float(x) for x in fix(c, "m_e")[6:]] == [0.06] * 4
    assert "NOTE: restitution_normal = 0.0" in deck.read_text()
    pair = c["pair_style"][0]
    assert pair[:4] == ["gran", "model", "hertz", "tangential"]
    assert pair[pair.index("limitForce") + 1] == "off"


@pytest.mark.integration
def test_sphere_bed_geometry_and_grains(bed_deck):
    case, _, c = bed_deck
    assert c["boundary"] == [["p", "f", "f"]]
    domain = [a for a in c["region"] if a[0] == "domain"][0]
    x0, x1, y0, y1 = (float(v) for v in domain[2:6])
    assert x1 - x0 == pytest.approx(case.trough.length)
    assert (y0, y1) == (-case.trough.width / 2, case.trough.width / 2)
    walls = {a[0]: a for a in c["fix"] if "wall/gran" in a}
    assert walls["floor"][walls["floor"].index("zplane") + 1] == "0.0"
    assert float(walls["side_lo"][walls["side_lo"].index("yplane") + 1]) == y0
    assert float(walls["side_hi"][walls["side_hi"].index("yplane") + 1]) == y1
    template = fix(c, "pts")
    assert float(template[template.index("density") + 2]) == case.material.density
    assert float(template[template.index("radius") + 2]) == case.particles.radius
    insert = fix(c, "ins")
    assert int(insert[insert.index("particles_in_region") + 1]) == case.particles.count
    assert fix(c, "integr")[2] == "nve/sphere"


@pytest.mark.integration
def test_sphere_bed_timestep_and_stages(bed_deck):
    _, _, c = bed_deck
    assert c["timestep"] == [["5e-06"]]
    runs = [int(a[0]) for a in c["run"]]
    assert runs[-2:] == [567, 1234]


@pytest.mark.integration
def test_sphere_bed_drive_is_the_accelerating_frame(bed_deck):
    case, _, c = bed_deck
    d = case.drive
    omega = 2 * math.pi * d.frequency
    phi = math.radians(d.angle)
    fill_steps = int(c["run"][0][0])
    for step in (fill_steps, fill_steps + 100, fill_steps + 2345):
        tau = evaluate(variable(c, "tau").replace("step", str(step)))
        assert tau == pytest.approx((step - fill_steps) * 5e-6, abs=1e-15)
        drive = evaluate(variable(c, "drive"), tau=tau)
        expected = d.amplitude * omega**2 * math.sin(omega * tau)
        assert drive == pytest.approx(expected, rel=1e-12, abs=1e-12)
        gx = evaluate(variable(c, "gx"), drive=drive)
        gz = evaluate(variable(c, "gz"), drive=drive)
        assert gx == pytest.approx(expected * math.cos(phi), abs=1e-12)
        assert gz == pytest.approx(-GRAVITY + expected * math.sin(phi), abs=1e-12)
        assert evaluate(variable(c, "gmag"), gx=gx, gz=gz) == pytest.approx(math.hypot(gx, gz))
    gravity = [a for a in c["fix"] if a[0] == "grav"]
    assert gravity[-1][2:] == ["gravity", "v_gmag", "vector", "v_gx", "0.0", "v_gz"]
    # the peak acceleration is Gamma g (alpha = 0)
    peak = float(variable(c, "drive").split("*")[0])
    assert peak * math.sin(phi) / GRAVITY == pytest.approx(d.throw_number, rel=1e-12)


@pytest.mark.integration
def test_inclination_tilts_static_gravity(tmp_path):
    case = load_case(CASES_DIR / "sphere-bed")
    tilted = dataclasses.replace(case, trough=dataclasses.replace(case.trough, inclination=4.0))
    c = parse(write_deck(tilted, tmp_path, timestep=5e-6, steps=10, settle_steps=0))
    alpha = math.radians(4.0)
    assert evaluate(variable(c, "gx"), drive=0.0) == pytest.approx(-GRAVITY * math.sin(alpha))
    assert evaluate(variable(c, "gz"), drive=0.0) == pytest.approx(-GRAVITY * math.cos(alpha))
    static = [a for a in c["fix"] if a[0] == "grav"][0]
    assert float(static[3]) == pytest.approx(GRAVITY)
    assert float(static[5]) == pytest.approx(-math.sin(alpha))


def _restitution_of_linear_dashpot(k: float, m: float, gamma: float) -> float:
    """Rebound speed of a unit-speed normal impact, m x'' = -k x - gamma x', overlap x > 0.

    Integrated with small symplectic Euler steps until the overlap returns to zero; no return
    within ten natural periods (over-critical damping) means no rebound.
    """
    period = 2 * math.pi * math.sqrt(m / k)
    dt = 1e-4 * period
    x, v = 0.0, 1.0
    for _ in range(100_000):
        v += (-k * x - gamma * v) / m * dt
        x += v * dt
        if x <= 0.0:
            return -v
    return 0.0


@pytest.mark.parametrize("e", [0.0, 0.3, 0.8])
def test_linear_deck_damping_gives_the_restitution(tmp_path, e):
    case = load_case(CASES_DIR / "single-sphere").with_tangential("coulomb")
    case = dataclasses.replace(
        case, material=dataclasses.replace(case.material, restitution_normal=e)
    )
    c = parse(write_deck(case, tmp_path, timestep=2e-6, steps=10))
    assert c["pair_style"][0][2] == "hooke/stiffness"
    assert fix(c, "integr")[2] == "nve"  # rotation = false
    kn = float(fix(c, "m_kn")[6])
    assert kn == case.contact.stiffness
    kappa = ContactLaw.from_case(case).params[contact.P_KT_RATIO]
    assert float(fix(c, "m_kt")[6]) == pytest.approx(kn * kappa)
    gn = [float(x) for x in fix(c, "m_gn")[6:]]
    mass = case.material.density * 4 / 3 * math.pi * case.particles.radius**3
    # grain-wall (types 1-2): m* = m; integrate the impact and compare the rebound speed
    e_measured = _restitution_of_linear_dashpot(kn, mass, gn[1])
    assert e_measured == pytest.approx(e, abs=2e-3)
    # grain-grain (1-1): m* = m/2
    assert _restitution_of_linear_dashpot(kn, mass / 2, gn[0]) == pytest.approx(e, abs=2e-3)


def test_damping_ratio_inverts_restitution():
    e = np.linspace(0.01, 0.99, 50)
    zeta = np.array([damping_ratio(x) for x in e])
    assert np.allclose(np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2)), e, rtol=1e-12)
    assert damping_ratio(0.0) == 1.0


def test_refuses_what_liggghts_primitives_cannot_do(tmp_path):
    case = load_case(CASES_DIR / "sphere-bed")
    # a screw case not built by load_case has no template to write
    screw = dataclasses.replace(case, particles=dataclasses.replace(case.particles, shape="screw"))
    with pytest.raises(InputError, match="particles.shape"):
        write_deck(screw, tmp_path, timestep=5e-6, steps=10, settle_steps=0)
    with pytest.raises(InputError, match="timestep"):
        write_deck(case, tmp_path, timestep=0.0, steps=10, settle_steps=0)


@pytest.mark.integration
def test_header_names_version_and_command(bed_deck):
    _, deck, _ = bed_deck
    header = deck.read_text().split("\n\n", 1)[0]
    assert f"dem {dem.__version__}" in header
    assert "liggghts -in in.dem" in header and "mpirun -np 2" in header
    assert "LIGGGHTS-PUBLIC 3.8.0" in header
    assert header.isascii()


@pytest.fixture
def screw_deck(tmp_path):
    case = load_case(CASES_DIR / "screw-trough")
    deck = write_deck(case, tmp_path / "deck", timestep=3e-6, steps=1000, settle_steps=100)
    return case, deck, parse(deck)


@pytest.mark.integration
def test_screw_deck_is_a_multisphere_deck(screw_deck):
    case, deck, c = screw_deck
    grain = case.particles.grain
    template = fix(c, "pts")
    assert template[2] == "particletemplate/multisphere"
    assert int(template[template.index("nspheres") + 1]) == grain.count == 8
    assert template[template.index("spheres") + 1 : template.index("spheres") + 5] == [
        "file", "grain.multisphere", "scale", "1.0",
    ]  # fmt: skip
    # the exact mass and principal inertia of dem.scene.shapes, not LIGGGHTS's Monte Carlo estimate
    assert float(template[template.index("mass") + 1]) == grain.mass == 0.0025
    i = template.index("inertia_tensor")
    tensor = [float(v) for v in template[i + 1 : i + 7]]
    m1, m2, m3 = grain.moments
    assert tensor == [m1, 0.0, 0.0, m2, 0.0, m3]
    assert "use_volume" in template and "tflag" not in template
    # members in the body frame read back as the same grain
    back = shapes.clump_from_file(deck.parent / "grain.multisphere", density=grain.density)
    np.testing.assert_allclose(back.input_centres(), grain.centres, atol=1e-15)
    np.testing.assert_array_equal(back.radii, grain.radii)
    assert back.mass == pytest.approx(grain.mass, rel=1e-12)
    # fix multisphere integrates the bodies and wants these settings
    assert fix(c, "integr")[2] == "multisphere"
    assert c["atom_modify"] == [["map", "array", "sort", "0", "0"]]
    assert c["newton"] == [["off"]]
    # the mean x-velocity is that of the bodies' centres of mass
    computes = {a[0]: a[1:] for a in c["compute"]}
    assert computes["vcm"] == ["all", "multisphere", "property", "vcm"]
    assert computes["vxm"] == ["all", "reduce", "ave", "c_vcm[1]"]
    # the fill check counts the grains insert/pack placed (its f_ins[1]), not member spheres
    assert f'"${{ninserted}} < {case.particles.count}"' in deck.read_text()
    assert ["ninserted", "equal", "f_ins[1]"] in c["variable"]
    insert = fix(c, "ins")
    assert int(insert[insert.index("particles_in_region") + 1]) == case.particles.count


@pytest.mark.integration
def test_screw_deck_neighbour_skin_and_linear_damping_use_clump_values(tmp_path):
    case = load_case(CASES_DIR / "screw-trough")
    locked = dataclasses.replace(
        case,
        particles=dataclasses.replace(case.particles, rotation=False),
        contact=dataclasses.replace(case.contact, model="linear", stiffness=2.0e4),
        material=dataclasses.replace(case.material, restitution_normal=0.3),
    )
    c = parse(write_deck(locked, tmp_path, timestep=3e-6, steps=10, settle_steps=0))
    template = fix(c, "pts")
    assert template[-4:] == ["tflag", "off", "off", "off"]
    assert float(c["neighbor"][0][0]) == pytest.approx(0.5 * min(case.particles.grain.radii))
    # gamma_n = 2 zeta sqrt(k_n m*) with the clump's mass: m* = M/2 grain-grain, M grain-wall
    zeta, m = damping_ratio(0.3), case.particles.grain.mass
    gn = [float(v) for v in fix(c, "m_gn")[6:]]
    assert gn == pytest.approx([2 * zeta * math.sqrt(2.0e4 * mm) for mm in (m / 2, m, m, m)])


def test_coulomb_case_deck_says_liggghts_caps_the_spring_alone(tmp_path):
    case = load_case(CASES_DIR / "single-sphere").with_tangential("coulomb")
    text = write_deck(case, tmp_path / "c", timestep=2e-6, steps=10).read_text()
    assert "NOTE: the case caps the total tangential force" in text
    text = write_deck(case.with_tangential("liggghts"), tmp_path / "l", timestep=2e-6, steps=10)
    assert "NOTE: the case caps" not in text.read_text()


def test_impact_case_deck_is_the_liggghts_law_and_says_so(tmp_path):
    """LIGGGHTS cannot express the impact-aware law: the deck is that of tangential =
    "liggghts" (k_t = 2/7 k_n, gamma_t = gamma_n for the linear law), with a note."""
    case = load_case(CASES_DIR / "single-sphere")
    assert case.contact.tangential == "impact"
    deck = write_deck(case, tmp_path / "i", timestep=2e-6, steps=10)
    same = write_deck(case.with_tangential("liggghts"), tmp_path / "l", timestep=2e-6, steps=10)
    text = deck.read_text()
    assert "NOTE: the case's impact-aware tangential law" in text
    c = parse(deck)
    assert float(fix(c, "m_kt")[6]) == pytest.approx(2 / 7 * case.contact.stiffness)
    assert fix(c, "m_gt") == fix(parse(same), "m_gt")


# --- mesh troughs ---------------------------------------------------------------------------


@pytest.fixture(params=["u-trough", "v-trough"])
def mesh_deck(request, tmp_path):
    case = load_case(CASES_DIR / request.param)
    deck = write_deck(case, tmp_path / "deck", timestep=8e-6, steps=100, settle_steps=10)
    return case, deck, parse(deck)


@pytest.mark.integration
def test_mesh_deck_reads_the_stl_as_a_granular_wall(mesh_deck):
    _, deck, c = mesh_deck
    surface = fix(c, "trough")
    assert surface[1:5] == ["all", "mesh/surface", "file", MESH_FILE]
    assert surface[surface.index("type") + 1] == "2"  # the walls' material type
    walls = fix(c, "walls")
    assert walls[1:3] == ["all", "wall/gran"]
    i = walls.index("mesh")
    assert walls[i : i + 5] == ["mesh", "n_meshes", "1", "meshes", "trough"]
    # the same contact model and settings as the grain pairs
    pair = c["pair_style"][0]
    model = walls[walls.index("model") : i]
    assert pair[1 : 1 + len(model)] == model
    assert walls[i + 5 :] == pair[pair.index("limitForce") :]
    # no primitive walls, and no move/mesh: the deck runs in the trough's frame
    assert not any("primitive" in a for a in c["fix"])
    assert not any("move/mesh" in a for a in c["fix"])
    assert "no move/mesh" in deck.read_text()


@pytest.mark.integration
def test_mesh_stl_round_trips_to_the_case_triangles(mesh_deck):
    case, deck, _ = mesh_deck
    length = case.trough.length
    written = load_mesh(deck.parent / MESH_FILE, length=length).tri
    original = load_mesh(case.trough.mesh, length=length).tri
    np.testing.assert_array_equal(written, original)
    assert (deck.parent / MESH_FILE).read_text().isascii()


@pytest.mark.integration
def test_mesh_box_holds_the_mesh_and_the_fill_region_lies_inside_the_pan(mesh_deck):
    case, _, c = mesh_deck
    mesh = load_mesh(case.trough.mesh, length=case.trough.length)
    lo, hi = mesh.tri.min(axis=(0, 1)), mesh.tri.max(axis=(0, 1))
    domain = [float(v) for v in [a for a in c["region"] if a[0] == "domain"][0][2:8]]
    assert domain[:2] == [0.0, case.trough.length]  # periodic over the section
    assert domain[2] < lo[1] and hi[1] < domain[3] and domain[4] < lo[2] and hi[2] < domain[5]
    x0, x1, y0, y1, z0, z1 = (float(v) for v in [a for a in c["region"] if a[0] == "fill"][0][2:8])
    assert (x0, x1) == (0.0, case.trough.length)
    assert lo[1] < y0 < y1 < hi[1] and lo[2] < z0 < hi[2] < z1 < domain[5]
    # the block is tall enough for the grains at the loose fill fraction
    grain = case.particles.grain
    volume = case.particles.count * grain.volume
    assert volume / ((x1 - x0) * (y1 - y0) * (z1 - z0)) <= 0.08 + 1e-12
    # the region holds the clumps' centres of mass (any orientation): their members reach the
    # block grown by the grain's reach across y and downwards, which must clear the mesh
    reach = grain.bounding_radius
    y0, y1, z0 = y0 - reach, y1 + reach, z0 - reach
    assert "all_in no orientation random" in " ".join(fix(c, "ins"))
    # every point of the block's surface lies on the grains' side of the mesh, clear of it
    # (an independent check: dem.scene.mesh's closest-point kernels, not strip_top)
    mesh.index(float(np.max(hi - lo)))
    u = np.linspace(0.0, 1.0, 41)
    xs = np.linspace(x0, x1, 7)
    faces = np.concatenate(
        [
            np.stack(np.broadcast_arrays(xs[:, None], y0 + (y1 - y0) * u, z0), -1),
            np.stack(np.broadcast_arrays(xs[:, None], y0, z0 + (z1 - z0) * u), -1),
            np.stack(np.broadcast_arrays(xs[:, None], y1, z0 + (z1 - z0) * u), -1),
        ]
    ).reshape(-1, 3)
    assert np.all(mesh.sides(faces) > 0.0)
    assert mesh.gaps(faces).min() >= float(c["neighbor"][0][0]) * (1 - 1e-9)
    # and the block reaches down into the pan: its floor is below the rim (both pans are 30 mm
    # deep, with 20 mm walls above: cases/geometry/make_troughs.py)
    assert z0 < 0.03 and hi[2] == pytest.approx(0.05)


def test_strip_top_clips_triangles_to_the_slab():
    # one triangle rising from z = 0 at y = 0 to z = 1 at y = 1 (and a corner at x = 1)
    tri = np.array([[[0.0, 0.0, 0.0], [0.0, 1.0, 1.0], [1.0, 0.0, 0.0]]])
    assert strip_top(tri, -1.0, 0.25) == pytest.approx(0.25)  # where an edge crosses y = 0.25
    assert strip_top(tri, 0.5, 2.0) == 1.0  # a corner inside the slab
    assert strip_top(tri, 1.5, 2.0) == -np.inf
    # a flat floor spanning the slab with no corner inside it
    floor = np.array([[[0.0, -1.0, 0.2], [0.0, 1.0, 0.2], [1.0, 1.0, 0.2]]])
    assert strip_top(floor, -0.1, 0.1) == pytest.approx(0.2)


def test_mesh_fill_block_in_a_box_pan_and_a_closed_one():
    # a box pan 0.1 wide, floor z = 0, walls to z = 0.05: the widest block short of the walls
    mesh = extrude(np.array([[-0.05, 0.05], [-0.05, 0.0], [0.05, 0.0], [0.05, 0.05]]), 0.1)
    tri = mesh.points[mesh.cells[0].data]
    y0, y1, z0 = mesh_fill_block(tri, 0.001)
    assert z0 == pytest.approx(0.001)
    assert -0.049 <= y0 < -0.048 and 0.048 < y1 <= 0.049
    lid = extrude(np.array([[-0.05, 0.05], [0.05, 0.05]]), 0.1)
    closed = np.concatenate([tri, lid.points[lid.cells[0].data]])  # no room below the lid
    with pytest.raises(ValueError, match="no block"):
        mesh_fill_block(closed, 0.001)


@pytest.mark.integration
@pytest.mark.skipif(find_liggghts() is None, reason=f"liggghts not on PATH ({LIGGGHTS_INSTALL})")
def test_liggghts_runs_the_u_trough_deck(tmp_path):
    case = load_case(CASES_DIR / "u-trough")
    dt = case.run.timestep
    # a short fill (grains inserted, falling) and 100 + 100 driven steps: LIGGGHTS reads the
    # mesh, inserts every screw and keeps every member sphere in the box
    deck = write_deck(case, tmp_path, timestep=dt, steps=100, settle_steps=100, fill_time=50 * dt)
    run = run_liggghts(tmp_path, deck.name, min_loops=3)
    assert "ERROR" not in run.stdout
    assert "containing 100 triangle(s) successful" in run.stdout
    members = case.particles.grain.count
    assert [loop.atoms for loop in run.loop_times] == [case.particles.count * members] * 3
    assert [loop.steps for loop in run.loop_times] == [50, 100, 100]


@pytest.mark.integration
def test_feeder_deck_has_the_back_wall_open_edge_and_one_grain_per_feed(tmp_path):
    """cases/feeder: x is open at the discharge edge L (lost spheres deleted and ignored), the
    back wall is the plane x = 0, the fill stands clear of both, and the feed inserts one grain
    every m / feed_rate into the zone at the back (LIGGGHTS rounds fractions of a grain down)."""
    from dem.engine.feeder import grain_mass

    case = load_case(CASES_DIR / "feeder")
    dt = case.run.timestep
    deck = write_deck(case, tmp_path / "deck", timestep=dt, steps=100, settle_steps=100)
    c = parse(deck)
    assert c["boundary"] == [["f", "f", "f"]]
    [domain] = [a for a in c["region"] if a[0] == "domain"]
    length = case.trough.length
    assert float(domain[3]) == length and float(domain[2]) < 0.0
    assert "lost" in c["thermo_modify"][0] and "ignore" in c["thermo_modify"][0]
    back = fix(c, "back")
    assert back[back.index("primitive") :][:4] == ["primitive", "type", "2", "xplane"]
    assert float(back[back.index("xplane") + 1]) == 0.0
    [fill] = [a for a in c["region"] if a[0] == "fill"]
    reach = case.particles.grain.bounding_radius
    assert float(fill[2]) == pytest.approx(reach) and float(fill[3]) == pytest.approx(
        length - reach
    )
    feed = fix(c, "feed")
    assert feed[2] == "insert/rate/region"
    rate = float(feed[feed.index("massrate") + 1])
    every = int(feed[feed.index("insert_every") + 1])
    assert rate == case.feeder.feed_rate
    assert rate * every * dt == pytest.approx(grain_mass(case), rel=1e-3)
    [zone] = [a for a in c["region"] if a[0] == "feedzone"]
    # the zone holds centres of mass, a reach clear of the back wall, as dem.engine.feeder places
    # them
    assert float(zone[2]) == pytest.approx(reach)
    assert float(zone[3]) == pytest.approx(case.feeder.feed_length - reach)
    assert "all_in no orientation random" in " ".join(feed)
    assert feed[feed.index("region") + 1] == "feedzone"
    assert fix(c, "balance")[2] == "print"


@pytest.mark.integration
@pytest.mark.skipif(find_liggghts() is None, reason=f"liggghts not on PATH ({LIGGGHTS_INSTALL})")
def test_liggghts_runs_a_feeder_deck_and_its_balance_closes(tmp_path):
    """A sphere feeder tilted 15 deg down to its edge: LIGGGHTS feeds grains, deletes those
    past x = L, and read_balance's discharged = charge + fed - in the box counts them."""
    from dem.io.liggghts import BALANCE_FILE, discharge_per_cycle, read_balance

    ov = {"feeder.feed_rate": 0.02, "feeder.feed_length": 0.02, "particles.count": 60,
          "trough.length": 0.05, "trough.inclination": -15.0, "run.settle_cycles": 0}  # fmt: skip
    case = load_case(CASES_DIR / "sphere-bed", overrides=ov)
    dt = 1e-5
    deck = write_deck(case, tmp_path / "deck", timestep=dt, steps=30000, settle_steps=0,
                      fill_time=0.05, sample_steps=500)  # fmt: skip
    run = run_liggghts(deck.parent, min_loops=2)
    assert "ERROR" not in run.stdout
    bal = read_balance(deck.parent / BALANCE_FILE, members=1)
    assert bal.charge == 60.0
    assert np.all(bal.in_trough == np.round(bal.in_trough))  # spheres: whole grains
    mass = case.material.density * 4.0 / 3.0 * math.pi * case.particles.radius**3
    want_fed = 0.02 * bal.tau[-1] / mass  # one grain every m / rate, from the drive start
    assert abs(bal.fed[-1] - want_fed) <= 1.0
    assert np.all(np.diff(bal.discharged) >= 0.0) and bal.discharged[-1] > 10
    assert bal.discharged[-1] == bal.charge + bal.fed[-1] - run.loop_times[-1].atoms
    rates, held = discharge_per_cycle(bal, 1.0 / case.drive.frequency, 0.0, mass)
    assert rates.size == int(bal.tau[-1] * case.drive.frequency + 1e-9)
    assert np.sum(rates) / case.drive.frequency == pytest.approx(
        np.interp(rates.size / case.drive.frequency, bal.tau, bal.discharged) * mass
    )
    assert 0.0 < held <= bal.charge + bal.fed[-1]


@pytest.mark.integration
def test_elliptical_drive_and_ramp_variables_are_the_kernels_acceleration(tmp_path):
    """The deck's gx, gz, evaluated as LIGGGHTS would (the equal-style expressions in Python),
    equal gravity minus s''(tau) of dem.physics.drive.Motion within and after the ramp."""
    import math
    import re

    from dem.io.liggghts import write_deck
    from dem.scene.case import load_case
    from dem.scene.trough import Trough

    ov = {"drive.second_amplitude": 2e-4, "drive.second_angle": 90.0,
          "drive.second_phase": 90.0, "drive.ramp_cycles": 3.0, "run.settle_cycles": 5}  # fmt: skip
    case = load_case("cases/sphere-bed", overrides=ov)
    deck = write_deck(case, tmp_path / "deck", timestep=1e-5, steps=10).read_text()
    exprs = dict(re.findall(r"^variable (\w+) equal (.+)$", deck, flags=re.M))
    trough = Trough.from_case(case)
    for tau in (0.0, 0.013, 0.031, 0.049, 0.07, 0.2):
        env = {"v_tau": tau, "min": min, "sin": math.sin, "cos": math.cos}
        for name in ("u", "r0", "r1", "r2", "cs", "cc", "drive1", "drive2", "gx", "gz"):
            env[f"v_{name}"] = eval(exprs[name], env)  # noqa: S307 - our own deck
        want = trough.gravity + trough.frame_acceleration(tau)
        assert env["v_gx"] == pytest.approx(want[0], abs=1e-9)
        assert env["v_gz"] == pytest.approx(want[2], abs=1e-9)


@pytest.mark.integration
@pytest.mark.skipif(find_liggghts() is None, reason="liggghts not on PATH")
def test_an_elliptical_ramped_deck_runs_in_liggghts(tmp_path):
    from dem.io.liggghts import run_liggghts, write_deck
    from dem.scene.case import load_case

    ov = {"drive.second_amplitude": 2e-4, "drive.second_angle": 90.0,
          "drive.second_phase": 90.0, "drive.ramp_cycles": 3.0, "run.settle_cycles": 5,
          "particles.count": 100}  # fmt: skip
    case = load_case("cases/sphere-bed", overrides=ov)
    deck = write_deck(case, tmp_path / "deck", timestep=1e-5, steps=100, settle_steps=100,
                      fill_time=0.002)  # fmt: skip
    run = run_liggghts(deck.parent)
    assert "ERROR" not in run.stdout
    assert [lt.steps for lt in run.loop_times][-2:] == [100, 100]
    assert run.loop_times[-1].atoms == 100


@pytest.mark.integration
def test_deck_notes_the_wall_lever_arm_only_where_it_differs_from_liggghts(tmp_path):
    """LIGGGHTS's walls act at r - delta/2: a case with dem's default r - delta says so in its
    deck, one with wall_lever_arm = "midpoint" (the same as LIGGGHTS) does not."""
    note = "LIGGGHTS's walls at r - delta/2"
    case = load_case(CASES_DIR / "sphere-bed")
    deck = write_deck(case, tmp_path / "a", timestep=5e-6, steps=10, settle_steps=0)
    assert note in deck.read_text()
    mid = load_case(CASES_DIR / "sphere-bed", overrides={"contact.wall_lever_arm": "midpoint"})
    deck = write_deck(mid, tmp_path / "b", timestep=5e-6, steps=10, settle_steps=0)
    assert note not in deck.read_text()


@pytest.mark.integration
def test_a_deck_of_grains_stiffer_than_1e9_pa_tells_liggghts_they_are_hard(tmp_path):
    """LIGGGHTS 3.8 stops on youngsModulus > 1e9 in SI units unless ``hard_particles yes``
    comes first; the shipped beds (2e9 Pa) need it, the 5e7 Pa LIGGGHTS-parity bed does not."""
    stiff = write_deck(load_case(CASES_DIR / "sphere-bed"), tmp_path / "stiff", timestep=1e-6,
                       steps=10, settle_steps=0)  # fmt: skip
    text = stiff.read_text()
    assert "hard_particles yes" in text
    assert text.index("hard_particles yes") < text.index("youngsModulus")
    parity = CASES_DIR.parent / "validation" / "liggghts-bulk" / "sphere-bed-5e7"
    soft = write_deck(load_case(parity), tmp_path / "soft", timestep=1e-6, steps=10, settle_steps=0)
    assert "hard_particles" not in soft.read_text()
