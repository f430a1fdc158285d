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

from dem.case import load_case
from dem.feeder import grain_mass
from dem.io.liggghts import LIGGGHTS_INSTALL, find_liggghts, run_liggghts, write_deck
from dem.timestep import timestep_for

CASES_DIR = Path(__file__).resolve().parents[1] / "cases"
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
    assert float(mass) == pytest.approx(case.particles.count * grain_mass(case), rel=1e-6)
