"""Entry points: :func:`solve` (transient, the case's window) and :func:`static`."""

from __future__ import annotations

import time
from typing import Callable

import meshio
import numpy as np

from cases.params import UnsupportedCase, newmark_only
from cases.recorder import StepRecorder
from cases.result import RunResult

from .equilibrium import Elastic, NotConverged, Plastic
from .linalg import AUTO, PCG_RTOL
from .exact import error_l2
from .frames import AXISYMMETRIC, mesh_frame_to_cartesian, to_cartesian
from .mesh import build_mesh, vtk_cells
from .model import INTORDER, Model
from .newmark import march, newmark_constants
from .pairs import PairLog, case_pair_rows, held_by_supports
from .probes import Probes, mandel_to_tensor
from .zones import snapshot as zone_snapshot
from .wall import ContactLog, WallSystem, case_wall_rows


def _system(model: Model, c: float, linear_solver: str = AUTO):
    if model.case.wall is not None:
        return WallSystem(model, c, case_wall_rows(model))
    if model.case.contacts:  # the wall's system on the pairs' rows (:mod:`.pairs`)
        return WallSystem(model, c, case_pair_rows(model))
    return Plastic(model, c, model.case.params["tol"], linear_solver) if model.law.nonlinear else Elastic(model, c)


def load_history(model):
    """The free dofs' load: the pressures' vector, held from t = 0, or with loads that vary in
    time (force terms, amplitudes, moving pressures) the function ``Q(t)``."""
    Q, free = model.Q[model.free], model.free
    if not model.timed_terms:
        return Q
    return lambda t: Q + sum(term(t)[free] for term in model.timed_terms)


def solve(case, progress: Callable[[int, int], None] | None = None, every: int = 0,
          grading: float = 1.0, linear_solver: str = AUTO, bbar: bool = False, fields: bool = True) -> RunResult:
    """Transient response of ``case`` over its time window, Newmark (alpha 0.25, delta 0.5).

    Parameters
    ----------
    case : cases.Case
    progress : optional ``callable(step, n_steps)`` called after every step
    every : also the field every ``every`` steps, t = 0 included (``frames``; 0: none)
    grading : mesh grading toward the re-entrant corner lines (:func:`~reference_fem.mesh.build_mesh`)
    linear_solver : how Newton's tangents are solved (:mod:`reference_fem.linalg`: ``'auto'``,
        ``'superlu'``, ``'pcg'``)
    bbar : the volumetric strain projected per element (B-bar, as the explicit engine's option):
        nearly incompressible plastic flow does not lock the element (the notched cylinder 2D at
        r1 and r2: 4.3 and 2.9 % from its truth against 6.5 and 4.3 % without)
    fields : the final state as ``mesh`` (False: None, and no stress at every point is made)

    Returns
    -------
    cases.result.RunResult
        ``iterations``: Newton iterations per step (1 for a linear step; with a wall, the
        active-set iterations); ``cpu_time_s``: assembly, factorization and time stepping, mesh
        generation excluded; ``mesh`` (with ``fields``): the final state (cartesian points; point data
        'displacement', 'velocity'; cell data 'stress', the element mean as a cartesian tensor,
        'peps', the element mean, when plastic, and 'region', the element's index into
        ``case.materials``); ``info``: 'dim',
        'representation', 'element', 'n_elements', 'intorder', 'counts' (elements per mesh
        direction), 'factorizations' (of K + a0 M and of tangents), 'linear_solver', in a plastic
        run 'cg_iterations', 'cg_fallbacks' and 'cg_rtol' (CG on the tangents, the tangents
        factorized after CG gave up, CG's relative residual: :mod:`reference_fem.linalg`), 'cpu_mesh_s'; with a wall
        also 'contact_nodes', 'energy_before' and 'energy_after' (kinetic + strain, J, at t = 0
        and at the last step), 'contact_window' (first and last time with a wall force, s, or
        None) and 'max_penetration' (m, over all nodes and steps; 0 if none); with contact pairs
        (:mod:`reference_fem.pairs`) the same, the penetration of the pairs' nodes into each
        other, and 'contact_pairs', 'momentum_before' and 'momentum_after' (``M v`` summed per
        mesh component, kg m/s, times 2 pi when axisymmetric), 'most_nodes_closed',
        'most_nodes_stick' and 'most_nodes_slip' (at any one step); ``snapshots``: 2D plastic runs only, as
        :mod:`reference_fem.zones` makes them

    Raises
    ------
    cases.params.UnsupportedCase
        for scenes the reference solver cannot represent (a 2D form that does not exist for
        the scene; contact with plasticity; a wall facing a face that is not plane; SMFEM's
        ``time_scheme=gauss``).
    """
    newmark_only(case, "reference solver")
    cpu0 = time.process_time()
    rmesh = build_mesh(case, grading)
    cpu_mesh = time.process_time() - cpu0
    cpu1 = time.process_time()
    model = Model(case, rmesh, bbar=bbar)
    dt, n_steps = case.dt, case.n_steps
    system = _system(model, newmark_constants(dt).a0, linear_solver)
    probes = Probes(model)
    free = model.free
    u_full, v_full, a_full = (np.zeros(model.basis.N) for _ in range(3))
    zero, v0 = np.zeros(free.size), model.initial_velocity()[free]
    v_full[free] = v0
    per_radian = model.rep == AXISYMMETRIC
    log = (PairLog(system, per_radian) if case.contacts
           else ContactLog(system, per_radian) if case.wall is not None else None)
    if log:
        log.record(0.0, zero, v0, u_full)
    plastic_2d = case.material.plastic and model.dim == 2  # the zones are drawn in a plane
    recorder = StepRecorder(case, probes.names, every, progress,
                            frame=lambda: output_mesh(model, u_full, system, v_full),
                            snapshot=(lambda t: zone_snapshot(t, model, system)) if plastic_2d else None)
    recorder.record(0, probes.values(u_full, system, v_full))
    try:
        for n, t, u, v, a, its in march(system, load_history(model), zero, v0, dt, n_steps):
            u_full[free], v_full[free], a_full[free] = u, v, a
            row = probes.values(u_full, system, v_full, a_full)
            if log:
                log.record(t, u, v, u_full)
            recorder.record(n, row, its)
    except NotConverged as err:
        step = recorder.done
        recorder.fail(f"step {step} (t = {step * dt:.6g} s) did not converge: {err}")
    cpu = time.process_time() - cpu1
    exact = {} if case.exact is None else {"error_l2": error_l2(model, u_full, case.exact, recorder.last_time)}
    return recorder.result(
        n_dof=int(free.size), cpu_time_s=cpu, mesh=output_mesh(model, u_full, system, v_full) if fields else None,
        info=dict(_info(model, system, cpu_mesh), grading=grading, linear_solver=linear_solver, bbar=bbar,
                  **(log.info() if log else {}), **exact),
    )


