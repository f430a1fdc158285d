"""dem against LIGGGHTS along one trajectory: free flight, and the states after each impact."""

from __future__ import annotations

import numpy as np

FLIGHT_TOL = 1e-9  # m/s: rows whose velocity moved less than this are free flight


def flight_segments(traj: np.ndarray, min_rows: int = 4) -> list[tuple[int, int]]:
    """Runs of rows (first, last) in free flight: horizontal velocity unchanged row to row."""
    still = np.all(np.abs(np.diff(traj[:, 4:6], axis=0)) < FLIGHT_TOL, axis=1)
    segments, first = [], None
    for i, s in enumerate(still):
        if s and first is None:
            first = i
        if not s and first is not None:
            segments.append((first, i))
            first = None
    if first is not None:
        segments.append((first, len(traj) - 1))
    return [seg for seg in segments if seg[1] - seg[0] + 1 >= min_rows]


def compare_rows(lig: np.ndarray, dem: np.ndarray) -> dict:
    """Differences dem - LIGGGHTS of one output row (t x y z v w q)."""
    vl, vd, wl, wd = lig[4:7], dem[4:7], lig[7:10], dem[7:10]
    return {
        "t": float(lig[0]),
        "v_liggghts": vl.tolist(),
        "v_dem": vd.tolist(),
        "omega_liggghts": wl.tolist(),
        "omega_dem": wd.tolist(),
        "vx_rel_percent": float(100.0 * (vd[0] - vl[0]) / abs(vl[0])),
        "v_rel_percent": float(100.0 * np.linalg.norm(vd - vl) / np.linalg.norm(vl)),
        "omega_rel_percent": float(100.0 * np.linalg.norm(wd - wl) / np.linalg.norm(wl)),
        "dx_um": (1e6 * (dem[1:4] - lig[1:4])).tolist(),
    }


def impact_table(lig: np.ndarray, dem: np.ndarray, n_impacts: int = 2) -> dict:
    """Free flight before the first impact and the states after the first impacts."""
    segs = flight_segments(lig)
    first_contact = segs[0][1] if segs else len(lig) - 1
    before = slice(0, first_contact + 1)
    out = {
        "first_contact_row_time": float(lig[first_contact, 0]),
        "free_flight_max_dx_m": float(np.abs(dem[before, 1:4] - lig[before, 1:4]).max()),
        "free_flight_max_dv": float(np.abs(dem[before, 4:7] - lig[before, 4:7]).max()),
        "free_flight_max_domega": float(np.abs(dem[before, 7:10] - lig[before, 7:10]).max()),
        "after_impact": [],
    }
    for k, (first, _last) in enumerate(segs[1 : n_impacts + 1], start=1):
        row = compare_rows(lig[first], dem[first])
        dem_flying = bool(np.all(np.abs(dem[first + 1, 4:6] - dem[first, 4:6]) < FLIGHT_TOL))
        out["after_impact"].append({"impact": k, "dem_in_flight": dem_flying, **row})
    out["final"] = compare_rows(lig[-1], dem[-1])
    return out
