"""Every shipped case's LIGGGHTS deck runs in LIGGGHTS 3.8 unedited, with dem's grains and mass.

`.ci/run` installs LIGGGHTS where it is missing (``apt-get install -y liggghts``); without it
these tests are skipped with that reason. Each deck is the one ``dem export liggghts`` writes,
with dem's time step, shortened to a few hundred steps (a fill of 50 steps, 100 settle and 100
measured driven steps): LIGGGHTS must read it without an ERROR, insert every grain, keep every
member sphere, and its own count of the inserted mass (the ``a total of N particle templates
(mass M)`` line of its log) must be dem's.
"""

import re
from pathlib import Path

import pytest

from dem.engine.feeder import grain_mass
from dem.io.liggghts import LIGGGHTS_INSTALL, find_liggghts, run_liggghts, write_deck
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
SHIPPED = sorted(p.parent.name for p in CASES_DIR.glob("*/case.toml"))
#: LIGGGHTS's running total after an insertion, e.g. "a total of 20 particle templates (mass
#: 5.000000e-02) inserted so far".
TOTAL_RE = re.compile(r"a total of (\d+) particle templates \(mass ([0-9.eE+-]+)\) inserted")

pytestmark = [
    pytest.mark.integration,
    pytest.mark.skipif(
        find_liggghts() is None, reason=f"liggghts not on PATH ({LIGGGHTS_INSTALL})"
    ),
]


@pytest.mark.integration
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_case_deck_runs_in_liggghts_with_dems_grains_and_mass(tmp_path, name):
    case = load_case(CASES_DIR / name)
    dt = timestep_for(case).dt
    deck = write_deck(case, tmp_path, timestep=dt, steps=100, settle_steps=100, fill_time=50 * dt)
    run = run_liggghts(tmp_path, deck.name, min_loops=3)
    assert "ERROR" not in run.stdout
    assert run.version is not None and run.version.startswith("LIGGGHTS-PUBLIC 3.8")
    members = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    assert [loop.steps for loop in run.loop_times] == [50, 100, 100]
    assert run.loop_times[0].atoms == case.particles.count * members
    # a feeder feeds more in 200 steps only at 1 grain per m / feed_rate (0.05 s here: none)
    assert run.loop_times[-1].atoms == case.particles.count * members
    [(count, mass)] = TOTAL_RE.findall(run.stdout)[:1]
    assert int(count) == case.particles.count
    # grain types: LIGGGHTS splits the count over the deck's size bins (a continuous
    # distribution in 8 bins of its mean volume) by whole grains, so the mass is the expected
    # one to the rounding of each bin's share (measured 1.8e-4 for sphere-mix)
    rel = 1e-3 if case.particles.types else 1e-6
    assert float(mass) == pytest.approx(case.particles.count * grain_mass(case), rel=rel)


@pytest.mark.integration
@pytest.mark.parametrize("name", ["screw-trough", "u-trough"])
def test_clump_decks_insert_random_orientations_inside_the_box(tmp_path, name):
    """LIGGGHTS's insert fixes default to the template's orientation: without ``orientation
    random`` every screw started along x (<u_x^2> = 1), a bed 8 % faster than dem's random fill
    (validation/liggghts-screws, part D). With it, the axes of the inserted screws are uniform
    (<u_x^2> = 1/3; 200 axes give a standard error of 0.021) and every member lies inside the box
    (its insertion region holds centres of mass, inset by the grain's reach)."""
    import numpy as np

    case = load_case(CASES_DIR / name)
    dt = timestep_for(case).dt
    deck = write_deck(case, tmp_path, timestep=dt, steps=1, settle_steps=1, fill_time=dt)
    text = deck.read_text()
    head = text[: text.index("# --- fill")]
    deck.write_text(
        head + "run 1\ndump m all custom 1 members.txt id x y z\ndump_modify m sort id\nrun 0\n"
    )
    run_liggghts(tmp_path, deck.name, min_loops=2)
    lines = (tmp_path / "members.txt").read_text().splitlines()
    x = np.array([[float(v) for v in row.split()[1:4]] for row in lines[9:]])
    grain = case.particles.grain
    k = grain.count
    assert x.shape == (case.particles.count * k, 3)
    # the screw's axis is body x: from its rearmost to its foremost member
    along = np.asarray(grain.centres)[:, 0]
    members = x.reshape(-1, k, 3)
    axis = members[:, np.argmax(along)] - members[:, np.argmin(along)]
    axis[:, 0] -= case.trough.length * np.round(axis[:, 0] / case.trough.length)
    ux2 = (axis[:, 0] / np.linalg.norm(axis, axis=1)) ** 2
    assert abs(ux2.mean() - 1.0 / 3.0) < 0.1
    box = [a.split() for a in text.splitlines() if a.startswith("region domain")][0]
    y0, y1, z0 = float(box[5]), float(box[6]), float(box[7])
    assert y0 < x[:, 1].min() and x[:, 1].max() < y1 and z0 < x[:, 2].min()
