"""Verification reports: studies over case x solver x resolution, errors, figures, HTML and PDF.

>>> from reports.build import build
>>> from smfem.studies.plan import quick
>>> report = build(quick(), "out/report")      # what `smfem report` does
>>> report.tables["headline"]

Reads results only; solvers are called through the study runner (:mod:`smfem.studies.study`).
Kept empty of imports: ``smfem run`` loads :mod:`reports.cli`, which must stay light.
"""
