"""Several deformable bodies in one scene, and the contact pairs between their faces.

A scene of several bodies has one section, a :class:`~cases.msh_section.MeshSection` assembled
from one mapped block per body (:func:`assemble`): the bodies share no nodes (a face of one and
the face of another that touches it are two rows of nodes at the same places), each body is a
named region (its physical surface: a ``body_mean`` probe's ``region``, a material's
:class:`~cases.geometry.Region`), and each block's named edge ``e`` of body ``b`` is the edge
``'b.e'``. Every solver takes it as it takes any mesh section; ``refine = k`` splits each element
k x k, so the two faces of a pair stay node for node at every refinement.

A gmsh mesh section may hold several bodies too (:mod:`cases.msh_section`): physical surfaces
that are connected pieces sharing no node, their physical curves named ``'body.edge'``.

A contact pair (:class:`~cases.geometry.ContactPair`) joins ``face`` of one body to ``other`` of
another. :func:`pair_faces` finds, for every node of ``face``, the node of ``other`` across it
(along the face's outward normal) and the initial gap there; :func:`check_pairs` refuses, in one
line, a pair that names one body twice, a face that is not its body's edge, bodies that are not
separate (one piece), a face that borders nothing (a node of it faces no node of the other face)
and bodies that overlap by more than the pair's stated interference; :func:`check_touching`
refuses bodies of a gmsh section that touch where no pair joins them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .geometry import Section
from .msh_section import MeshSection
from .params import UnsupportedCase
from .section_mesh import block_mesh

#: node positions closer than this (times the section's size) along a face are across each other
ACROSS_TOL = 1e-6
#: the largest clearance of a pair, as a share of its face's length: a face farther from the
#: other borders nothing
MAX_CLEARANCE = 0.1
#: a stated interference is met to this share of the section's size (round-off of the geometry)
OVERLAP_TOL = 1e-9


@dataclass(frozen=True)
class Body:
    """One body of a scene: its name and its cross-section block (named edges for loads,
    supports and contact; the name may hold no ``'.'``)."""

    name: str
    section: Section


def assemble(bodies, path: str = "") -> MeshSection:
    """The section of several bodies: each block's 9-node mesh at its own counts, numbered one
    body after another with no node shared, regions named by body, edges ``'body.edge'``
    (running counter-clockwise round their elements, as a mesh section's do)."""
    names = [b.name for b in bodies]
    if len(bodies) < 2:
        raise UnsupportedCase("a scene of several bodies needs at least two")
    if len(set(names)) != len(names) or any("." in n or not n for n in names):
        raise UnsupportedCase(f"bodies need distinct names without '.': {', '.join(map(repr, names))}")
    xs, elements, edges, owners, regions = [], [], {}, {}, {}
    n_nodes = n_elements = 0
    for body in bodies:
        m = block_mesh(body.section, 1, order=2)
        xs.append(m.x)
        elements.append(m.elements + n_nodes)
        regions[body.name] = n_elements + np.arange(m.n_elements)
        for edge in body.section.edges:
            seg, owner = m.edge_segments(edge)
            if _clockwise(m.x, seg, m.elements[owner]):
                seg, owner = seg[::-1, ::-1], owner[::-1]
            edges[f"{body.name}.{edge}"] = seg + n_nodes
            owners[f"{body.name}.{edge}"] = owner + n_elements
        n_nodes += m.n_nodes
        n_elements += m.n_elements
    return MeshSection(np.concatenate(xs), np.concatenate(elements), 2, edges, owners, regions, path)


def _clockwise(x: np.ndarray, seg: np.ndarray, owner_nodes: np.ndarray) -> bool:
    """Whether the segments run clockwise round their elements (the element to their right)."""
    a, b, c = x[seg[0, 0]], x[seg[0, -1]], x[owner_nodes[0, 8]]
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0


def body_of(edge: str) -> str:
    """The body an edge ``'body.edge'`` belongs to."""
    return edge.split(".", 1)[0]


class FacePairing(NamedTuple):
    """The nodes of a pair's ``face`` and, across each, the node of ``other``.

    ``face``, ``other`` (n,): node ids; ``normal`` (n, 2): the outward unit normal of ``face``
    at its node (the mean of its segments' at a corner); ``gap`` (n,): the initial gap
    ``(x_other - x_face) . normal`` (negative: an overlap).
    """

    face: np.ndarray
    other: np.ndarray
    normal: np.ndarray
    gap: np.ndarray


def node_normals(x: np.ndarray, segments: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nodes of an edge and their outward unit normals, from its segments ``(n_seg, k)``
    (corner, [mid,] corner) and their elements' ``centres`` (n_seg, 2)."""
    nodes, where = np.unique(segments, return_inverse=True)
    where = where.reshape(segments.shape)
    tangent = x[segments[:, -1]] - x[segments[:, 0]]
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    inward = centres - 0.5 * (x[segments[:, -1]] + x[segments[:, 0]])
    normal *= -np.sign(np.einsum("ea,ea->e", normal, inward))[:, None]
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    out = np.zeros((len(nodes), 2))
    np.add.at(out, where, np.repeat(normal[:, None, :], segments.shape[1], axis=1))
    return nodes, out / np.linalg.norm(out, axis=1, keepdims=True)


def pair_faces(mesh, pair) -> FacePairing:
    """The node of ``pair.other`` across every node of ``pair.face`` in a section mesh
    (:class:`cases.section_mesh.SectionMesh`), or :class:`UnsupportedCase` naming a node of the
    face that faces none."""
    x = mesh.x
    size = float(np.abs(x).max()) or 1.0
    sides = []
    for edge in (pair.face, pair.other):
        seg, owner = mesh.edge_segments(edge)
        sides.append(node_normals(x, seg, x[mesh.elements[owner, :4]].mean(axis=1)))
    (face, normal), (other, other_normal) = sides
    d = x[other][None, :, :] - x[face][:, None, :]  # (n_face, n_other, 2)
    along = np.einsum("fok,fk->fo", d, normal)
    sideways = np.linalg.norm(d - along[..., None] * normal[:, None, :], axis=2)
    best = np.argmin(sideways, axis=1)
    missing = np.flatnonzero(sideways[np.arange(len(face)), best] > ACROSS_TOL * size)
    if len(missing) or len(np.unique(best)) != len(best):
        k = missing[0] if len(missing) else int(np.flatnonzero(np.bincount(best) > 1)[0])
        where = x[face[k]] if len(missing) else x[other[k]]
        raise UnsupportedCase(f"contact pair {pair.face} / {pair.other}: the face borders nothing at "
                              f"({where[0]:.6g}, {where[1]:.6g}): no node of {pair.other} lies across that node of "
                              f"{pair.face} alone (the two faces must face each other, meshed node for node)")
    facing = np.einsum("fk,fk->f", normal, other_normal[best])
    if facing.max() > -0.9:
        raise UnsupportedCase(f"contact pair {pair.face} / {pair.other}: the faces do not face each other (their "
                              "outward normals must be opposite)")
    return FacePairing(face, other[best], normal, along[np.arange(len(face)), best])


def check_pairs(case) -> None:
    """Refuse (:class:`UnsupportedCase`, one line) a scene's contact pairs that no solver should
    take: an edge that is not the section's, a pair within one body, a face that is not an
    edge of its body, two bodies that are one piece (they share nodes), a face that borders
    nothing, a gap beyond :data:`MAX_CLEARANCE` of the face, an overlap beyond the pair's stated
    interference, a face in two pairs."""
    section = case.section
    edges = getattr(section, "edges", {})
    bodies = getattr(section, "regions", {})
    seen: set[str] = set()
    for pair in case.contacts:
        name = f"contact pair {pair.face} / {pair.other}"
        for edge in (pair.face, pair.other):
            if edge not in edges or body_of(edge) not in bodies:
                raise UnsupportedCase(f"{case.name}: {name}: {edge!r} is not a face of one of the scene's bodies "
                                      f"(its edges: {', '.join(edges) or 'none'}; a body's edge is named "
                                      "'body.edge')")
            if edge in seen:
                raise UnsupportedCase(f"{case.name}: {name}: the face {edge} is in two contact pairs")
            seen.add(edge)
        if body_of(pair.face) == body_of(pair.other):
            raise UnsupportedCase(f"{case.name}: {name}: both faces are of the body {body_of(pair.face)!r}: a pair "
                                  "joins two bodies")
        _check_separate(case.name, name, section, pair)
        if not (np.isfinite(pair.friction) and pair.friction >= 0 and np.isfinite(pair.interference)
                and pair.interference >= 0):
            raise UnsupportedCase(f"{case.name}: {name}: friction and interference must be finite and >= 0")
        mesh = section.mesh(1, order=1)
        try:
            pairing = pair_faces(mesh, pair)
        except UnsupportedCase as e:
            raise UnsupportedCase(f"{case.name}: {e}") from None
        size = float(np.abs(mesh.x).max())
        length = float(np.ptp(mesh.x[pairing.face], axis=0).max())
        overlap = -float(pairing.gap.min())
        if overlap > pair.interference + OVERLAP_TOL * size:
            raise UnsupportedCase(f"{case.name}: {name}: the bodies overlap by {overlap:.6g} there, more than the "
                                  f"pair's interference {pair.interference:g}: move them apart or state the "
                                  "interference (a shrink fit)")
        if pairing.gap.max() > MAX_CLEARANCE * length:
            raise UnsupportedCase(f"{case.name}: {name}: the faces are {pairing.gap.max():.6g} apart, more than "
                                  f"{MAX_CLEARANCE:.0%} of the face's length: the face borders nothing")


def _check_separate(case_name: str, name: str, section, pair) -> None:
    """Refuse a pair whose two bodies are one piece of the section (a mesh section's bodies
    share no node), or whose faces are not edges of their bodies (physical surfaces)."""
    pieces = [np.unique(section.pieces[section.regions[body_of(e)]]) for e in (pair.face, pair.other)]
    if np.intersect1d(*pieces).size:
        raise UnsupportedCase(f"{case_name}: {name}: the bodies {body_of(pair.face)!r} and {body_of(pair.other)!r} "
                              "are one piece of the mesh (they share nodes): a pair joins separate bodies (gmsh: "
                              "two surfaces that share no curve, without Coherence or fragment)")
    for edge in (pair.face, pair.other):
        owner = section.edge_owner[edge]
        stray = owner[~np.isin(owner, section.regions[body_of(edge)])]
        if len(stray):
            centre = section.x[section.elements[stray[0], 8]]
            raise UnsupportedCase(f"{case_name}: {name}: {edge!r} is not an edge of the body {body_of(edge)!r}: its "
                                  f"element at ({centre[0]:.6g}, {centre[1]:.6g}) is not (put the curve on the "
                                  "boundary of that physical surface)")


def check_touching(case_name: str, section, contacts) -> None:
    """Refuse (:class:`UnsupportedCase`, one line) bodies of a mesh section that touch (nodes at
    one point in two pieces, :attr:`cases.msh_section.MeshSection.touching`) where no contact
    pair's face is: two surfaces meshed apart would otherwise pass through each other, where
    most likely one body was meant (gmsh: Coherence)."""
    touching = section.touching
    if not len(touching):
        return
    faces = [section.edges[e] for p in contacts for e in (p.face, p.other) if e in section.edges]
    on_faces = np.unique(np.concatenate(faces)) if faces else np.empty(0, np.int64)
    loose = np.flatnonzero(~np.all(np.isin(touching, on_faces), axis=1))
    if len(loose):
        a, b = touching[loose[0]]
        elements = [np.argmax(np.any(section.elements == n, axis=1)) for n in (a, b)]
        names = " and ".join(repr(next(n for n, ids in section.regions.items() if e in ids)) for e in elements)
        x1, x2 = section.x[a]
        raise UnsupportedCase(f"{case_name}: the bodies {names} touch at (x1, x2) = ({x1:.6g}, {x2:.6g}) where no "
                              "[[contact]] pair joins them: add a pair of their faces (physical curves 'body.edge'), "
                              "or make them one body (gmsh: Coherence)")
