"""Bulk answers that hold: error-bar coverage, and the bed's velocity converged in stiffness.

Regenerates the CSV files, provenance.json and figures of this folder (README.md shows them).
Runs go to scratch/ (ignored by git); a rerun reuses finished replicas (``--resume``).

    .venv/bin/python validation/bulk-convergence/run.py coverage     # 60 small beds, ~12 min
    .venv/bin/python validation/bulk-convergence/run.py persistence  # 6 fills x 200 cycles
    .venv/bin/python validation/bulk-convergence/run.py stiffness sphere-bed     # ~20 min
    .venv/bin/python validation/bulk-convergence/run.py stiffness screw-trough   # ~20 min
    .venv/bin/python validation/bulk-convergence/run.py timestep sphere-bed      # dt check
    .venv/bin/python validation/bulk-convergence/run.py section screw-trough     # 2x section
    .venv/bin/python validation/bulk-convergence/run.py fills screw-trough       # 5 more fills
    .venv/bin/python validation/bulk-convergence/run.py figures

Everything goes through the public API a user has: ``dem.scene.case.load_case`` with overrides, and
``dem.run.replicas.run_replicas`` (``dem run --replicas N``), whose pooled summaries are read back.

- coverage: a small sphere bed (cases/sphere-bed cut to 300 spheres in a 20 mm section, the
  same depth) run from 60 fills. Each run's own 95 % interval (1.96 times its autocorrelated
  standard error), and the pooled interval of each of 20 disjoint triples (``measure.pooled``),
  are checked against the long-run mean: the pooled mean of every *other* run (leave the
  run or the triple out), so no interval is judged against itself.
- stiffness: the shipped bed (cases/sphere-bed, cases/screw-trough) at Young's moduli from 5e7 to
  5e10 Pa, 3 replicas each, the time step a fixed fraction (DT_FRACTION) of the stability limit
  at every E, so that only the stiffness changes; the rigid limit extrapolated by a fit
  v(E) = v_inf + b E^(-2/3) (the bed's compliance scaling) on the stiff points, weighted by the
  pooled errors, checked on the stiffest point held out.
- timestep: the same bed at two stiffnesses with the step halved, to show dt is converged.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from dem import provenance
from dem.physics import measure
from dem.run.replicas import run_replicas
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import replicas  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SCRATCH = HERE / "scratch"
MODULI = [5e7, 2e8, 5e8, 2e9, 5e9, 2e10, 5e10]
DT_FRACTION = 0.5  #: time step over the stability limit in the stiffness sweep
REPLICAS = 3
CYCLES = 20
COVERAGE_RUNS = 60
#: The small bed of the coverage check: cases/sphere-bed at a fifth of its length and count.
COVERAGE_CASE = {
    "trough.length": 0.02,
    "particles.count": 300,
    "run.cycles": CYCLES,
    "contact.youngs_modulus": 5.0e7,
    "run.timestep": "auto",
}  # as measured


def _run(case, out: Path) -> dict:
    """A replicated run into ``out`` (resumed if it was started), its pooled summary."""
    resume = (out / "summary.json").is_file() or (out / "replicas").is_dir()
    return run_replicas(case, out, threads=2, progress=True, resume=resume, frames=False)


def _own(out: Path, k: int) -> dict:
    return json.loads((out / "replicas" / str(k) / "summary.json").read_text())


def coverage() -> None:
    """Coverage of one run's interval and of pooled triples against the long-run mean."""
    case = load_case(ROOT / "cases" / "sphere-bed",
                     {**COVERAGE_CASE, "run.replicas": COVERAGE_RUNS})  # fmt: skip
    out = SCRATCH / "coverage"
    _run(case, out)
    runs = [_own(out, k) for k in range(COVERAGE_RUNS)]
    m = np.array([r["mean_velocity"] for r in runs])
    s = np.array([r["mean_velocity_stderr"] for r in runs])
    rows, single_hits, triple_hits = [], 0, 0
    for i in range(COVERAGE_RUNS):
        others = np.arange(COVERAGE_RUNS) != i
        truth = measure.pooled(m[others], s[others]).mean
        hit = abs(m[i] - truth) <= 1.959963984540054 * s[i]
        single_hits += hit
        rows.append({"kind": "one run", "index": i, "seed": runs[i]["seed"], "mean_m_s": m[i],
                     "half_width_m_s": 1.959963984540054 * s[i], "long_run_mean_m_s": truth,
                     "covers": int(hit)})  # fmt: skip
    triples = COVERAGE_RUNS // 3
    for g in range(triples):
        members = np.arange(3 * g, 3 * g + 3)
        others = np.ones(COVERAGE_RUNS, bool)
        others[members] = False
        truth = measure.pooled(m[others], s[others]).mean
        p = measure.pooled(m[members], s[members])
        hit = abs(p.mean - truth) <= p.half_width
        triple_hits += hit
        rows.append({"kind": "3 replicas", "index": g, "seed": runs[3 * g]["seed"],
                     "mean_m_s": p.mean, "half_width_m_s": p.half_width,
                     "long_run_mean_m_s": truth, "covers": int(hit)})  # fmt: skip
    _write_csv(HERE / "coverage.csv", rows)
    grand = measure.pooled(m, s)
    result = {
        "runs": COVERAGE_RUNS, "cycles": CYCLES, "case": "cases/sphere-bed", **{
            f"override_{k}": v for k, v in COVERAGE_CASE.items()},
        "one_run_coverage": single_hits / COVERAGE_RUNS,
        "three_replica_coverage": triple_hits / triples, "triples": triples,
        "long_run_mean_m_s": grand.mean, "long_run_mean_stderr_m_s": grand.stderr,
        "fill_to_fill_spread_m_s": grand.between,
        "median_one_run_stderr_m_s": float(np.median(s)),
        "spread_of_one_run_means_m_s": float(np.std(m, ddof=1)),
    }  # fmt: skip
    _record("coverage", result)
    print(json.dumps(result, indent=1))


