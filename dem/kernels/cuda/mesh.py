"""Trough meshes on the GPU: the CPU engine's mesh contacts compiled from the same source.

The CPU's mesh functions (:mod:`dem.kernels.mesh`: closest points, the cell index, the rule
against counting a contact twice, the slot matching that carries a spring from triangle to
triangle, and the contact law's history wrapper :func:`dem.kernels.contact.contact_force`) take
arrays, which numba's CUDA simulator cannot pass into CPU-compiled code. :func:`device` compiles
each of them a second time, as a CUDA device function, from its Python source, with the
array-taking functions it calls replaced by their device versions; the scalar ones (the contact
law's core, the periodic wrap) it calls as they are. So there is one definition of each: in the
simulator the device versions run the CPU's operations in its order (the same bits), on a GPU
they are compiled by numba-cuda from the same code.

:func:`mesh_walls` is the entry: sphere i's mesh contacts added to its force and torque, its
``MESH_SLOTS`` slot rows updated in place (a thread owns its sphere's rows; no other reads them).
"""

from __future__ import annotations

import types

from numba import cuda

from dem.kernels import mesh as _cpu
from dem.kernels.contact import force as _contact


def device(function, **names):
    """``function`` (a CPU kernel function or its Python source) as a CUDA device function.

    The names in ``names`` (the array-taking functions it calls) are bound to the given device
    functions instead of the CPU's; everything else it refers to is as in its own module.
    """
    py = getattr(function, "py_func", function)
    scope = dict(py.__globals__)
    scope.update(names)
    source = types.FunctionType(py.__code__, scope, py.__name__, py.__defaults__, py.__closure__)
    source.__doc__ = py.__doc__
    return cuda.jit(device=True)(source)


closest_point = device(_cpu.closest_point)
cell_of = device(_cpu.cell_of)
counted = device(_cpu.counted, closest_point=closest_point)
mesh_contact = device(_cpu.mesh_contact, closest_point=closest_point, counted=counted)
contact_force = device(_contact.contact_force)
mesh_forces = device(_cpu.mesh_forces, mesh_contact=mesh_contact, contact_force=contact_force)
cell_list = device(_cpu.cell_list, cell_of=cell_of)
mesh_walls = device(_cpu.mesh_walls, cell_list=cell_list, mesh_forces=mesh_forces)