def static(case, factors=(1.0,)) -> tuple[Model, list[np.ndarray], list[int], object]:
    """Static solution under the case's loads scaled by each of ``factors`` in turn.

    Plastic cases are loaded incrementally (each factor is one load step, the state carried
    over). In-plane rigid-body motion of rings that are not axisymmetric is removed as in
    :class:`~reference_fem.model.Model` (``fix_rigid_body``). Contact pairs are solved as in a
    time step (:mod:`reference_fem.pairs`, the contact state carried from one factor to the
    next); every body must then be supported on its own (a body held by contact alone has no
    static state here: refused in one line).

    Returns
    -------
    model : Model
    displacements : list of (n_dof,) full dof vectors (m), one per factor
    iterations : Newton iterations per load step
    system : the equilibrium system after the last step (``sigma``, ``peps``)
    """
    if case.wall is not None:
        raise UnsupportedCase("reference solver: contact is transient only (a free body has no static state)")
    model = Model(case, fix_rigid_body=True)
    if model.timed_terms:
        raise UnsupportedCase("reference solver: a static solve takes loads held in place; this case's vary in time")
    if case.contacts:
        held_by_supports(model)
    system = _system(model, 0.0)
    u = np.zeros(model.free.size)
    out, iterations = [], []
    for f in factors:
        u, its = system.solve(f * model.Q[model.free], u)
        full = np.zeros(model.basis.N)
        full[model.free] = u
        out.append(full)
        iterations.append(its)
    return model, out, iterations, system


def output_mesh(model: Model, u_full: np.ndarray, system, v_full: np.ndarray) -> meshio.Mesh:
    """meshio mesh of the quadratic elements with the displacement and velocity (cartesian, 3
    components), the element mean of the stress (a cartesian tensor) and of the equivalent
    plastic strain (plastic runs), and each element's material, ``region`` (its index into
    ``case.materials``: 0 outside every region)."""
    mesh, case, rep = model.rmesh.mesh, model.case, model.rep
    to_frame = mesh_frame_to_cartesian(case, rep)
    vectors = {}
    for name, values in (("displacement", u_full), ("velocity", v_full)):
        x = np.zeros((3, model.nodes_x.shape[1]))
        x[: model.dim] = model.nodal_displacement(values)
        vectors[name] = (to_frame @ x).T
    cell_type, cells = vtk_cells(mesh)
    # the element mean of the stress at its quadrature points, cartesian (9 components: a tensor to ParaView)
    sigma = mandel_to_tensor(system.sigma).reshape(mesh.nelements, -1, 3, 3).mean(axis=1)
    cell_data = {"stress": [(to_frame @ sigma @ to_frame.T).reshape(-1, 9)]}
    if case.material.plastic:
        cell_data["peps"] = [system.peps.reshape(mesh.nelements, -1).mean(axis=1)]
    cell_data["solid"] = [np.ones(mesh.nelements, np.uint8)]  # as SMFEM's field: the cut-outs are not meshed here
    cell_data["region"] = [model.material_index.astype(np.int32)]  # index into case.materials
    return meshio.Mesh(to_cartesian(case, rep, model.nodes_x).T, {cell_type: cells}, point_data=vectors,
                       cell_data=cell_data)


def _info(model: Model, system, cpu_mesh: float) -> dict:
    return {
        "dim": model.dim,
        "representation": model.rep,
        "element": type(model.element.elem).__name__,
        "n_elements": int(model.rmesh.mesh.nelements),
        "intorder": INTORDER,
        "counts": model.rmesh.counts,
        "factorizations": system.factorizations,
        # Newton tangents solved by CG on the elastic factors (reference_fem.linalg)
        **({"cg_iterations": system.cg_iterations, "cg_fallbacks": system.cg_fallbacks, "cg_rtol": PCG_RTOL}
           if hasattr(system, "cg_iterations") else {}),
        "cpu_mesh_s": cpu_mesh,
    }


__all__ = ["solve", "static"]