PERSISTENCE_RUNS, PERSISTENCE_CYCLES = 6, 200


def persistence() -> None:
    """Why one run under-covers: do fills differ for good, or do short runs err by more?

    Six fills of the coverage bed run 200 measured cycles each. If the fills differed only by
    slow noise, their 200-cycle means would agree within their own errors and the 20-cycle
    blocks of one long run would scatter as much as 20-cycle runs of different fills do; if
    each fill keeps its own velocity, the 200-cycle means stay apart.
    """
    overrides = {**COVERAGE_CASE, "run.cycles": PERSISTENCE_CYCLES,
                 "run.replicas": PERSISTENCE_RUNS}  # fmt: skip
    case = load_case(ROOT / "cases" / "sphere-bed", overrides)
    out = SCRATCH / "persistence"
    _run(case, out)
    runs = [_own(out, k) for k in range(PERSISTENCE_RUNS)]
    long_means = np.array([r["mean_velocity"] for r in runs])
    long_errors = np.array([r["mean_velocity_stderr"] for r in runs])
    blocks = np.array([[np.mean(r["per_cycle_velocity"][i : i + CYCLES])
                        for i in range(0, PERSISTENCE_CYCLES, CYCLES)] for r in runs])  # fmt: skip
    within = float(np.mean(np.std(blocks, axis=1, ddof=1)))
    across = float(np.mean(np.std(blocks, axis=0, ddof=1)))
    p = measure.pooled(long_means, long_errors)
    rows = [{"seed": r["seed"], "mean_200_m_s": m, "stderr_200_m_s": e,
             "blocks_of_20_m_s": " ".join(f"{b:.5g}" for b in bl)}
            for r, m, e, bl in zip(runs, long_means, long_errors, blocks, strict=True)]  # fmt: skip
    _write_csv(HERE / "persistence.csv", rows)
    result = {
        "fills": PERSISTENCE_RUNS, "cycles": PERSISTENCE_CYCLES,
        "spread_of_200_cycle_means_m_s": float(np.std(long_means, ddof=1)),
        "median_200_cycle_stderr_m_s": float(np.median(long_errors)),
        "fill_to_fill_spread_200_m_s": p.between,
        "block_spread_within_a_fill_m_s": within,
        "block_spread_across_fills_m_s": across,
    }  # fmt: skip
    _record("persistence", result)
    print(json.dumps(result, indent=1))


def _bed_case(bed: str, youngs: float, fraction: float = DT_FRACTION):
    """The shipped bed at Young's modulus ``youngs``, dt = ``fraction`` of its stability limit."""
    base = {"contact.youngs_modulus": youngs, "run.cycles": CYCLES, "run.replicas": REPLICAS}
    probe = load_case(ROOT / "cases" / bed, {**base, "run.timestep": "auto"})
    dt = fraction * timestep_for(probe).limit
    return load_case(ROOT / "cases" / bed, {**base, "run.timestep": float(f"{dt:.4g}")})


def stiffness(bed: str, moduli: list[float]) -> None:
    """The pooled bed velocity at each Young's modulus; the rigid-limit fit."""
    rows = []
    for youngs in moduli:
        case = _bed_case(bed, youngs)
        summary = _run(case, SCRATCH / f"{bed}_E{youngs:.0e}")
        rows.append(_row(bed, youngs, DT_FRACTION, case, summary))
        print(f"{bed} E = {youngs:.0e}: v = {summary['mean_velocity']:.5f} +- "
              f"{summary['mean_velocity_stderr']:.5f} m/s", flush=True)  # fmt: skip
    path = HERE / f"stiffness_{bed}.csv"
    old = _read_csv(path) if path.is_file() else []
    keep = [r for r in old if float(r["youngs_modulus_pa"]) not in moduli]
    rows = sorted(keep + rows, key=lambda r: float(r["youngs_modulus_pa"]))
    _write_csv(path, rows)
    fit = rigid_limit(rows, bed)
    _record(f"stiffness_{bed}", {"rows": len(rows), "dt_fraction": DT_FRACTION, **fit})
    print(json.dumps(fit, indent=1))


def timestep(bed: str, moduli: list[float]) -> None:
    """The bed with dt halved (DT_FRACTION / 2) at the given moduli."""
    rows = []
    for youngs in moduli:
        case = _bed_case(bed, youngs, DT_FRACTION / 2)
        summary = _run(case, SCRATCH / f"{bed}_E{youngs:.0e}_halfdt")
        rows.append(_row(bed, youngs, DT_FRACTION / 2, case, summary))
    path = HERE / f"timestep_{bed}.csv"
    _write_csv(path, rows)
    _record(f"timestep_{bed}", {"rows": rows})


