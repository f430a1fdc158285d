"""LAMMPS (22 Jul 2025, GRANULAR): a case exported as a ``pair_style granular`` deck, and run.

:mod:`~dem.io.lammps.contact` maps dem's contact law onto LAMMPS's models (or refuses it),
:mod:`~dem.io.lammps.deck` writes the deck and dem's settled fill as its data file,
:mod:`~dem.io.lammps.export` is ``dem export lammps``, and :mod:`~dem.io.lammps.launcher` runs
LAMMPS on the deck and writes its ``summary.json``.
"""
