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
  unfolded (docs/model.md, model family);
* constant-strain neo-Hookean triangle (``P_MU > 0``): the FEM reference's energy on each
  linear triangle of the mesh;
* nh-quad (``P_MU > 0``, ``P_LAM = 0``, ``P_QUAD > 0``): each triangle's neo-Hookean energy
  without its volumetric ``lambda`` term, which acts once per quad instead, as the area energy
  of the quad with ``k_A = lambda / E``: ``lambda / 2 (ln J_q)^2`` on the quad's area ratio
  ``J_q``. Per triangle, that term locks the coarse mesh (two constraints per point pair for
  ``nu`` near 1/2); per quad it is one constraint a point, and its stiffening no longer grows
  with ``nu``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .layout import P_KA, P_KAPPA, P_LAM, P_MU, P_QUAD, P_RINGS, P_TAU, P_TH0
from .rings import (
    edge_constants,
    edge_ends,
    edge_xy,
    kernel_params,
    n_edge_types,
    n_state,
    n_tri_types,
    point_dof,
    quad_corners,
    quad_rest_area_at,
    quad_xy,
    rest_xy,
    tri_corners,
    tri_rest_area,
    tri_xy,
)

__all__ = [
    "bulk_modulus_2d",
    "lame_per_e",
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
    "quad_area",
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


def lame_per_e(poisson_ratio):
    """Plane-strain Lame moduli ``(lambda / E, mu / E)`` of a Poisson ratio (a float or an
    array, elementwise)."""
    nu = poisson_ratio
    return nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), 1.0 / (2.0 * (1.0 + nu))


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


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def quad_area(xa, ya, xb, yb, xc, yc, xd, yd):
    """Signed area of the quad (a, b, c, d) (counter-clockwise positive; the shoelace sum,
    equal to its two triangles' areas whichever diagonal cuts it). Its gradient over a corner
    is ``(y_next - y_prev, x_prev - x_next) / 2`` and its second derivatives follow the
    triangle's rule between neighbouring corners (opposite corners: 0)."""
    return 0.5 * ((xa * yb - xb * ya) + (xb * yc - xc * yb) + (xc * yd - xd * yc)
                  + (xd * ya - xa * yd))



