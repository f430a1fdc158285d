"""Physics written once in plain Python.

The drive, the eps_t mapping, the contact-law registry, per-cycle statistics.
"""
