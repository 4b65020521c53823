"""Stored truths, one directory per scene: ``smfem/truths/CASE/history.csv`` and ``summary.json``.

``smfem truth CASE --full`` makes them (it may run for hours) and writes them here; nothing
else writes them, and they are never edited by hand. ``summary.json`` carries the key the
truth was made for, a hash of the case's definition and of the truth method
(:mod:`smfem.studies.stored`): the report uses a stored truth only while its key matches, and a test
fails when a scene or the method changes and the stored truth no longer matches.

Beside it, ``smfem/truths/CASE/front.csv``: the scene's measured work-precision points (settings, CPU,
total error against this truth, its key), written by ``smfem report --store-fronts`` only; ``smfem
run --tol`` starts from it while its key is the stored truth's.
"""

from pathlib import Path

#: the directory that holds the stored truths
ROOT = Path(__file__).resolve().parent
