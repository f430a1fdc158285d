"""A record written before a case key existed still matches the case it ran (resume, atlas)."""

from pathlib import Path

import pytest

from dem.run.summary import ADDED_KEYS, fingerprint, fingerprint_changes
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.mark.parametrize("key", sorted(ADDED_KEYS))
def test_a_record_without_an_added_key_matches_the_default_case(key):
    """An atlas point or a checkpoint from before the key ran with its default."""
    case = load_case(CASES / "screw-trough")
    now = fingerprint(case)
    before = {k: v for k, v in now.items() if k != key}
    assert fingerprint_changes(before, now) == []


def test_a_record_without_the_grain_types_does_not_match_a_case_with_types():
    mix = fingerprint(load_case(CASES / "sphere-mix"))
    before = {k: v for k, v in mix.items() if k != "particles.types"}
    changes = fingerprint_changes(before, mix)
    assert len(changes) == 1 and changes[0].startswith("particles.types = []")