def section(bed: str, moduli: list[float], factors: list[float]) -> None:
    """The bed in a section ``factor`` times longer (and as many times the grains: the same
    depth), at the given moduli, against the shipped section's point of the stiffness sweep."""
    base = {float(r["youngs_modulus_pa"]): r for r in _read_csv(HERE / f"stiffness_{bed}.csv")}
    path = HERE / f"section_{bed}.csv"
    rows = _read_csv(path) if path.is_file() else []
    for youngs in moduli:
        for factor in factors:
            shipped = _bed_case(bed, youngs)
            over = {"trough.length": shipped.trough.length * factor,
                    "particles.count": int(round(shipped.particles.count * factor))}  # fmt: skip
            keys = {"contact.youngs_modulus": youngs, "run.cycles": CYCLES,
                    "run.replicas": REPLICAS, "run.timestep": shipped.run.timestep}  # fmt: skip
            case = load_case(ROOT / "cases" / bed, keys | over)
            summary = _run(case, SCRATCH / f"{bed}_E{youngs:.0e}_section{factor:g}")
            row = _row(bed, youngs, DT_FRACTION, case, summary)
            ref = base[youngs]
            v0, e0 = float(ref["mean_velocity_m_s"]), float(ref["stderr_m_s"])
            v, e = row["mean_velocity_m_s"], row["stderr_m_s"]
            row |= {"section_factor": factor, "trough_length_m": case.trough.length,
                    "grains": case.particles.count, "shipped_section_m_s": v0,
                    "difference": v / v0 - 1.0,
                    "difference_stderr": math.hypot(e / v0, e0 * v / v0**2)}  # fmt: skip
            rows = [r for r in rows if not (float(r["youngs_modulus_pa"]) == youngs
                                             and float(r["section_factor"]) == factor)]  # fmt: skip
            rows.append(row)
            print(f"{bed} E = {youngs:.0e}, section x{factor:g}: v = "
                  f"{row['mean_velocity_m_s']:.5f} +- {row['stderr_m_s']:.5f} m/s, "
                  f"{100 * row['difference']:+.2f} +- {100 * row['difference_stderr']:.2f} % "
                  "against the shipped section", flush=True)  # fmt: skip
    _write_csv(path, rows)
    _record(f"section_{bed}", {"rows": rows})


def fills(bed: str, moduli: list[float], seed: int, replicas: int) -> None:
    """More fills at the given moduli (seeds ``seed`` .. ``seed + replicas - 1``), pooled with
    the stiffness sweep's fills of the same E and step: the mean over all fills with the
    standard error of their scatter (each fill's own noise is inside that scatter)."""
    base = {float(r["youngs_modulus_pa"]): r for r in _read_csv(HERE / f"stiffness_{bed}.csv")}
    path = HERE / f"fills_{bed}.csv"
    rows = _read_csv(path) if path.is_file() else []
    for youngs in moduli:
        case = _bed_case(bed, youngs)
        case = load_case(case.source, {**_bed_keys(youngs, case), "run.seed": seed,
                                       "run.replicas": replicas})  # fmt: skip
        summary = _run(case, SCRATCH / f"{bed}_E{youngs:.0e}_seed{seed}x{replicas}")
        old = [float(v) for v in base[youngs]["per_replica_m_s"].split()]
        new = [r["mean_velocity"] for r in summary["per_replica"]]
        values = np.array(old + new)
        row = {
            "bed": bed, "youngs_modulus_pa": youngs, "dt_fraction_of_limit": DT_FRACTION,
            "fills": len(values), "seeds": f"1-{len(old)}, {seed}-{seed + replicas - 1}",
            "mean_velocity_m_s": float(values.mean()),
            "stderr_m_s": replicas.replica_stderr(values),
            "fill_to_fill_sd_m_s": float(values.std(ddof=1)),
            "per_fill_m_s": " ".join(f"{v:.6g}" for v in values),
            "cpu_s_new_fills": summary["wall_time_s"],
        }  # fmt: skip
        rows = [r for r in rows if float(r["youngs_modulus_pa"]) != youngs] + [row]
        print(f"{bed} E = {youngs:.0e}: {len(values)} fills, v = {row['mean_velocity_m_s']:.5f}"
              f" +- {row['stderr_m_s']:.5f} m/s (sd {row['fill_to_fill_sd_m_s']:.5f})",
              flush=True)  # fmt: skip
    rows.sort(key=lambda r: float(r["youngs_modulus_pa"]))
    _write_csv(path, rows)
    _record(f"fills_{bed}", {"rows": rows})


def _bed_keys(youngs: float, case) -> dict:
    """The overrides of :func:`_bed_case` (its step included), to add more to them."""
    return {"contact.youngs_modulus": youngs, "run.cycles": CYCLES,
            "run.timestep": case.run.timestep}  # fmt: skip


#: Samples of the bed's vertical centre of mass per drive period, and the periods sampled.
SPECTRUM_SAMPLES, SPECTRUM_CYCLES, SPECTRUM_SETTLE = 64, 20, 10


def spectrum(bed: str, moduli: list[float]) -> None:
    """The bed's vertical centre of mass against E: its power at each drive harmonic.

    One fill per E (seed 1, dt as the stiffness sweep), settled, driven SPECTRUM_SETTLE cycles,
    then sampled SPECTRUM_SAMPLES times a period over SPECTRUM_CYCLES periods; the Fourier
    amplitude of z_com at harmonics 1-12 of the drive, beside the bed's lowest vertical mode
    (:func:`dem.run.stiffness.bed_mode`) in drive harmonics. A bed mode near harmonic k amplifies
    harmonic k: where the velocity's band over E lines up with that, the band is the resonance.
    """
    from dem.engine import setup
    from dem.run import stiffness
    from dem.scene.resolved import resolve

    rows = []
    for youngs in moduli:
        case = _bed_case(bed, youngs)  # seed 1; setup fills one bed
        mode = stiffness.bed_mode(resolve(case))
        sim = setup.from_case(case)
        sim.settle()
        sim.start_drive()
        period = sim.trough.period
        sim.run(round(SPECTRUM_SETTLE * period / sim.dt))
        every = max(1, round(period / sim.dt / SPECTRUM_SAMPLES))
        n = round(SPECTRUM_CYCLES * period / (every * sim.dt))
        z = np.empty(n)
        for k in range(n):
            sim.run(every)
            if sim.bodies is not None:
                b = sim.bodies
                z[k] = np.sum(b.mass * b.x[:, 2]) / np.sum(b.mass)
            else:
                sp = sim.spheres
                z[k] = np.sum(sp.mass * sp.x[:, 2]) / np.sum(sp.mass)
        amp = np.abs(np.fft.rfft(z - z.mean())) * 2.0 / n
        freq = np.fft.rfftfreq(n, every * sim.dt) * period  # in drive harmonics
        row = {"bed": bed, "youngs_modulus_pa": youngs,
               "bed_mode_harmonic": mode.omega_bed / case.drive.omega,
               "z_rms_m": float(np.std(z))}  # fmt: skip
        for h in range(1, 13):
            row[f"amplitude_h{h}_m"] = float(amp[int(np.argmin(np.abs(freq - h)))])
        rows.append(row)
        print(f"{bed} E = {youngs:.0e}: bed mode at {row['bed_mode_harmonic']:.2f} f, "
              + ", ".join(f"h{h} {row[f'amplitude_h{h}_m']:.2e}" for h in range(1, 9)),
              flush=True)  # fmt: skip
    _write_csv(HERE / f"spectrum_{bed}.csv", rows)
    _record(f"spectrum_{bed}", {"rows": len(rows), "samples_per_period": SPECTRUM_SAMPLES,
                                "cycles": SPECTRUM_CYCLES})  # fmt: skip


