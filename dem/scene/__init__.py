"""A case and what it resolves to.

The case file, grain shapes, the trough and its mesh, the fill, the time step.
"""
