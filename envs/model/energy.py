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

from .layout import P_A0, P_H, P_KA, P_KAPPA, P_KC, P_KR, P_TAU, P_TH0

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


@njit(cache=True, error_model="numpy", _nrt=False)
def fan_energy(x, n, prm):
    """Total energy of the fan and the two finger joints [scaled]."""
    e = 0.0
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        qx, qy = x[2 * i], x[2 * i + 1]
        e += spring_energy(qx, qy, kr, 1.0)
        e += spring_energy(x[2 * i1] - qx, x[2 * i1 + 1] - qy, kc, h)
    for j in range(2):
        e += joint_energy(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0:
        for i in range(n):
            i1 = i + 1 if i + 1 < n else 0
            e += area_energy(fan_area(x[2 * i], x[2 * i + 1], x[2 * i1], x[2 * i1 + 1]),
                             prm[P_KA], prm[P_A0])
    return e


@njit(cache=True, error_model="numpy", _nrt=False)
def fan_gradient(x, n, prm, grad):
    """Add the gradient of :func:`fan_energy` to ``grad`` (natural order)."""
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    for i in range(n):
        qx, qy = x[2 * i], x[2 * i + 1]
        f = spring_force(qx, qy, kr, 1.0)
        grad[2 * i] += f * qx
        grad[2 * i + 1] += f * qy
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        dx, dy = x[2 * i1] - x[2 * i], x[2 * i1 + 1] - x[2 * i + 1]
        f = spring_force(dx, dy, kc, h)
        grad[2 * i] -= f * dx
        grad[2 * i + 1] -= f * dy
        grad[2 * i1] += f * dx
        grad[2 * i1 + 1] += f * dy
    for j in range(2):
        grad[2 * n + j] += joint_gradient(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0:
        for i in range(n):
            i1 = i + 1 if i + 1 < n else 0
            xi, yi, xj, yj = x[2 * i], x[2 * i + 1], x[2 * i1], x[2 * i1 + 1]
            f = 0.5 * area_slope(fan_area(xi, yi, xj, yj), prm[P_KA], prm[P_A0])
            grad[2 * i] += f * yj
            grad[2 * i + 1] -= f * xj
            grad[2 * i1] -= f * yi
            grad[2 * i1 + 1] += f * xi


def energy_scaled(x: np.ndarray, params: np.ndarray, n: int) -> float:
    """:func:`fan_energy` of a state, from Python (float64 copies)."""
    return float(fan_energy(np.ascontiguousarray(x, dtype=np.float64), int(n),
                            np.ascontiguousarray(params, dtype=np.float64)))


def gradient_scaled(x: np.ndarray, params: np.ndarray, n: int) -> np.ndarray:
    """Gradient of :func:`energy_scaled`, a new array."""
    grad = np.zeros(2 * int(n) + 2)
    fan_gradient(np.ascontiguousarray(x, dtype=np.float64), int(n),
                 np.ascontiguousarray(params, dtype=np.float64), grad)
    return grad
