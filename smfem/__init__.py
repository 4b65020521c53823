"""smfem: the semi-analytic finite element method (SMFEM) for bodies of revolution and prisms,
verified against an independent scikit-fem solver.

The public interface (:mod:`smfem.api`)::

    import smfem
    run = smfem.run("thick_cylinder", t_end=2e-4)     # SMFEM with its error estimate
    run.history                                      # pandas DataFrame: t and each probe
    smfem.error(run)                                 # total error against the stored truth

:func:`load`, :func:`run`, :func:`read`, :func:`compare`, :func:`truth`, :func:`error`,
:func:`study`, :func:`report`, :func:`scenes`, :func:`solvers` and :class:`Result`. They are
loaded on first use: the numerics modules (``smfem.model``, ``smfem.solver``, ...) import
without the framework above them.
"""

from smfem.version import __version__

_API = ("Result", "compare", "error", "load", "read", "report", "run", "scenes", "solvers", "study", "truth")
__all__ = ["__version__", *_API]


def __getattr__(name: str):
    if name in _API:
        from smfem import api

        return getattr(api, name)
    raise AttributeError(f"module 'smfem' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_API])