#: In-plane sampling: samples per drive period, periods sampled, driven periods before.
INPLANE_SAMPLES, INPLANE_CYCLES, INPLANE_SETTLE = 32, 30, 10
#: A screw touches the floor when its lowest member's gap is below this, m (Hertz overlaps are
#: negative gaps; 10 um is under a thousandth of a screw's length).
FLOOR_GAP = 1.0e-5


def inplane(bed: str, moduli: list[float], seeds: list[int]) -> None:
    """The screws' in-plane state against E: what the band of soft contacts changes.

    Per E and fill (dt as the stiffness sweep), settled, driven INPLANE_SETTLE periods, then
    sampled INPLANE_SAMPLES times a period over INPLANE_CYCLES periods: the bed velocity v_x;
    the alignment S = <cos 2 theta> of the screws' long axes (smallest principal moment)
    projected on the floor, theta from the conveying direction x (S = 1: all along the flow,
    -1: all across, 0: isotropic); the tilt <|a_z|> out of the floor plane; the fraction of
    screws touching the floor; v_x of the lower and upper half of the bed (by height); and,
    per period, the correlation of v_x with S. Only clump beds have axes. ``inplane_phase_BED.csv``
    holds the same quantities binned by the drive's phase (32 bins, from the drive time), the
    mean over the cycles and fills of each E, with the bed's mean x-acceleration from contacts
    (the walls': grain-grain forces cancel): where in the cycle momentum is gained and lost.
    """
    from dem.engine import setup
    from dem.kernels.rigid import quat_to_matrix

    rows, phase_rows = [], []
    for youngs in moduli:
        by_phase = []
        for seed in seeds:
            case = _bed_case(bed, youngs)
            case = load_case(case.source, {**_bed_keys(youngs, case), "run.seed": seed})
            sim = setup.from_case(case)
            sim.settle()
            sim.start_drive()
            b, sp = sim.bodies, sim.spheres
            long_axis = np.argmin(b.moments[0])
            period = sim.trough.period
            sim.run(round(INPLANE_SETTLE * period / sim.dt))
            # two steps short of a bin: the samples' phase drifts by 2 x samples steps a period,
            # so each bin is sampled across its width, not at one sub-phase (which made the
            # beds' profiles look shifted against each other by up to a bin)
            every = max(1, int(period / sim.dt / INPLANE_SAMPLES) - 2)
            per = INPLANE_SAMPLES
            n = INPLANE_CYCLES * per
            t0 = time.perf_counter()
            keys = ("v", "s", "tilt", "touch", "v_low", "v_high", "z", "a")
            rec = {k: np.empty(n) for k in keys}
            total = float(b.mass.sum())
            phase = np.empty(n, dtype=np.int64)
            for k in range(n):
                sim.run(every)
                phase[k] = int(sim.drive_time / period % 1.0 * per) % per
                axes = np.array([quat_to_matrix(q)[:, long_axis] for q in b.q])
                flat = axes[:, 0] ** 2 + axes[:, 1] ** 2
                cos2 = (axes[:, 0] ** 2 - axes[:, 1] ** 2) / np.maximum(flat, 1e-30)
                gap = sp.x[:, 2] - sp.radius
                lowest = np.full(len(b.mass), np.inf)
                np.minimum.at(lowest, b.body_of, gap)
                z = b.x[:, 2]
                low = z <= np.median(z)
                rec["v"][k] = b.v[:, 0].mean()
                rec["s"][k] = cos2.mean()
                rec["tilt"][k] = np.abs(axes[:, 2]).mean()
                rec["touch"][k] = np.mean(lowest < FLOOR_GAP)
                rec["v_low"][k] = b.v[low, 0].mean()
                rec["v_high"][k] = b.v[~low, 0].mean()
                rec["z"][k] = z.mean()
                body = sim.gravity[0] + sim.trough.frame_acceleration(sim.drive_time)[0]
                rec["a"][k] = float(np.sum(b.force[:, 0] - b.mass * body)) / total
            by_phase.append({k: np.bincount(phase, v, per) / np.maximum(np.bincount(phase, None,
                             per), 1) for k, v in rec.items()})  # fmt: skip
            cyc = {k: v.reshape(INPLANE_CYCLES, per).mean(axis=1) for k, v in rec.items()}
            row = {"bed": bed, "youngs_modulus_pa": youngs, "seed": seed,
                   "velocity_m_s": float(cyc["v"].mean()),
                   "velocity_cycle_sd_m_s": float(cyc["v"].std(ddof=1)),
                   "alignment_S": float(cyc["s"].mean()),
                   "alignment_cycle_sd": float(cyc["s"].std(ddof=1)),
                   "tilt_abs_az": float(cyc["tilt"].mean()),
                   "floor_contact_fraction": float(cyc["touch"].mean()),
                   "velocity_lower_half_m_s": float(cyc["v_low"].mean()),
                   "velocity_upper_half_m_s": float(cyc["v_high"].mean()),
                   "corr_v_S_per_cycle": float(np.corrcoef(cyc["v"], cyc["s"])[0, 1]),
                   "cpu_s": time.perf_counter() - t0}  # fmt: skip
            rows.append(row)
            print(f"{bed} E = {youngs:.0e} seed {seed}: v {row['velocity_m_s']:.4f} m/s, "
                  f"S {row['alignment_S']:+.3f}, tilt {row['tilt_abs_az']:.3f}, floor "
                  f"{row['floor_contact_fraction']:.3f}, low/high "
                  f"{row['velocity_lower_half_m_s']:.4f}/{row['velocity_upper_half_m_s']:.4f}, "
                  f"corr(v, S) {row['corr_v_S_per_cycle']:+.2f}", flush=True)  # fmt: skip
        for j in range(INPLANE_SAMPLES):
            mean = {k: float(np.mean([f[k][j] for f in by_phase])) for k in by_phase[0]}
            phase_rows.append({"bed": bed, "youngs_modulus_pa": youngs, "phase_bin": j,
                               "phase_deg": 360.0 * (j + 0.5) / INPLANE_SAMPLES,
                               "velocity_m_s": mean["v"], "floor_contact_fraction": mean["touch"],
                               "height_m": mean["z"], "alignment_S": mean["s"],
                               "velocity_lower_half_m_s": mean["v_low"],
                               "contact_accel_x_m_s2": mean["a"]})  # fmt: skip
    _write_csv(HERE / f"inplane_{bed}.csv", rows)
    _write_csv(HERE / f"inplane_phase_{bed}.csv", phase_rows)
    _record(f"inplane_{bed}", {"rows": len(rows), "samples_per_period": INPLANE_SAMPLES,
                               "cycles": INPLANE_CYCLES, "settle_cycles": INPLANE_SETTLE,
                               "floor_gap_m": FLOOR_GAP})  # fmt: skip