# --- constant-strain neo-Hookean triangle (the FEM reference's energy on a linear element) ---


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def cst_rest(qax, qay, qbx, qby, qcx, qcy):
    """Inverse ``(m00, m01, m10, m11)`` of the rest edge matrix ``Dm = [b - a, c - a]`` and the
    rest area of the triangle (a, b, c)."""
    d00, d01, d10, d11 = qbx - qax, qcx - qax, qby - qay, qcy - qay
    det = d00 * d11 - d01 * d10
    return d11 / det, -d01 / det, -d10 / det, d00 / det, 0.5 * det


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _deformation(ds00, ds01, ds10, ds11, m00, m01, m10, m11):
    """``F = Ds Dm^-1`` row by row."""
    return (ds00 * m00 + ds01 * m10, ds00 * m01 + ds01 * m11,
            ds10 * m00 + ds11 * m10, ds10 * m01 + ds11 * m11)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def cst_energy(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam):
    """``A0 W(F)``, ``W = mu/2 (I1 - 2) - mu ln J + lam/2 (ln J)^2`` (plane strain: the
    out-of-plane stretch is 1); infinite for ``J <= 0``. ``Ds`` holds the current edges
    ``[b - a, c - a]`` by rows (x row, y row).

    Evaluated in the displacement gradient ``H = F - I`` free of first-order cancellations,
    as the FEM reference does (:func:`envs.fem.material._neo_hookean`):
    ``I1 - 2 - 2 ln J = (H00 - H11)^2 + (H01 + H10)^2 + 2 (u - ln(1 + u))`` with
    ``u = J - 1 = tr H + det H``. Why: the textbook form subtracts terms of size ``mu A0``
    whose difference is of the order of the strain squared, so each triangle's energy had an
    absolute round-off of about ``eps mu A0`` however small its strain (here: about ``eps``
    times the strain). The interior point's line search compares merit values with a
    round-off allowance relative to the merit; on a contact-free answer the merit is nearly
    zero, the Newton step's last decreases (about 1e-19, scaled) drowned in that noise (about
    5e-18) and the solve crawled into the iteration limit.
    """
    f00, f01, f10, f11 = _deformation(ds00, ds01, ds10, ds11, m00, m01, m10, m11)
    det = f00 * f11 - f01 * f10
    h00 = f00 - 1.0
    h11 = f11 - 1.0
    u = h00 + h11 + (h00 * h11 - f01 * f10)
    # both tests: the two ways to J may round apart where J is within eps of 0
    if not (det > 0.0 and u > -1.0):
        return math.inf
    lnj = math.log1p(u)
    shear = (h00 - h11) ** 2 + (f01 + f10) ** 2
    return a0 * (0.5 * mu * shear + mu * (u - lnj) + 0.5 * lam * lnj * lnj)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _edge_force(p00, p01, p10, p11, m00, m01, m10, m11, a0):
    """``dE/dDs = A0 P Dm^-T`` from the first Piola stress P (rows)."""
    return (a0 * (p00 * m00 + p01 * m01), a0 * (p00 * m10 + p01 * m11),
            a0 * (p10 * m00 + p11 * m01), a0 * (p10 * m10 + p11 * m11))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def cst_gradient(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam):
    """``dE/dDs`` (rows): the gradient over corner b is its column 0, over c its column 1, over
    a minus their sum. ``P = mu F + (lam ln J - mu) F^-T``."""
    f00, f01, f10, f11 = _deformation(ds00, ds01, ds10, ds11, m00, m01, m10, m11)
    det = f00 * f11 - f01 * f10
    c = (lam * math.log(det) - mu) / det
    # F^-T = [[f11, -f10], [-f01, f00]] / J
    return _edge_force(mu * f00 + c * f11, mu * f01 - c * f10, mu * f10 - c * f01,
                       mu * f11 + c * f00, m00, m01, m10, m11, a0)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam, r, e, psd):
    """Column ``(r, e)`` of the Hessian ``d2E / dDs2``: ``d(dE/dDs)`` for a unit change of
    ``Ds[r, e]`` (rows of the result as in :func:`cst_gradient`).

    ``dP = mu dF + (mu - lam ln J) F^-T dF^T F^-T + lam (F^-T : dF) F^-T``. ``psd`` takes the
    tangent at rest (F = I: linear elasticity, positive semi-definite) instead, the interior
    point's convexified fallback.
    """
    if psd:
        f00, f01, f10, f11 = 1.0, 0.0, 0.0, 1.0
    else:
        f00, f01, f10, f11 = _deformation(ds00, ds01, ds10, ds11, m00, m01, m10, m11)
    det = f00 * f11 - f01 * f10
    g00, g01, g10, g11 = f11 / det, -f10 / det, -f01 / det, f00 / det  # F^-T
    # dF = E_re Dm^-1: row r is row e of Dm^-1
    me0 = m00 if e == 0 else m10
    me1 = m01 if e == 0 else m11
    d00, d01 = (me0, me1) if r == 0 else (0.0, 0.0)
    d10, d11 = (0.0, 0.0) if r == 0 else (me0, me1)
    tr = g00 * d00 + g01 * d01 + g10 * d10 + g11 * d11  # F^-T : dF
    # F^-T dF^T F^-T
    t00, t01 = g00 * d00 + g01 * d01, g00 * d10 + g01 * d11
    t10, t11 = g10 * d00 + g11 * d01, g10 * d10 + g11 * d11
    s00, s01 = t00 * g00 + t01 * g10, t00 * g01 + t01 * g11
    s10, s11 = t10 * g00 + t11 * g10, t10 * g01 + t11 * g11
    c = mu - lam * math.log(det)
    return _edge_force(mu * d00 + c * s00 + lam * tr * g00, mu * d01 + c * s01 + lam * tr * g01,
                       mu * d10 + c * s10 + lam * tr * g10, mu * d11 + c * s11 + lam * tr * g11,
                       m00, m01, m10, m11, a0)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _cst_triangle(x, n, m, prm, t, i):
    """Current edges ``Ds`` (rows), rest inverse and area of triangle ``i`` of family ``t``."""
    ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
    xa, ya, xb, yb, xc, yc = tri_xy(x, n, m, prm, t, i)
    qax, qay = rest_xy(prm, n, m, ka, ia)
    qbx, qby = rest_xy(prm, n, m, kb, ib)
    qcx, qcy = rest_xy(prm, n, m, kc, ic)
    m00, m01, m10, m11, a0 = cst_rest(qax, qay, qbx, qby, qcx, qcy)
    return xb - xa, xc - xa, yb - ya, yc - ya, m00, m01, m10, m11, a0


@njit(cache=True, error_model="numpy", _nrt=False)
def _quad_energy_all(x, n, m, prm):
    """Volumetric energy of every quad of a ring mesh (the nh-quad element)."""
    e = 0.0
    for k in range(1, m + 1):
        for i in range(n):
            a0 = quad_rest_area_at(prm, n, m, k, i)
            xa, ya, xb, yb, xc, yc, xd, yd = quad_xy(x, n, m, prm, k, i)
            e += area_energy(quad_area(xa, ya, xb, yb, xc, yc, xd, yd), prm[P_QUAD], a0)
    return e


