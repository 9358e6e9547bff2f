"""Deformation measures of a state of the fan, compiled (they run on every solved grasp).

Peak deformation per CONVENTIONS.md: the largest ``|L - L0| / L0`` over the radial and contour
springs, and the largest contour-point displacement over r; and, per triangle, the largest
principal logarithmic (Hencky) strain ``max |ln lambda|`` of its constant deformation gradient,
the measure the FEM reference reports.
"""

from __future__ import annotations

import math

from numba import njit

from .energy import fan_energy
from .geometry import rest_point
from .layout import P_H, P_PHASE

__all__ = ["M_PEAK_STRAIN", "M_DISPLACEMENT", "M_ENERGY", "M_INVERTED", "M_PEAK_LOG_STRAIN",
           "N_METRICS", "state_metrics", "triangle_log_strain"]

# metric vector layout
M_PEAK_STRAIN = 0  # max |spring strain| [-]
M_DISPLACEMENT = 1  # max contour-point displacement / r [-]
M_ENERGY = 2  # total energy [scaled: s E t r^2]
M_INVERTED = 3  # fan triangles (centre, q_i, q_i+1) turned over
M_PEAK_LOG_STRAIN = 4  # max over triangles of the largest principal |ln lambda| [-]
N_METRICS = 5


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def triangle_log_strain(ax, ay, bx, by, px, py, qx, qy):
    """Largest principal ``|ln lambda|`` of the triangle (0, a, b) deformed into (0, p, q).

    The deformation gradient ``F = [p q] [a b]^-1`` is constant on the triangle; the principal
    stretches are the square roots of the eigenvalues of ``C = F^T F``. A folded triangle
    (``det F <= 0``) has no logarithmic strain: infinite.
    """
    det = ax * by - ay * bx
    # [a b]^-1 = [[by, -bx], [-ay, ax]] / det
    f11 = (px * by - qx * ay) / det
    f12 = (-px * bx + qx * ax) / det
    f21 = (py * by - qy * ay) / det
    f22 = (-py * bx + qy * ax) / det
    if f11 * f22 - f12 * f21 <= 0.0:
        return math.inf
    c11 = f11 * f11 + f21 * f21
    c22 = f12 * f12 + f22 * f22
    c12 = f11 * f12 + f21 * f22
    mean = 0.5 * (c11 + c22)
    rad = math.sqrt(0.25 * (c11 - c22) ** 2 + c12 * c12)
    lo = max(mean - rad, 1e-300)
    return max(abs(0.5 * math.log(mean + rad)), abs(0.5 * math.log(lo)))


@njit(cache=True, error_model="numpy", _nrt=False)
def state_metrics(x, n, prm, out):
    """Fill ``out`` (layout ``M_*``) for the scaled state ``x`` of one grasp."""
    h = prm[P_H]
    peak = 0.0
    disp = 0.0
    inverted = 0
    log_strain = 0.0
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        qx, qy = x[2 * i], x[2 * i + 1]
        ax, ay = rest_point(i, n, prm[P_PHASE])
        bx, by = rest_point(i1, n, prm[P_PHASE])
        log_strain = max(log_strain, triangle_log_strain(ax, ay, bx, by, qx, qy, x[2 * i1],
                                                         x[2 * i1 + 1]))
        peak = max(peak, abs(math.sqrt(qx * qx + qy * qy) - 1.0))
        dx, dy = x[2 * i1] - qx, x[2 * i1 + 1] - qy
        peak = max(peak, abs(math.sqrt(dx * dx + dy * dy) / h - 1.0))
        ux, uy = qx - ax, qy - ay
        disp = max(disp, math.sqrt(ux * ux + uy * uy))
        if qx * x[2 * i1 + 1] - qy * x[2 * i1] <= 0.0:
            inverted += 1
    out[M_PEAK_STRAIN] = peak
    out[M_DISPLACEMENT] = disp
    out[M_ENERGY] = fan_energy(x, n, prm)
    out[M_INVERTED] = inverted
    out[M_PEAK_LOG_STRAIN] = log_strain
