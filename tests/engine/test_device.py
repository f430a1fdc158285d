"""``[run] device`` and ``--device``: the key, the option, and the GPU engine's pre-flight check.

None of these tests needs a GPU: numba's ``cuda.is_available`` is replaced where a test needs a
machine with or without one, and nothing is run past the check.
"""

from pathlib import Path

import pytest
from small_case import SMALL_CASE, run_cli, write_case

from dem.engine.device import check_device
from dem.errors import InputError
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"
#: The U pan of cases/u-trough over the small case (its length and width are the mesh's).
U_PAN = {"trough.length": 0.12, "trough.width": 0.06,
         "trough.mesh": str(CASES / "geometry" / "u_trough.stl")}  # fmt: skip
#: What the GPU engine lacks: (the case, its overrides, the key a refusal names).
REFUSED = [
    ("feeder", {"feeder.feed_rate": 0.0}, "feeder"),
]


def _with_run_key(text: str, line: str) -> str:
    return text.replace("[run]\n", f"[run]\n{line}\n", 1)


@pytest.fixture
def gpu(monkeypatch):
    """A machine where numba's CUDA target works."""
    monkeypatch.setattr("numba.cuda.is_available", lambda: True)


@pytest.fixture
def no_gpu(monkeypatch):
    """A machine where numba's CUDA target finds no GPU."""
    monkeypatch.setattr("numba.cuda.is_available", lambda: False)


# --- the key ---------------------------------------------------------------------------------


def test_device_defaults_to_cpu_and_reads_cuda(tmp_path):
    assert load_case(write_case(tmp_path / "a")).run.device == "cpu"
    case = load_case(write_case(tmp_path / "b", _with_run_key(SMALL_CASE, 'device = "cuda"')))
    assert case.run.device == "cuda"
    assert load_case(write_case(tmp_path / "c"), {"run.device": "cuda"}).run.device == "cuda"


@pytest.mark.parametrize("value", ['"gpu"', '"CUDA"', "1", "true"])
def test_a_bad_device_is_refused_naming_key_value_and_choices(tmp_path, value):
    case_dir = write_case(tmp_path, _with_run_key(SMALL_CASE, f"device = {value}"))
    with pytest.raises(InputError) as info:
        load_case(case_dir)
    err = info.value
    assert err.key == "run.device" and err.source == str(case_dir / "case.toml")
    assert "'cpu', 'cuda'" in str(err)


@pytest.mark.integration
def test_a_bad_device_on_the_command_line_exits_2_before_any_work(capsys, tmp_path):
    case_dir = write_case(tmp_path / "case", _with_run_key(SMALL_CASE, 'device = "gpu"'))
    code, _, err = run_cli(capsys, "run", case_dir, "--out", tmp_path / "out")
    assert code == 2 and "run.device = 'gpu'" in err and "'cpu', 'cuda'" in err
    code, _, err = run_cli(capsys, "run", write_case(tmp_path / "ok"), "--device", "gpu")
    assert code == 2 and "--device" in err and "cuda" in err
    assert not (tmp_path / "out").exists()


def test_the_case_device_reaches_the_simulation_which_checks_it(tmp_path):
    from dem.engine import setup
    from dem.engine.simulation import Simulation

    cpu = setup.from_grains(load_case(write_case(tmp_path)), [[0.015, 0.0, 0.002]])
    assert cpu.device == "cpu"
    cuda = setup.from_grains(load_case(tmp_path, {"run.device": "cuda"}), [[0.015, 0.0, 0.002]])
    assert cuda.device == "cuda"
    assert Simulation(cpu.spheres, cpu.trough, cpu.law, cpu.dt).device == "cpu"
    with pytest.raises(ValueError, match="'gpu'"):
        Simulation(cpu.spheres, cpu.trough, cpu.law, cpu.dt, device="gpu")


# --- the option ------------------------------------------------------------------------------


def test_device_option_on_every_command_with_threads():
    """``--device`` beside every ``--threads``, with the schema's choices."""
    import argparse

    from dem.cli.parser import DEVICES, build_parser
    from dem.scene.schema import DEVICES as SCHEMA_DEVICES

    assert DEVICES == SCHEMA_DEVICES

    def commands(parser, path=()):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from commands(sub, (*path, name))
        yield path, {o for a in parser._actions for o in a.option_strings}, parser

    with_threads = [(path, p) for path, opts, p in commands(build_parser()) if "--threads" in opts]
    assert {path for path, _ in with_threads} == {("run",), ("plan",), ("sweep",), ("atlas",)}
    for path, p in with_threads:
        device = next(a for a in p._actions if "--device" in a.option_strings)
        assert tuple(device.choices) == SCHEMA_DEVICES and device.default is None, path


@pytest.mark.integration
def test_the_option_overrides_the_case_key(capsys, tmp_path, no_gpu):
    """Without a GPU: --device cuda over a cpu case is refused, --device cpu over a cuda case
    plans."""
    cpu_case = write_case(tmp_path / "cpu")
    cuda_case = write_case(tmp_path / "cuda", _with_run_key(SMALL_CASE, 'device = "cuda"'))
    code, _, err = run_cli(capsys, "plan", cuda_case, "--json")
    assert code == 2 and "run.device = 'cuda'" in err
    code, _, err = run_cli(capsys, "plan", cpu_case, "--device", "cuda", "--json")
    assert code == 2 and "run.device = 'cuda'" in err
    code, out, err = run_cli(capsys, "plan", cuda_case, "--device", "cpu", "--json")
    assert code == 0, err


