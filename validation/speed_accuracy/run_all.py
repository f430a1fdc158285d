"""Every speed-accuracy study in one go: all runs in one pool (about 30 min on 2 cores), then
each study's CSV and chart, and summary.md (the cheapest acceptable settings).

    .venv/bin/python validation/speed_accuracy/run_all.py [--figures]
"""

import sys

import contact_model
import ladder
import reference
import resolution
import section
import skin
import stiffness
import timestep
from study import HERE, cached, ensure, plot, print_table, table, write_csv

STUDIES = (reference, timestep, stiffness, contact_model, skin, section, resolution)


def main() -> int:
    if "--figures" not in sys.argv:
        ensure([p for m in STUDIES for p in m.POINTS] + ladder.POINTS)
    rows = cached()
    for m in STUDIES:
        name = m.__name__
        out = table(m.POINTS, rows)
        write_csv(name, out, m.__file__)
        plot(out, HERE / f"{name}.png", (m.__doc__ or name).splitlines()[0])
        print(f"\n== {name}")
        print_table(out)
    sys.argv = [sys.argv[0], "--figures"]
    return ladder.main()


if __name__ == "__main__":
    raise SystemExit(main())
