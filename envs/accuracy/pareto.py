"""Pareto front of (cost, error) points, for the study scripts (:func:`pareto_front`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def pareto_front(costs: Sequence[float], errors: Sequence[float]) -> list[int]:
    """Indices of the non-dominated points when minimising both ``costs`` and ``errors``.

    A point is dominated when another one is no worse in both and better in one. Points with a
    non-finite value are never on the front. The indices are returned by increasing cost.
    """
    c = np.asarray(costs, dtype=float)
    e = np.asarray(errors, dtype=float)
    idx = [i for i in range(len(c)) if math.isfinite(c[i]) and math.isfinite(e[i])]
    front = []
    for i in idx:
        dominated = any(
            c[j] <= c[i] and e[j] <= e[i] and (c[j] < c[i] or e[j] < e[i]) for j in idx
        )
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: (c[i], e[i]))
