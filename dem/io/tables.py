"""CSV tables as spreadsheets and ``pandas.read_csv`` read them, with a JSON sidecar.

Every CSV file dem writes follows the same conventions:

- the first line is the header, one plain name per column; there are no ``#`` comment lines
  (they break spreadsheets, a plain ``pandas.read_csv`` and ``numpy.genfromtxt(names=True)``);
- a column with a unit names it at the end: ``angle_deg``, ``velocity_m_s``, ``time_s``,
  ``mass_flow_rate_kg_s`` (:func:`column_name`); a name without a unit is a dimensionless
  number (``throw_number``, ``velocity_norm``, ``friction``) or a count or a word;
- numbers are written to a stated number of significant digits (6 unless a column asks for
  more), so 0.15000000000000002 is written 0.15; whole numbers as whole numbers; an undefined
  value (None, NaN) as an empty field;
- where the file was made (dem version, commit, date, host, load, the command) and what each
  column means goes into a sidecar JSON of the same stem beside it (``sweep.csv`` ->
  ``sweep.json``; :func:`write_sidecar`), never into the CSV itself.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

from dem.io.files import json_text, replace_text

#: Significant digits of a number unless its column asks for more.
DIGITS = 6

#: Unit words as they appear at the end of a column name.
_UNIT_SUFFIX = {
    "m/s": "m_s",
    "kg/s": "kg_s",
    "kg/m^3": "kg_m3",
    "N/m": "N_m",
    "m/s^2": "m_s2",
    "kg/(s m)": "kg_s_m",
    "rad/s": "rad_s",
}


def unit_suffix(unit: str) -> str:
    """The unit as a column-name suffix: ``"m/s"`` -> ``"m_s"``, ``"deg"`` -> ``"deg"``."""
    return _UNIT_SUFFIX.get(unit, unit.replace("/", "_").replace("^", "").replace(" ", ""))


def column_name(name: str, unit: str = "") -> str:
    """``name`` with its unit appended (``angle``, ``deg`` -> ``angle_deg``); "" for none."""
    return f"{name}_{unit_suffix(unit)}" if unit else name


def case_key_unit(key: str) -> str:
    """The unit of a case key (``drive.angle`` -> ``deg``), from :data:`dem.quantities.QUANTITIES`.

    "" for a dimensionless key, a word-valued key, or one the table does not know.
    """
    from dem.quantities import QUANTITIES

    name = key.rsplit(".", 1)[-1]
    q = QUANTITIES.get(name)
    return q.unit if q is not None else ""


def format_value(value, digits: int = DIGITS) -> str:
    """One CSV field: numbers to ``digits`` significant digits, None and NaN empty.

    True/False are written ``true``/``false``; whole numbers (int) as they are; any other value
    as its text.
    """
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    try:
        import numpy as np

        if isinstance(value, np.bool_):
            return "true" if bool(value) else "false"
        if isinstance(value, np.integer):
            return str(int(value))
        if isinstance(value, np.floating):
            value = float(value)
    except ImportError:  # pragma: no cover - numpy is a dependency
        pass
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return ""
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = format(value, f".{digits}g")
        return "0" if text == "-0" else text
    return str(value)


def csv_text(
    columns: Sequence[str],
    rows: Iterable[Mapping | Sequence],
    digits: Mapping[str, int] | None = None,
) -> str:
    """The CSV text: the header line, then one line per row (a mapping by column, or a sequence).

    ``digits`` gives a column more (or fewer) significant digits than :data:`DIGITS`.
    """
    digits = digits or {}
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        values = [row.get(c) for c in columns] if isinstance(row, Mapping) else list(row)
        if len(values) != len(columns):
            raise ValueError(f"a row of {len(values)} values for {len(columns)} columns")
        writer.writerow(
            format_value(v, digits.get(c, DIGITS)) for c, v in zip(columns, values, strict=True)
        )
    return buf.getvalue()


def write_csv(
    path: Path,
    columns: Sequence[str],
    rows: Iterable[Mapping | Sequence],
    *,
    digits: Mapping[str, int] | None = None,
    meta: Mapping | None = None,
    command: str | None = None,
) -> Path:
    """Write ``path`` (whole or not at all) and its sidecar JSON; returns the CSV's path.

    Args:
        path: The CSV file.
        columns: Column names, units included (:func:`column_name`).
        rows: Mappings by column name, or sequences in column order.
        digits: Significant digits per column where not :data:`DIGITS`.
        meta: What the sidecar records beside the provenance: ``columns`` (name -> meaning),
            the case, the held values, ... (JSON-serialisable).
        command: The command that made the file (``dem sweep``), recorded in the sidecar.

    """
    path = Path(path)
    replace_text(path, csv_text(columns, rows, digits), encoding="utf-8")
    write_sidecar(path, meta, command=command)
    return path


def sidecar_path(path: Path) -> Path:
    """The sidecar JSON of a CSV file: the same stem, ``.json``."""
    return Path(path).with_suffix(".json")


def write_sidecar(path: Path, meta: Mapping | None = None, *, command: str | None = None) -> Path:
    """Write the provenance and ``meta`` of the CSV ``path`` to :func:`sidecar_path`."""
    from dem.provenance import record

    doc = {"file": Path(path).name, "command": command, "provenance": record()}
    doc |= dict(meta or {})
    target = sidecar_path(path)
    replace_text(target, json_text(doc, indent=1) + "\n")
    return target


#: Units of the summary.json values that tables gather (``dem sweep``, ``dem report``).
SUMMARY_UNITS = {
    "mean_velocity": "m/s",
    "mean_velocity_stderr": "m/s",
    "velocity_scale": "m/s",
    "mass_flow_rate": "kg/s",
    "mass_flow_rate_per_width": "kg/(s m)",
    "amplitude": "m",
    "angle": "deg",
    "inclination": "deg",
    "frequency": "Hz",
    "timestep": "s",
    "total_mass": "kg",
    "wall_time_s": "s",
    "settle_time_s": "s",
}


def summary_column(key: str) -> str:
    """The column name of a summary.json key or a case key, its unit appended.

    ``mean_velocity`` -> ``mean_velocity_m_s``, ``drive.angle`` -> ``drive.angle_deg``,
    ``wall_time_s`` stays; a dimensionless value (``throw_number``, ``mean_velocity_norm``,
    ``grains``) or a word keeps its name.
    """
    unit = SUMMARY_UNITS.get(key, case_key_unit(key) if "." in key else "")
    if unit and key.endswith("_" + unit_suffix(unit)):
        return key
    return column_name(key, unit)


#: cycles.csv, a run's per-cycle table beside its summary.json.
CYCLES_CSV = "cycles.csv"

#: results.h5 /cycles keys as cycles.csv writes them: (column, unit, meaning), in order.
_CYCLE_COLUMNS = {
    "cycle": ("cycle", "", "drive cycle index, counted from the drive's start (settling included)"),
    "time": ("time_s", "s", "drive time at the end of the cycle"),
    "mean_velocity": ("mean_velocity_m_s", "m/s",
                      "mass-weighted mean x-velocity over the cycle, relative to the trough"),
    "velocity_norm": ("velocity_norm", "",
                      "mean_velocity over the drive's velocity scale A omega cos(phi)"),
    "kinetic_energy": ("kinetic_energy_J", "J",
                       "kinetic energy of the grains in the trough frame at the cycle's end"),
    "contacts": ("contacts", "",
                 "touching neighbours and walls summed over the spheres at the cycle's end"),
    "discharged_mass": ("discharged_mass_kg", "kg", "mass that left over the discharge edge"),
    "discharge_rate": ("discharge_rate_kg_s", "kg/s", "discharged mass over the drive period"),
    "mass_in_trough": ("mass_in_trough_kg", "kg", "grain mass in the trough at the cycle's end"),
    "grains_in_trough": ("grains_in_trough", "", "grains in the trough at the cycle's end"),
    "grains_inserted": ("grains_inserted", "", "grains fed so far"),
    "grains_discharged": ("grains_discharged", "", "grains discharged so far"),
    "feed_backlog": ("feed_backlog", "", "grains due to be fed that found no room yet"),
}  # fmt: skip


def write_cycles_csv(out_dir: Path, summary: Mapping) -> Path:
    """Write ``OUT/cycles.csv`` (and ``cycles.json``): one row per measured cycle of the run.

    The rows are results.h5's ``/cycles`` (:mod:`dem.io.hdf5`) where ``measured`` is 1, so the
    mean of ``mean_velocity_m_s`` is summary.json's ``mean_velocity`` (to the 6 significant
    digits written); ``velocity_norm`` divides it by summary.json's ``velocity_scale``. The
    settling cycles before them are left out (results.h5 has them); their count, the case and
    what each column means are in the sidecar ``cycles.json``.
    """
    import h5py
    import numpy as np

    out_dir = Path(out_dir)
    with h5py.File(out_dir / "results.h5", "r", locking=False) as f:
        g = f["cycles"]
        data = {k: g[k][()] for k in g}
    rows = min((len(v) for v in data.values()), default=0)
    data = {k: np.asarray(v[:rows]) for k, v in data.items()}
    if "measured" in data:
        keep = data.pop("measured").astype(bool)
        data = {k: v[keep] for k, v in data.items()}
    scale = summary.get("velocity_scale")
    if "mean_velocity" in data and isinstance(scale, int | float) and scale > 0:
        data["velocity_norm"] = data["mean_velocity"] / float(scale)
    keys = [k for k in _CYCLE_COLUMNS if k in data] + sorted(set(data) - set(_CYCLE_COLUMNS))
    columns = [_CYCLE_COLUMNS[k][0] if k in _CYCLE_COLUMNS else k for k in keys]
    n = len(data[keys[0]]) if keys else 0
    meta = {
        "case": summary.get("case"),
        "settle_cycles_left_out": summary.get("settle_cycles"),
        "measured_cycles": n,
        "mean_velocity_m_s": summary.get("mean_velocity"),
        "velocity_scale_m_s": scale,
        "columns": {
            c: {"unit": _CYCLE_COLUMNS[k][1], "meaning": _CYCLE_COLUMNS[k][2]}
            for c, k in zip(columns, keys, strict=True)
            if k in _CYCLE_COLUMNS
        },
    }
    return write_csv(
        out_dir / CYCLES_CSV, columns, ([data[k][i] for k in keys] for i in range(n)),
        digits={"time_s": 9}, meta=meta, command="dem run",
    )  # fmt: skip
