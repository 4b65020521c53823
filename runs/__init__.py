"""The run layer: one call for every solver (:mod:`runs.registry`), the record it returns
(:class:`cases.result.RunResult`), the files a run writes (:mod:`runs.files`), plastic zones
(:mod:`runs.zones`, :mod:`runs.figures`) and the one error measure (:mod:`runs.errors`).

Imports the solvers (``smfem``, ``reference_fem``) and ``cases``; nothing above.
"""
