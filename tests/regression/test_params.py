"""Every shipped case's contact-law parameters are the recorded bits (params.py)."""

import json

import params
import pinned


def test_every_shipped_case_packs_the_recorded_kernel_parameters_bit_for_bit():
    record = json.loads(params.PINNED.read_text())
    recorded = record["cases"]
    now = params.arrays()
    assert sorted(now) == sorted(recorded)
    here = pinned.fingerprint() == record["fingerprint"]

    def moved(a: str, b: str) -> bool:
        return a != b if here else not pinned.same(float.fromhex(a), float.fromhex(b))

    slots = {}
    for name in now:
        pairs = zip(now[name]["params"], recorded[name]["params"], strict=True)
        slots[name] = [i for i, (a, b) in enumerate(pairs) if moved(a, b)]
    slots = {k: v for k, v in slots.items() if v}
    for name in now:
        assert now[name]["model"] == recorded[name]["model"], name
        assert not moved(now[name]["dt"], recorded[name]["dt"]), f"{name}: the time step moved"
    assert not slots, (
        f"kernel parameters moved (case: slots; {'bits' if here else '12 digits'}): {slots}. If "
        "the physics was meant to change, rerun `python tests/regression/params.py --why '...'` "
        "and commit params.json"
    )
