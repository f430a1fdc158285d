"""The GPU engine on numba.cuda: the engine, its buffers, its step schemes, replicas.

:mod:`dem.engine.gpu.engine` holds :class:`~dem.engine.gpu.engine.GpuEngine` (the engine door's
contract, :class:`dem.engine.door.Engine`), :mod:`~dem.engine.gpu.buffers` the device arrays and
their copies, :mod:`~dem.engine.gpu.schemes` which step kernel a call runs, and
:mod:`~dem.engine.gpu.replicas` many scenes stepped as one. numba.cuda is imported when an engine
is made, not with this package.
"""