#: The mesh pans as shipped, and 10x stiffer at the same fraction of the stability limit.
PAN_STIFF = 2.0e10


def pans() -> None:
    """cases/u-trough and cases/v-trough as shipped (2e9 Pa, dt 4e-6 s) against the same pan at
    2e10 Pa, 3 fills each: are the pans, which the sweep did not cover, converged where the
    flat screw bed is? The stiff runs take dt at the shipped step's fraction of their limit."""
    rows = []
    for name in ("u-trough", "v-trough"):
        shipped = load_case(ROOT / "cases" / name)
        fraction = shipped.run.timestep / timestep_for(shipped).limit
        probe = load_case(ROOT / "cases" / name, {"contact.youngs_modulus": PAN_STIFF,
                                                  "run.timestep": "auto"})  # fmt: skip
        dt = float(f"{fraction * timestep_for(probe).limit:.3g}")
        found = {}
        for youngs, keys in ((shipped.contact.youngs_modulus, {}),
                             (PAN_STIFF, {"contact.youngs_modulus": PAN_STIFF,
                                          "run.timestep": dt})):  # fmt: skip
            case = load_case(ROOT / "cases" / name, {**keys, "run.replicas": REPLICAS})
            s = _run(case, SCRATCH / f"pan_{name}_E{youngs:.0e}")
            found[youngs] = s
            rows.append({"case": name, "youngs_modulus_pa": youngs,
                         "timestep_s": case.run.timestep, "replicas": s["replicas"],
                         "mean_velocity_m_s": s["mean_velocity"],
                         "stderr_m_s": s["mean_velocity_stderr"],
                         "mean_velocity_norm": s["mean_velocity_norm"],
                         "per_replica_m_s": " ".join(f"{r['mean_velocity']:.6g}"
                                                     for r in s["per_replica"]),
                         "cpu_s": s["wall_time_s"]})  # fmt: skip
        a, b = found[shipped.contact.youngs_modulus], found[PAN_STIFF]
        diff = a["mean_velocity"] / b["mean_velocity"] - 1.0
        err = math.hypot(
            a["mean_velocity_stderr"] / b["mean_velocity"],
            b["mean_velocity_stderr"] * a["mean_velocity"] / b["mean_velocity"] ** 2,
        )
        rows[-1]["shipped_vs_stiff"] = diff
        rows[-1]["shipped_vs_stiff_stderr"] = err
        print(f"{name}: shipped {a['mean_velocity']:.5f} +- {a['mean_velocity_stderr']:.5f}, "
              f"2e10 Pa {b['mean_velocity']:.5f} +- {b['mean_velocity_stderr']:.5f} m/s: "
              f"{100 * diff:+.1f} +- {100 * err:.1f} %", flush=True)  # fmt: skip
    _write_csv(HERE / "pans.csv", rows)
    _record("pans", {"rows": rows, "stiff_youngs_pa": PAN_STIFF})


def _row(bed, youngs, fraction, case, s) -> dict:
    return {
        "bed": bed, "youngs_modulus_pa": youngs, "dt_fraction_of_limit": fraction,
        "timestep_s": case.run.timestep, "replicas": s["replicas"],
        "mean_velocity_m_s": s["mean_velocity"], "stderr_m_s": s["mean_velocity_stderr"],
        "ci95_m_s": s["mean_velocity_ci95"], "mean_velocity_norm": s["mean_velocity_norm"],
        "fill_to_fill_spread_m_s": s["replica_spread"],
        "per_replica_m_s": " ".join(f"{r['mean_velocity']:.6g}" for r in s["per_replica"]),
        "settle_cycles": " ".join(str(r["settle_cycles"]) for r in s["per_replica"]),
        "cpu_s": s["wall_time_s"], "particle_steps_per_s": s["particle_steps_per_s"],
    }  # fmt: skip


