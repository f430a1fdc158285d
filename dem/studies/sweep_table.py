"""The points, table and figure of a ``dem sweep``: its rows gathered, written and drawn.

:func:`gather` reads each point's summary.json into one row, :func:`write_table` writes the rows as
``sweep.csv`` (units in the column names, its provenance in ``sweep.json``) and ``sweep.h5`` (one
dataset per column), and :func:`plot` draws ``sweep.png``: the bulk velocity in m/s and normalised
against the first swept key, the point-mass model beside it, the held values
(:func:`held_values`) in the title. ``dem atlas`` writes its table with :func:`write_table` too.

Cost: O(P) in the P points (one summary.json read each).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from dem.io.files import replace_file


@dataclass(frozen=True)
class SweepPoint:
    """One point of a sweep: its index, its overrides, its output folder and its record.

    ``record`` is what :data:`dem.studies.sweep.RECORD` holds once the point has finished
    (:func:`dem.studies.sweep.record`).
    """

    index: int
    overrides: dict
    folder: Path
    record: dict | None = None

    @property
    def name(self) -> str:
        """The folder's name, which identifies the point in messages."""
        return self.folder.name


#: summary.json values gathered into the sweep table, beside the swept keys.
COLUMNS = (
    "mean_velocity",
    "mean_velocity_stderr",
    "mean_velocity_norm",
    "mean_velocity_norm_stderr",
    "pointmass_velocity_norm",
    "velocity_scale",
    "mass_flow_rate",
    "throw_number",
    "amplitude",
    "grains",
    "timestep",
    "settle_cycles",
    "cycles",
    "wall_time_s",
)
TABLE = "sweep"


def gather(points: list[SweepPoint], failed: dict[str, str]) -> list[dict]:
    """One row per point: its overrides, its summary's values, and its status."""
    from dem.run.output import SUMMARY
    from dem.studies.report_inputs import read_summary

    rows = []
    for p in points:
        row = {"point": p.name} | {k: v for k, v in p.overrides.items()}
        path = p.folder / SUMMARY
        if path.is_file():
            summary = read_summary(path, "--out")
            row |= {c: summary.get(c) for c in COLUMNS} | {"status": "done", "error": ""}
        else:
            row |= {c: None for c in COLUMNS}
            row |= {"status": "failed", "error": failed.get(p.name, "no summary.json")}
        rows.append(row)
    return rows


def write_table(rows: list[dict], out: Path, context: dict | None = None, *, table: str = TABLE,
                command: str = "dem sweep") -> Path:  # fmt: skip
    """``sweep.csv``, its sidecar ``sweep.json`` and ``sweep.h5`` (one dataset per column).

    ``table`` and ``command`` name the files and the command that wrote them (``dem atlas``).

    Column names carry their units (:func:`dem.io.tables.summary_column`: ``drive.angle_deg``,
    ``mean_velocity_m_s``); the CSV has one header line and numbers to 6 significant digits
    (:mod:`dem.io.tables`), the sidecar the provenance and what each column means. sweep.h5
    has the same names, numbers as float64 (NaN for none), each dataset's unit as its ``unit``
    attribute. ``context`` (the case folder, the swept values) goes into the sidecar too.
    """
    import h5py
    import numpy as np

    from dem.io.tables import SUMMARY_UNITS as UNITS
    from dem.io.tables import case_key_unit, summary_column, write_csv

    fields = list(rows[0])
    names = {f: summary_column(f) for f in fields}
    if len(set(names.values())) < len(names):  # a swept key named like a summary column
        names = {f: f for f in fields}
    columns = [names[f] for f in fields]
    units = {names[f]: UNITS.get(f, case_key_unit(f) if "." in f else "") for f in fields}
    meaning = {
        "point": "the point's folder under the sweep folder",
        "status": "done, or failed (error says why)",
        "error": "why the point failed",
    }
    meaning |= {names[f]: f"swept case key {f}" for f in fields if "." in f}
    meaning |= {names[c]: f"summary.json {c}" for c in COLUMNS if c in names}
    meta = dict(context or {})
    meta["columns"] = {c: {"unit": units[c], "meaning": meaning.get(c, "")} for c in columns}
    path = write_csv(out / f"{table}.csv", columns, ([r[f] for f in fields] for r in rows),
                     meta=meta, command=command)  # fmt: skip

    def write_h5(tmp: Path) -> None:
        with h5py.File(tmp, "w") as h5:
            g = h5.create_group(table)
            for f in fields:
                values = [r[f] for r in rows]
                name = names[f]
                if all(isinstance(v, (int, float)) or v is None for v in values) and not all(
                    isinstance(v, bool) for v in values
                ):
                    g[name] = np.array([math.nan if v is None else float(v) for v in values])
                else:
                    g[name] = np.array([str(v) for v in values], dtype=h5py.string_dtype())
                g[name].attrs["unit"] = units[name]
            g.attrs["columns"] = json.dumps(columns)

    replace_file(out / f"{table}.h5", write_h5)
    return path


