"""Energy terms of the model, each written once with its value, gradient and Hessian.

Scaled units (lengths / r, stiffness / (s E t), torques / (s E t r^2)); state
``x = (q_0 .. q_N-1, theta_R, theta_L)`` with ``q_i`` the contour points relative to the pinned
centre. The compiled solver assembles its Newton matrix from these primitives; the Python side
(energies of results, the baselines) calls :func:`fan_energy` and :func:`fan_gradient`.

Terms
-----
* spring (radial: centre to ``q_i``, rest length 1; contour: ``q_i`` to ``q_i+1``, rest ``h``):
  ``k/2 (L - L0)^2``, geometrically exact;
* joint (each finger): actuation ``tau theta`` plus torsion spring ``kappa/2 (theta - theta0)^2``
  (``tau`` closes the finger: the energy falls as ``theta`` falls);
* area (each fan triangle centre, ``q_i``, ``q_i+1``, when ``k_A > 0``): ``k_A A0 / 2
  (ln(A / A0))^2`` with ``A`` the signed area (counter-clockwise positive) and ``A0`` its rest
  value; infinite for ``A <= 0``, so a solver that keeps the energy finite keeps every triangle
  unfolded (CONVENTIONS.md, model family).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .layout import P_KA, P_KAPPA, P_RINGS, P_TAU, P_TH0
from .rings import (
    edge_constants,
    edge_ends,
    kernel_params,
    n_edge_types,
    n_state,
    n_tri_types,
    point_dof,
    point_xy,
    tri_corners,
    tri_rest_area,
)

__all__ = [
    "bulk_modulus_2d",
    "area_energy",
    "area_slope",
    "area_curvature",
    "fan_area",
    "spring_energy",
    "spring_force",
    "spring_hessian",
    "joint_energy",
    "joint_gradient",
    "tri_area",
    "mesh_energy",
    "mesh_gradient",
    "folded_triangles",
    "fan_energy",
    "fan_gradient",
]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def spring_energy(dx, dy, k, rest):
    """``k/2 (L - rest)^2`` of a spring whose end-to-end vector is ``(dx, dy)``."""
    length = math.sqrt(dx * dx + dy * dy)
    return 0.5 * k * (length - rest) ** 2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def spring_force(dx, dy, k, rest):
    """Coefficient ``f = k (L - rest) / L``: the energy's gradient with respect to the spring's
    end point is ``f (dx, dy)`` (minus that at its start)."""
    length = math.sqrt(dx * dx + dy * dy)
    return k * (length - rest) / length


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def spring_hessian(dx, dy, k, rest, psd):
    """2x2 block ``K = (kxx, kyy, kxy)`` of the spring's Hessian (``[[K, -K], [-K, K]]`` over its
    two ends). ``psd`` drops the negative transverse stiffness of a compressed spring (a
    convexified matrix for the interior point's fallback)."""
    length = math.sqrt(dx * dx + dy * dy)
    ux, uy = dx / length, dy / length
    tt = k * (1.0 - rest / length)
    if psd and tt < 0.0:
        tt = 0.0
    return (k * ux * ux + tt * (1.0 - ux * ux), k * uy * uy + tt * (1.0 - uy * uy),
            k * ux * uy - tt * ux * uy)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def bulk_modulus_2d(youngs_modulus, poisson_ratio):
    """Plane-strain 2-D bulk modulus ``lambda + mu = E / (2 (1 + nu) (1 - 2 nu))`` [Pa]."""
    return youngs_modulus / (2.0 * (1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def fan_area(xi, yi, xj, yj):
    """Signed area of the fan triangle (centre, q_i, q_j) (counter-clockwise positive); its
    gradient is ``(yj, -xj, -yi, xi) / 2`` over ``(xi, yi, xj, yj)``."""
    return 0.5 * (xi * yj - yi * xj)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def area_energy(area, k_area, rest_area):
    """``k_A A0 / 2 (ln(A / A0))^2``; infinite for a folded (``A <= 0``) triangle."""
    if not area > 0.0:
        return math.inf
    log_ratio = math.log(area / rest_area)
    return 0.5 * k_area * rest_area * log_ratio * log_ratio


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def area_slope(area, k_area, rest_area):
    """``dE/dA = k_A A0 ln(A / A0) / A`` of :func:`area_energy`."""
    return k_area * rest_area * math.log(area / rest_area) / area


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def area_curvature(area, k_area, rest_area):
    """``d2E/dA2 = k_A A0 (1 - ln(A / A0)) / A^2`` of :func:`area_energy`."""
    return k_area * rest_area * (1.0 - math.log(area / rest_area)) / (area * area)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def joint_energy(theta, tau, kappa, theta0):
    """Actuation and torsion-spring energy of one finger; its Hessian is ``kappa``."""
    return tau * theta + 0.5 * kappa * (theta - theta0) ** 2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def joint_gradient(theta, tau, kappa, theta0):
    """Derivative of :func:`joint_energy` with respect to the finger angle."""
    return tau + kappa * (theta - theta0)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def tri_area(xa, ya, xb, yb, xc, yc):
    """Signed area of the triangle (a, b, c) (counter-clockwise positive). Its gradient over
    corner a is ``((yb - yc), (xc - xb)) / 2`` (cyclically for b, c) and its second derivative
    ``d2A / dx_u dy_v = +1/2`` when v follows u (a -> b -> c -> a), ``-1/2`` when it precedes."""
    return 0.5 * ((xb - xa) * (yc - ya) - (xc - xa) * (yb - ya))


@njit(cache=True, error_model="numpy", _nrt=False)
def mesh_energy(x, n, prm):
    """Total energy of the disk's point mesh (springs, area energy) and the two finger joints
    [scaled]; ``prm`` is the kernels' copy with the ring table (:mod:`envs.model.rings`)."""
    m = int(prm[P_RINGS])
    e = 0.0
    ne = n_edge_types(m)
    for i in range(n):
        for t in range(ne):
            ka, ia, kb, ib = edge_ends(t, i, n, m)
            xa, ya = point_xy(x, n, m, prm, ka, ia)
            xb, yb = point_xy(x, n, m, prm, kb, ib)
            k, rest = edge_constants(prm, t, i, n, m)
            e += spring_energy(xb - xa, yb - ya, k, rest)
    for j in range(2):
        e += joint_energy(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0:
        for t in range(n_tri_types(m)):
            for i in range(n):
                ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
                xa, ya = point_xy(x, n, m, prm, ka, ia)
                xb, yb = point_xy(x, n, m, prm, kb, ib)
                xc, yc = point_xy(x, n, m, prm, kc, ic)
                e += area_energy(tri_area(xa, ya, xb, yb, xc, yc), prm[P_KA],
                                 tri_rest_area(prm, t, i, m))
    return e


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _add2(grad, d, gx, gy):
    """Add ``(gx, gy)`` to the gradient of the point whose x row is ``d`` (fixed: d < 0)."""
    if d >= 0:
        grad[d] += gx
        grad[d + 1] += gy


@njit(cache=True, error_model="numpy", _nrt=False)
def mesh_gradient(x, n, prm, grad):
    """Add the gradient of :func:`mesh_energy` to ``grad`` (state order)."""
    m = int(prm[P_RINGS])
    for t in range(n_edge_types(m)):
        for i in range(n):
            ka, ia, kb, ib = edge_ends(t, i, n, m)
            xa, ya = point_xy(x, n, m, prm, ka, ia)
            xb, yb = point_xy(x, n, m, prm, kb, ib)
            k, rest = edge_constants(prm, t, i, n, m)
            dx, dy = xb - xa, yb - ya
            f = spring_force(dx, dy, k, rest)
            _add2(grad, point_dof(n, m, ka, ia), -(f * dx), -(f * dy))
            _add2(grad, point_dof(n, m, kb, ib), f * dx, f * dy)
    for j in range(2):
        grad[2 * n + j] += joint_gradient(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0:
        for t in range(n_tri_types(m)):
            for i in range(n):
                ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
                xa, ya = point_xy(x, n, m, prm, ka, ia)
                xb, yb = point_xy(x, n, m, prm, kb, ib)
                xc, yc = point_xy(x, n, m, prm, kc, ic)
                f = 0.5 * area_slope(tri_area(xa, ya, xb, yb, xc, yc), prm[P_KA],
                                     tri_rest_area(prm, t, i, m))
                _add2(grad, point_dof(n, m, ka, ia), f * (yb - yc), f * (xc - xb))
                _add2(grad, point_dof(n, m, kb, ib), f * (yc - ya), f * (xa - xc))
                _add2(grad, point_dof(n, m, kc, ic), f * (ya - yb), f * (xb - xa))


@njit(cache=True, error_model="numpy", _nrt=False)
def folded_triangles(x, n, prm):
    """Number of mesh triangles turned over (signed area <= 0) in state ``x``."""
    m = int(prm[P_RINGS])
    count = 0
    for t in range(n_tri_types(m)):
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            xa, ya = point_xy(x, n, m, prm, ka, ia)
            xb, yb = point_xy(x, n, m, prm, kb, ib)
            xc, yc = point_xy(x, n, m, prm, kc, ic)
            if tri_area(xa, ya, xb, yb, xc, yc) <= 0.0:
                count += 1
    return count


# the paper's fan is the one-ring member of the mesh family: one implementation serves both
fan_energy = mesh_energy
fan_gradient = mesh_gradient


def energy_scaled(x: np.ndarray, params: np.ndarray, n: int) -> float:
    """:func:`mesh_energy` of a state, from Python (float64 copies; ``params`` a packed row)."""
    return float(mesh_energy(np.ascontiguousarray(x, dtype=np.float64), int(n),
                             kernel_params(params, int(n))))


def gradient_scaled(x: np.ndarray, params: np.ndarray, n: int) -> np.ndarray:
    """Gradient of :func:`energy_scaled`, a new array."""
    prm = kernel_params(params, int(n))
    grad = np.zeros(n_state(int(n), int(prm[P_RINGS])))
    mesh_gradient(np.ascontiguousarray(x, dtype=np.float64), int(n), prm, grad)
    return grad
