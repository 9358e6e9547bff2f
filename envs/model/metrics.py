"""Deformation measures of a state of the fan, compiled (they run on every solved grasp).

Peak deformation per CONVENTIONS.md: the largest ``|L - L0| / L0`` over the radial and contour
springs, and the largest contour-point displacement over r.
"""

from __future__ import annotations

import math

from numba import njit

from .energy import fan_energy
from .geometry import rest_point
from .layout import P_H, P_PHASE

__all__ = ["M_PEAK_STRAIN", "M_DISPLACEMENT", "M_ENERGY", "M_INVERTED", "N_METRICS",
           "state_metrics"]

# metric vector layout
M_PEAK_STRAIN = 0  # max |spring strain| [-]
M_DISPLACEMENT = 1  # max contour-point displacement / r [-]
M_ENERGY = 2  # total energy [scaled: s E t r^2]
M_INVERTED = 3  # fan triangles (centre, q_i, q_i+1) turned over
N_METRICS = 4


@njit(cache=True, error_model="numpy", _nrt=False)
def state_metrics(x, n, prm, out):
    """Fill ``out`` (layout ``M_*``) for the scaled state ``x`` of one grasp."""
    h = prm[P_H]
    peak = 0.0
    disp = 0.0
    inverted = 0
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        qx, qy = x[2 * i], x[2 * i + 1]
        peak = max(peak, abs(math.sqrt(qx * qx + qy * qy) - 1.0))
        dx, dy = x[2 * i1] - qx, x[2 * i1 + 1] - qy
        peak = max(peak, abs(math.sqrt(dx * dx + dy * dy) / h - 1.0))
        cx, cy = rest_point(i, n, prm[P_PHASE])
        ux, uy = qx - cx, qy - cy
        disp = max(disp, math.sqrt(ux * ux + uy * uy))
        if qx * x[2 * i1 + 1] - qy * x[2 * i1] <= 0.0:
            inverted += 1
    out[M_PEAK_STRAIN] = peak
    out[M_DISPLACEMENT] = disp
    out[M_ENERGY] = fan_energy(x, n, prm)
    out[M_INVERTED] = inverted
