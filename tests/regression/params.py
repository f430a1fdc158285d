"""The pinned kernel parameters: every shipped case's contact-law array, bit for bit.

``python tests/regression/params.py --why "..."`` rewrites ``params.json`` (the reason, the commit,
the date and the machine's fingerprint are recorded beside the arrays). test_params.py resolves
every case again and compares each float's bits on a machine of the same fingerprint, and to 12
significant digits on another (numpy's SIMD paths may move a derived coefficient's last bit). A
refactor of the contact law (its sub-models, where its parameters are packed) must leave the file
alone; only a change meant to move the physics regenerates it.

Beside the shipped cases, the variants cover every law a user can choose: each tangential law on
the Hertz and the linear normal law, eps_n above 0, rolling friction and the lever-arm choices.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
PINNED = HERE / "params.json"

#: name -> (case directory, overrides)
VARIANTS: dict[str, tuple[str, dict]] = {
    **{
        name: (name, {})
        for name in (
            "feeder",
            "screw-trough",
            "single-sphere",
            "sphere-bed",
            "sphere-mix",
            "u-trough",
            "v-trough",
        )
    },  # fmt: skip
    "screw-trough coulomb": ("screw-trough", {"contact.tangential": "coulomb"}),
    "screw-trough liggghts": ("screw-trough", {"contact.tangential": "liggghts"}),
    "screw-trough eps_n 0.5": ("screw-trough", {"material.restitution_normal": 0.5}),
    "sphere-bed coulomb eps_n 0.3": (
        "sphere-bed",
        {"contact.tangential": "coulomb", "material.restitution_normal": 0.3},
    ),
    "sphere-bed rolling 0.05 limit_force": (
        "sphere-bed",
        {"material.rolling_friction": 0.05, "contact.limit_force": True},
    ),
    "sphere-bed arms": (
        "sphere-bed",
        {"contact.wall_lever_arm": "radius", "contact.slip_lever_arm": "radius"},
    ),
    "single-sphere coulomb": ("single-sphere", {"contact.tangential": "coulomb"}),
    "single-sphere liggghts": (
        "single-sphere",
        {"contact.tangential": "liggghts", "contact.tangential_stiffness_ratio": 0.5},
    ),
    "single-sphere eps_n 0.4": ("single-sphere", {"material.restitution_normal": 0.4}),
}


def arrays() -> dict:
    """{variant: {"model": ..., "dt": hex, "params": [hex, ...]}} of the resolved cases."""
    from dem.scene.case import load_case
    from dem.scene.resolved import resolve

    out = {}
    for name, (folder, overrides) in VARIANTS.items():
        scene = resolve(load_case(ROOT / "cases" / folder, overrides))
        out[name] = {
            "model": scene.law.model,
            "dt": float(scene.step.dt).hex(),
            "params": [float(v).hex() for v in scene.law.params],
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--why", required=True, help="why the arrays move (recorded)")
    args = parser.parse_args()
    from pinned import fingerprint

    from dem import provenance

    record = {
        "why": args.why, "provenance": provenance.record(), "fingerprint": fingerprint(),
        "cases": arrays(),
    }  # fmt: skip
    PINNED.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {PINNED}: {len(record['cases'])} arrays")


if __name__ == "__main__":
    main()
