"""``dem export lammps``: the deck, dem's settled fill as its data file, and optionally the run.

With ``--fill lammps`` no dem fill is made: the deck pours and settles its own grains
(:mod:`dem.io.lammps.pour`), and a clump's template goes beside it as ``grain.mol``.

The step, the measured steps and the settling are chosen as for the LIGGGHTS deck
(:func:`dem.io.liggghts.export.plan_export`: dem's own step, the case's cycles); everything
LAMMPS cannot express is refused before the fill (:func:`dem.io.lammps.deck.refuse_unsupported`),
and a folder that already holds a deck is refused unless ``overwrite``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from dem.errors import InputError
from dem.io.files import refuse_links
from dem.io.lammps.deck import (
    BODIES_NAME,
    DATA_NAME,
    DECK_NAME,
    VX_FILE,
    refuse_unsupported,
    write_bodies,
    write_data,
    write_deck,
)
from dem.io.lammps.launcher import LOG_NAME, SUMMARY_NAME
from dem.io.lammps.pour import FILLS, MOLECULE_NAME, refuse_unpourable, write_molecule
from dem.io.liggghts.export import ExportPlan, plan_export
from dem.io.paths import refuse_replacing
from dem.kernels.rigid import quat_to_matrix
from dem.scene.case import Case

#: The files ``dem export lammps`` writes into its folder.
DECK_FILES = (DECK_NAME, DATA_NAME, BODIES_NAME, MOLECULE_NAME)
#: The files a ``--run`` adds (LAMMPS's log and velocity, dem's summary): never written through
#: a link either, since LAMMPS itself would follow one.
RUN_FILES = (LOG_NAME, VX_FILE, SUMMARY_NAME)


def plan_lammps(case: Case, **options) -> ExportPlan:
    """:func:`plan_export` for a LAMMPS deck, with its refusals checked."""
    plan = plan_export(case, **options)
    refuse_unsupported(plan.scene)
    return plan


def export_lammps(plan: ExportPlan, out_dir, *, overwrite: bool = False, progress: bool = True,
                  fill: str = "dem") -> Path:  # fmt: skip
    """Write the deck; the deck's path.

    ``fill`` "dem": fill and settle the case in dem and write ``data.fill`` (and for clumps
    ``bodies.rigid``) beside ``in.lammps``; "lammps": no dem fill, the deck pours its own
    (:mod:`dem.io.lammps.pour`), clumps from ``grain.mol``.
    """
    from dem.engine import setup

    if fill not in FILLS:
        raise InputError("--fill", fill, " or ".join(FILLS))
    if fill == "lammps":
        refuse_unpourable(plan.scene)
    out = Path(out_dir)
    refuse_links(out, (*DECK_FILES, *RUN_FILES), "OUT_DIR")
    if not overwrite:
        refuse_replacing("OUT_DIR", out, DECK_FILES)
    case = plan.scene.case
    if fill == "lammps":
        out.mkdir(parents=True, exist_ok=True)
        if case.particles.clumps:
            write_molecule(out / MOLECULE_NAME, plan.scene)
        return write_deck(plan.scene, out, timestep=plan.timestep, steps=plan.steps,
                          settle_steps=plan.settle_steps, r_max=plan.scene.max_radius,
                          settle_note=plan.settle_note, fill=fill)  # fmt: skip
    if progress:
        print(f"dem: filling and settling {case.particles.count} grains (drive off) for the "
              "deck's data file", file=sys.stderr)  # fmt: skip
    sim = setup.from_case(case, timestep=plan.timestep)
    sim.settle()
    s = sim.spheres
    out.mkdir(parents=True, exist_ok=True)
    b = sim.bodies
    if b is None:
        write_data(out / DATA_NAME, plan.scene, s.x, s.v, s.omega, s.radius, s.mass,
                   kind=sim.grain_type)  # fmt: skip
    else:
        # the member spheres' own masses only set their density: fix rigid/small takes each
        # body's mass, centre and inertia from the bodies file
        b.place(s)
        per = np.full(s.n, float(b.mass[0]) / plan.scene.grain.count)
        write_data(out / DATA_NAME, plan.scene, s.x, s.v, s.omega, s.radius, per, body=b.body_of)
        inertia = np.array([quat_to_matrix(q) @ np.diag(m) @ quat_to_matrix(q).T
                            for q, m in zip(b.q, b.moments, strict=True)])  # fmt: skip
        write_bodies(out / BODIES_NAME, b, inertia, plan.scene.trough.length)
    return write_deck(plan.scene, out, timestep=plan.timestep, steps=plan.steps,
                      settle_steps=plan.settle_steps, r_max=float(s.radius.max()),
                      settle_note=plan.settle_note)  # fmt: skip
