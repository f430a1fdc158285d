"""The test tree mirrors the package (tests/kernels, tests/scene, ...); the brute-force references
live in tests/oracles and the shared small case in tests/support, importable from every folder."""

import sys
from pathlib import Path

HERE = Path(__file__).parent
for folder in (HERE, HERE / "oracles", HERE / "support"):
    sys.path.insert(0, str(folder))
