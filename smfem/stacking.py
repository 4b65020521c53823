"""All modes stacked: the assembled matrices and the timed loads of a model's modes, one after
another in ``model.offsets``."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .linalg import block_diagonal
from .model import Model


def stacked(model: Model):
    """``K``, ``M``, ``Q``, ``V0`` of all modes stacked, and the offsets of each mode.

    Decoupled modes give a block-diagonal ``K`` and a mass diagonal; coupled ones (material
    varying along x3) the whole block system with the mass as a sparse matrix.
    """
    S = model.systems
    offsets = np.cumsum([0] + [s.K.shape[0] for s in S])
    Q, V0 = np.concatenate([s.Q for s in S]), np.concatenate([s.V0 for s in S])
    if not model.coupling:
        return block_diagonal([s.K for s in S]), model.mass_matrix(), Q, V0, offsets
    K = (block_diagonal([s.K for s in S]) + model.coupled_stiffness()).tocsr()
    return K, model.mass_matrix(), Q, V0, offsets


def force_terms(case, model: Model) -> list:
    """The model's timed loads (force terms, pressures with an amplitude or moving) as callables
    ``t -> Q_k(t)``, all modes stacked (:class:`smfem.newmark.Load`)."""
    return [_stacked_term(model, k, term) for k, term in enumerate(model.timed)]


def _stacked_term(model: Model, k: int, term):
    """``t -> S @ factors(t)`` (:meth:`smfem.loads.TimedLoad.factors_of`): column i of ``S`` is mode i's reduced vector in its own rows."""
    blocks = [s.Q_terms[k] for s in model.systems]
    if term.pressure is None:  # one factor for every mode
        Q = np.concatenate(blocks)
        return lambda t: float(term.factor(t)) * Q
    rows = np.concatenate([np.arange(a, b) for a, b in zip(model.offsets[:-1], model.offsets[1:])])
    cols = np.repeat(np.arange(len(blocks)), np.diff(model.offsets))
    S = sp.csr_matrix((np.concatenate(blocks), (rows, cols)), shape=(int(model.offsets[-1]), len(blocks)))
    S.eliminate_zeros()
    factors = term.factors_of(model.modes)
    return lambda t: S @ factors(t)
