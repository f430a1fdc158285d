"""``dem plan``: cost, memory, expected error and advice of a case, without running it."""

import dataclasses
import json
import math
import tracemalloc
from datetime import date
from pathlib import Path

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.engine import setup
from dem.run import accuracy, cost, plan, stiffness
from dem.run.runner import run_case
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
PARITY = CASES_DIR.parent / "validation" / "liggghts-bulk" / "sphere-bed-5e7"  # 5e7 Pa
SHIPPED = sorted(p.parent for p in CASES_DIR.glob("*/case.toml"))
TABLES = ("trough", "drive", "material", "contact", "particles", "run", "output", "feeder")


def synthetic_study(base_error=0.01, stderr=0.005) -> dict:
    """A study summary with known numbers (the shape run_all.py writes)."""
    kind = {
        "reference": 0.7, "fill_spread": 0.01, "base_error": base_error,
        "base_stderr": stderr, "base_cycles": 20, "settle_cycles": 10.0,
        "particle_steps_per_s_1thread": 5.0e6, "reference_uncertainty": 0.0,
        # against the reference:
        "stiffness": [[1e6, 0.2], [1e7, base_error], [5e7, base_error], [1e9, 0.0]],
        # against the base settings:
        "timestep": [[0.1, 0.0], [0.3046, 0.0], [1.0, 0.04]],
        "contact_model": {"hertz_mindlin coulomb": 0.0, "linear coulomb": 0.05},
        "section_length": [[10.0, 0.1], [25.0, 0.0], [50.0, 0.0]],
        "section_width": [[1.0, 0.1], [10.0, 0.0], [20.0, 0.0]],
        "resolution": [[6, 0.0], [8, 0.0], [15, 0.0]],
        "ladder": {"point mass": 0.03, "one grain": 0.04, "one grain vs point mass": 0.01,
                   "point mass wall_time_s": 1e-3, "one grain wall_time_s": 1.0},
        "cheapest": {"youngs_modulus": 3e7, "timestep_fraction": 0.6,
                     "section_length_grains": 12.0, "section_width_grains": 5.0},
        # measured under the default law (only the keys given are compared)
        "conditions": {"tangential": "impact", "layers": None},  # depth: not this study's test
    }  # fmt: skip
    return {"cases": {"sphere-bed": kind, "screw-trough": kind}}


@pytest.fixture
def study(monkeypatch):
    """The synthetic speed-accuracy study alone (the bed-compliance rule of dem.run.stiffness has
    its own data and tests/run/test_stiffness.py)."""
    data = synthetic_study()
    monkeypatch.setattr(accuracy, "study_data", lambda: data)
    monkeypatch.setattr(stiffness, "study", lambda: None)
    return data


def small(tmp_path, keys=None):
    """SMALL_CASE in the 100 x 40 mm section of cases/sphere-bed, with ``keys`` overridden.

    Settled for 6 cycles, not SMALL_CASE's 2: at its Gamma 3.06 friction needs 3 cycles at
    least to take the drive's start-up velocity out of the bed, and plan warns of a shorter
    settle (:func:`dem.run.plan.relax_advice`), which these tests of other advice do not ask.
    """
    directory = write_case(tmp_path / "case", SMALL_CASE)
    base = {"trough.length": 0.10, "trough.width": 0.04, "run.settle_cycles": 6}
    return load_case(directory, base | (keys or {}))


