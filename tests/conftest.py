"""The test tree mirrors the package (tests/kernels, tests/scene, ...); the brute-force references
live in tests/oracles and the shared small case in tests/support. Every folder is importable from
every other, so a test run on one file finds the helpers it shares with another folder's tests."""

import sys
from pathlib import Path

HERE = Path(__file__).parent
for folder in [HERE, *sorted(p for p in HERE.iterdir() if p.is_dir() and p.name != "__pycache__")]:
    sys.path.insert(0, str(folder))
