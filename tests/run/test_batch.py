"""Replicas as one GPU job (dem.run.batch): the run's bookkeeping, with the batch on the CPU.

The batch's own stepping (:class:`dem.engine.gpu.replicas.GpuReplicas`: one scene of all the
replicas, scattered back into each replica's Simulation) is checked against single runs in
numba's CUDA simulator (tests/engine/test_gpu_replicas.py); a whole case there would take
hours. Here :class:`LockstepCpu` stands in for it, stepping each replica's own Simulation on the
CPU in lockstep, so that what :mod:`dem.run.batch` adds is tested on a real case: the fills and
seeds, the common settling, per-replica writers, checks, cycle records and summaries, the pool.
"""

import json

import numpy as np
import pytest
from small_case import SMALL_CASE, sigterm_at_check, write_case

from dem.run import batch, replicas
from dem.run.interrupts import RunInterrupted
from dem.run.output import CHECKPOINT
from dem.scene.case import load_case

TINY = SMALL_CASE.replace("count = 120", "count = 40").replace("cycles = 6", "cycles = 3")


class LockstepCpu:
    """The interface of GpuReplicas, each replica stepped on the CPU, all at one step."""

    instances = []

    def __init__(self, sims):
        self.sims = list(sims)
        for sim in self.sims:
            sim.device = "cpu"
        self.sim = self.sims[0]
        self.settled = None
        LockstepCpu.instances.append(self)

    def settle(self, progress=None):
        for sim in self.sims:
            sim.settle()
        last = max(sim.step_index for sim in self.sims)
        for sim in self.sims:  # every replica rests as long as the slowest
            sim.run(last - sim.step_index)
        self.settled = [sim.step_index for sim in self.sims]
        return last * self.sim.dt

    def start_drive(self):
        for sim in self.sims:
            sim.start_drive()

    def step_scheme(self):
        return {"kernel": "the CPU engine (LockstepCpu)"}

    def run(self, n_steps, stop=None):
        done = self.sims[0].run(n_steps, stop=stop)  # stopped early by a signal, as the batch
        for sim in self.sims[1:]:
            assert sim.run(done) == done
        return done


@pytest.fixture
def cpu_batch(monkeypatch):
    monkeypatch.setattr("numba.cuda.is_available", lambda: True)  # check_device lets cuda pass
    monkeypatch.setattr(batch, "GpuReplicas", LockstepCpu)
    LockstepCpu.instances.clear()


def test_cuda_cases_are_batched(tmp_path):
    case = load_case(write_case(tmp_path), {"run.device": "cuda"})
    assert batch.batchable(case) is None
    assert "CPU" in batch.batchable(load_case(write_case(tmp_path)))
    from pathlib import Path

    screws = Path(__file__).resolve().parents[2] / "cases" / "screw-trough"
    assert batch.batchable(load_case(screws, {"run.device": "cuda"})) is None


@pytest.mark.integration
def test_a_cuda_replica_run_is_one_batch_with_each_replicas_own_outputs(
    cpu_batch, tmp_path, capsys
):
    case = load_case(write_case(tmp_path / "case", TINY),
                     {"run.replicas": 2, "run.device": "cuda"})  # fmt: skip
    out = tmp_path / "out"
    pooled = replicas.run_replicas(case, out, progress=True)
    assert "one GPU batch" in capsys.readouterr().err
    (stepper,) = LockstepCpu.instances
    assert len(set(stepper.settled)) == 1  # one settling time for all
    own = [json.loads((out / "replicas" / str(k) / "summary.json").read_text()) for k in (0, 1)]
    assert [o["seed"] for o in own] == [3, 4]
    assert own[0]["mean_velocity"] != own[1]["mean_velocity"]  # two fills
    for o in own:
        assert o["gpu_batch"]["replicas"] == 2 and o["gpu_batch"]["spheres"] == 40
        assert o["gpu_batch"]["step"] == {"kernel": "the CPU engine (LockstepCpu)"}
        assert len(o["per_cycle_velocity"]) == 3
        assert np.all(np.isfinite(o["per_cycle_velocity"]))
        assert o["settle_time_s"] == own[0]["settle_time_s"]
    assert [r["mean_velocity"] for r in pooled["per_replica"]] == [o["mean_velocity"] for o in own]
    assert json.loads((out / "summary.json").read_text())["replicas"] == 2
    # replica 0 writes frames and results.h5 in the folder itself, the others their summary
    assert (out / "results.h5").is_file() and (out / "particles.pvd").is_file()
    assert not (out / CHECKPOINT).exists()
    assert not (out / "replicas" / "1" / "results.h5").exists()
    assert not (out / "replicas" / "1" / "frames").exists()


@pytest.mark.integration
def test_a_signal_checkpoints_every_unfinished_replica(cpu_batch, tmp_path, monkeypatch):
    """SIGTERM in the driven cycles: the batch stops after its chunk, every replica writes its
    checkpoint (what ``--resume`` continues, replica by replica) and no summary."""
    case = load_case(write_case(tmp_path / "case", TINY),
                     {"run.replicas": 2, "run.device": "cuda"})  # fmt: skip
    out = tmp_path / "out"
    sigterm_at_check(monkeypatch, 3)
    with pytest.raises(RunInterrupted):
        replicas.run_replicas(case, out, progress=False)
    monkeypatch.undo()
    for run_dir in (out, out / "replicas" / "1"):
        assert (run_dir / CHECKPOINT).is_file()
        assert not (run_dir / "summary.json").exists()


@pytest.mark.integration
def test_a_cuda_sweep_of_the_drive_is_one_batch(cpu_batch, tmp_path):
    """``dem sweep --device cuda`` over the drive angle and amplitude: one batch, each
    point its own drive, folder, summary and record; a rerun recomputes nothing."""
    from dem.studies.sweep import run_sweep

    case_dir = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    sets = [("drive.angle", [20.0, 40.0]), ("drive.amplitude", [0.0004, 0.0007])]
    done = run_sweep(case_dir, sets, out, device="cuda", progress=False)
    assert done["done"] == 4 and done["failed"] == {} and done["skipped"] == 0
    (stepper,) = LockstepCpu.instances
    assert len(stepper.sims) == 4
    angles = sorted({round(float(np.degrees(s.trough.angle)), 6) for s in stepper.sims})
    assert angles == [20.0, 40.0]
    summaries = [json.loads(p.read_text()) for p in sorted(out.glob("*/summary.json"))]
    assert len(summaries) == 4 and len({s["mean_velocity"] for s in summaries}) == 4
    assert len({s["timestep"] for s in summaries}) == 1  # the batch's one step, the smallest
    assert all(s["gpu_batch"]["replicas"] == 4 for s in summaries)
    assert len(list(out.glob("*/sweep_point.json"))) == 4
    again = run_sweep(case_dir, sets, out, device="cuda", progress=False)
    assert again["skipped"] == 4 and len(LockstepCpu.instances) == 1
