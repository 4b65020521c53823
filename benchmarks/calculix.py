"""CalculiX against SMFEM and the reference FEM on every case, at equal settings.

    python benchmarks/calculix.py [--tiny] [CASE ...]

Each case at its defaults (2D, refine 1, the case's dt and window): per probe the difference
of each pair of solvers (``smfem.runs.errors.probe_error``: relative max-norm; relative peak
difference for plastic strains, where CalculiX reports PEEQ), and each solver's CPU time.
These are same-dt (spatial and formulation) differences, not errors against a truth: the
report's tables give those. Needs ``ccx`` on PATH.
"""

from __future__ import annotations

import argparse

from cases import CASES, get_case
from cases.params import ToolMissing
from smfem.runs.errors import probe_error
from smfem.runs.registry import CALCULIX, REFERENCE, SMFEM, solve

PAIRS = ((CALCULIX, REFERENCE), (CALCULIX, SMFEM), (SMFEM, REFERENCE))


def compare(name: str, overrides: dict) -> None:
    case = get_case(name, overrides)
    results = {s: solve(s, case) for s in (SMFEM, REFERENCE, CALCULIX)}
    cpu = ", ".join(f"{s} {r.cpu_time_s:.3g} s" for s, r in results.items())
    ccx = results[CALCULIX]
    status = "" if ccx.converged else f" (calculix: {ccx.message})"
    print(f"\n{name} {overrides or ''}: CPU {cpu}; calculix {ccx.info.get('increments')} increments, "
          f"{sum(ccx.iterations)} Newton iterations{status}")
    print(f"  {'probe':12s}" + "".join(f"{a + ' - ' + b:>22s}" for a, b in PAIRS))
    for probe in case.probe_names:
        cells = []
        for a, b in PAIRS:
            ra, rb = results[a], results[b]
            measure, value = probe_error(probe, ra.t, ra.history[probe], rb.t, rb.history[probe])
            cells.append(f"{100 * value:20.2f} %")
        print(f"  {probe:12s}" + "".join(cells))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", default=list(CASES))
    parser.add_argument("--tiny", action="store_true", help="the dome on a short window (seconds)")
    args = parser.parse_args(argv)
    try:
        for name, overrides in [("dome", {"t_end": 5e-5})] if args.tiny else [(n, {}) for n in args.cases]:
            compare(name, overrides)
    except ToolMissing as exc:
        print(f"{exc}\nnothing compared")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
