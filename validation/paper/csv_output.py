"""The CSV files of this folder: ``#`` comment lines (provenance, fixed inputs), then a table."""

import csv
import json
from pathlib import Path

import numpy as np


def write_csv(path: Path, columns: dict, meta: dict, fixed: dict) -> Path:
    """CSV with ``#`` comment lines (provenance, fixed inputs) and a header row."""
    names = list(columns)
    data = [np.asarray(columns[k]) for k in names]
    with path.open("w", newline="") as stream:
        for key, value in meta.items():
            stream.write(f"# {key}: {value}\n")
        stream.write(f"# fixed: {json.dumps(fixed)}\n")
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(names)
        for i in range(len(data[0])):
            row = []
            for col in data:
                value = col[i]
                if isinstance(value, np.bool_ | bool):
                    row.append(int(value))
                elif isinstance(value, np.floating | float):
                    row.append(f"{float(value):.8g}")
                else:
                    row.append(str(value))
            writer.writerow(row)
    return path
