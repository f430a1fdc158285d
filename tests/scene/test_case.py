"""Case files: every shipped case loads; every bad input is refused naming key, value and file."""

import copy
import dataclasses
import math
from pathlib import Path

import pytest

from dem.config import GRAVITY
from dem.errors import InputError
from dem.scene.case import Case, load_case

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
SHIPPED = sorted(p.parent for p in CASES_DIR.glob("*/case.toml"))

BASE = {
    "trough": {"length": 0.1, "width": 0.04},
    "drive": {"frequency": 60.0, "angle": 25.0, "amplitude": 0.0005},
    "material": {"density": 7800.0, "friction": 0.35},
    "contact": {"youngs_modulus": 5.0e7},
    "particles": {"count": 10, "radius": 0.002},
}


def _toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float) and math.isnan(value):
        return "nan"
    return repr(value)


def write_case(tmp_path: Path, tables: dict) -> Path:
    """Write a case.toml from {table: {key: value}} (a value of None drops the key)."""
    lines = []
    for table, keys in tables.items():
        lines.append(f"[{table}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in keys.items() if v is not None]
        lines.append("")
    path = tmp_path / "case.toml"
    path.write_text("\n".join(lines))
    return path


def with_changes(changes: dict) -> dict:
    """BASE with {"table.key": value} applied (None removes the key)."""
    tables = copy.deepcopy(BASE)
    for dotted, value in changes.items():
        table, key = dotted.split(".")
        tables.setdefault(table, {})
        if value is None:
            tables[table].pop(key, None)
        else:
            tables[table][key] = value
    return tables


# --- good input ----------------------------------------------------------------------------------


def test_there_are_shipped_cases():
    names = {p.name for p in SHIPPED}
    assert {"single-sphere", "sphere-bed"} <= names


@pytest.mark.parametrize("directory", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_case_loads(directory):
    case = load_case(directory)
    assert isinstance(case, Case)
    assert case.name == directory.name
    assert case.source == directory / "case.toml"
    d, t = case.drive, case.trough
    # independent check of the resolved drive: Gamma = A w^2 sin(phi) / (g cos(alpha))
    gamma = (
        d.amplitude
        * (2 * math.pi * d.frequency) ** 2
        * math.sin(math.radians(d.angle))
        / (GRAVITY * math.cos(math.radians(t.inclination)))
    )
    assert d.throw_number == pytest.approx(gamma, rel=1e-12)
    assert case.particles.count >= 1
    p = case.particles
    r_max = p.radius if p.shape == "sphere" else float(max(p.grain.radii))
    assert t.width >= 2 * r_max


def test_screw_trough_is_the_issue_spec():
    case = load_case(CASES_DIR / "screw-trough")
    p, d = case.particles, case.drive
    assert (p.shape, p.count, p.rotation) == ("screw", 200, True)
    assert p.grain.mass == pytest.approx(0.0025, rel=1e-12)
    assert p.grain.density == pytest.approx(7765, rel=1e-3)  # steel, from mass / union volume
    assert (d.frequency, d.angle, d.throw_number) == (60.0, 25.0, 1.8)
    assert case.material.friction == 0.35


def test_sphere_bed_is_the_issue_spec():
    case = load_case(CASES_DIR / "sphere-bed" / "case.toml")
    assert case.particles.count == 1500
    assert case.particles.radius == 0.002
    assert case.material.density == 7800.0
    assert case.contact.model == "hertz_mindlin"
    assert case.contact.youngs_modulus == 2.0e9  # the rigid answer within 2 %
    assert case.contact.poisson_ratio == 0.3
    assert case.material.friction == 0.35
    assert (case.trough.length, case.trough.width) == (0.10, 0.04)
    assert (case.drive.frequency, case.drive.angle, case.drive.amplitude) == (60.0, 25.0, 0.0005)
    assert case.drive.given == "amplitude"
    assert (case.material.restitution_normal, case.material.restitution_tangential) == (0.0, 0.8)


def test_single_sphere_slides_without_flight():
    case = load_case(CASES_DIR / "single-sphere")
    assert case.particles.count == 1 and not case.particles.rotation
    assert case.contact.model == "linear"
    mass = case.material.density * 4 / 3 * math.pi * case.particles.radius**3
    contact_frequency = math.sqrt(case.contact.stiffness / mass) / (2 * math.pi)
    assert contact_frequency > 20 * case.drive.frequency
    mu, phi = case.material.friction, math.radians(case.drive.angle)
    forward = mu / (1 / math.tan(phi) + mu)  # the paper's Eq. 1 at alpha = 0
    assert forward < case.drive.throw_number < 1.0


def test_defaults(tmp_path):
    case = load_case(write_case(tmp_path, BASE))
    assert case.trough.inclination == 0.0 and case.trough.mesh is None
    assert case.material.restitution_normal == 0.0
    assert case.material.restitution_tangential == 0.8
    assert case.material.rolling_friction == 0.0
    assert case.contact.model == "hertz_mindlin"
    assert case.contact.poisson_ratio == 0.3
    assert case.contact.stiffness is None
    assert case.contact.limit_force is False
    assert case.particles.shape == "sphere" and case.particles.rotation is True
    assert (case.run.settle_cycles, case.run.cycles, case.run.timestep, case.run.seed) == (
        10,
        30,
        None,
        1,
    )
    assert case.output.frames_per_cycle == 4
    assert case.directory == tmp_path.resolve()


def test_throw_number_gives_amplitude(tmp_path):
    tables = with_changes(
        {"drive.amplitude": None, "drive.throw_number": 2.0, "trough.inclination": 5.0}
    )
    drive = load_case(write_case(tmp_path, tables)).drive
    omega = 2 * math.pi * 60.0
    expected = 2.0 * GRAVITY * math.cos(math.radians(5.0)) / (omega**2 * math.sin(math.radians(25)))
    assert drive.given == "throw_number"
    assert drive.amplitude == pytest.approx(expected, rel=1e-12)
    assert drive.omega == pytest.approx(omega)


def test_ints_are_accepted_for_floats(tmp_path):
    case = load_case(write_case(tmp_path, with_changes({"material.density": 7800})))
    assert isinstance(case.material.density, float) and case.material.density == 7800.0


def test_linear_contact(tmp_path):
    tables = with_changes(
        {"contact.model": "linear", "contact.youngs_modulus": None, "contact.stiffness": 2000}
    )
    contact = load_case(write_case(tmp_path, tables)).contact
    assert contact.stiffness == 2000.0 and contact.youngs_modulus is None
    # "impact" is the default and takes no tangential spring
    assert contact.tangential == "impact" and contact.tangential_stiffness_ratio is None
    tables["contact"]["tangential"] = "coulomb"
    contact = load_case(write_case(tmp_path, tables)).contact
    # "coulomb" derives k_t from eps_t when the ratio is not given
    assert contact.tangential == "coulomb" and contact.tangential_stiffness_ratio is None
    tables["contact"]["tangential"] = "liggghts"
    contact = load_case(write_case(tmp_path, tables)).contact
    assert contact.tangential_stiffness_ratio == pytest.approx(2 / 7)


def test_tangential_keys(tmp_path):
    keys = {"contact.tangential_stiffness_ratio": 0.5, "contact.tangential_damping_ratio": 0.2}
    contact = load_case(
        write_case(tmp_path, with_changes({**keys, "contact.tangential": "coulomb"}))
    ).contact
    assert (contact.tangential, contact.tangential_stiffness_ratio) == ("coulomb", 0.5)
    assert contact.tangential_damping_ratio == 0.2
    # the default impact-aware law has no tangential spring: its keys are refused, not ignored
    for key in keys:
        with pytest.raises(InputError, match=f"{key}.*tangential = 'impact'; remove it"):
            load_case(write_case(tmp_path, with_changes({key: keys[key]})))


@pytest.mark.validation
def test_wall_lever_arm_reaches_the_kernels_and_a_bad_one_is_refused_by_key(tmp_path):
    from dem.kernels.contact import P_WALL_ARM
    from dem.scene.timestep import ContactLaw

    case = load_case(write_case(tmp_path, with_changes({})))
    assert case.contact.wall_lever_arm == "surface"
    assert ContactLaw.from_case(case).params[P_WALL_ARM] == 1.0
    case = load_case(write_case(tmp_path, with_changes({"contact.wall_lever_arm": "midpoint"})))
    law = ContactLaw.from_case(case)
    assert law.params[P_WALL_ARM] == 0.5
    assert law.tangential_coefficients()["wall_lever_arm"] == "midpoint"
    with pytest.raises(InputError, match="contact.wall_lever_arm") as info:
        load_case(write_case(tmp_path, with_changes({"contact.wall_lever_arm": "middle"})))
    assert "'surface', 'midpoint'" in str(info.value)


def test_explicit_timestep_and_mesh(tmp_path):
    import meshio

    from dem.scene.mesh import extrude

    (tmp_path / "geometry").mkdir()
    box = [[-0.02, 0.02], [-0.02, 0.0], [0.02, 0.0], [0.02, 0.02]]  # floor, walls: 0.04 wide
    meshio.write(tmp_path / "geometry" / "trough.stl", extrude(box, 0.1), binary=False)
    tables = with_changes({"run.timestep": 1e-6, "trough.mesh": "geometry/trough.stl"})
    case = load_case(write_case(tmp_path, tables))
    assert case.run.timestep == 1e-6
    assert case.trough.mesh == (tmp_path / "geometry" / "trough.stl").resolve()


def test_a_mesh_without_triangles_is_refused_at_load(tmp_path):
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "trough.stl").write_text("solid t\nendsolid t\n")
    tables = with_changes({"trough.mesh": "geometry/trough.stl"})
    with pytest.raises(InputError, match="trough.mesh") as info:
        load_case(write_case(tmp_path, tables))
    assert "trough.stl" in str(info.value)


def test_user_timestep_above_the_stability_limit_is_refused_at_load(tmp_path):
    tables = with_changes({"run.timestep": 1e-3})
    with pytest.raises(InputError, match="run.timestep") as info:
        load_case(write_case(tmp_path, tables))
    assert "stability limit" in str(info.value)


def test_periodic_length_must_hold_a_grain_and_its_skin_twice(tmp_path):
    # 4 radii passed the old two-diameter check and failed only when the run was built
    tables = with_changes({"trough.length": 4.2 * 0.002})
    with pytest.raises(InputError, match="trough.length"):
        load_case(write_case(tmp_path, tables))


def test_the_schema_is_consistent_with_the_quantities_and_the_law_registry():
    """Every number has its range in dem.quantities, every default is one of its choices, the
    owners are shapes or laws, and the contact owners refuse exactly the registry's foreign keys."""
    from dem.physics import laws
    from dem.quantities import QUANTITIES
    from dem.scene.schema import (
        CONTACT,
        CONTACT_MODELS,
        PARTICLE_TYPE,
        RADIUS_DISTRIBUTIONS,
        SCHEMA,
        SHAPES,
        TANGENTIAL_CONVENTIONS,
    )
    from dem.scene.tomltable import ALL

    selectors = {ALL, *SHAPES, *CONTACT_MODELS, *TANGENTIAL_CONVENTIONS, *RADIUS_DISTRIBUTIONS}
    for table, keys in {**SCHEMA, "particles.types": PARTICLE_TYPE}.items():
        assert len({k.name for k in keys}) == len(keys), table
        for k in keys:
            ranged = k.numeric or k.kind == "numbers"
            assert (k.quantity in QUANTITIES) == ranged, f"{table}.{k.name}"
            if k.kind == "choice":
                assert k.default in k.choices, f"{table}.{k.name}"
            if k.numeric and isinstance(k.default, int | float):
                assert QUANTITIES[k.quantity].accepts(k.default), f"{table}.{k.name}"
            for owner in k.owners:
                assert set(owner.split("+")) <= selectors, f"{table}.{k.name}: {owner}"
    for model in CONTACT_MODELS:
        for tangential in TANGENTIAL_CONVENTIONS:
            foreign = tuple(k.name for k in CONTACT if not k.owned((model, tangential)))
            assert foreign == laws.foreign_keys(model, tangential), (model, tangential)


@pytest.mark.parametrize(
    "shape, key, owner",
    [("sphere", "length", "screw"), ("screw", "template", "clump"), ("clump", "radius", "sphere"),
     ("sphere", "mass", "screw")],
)  # fmt: skip
def test_a_key_of_another_shape_is_refused_naming_its_shape(tmp_path, shape, key, owner):
    changes = {"particles.shape": shape, "particles.radius": None, f"particles.{key}": 0.01}
    tables = with_changes(changes)
    with pytest.raises(InputError, match=f"a key of shape = '{owner}', not of '{shape}'") as info:
        load_case(write_case(tmp_path, tables))
    assert info.value.key == f"particles.{key}"


@pytest.mark.validation
def test_screw_and_clump_build_their_template(tmp_path):
    screw = with_changes(
        {
            "particles.radius": None,
            "particles.shape": "screw",
            "particles.length": 0.02,
            "particles.shank_radius": 0.0015,
            "particles.head_radius": 0.003,
            "particles.mass": 0.0025,
            "material.density": None,  # the mass sets it
        }
    )
    (tmp_path / "screw").mkdir()
    case = load_case(write_case(tmp_path / "screw", screw))
    assert case.particles.grain.name == "screw"
    assert case.particles.grain.mass == pytest.approx(0.0025)
    assert "grain" not in case.as_dict()["particles"]
    (tmp_path / "clump").mkdir()
    (tmp_path / "clump" / "pair.spheres").write_text("0 0 0 0.002\n0.003 0 0 0.002\n")
    clump = with_changes(
        {"particles.radius": None, "particles.shape": "clump", "particles.template": "pair.spheres"}
    )
    case = load_case(write_case(tmp_path / "clump", clump))
    grain = case.particles.grain
    assert grain.count == 2
    assert grain.mass == pytest.approx(case.material.density * grain.volume)


@pytest.mark.parametrize(
    "text, key, allowed",
    [
        ("0 0 0 0.002\n0 0 0 0.002\n", "spheres 1 and 2", "listed twice"),
        ("0 0 0 1e-12\n", "line 1: r", "[1e-7, 10] m"),
        ("0 0 0 0.002\n0 0 zero 0.002\n", "line 2", "four finite numbers"),
    ],
)
def test_a_bad_clump_template_is_named_with_its_file_and_line(tmp_path, text, key, allowed):
    """Errors inside a template name the template file (not case.toml), the line or members,
    and the case key that points to it; 1e-12 m spheres (a segfault before) are refused."""
    (tmp_path / "t.spheres").write_text(text)
    clump = with_changes(
        {"particles.radius": None, "particles.shape": "clump", "particles.template": "t.spheres"}
    )
    with pytest.raises(InputError) as info:
        load_case(write_case(tmp_path, clump))
    message = str(info.value)
    assert info.value.key == key and allowed in message
    assert str(tmp_path / "t.spheres") in message and "particles.template" in message


# --- bad input -----------------------------------------------------------------------------------

BAD = [
    # (id, changes, key in the error, snippet of the allowed range)
    ("missing-length", {"trough.length": None}, "trough.length", "required"),
    ("missing-width", {"trough.width": None}, "trough.width", "required"),
    ("missing-frequency", {"drive.frequency": None}, "drive.frequency", "required"),
    ("missing-angle", {"drive.angle": None}, "drive.angle", "required"),
    ("missing-density", {"material.density": None}, "material.density", "required"),
    ("missing-friction", {"material.friction": None}, "material.friction", "required"),
    (
        "missing-count",
        {"particles.count": None},
        "particles.count",
        "exactly one of particles.count, layers",
    ),
    ("count-and-layers", {"particles.layers": 2.0}, "particles.count", "(given: count, layers)"),
    ("missing-radius", {"particles.radius": None}, "particles.radius", "required"),
    ("missing-E", {"contact.youngs_modulus": None}, "contact.youngs_modulus", "required"),
    (
        "missing-stiffness",
        {"contact.model": "linear", "contact.youngs_modulus": None},
        "contact.stiffness",
        "required",
    ),
    ("unknown-key", {"particles.radus": 0.002}, "particles.radus", "did you mean 'radius'"),
    ("unknown-model", {"contact.model": "hertz"}, "contact.model", "did you mean 'hertz_mindlin'"),
    ("unknown-shape", {"particles.shape": "cube"}, "particles.shape", "one of"),
    ("bool-not-number", {"particles.radius": True}, "particles.radius", "a number"),
    ("string-not-number", {"trough.length": "0.1 m"}, "trough.length", "a number"),
    ("float-not-int", {"particles.count": 3.5}, "particles.count", "an integer"),
    ("bool-not-int", {"run.seed": True}, "run.seed", "an integer"),
    ("int-not-bool", {"particles.rotation": 1}, "particles.rotation", "true or false"),
    ("nan", {"material.density": float("nan")}, "material.density", "[1, 1e5]"),
    ("radius-zero", {"particles.radius": 0.0}, "particles.radius", "[1e-7, 10]"),
    ("radius-negative", {"particles.radius": -0.002}, "particles.radius", "[1e-7, 10]"),
    ("length-zero", {"trough.length": 0.0}, "trough.length", "(0, 1000]"),
    ("width-negative", {"trough.width": -0.04}, "trough.width", "(0, 1000]"),
    ("density-zero", {"material.density": 0.0}, "material.density", "[1, 1e5]"),
    ("frequency-negative", {"drive.frequency": -60.0}, "drive.frequency", "[0.01, 1e5]"),
    ("E-zero", {"contact.youngs_modulus": 0.0}, "contact.youngs_modulus", "[1e3, 1e13]"),
    (
        "stiffness-negative",
        {"contact.model": "linear", "contact.youngs_modulus": None, "contact.stiffness": -1.0},
        "contact.stiffness",
        "[1e-3, 1e12]",
    ),
    ("count-zero", {"particles.count": 0}, "particles.count", "[1, 1e9]"),
    ("angle-zero", {"drive.angle": 0.0}, "drive.angle", "(0, 90)"),
    ("angle-90", {"drive.angle": 90.0}, "drive.angle", "(0, 90)"),
    ("angle-negative", {"drive.angle": -10.0}, "drive.angle", "(0, 90)"),
    ("inclination-90", {"trough.inclination": 90.0}, "trough.inclination", "< 90"),
    ("inclination-minus-95", {"trough.inclination": -95.0}, "trough.inclination", "< 90"),
    ("friction-negative", {"material.friction": -0.1}, "material.friction", "[0, 1e12]"),
    ("en-negative", {"material.restitution_normal": -0.1}, "material.restitution_normal", "<= 1"),
    ("en-above-1", {"material.restitution_normal": 1.5}, "material.restitution_normal", "<= 1"),
    (
        "et-above-1",
        {"material.restitution_tangential": 1.01},
        "material.restitution_tangential",
        "<= 1",
    ),
    (
        "et-negative",
        {"material.restitution_tangential": -0.5},
        "material.restitution_tangential",
        "<= 1",
    ),
    ("poisson-minus-1", {"contact.poisson_ratio": -1.0}, "contact.poisson_ratio", "-1 < nu < 0.5"),
    ("poisson-half", {"contact.poisson_ratio": 0.5}, "contact.poisson_ratio", "-1 < nu < 0.5"),
    ("width-below-diameter", {"trough.width": 0.003}, "trough.width", "grain diameter"),
    ("both-drives", {"drive.throw_number": 2.0}, "drive.amplitude", "both are given"),
    ("no-drive", {"drive.amplitude": None}, "drive.amplitude|throw_number", "neither is given"),
    ("amplitude-zero", {"drive.amplitude": 0.0}, "drive.amplitude", "[1e-9, 1]"),
    ("missing-mesh", {"trough.mesh": "geometry/nope.stl"}, "trough.mesh", "nope.stl"),
    (
        "missing-template",
        {"particles.radius": None, "particles.shape": "clump", "particles.template": "x.spheres"},
        "particles.template",
        "x.spheres",
    ),
    (
        "screw-shank-above-head",
        {
            "particles.radius": None,
            "particles.shape": "screw",
            "particles.length": 0.02,
            "particles.shank_radius": 0.004,
            "particles.head_radius": 0.003,
        },
        "particles.shank_radius",
        "<= head_radius",
    ),
    ("stiffness-with-hertz", {"contact.stiffness": 2000.0}, "contact.stiffness", "remove it"),
    (
        "kt-ratio-with-liggghts-hertz",
        {"contact.tangential": "liggghts", "contact.tangential_stiffness_ratio": 0.5},
        "contact.tangential_stiffness_ratio",
        "remove it",
    ),
    (
        "damping-with-liggghts",
        {"contact.tangential": "liggghts", "contact.tangential_damping_ratio": 0.3},
        "contact.tangential_damping_ratio",
        "remove it",
    ),
    ("tangential-word", {"contact.tangential": "mindlin"}, "contact.tangential", "coulomb"),
    (
        "damping-negative",
        {"contact.tangential": "coulomb", "contact.tangential_damping_ratio": -0.1},
        "contact.tangential_damping_ratio",
        "0 <= value <= 10",
    ),
    (
        "et-1-derives-no-spring",
        {"contact.tangential": "coulomb", "material.restitution_tangential": 1.0},
        "material.restitution_tangential",
        "< eps_t < 1",
    ),
    ("radius-with-screw", {"particles.shape": "screw"}, "particles.radius", "shape = 'sphere'"),
    ("timestep-word", {"run.timestep": "fast"}, "run.timestep", '"auto"'),
    ("timestep-negative", {"run.timestep": -1e-6}, "run.timestep", '"auto"'),
    ("cycles-zero", {"run.cycles": 0}, "run.cycles", "[1, 1e7]"),
    (
        "second-angle-alone",
        {"drive.second_angle": 90.0},
        "drive.second_angle",
        "only with drive.second_amplitude > 0",
    ),
    (
        "second-amplitude-without-angle",
        {"drive.second_amplitude": 1e-4},
        "drive.second_angle",
        "required",
    ),
    (
        "second-amplitude-negative",
        {"drive.second_amplitude": -1e-4},
        "drive.second_amplitude",
        "[0, 1] m",
    ),
    (
        "second-angle-180",
        {"drive.second_amplitude": 1e-4, "drive.second_angle": 180.0},
        "drive.second_angle",
        "[0, 180)",
    ),
    (
        "second-phase-huge",
        {"drive.second_amplitude": 1e-4, "drive.second_angle": 90.0, "drive.second_phase": 1e4},
        "drive.second_phase",
        "[-360, 360]",
    ),
    ("ramp-negative", {"drive.ramp_cycles": -1.0}, "drive.ramp_cycles", "[0, 1000]"),
    (
        "ramp-into-measuring",
        {"drive.ramp_cycles": 12.0, "run.settle_cycles": 10},
        "drive.ramp_cycles",
        "<= run.settle_cycles = 10",
    ),
    ("frames-zero", {"output.frames_per_cycle": 0}, "output.frames_per_cycle", "[1, 1e6]"),
]


@pytest.mark.parametrize(
    ("changes", "key", "allowed"), [b[1:] for b in BAD], ids=[b[0] for b in BAD]
)
def test_bad_input_names_key_value_and_file(tmp_path, changes, key, allowed):
    path = write_case(tmp_path, with_changes(changes))
    with pytest.raises(InputError) as info:
        load_case(path)
    error = info.value
    message = str(error)
    assert error.key == key
    assert key in message
    assert repr(error.value) in message
    if key in changes and changes[key] is not None:
        # the error carries the value as written in the file
        written = changes[key]
        assert error.value == written or math.isnan(written)
        assert type(error.value) is type(written) or not isinstance(written, bool)
    assert allowed in message
    assert str(path.resolve()) in message


def test_unknown_table_suggests(tmp_path):
    tables = copy.deepcopy(BASE)
    tables["partciles"] = tables.pop("particles")
    path = write_case(tmp_path, tables)
    with pytest.raises(InputError, match="did you mean 'particles'") as info:
        load_case(path)
    assert info.value.key == "partciles"
    assert str(path.resolve()) in str(info.value)


def test_table_that_is_not_a_table(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text("trough = 3\n")
    with pytest.raises(InputError, match=r"trough = 3 .*a table \[trough\]"):
        load_case(path)


def test_syntax_error_gives_the_line(tmp_path):
    path = tmp_path / "case.toml"
    text = write_case(tmp_path, BASE).read_text().splitlines()
    text.insert(3, "angle = 25 deg")  # line 4
    path.write_text("\n".join(text))
    with pytest.raises(InputError) as info:
        load_case(path)
    assert info.value.key == "line 4"
    assert "line 4" in str(info.value) and str(path.resolve()) in str(info.value)


def test_missing_case(tmp_path):
    with pytest.raises(InputError, match="case.toml") as info:
        load_case(tmp_path / "nowhere")
    assert info.value.key == "case"


def test_with_drive_keeps_the_given_quantity_and_recomputes_the_other():
    """A throw-number case keeps Gamma at a new angle (A follows); an amplitude case keeps A
    (Gamma follows); giving one of them sets it. Checked against Gamma = A w^2 sin(phi) / g."""
    case = load_case(Path(__file__).resolve().parents[2] / "cases" / "screw-trough")
    assert case.drive.given == "throw_number"
    w2 = (2 * math.pi * case.drive.frequency) ** 2

    turned = case.with_drive(angle=40.0)
    assert turned.drive.throw_number == case.drive.throw_number
    assert turned.drive.amplitude * w2 * math.sin(math.radians(40.0)) / GRAVITY == pytest.approx(
        case.drive.throw_number, rel=1e-14
    )
    by_amplitude = case.with_drive(amplitude=4e-4)
    assert by_amplitude.drive.given == "amplitude"
    held = by_amplitude.with_drive(angle=40.0)
    assert held.drive.amplitude == 4e-4
    assert held.drive.throw_number == pytest.approx(
        4e-4 * w2 * math.sin(math.radians(40.0)) / GRAVITY, rel=1e-14
    )
    assert case.drive.angle == 25.0  # frozen: the original is untouched


@pytest.mark.validation
def test_second_component_and_ramp_are_read_and_kept_by_with_drive(tmp_path):
    changes = {"drive.second_amplitude": 2e-4, "drive.second_angle": 90.0,
               "drive.second_phase": 90.0, "drive.ramp_cycles": 3.5}  # fmt: skip
    case = load_case(write_case(tmp_path, with_changes(changes)))
    d = case.drive
    assert (d.second_amplitude, d.second_angle, d.second_phase, d.ramp_cycles) == (
        2e-4, 90.0, 90.0, 3.5)  # fmt: skip
    assert d.elliptical
    assert len(d.motion.components) == 2
    assert d.motion.ramp_time == pytest.approx(3.5 / 60.0)
    # |Z|^2 = (A sin phi)^2 + A_2^2 a quarter period apart; |X| = A cos phi
    a, phi = d.amplitude, math.radians(d.angle)
    z = math.hypot(a * math.sin(phi), 2e-4)
    assert d.effective_throw_number(0.0) == pytest.approx(z * d.omega**2 / GRAVITY, rel=1e-12)
    assert d.velocity_scale == pytest.approx(a * math.cos(phi) * d.omega, rel=1e-12)
    turned = case.with_drive(angle=40.0)
    assert (turned.drive.second_amplitude, turned.drive.ramp_cycles) == (2e-4, 3.5)
    plain = load_case(write_case(tmp_path, BASE)).drive
    assert not plain.elliptical and plain.ramp_cycles == 0.0
    assert plain.velocity_scale == plain.amplitude * plain.omega * math.cos(math.radians(25.0))


@pytest.mark.validation
def test_with_tangential_gives_the_deck_equivalent_case():
    hertz = load_case(CASES_DIR / "sphere-bed").with_tangential("liggghts")
    assert hertz.contact.tangential == "liggghts"
    assert hertz.contact.tangential_stiffness_ratio is None
    assert hertz.contact.tangential_damping_ratio is None
    linear = load_case(CASES_DIR / "single-sphere").with_tangential("liggghts")
    assert linear.contact.tangential_stiffness_ratio == pytest.approx(2 / 7)
    with pytest.raises(ValueError):
        linear.with_tangential("mindlin")


def test_more_frames_than_steps_per_cycle_is_refused_at_load(tmp_path):
    """A frame rate above the step rate would write empty frames forever: refused by key."""
    tables = with_changes({"output.frames_per_cycle": 10**5})
    with pytest.raises(InputError, match="output.frames_per_cycle") as info:
        load_case(write_case(tmp_path, tables))
    assert "time steps per drive cycle" in str(info.value)


def test_a_clumps_mass_sets_its_density_and_a_density_beside_it_is_refused():
    """material.density beside particles.mass would be read and ignored: refused, by key."""
    from small_case import SMALL_CASE, write_case

    screws = SMALL_CASE.replace(
        'shape = "sphere"\ncount = 120\nradius = 0.002',
        'shape = "screw"\ncount = 10\nlength = 0.022\nshank_radius = 0.0018\nhead_radius = 0.0036\n'
        "mass = 0.0025",
    ).replace("length = 0.03", "length = 0.08")
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        with pytest.raises(InputError) as info:
            load_case(write_case(Path(tmp) / "both", screws))
        assert info.value.key == "material.density" and "particles.mass" in str(info.value)
        case = load_case(write_case(Path(tmp) / "mass", screws.replace("density = 7800.0\n", "")))
        grain = case.particles.grain
        assert case.material.density == grain.density == pytest.approx(0.0025 / grain.volume)
        with pytest.raises(InputError) as info:  # spheres need it
            load_case(write_case(Path(tmp) / "none", SMALL_CASE.replace("density = 7800.0\n", "")))
        assert info.value.key == "material.density" and "required" in str(info.value)


@pytest.mark.validation
def test_the_liggghts_parity_bed_is_the_sphere_bed_at_5e7_pa():
    """validation/liggghts-bulk/sphere-bed-5e7 differs from cases/sphere-bed in stiffness and
    step only: the LIGGGHTS comparisons keep their bed while the shipped one is converged."""
    parity = load_case(CASES_DIR.parent / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
    shipped = load_case(CASES_DIR / "sphere-bed")
    assert parity.contact.youngs_modulus == 5.0e7 and parity.run.timestep is None
    same = dataclasses.replace(
        parity,
        contact=dataclasses.replace(parity.contact, youngs_modulus=shipped.contact.youngs_modulus),
        run=dataclasses.replace(parity.run, timestep=shipped.run.timestep),
        name=shipped.name,
        source=shipped.source,
        directory=shipped.directory,
    )
    assert same == shipped