#: Where the fit is rejected, the rigid limit is the mean of the points below this compliance
#: (where the sphere bed, whose fit holds, is within 1.5 % of its limit).
MEAN_COMPLIANCE = 0.01
#: A held-out point further than this many of its standard errors from the fit rejects the fit.
HELD_OUT_Z = 3.0
#: Points of the rigid-limit fit: where the bed's compliance (omega / omega_bed)^2 is below this
#: (:func:`dem.run.stiffness.bed_mode`), the response is linear in it.
FIT_COMPLIANCE = 0.025


def rigid_limit(rows: list[dict], bed: str) -> dict:
    """v(E) = v_inf + b E^(-2/3) by weighted least squares on the stiff points; held-out check.

    The exponent is the compliance's: (omega / omega_bed)^2 ~ 1 / S ~ E^(-2/3) (Hertz at a fixed
    load, :mod:`dem.run.stiffness`), fitted where c < FIT_COMPLIANCE. Checked on a held-out point:
    fitted without the stiffest point, which it must predict. v_inf's error combines the fit's
    statistical error with half the spread of v_inf over the exponents 1/3 and 1 (the form).
    """
    from dem.run import stiffness
    from dem.scene.resolved import resolve

    e = np.array([float(r["youngs_modulus_pa"]) for r in rows])
    v = np.array([float(r["mean_velocity_m_s"]) for r in rows])
    s = np.array([float(r["stderr_m_s"]) for r in rows])
    c = np.array([
        stiffness.bed_mode(resolve(load_case(ROOT / "cases" / bed, {
            "contact.youngs_modulus": x, "run.timestep": "auto"}))).compliance for x in e
    ])  # fmt: skip
    use = c < FIT_COMPLIANCE
    if use.sum() < 3:
        return {"fit": "too few stiff points"}

    def fit(mask, p):
        x = e[mask] ** (-p)
        a = np.column_stack([np.ones_like(x), x]) / s[mask, None]
        coef, *_ = np.linalg.lstsq(a, v[mask] / s[mask], rcond=None)
        chi2 = float(np.sum((a @ coef - v[mask] / s[mask]) ** 2))
        return coef, math.sqrt(float(np.linalg.inv(a.T @ a)[0, 0])), chi2

    (v_inf, b), err, chi2 = fit(use, 2.0 / 3.0)
    form = [fit(use, p)[0][0] for p in (1.0 / 3.0, 1.0)]
    held = int(np.argmax(e))
    train = use.copy()
    train[held] = False
    (v0, b0), _, _ = fit(train, 2.0 / 3.0)
    predicted = v0 + b0 * e[held] ** (-2.0 / 3.0)
    total = math.hypot(err, (max(form) - min(form)) / 2.0)
    z_held = float((v[held] - predicted) / s[held])
    if abs(z_held) > HELD_OUT_Z:
        # the form fails on the point it did not see: the stiff points scatter beyond their
        # error bars (few fills against a large fill-to-fill spread), so no trend in E is
        # resolved there; their plain mean, with the error of their scatter, is the estimate
        flat = c < MEAN_COMPLIANCE
        stiff = v[flat]
        return {
            "form": f"mean of the points with (omega / omega_bed)^2 < {MEAN_COMPLIANCE}: the fit "
                    f"v_inf + b E^(-2/3) failed its held-out check (z = {z_held:.1f}, chi^2 "
                    f"{chi2:.1f} on {int(use.sum() - 2)} dof)",
            "fitted_youngs_pa": [float(x) for x in e[flat]],
            "held_out_youngs_pa": float(e[held]), "held_out_z": z_held,
            "rejected_fit_v_inf_m_s": float(v_inf),
            "v_inf_m_s": float(np.mean(stiff)),
            "v_inf_stderr_m_s": replicas.replica_stderr(stiff),
            "scatter_m_s": float(np.std(stiff, ddof=1)), "chi2": chi2,
            "dof": int(use.sum() - 2),
        }  # fmt: skip
    return {
        "form": "v(E) = v_inf + b E^(-2/3), weighted least squares on the points with "
                f"(omega / omega_bed)^2 < {FIT_COMPLIANCE}",
        "fitted_youngs_pa": [float(x) for x in e[use]],
        "held_out_youngs_pa": float(e[held]),
        "held_out_measured_m_s": float(v[held]), "held_out_stderr_m_s": float(s[held]),
        "held_out_predicted_m_s": float(predicted),
        "held_out_z": z_held,
        "v_inf_m_s": float(v_inf), "v_inf_stderr_m_s": float(total),
        "v_inf_stat_m_s": float(err), "v_inf_exponents_1_3_and_1_m_s": [float(x) for x in form],
        "p": 2.0 / 3.0, "c": float(b), "chi2": chi2, "dof": int(use.sum() - 2),
    }  # fmt: skip


def stiffness_rows(bed: str) -> list[dict]:
    """The stiffness sweep of ``bed``, each E pooled with the extra fills of ``run.py fills``
    where it has them (same E and step: the mean over all fills, the standard error of their
    scatter)."""
    rows = _read_csv(HERE / f"stiffness_{bed}.csv")
    path = HERE / f"fills_{bed}.csv"
    more = {float(r["youngs_modulus_pa"]): r for r in _read_csv(path)} if path.is_file() else {}
    for r in rows:
        r["cpu_s_per_fill"] = float(r["cpu_s"]) / int(r["replicas"])  # the sweep's own fills
        f = more.get(float(r["youngs_modulus_pa"]))
        if f is not None:
            r.update({"mean_velocity_m_s": f["mean_velocity_m_s"], "stderr_m_s": f["stderr_m_s"],
                      "replicas": f["fills"], "per_replica_m_s": f["per_fill_m_s"]})  # fmt: skip
    return rows


