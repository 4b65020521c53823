"""The reference's vector element: scikit-fem's ``ElementVector`` whose components share one
evaluation of their scalar function.

The vector function ``dim j + a`` is the scalar function ``j`` along component ``a``; a basis
asks for the functions in order, so the ``dim`` components of one scalar function come one after
another, at the same points: scikit-fem evaluates the scalar function (its values, and its
gradients through the inverse Jacobian) again for each. Here it is kept for the points, elements
and function last asked for, and each component places the same arrays.
"""

from __future__ import annotations

import numpy as np
from skfem import ElementVector
from skfem.element import DiscreteField


class VectorElement(ElementVector):
    """``ElementVector(elem)`` evaluating ``elem``'s function once for its ``dim`` components."""

    _last = None

    def gbasis(self, mapping, X, i, tind=None):
        j, component = divmod(i, self.dim)
        last = self._last
        # the arguments are kept with the field, so their identities stand for their values
        if (last is None or last[3] != j or last[0] is not mapping or last[1] is not X
                or last[2] is not tind):
            last = self._last = (mapping, X, tind, j, self.elem.gbasis(mapping, X, j, tind)[0])
        fields = []
        for field in last[4].astuple:
            if field is None:
                fields.append(None)
            else:
                placed = np.zeros((self.dim,) + field.shape)
                placed[component] = field
                fields.append(placed)
        return (DiscreteField(*fields),)