def test_the_resume_line_keeps_the_device(tmp_path):
    from dem.cli.commands import resume_command
    from dem.cli.parser import build_parser

    case_dir = write_case(tmp_path / "case")
    args = build_parser().parse_args(["run", str(case_dir), "--device", "cuda", "--threads", "2"])
    line = resume_command(args, load_case(case_dir), tmp_path / "out")
    assert "--device cuda" in line and "--threads 2" in line and "--resume" in line
    args = build_parser().parse_args(["run", str(case_dir)])
    assert "--device" not in resume_command(args, load_case(case_dir), tmp_path / "out")


def test_a_checkpoint_from_before_the_key_resumes_on_the_cpu(tmp_path):
    """A record written before run.device existed ran on the CPU: no change on "cpu"."""
    from dem.run.summary import fingerprint, fingerprint_changes

    case = load_case(write_case(tmp_path))
    before = fingerprint(case)
    del before["run.device"]
    assert fingerprint_changes(before, fingerprint(case)) == []
    cuda = fingerprint(load_case(write_case(tmp_path), {"run.device": "cuda"}))
    assert fingerprint_changes(before, cuda) == ["run.device = 'cpu' (now 'cuda')"]


# --- the pre-flight check --------------------------------------------------------------------


def test_cpu_is_never_refused(tmp_path, no_gpu):
    check_device("cpu", load_case(CASES / "screw-trough"))


def test_spheres_and_clumps_pass_where_numba_cuda_works(tmp_path, gpu):
    case = load_case(write_case(tmp_path), {"run.device": "cuda"})
    check_device("cuda", case)
    from dem.scene.resolved import resolve

    check_device("cuda", resolve(case))  # a resolved scene as well as a case
    check_device("cuda", load_case(CASES / "screw-trough", {"run.device": "cuda"}))


@pytest.mark.parametrize("name, overrides, key", REFUSED)
def test_what_the_gpu_engine_lacks_is_refused_naming_its_key(
    capsys, tmp_path, gpu, name, overrides, key
):
    case = load_case(write_case(tmp_path / name), overrides | {"run.device": "cuda"})
    with pytest.raises(InputError) as info:
        check_device("cuda", case)
    err = info.value
    assert err.key == key and err.source == str(case.source)
    assert 'run.device = "cuda"' in err.allowed and 'run.device = "cpu"' in err.allowed
    check_device("cpu", case)


def test_a_mesh_trough_passes_the_check_and_its_replicas_are_one_batch(tmp_path, gpu):
    """The GPU engine has trough meshes, and so have its batches (replicas, sweeps); the
    feeder's finite section is refused for both."""
    from dem.run.batch import batchable

    case = load_case(write_case(tmp_path / "pan"), U_PAN | {"run.device": "cuda"})
    check_device("cuda", case)
    assert batchable(case) is None
    assert batchable(load_case(write_case(tmp_path / "flat"), {"run.device": "cuda"})) is None


@pytest.mark.integration
def test_dem_run_refuses_them_with_exit_2_naming_the_key(capsys, tmp_path, gpu):
    for name, overrides, key in REFUSED:
        case_dir = write_case(tmp_path / name)
        sets = [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]
        code, _, text = run_cli(capsys, "run", case_dir, "--out", tmp_path / "out", "--device",
                                "cuda", *sets)  # fmt: skip
        assert code == 2 and f"{key} = " in text and 'run.device = "cpu"' in text, name
        assert not (tmp_path / "out").exists()


@pytest.mark.integration
@pytest.mark.parametrize("installed", [True, False])
def test_no_gpu_exits_2_saying_what_is_missing(capsys, monkeypatch, tmp_path, no_gpu, installed):
    from dem.engine import device

    monkeypatch.setattr(device, "_numba_cuda_installed", lambda: installed)
    monkeypatch.setattr("numba.cuda.cuda_error", lambda: "CUDA driver library cannot be found.")
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", write_case(tmp_path / "case"), "--out", out,
                           "--device", "cuda")  # fmt: skip
    assert code == 2 and err.startswith("dem: error: run.device = 'cuda': ")
    assert "CUDA driver library cannot be found" in err
    assert ("pip install -e '.[cuda]'" in err) != installed
    assert "numba-cuda is not installed" in err if not installed else "no CUDA GPU" in err
    assert not out.exists()


def test_no_gpu_refuses_replicas_and_sweeps_at_the_door(tmp_path, no_gpu):
    from dem.run.replicas import run_replicas
    from dem.studies.sweep import plan_points

    case_dir = write_case(tmp_path / "case")
    case = load_case(case_dir, {"run.device": "cuda", "run.replicas": 2})
    with pytest.raises(InputError, match="run.device"):
        run_replicas(case, tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()
    with pytest.raises(InputError, match=r"run.device.*sweep point"):
        plan_points(case_dir, [("drive.angle", [20.0, 30.0])], tmp_path / "sweep", device="cuda")
    points = plan_points(case_dir, [("drive.angle", [20.0])], tmp_path / "sweep", device="cpu")
    assert points[0].overrides == {"drive.angle": 20.0}  # the folder names only the swept keys
    assert points[0].record["run.device"] == "cpu"
