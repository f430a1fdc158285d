"""The state, the step loop and its checks.

A simulation built from a scene, the engine door and its CPU and GPU engines, the finite feeder,
the thread guard.
"""
