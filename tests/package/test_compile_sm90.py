"""The sm_90 compile check's reading of ptxas's report (validation/performance/compile_sm90.py).

CI runs the check itself in a venv with numba-cuda and CUDA 13's compiler wheels (.ci/run); this
test keeps its verdict honest without them: a spill or a failed assembly must fail the check.
"""

import importlib.util
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "validation" / "performance" / "compile_sm90.py"


def _module():
    spec = importlib.util.spec_from_file_location("compile_sm90", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


CLEAN = """ptxas info    : Compiling entry function 'step_kernel' for 'sm_90'
ptxas info    : Function properties for step_kernel
    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
ptxas info    : Used 136 registers, used 0 barriers"""


def test_a_clean_report_passes_and_names_the_registers():
    verdict, failed = _module().read_report(CLEAN, 0)
    assert verdict == "136 registers, no spills" and not failed


def test_a_spill_fails():
    spilled = CLEAN.replace("0 bytes spill stores", "48 bytes spill stores")
    verdict, failed = _module().read_report(spilled, 0)
    assert failed and "SPILLS (48 bytes)" in verdict


def test_a_failed_assembly_fails():
    verdict, failed = _module().read_report("ptxas fatal   : Ptx assembly aborted", 255)
    assert failed and verdict == "ptxas FAILED"
