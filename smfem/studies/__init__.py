"""Orchestration: what to run and running it, between the runs and the documents.

A study's plan (:mod:`smfem.studies.plan`), its jobs and their execution on local processes or a
dask cluster (:mod:`smfem.studies.jobs`, :mod:`smfem.studies.executors`), the run cache
(:mod:`smfem.studies.cache`), the study runner (:mod:`smfem.studies.study`), the truths built from
ladders of runs or stored with the project (:mod:`smfem.studies.truth`, :mod:`smfem.studies.stored`,
:mod:`smfem.studies.calibration`), the error estimates' effectivity (:mod:`smfem.studies.effectivity`) and
the metrics against a truth (:mod:`smfem.studies.metrics`). ``reports/`` turns their results into
tables, figures and documents; this package writes no document.
"""