def refit() -> None:
    """The rigid-limit fit of every bed whose table is here, from the tables alone (each E
    pooled with its extra fills, :func:`stiffness_rows`)."""
    for bed in ("sphere-bed", "screw-trough"):
        path = HERE / f"stiffness_{bed}.csv"
        if path.is_file():
            rows = stiffness_rows(bed)
            fit = rigid_limit(rows, bed)
            _record(f"stiffness_{bed}", {"rows": len(rows), "dt_fraction": DT_FRACTION, **fit})
            print(bed, json.dumps(fit, indent=1))


def rule() -> None:
    """The stiffness rule dem warns by: compliance (omega / omega_bed)^2 against the error.

    Per bed and E: c from :func:`dem.run.stiffness.bed_mode`, the error v / v_inf - 1 against the
    fitted rigid limit. The limit is the largest c below which no measured point of either bed
    misses its rigid limit by more than 2 % beyond two of its standard errors (a 3-fill point
    of the screws scatters by 1-2 %); written to dem/data/stiffness_convergence.json.
    """
    from dem.run import stiffness
    from dem.scene.resolved import resolve

    record = _read_record()
    rows, limits = [], {}
    for bed in ("sphere-bed", "screw-trough"):
        fit = record.get(f"stiffness_{bed}", {})
        path = HERE / f"stiffness_{bed}.csv"
        if "v_inf_m_s" not in fit or not path.is_file():
            continue
        drive = load_case(ROOT / "cases" / bed).drive
        scale = drive.amplitude * drive.omega * math.cos(math.radians(drive.angle))
        limits[bed] = {
            "velocity_m_s": fit["v_inf_m_s"], "stderr_m_s": fit["v_inf_stderr_m_s"],
            "velocity_norm": fit["v_inf_m_s"] / scale,
            "stderr_norm": fit["v_inf_stderr_m_s"] / scale, "form": fit["form"],
        }  # fmt: skip
        for r in stiffness_rows(bed):
            youngs = float(r["youngs_modulus_pa"])
            scene = resolve(load_case(ROOT / "cases" / bed, {"contact.youngs_modulus": youngs,
                                                             "run.timestep": "auto"}))  # fmt: skip
            mode = stiffness.bed_mode(scene)
            error = float(r["mean_velocity_m_s"]) / fit["v_inf_m_s"] - 1.0
            rows.append({
                "bed": bed, "youngs_modulus_pa": youngs, "compliance": mode.compliance,
                "bed_mode_hz": mode.omega_bed / (2 * math.pi), "error_vs_rigid": error,
                "error_stderr": float(r["stderr_m_s"]) / fit["v_inf_m_s"],
                "fills": int(r["replicas"]), "cpu_s_per_fill": r["cpu_s_per_fill"],
            })  # fmt: skip
    if not rows:
        return
    # beyond 2 % by more than two of its standard errors: measured to miss, not noise
    bad = [r["compliance"] for r in rows
           if abs(r["error_vs_rigid"]) - 2.0 * r["error_stderr"] > 0.02]  # fmt: skip
    limit = min(bad) if bad else max(r["compliance"] for r in rows)
    good = [r for r in rows if r["compliance"] < limit]
    limit = max(r["compliance"] for r in good) if good else limit
    data = {
        "compliance_limit": limit,
        "evidence": ", ".join(
            f"{r['bed']} at E = {r['youngs_modulus_pa']:.0e} Pa: c = {r['compliance']:.3f}, "
            f"{100 * r['error_vs_rigid']:+.1f} %"
            for r in sorted(
                (r for r in rows if abs(r["error_vs_rigid"]) - 2.0 * r["error_stderr"] > 0.02),
                key=lambda r: r["compliance"],
            )[:2]
        )
        + f"; within 2 % at c <= {limit:.4f}",  # fmt: skip
        "rows": rows,
        "rigid_limits": limits,
        "source": "validation/bulk-convergence/run.py fit; run.py rule",
        "provenance": provenance.record(),
    }
    _write_csv(HERE / "rule.csv", rows)
    (ROOT / "dem" / "data" / "stiffness_convergence.json").write_text(
        json.dumps(data, indent=1) + "\n"
    )
    print(json.dumps({k: data[k] for k in ("compliance_limit", "evidence")}, indent=1))


