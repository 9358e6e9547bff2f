"""Deformation measures of a state of the fan, compiled (they run on every solved grasp).

Peak deformation per docs/model.md: the largest ``|L - L0| / L0`` over the radial and contour
springs, and the largest contour-point displacement over r; and, per triangle, the largest
principal logarithmic (Hencky) strain ``max |ln lambda|`` of its constant deformation gradient,
the measure the FEM reference reports.
"""

from __future__ import annotations

import math

from numba import njit

from .energy import folded_triangles, mesh_energy
from .layout import P_RINGS, P_SHAPE, SHAPE_DISK
from .rings import (
    HUB_RADIUS,
    contour_rest_radius,
    edge_constants,
    edge_ends,
    edge_xy,
    n_edge_types,
    n_tri_types,
    point_xy,
    rest_xy,
    ring_rho,
    tri_corners,
)

__all__ = ["M_PEAK_STRAIN", "M_DISPLACEMENT", "M_ENERGY", "M_INVERTED", "M_PEAK_LOG_STRAIN",
           "M_COMPRESSION", "N_METRICS", "state_metrics", "triangle_log_strain"]

# metric vector layout
M_PEAK_STRAIN = 0  # max |spring strain| [-]
M_DISPLACEMENT = 1  # max contour-point displacement / r [-]
M_ENERGY = 2  # total energy [scaled: s E t r^2]
M_INVERTED = 3  # mesh triangles turned over
M_PEAK_LOG_STRAIN = 4  # max over triangles of the largest principal |ln lambda| [-]
# largest shortening of a radius: max over contour points of (r - |p - C|) / r, >= 0 [-]
# (an outline's point: (r_i - |p - C|) / r_i with r_i its own rest distance from the centroid)
M_COMPRESSION = 5
N_METRICS = 6


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def triangle_log_strain(ax, ay, bx, by, px, py, qx, qy):
    """Largest principal ``|ln lambda|`` of the triangle (0, a, b) deformed into (0, p, q).

    The deformation gradient ``F = [p q] [a b]^-1`` is constant on the triangle; the principal
    stretches are the square roots of the eigenvalues of ``C = F^T F``. A folded triangle
    (``det F <= 0``) has no logarithmic strain: infinite. A triangle (a0, a, b) is measured
    with its edges from a0 (the fan's centre is at the origin).
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
def _mesh_log_strain(x, n, m, prm):
    """Largest principal log strain over the mesh's triangles; on a ring mesh outside twice the
    hub radius, where the FEM reference measures it too (the rigid hub concentrates strain
    next to it)."""
    peak = 0.0
    for t in range(n_tri_types(m)):
        if m > 1 and ring_rho(prm, t // 2) < 2.0 * HUB_RADIUS:
            continue
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            ra = rest_xy(prm, n, m, ka, ia)
            rb = rest_xy(prm, n, m, kb, ib)
            rc = rest_xy(prm, n, m, kc, ic)
            pa = point_xy(x, n, m, prm, ka, ia)
            pb = point_xy(x, n, m, prm, kb, ib)
            pc = point_xy(x, n, m, prm, kc, ic)
            peak = max(peak, triangle_log_strain(
                rb[0] - ra[0], rb[1] - ra[1], rc[0] - ra[0], rc[1] - ra[1],
                pb[0] - pa[0], pb[1] - pa[1], pc[0] - pa[0], pc[1] - pa[1]))
    return peak


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _rest_edge(prm, n, m, t, i):
    """Rest length of edge ``i`` of family ``t`` from its ends' rest positions (an outline's
    edges differ around a ring)."""
    ka, ia, kb, ib = edge_ends(t, i, n, m)
    xa, ya = rest_xy(prm, n, m, ka, ia)
    xb, yb = rest_xy(prm, n, m, kb, ib)
    return math.hypot(xb - xa, yb - ya)


@njit(cache=True, error_model="numpy", _nrt=False)
def state_metrics(x, n, prm, out):
    """Fill ``out`` (layout ``M_*``) for the scaled state ``x`` of one grasp (``prm``: the
    kernels' copy with the ring table, :func:`envs.model.rings.kernel_params`)."""
    m = int(prm[P_RINGS])
    disk = prm[P_SHAPE] == SHAPE_DISK
    peak = 0.0
    for t in range(n_edge_types(m)):
        for i in range(n):
            xa, ya, xb, yb = edge_xy(x, n, m, prm, t, i)
            rest = edge_constants(prm, t, i, n, m)[1] if disk else _rest_edge(prm, n, m, t, i)
            dx, dy = xb - xa, yb - ya
            peak = max(peak, abs(math.sqrt(dx * dx + dy * dy) / rest - 1.0))
    disp = 0.0
    compression = 0.0
    for i in range(n):
        ax, ay = rest_xy(prm, n, m, m, i)
        ux, uy = x[2 * i] - ax, x[2 * i + 1] - ay
        disp = max(disp, math.sqrt(ux * ux + uy * uy))
        # the contour points lie on the unit circle about the centre at rest: how far a
        # finger has pushed one in (a rigid turn about the centre does not count); an
        # outline's point at its own rest distance, the shortening relative to it
        now = math.sqrt(x[2 * i] ** 2 + x[2 * i + 1] ** 2)
        if disk:
            compression = max(compression, 1.0 - now)
        else:
            rest = contour_rest_radius(prm, n, m, i)
            compression = max(compression, (rest - now) / rest)
    out[M_PEAK_STRAIN] = peak
    out[M_DISPLACEMENT] = disp
    out[M_ENERGY] = mesh_energy(x, n, prm)
    out[M_INVERTED] = folded_triangles(x, n, prm)
    out[M_PEAK_LOG_STRAIN] = _mesh_log_strain(x, n, m, prm)
    out[M_COMPRESSION] = compression
