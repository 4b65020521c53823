"""The time-integration convention every solver follows (docs/scenes.md, conventions).

Newmark's method with alpha = 0.25, delta = 0.5 (average acceleration), the load on at t = 0 so
that the initial acceleration solves ``M a0 = Q(0) - K u0``. Each solver computes its own
integration constants from these two numbers: the solvers share data, never numerics.
"""

ALPHA, DELTA = 0.25, 0.5
