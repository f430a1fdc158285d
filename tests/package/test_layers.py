"""The package's layers: every import in dem/ points down, and no module reaches into another's
private names.

The order is the one ARCHITECTURE.md draws: a module may import its own layer and the layers
below it. Imports inside functions count as well (a lazy import hides the direction, it does not
change it). Private names (one leading underscore) stay inside their module.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "dem"

#: Bottom to top. The ground is dem's top-level modules other than the command line.
LAYERS = [
    ("ground", ["dem", "dem.config", "dem.errors", "dem.quantities", "dem.provenance"]),
    ("kernels", ["dem.kernels"]),
    ("physics", ["dem.physics"]),
    ("scene", ["dem.scene"]),
    ("engine", ["dem.engine"]),
    ("io", ["dem.io"]),
    ("pointmass", ["dem.pointmass"]),
    ("run", ["dem.run"]),
    ("studies", ["dem.studies"]),
    ("cli", ["dem.cli"]),
]


def layer_of(module: str) -> int:
    """Index in LAYERS of a dotted module name (the longest matching prefix)."""
    best, best_len = None, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            exact_only = p == "dem"
            hit = module == p if exact_only else module == p or module.startswith(p + ".")
            if hit and len(p) > best_len:
                best, best_len = i, len(p)
    if best is None:
        raise KeyError(f"{module} is in no layer: add it to LAYERS (tests) and ARCHITECTURE.md")
    return best


def module_name(path: Path, root: Path) -> str:
    """Dotted name of a source file under ``root``'s parent."""
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports_of(path: Path, root: Path) -> list[tuple[int, str, list[str]]]:
    """(line, imported module, names taken from it) for every use of a dem module in ``path``.

    ``from dem.x import y`` gives module ``dem.x.y`` when ``y`` is a submodule, else ``dem.x``
    with the name ``y``; ``mod._name`` on a module bound by ``import`` or ``from`` gives that
    module with the name ``_name``.
    """
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    imports, attributes = _nodes(path.read_text())
    for node in imports:
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "dem":
                    found.append((node.lineno, alias.name, []))
        else:
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "dem":
                continue
            names = [a.name for a in node.names]
            for n in names:
                sub = root.parent / (target.replace(".", "/") + "/" + n)
                if sub.with_suffix(".py").is_file() or (sub / "__init__.py").is_file():
                    found.append((node.lineno, f"{target}.{n}", []))
                else:
                    found.append((node.lineno, target, [n]))
    bound = {}  # local name -> dem module it stands for
    for node in imports:
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for alias in node.names:
                full = f"{node.module}.{alias.name}"
                if full.startswith("dem.") and any(full == t for _, t, _ in found):
                    bound[alias.asname or alias.name] = full
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.asname and alias.name.startswith("dem."):
                    bound[alias.asname] = alias.name
    for node in attributes:
        if node.value.id in bound and node.attr.startswith("_"):
            found.append((node.lineno, bound[node.value.id], [node.attr]))
    return found


@functools.cache
def _nodes(text: str) -> tuple[list, list]:
    """The import nodes and the ``name.attribute`` nodes of a source, in one walk of its tree
    (parsed once per text: a planted copy of the package reuses the others)."""
    imports, attributes = [], []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import | ast.ImportFrom):
            imports.append(node)
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            attributes.append(node)
    return imports, attributes


def violations(root: Path) -> list[str]:
    """Every upward import and every private name taken from another module, as messages."""
    out = []
    for path in sorted(root.rglob("*.py")):
        if "data" in path.relative_to(root).parts:
            continue  # scripts shipped for other programs (ParaView)
        here = module_name(path, root)
        mine = layer_of(here)
        for line, target, names in imports_of(path, root):
            theirs = layer_of(target)
            where = f"{path.relative_to(root.parent)}:{line}"
            if theirs > mine:
                out.append(
                    f"{where}: {here} ({LAYERS[mine][0]}) imports {target} "
                    f"({LAYERS[theirs][0]}), a layer above it"
                )
            for n in names:
                if n.startswith("_") and not n.startswith("__") and target != here:
                    out.append(f"{where}: {here} imports {target}.{n}, private to {target}")
    return out


def circles(root: Path) -> list[list[str]]:
    """Every set of modules that import each other round a circle (inside a layer, where the
    order of the layers cannot see it): the strongly connected components of the import graph,
    lazy imports included."""
    graph: dict[str, set[str]] = {}
    for path in sorted(root.rglob("*.py")):
        if "data" in path.relative_to(root).parts:
            continue
        here = module_name(path, root)
        graph.setdefault(here, set()).update(t for _, t, _ in imports_of(path, root) if t != here)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []

    def visit(v: str) -> None:  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while not component or component[-1] != v:
                component.append(stack.pop())
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_every_import_in_dem_points_down_and_no_private_name_crosses_a_module():
    assert violations(PACKAGE) == []


def test_no_modules_of_dem_import_each_other_round_a_circle():
    assert circles(PACKAGE) == []


def test_the_circle_check_finds_a_planted_circle(tmp_path):
    import shutil

    root = tmp_path / "dem"
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__", "data"))
    before = circles(root)
    (root / "physics" / "extra_a.py").write_text("from dem.physics import extra_b\n")
    (root / "physics" / "extra_b.py").write_text("def f():\n    from dem.physics import extra_a\n")
    found = [c for c in circles(root) if c not in before]
    assert found == [["dem.physics.extra_a", "dem.physics.extra_b"]]


def test_every_module_of_dem_is_in_a_layer():
    for path in PACKAGE.rglob("*.py"):
        if "data" not in path.relative_to(PACKAGE).parts:
            layer_of(module_name(path, PACKAGE))


@pytest.mark.parametrize(
    "where, source, expected",
    [
        ("scene/trough.py", "from dem.run import runner\n", "imports dem.run.runner (run)"),
        ("kernels/extra.py", "def f():\n    from dem.physics import drive\n", "(physics)"),
        ("physics/extra.py", "import dem.engine.state\n", "imports dem.engine.state"),
        ("engine/extra.py", "from dem.scene.case import _read_table\n", "private to"),
    ],
)
def test_the_layer_check_fails_on_a_planted_upward_import(tmp_path, where, source, expected):
    """A copy of the package with one bad import planted: the check names it."""
    import shutil

    root = tmp_path / "dem"
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__", "data"))
    before = set(violations(root))
    (root / where).write_text(source)
    found = sorted(set(violations(root)) - before)
    assert len(found) == 1 and expected in found[0], found


def test_architecture_md_draws_the_package_as_it_is():
    import tree

    assert tree.drawn() == tree.render(), (
        "ARCHITECTURE.md's tree differs from the package: python tests/package/tree.py --write"
    )
