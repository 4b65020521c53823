"""Orchestration: what to run and running it, between the runs and the documents.

A study's plan (:mod:`studies.plan`), its jobs and their execution on local processes or a
dask cluster (:mod:`studies.jobs`, :mod:`studies.executors`), the run cache
(:mod:`studies.cache`), the study runner (:mod:`studies.study`), the truths built from
ladders of runs or stored with the project (:mod:`studies.truth`, :mod:`studies.stored`,
:mod:`studies.calibration`), the error estimates' effectivity (:mod:`studies.effectivity`) and
the metrics against a truth (:mod:`studies.metrics`). ``reports/`` turns their results into
tables, figures and documents; this package writes no document.
"""
