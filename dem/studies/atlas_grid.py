"""The grid of ``dem atlas``: its file read and checked, and each point's case and folder.

:func:`read_grid` reads the grid file (the ``[atlas]`` settings, ``[atlas.cases]`` and the
``[[grid]]`` blocks; :mod:`dem.studies.atlas` shows one) into a :class:`Grid`; :func:`plan_points`
turns it into one :class:`AtlasPoint` per point, each with its case loaded and checked
(:func:`point_case`: the base case with the point's keys and the atlas's run keys, stiffened where
``stiffness = "converged"`` asks, :func:`converged_keys`), its folder
``OUT/points/<shape>/<keys>`` (:func:`folder_name`) and the record of what it runs
(:func:`point_record`). Nothing here runs a point.

Cost: O(points) case loads; the stiffness rule resolves each point's bed once more where it applies.
"""

from __future__ import annotations

import itertools
import json
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from dem.errors import InputError

#: The folder under ``--out`` that holds the points, one folder per shape.
POINTS_DIR = "points"
#: Most points one atlas runs (each is several whole bulk runs).
MAX_POINTS = 5000
#: Keys of ``[atlas]``.
ATLAS_KEYS = ("target_error", "max_replicas", "cycles", "stiffness", "flight_phases", "seed",
              "cases")  # fmt: skip
#: ``[atlas] stiffness``: "converged" raises a point's Young's modulus (or linear stiffness) to
#: what the stiffness rule asks for its bed (:mod:`dem.run.stiffness`), its time step kept at
#: the same fraction of the stability limit; "as given" runs the base case's.
STIFFNESS = ("converged", "as given")


@dataclass(frozen=True)
class AtlasPoint:
    """One point: its shape, its case overrides, its folder and the record of what it runs."""

    index: int
    shape: str
    overrides: dict
    folder: Path
    record: dict

    @property
    def name(self) -> str:
        """The point's folder under ``OUT/points``, which names it in messages."""
        return f"{self.shape}/{self.folder.name}"


@dataclass(frozen=True)
class Grid:
    """A grid file, read and checked: the settings, the base cases and the points' overrides."""

    path: Path
    target_error: float
    max_replicas: int
    cycles: int | None
    stiffness: str
    flight_phases: int
    cases: dict  # shape -> case folder
    points: list  # (shape, overrides)
    seed: int | None = None  # the first fill's seed (None: the base case's run.seed)


def read_grid(path: str | Path) -> Grid:
    """Read and check a grid file; errors name the file, the key and what is allowed."""
    path = Path(path)
    where = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError("GRID", where, f"a readable grid file ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError("GRID", str(exc), "valid TOML (https://toml.io)", where) from None
    unknown = set(data) - {"atlas", "grid"}
    if unknown:
        raise InputError(sorted(unknown)[0], None, "a table [atlas] or [[grid]] blocks", where)
    atlas = data.get("atlas", {})
    if not isinstance(atlas, dict):
        raise InputError("atlas", atlas, "a table [atlas]", where)
    for key in atlas:
        if key not in ATLAS_KEYS:
            raise InputError(f"atlas.{key}", atlas[key], f"a key of [atlas]: "
                             f"{', '.join(ATLAS_KEYS)}", where)  # fmt: skip
    from dem.quantities import QUANTITIES

    target = atlas.get("target_error", 0.03)
    QUANTITIES["target_error"].check(_number(target, "atlas.target_error", where),
                                     "atlas.target_error")  # fmt: skip
    most = atlas.get("max_replicas", 12)
    if not isinstance(most, int) or isinstance(most, bool) or not 3 <= most <= 1000:
        raise InputError("atlas.max_replicas", most, "a whole number of fills in [3, 1000]", where)
    cycles = atlas.get("cycles")
    if cycles is not None and (not isinstance(cycles, int) or isinstance(cycles, bool)
                               or not 1 <= cycles <= 10**7):  # fmt: skip
        raise InputError("atlas.cycles", cycles, "a whole number of cycles in [1, 1e7]", where)
    phases = atlas.get("flight_phases", 12)
    if not isinstance(phases, int) or isinstance(phases, bool) or not 0 <= phases <= 360:
        raise InputError("atlas.flight_phases", phases, "a whole number of phase bins in "
                         "[0, 360] (0: the grains in flight are not counted)", where)  # fmt: skip
    seed = atlas.get("seed")
    if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)
                             or not 0 <= seed < 2**62):  # fmt: skip
        raise InputError(
            "atlas.seed",
            seed,
            "a whole number in [0, 2^62): the first fill's "
            "seed at every point (default: the base case's run.seed)",
            where,
        )
    stiffness = atlas.get("stiffness", "converged")
    if stiffness not in STIFFNESS:
        raise InputError("atlas.stiffness", stiffness, f"one of {', '.join(STIFFNESS)}", where)
    cases = atlas.get("cases")
    if not isinstance(cases, dict) or not cases:
        raise InputError("atlas.cases", cases, "a table of shape = 'case folder' (relative "
                         "to the grid file), e.g. sphere = 'cases/sphere-bed'", where)  # fmt: skip
    folders = {}
    for shape, folder in cases.items():
        if not isinstance(folder, str):
            raise InputError(f"atlas.cases.{shape}", folder, "a case folder (a string)", where)
        folders[shape] = (path.parent / folder).resolve()
        if not (folders[shape] / "case.toml").is_file():
            raise InputError(f"atlas.cases.{shape}", folder, "a folder holding case.toml "
                             f"(looked in {folders[shape]})", where)  # fmt: skip
    blocks = data.get("grid")
    if not isinstance(blocks, list) or not blocks:
        raise InputError("grid", blocks, "one or more [[grid]] blocks of axes", where)
    points: list[tuple[str, dict]] = []
    for b, block in enumerate(blocks):
        points += _block_points(block, b, folders, where)
    unique = list({(s, json.dumps(o, sort_keys=True)): (s, o) for s, o in points}.values())
    if len(unique) > MAX_POINTS:
        raise InputError("grid", len(unique), f"at most {MAX_POINTS} points (each is several "
                         "bulk runs): fewer values, or several atlases", where)  # fmt: skip
    return Grid(path.resolve(), float(target), most, cycles, stiffness, phases, folders, unique,
                seed)  # fmt: skip