@njit(cache=True, error_model="numpy", _nrt=False)
def _quad_gradient_all(x, n, m, prm, grad):
    """Add the gradient of :func:`_quad_energy_all`."""
    for k in range(1, m + 1):
        for i in range(n):
            a0 = quad_rest_area_at(prm, n, m, k, i)
            ka, ia, kb, ib, kc, ic, kd, id_ = quad_corners(k, i, n)
            xa, ya, xb, yb, xc, yc, xd, yd = quad_xy(x, n, m, prm, k, i)
            f = 0.5 * area_slope(quad_area(xa, ya, xb, yb, xc, yc, xd, yd), prm[P_QUAD], a0)
            _add2(grad, point_dof(n, m, ka, ia), f * (yb - yd), f * (xd - xb))
            _add2(grad, point_dof(n, m, kb, ib), f * (yc - ya), f * (xa - xc))
            _add2(grad, point_dof(n, m, kc, ic), f * (yd - yb), f * (xb - xd))
            _add2(grad, point_dof(n, m, kd, id_), f * (ya - yc), f * (xc - xa))


@njit(cache=True, error_model="numpy", _nrt=False)
def _element_energy(x, n, m, prm):
    """Elastic energy of the mesh's elements: constant-strain triangles when ``P_MU > 0``,
    else every edge's spring (the area energy is added by :func:`mesh_energy`)."""
    e = 0.0
    if prm[P_MU] > 0.0:
        for t in range(n_tri_types(m)):
            for i in range(n):
                ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0 = _cst_triangle(x, n, m, prm, t,
                                                                               i)
                e += cst_energy(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, prm[P_MU],
                                prm[P_LAM])
        if prm[P_QUAD] > 0.0:
            e += _quad_energy_all(x, n, m, prm)
        return e
    ne = n_edge_types(m)
    for i in range(n):
        for t in range(ne):
            xa, ya, xb, yb = edge_xy(x, n, m, prm, t, i)
            k, rest = edge_constants(prm, t, i, n, m)
            e += spring_energy(xb - xa, yb - ya, k, rest)
    return e


@njit(cache=True, error_model="numpy", _nrt=False)
def mesh_energy(x, n, prm):
    """Total energy of the disk's point mesh (springs and area energy, or constant-strain
    triangles) and the two finger joints [scaled]; ``prm`` is the kernels' copy with the ring
    table (:mod:`envs.model.rings`)."""
    m = int(prm[P_RINGS])
    e = _element_energy(x, n, m, prm)
    for j in range(2):
        e += joint_energy(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0 and prm[P_MU] == 0.0:
        for t in range(n_tri_types(m)):
            for i in range(n):
                xa, ya, xb, yb, xc, yc = tri_xy(x, n, m, prm, t, i)
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
def _cst_gradient_all(x, n, m, prm, grad):
    """Add the gradient of every constant-strain triangle."""
    for t in range(n_tri_types(m)):
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0 = _cst_triangle(x, n, m, prm, t, i)
            h00, h01, h10, h11 = cst_gradient(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0,
                                              prm[P_MU], prm[P_LAM])
            _add2(grad, point_dof(n, m, ka, ia), -(h00 + h01), -(h10 + h11))
            _add2(grad, point_dof(n, m, kb, ib), h00, h10)
            _add2(grad, point_dof(n, m, kc, ic), h01, h11)


@njit(cache=True, error_model="numpy", _nrt=False)
def _spring_gradient_all(x, n, m, prm, grad):
    """Add the gradient of every edge's spring."""
    for t in range(n_edge_types(m)):
        for i in range(n):
            ka, ia, kb, ib = edge_ends(t, i, n, m)
            xa, ya, xb, yb = edge_xy(x, n, m, prm, t, i)
            k, rest = edge_constants(prm, t, i, n, m)
            dx, dy = xb - xa, yb - ya
            f = spring_force(dx, dy, k, rest)
            _add2(grad, point_dof(n, m, ka, ia), -(f * dx), -(f * dy))
            _add2(grad, point_dof(n, m, kb, ib), f * dx, f * dy)


@njit(cache=True, error_model="numpy", _nrt=False)
def mesh_gradient(x, n, prm, grad):
    """Add the gradient of :func:`mesh_energy` to ``grad`` (state order)."""
    m = int(prm[P_RINGS])
    if prm[P_MU] > 0.0:
        _cst_gradient_all(x, n, m, prm, grad)
        if prm[P_QUAD] > 0.0:
            _quad_gradient_all(x, n, m, prm, grad)
    else:
        _spring_gradient_all(x, n, m, prm, grad)
    for j in range(2):
        grad[2 * n + j] += joint_gradient(x[2 * n + j], prm[P_TAU], prm[P_KAPPA], prm[P_TH0])
    if prm[P_KA] > 0.0 and prm[P_MU] == 0.0:
        for t in range(n_tri_types(m)):
            for i in range(n):
                ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
                xa, ya, xb, yb, xc, yc = tri_xy(x, n, m, prm, t, i)
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
            xa, ya, xb, yb, xc, yc = tri_xy(x, n, m, prm, t, i)
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
