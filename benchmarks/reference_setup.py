"""The reference FEM's set-up: its consistent mass and stiffness as assembled, against the forms
they replaced.

    python benchmarks/reference_setup.py [--runs thick_cylinder:3:2 ...] [--tiny]

Per model (scene, dim, refine; B-bar on the notched scenes, as the reports run them), CPU
seconds (one thread) of: the mass element by element from the scalar element's functions (read
off the vector basis), one copy per component, against skfem's vector form ``rho u . v``; the
stiffness per pair of nodes (:func:`reference_fem.forms.stiffness`: the scalar gradients'
products, B-bar's the strains') against the sparse product ``B' (w D B)``; each pair's largest
difference relative to the largest entry.
"""

from __future__ import annotations

import argparse
import time

from smfem.runs.threads import pin

pin()

import numpy as np  # noqa: E402
from skfem import BilinearForm, asm  # noqa: E402
from skfem.helpers import dot  # noqa: E402

from cases import get_case  # noqa: E402
from reference_fem import forms  # noqa: E402
from reference_fem.mass import consistent_mass  # noqa: E402
from reference_fem.model import AXISYMMETRIC, Model  # noqa: E402

RUNS = ("thick_cylinder:3:2", "rod_impact:3:1", "notched_strip:3:1", "layered_cylinder:3:1", "notched_cylinder:2:2")


@BilinearForm
def vector_mass(u, v, w):
    """The consistent mass as the vector form gives it (the form the scalar one replaced)."""
    return w.rho * dot(u, v) * w.weight


def _timed(f):
    t = time.process_time()
    out = f()
    return out, time.process_time() - t


def _difference(a, b) -> float:
    return float(abs(a - b).max() / abs(b).max())


def measure(name: str, dim: int, refine: int, sets: dict | None = None) -> dict:
    case = get_case(name, {"dim": dim, "refine": refine, **(sets or {})})
    model = Model(case, bbar=name.startswith("notched"))
    basis, axisymmetric = model.basis, model.rep == AXISYMMETRIC
    radius = np.asarray(basis.global_coordinates())[0] if axisymmetric else np.ones(basis.dx.shape)
    rho = case.material.rho
    scalar, t_scalar = _timed(lambda: consistent_mass(basis, rho, axisymmetric))
    vector, t_vector = _timed(lambda: asm(vector_mass, basis, rho=rho, weight=radius).tocsr())
    by_element, t_element = _timed(model.stiffness)
    product, t_product = _timed(lambda: (model.B.T @ (forms.material_blocks(model.D, model.stiffness_weights())
                                                       @ model.B)).tocsr())
    return {"model": f"{name} {dim}D r{refine}", "n_dof": basis.N, "mass_scalar": t_scalar, "mass_vector": t_vector,
            "mass_difference": _difference(scalar, vector), "stiffness_elements": t_element,
            "stiffness_product": t_product, "stiffness_difference": _difference(by_element, product)}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="*", default=RUNS, help="scene:dim:refine")
    parser.add_argument("--tiny", action="store_true", help="the dome in 2D at refine 1")
    args = parser.parse_args(argv)
    runs = ["dome:2:1"] if args.tiny else args.runs
    print(f"{'model':24} {'dofs':>7} {'M scalar':>8} {'M vector':>8} {'M diff':>8} {'K elem':>7} {'K prod':>7} "
          f"{'K diff':>8}")
    for item in runs:
        name, dim, refine = item.split(":")
        r = measure(name, int(dim), int(refine))
        print(f"{r['model']:24} {r['n_dof']:7d} {r['mass_scalar']:8.2f} {r['mass_vector']:8.2f} "
              f"{r['mass_difference']:8.1e} {r['stiffness_elements']:7.2f} {r['stiffness_product']:7.2f} "
              f"{r['stiffness_difference']:8.1e}", flush=True)


if __name__ == "__main__":
    main()
