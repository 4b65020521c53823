"""Loads in time: the factor each load is scaled by at time t, shared by every solver.

A pressure is a step (on at t = 0, held) unless it has an :class:`~cases.geometry.Amplitude`;
a force term is its ``time`` expression times its amplitude. A moving pressure's place changes
too (:meth:`cases.geometry.Pressure.intervals_at`): each solver integrates its own basis over
the covered intervals at each time it needs the load.
"""

from __future__ import annotations

import numpy as np


def _one(t):
    return 1.0 if np.ndim(t) == 0 else np.ones(np.shape(t))


def time_factor(load):
    """``g(t)`` of a pressure or a force term (a float for a float ``t``): its amplitude (1 when
    it has none) times a force's ``time`` expression."""
    amplitude = load.amplitude if load.amplitude is not None else _one
    text = getattr(load, "time", "1")
    if text == "1":
        return amplitude
    from .manufactured import time_function  # sympy: only for a scene whose forces vary in time

    g = time_function(text)
    return lambda t: g(t) * amplitude(t)
