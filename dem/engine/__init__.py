"""The state, the step loop and its checks.

A simulation built from a scene, the finite feeder, the thread guard.
"""
