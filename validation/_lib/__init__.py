"""What every validation study needs and used to copy: one place for the studies' scaffolding.

The studies run as scripts (``python validation/<study>/run.py``) and import this package after
putting the repository root on ``sys.path`` (two lines at the top of each script):

- :mod:`validation._lib.header`: the provenance header of result files (JSON and CSV), from
  :mod:`dem.provenance`;
- :mod:`validation._lib.cycles`: drive-cycle edges (steps per cycle, the step ending each cycle)
  and per-cycle means of a per-step series;
- :mod:`validation._lib.replicas`: statistics of independent replicas (seeds) and of per-cycle
  series (correlated standard error), and the difference of two results in standard errors;
- :mod:`validation._lib.tables`: a study's CSV rows, written with their header and read back;
- :mod:`validation._lib.pair`: the dem-and-reference pair runner of the LIGGGHTS studies (one
  configuration through ``dem.run.runner.run_case`` and through its LIGGGHTS deck).
"""