@pytest.mark.integration
@pytest.mark.parametrize("directory", SHIPPED, ids=lambda p: p.name)
def test_plan_on_every_shipped_case(directory, capsys):
    """The study's own data: every field present and consistent with the case."""
    assert main(["plan", str(directory)]) == 0
    text = capsys.readouterr().out
    for word in ("grains", "time step", "steps per cycle", "memory", "wall time", "expected error"):
        assert word in text
    assert main(["plan", str(directory), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    case = load_case(directory)
    step = timestep_for(case)
    per = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    assert out["spheres"] == case.particles.count * per
    assert out["timestep"] == step.dt and out["timestep_limit"] == step.limit
    assert out["steps_per_cycle"] == pytest.approx(1.0 / case.drive.frequency / step.dt)
    # B a sphere (the impact law keeps 5 floats of history per contact); a mesh adds slots
    per = 1400 if case.trough.mesh is None else 1700
    assert 0 < out["memory_bytes"] < per * out["spheres"] + 8000  # and 8 kB fixed
    assert out["wall_time_s"] > 0
    if accuracy.unmeasured(case, accuracy.study_data()["cases"][accuracy.study_kind(case)],
                       accuracy.study_kind(case)):  # fmt: skip
        # the study ran the "coulomb" law at its own drives: nothing is claimed elsewhere
        # (NaN in Python, null in the strict JSON)
        assert out["expected_error"] is None and "not measured" in out["error_source"]
        assert ("dem run" if case.particles.count == 1 else "dem sweep") in out["error_source"]
    elif case.particles.count > 1:  # a bed: the study's error; one grain: the point mass's
        assert 0 <= out["expected_error"] < 1
    else:
        assert out["expected_error"] is None and "point mass" in out["error_source"]
    for advice in out["advice"]:
        assert advice["level"] in ("warn", "note")
        assert advice["key"].split(".")[0] in TABLES


@pytest.mark.integration
def test_memory_estimate_matches_what_a_run_allocates(tmp_path, study):
    """Independent check: tracemalloc's count of the bytes the built simulation holds.

    A first build of the same case is thrown away: it imports the modules setup loads lazily
    and compiles what it needs, 1.4 MB that a run holds once, not per sphere, and that the
    test run alone counted (4.2 MB held against 2.8 MB estimated, 2.8 MB on the second build).
    """
    case = small(tmp_path, {"particles.count": 3000})
    case = dataclasses.replace(case, particles=dataclasses.replace(case.particles, count=3000))
    expected = plan.plan(case, threads=1).memory_bytes
    setup.from_case(case)  # the one-time imports and compilation, outside the count
    tracemalloc.start()
    sim = setup.from_case(case)
    held, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert sim.spheres.n == 3000
    assert 0.8 * held < expected < 1.25 * held, (expected, held)


@pytest.mark.integration
def test_expected_error_is_the_base_error_at_shipped_settings(tmp_path, study):
    """At the shipped settings only the stiffness error counts; more cycles cut a run's noise."""
    case = small(tmp_path, {"particles.count": 1500})
    p = plan.plan(case, cycles=20)
    assert p.error_parts["systematic"] == pytest.approx(0.01, abs=1e-4)
    # at the study's cycles a run scatters by the fill-to-fill spread ...
    assert p.error_parts["statistical"] == pytest.approx(0.01)
    assert p.expected_error == pytest.approx(math.hypot(0.01, 0.01), abs=1e-4)
    # ... of which only the within-run part (stderr 0.005) falls with more cycles
    p4 = plan.plan(case, cycles=80)
    between = math.sqrt(0.01**2 - 0.005**2)
    assert p4.error_parts["statistical"] == pytest.approx(math.hypot(between, 0.0025))
    assert p.warnings() == []


@pytest.mark.integration
def test_the_step_counts_against_the_step_the_stiffness_was_measured_at(tmp_path, study):
    """The stiffness series comes from a sweep at its own step (0.5 of the limit in the
    shipped data): the step's part is its effect there minus its effect at the sweep's step,
    so a case at the sweep's step gets the stiffness error alone."""
    kind = study["cases"]["sphere-bed"]
    kind["timestep"] = [[0.1, 0.0], [0.3046, 0.0], [0.5, 0.02], [1.0, 0.04]]
    case = small(tmp_path, {"particles.count": 1500})
    limit = plan.plan(case).timestep_limit
    at = {}
    for f in (0.5, 1.0):
        c = load_case(case.directory, {"trough.length": 0.10, "trough.width": 0.04,
                                       "particles.count": 1500,
                                       "run.timestep": f * limit * (1 - 1e-9)})  # fmt: skip
        at[f] = plan.plan(c).error_parts.get("time step", 0.0)
    assert at[0.5] == pytest.approx(0.02, abs=1e-6) and at[1.0] == pytest.approx(0.04, abs=1e-6)
    kind["stiffness_timestep_fraction"] = 0.5
    for f, want in ((0.5, 0.0), (1.0, 0.02)):
        c = load_case(case.directory, {"trough.length": 0.10, "trough.width": 0.04,
                                       "particles.count": 1500,
                                       "run.timestep": f * limit * (1 - 1e-9)})  # fmt: skip
        assert plan.plan(c).error_parts.get("time step", 0.0) == pytest.approx(want, abs=1e-6)


@pytest.mark.integration
def test_advice_names_what_a_case_overdoes_or_underdoes(tmp_path, study):
    stiff = plan.plan(small(tmp_path / "a", {"contact.youngs_modulus": 1e9}))
    assert [a.key for a in stiff.warnings()] == ["contact.youngs_modulus"]
    assert "far stiffer" in stiff.warnings()[0].text
    short = plan.plan(small(tmp_path / "b", {"trough.length": 0.03}))
    keys = [a.key for a in short.warnings()]
    assert "trough.length" in keys
    assert short.error_parts["section length"] == pytest.approx(0.1, rel=0.2)
    few = plan.plan(small(tmp_path / "c"), cycles=1)
    assert "run.cycles" in [a.key for a in few.warnings()]
    fine = small(tmp_path / "d", {"run.timestep": 1e-6})
    assert "far finer" in plan.plan(fine).warnings()[0].text
    one = plan.plan(small(tmp_path / "e", {"particles.count": 1}))
    note = next(a for a in one.advice if a.key == "particles.count")
    assert note.level == "note" and "dem pointmass velocity --throw-number" in note.text


@pytest.mark.integration
def test_soft_contacts_outside_the_study_are_flagged(tmp_path, study):
    soft = plan.plan(small(tmp_path, {"contact.youngs_modulus": 1e5}))
    texts = " ".join(a.text for a in soft.warnings())
    assert "softer than the stiffness sweep found accurate" in texts
    assert "outside the studied range" in soft.error_source
    assert len([a for a in soft.warnings() if a.key == "contact.youngs_modulus"]) == 1


@pytest.mark.integration
def test_wall_time_uses_the_last_run_of_the_case(tmp_path, study):
    case = small(tmp_path)
    directory = case.directory
    before = plan.plan(case, threads=1)
    assert "shipped sphere cases" in before.rate_source
    (directory / "output").mkdir()
    (directory / "output" / "summary.json").write_text(
        json.dumps({"particle_steps_per_s": 1.0e6, "threads": 1, "spheres": 120})
    )
    after = plan.plan(case, threads=1)
    assert after.particle_steps_per_s == 1.0e6 and "last run" in after.rate_source
    overhead = after.steps * cost.STEP_OVERHEAD_S + cost.STARTUP_S + after.compile_s
    overhead += after.fill_s + after.frames_s
    assert after.wall_time_s == pytest.approx(after.particle_steps / 1.0e6 + overhead)


@pytest.mark.integration
def test_wall_time_adds_the_compile_only_where_the_cache_is_cold(tmp_path, monkeypatch, study):
    from dem import kernels

    case = small(tmp_path)
    monkeypatch.setattr(kernels, "compiled", lambda clumps=False, mesh=False: True)
    warm = plan.plan(case, threads=1)
    monkeypatch.setattr(kernels, "compiled", lambda clumps=False, mesh=False: False)
    cold = plan.plan(case, threads=1)
    assert warm.compile_s == 0.0 and cold.compile_s == cost.COMPILE_S["sphere"]
    assert cold.wall_time_s - warm.wall_time_s == pytest.approx(cost.COMPILE_S["sphere"])
    assert "no numba cache yet" in cold.text() and "no numba cache" not in warm.text()
    fill = cost.FILL_S["sphere"] + 120 * cost.FILL_S_PER_GRAIN["sphere"]
    assert cold.fill_s == pytest.approx(fill)
    frames = 1 + (cold.settle_cycles + cold.cycles) * case.output.frames_per_cycle
    assert cold.frames == frames and plan.plan(case, threads=1, frames=False).frames == 0


@pytest.mark.integration
def test_suggest_writes_the_case_the_advice_recommends(tmp_path, capsys):
    """The 5e7 LIGGGHTS-parity sphere bed: the stiffness rule asks for more; applied, it asks
    nothing."""
    out = tmp_path / "suggested"
    assert main(["plan", str(PARITY), "--suggest", str(out)]) == 0
    printed = capsys.readouterr().out
    before = plan.plan(load_case(PARITY))
    warned = [a for a in before.warnings() if a.key == "contact.youngs_modulus"]
    assert warned and warned[0].value is not None and "contact.youngs_modulus" in printed
    case = load_case(out)  # it loads
    assert case.contact.youngs_modulus == warned[0].value
    after = plan.plan(case)
    assert not [a for a in after.advice if a.value is not None], after.text()
    text = (out / "case.toml").read_text()
    assert "# dem plan --suggest" in text and "was 50000000.0" in text
    # nothing of the original is lost: each line is there, a changed key's as "# was: ..."
    # (its unit and the comment lines that continue it stay where they were), and the header
    # says the comments are the original case's
    lines = text.splitlines()
    for line in (PARITY / "case.toml").read_text().splitlines():
        assert line in lines or f"# was: {line.strip()}" in lines, line
    was = lines.index("# was: youngs_modulus = 5.0e7  # Pa, as specified for the LIGGGHTS and "
                      "speed references. Too soft for")  # fmt: skip
    assert lines[was - 1].startswith("youngs_modulus = ") and lines[was + 1].startswith("# the ")
    assert lines[0].startswith("# dem plan --suggest") and "contact.youngs_modulus" in lines[1]
    assert not (out / "README.md").exists()  # it describes the case as it was
    # nothing is replaced: a second suggestion into the same folder is refused
    assert main(["plan", str(PARITY), "--suggest", str(out)]) == 2
    assert "--suggest" in capsys.readouterr().err


@pytest.mark.integration
def test_suggest_keeps_a_mesh_trough_and_the_set_keys(tmp_path, capsys):
    out = tmp_path / "deep" / "u"
    argv = ["plan", str(CASES_DIR / "u-trough"), "--set", "run.cycles=30", "--suggest", str(out)]
    assert main(argv) == 0
    case = load_case(out)
    assert case.trough.mesh == load_case(CASES_DIR / "u-trough").trough.mesh
    assert case.run.cycles == 30
    cycles_line = [line for line in (out / "case.toml").read_text().splitlines()
                   if line.startswith("cycles = ")]  # fmt: skip
    filed = load_case(CASES_DIR / "u-trough").run.cycles
    assert cycles_line == [f"cycles = 30  # dem plan --suggest {date.today()}, was {filed!r}"]


@pytest.mark.integration
def test_suggest_refuses_advice_that_moves_a_key_back_and_forth(tmp_path, monkeypatch):
    from dem.errors import InputError

    calls = iter(range(100))

    def flip(case, **kw):  # advice that alternates between two values
        value = [1e8, 2e8][next(calls) % 2]
        return dataclasses.replace(
            real(case, **kw), advice=[accuracy.Advice("warn", "contact.youngs_modulus", "x", value)]
        )

    real = plan.plan
    monkeypatch.setattr(plan, "plan", flip)
    with pytest.raises(InputError, match="back and forth"):
        plan.suggest(CASES_DIR / "sphere-bed", tmp_path / "s")
    assert not (tmp_path / "s").exists()  # nothing written


@pytest.mark.integration
def test_run_warns_once_at_start_and_writes_the_plan(tmp_path, study):
    """The driven steps the plan counts are the steps the run takes."""
    case = small(tmp_path, {"contact.youngs_modulus": 1e9})
    case = dataclasses.replace(case, particles=dataclasses.replace(case.particles, count=40))
    with pytest.warns(plan.PlanWarning, match="contact.youngs_modulus") as record:
        summary = run_case(case, tmp_path / "out", progress=False, frames=False)
    assert len([w for w in record if w.category is plan.PlanWarning]) == 1
    p = summary["plan"]
    driven = p["steps"] - cost.settle_steps(case, p["timestep"])
    assert abs(summary["steps"] - driven) <= p["settle_cycles"] + p["cycles"]
    assert p["timestep"] == summary["timestep"]
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["plan"] == json.loads(
        json.dumps(p)
    )


@pytest.mark.integration
def test_plan_claims_only_what_was_measured(tmp_path):
    """The study's figures hold under its law and drive: elsewhere plan says "not measured"
    and names the command that measures it; at the study's own conditions it gives a number."""
    data = accuracy.study_data()
    assert data is not None
    case = load_case(CASES_DIR / "screw-trough")
    assert case.contact.tangential == "impact"
    assert data["cases"]["screw-trough"]["conditions"]["tangential"] == "impact"
    assert math.isfinite(plan.plan(case).expected_error)  # the study's own case
    other_law = case.with_tangential("coulomb")
    p = plan.plan(other_law)
    assert math.isnan(p.expected_error) and "not measured" in p.error_source
    assert "contact.tangential = 'coulomb' (study: 'impact')" in p.error_source
    assert "expected error    not estimated: not measured" in p.text()
    other_drive = case.with_drive(throw_number=1.3)
    p = plan.plan(other_drive)
    assert math.isnan(p.expected_error) and "drive.throw_number = 1.3" in p.error_source


@pytest.mark.integration
def test_plan_json_is_strict_json_with_null_for_what_was_not_measured(capsys):
    """'not measured' is NaN in Python and null in the JSON (NaN is not JSON)."""

    def refuse(name):
        raise ValueError(f"not JSON: {name}")

    argv = ["plan", str(CASES_DIR / "screw-trough"), "--set", "drive.angle=40", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out, parse_constant=refuse)
    assert out["expected_error"] is None and "not measured" in out["error_source"]
    assert main(["plan", str(CASES_DIR / "screw-trough"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out, parse_constant=refuse)
    assert 0.0 < out["expected_error"] < 0.05


def test_plan_warns_when_calibrated_contact_values_belong_to_another_drive(tmp_path):
    """dem calibrate's comment records the drive it fitted k_t / k_n on; another drive (here by
    an override, as dem run --set makes) gets a warning naming both."""
    from small_case import SMALL_CASE, write_case

    from dem.run.plan import plan
    from dem.scene.case import load_case

    text = SMALL_CASE.replace(
        "youngs_modulus = 5.0e7",
        'youngs_modulus = 5.0e7\ntangential = "coulomb"\n'
        "tangential_stiffness_ratio = 0.1581  # dem calibrate 2026-11-26: eps_t 0.800 for 0.8 "
        "at Gamma 3.06, phi 25 deg, mu 0.35, alpha 0 deg",
    )
    case_dir = write_case(tmp_path / "case", text)
    here = plan(load_case(case_dir))
    assert not [a for a in here.advice if a.key == "contact.tangential_stiffness_ratio"]
    there = plan(load_case(case_dir, {"drive.angle": 30.0}))
    [warn] = [a for a in there.advice if a.key == "contact.tangential_stiffness_ratio"]
    assert warn.level == "warn" and "phi 25 deg" in warn.text and "phi 30 deg" in warn.text


def test_a_cuda_plan_says_its_times_are_the_cpu_engines(tmp_path):
    cpu = plan.plan(load_case(write_case(tmp_path)), threads=1)
    cuda = plan.plan(load_case(write_case(tmp_path), {"run.device": "cuda"}), threads=1)
    assert cuda.wall_time_s == cpu.wall_time_s
    assert "GPU is not estimated" in cuda.rate_source and "GPU" not in cpu.rate_source
    assert "GPU is not estimated" in cuda.text()


def test_the_plan_counts_replicas_in_its_time_and_its_error():
    """Issue 48, item 4: `dem plan` ignored run.replicas in its time and error."""
    from dem.run.plan import plan as make_plan
    from dem.scene.case import load_case

    one = make_plan(load_case("cases/sphere-bed", {"run.replicas": 1}), threads=2)
    three = make_plan(load_case("cases/sphere-bed", {"run.replicas": 3}), threads=2)
    assert three.replicas == 3 and "for 3 fills" in three.text()
    # the statistical part of a pool of 3 fills is that of one over sqrt(3)
    ratio = three.error_parts["statistical"] / one.error_parts["statistical"]
    assert ratio == pytest.approx(3**-0.5, rel=1e-9)
    # 2 processes at a time on 2 threads, each at half the rate: 2 batches of 2 runs' time
    one_run = one.wall_time_s - one.compile_s - cost_startup() - one.frames_s
    assert three.wall_time_s - three.compile_s - cost_startup() - three.frames_s == pytest.approx(
        2 * (one_run + one.particle_steps / one.particle_steps_per_s), rel=1e-9
    )


def cost_startup():
    from dem.run import cost

    return cost.STARTUP_S


# --- plausibility at the door (issue 48, item 3) ---------------------------------------------


def test_a_grain_of_implausible_mass_is_refused_naming_the_mass_and_its_density():
    from dem.errors import InputError

    with pytest.raises(InputError, match=r"particles\.mass.*7\.77e\+06 kg/m\^3.*a mass in g"):
        load_case(CASES_DIR / "screw-trough", {"particles.mass": 2.5})


@pytest.mark.parametrize("key, value, named", [
    ("drive.angle", 0.35, "drive.angle 0.35 deg"),  # radians for degrees
    ("drive.throw_number", 50, "Gamma 50"),
    ("particles.count", 20000, "particles.count 20000"),
])  # fmt: skip
def test_a_unit_mistake_is_named_where_the_step_refuses_it(key, value, named):
    """The step is what such a mistake breaks first; its error names what set the impact."""
    from dem.errors import InputError

    with pytest.raises(InputError, match="run.timestep") as info:
        load_case(CASES_DIR / "screw-trough", {key: value})
    assert "hardest impact" in str(info.value) and named in str(info.value)


def test_no_error_figure_is_claimed_for_a_bed_unlike_the_studys():
    """A 120 m section (0.002 layers) and a contact the stiffness rule finds too soft leave
    the study's beds: no expected error, and a note naming the key."""
    for key, value, note in (
        ("trough.length", 120.0, "particles.layers"),
        ("contact.youngs_modulus", 5e7, "contact.youngs_modulus"),
    ):
        p = plan.plan(load_case(CASES_DIR / "screw-trough", {key: value}))
        assert math.isnan(p.expected_error), key
        assert note in p.error_source and any(a.key == note for a in p.advice)
    assert math.isfinite(plan.plan(load_case(CASES_DIR / "screw-trough")).expected_error)
