"""The run layer: one call for every solver (:mod:`smfem.runs.registry`), the record it returns
(:class:`cases.result.RunResult`), the files a run writes (:mod:`smfem.runs.files`), plastic zones
(:mod:`smfem.runs.zones`, :mod:`smfem.runs.figures`) and the one error measure (:mod:`smfem.runs.errors`).

Imports the solvers (``smfem``, ``reference_fem``) and ``cases``; nothing above.
"""
