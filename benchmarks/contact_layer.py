"""Influence of the SMFEM contact layer's stiffness and thickness on the rod impact (nu = 0).

    python benchmarks/contact_layer.py

For each layer (Young's modulus as a multiple of E, thickness h) prints the errors against 1-D
rod theory: mid-length stress over its plateau, contact duration, rebound velocity, the energy
change over the impact, the largest layer compression (in thicknesses), state iterations per
step and factorizations; or the error the run reported.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case
from smfem.solver import solve


def errors(case, r) -> dict:
    th = case.references["rod_theory"]
    a, b = th["t_mid_stress"]
    plateau = (r.t > a + 0.1 * (b - a)) & (r.t < b - 0.1 * (b - a))
    first, last = r.info["contact_window"]
    return {
        "plateau": r.history["mid_szz"][plateau].mean() / th["stress"] - 1,
        "duration": (last - first + case.dt) / (th["t_contact"][1] - th["t_contact"][0]) - 1,
        "rebound": r.history["rod_vz"][-1] / th["rebound_velocity"] - 1,
        "energy": r.info["energy_after"] / r.info["energy_before"] - 1,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    window = {"t_end": 2e-5} if args.tiny else {}
    print("E_l/E     h (m)   k=E_l/h (Pa/m)  plateau  duration  rebound  energy   compression  it mean/max  fact  cpu s")
    for thickness in (1e-4,) if args.tiny else (1e-4, 1e-3):
        for factor in (1.0,) if args.tiny else (0.003, 0.01, 0.03, 0.1, 0.3, 1.0):
            case = get_case("rod_impact", {"nu": 0.0, "layer_stiffness": factor, "layer_thickness": thickness, **window})
            t0 = time.process_time()
            r = solve(case, with_fields=False)
            cpu = time.process_time() - t0
            k = factor * case.material.E / thickness
            head = f"{factor:<8g}  {thickness:<6g}  {k:<14.3g}"
            if not r.converged:
                print(f"{head}  reported: {r.message}")
                continue
            if args.tiny:  # a few steps: no plateau, no rebound yet
                print(f"{head}  converged, {len(r.iterations)} steps, cpu {cpu:.2f}")
                continue
            e = errors(case, r)
            print(f"{head}  {e['plateau']:+7.2%}  {e['duration']:+7.2%}  {e['rebound']:+7.2%}  {e['energy']:+7.3%}  "
                  f"{r.info['max_layer_compression']:11.3g}  {r.info['iterations_mean']:5.2f}/{r.info['iterations_max']:<4d}  "
                  f"{r.info['factorizations']:4d}  {cpu:5.2f}")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    np.set_printoptions(precision=4)
    main()
