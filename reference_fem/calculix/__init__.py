"""CalculiX as a third solver: the reference mesh as an Abaqus/CalculiX input deck
(:mod:`.deck`), ``ccx`` run on it and its results read back as a run (:mod:`.solver`).

CalculiX does its own numerics (serendipity CPE8 / CAX8 / C3D20 elements, its own plasticity,
contact and Newmark); only the mesh, and so the node positions of the probes, is shared with
the reference FEM.
"""

from .deck import Deck, build_deck
from .solver import CCX, CalculixMissing, find_ccx, solve

__all__ = ["CCX", "CalculixMissing", "Deck", "build_deck", "find_ccx", "solve"]
