"""The package tree in ARCHITECTURE.md, drawn from the package itself.

Each module and folder of dem/ with the first line of its docstring, folders in layer order
(:data:`test_layers.LAYERS`, bottom first), so the map cannot drift from the code:
tests/package/test_layers.py fails when the drawn tree differs from ARCHITECTURE.md's, and

    python tests/package/tree.py --write

redraws it there (between the ``<!-- tree -->`` markers).
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from test_layers import LAYERS, PACKAGE  # noqa: E402

ARCHITECTURE = PACKAGE.parent / "ARCHITECTURE.md"
BEGIN, END = "<!-- tree -->", "<!-- /tree -->"
WIDTH = 30  # the column the descriptions start at


def summary(path: Path) -> str:
    """First line of a module's docstring (a package: of its __init__), or ''."""
    source = path / "__init__.py" if path.is_dir() else path
    doc = ast.get_docstring(ast.parse(source.read_text())) if source.is_file() else None
    return (doc or "").strip().split("\n")[0]


def _entries(folder: Path, depth: int) -> list[str]:
    lines = []
    files = sorted(p for p in folder.glob("*.py") if p.name != "__init__.py")
    dirs = sorted(p for p in folder.iterdir() if p.is_dir() and (p / "__init__.py").is_file())
    for p in files + dirs:
        name = "  " * depth + p.name + ("/" if p.is_dir() else "")
        lines.append(f"{name:<{WIDTH}}{summary(p)}".rstrip())
        if p.is_dir():
            lines += _entries(p, depth + 1)
    return lines


def render() -> str:
    """The tree as ARCHITECTURE.md shows it: one block per layer, bottom first."""
    out = ["```", f"{'dem/':<{WIDTH}}{summary(PACKAGE)}".rstrip()]
    for layer, prefixes in LAYERS:
        out.append(f"  # {layer}")
        for prefix in prefixes:
            parts = prefix.split(".")[1:]
            if not parts:
                continue  # the package itself: its __init__ is the first line
            p = PACKAGE.joinpath(*parts)
            if p.is_dir():
                out.append(f"{'  ' + p.name + '/':<{WIDTH}}{summary(p)}".rstrip())
                out += ["  " + line for line in _entries(p, 1)]
            else:
                p = p.with_suffix(".py")
                out.append(f"{'  ' + p.name:<{WIDTH}}{summary(p)}".rstrip())
    out.append("```")
    return "\n".join(out)


def drawn() -> str:
    """The tree ARCHITECTURE.md shows now ('' without the markers)."""
    text = ARCHITECTURE.read_text()
    if BEGIN not in text or END not in text:
        return ""
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="redraw it in ARCHITECTURE.md")
    args = parser.parse_args()
    if not args.write:
        print(render())
        return
    text = ARCHITECTURE.read_text()
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    ARCHITECTURE.write_text(f"{head}{BEGIN}\n{render()}\n{END}{tail}")
    print(f"redrew the tree in {ARCHITECTURE}")


if __name__ == "__main__":
    main()
