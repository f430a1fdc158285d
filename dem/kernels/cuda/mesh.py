"""Trough meshes on the GPU: the CPU engine's mesh contacts compiled from the same source.

The CPU's mesh functions (:mod:`dem.kernels.mesh`: closest points, the cell index, the rule
against counting a contact twice, the slot matching that carries a spring from triangle to
triangle, and the contact law's history wrapper :func:`dem.kernels.contact.contact_force`) take
arrays, which numba's CUDA simulator cannot pass into CPU-compiled code:
:func:`dem.kernels.cuda.source.device` compiles each of them a second time, as a CUDA device
function, from its Python source. One definition of each: in the simulator the CPU's operations
in its order (the same bits), on a GPU compiled by numba-cuda from the same code.

:func:`mesh_walls` is the entry: sphere i's mesh contacts added to its force and torque, its
``MESH_SLOTS`` slot rows updated in place (a thread owns its sphere's rows; no other reads them).
"""

from __future__ import annotations

from dem.kernels import mesh as _cpu
from dem.kernels.contact import force as _contact
from dem.kernels.cuda.source import device

closest_point = device(_cpu.closest_point)
cell_of = device(_cpu.cell_of)
counted = device(_cpu.counted, closest_point=closest_point)
mesh_contact = device(_cpu.mesh_contact, closest_point=closest_point, counted=counted)
contact_force = device(_contact.contact_force)
mesh_forces = device(_cpu.mesh_forces, mesh_contact=mesh_contact, contact_force=contact_force)
cell_list = device(_cpu.cell_list, cell_of=cell_of)
mesh_walls = device(_cpu.mesh_walls, cell_list=cell_list, mesh_forces=mesh_forces)
