"""The contact law as named sub-models, as LAMMPS's ``pair granular`` composes them.

A law between two bodies (:class:`Interaction`) is a normal sub-model (:class:`Hertz` or
:class:`Linear`, :mod:`dem.physics.contact.normal`), a damping sub-model that follows from the
normal restitution eps_n (:class:`Damping`), a tangential sub-model (:class:`Coulomb`,
:class:`Liggghts` or :class:`Impact`, :mod:`dem.physics.contact.tangential`), rolling resistance
mu_r, Coulomb friction mu and the lever arms. :class:`ContactLaw` holds one for grain-grain and
one for grain-wall contacts and packs the kernels' parameter array once, at the kernels' door
(:func:`dem.kernels.contact.make_params` is the only code that writes a slot). Everything above
:mod:`dem.physics` asks the law, never the array: its time scales, its stiffer copy, its words
in LAMMPS and LIGGGHTS decks, and :meth:`ContactLaw.report` for summary.json.
"""

from dem.physics.contact.damping import Damping
from dem.physics.contact.law import ContactLaw, Interaction, wall_params
from dem.physics.contact.normal import Hertz, Linear, normal_from_case
from dem.physics.contact.tangential import Coulomb, Impact, Liggghts, tangential_from_case

__all__ = [
    "ContactLaw",
    "Coulomb",
    "Damping",
    "Hertz",
    "Impact",
    "Interaction",
    "Liggghts",
    "Linear",
    "normal_from_case",
    "tangential_from_case",
    "wall_params",
]