def figures() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    beds = [b for b in ("sphere-bed", "screw-trough") if (HERE / f"stiffness_{b}.csv").is_file()]
    if beds:
        fig, axes = plt.subplots(1, len(beds), figsize=(5.2 * len(beds), 4.0), squeeze=False,
                                 constrained_layout=True)  # fmt: skip
        record = _read_record()
        for ax, bed in zip(axes[0], beds, strict=True):
            rows = _read_csv(HERE / f"stiffness_{bed}.csv")
            e = np.array([float(r["youngs_modulus_pa"]) for r in rows])
            v = np.array([float(r["mean_velocity_m_s"]) for r in rows])
            ci = np.array([float(r["ci95_m_s"]) for r in rows])
            ax.errorbar(e, v, yerr=ci, fmt="o", capsize=3, label="3 fills pooled, 95 %")
            for r in rows:
                reps = [float(x) for x in r["per_replica_m_s"].split()]
                ax.plot([float(r["youngs_modulus_pa"])] * len(reps), reps, ".", color="0.6")
            fit = record.get(f"stiffness_{bed}", {})
            if "v_inf_m_s" in fit:
                grid = np.geomspace(min(fit["fitted_youngs_pa"]), 1e12, 100)
                shape = grid ** (-fit["p"]) * fit["c"] if "c" in fit else 0.0 * grid
                what = "fit" if "c" in fit else "mean of the stiff points"
                ax.plot(grid, fit["v_inf_m_s"] + shape, "-",
                        label=f"{what}, v_inf = {fit['v_inf_m_s']:.4f} +- "
                              f"{fit['v_inf_stderr_m_s']:.4f} m/s")  # fmt: skip
                ax.axhspan(
                    fit["v_inf_m_s"] - 1.96 * fit["v_inf_stderr_m_s"],
                    fit["v_inf_m_s"] + 1.96 * fit["v_inf_stderr_m_s"],
                    alpha=0.15,
                )
            half = HERE / f"timestep_{bed}.csv"
            if half.is_file():
                for r in _read_csv(half):
                    ax.errorbar(float(r["youngs_modulus_pa"]) * 1.15,
                                float(r["mean_velocity_m_s"]), yerr=float(r["ci95_m_s"]),
                                fmt="s", color="C3", capsize=3)  # fmt: skip
                ax.plot([], [], "s", color="C3", label="dt halved")
            ax.set_xscale("log")
            ax.set_xlabel("Young's modulus E (Pa)")
            ax.set_ylabel("mean conveying velocity v (m/s)")
            ax.set_title(f"cases/{bed}: v against contact stiffness")
            ax.legend(fontsize=8)
        fig.savefig(HERE / "stiffness.png", dpi=120)
    if (HERE / "coverage.csv").is_file():
        rows = _read_csv(HERE / "coverage.csv")
        fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
        for ax, kind in zip(axes, ("one run", "3 replicas"), strict=True):
            sel = [r for r in rows if r["kind"] == kind]
            z = [(float(r["mean_m_s"]) - float(r["long_run_mean_m_s"]))
                 / (float(r["half_width_m_s"]) / 1.959963984540054) for r in sel]  # fmt: skip
            share = np.mean([int(r["covers"]) for r in sel])
            ax.hist(z, bins=np.linspace(-8, 8, 33), color="C0")
            for x in (-1.96, 1.96):
                ax.axvline(x, color="C3", ls="--")
            ax.set_xlabel("(estimate - long-run mean) / reported standard error")
            ax.set_ylabel("runs" if kind == "one run" else "triples")
            ax.set_title(f"{kind}: 95 % interval covers in {100 * share:.0f} % of {len(sel)}")
        fig.savefig(HERE / "coverage.png", dpi=120)
    phase = HERE / "inplane_phase_screw-trough.csv"
    if phase.is_file():
        rows = _read_csv(phase)
        fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True, constrained_layout=True)
        moduli = sorted({float(r["youngs_modulus_pa"]) for r in rows})
        for i, e in enumerate(moduli):
            sel = [r for r in rows if float(r["youngs_modulus_pa"]) == e]
            x = [float(r["phase_deg"]) for r in sel]
            mean = np.mean([float(r["velocity_m_s"]) for r in sel])
            label = f"E = {e:.0e} Pa (v = {mean:.4f} m/s)"
            for ax, key in zip(axes, ("velocity_m_s", "contact_accel_x_m_s2",
                                      "floor_contact_fraction"), strict=True):  # fmt: skip
                ax.plot(x, [float(r[key]) for r in sel], "o-", ms=2.5, color=f"C{i}",
                        label=label)  # fmt: skip
        axes[0].set_ylabel("bed v_x relative to\nthe trough (m/s)")
        axes[1].set_ylabel("bed x-acceleration\nfrom the walls (m/s^2)")
        axes[2].set_ylabel("fraction of screws\ntouching the floor")
        axes[2].set_xlabel("drive phase (deg; trough acceleration A w^2 sin(phase))")
        axes[0].legend(fontsize=7)
        axes[0].set_title("screw-trough: the cycle against stiffness (2 fills x 30 cycles each)",
                          fontsize=10)  # fmt: skip
        fig.savefig(HERE / "inplane_phase.png", dpi=120)


def _write_csv(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def _read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _read_record() -> dict:
    path = HERE / "provenance.json"
    return json.loads(path.read_text()) if path.is_file() else {}


def _record(name: str, result: dict) -> None:
    data = _read_record()
    data[name] = {**result, "command": " ".join(["run.py", *sys.argv[1:]]),
                  "provenance": provenance.record()}  # fmt: skip
    (HERE / "provenance.json").write_text(json.dumps(data, indent=1, default=float) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parts = [
        "coverage",
        "persistence",
        "stiffness",
        "timestep",
        "spectrum",
        "inplane",
        "pans",
        "section",
        "fills",
        "fit",
        "rule",
        "figures",
    ]
    parser.add_argument("what", choices=parts)
    parser.add_argument("bed", nargs="?", default="sphere-bed",
                        choices=["sphere-bed", "screw-trough"])  # fmt: skip
    parser.add_argument("--moduli", type=float, nargs="+", default=None)
    parser.add_argument("--factors", type=float, nargs="+", default=[2.0],
                        help="section: section lengths over the shipped one")  # fmt: skip
    parser.add_argument("--seed", type=int, default=4, help="fills: the first new seed")
    parser.add_argument("--replicas", type=int, default=5, help="fills: new fills per E")
    args = parser.parse_args()
    SCRATCH.mkdir(exist_ok=True)
    if args.what == "coverage":
        coverage()
    elif args.what == "persistence":
        persistence()
    elif args.what == "stiffness":
        stiffness(args.bed, args.moduli or MODULI)
    elif args.what == "fit":
        refit()
    elif args.what == "rule":
        rule()
    elif args.what == "timestep":
        timestep(args.bed, args.moduli or [5e8, 5e9])
    elif args.what == "fills":
        fills(args.bed, args.moduli or [2e9, 5e9, 2e10], args.seed, args.replicas)
    elif args.what == "section":
        section(args.bed, args.moduli or [2e9], args.factors)
    elif args.what == "spectrum":
        spectrum(args.bed, args.moduli or MODULI[:5])
    elif args.what == "pans":
        pans()
    elif args.what == "inplane":
        inplane(args.bed, args.moduli or [5e7, 2e8, 5e8, 2e9, 2e10], [1, 2])
    figures()


if __name__ == "__main__":
    main()
