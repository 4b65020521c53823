"""Which sample points a change of the amplitudes could carry out of the law's elastic range.

Within a time step the additional-loads iterations move the amplitudes by less and less, and
most of the body stays elastic: after the step's first iteration has made the trial stress at
every point, a later iterate ``x`` changes it by the stress of ``x - x1``, linear in it. A
bound on that change per section point, over every point along x3 at once, is cheap: each
series of a section dof is at most the sum over the modes of its coefficients' magnitudes
(:meth:`smfem.sampling.DofSeries.bound`), and the stress rows are sparse sums of the series.
Where the first trial's distance to the yield surface (the law's ``headroom``, in the von Mises
stress) exceeds the bound on the change, the point stays elastic whatever ``x`` is, and neither
the synthesis nor the law need visit it (the notched moving load at 120 harmonics: 0.4 % of
the points are left to visit in the iterations after a step's first).
"""

from __future__ import annotations

import numpy as np

#: a point whose headroom is within this share of its bound is visited too (round-off in both)
MARGIN = 1e-9


def von_mises_bound(rows: np.ndarray) -> np.ndarray:
    """An upper bound of the von Mises stress ``sqrt(3 J2)`` of every stress whose Voigt rows
    (6, n) are at most ``rows`` in magnitude (n,)."""
    s1, s2, s3 = rows[0], rows[1], rows[2]
    normal = 0.5 * ((s1 + s2) ** 2 + (s2 + s3) ** 2 + (s3 + s1) ** 2)
    return np.sqrt(normal + 3.0 * (rows[3] ** 2 + rows[4] ** 2 + rows[5] ** 2))


class Screen:
    """The points a change of the amplitudes may carry past the yield surface.

    Parameters
    ----------
    points : the :class:`smfem.sampling.SamplePoints` of the iterations
    """

    def __init__(self, points):
        self.points = points
        self.magnitude = abs(points.to_stress).tocsr()
        _, ne, ng, self.nq = points.point_shape
        largest = np.ones(ne)  # the stiffness factor's largest magnitude along x3, per element
        if len(points.scaled):
            largest[points.scaled] = np.abs(points.factor[points.scaled]).max(axis=1)
        self.factor = np.repeat(largest, ng)

    def change_bound(self, coefficients: np.ndarray) -> np.ndarray:
        """(n_section_points,) a bound of the von Mises stress, at every point along x3 of each
        section point, of the change of the amplitudes whose series have these coefficients
        (:meth:`smfem.sampling.DofSeries.coefficients`)."""
        rows = (self.magnitude @ self.points.series.bound(coefficients)).reshape(6, -1) * self.factor
        return von_mises_bound(rows)

    @staticmethod
    def room(headroom: np.ndarray) -> np.ndarray:
        """The law's ``headroom`` (n_points,) less its share :data:`MARGIN`: what :meth:`at_risk` takes."""
        return headroom - MARGIN * np.abs(headroom)

    def at_risk(self, coefficients: np.ndarray, room: np.ndarray) -> np.ndarray:
        """The flat points, sorted, whose ``room`` (:meth:`room`) a change of the amplitudes
        whose series have these coefficients may use up: every other one stays elastic."""
        bound = self.change_bound(coefficients) * (1 + MARGIN)
        return np.flatnonzero(room.reshape(len(bound), self.nq) <= bound[:, None])