def _number(value, key: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(key, value, "a number", where)
    return float(value)


def _block_points(block, b: int, folders: dict, where: str) -> list[tuple[str, dict]]:
    """The Cartesian product of one [[grid]] block's axes, for each of its shapes."""
    name = f"grid[{b}]"
    if not isinstance(block, dict):
        raise InputError(name, block, "a [[grid]] block of axes", where)
    shapes = block.get("shape", list(folders))
    shapes = [shapes] if isinstance(shapes, str) else shapes
    if not isinstance(shapes, list) or not shapes:
        raise InputError(f"{name}.shape", shapes, "a list of shapes of [atlas.cases]", where)
    for shape in shapes:
        if shape not in folders:
            raise InputError(f"{name}.shape", shape, f"a shape of [atlas.cases]: "
                             f"{', '.join(folders)}", where)  # fmt: skip
    axes = []
    for key, values in block.items():
        if key == "shape":
            continue
        if "." not in key or key.startswith("run.") or key.startswith("output."):
            raise InputError(f"{name}.{key}", values, "a case key table.key (the run and "
                             "output keys are the atlas's: [atlas])", where)  # fmt: skip
        values = values if isinstance(values, list) else [values]
        if not values:
            raise InputError(f"{name}.{key}", values, "one value at least", where)
        axes.append((key, values))
    return [(shape, dict(zip([k for k, _ in axes], combo, strict=True)))
            for shape in shapes for combo in itertools.product(*(v for _, v in axes))]  # fmt: skip


def folder_name(overrides: dict) -> str:
    """``drive.throw_number=1.8_drive.angle=25`` (safe on every file system), or ``base``."""
    parts = [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in overrides.items()]
    return re.sub(r"[^A-Za-z0-9_.=+-]", "-", "_".join(parts)) or "base"


def point_case(grid: Grid, shape: str, overrides: dict, device: str | None = None):
    """The case of one point: its base case with the overrides and the atlas's run keys.

    With ``stiffness = "converged"`` the contact is stiffened where the stiffness rule finds
    the point's bed too soft (:func:`converged_keys`).
    """
    from dem.scene.case import load_case

    keys = dict(overrides) | {"run.target_error": grid.target_error,
                              "run.max_replicas": grid.max_replicas,
                              "output.flight_phases": grid.flight_phases}  # fmt: skip
    if grid.seed is not None:
        keys["run.seed"] = grid.seed
    if device is not None:
        keys["run.device"] = device
    case = load_case(grid.cases[shape], keys)
    if grid.stiffness == "converged":
        more = converged_keys(case)
        if more:
            case = load_case(grid.cases[shape], keys | more)
    return case


def converged_keys(case) -> dict:
    """The stiffness the stiffness rule asks for ``case`` and a step at the same stability share.

    {} where the case is stiff enough. As ``dem plan --suggest`` applies the rule
    (:mod:`dem.run.stiffness`): the modulus (or k_n) rounded up, a given step scaled with the
    limit and rounded down.
    """
    from dem.run import accuracy, stiffness
    from dem.scene.case import load_case
    from dem.scene.resolved import resolve

    scene = resolve(case)
    advice = stiffness.advice(scene)
    if advice is None:
        return {}
    keys = {advice.key: advice.value}
    if case.run.timestep is not None:
        stiffer = load_case(case.source.parent, dict(case.overrides) | keys
                            | {"run.timestep": None})  # fmt: skip
        limit = resolve(stiffer).step.limit
        keys["run.timestep"] = accuracy.round_down(case.run.timestep / scene.step.limit * limit)
    return keys


def plan_points(grid: Grid, out: Path, device: str | None = None) -> list[AtlasPoint]:
    """Every point, its case loaded and checked (an error names the point and the key)."""
    from dem.engine.device import check_device

    points = []
    for i, (shape, overrides) in enumerate(grid.points):
        try:
            case = point_case(grid, shape, overrides, device)
            check_device(case.run.device, case)
        except InputError as err:
            raise InputError(err.key, err.value, f"{err.allowed} (atlas point {shape} "
                             f"{overrides})", err.source) from None  # fmt: skip
        folder = out / POINTS_DIR / shape / folder_name(overrides)
        points.append(AtlasPoint(i, shape, overrides, folder, point_record(case, grid, shape)))
    return points


def point_record(case, grid: Grid, shape: str) -> dict:
    """What a point runs: the resolved case (as a checkpoint records it) and the atlas's keys."""
    from dem.run.summary import fingerprint

    cycles = case.run.cycles if grid.cycles is None else grid.cycles
    return fingerprint(case) | {"atlas.shape": shape, "atlas.cycles": cycles}
