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
    moved = pinned.matches(now, recorded["numbers"])
    others = recorded.get("machines", [])
    if moved and any(not pinned.matches(now, m["numbers"]) for m in others):
        return  # this machine's own set, recorded with --machine
    assert not moved, (
        f"{len(moved)} pinned numbers moved (recorded, now): {moved}. If the physics was meant "
        "to change, rerun `python tests/regression/pinned.py --why '...'` and commit pinned.json; "
        f"if only the machine differs (this one: {pinned.fingerprint()}; "
        f"{len(others)} other machines recorded), `pinned.py --machine --why '...'` adds its set"
    )
