"""Bed depth as a designer reads it: grain layers, bed height or mass per floor area.

A case gives exactly one of ``particles.count`` and the depths ``particles.layers``,
``particles.bed_height`` and ``particles.mass_per_area``; the others follow from it over the
section's floor area L W (trough length times width) at the solid fraction
:data:`dem.config.BED_PACKING` (phi):

- mass per area M = N m / (L W), exact (m the grain's mass);
- bed height H = N V / (phi L W), V the grain's volume (a clump's union volume);
- layers n = H / d_v, d_v = (6 V / pi)^(1/3) the volume-equivalent diameter (a sphere's own
  diameter; 8.5 mm for the shipped 2.5 g screw, whose head is 7.2 mm across).

Spheres of several types or sizes take V as the mean grain volume by number (and the bed's
density by volume), so a depth gives the count of the mean grain.

A depth gives N = round(...) grains, at least one. Height and layers are nominal: a driven bed
dilates, and elongated grains pack looser than 0.6; the summary reports all three beside the
count, and which one the case gave. A mesh trough has no flat floor of area L W, and a finite
feeder's bed is set by its feed, so both take ``particles.count`` only.
"""

from __future__ import annotations

import math

from dem.config import BED_PACKING
from dem.physics.mass import sphere_volume

#: The depth keys of ``[particles]`` (``count`` is the fourth way to say how much grain).
DEPTHS = ("layers", "bed_height", "mass_per_area")


def grain_volume(particles) -> float:
    """V of one grain, m^3: a sphere's, a clump's union volume, or the mean over grain types.

    Spheres of several types or sizes (``particles.types``): the mean grain volume by number
    (:func:`dem.scene.sizes.mean_volume`), with ``material.density`` their density by volume,
    so that N V rho is the bed's mass.
    """
    if particles.types:
        from dem.scene.sizes import mean_volume

        return mean_volume(particles.types)
    return particles.grain.volume if particles.clumps else sphere_volume(particles.radius)


def layer_thickness(particles) -> float:
    """d_v = (6 V / pi)^(1/3), m: the diameter of the sphere of the grain's volume."""
    return (6.0 * grain_volume(particles) / math.pi) ** (1.0 / 3.0)


def count_for(key: str, value: float, particles, density: float, area: float) -> float:
    """Grains (not yet rounded) that the depth ``key`` = ``value`` puts on ``area`` m^2."""
    volume = grain_volume(particles)
    if key == "mass_per_area":
        return value * area / (density * volume)
    height = value * layer_thickness(particles) if key == "layers" else value
    return height * BED_PACKING * area / volume


def bed(particles, density: float, length: float, width: float) -> dict:
    """The bed as summary.json reports it: count, layers, height, mass per area, and the given."""
    volume = grain_volume(particles)
    area = length * width
    height = particles.count * volume / (BED_PACKING * area)
    given = next((k for k in DEPTHS if getattr(particles, k) is not None), "count")
    return {
        "given": given,
        "count": particles.count,
        "layers": height / layer_thickness(particles),
        "bed_height_m": height,
        "mass_per_area_kg_m2": particles.count * density * volume / area,
        "layer_thickness_m": layer_thickness(particles),
        "packing_assumed": BED_PACKING,
        "floor_area_m2": area,
    }