def held_values(case_dir: Path, sets: list[tuple[str, list]]) -> dict:
    """The base case's drive and material values that the sweep does not vary, by key.

    The drive as the case gives it (its throw number or its amplitude), the angle, frequency,
    friction and inclination: what a sweep's figure names as held fixed.
    """
    from dem.scene.case import load_case

    case = load_case(case_dir)
    d = case.drive
    values = {
        "drive.angle": d.angle,
        f"drive.{d.given}": getattr(d, d.given),
        "drive.frequency": d.frequency,
        "material.friction": case.material.friction,
        "trough.inclination": case.trough.inclination,
    }
    swept = {k.rsplit(".", 1)[-1] for k, _ in sets}
    if swept & {"amplitude", "throw_number"}:  # setting one of them moves the other
        swept |= {"amplitude", "throw_number"}
    return {k: v for k, v in values.items() if k.rsplit(".", 1)[-1] not in swept}


def plot(rows: list[dict], path: Path, keys: list[str], held: dict | None = None) -> None:
    """The bulk velocity against the first swept key: in m/s (left) and normalised (right).

    One line per value of the other swept keys; the point-mass model dashed beside each (its
    velocity in m/s is its v_norm times the run's velocity scale A omega cos phi). The title
    names the case's values the sweep held fixed (``held``, :func:`held_values`).
    """
    from dem.studies import plots

    plt = plots.plt
    first, rest = keys[0], keys[1:]
    numeric = all(isinstance(r[first], (int, float)) for r in rows)
    fig, (ax_v, ax_n) = plt.subplots(1, 2, figsize=(11, 4.4))
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in rest), []).append(r)
    for i, (label, sel) in enumerate(groups.items()):
        sel = [r for r in sel if r["status"] == "done"]
        if not sel:
            continue
        xs = [r[first] if numeric else j for j, r in enumerate(sel)]
        name = plots.held_text(dict(zip(rest, label, strict=True)))
        scale = [_number(r.get("velocity_scale")) for r in sel]
        pm_norm = [_number(r.get("pointmass_velocity_norm")) for r in sel]
        for ax, key, pm in (
            (ax_v, "mean_velocity", [p * v for p, v in zip(pm_norm, scale, strict=True)]),
            (ax_n, "mean_velocity_norm", pm_norm),
        ):
            ax.errorbar(xs, [_number(r[key]) for r in sel],
                        yerr=[_number(r[key + "_stderr"]) for r in sel], fmt="o-", capsize=2,
                        color=f"C{i}", label="DEM" + (f", {name}" if name else ""))  # fmt: skip
            ax.plot(xs, pm, "--", color=f"C{i}", lw=1,
                    label="point mass" + (f", {name}" if name else ""))  # fmt: skip
            if not numeric:
                ax.set_xticks(xs, [str(r[first]) for r in sel])
    for ax in (ax_v, ax_n):
        ax.set_xlabel(plots.axis_label(first))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    ax_v.set_ylabel(plots.VELOCITY_LABEL)
    ax_n.set_ylabel(plots.NORM_LABEL)
    failed = sum(r["status"] != "done" for r in rows)
    varied = ", ".join(plots.QUANTITY.get(k.rsplit(".", 1)[-1], (k,))[0] for k in keys)
    title = f"Bulk conveying velocity over {varied}"
    if held:
        title += f"; held: {plots.held_text(held)}"
    if failed:
        title += f" ({failed} of {len(rows)} points failed: not drawn)"
    fig.suptitle(plots.wrap_title(title, fig, 10), fontsize=10)
    plots.save(fig, path)


def _number(v) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan
