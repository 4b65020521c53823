"""Several materials in one body: the material of each element of a reference mesh.

A case's regions (:class:`cases.geometry.Region`) are the parts of its section made of their own
material; ``case.materials`` lists them, index 0 the case's ``material`` (outside every region).
Every per-element array of the reference (Lame constants and the law at the quadrature points,
density, the CalculiX element sets, the ``region`` cell array) is made from one index per
element, ``materials[index]``; only :func:`element_index`, the lookup of that index, depends on
how a region is given (a parametric box of the mapped block, or a mesh section's physical
surface: the region of the section element an element's centre lies in).
"""

from __future__ import annotations

import numpy as np

from cases.params import UnsupportedCase

from .frames import section_of


def element_centres(mesh) -> np.ndarray:
    """Centre nodes of a quadratic mesh's elements, ``(dim, n_elements)`` (the image of the
    reference element's centre, as :func:`reference_fem.mesh.assemble_blocks` keeps them)."""
    return mesh.doflocs[:, mesh.dofs.element_dofs[-1]]


def element_index(case, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Index into ``case.materials`` of elements whose centres have section parameters
    ``(s, t)``, each ``(n_elements,)``; 0 outside every region.

    A direction the mesh leaves out (NaN throughout: a plane-strain ring's axial t, a prism's
    width s) counts as inside every region's range along it, which each region must then span
    (as a cut-out must).
    """
    if case.section.kind == "mesh":  # (s, t) = (x1, x2): the region of the section element each lies in
        sec = case.section
        parent = sec.locate(np.asarray(s, float), np.asarray(t, float))[0]
        return case.material_index(st=sec.x[sec.elements[:, 8]], region_elements=sec.regions)[parent]
    st = []
    for values, axis, which in ((s, case.section.s, "s_range"), (t, case.section.t, "t_range")):
        values = np.asarray(values, float)
        if values.size and np.all(np.isnan(values)):
            if not all(np.allclose(getattr(r, which), axis.span) for r in case.regions):
                raise UnsupportedCase(f"reference solver: a region that does not span the plane-strain "
                                      f"direction of {case.name!r} needs dim=3")
            values = np.full(values.shape, 0.5 * (axis.span[0] + axis.span[1]))
        st.append(values)
    return case.material_index(st=np.column_stack(st))


def mesh_material_index(case, rep: str, mesh, section=None, parent: np.ndarray | None = None) -> np.ndarray:
    """Index into ``case.materials`` of every element of a reference ``mesh`` in
    representation ``rep``, ``(n_elements,)`` (zeros without regions); ``section``, ``parent``:
    a mesh section's quadratic mesh at the case's refinement and the element of it each element
    was made from, whose region it is in."""
    if not case.regions:
        return np.zeros(mesh.nelements, int)
    if parent is not None:
        return case.material_index(st=section.x[section.elements[:, 8]], region_elements=section.regions)[parent]
    return element_index(case, *section_of(case, rep, element_centres(mesh)))


def per_element(materials, index: np.ndarray, name: str) -> np.ndarray:
    """The constant ``name`` (an attribute of each material: ``'rho'``, ``'E'``, ...) of every
    element, ``(n_elements,)``."""
    return np.array([getattr(m, name) for m in materials], float)[index]
