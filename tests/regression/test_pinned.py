"""The pinned regression: a seeded run of 20 screws over 2 cycles gives the recorded numbers."""

import json

import pinned
import pytest


@pytest.mark.integration
def test_the_seeded_20_grain_run_gives_the_pinned_numbers_to_12_digits():
    recorded = json.loads(pinned.PINNED.read_text())
    assert recorded["overrides"] == pinned.OVERRIDES
    now = pinned.run()
    assert sorted(now) == sorted(recorded["numbers"]), "the summary's numbers changed their keys"
    moved = {
        k: (recorded["numbers"][k], v)
        for k, v in now.items()
        if not pinned.same(recorded["numbers"][k], v)
    }
    assert not moved, (
        f"{len(moved)} pinned numbers moved (recorded, now): {moved}. If the physics was meant "
        "to change, rerun `python tests/regression/pinned.py --why '...'` and commit pinned.json"
    )
