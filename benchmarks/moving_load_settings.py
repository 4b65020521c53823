"""The moving load's dt and harmonics: SMFEM's total error against the stored truth.

    python benchmarks/moving_load_settings.py [--tiny]

``moving_load`` at refine 1 over harmonics 20 ... 120 and dt 4e-6 ... 1e-6 (the scene's 2e-6
in the middle): per setting the largest relative max-norm error of ``mid_uz`` and ``q_uz``
against ``smfem/truths/moving_load`` (interpolated onto the run's times), and the CPU time. The
scene's defaults (dt = 2e-6 s, 60 harmonics) come from this table. ``--tiny``: two settings
against the quick modal truth of a short window (the tests run every benchmark so).
"""

from __future__ import annotations

import argparse

import numpy as np

from cases import get_case
from smfem.runs.registry import MODAL, SMFEM, solve
from smfem.runs.threads import pin

NAME = "moving_load"


def truth_histories(tiny: bool):
    """``(t, {probe: history})`` of the stored truth, or at ``tiny`` the modal model's answer
    over a short window."""
    if tiny:
        run = solve(MODAL, get_case(NAME, {"t_end": 1e-4, "harmonics": 120}))
        return run.t, run.history
    from smfem.studies import stored

    truth = stored.read(stored.directory(NAME))
    return truth.t, truth.values


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="two settings over a short window")
    args = parser.parse_args(argv)
    pin()
    t_ref, ref = truth_histories(args.tiny)
    window = {"t_end": 1e-4} if args.tiny else {}
    settings = [(20, 2e-6), (60, 2e-6)] if args.tiny else [(h, dt) for h in (20, 40, 60, 120) for dt in (4e-6, 2e-6, 1e-6)]
    print(f"{'harmonics':>9} {'dt':>8} {'CPU s':>7}  error (mid_uz, q_uz)")
    for harmonics, dt in settings:
        run = solve(SMFEM, get_case(NAME, {"harmonics": harmonics, "dt": dt, **window}))
        errors = [np.abs(run.history[p] - np.interp(run.t, t_ref, ref[p])).max() / np.abs(ref[p]).max()
                  for p in ("mid_uz", "q_uz")]
        print(f"{harmonics:>9} {dt:>8.1e} {run.cpu_time_s:>7.3f}  " + ", ".join(f"{100 * e:.3f} %" for e in errors))


if __name__ == "__main__":
    main()
