"""The assembled finite element model of one case: bases, operators, loads and supports."""

from __future__ import annotations

import functools

import numpy as np
import scipy.sparse as sp
from skfem import ElementHex2, ElementQuad2, asm

from cases.params import UnsupportedCase
from cases.geometry import PRISM, RING

from . import forms, laws, regions, swept, ties
from .element import VectorElement
from .frames import AXISYMMETRIC, SOLID, body_coordinates, body_rotation, in_intervals, section_of, x3_of
from .mass import consistent_mass, lumped_mass, redistributed_mass
from .mesh import RefMesh, build_mesh

#: Gauss rule: 3 points per direction, exact for the stiffness and the consistent mass of
#: straight-sided quadratic elements (the mass also with the axisymmetric factor r)
INTORDER = 4


class Model:
    """Mesh, strain operator, mass, load vector and supported dofs of a case.

    Attributes
    ----------
    case, rmesh : the case and its :class:`~reference_fem.mesh.RefMesh`
    basis : skfem.CellBasis of the vector quadratic element
    B, weights : strain operator ``(n_qp * nc, n_dof)``, made when first read, and weights
        ``(n_qp,)`` (see :func:`reference_fem.forms.strain_operator`); ``bbar``: its volumetric
        part projected per element (:func:`reference_fem.forms.bbar_operator`)
    x_qp : ndarray, ``(dim, n_qp)``, quadrature points in mesh coordinates
    M : csr_matrix, consistent mass (kg, or kg per radian when axisymmetric); with a wall, the
        layer at the wall's face redistributed (:mod:`reference_fem.mass`); ``lumped``: the
        diagonal HRZ mass instead (explicit time stepping), not redistributed
    Q : ndarray, ``(n_dof,)``, load vector of the case's pressures (N; per radian if axisymmetric)
    fixed, free : ndarray of int, supported and free dof indices
    fix_rigid_body : for static solves of rings that are not axisymmetric (no support against
        in-plane rigid-body motion): also fix u_y at the two inner-surface nodes on the x axis
        and u_x at the one on the +y axis, exact for loads symmetric about both axes
    lam, mu : Lame constants of ``case.material`` (Pa)
    material_index : ndarray of int, ``(n_elements,)``, each element's index into
        ``case.materials`` (:mod:`reference_fem.regions`; 0 everywhere without regions)
    law : the material law (:mod:`reference_fem.laws`; with regions a
        :class:`~reference_fem.laws.Regional` one)
    D : elastic Mandel matrix (Pa), ``(nc, nc)``; with regions one per quadrature point,
        ``(n_qp, nc, nc)`` (:func:`reference_fem.forms.elastic_stress` takes either)

    Supports: a support on edge ``'all'`` fixes that component at every node, so in 3D the
    plane-strain direction (u_z of the cylinders, u_width of the strip) is zero on both faces
    and in between (exact plane strain). Prisms also get their diaphragm ends (u1 = u2 = 0 at
    x3 = 0 and L, the Fourier basis's end condition), axisymmetric sections u_r = 0 on the axis.
    """

    def __init__(self, case, rmesh: RefMesh | None = None, fix_rigid_body: bool = False, lumped: bool = False,
                 bbar: bool = False):
        self.case = case
        self.rmesh = rmesh if rmesh is not None else build_mesh(case)
        self.rep = self.rmesh.rep
        mesh = self.rmesh.mesh
        self.dim = mesh.dim()
        scalar = ElementQuad2() if self.dim == 2 else ElementHex2()
        self.element = VectorElement(scalar)
        self.basis = ties.cell_basis(mesh, self.element, intorder=INTORDER)
        axisym = self.rep == AXISYMMETRIC
        self.weights = forms.quadrature_weights(self.basis, axisym)
        self.x_qp = np.asarray(self.basis.global_coordinates()).reshape(self.dim, -1)
        #: ``(dim, n_nodes)``: the nodes of the unknowns (a node tied on the axis once, :mod:`.ties`)
        self.nodes_x = ties.node_positions(mesh)
        #: B-bar's volumetric projection per element, or None (:func:`~reference_fem.forms.volumetric_projection`)
        self.projection = forms.volumetric_projection(self.weights, self.x_qp, self.basis.dx.shape[1]) if bbar else None
        self._free_rows = {}  # a stress probe's point -> its rows of B on the free dofs
        self.lam, self.mu = case.material.lame
        #: each element's index into ``case.materials`` (0 everywhere without regions)
        self.material_index = regions.mesh_material_index(case, self.rep, mesh, self.rmesh.section, self.rmesh.parent)
        # the reference's implementation of the material's law (an unknown one is refused here) and
        # the density: with regions each material's at its own elements (their quadrature points)
        if case.regions:
            points = np.repeat(self.material_index, self.basis.dx.shape[1])
            self.law = laws.regional(case.materials, self.dim, points)
            rho = regions.per_element(case.materials, self.material_index, "rho")
        else:
            self.law, rho = laws.get(case.material, self.dim), case.material.rho
        self.D = self.law.elastic_matrix()
        if (case.variation or case.forces) and (case.material.plastic or case.wall is not None):
            raise UnsupportedCase("reference solver: body forces and a varying material are elastic and without "
                                  "a wall so far")
        if case.wall is not None and any(load.timed for load in case.loads):
            raise UnsupportedCase("reference solver: with a wall, loads are steps held in place (no amplitude, "
                                  "no moving load) so far")
        if case.contacts:
            _refuse_pairs(case)
        #: E and rho's variation along x3 at the quadrature points (n_qp,), or None
        self.factor = case.variation_factor(x3_of(case, self.rep, self.x_qp)) if case.variation else None
        factor = None if self.factor is None else self.factor.reshape(self.basis.dx.shape)
        if lumped:
            self.M = sp.diags(lumped_mass(self.basis, rho, axisym, factor)).tocsr()
        else:
            self.M = consistent_mass(self.basis, rho, axisym, factor)
        if case.wall is not None and not lumped:
            self.M = redistributed_mass(self.M, self.basis, self.edge_facets(case.wall.edge), rho, axisym,
                                        INTORDER)
        if case.contacts and not lumped:  # both faces of every pair: their nodes massless, as at a wall
            faces = np.concatenate([self.edge_facets(e) for pair in case.contacts for e in (pair.face, pair.other)])
            self.M = redistributed_mass(self.M, self.basis, faces, rho, axisym, INTORDER)
        self.Q = self._load_vector()
        #: the loads that vary in time (force terms, then pressures with an amplitude or moving)
        #: as callables ``t -> nodal forces`` (full dofs)
        self.timed_terms = [self._timed(*self.force_vector(term)) for term in case.forces] + \
            [self._timed_pressure(load) for load in case.loads if load.timed]
        self.fixed = self._fixed_dofs()
        if fix_rigid_body and case.body == RING and self.rep != AXISYMMETRIC:
            self.fixed = np.union1d(self.fixed, self._rigid_body_dofs())
        self.free = np.setdiff1d(np.arange(self.basis.N), self.fixed)

    @property
    def n_qp(self) -> int:
        return self.weights.shape[0]

    @functools.cached_property
    def B(self) -> sp.csr_matrix:
        """The strain operator (:func:`~reference_fem.forms.strain_operator`; B-bar's with a
        ``projection``), made when first read: by plastic steps and stresses at every point,
        not by an elastic run, whose probes read their points' rows (:meth:`strain_rows`)."""
        B = forms.strain_operator(self.basis, self.rep == AXISYMMETRIC)
        return B if self.projection is None else forms.bbar_operator(B, self.projection)

    @functools.cached_property
    def free_B(self) -> sp.csr_matrix:
        """:attr:`B`'s columns of the free dofs (the equilibrium systems' strain operator)."""
        return self.B[:, self.free].tocsr()

    def strain_rows(self, q: int) -> sp.csr_matrix:
        """The rows of :attr:`B` at quadrature point ``q``, ``(nc, n_dof)``: of its element
        alone unless ``B`` is made or B-bar's (whose projection is made over the whole mesh)."""
        nc = forms.n_components(self.dim)
        if "B" in self.__dict__ or self.projection is not None:
            return self.B[q * nc:(q + 1) * nc]
        element, k = divmod(q, self.basis.dx.shape[1])
        return forms.strain_operator(self.basis, self.rep == AXISYMMETRIC, element)[k * nc:(k + 1) * nc]

    def free_strain_rows(self, q: int) -> sp.csr_matrix:
        """:meth:`strain_rows` of the free dofs, kept per point (a stress probe reads them every step)."""
        if q not in self._free_rows:
            self._free_rows[q] = self.strain_rows(q)[:, self.free]
        return self._free_rows[q]

    def stiffness(self) -> sp.csr_matrix:
        """Elastic stiffness (N/m, or N/m per radian when axisymmetric)."""
        return forms.stiffness(self.basis, self.rep == AXISYMMETRIC, self.stiffness_weights(), self.D,
                               self.projection)

    def stiffness_times(self, x: np.ndarray) -> np.ndarray:
        """``K x`` (full dofs) without forming ``K``: the stiffness of the elements ``x`` is
        nonzero on (a probe's row of K: a face's few elements)."""
        elements = np.flatnonzero(np.any(x[self.basis.element_dofs] != 0, axis=0))
        points = (elements[:, None] * self.basis.dx.shape[1] + np.arange(self.basis.dx.shape[1])).ravel()
        basis = ties.cell_basis(self.rmesh.mesh, self.element, intorder=INTORDER, elements=elements)
        return forms.stiffness(basis, self.rep == AXISYMMETRIC, self.stiffness_weights()[points],
                               forms.at_points(self.D, points),
                               None if self.projection is None else self.projection[elements]) @ x

    def stiffness_weights(self) -> np.ndarray:
        """The quadrature weights the stiffness integrates with: ``weights`` times the material's
        variation along x3, where the case has one."""
        return self.weights if self.factor is None else self.weights * self.factor

    def edge_facets(self, edge: str) -> np.ndarray:
        """Boundary facets on a named (or parametric) section edge."""
        mesh = self.rmesh.mesh
        facets = mesh.boundary_facets()
        if self.case.section.kind == "mesh":
            return swept.edge_facets(self.case, self.rep, mesh, self.rmesh.section, facets, edge, self.rmesh.parent)
        name = self.case.section.edge(edge)
        axis = self.case.section.s if name[0] == "s" else self.case.section.t
        target = axis.span[0] if name.endswith("min") else axis.span[1]
        s, t = section_of(self.case, self.rep, mesh.p[:, mesh.facets[:, facets].ravel()])
        v = (s if name[0] == "s" else t).reshape(mesh.facets.shape[0], -1)
        size = max(abs(a) for a in axis.span) or 1.0
        found = facets[np.all(np.abs(v - target) < 1e-8 * size, axis=0)]
        if found.size == 0:
            raise ValueError(f"reference solver: edge {edge!r} has no boundary facets")
        return found

    def _facet_midpoints(self, facets: np.ndarray) -> np.ndarray:
        mesh = self.rmesh.mesh
        return mesh.p[:, mesh.facets[:, facets]].mean(axis=1)

    def _facets_where(self, mask_of_points) -> np.ndarray:
        """Boundary facets all of whose vertices satisfy ``mask_of_points(x)``."""
        mesh = self.rmesh.mesh
        facets = mesh.boundary_facets()
        x = mesh.p[:, mesh.facets[:, facets].ravel()]
        return facets[np.all(mask_of_points(x).reshape(mesh.facets.shape[0], -1), axis=0)]

    def load_facets(self, load) -> np.ndarray:
        """Boundary facets a pressure ``load`` acts on (its edge, within its x3 intervals)."""
        facets = self.edge_facets(load.edge)
        if self.rep != AXISYMMETRIC:
            period = 2 * np.pi if self.case.body == RING else None
            return facets[in_intervals(x3_of(self.case, self.rep, self._facet_midpoints(facets)),
                                       load.x3_intervals, period)]
        if not np.isclose(sum(b - a for a, b in load.x3_intervals), 2 * np.pi):
            raise UnsupportedCase("reference solver: a load that is not axisymmetric needs dim=3")
        return facets

    def _load_vector(self, loads=None) -> np.ndarray:
        """The nodal forces of ``loads`` (default: the case's pressures held from t = 0)."""
        Q = np.zeros(self.basis.N)
        for load in [x for x in self.case.loads if not x.timed] if loads is None else loads:
            facets = self.load_facets(load)
            fb = ties.facet_basis(self.rmesh.mesh, self.element, facets=facets, intorder=INTORDER)
            x = np.asarray(fb.global_coordinates())
            weight = x[0] if self.rep == AXISYMMETRIC else np.ones_like(x[0])
            Q += asm(forms.pressure, fb, q=load.q, weight=weight)
        return Q

    @staticmethod
    def _timed(g, F: np.ndarray):
        return lambda t: float(g(t)) * F

    def _timed_pressure(self, load):
        """``t -> nodal forces`` of a pressure with an amplitude or moving along x3."""
        from cases.histories import time_factor

        g = time_factor(load)
        if not load.moving:
            return self._timed(g, self._load_vector((load,)))
        from .moving import MovingPressure

        unit = MovingPressure(self, load)
        return lambda t: (load.q * float(g(t))) * unit(t)

    def force_vector(self, term):
        """A force term's time function and load vector: its pattern at the quadrature points of
        the elements (a body force) or of the edge's boundary facets (a traction), in body
        coordinates and components, turned into the mesh frame."""
        from cases.histories import time_factor
        from cases.manufactured import numeric

        basis = self.basis if term.edge is None else ties.facet_basis(
            self.rmesh.mesh, self.element, facets=self.edge_facets(term.edge), intorder=INTORDER)
        points = np.asarray(basis.global_coordinates())  # (dim, n, n_qp)
        shape, x_qp = points.shape[1:], points.reshape(self.dim, -1)
        x1, x2, x3 = body_coordinates(self.case, self.rep, x_qp)
        f_body = np.array([np.asarray(numeric(c)(x1, x2, x3, 0.0), float) for c in term.pattern])  # (3, n_qp)
        if not np.isfinite(f_body).all():
            raise UnsupportedCase(f"reference solver: the force {term.pattern} varies along a direction "
                                  f"the {self.rep} model leaves out; use dim=3")
        R = body_rotation(self.case, self.rep, x_qp)  # mesh frame -> body, (n_qp, 3, 3)
        f_mesh = np.einsum("nji,jn->in", R, f_body)[: self.dim].reshape((self.dim,) + shape)
        r = points[0] if self.rep == AXISYMMETRIC else np.ones(shape)
        return time_factor(term), asm(forms.body_force, basis, b=f_mesh, weight=r)

    def mesh_components(self, components) -> list[int]:
        """Mesh-frame displacement components (0-based) of body ``components`` (1-based).

        A component the 2D representation has no dof for (the plane-strain direction; the
        hoop displacement of an axisymmetric section) is zero by construction and maps to
        nothing. Radial or hoop alone on a cartesian mesh cannot be expressed as a dof
        constraint and raises ``ValueError``.
        """
        comps = set(components)
        if self.case.body == PRISM:
            table = {1: [1] if self.rep == SOLID else [], 2: [2] if self.rep == SOLID else [1], 3: [0]}
            return sorted(c for k in comps for c in table[k])
        if self.rep == AXISYMMETRIC:
            return sorted({1: 0, 2: 1}[k] for k in comps if k != 3)
        out = []
        if comps & {1, 3}:
            if not {1, 3} <= comps:
                raise UnsupportedCase("reference solver: a radial or hoop support alone is not available "
                                 "on a cartesian mesh")
            out += [0, 1]
        if 2 in comps and self.rep == SOLID:
            out.append(2)
        return out

    def _dofs(self, facets: np.ndarray | None, comps: list[int]) -> np.ndarray:
        """Dofs of mesh components ``comps`` on ``facets`` (all elements when ``None``)."""
        if not comps:
            return np.zeros(0, int)
        if facets is None:
            view = self.basis.get_dofs(elements=np.arange(self.rmesh.mesh.nelements))
        else:
            view = self.basis.get_dofs(facets=facets)
        return np.concatenate([view.all(f"u^{c + 1}") for c in comps])

    def _fixed_dofs(self) -> np.ndarray:
        case = self.case
        fixed = [np.zeros(0, int)]
        for support in case.supports:
            comps = self.mesh_components(support.components)
            facets = None if support.edge == "all" else self.edge_facets(support.edge)
            fixed.append(self._dofs(facets, comps))
        if case.body == PRISM:
            # the prism's Fourier basis is a diaphragm end: u1 = u2 = 0 at x3 = 0 and x3 = L
            for end in (0.0, case.length):
                facets = self._facets_where(lambda x, end=end: np.abs(x3_of(case, self.rep, x) - end) < 1e-9 * case.length)
                fixed.append(self._dofs(facets, self.mesh_components((1, 2))))
        if case.params.get("mirror"):
            # the half ring 0 <= theta <= pi (reference_fem.mesh.ring_span): u_theta = u_y = 0 on its mirror planes
            size = np.abs(self.rmesh.mesh.p).max()
            fixed.append(self._dofs(self._facets_where(lambda x: np.abs(x[1]) < 1e-9 * size), [1]))
        if self.rep == AXISYMMETRIC:
            # regularity on the axis: no radial displacement at r = 0
            size = np.abs(self.rmesh.mesh.p).max()
            facets = self._facets_where(lambda x: np.abs(x[0]) < 1e-9 * size)
            fixed.append(self._dofs(facets, [0]))
        return np.unique(np.concatenate(fixed)).astype(int)

    def _rigid_body_dofs(self) -> np.ndarray:
        p = self.basis.doflocs[:, :: self.dim]
        r = np.hypot(p[0], p[1])
        inner = np.isclose(r, r.min())
        if self.dim == 3:
            inner &= np.isclose(p[2], p[2].min())
        out = []
        for angle, comp in ((0.0, 1), (np.pi, 1), (np.pi / 2, 0)):
            target = r.min() * np.array([np.cos(angle), np.sin(angle)])
            node = int(np.argmin(np.where(inner, np.hypot(p[0] - target[0], p[1] - target[1]), np.inf)))
            out.append(node * self.dim + comp)
        return np.array(out)

    def initial_velocity(self) -> np.ndarray:
        """The case's uniform initial velocity as a full dof vector, zero on supported dofs (m/s):
        of every node, or of the nodes of its ``region`` (a body of a scene of several). The
        body component is turned into the mesh frame at each node (a ring's radial one in 3D
        points away from the axis everywhere); one the 2D representation has no dof for (the
        hoop velocity of an axisymmetric section) is zero by construction."""
        v = np.zeros((self.basis.N // self.dim, self.dim))
        R = None
        for iv in self.case.initial_velocity:
            if R is None:
                R = body_rotation(self.case, self.rep, self.nodes_x)  # mesh frame -> body, per node
            nodes = slice(None) if iv.region is None else self.region_nodes(iv.region, "an initial velocity")
            v[nodes] += iv.value * R[nodes, iv.component - 1, : self.dim]
        v = v.ravel()
        v[self.fixed] = 0.0
        return v

    def region_nodes(self, name: str, what: str = "it") -> np.ndarray:
        """The nodes of the elements of a mesh section's region ``name`` (a body of a scene of
        several); refused in one line (:class:`UnsupportedCase`, naming ``what`` asks for it)
        where the region has none of its own: a mapped block's, or one bonded to the rest of
        the section (sharing nodes with it: a region of another material in one body)."""
        section, parent = self.rmesh.section, self.rmesh.parent
        if section is None or name not in section.regions:
            raise UnsupportedCase(f"reference solver: {what} of region {name!r}: the section has no such region")
        inside = np.isin(parent, section.regions[name])
        nodes_of = lambda mask: np.unique(self.basis.element_dofs[:, mask] // self.dim)  # noqa: E731
        nodes = nodes_of(inside)
        if np.intersect1d(nodes, nodes_of(~inside)).size:
            raise UnsupportedCase(f"reference solver: {what} of region {name!r}: the region is bonded to the rest of "
                                  "the section (shares nodes with it): only a body of its own has a velocity and a "
                                  "mean of its own")
        return nodes

    def nodal_displacement(self, u: np.ndarray) -> np.ndarray:
        """Mesh-frame displacement at the mesh nodes, shape ``(dim, n_nodes)``."""
        return u.reshape(-1, self.dim).T


def _refuse_pairs(case) -> None:
    """Refuse, in one line, the scenes with contact pairs the reference does not solve."""
    if case.wall is not None:
        raise UnsupportedCase("reference solver: a wall and contact pairs in one scene are not available so far")
    if any(getattr(m, "plastic", False) for m in case.materials):
        raise UnsupportedCase("reference solver: contact with plasticity is not available")
    if case.variation or case.forces:
        # the faces' redistributed mass (:mod:`.mass`) takes a density of its own, and a body force's share of a
        # massless face node would have no inertia to meet it (a spurious stress of b h at the face)
        raise UnsupportedCase("reference solver: contact pairs with body forces or a material varying along x3 are "
                              "not available so far")
