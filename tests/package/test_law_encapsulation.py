"""No layer above dem.physics reads a kernel parameter slot or branches on a contact law's name.

The contact law's kernel parameters are packed once, in :mod:`dem.physics.contact`
(:meth:`dem.physics.contact.ContactLaw.from_case`, through
:func:`dem.kernels.contact.make_params`); everything above asks the law (its sub-models, time
scales, deck words, :meth:`~dem.physics.contact.ContactLaw.report`). So no module of dem outside
``dem/kernels`` and ``dem/physics``:

- imports a ``P_*`` slot constant or reads one as an attribute (``contact.P_BETA``), nor
- compares anything with a string literal that names a DEM contact law (a key of
  :data:`dem.physics.laws.NORMAL_LAWS` or :data:`dem.physics.laws.TANGENTIAL_LAWS`).

Allowed exceptions, each with its reason:

- ``dem/pointmass/**``: the point-mass model has its own landing laws
  (:data:`dem.pointmass.model.IMPACT_LAWS`: ``"paper"``, ``"coulomb"``), a distinct vocabulary
  that names how an instantaneous landing is bounded, not a DEM contact law.
- The case schema (:mod:`dem.scene.schema`) lists the allowed ``[contact]`` values; it takes
  them from the registry (no literal), so it needs no exception.
"""

import ast
import re
from pathlib import Path

from dem.physics import laws

DEM = Path(__file__).resolve().parents[2] / "dem"
SLOT = re.compile(r"^P_[A-Z0-9_]+$")
LAW_NAMES = set(laws.NORMAL_LAWS) | set(laws.TANGENTIAL_LAWS)
#: Below the line: the layers that own the law's kernel form.
OWNERS = ("kernels", "physics")
#: Allowed: the point mass's own landing-law names (module docstring).
DISTINCT_VOCABULARY = ("pointmass",)


def _modules():
    for path in sorted(DEM.rglob("*.py")):
        rel = path.relative_to(DEM).as_posix()
        if rel.split("/")[0] in OWNERS + DISTINCT_VOCABULARY:
            continue
        yield rel, ast.parse(path.read_text(encoding="utf-8"))


def _law_literals(node) -> list[str]:
    """The law names among the string literals of a comparison's operand (or its tuple)."""
    items = node.elts if isinstance(node, ast.Tuple | ast.List | ast.Set) else [node]
    return [i.value for i in items if isinstance(i, ast.Constant) and i.value in LAW_NAMES]


def _offences(tree) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found += [f"imports {a.name}" for a in node.names if SLOT.match(a.name)]
        elif isinstance(node, ast.Attribute) and SLOT.match(node.attr):
            found.append(f"line {node.lineno}: reads .{node.attr}")
        elif isinstance(node, ast.Compare):
            for operand in (node.left, *node.comparators):
                for name in _law_literals(operand):
                    found.append(f"line {node.lineno}: compares with the law name {name!r}")
    return found


def test_no_slot_index_or_law_name_above_physics():
    offences = {rel: found for rel, tree in _modules() if (found := _offences(tree))}
    assert not offences, offences


def test_the_check_sees_a_slot_read_and_a_law_branch():
    """The check itself: it flags what it must (so an empty result means something)."""
    tree = ast.parse(
        "from dem.kernels.contact import P_BETA\n"
        "x = law.params[contact.P_KN]\n"
        "if model == 'linear': pass\n"
        "if t in ('impact', 'other'): pass\n"
    )
    assert len(_offences(tree)) == 4
