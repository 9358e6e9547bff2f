"""Compiled equilibrium solver for the point-spring grasp (numba).

Problem (all quantities non-dimensional, see :class:`envs.psm.ScaledProblem`)::

    minimise  Pi(x) = sum_radial k_int/2 (|q_i| - 1)^2 + sum_contour k_ext/2 (|q_i+1 - q_i| - h)^2
                      + sum_fingers [tau theta_j + kappa/2 (theta_j - theta_0)^2]
    subject to  g_m(x) >= 0

with ``x = (q_0 .. q_N-1, theta_R, theta_L)``. The constraints are

* face:   distance from contour point ``i`` to the body of finger ``j``: the bar of length l and
          width w with its four corners rounded (gripping face, tip and root ends, back);
* corner: each rounded corner of finger ``j`` (face tip, face root, back tip, back root) keeps
          off each contour edge near the arc it sweeps (distance to the edge as a segment, so
          a corner passes from edge to edge through a vertex without any switching);
* stop:   ``theta_j >= theta_min`` (jaws closed on each other).

Method: a primal-dual interior-point Newton method with exact Hessians, inertia correction and a
backtracking line search on the barrier merit, followed by an augmented-Lagrangian Newton polish
on the identified contact set so that contacts hold to round-off. The Newton matrix is a
cyclic block-tridiagonal matrix (springs) bordered by the two finger angles; ordering the contour
points 0, N-1, 1, N-2, ... makes it banded (half bandwidth 5), so each factorization is a banded
Cholesky plus a 2x2 Schur complement: O(N) work. The gaps are distances, positive again on the
far side of a thin bar or an edge, so line-search steps that would jump across one are refused.
Outer rounds add constraints the solution reaches that were left out at the start; a final guard
reports a penetrating answer, and an answer with a turned-over fan triangle is reported as such.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .psm import (
    P_C0X,
    P_H,
    P_HW,
    P_KAPPA,
    P_KC,
    P_KR,
    P_LMAX,
    P_PHASE,
    P_RHO,
    P_TAU,
    P_TH0,
    P_THMIN,
)

BW = 5  # half bandwidth of the interleaved point ordering
CH_BLOCK = 15  # column of the constraint curvature cache: 1 where the constraint has a block
P_GAUGE = 15  # extra slot of the kernel's parameter copy: gauge spring stiffness
P_POLICY = 16  # extra slot: contact policy of this attempt (see solve_one)
CORNER_NEAR = 0.25  # corner-edge constraints for edges this close to a corner's path (units of r)
CORNER_SWEEP = 12  # samples of the arc a corner sweeps from its start to the closed jaws

# status codes
OK = 0
ITER_LIMIT = 1
LINALG_FAIL = 2
LINESEARCH_FAIL = 3
CONTACT_CYCLE = 4
POLISH_FAIL = 5
INFEASIBLE_START = 6
SADDLE = 7
INVERTED = 8
PENETRATION = 9
BLOCKED = 10  # internal: steps refused by an anti-tunnelling test; widen the candidate set
STATUS_MESSAGES = {
    OK: "converged",
    ITER_LIMIT: "interior-point iteration limit reached",
    LINALG_FAIL: "Newton matrix could not be made positive definite",
    LINESEARCH_FAIL: "line search failed to decrease the barrier merit",
    CONTACT_CYCLE: "contact candidate set did not settle (cycling between finger tip and face)",
    POLISH_FAIL: "active-set polish did not reach the contact tolerance",
    INFEASIBLE_START: "start point violates a contact constraint",
    SADDLE: "stuck at an unstable (saddle) equilibrium; escapes from it failed",
    PENETRATION: "answer penetrates a finger outside the contact constraints considered",
    INVERTED: "equilibrium with inverted (folded) fan triangles: the squeeze is beyond the "
              "point-spring model's valid range",
    BLOCKED: "steps kept refused by the anti-tunnelling tests and no new contact candidate "
             "explains why",
}

# option vector layout
O_TOL, O_MAXIT, O_MAXROUND, O_MU0, O_POLISH, O_GAUGE = range(6)
N_OPTIONS = 6


def default_options() -> np.ndarray:
    """Solver options: [stationarity tol, max iterations, max rounds, mu0 factor, polish,
    gauge]."""
    return np.array([1e-12, 300.0, 12.0, 1e-2, 1.0, 1.0])


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _frame(j, s, c):
    """Unit axis (ex, ey) and inward normal (nx, ny) of finger j at sin/cos of its angle."""
    if j == 0:
        return s, c, -c, s  # ex, ey, nx, ny
    return -s, c, c, s


@njit(cache=True, error_model="numpy")
def _band_index(n):
    """Scalar index of component 0 of each point in the interleaved (banded) ordering."""
    idx = np.empty(n, dtype=np.int64)
    half = (n - 1) // 2
    for i in range(n):
        pos = 2 * i if i <= half else 2 * (n - 1 - i) + 1
        idx[i] = 2 * pos
    return idx


# --------------------------------------------------------------------------------------------
# constraints


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _finger_coords(q, i, j, sj, cj, prm):
    """Frame of finger j and the coordinates (s along the bar, m along the inward normal) of
    point i relative to its joint."""
    ex, ey, nx, ny = _frame(j, sj, cj)
    vx = q[i, 0] + prm[P_C0X + 2 * j]
    vy = q[i, 1] + prm[P_C0X + 2 * j + 1]
    return ex, ey, nx, ny, ex * vx + ey * vy, nx * vx + ny * vy


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _face_eval(q, i, j, sj, cj, prm, grad, hess, want_hess):
    """Gap of point i to the body of finger j: value, local grad/Hessian over (qx, qy, theta).

    The body is the bar 0 <= s <= l, |m| <= w/2 in finger coordinates (s along the axis, m
    along the inward normal) with its four corners rounded to the radius rho: the rectangle
    R = [0, l] x [-(w/2 - rho), w/2 - rho] grown by rho. The gap is dist(p, R) - rho, C1
    outside the body: the gripping face (m = w/2), the tip and root ends and the back of the
    bar, which a disk wrapping round a finger tip can reach.
    """
    ex, ey, nx, ny, s, m = _finger_coords(q, i, j, sj, cj, prm)
    rho = prm[P_RHO]
    hc = prm[P_HW] - rho
    ds = s - min(max(s, 0.0), prm[P_LMAX])
    dm = m - min(max(m, -hc), hc)
    if ds == 0.0 and dm != 0.0:
        # the common case, beside a long side of the bar: the gap is |m| - w/2
        g_m = 1.0 if dm > 0.0 else -1.0
        grad[0] = g_m * nx
        grad[1] = g_m * ny
        grad[2] = g_m * s
        if want_hess:
            hx = g_m * ex
            hy = g_m * ey
            hess[0, 0] = 0.0
            hess[0, 1] = 0.0
            hess[1, 0] = 0.0
            hess[1, 1] = 0.0
            hess[0, 2] = hx
            hess[2, 0] = hx
            hess[1, 2] = hy
            hess[2, 1] = hy
            hess[2, 2] = -g_m * m
        return abs(dm) - rho
    for a in range(3):
        grad[a] = 0.0
        if want_hess:
            for b in range(3):
                hess[a, b] = 0.0
    # derivatives of s and m: ds/dq = e, dm/dq = n, ds/dth = -m, dm/dth = s,
    # d2s/dq dth = -n, d2m/dq dth = e, d2s/dth2 = -s, d2m/dth2 = -m
    if ds != 0.0 and dm != 0.0:
        dist = math.sqrt(ds * ds + dm * dm)
        g_s = ds / dist
        g_m = dm / dist
        d3 = dist * dist * dist
        g_ss = dm * dm / d3
        g_mm = ds * ds / d3
        g_sm = -ds * dm / d3
    elif dm != 0.0:
        dist = abs(dm)
        g_s = 0.0
        g_m = 1.0 if dm > 0.0 else -1.0
        g_ss = 0.0
        g_mm = 0.0
        g_sm = 0.0
    elif ds != 0.0:
        dist = abs(ds)
        g_s = 1.0 if ds > 0.0 else -1.0
        g_m = 0.0
        g_ss = 0.0
        g_mm = 0.0
        g_sm = 0.0
    else:
        return -rho  # inside the core rectangle: deep penetration (never at a feasible point)
    # first derivatives: grad = g_s grad(s) + g_m grad(m)
    as0, as1, as2 = ex, ey, -m
    am0, am1, am2 = nx, ny, s
    grad[0] = g_s * as0 + g_m * am0
    grad[1] = g_s * as1 + g_m * am1
    grad[2] = g_s * as2 + g_m * am2
    if not want_hess:
        return dist - rho
    # second derivatives: sum of g_ab grad(a) grad(b)^T plus g_s Hess(s) + g_m Hess(m)
    sv = (as0, as1, as2)
    mv = (am0, am1, am2)
    for a in range(3):
        for b in range(3):
            hess[a, b] = (g_ss * sv[a] * sv[b] + g_mm * mv[a] * mv[b]
                          + g_sm * (sv[a] * mv[b] + mv[a] * sv[b]))
    # Hess(s): (q, th) entries -n, (th, th) -s ; Hess(m): (q, th) entries e, (th, th) -m
    hx = -g_s * nx + g_m * ex
    hy = -g_s * ny + g_m * ey
    hess[0, 2] += hx
    hess[2, 0] += hx
    hess[1, 2] += hy
    hess[2, 1] += hy
    hess[2, 2] += -g_s * s - g_m * m
    return dist - rho


@njit(cache=True, error_model="numpy", _nrt=False)
def _corner_eval(q, k, j, sj, cj, c, prm, grad, hess, want_hess):
    """Rounded corner c of finger j vs contour edge k -> k+1.

    Corners: 0 tip and 1 root of the gripping face, 2 tip and 3 root of the back of the bar.

    Local variables (ax, ay, bx, by, theta). Value: distance from the centre of the rounded
    corner to the segment, minus the corner radius: the distance to the edge line where the foot
    lies on the edge, to the nearer end point beyond it. The distance to a segment is C1 away
    from the segment, so a corner may slide from one edge to the next through their common
    vertex with every nearby edge kept as its own constraint.
    """
    n = q.shape[0]
    k1 = k + 1 if k + 1 < n else 0
    ex, ey, nx, ny = _frame(j, sj, cj)
    rho = prm[P_RHO]
    sc = prm[P_LMAX] if c % 2 == 0 else 0.0
    hw = prm[P_HW] - rho  # centre of the rounded corner, in finger coordinates (sc, hw)
    if c >= 2:
        hw = -hw
    cx = prm[P_C0X + 2 * j]
    cy = prm[P_C0X + 2 * j + 1]
    kx = -cx + sc * ex + hw * nx
    ky = -cy + sc * ey + hw * ny
    k1x = -sc * nx + hw * ex
    k1y = -sc * ny + hw * ey
    k2x = -sc * ex - hw * nx
    k2y = -sc * ey - hw * ny
    ax, ay = q[k, 0], q[k, 1]
    ux, uy = kx - ax, ky - ay
    dx, dy = q[k1, 0] - ax, q[k1, 1] - ay
    tpar = (ux * dx + uy * dy) / (dx * dx + dy * dy)
    if tpar < 0.0 or tpar > 1.0:
        # beyond an end: distance between the end point v and the corner K
        for a in range(5):
            grad[a] = 0.0
            for b in range(5):
                hess[a, b] = 0.0
        off = 0 if tpar < 0.0 else 2
        vx, vy = q[k, 0], q[k, 1]
        if off == 2:
            vx, vy = q[k1, 0], q[k1, 1]
        wx, wy = kx - vx, ky - vy
        g = math.sqrt(wx * wx + wy * wy)
        if g < 1e-300:
            return -rho
        ux_, uy_ = wx / g, wy / g
        pxx, pxy, pyy = (1.0 - ux_ * ux_) / g, -ux_ * uy_ / g, (1.0 - uy_ * uy_) / g
        grad[off] = -ux_
        grad[off + 1] = -uy_
        grad[4] = ux_ * k1x + uy_ * k1y
        hess[off, off] = pxx
        hess[off, off + 1] = pxy
        hess[off + 1, off] = pxy
        hess[off + 1, off + 1] = pyy
        hx = -(pxx * k1x + pxy * k1y)
        hy = -(pxy * k1x + pyy * k1y)
        hess[off, 4] = hx
        hess[4, off] = hx
        hess[off + 1, 4] = hy
        hess[4, off + 1] = hy
        hess[4, 4] = (k1x * (pxx * k1x + pxy * k1y) + k1y * (pxy * k1x + pyy * k1y)
                      + ux_ * k2x + uy_ * k2y)
        return g - rho
    L = math.sqrt(dx * dx + dy * dy)
    cr = ux * dy - uy * dx
    g = cr / L
    # first derivatives in (u, d)
    jdx, jdy = dy, -dx  # J d
    jux, juy = uy, -ux  # J u
    gux, guy = jdx / L, jdy / L
    L3 = L * L * L
    gdx = -jux / L - cr * dx / L3
    gdy = -juy / L - cr * dy / L3
    # M_ud[a, b] = J[a, b]/L - (Jd)_a d_b / L^3 ; J = [[0, 1], [-1, 0]]
    m00 = -jdx * dx / L3
    m01 = 1.0 / L - jdx * dy / L3
    m10 = -1.0 / L - jdy * dx / L3
    m11 = -jdy * dy / L3
    L5 = L3 * L * L
    d00 = 2.0 * jux * dx / L3 - cr / L3 + 3.0 * cr * dx * dx / L5
    d11 = 2.0 * juy * dy / L3 - cr / L3 + 3.0 * cr * dy * dy / L5
    d01 = (jux * dy + dx * juy) / L3 + 3.0 * cr * dx * dy / L5
    # chain rule to z = (ax, ay, bx, by, theta): u = K(theta) - a, d = b - a
    grad[0] = -gux - gdx
    grad[1] = -guy - gdy
    grad[2] = gdx
    grad[3] = gdy
    grad[4] = gux * k1x + guy * k1y
    sgn = 1.0 if cr >= 0.0 else -1.0
    if not want_hess:
        # the corner on the inner side of this edge's line: the distance is -cr / L
        for a in range(5):
            grad[a] *= sgn
        return sgn * g - rho
    # per-z columns of du and dd (du for z = bx, by is zero; dd for theta is zero)
    u0 = (-1.0, 0.0, 0.0, 0.0, k1x)
    u1 = (0.0, -1.0, 0.0, 0.0, k1y)
    e0 = (-1.0, 0.0, 1.0, 0.0, 0.0)
    e1 = (0.0, -1.0, 0.0, 1.0, 0.0)
    for a in range(5):
        ua0, ua1, da0, da1 = u0[a], u1[a], e0[a], e1[a]
        # (M t_a) components: Mu = M_ud d, Md = M_du u + M_dd d
        mu0 = m00 * da0 + m01 * da1
        mu1 = m10 * da0 + m11 * da1
        md0 = m00 * ua0 + m10 * ua1 + d00 * da0 + d01 * da1
        md1 = m01 * ua0 + m11 * ua1 + d01 * da0 + d11 * da1
        for b in range(5):
            hess[a, b] = u0[b] * mu0 + u1[b] * mu1 + e0[b] * md0 + e1[b] * md1
    hess[4, 4] += gux * k2x + guy * k2y
    if cr < 0.0:
        # the corner lies on the inner side of this edge's line: the distance to the segment
        # is -cr / L (every edge near the corner is a constraint, not only the one it faces)
        for a in range(5):
            grad[a] = -grad[a]
            for b in range(5):
                hess[a, b] = -hess[a, b]
        return -g - rho
    return g - rho


# --------------------------------------------------------------------------------------------
# energy, gradient, Hessian


@njit(cache=True, error_model="numpy", _nrt=False)
def _energy(x, n, prm):
    e = 0.0
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        qx, qy = x[2 * i], x[2 * i + 1]
        lr = math.sqrt(qx * qx + qy * qy)
        e += 0.5 * kr * (lr - 1.0) ** 2
        dx, dy = x[2 * i1] - qx, x[2 * i1 + 1] - qy
        lc = math.sqrt(dx * dx + dy * dy)
        e += 0.5 * kc * (lc - h) ** 2
    for j in range(2):
        th = x[2 * n + j]
        e += prm[P_TAU] * th + 0.5 * prm[P_KAPPA] * (th - prm[P_TH0]) ** 2
    kg = prm[P_GAUGE]
    if kg > 0.0:
        tx, ty = -math.sin(prm[P_PHASE]), math.cos(prm[P_PHASE])
        ut = (x[0] - ty) * tx + (x[1] + tx) * ty
        e += 0.5 * kg * ut * ut
    return e


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _add(ab, bb, dd, nb, p, r, v):
    """Add v to the symmetric Newton matrix entry (p, r) (band-ordered; >= nb is an angle)."""
    if p < nb and r < nb:
        if p >= r:
            ab[p, p - r] += v
        else:
            ab[r, r - p] += v
    elif p < nb:
        bb[p, r - nb] += v
    elif r < nb:
        bb[r, p - nb] += v
    else:
        dd[p - nb, r - nb] += v
        if p != r:
            dd[r - nb, p - nb] += v


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _add_point(ab, p, kxx, kyy, kxy):
    """Add the symmetric block [[kxx, kxy], [kxy, kyy]] of the point at band index p."""
    ab[p, 0] += kxx
    ab[p + 1, 0] += kyy
    ab[p + 1, 1] += kxy


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _add_spring(ab, bb, dd, nb, pa, pb, kxx, kyy, kxy):
    """Add the stiffness K = [[kxx, kxy], [kxy, kyy]] of a spring between the points at band
    indices pa and pb: [[K, -K], [-K, K]]."""
    _add_point(ab, pa, kxx, kyy, kxy)
    _add_point(ab, pb, kxx, kyy, kxy)
    _add(ab, bb, dd, nb, pa, pb, -kxx)
    _add(ab, bb, dd, nb, pa + 1, pb + 1, -kyy)
    _add(ab, bb, dd, nb, pa, pb + 1, -kxy)
    _add(ab, bb, dd, nb, pa + 1, pb, -kxy)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_stretch(x, prm):
    """Tangent (tx, ty) of the contour at point 0's rest position and point 0's displacement
    ut along it: the gauge spring's direction and stretch."""
    tx, ty = -math.sin(prm[P_PHASE]), math.cos(prm[P_PHASE])
    return tx, ty, (x[0] - ty) * tx + (x[1] + tx) * ty


@njit(cache=True, error_model="numpy", _nrt=False)
def _spring_terms(x, n, prm, bidx, grad, ab, bb, dd, want_hess, psd=False):
    """Spring and finger energy gradient (natural order) and Hessian (band order)."""
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    nb = 2 * n
    for i in range(n):
        qx, qy = x[2 * i], x[2 * i + 1]
        lr = math.sqrt(qx * qx + qy * qy)
        f = kr * (lr - 1.0) / lr
        grad[2 * i] += f * qx
        grad[2 * i + 1] += f * qy
        if want_hess:
            ux, uy = qx / lr, qy / lr
            tt = kr * (1.0 - 1.0 / lr)
            if psd and tt < 0.0:
                tt = 0.0
            _add_point(ab, bidx[i], kr * ux * ux + tt * (1.0 - ux * ux),
                       kr * uy * uy + tt * (1.0 - uy * uy), kr * ux * uy - tt * ux * uy)
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        dx, dy = x[2 * i1] - x[2 * i], x[2 * i1 + 1] - x[2 * i + 1]
        lc = math.sqrt(dx * dx + dy * dy)
        f = kc * (lc - h) / lc
        grad[2 * i] -= f * dx
        grad[2 * i + 1] -= f * dy
        grad[2 * i1] += f * dx
        grad[2 * i1 + 1] += f * dy
        if want_hess:
            ux, uy = dx / lc, dy / lc
            tt = kc * (1.0 - h / lc)
            if psd and tt < 0.0:
                tt = 0.0
            _add_spring(ab, bb, dd, nb, bidx[i], bidx[i1], kc * ux * ux + tt * (1.0 - ux * ux),
                        kc * uy * uy + tt * (1.0 - uy * uy), kc * ux * uy - tt * ux * uy)
    for j in range(2):
        th = x[nb + j]
        grad[nb + j] += prm[P_TAU] + prm[P_KAPPA] * (th - prm[P_TH0])
        if want_hess:
            dd[j, j] += prm[P_KAPPA]
    kg = prm[P_GAUGE]
    if kg > 0.0:
        # gauge: a stiff tangential spring on point 0 removes the free rotation of the contour
        # about the pin; its reaction must vanish at the answer (checked by the caller)
        tx, ty, ut = _gauge_stretch(x, prm)
        grad[0] += kg * ut * tx
        grad[1] += kg * ut * ty
        if want_hess:
            _add_point(ab, bidx[0], kg * tx * tx, kg * ty * ty, kg * tx * ty)


# --------------------------------------------------------------------------------------------
# constraint bookkeeping: constraint m has kind (0 face, 1 corner, 2 stop), finger j, index i/k
# and corner position sc. Gradients/Hessians are evaluated on demand.


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _face_gap(q, i, j, sj, cj, prm):
    """Value of :func:`_face_eval` only."""
    ex, ey, nx, ny, s, m = _finger_coords(q, i, j, sj, cj, prm)
    rho = prm[P_RHO]
    hc = prm[P_HW] - rho
    ds = s - min(max(s, 0.0), prm[P_LMAX])
    dm = m - min(max(m, -hc), hc)
    return math.sqrt(ds * ds + dm * dm) - rho


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _seg_dist(q, k, px, py):
    """Distance from (px, py) to the contour edge k -> k+1."""
    n = q.shape[0]
    k1 = k + 1 if k + 1 < n else 0
    ax, ay = q[k, 0], q[k, 1]
    dx, dy = q[k1, 0] - ax, q[k1, 1] - ay
    t = ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)
    t = min(1.0, max(0.0, t))
    wx = px - ax - t * dx
    wy = py - ay - t * dy
    return math.sqrt(wx * wx + wy * wy)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_gap(q, k, j, sj, cj, c, prm):
    """Value of :func:`_corner_eval` only: corner centre to segment distance minus rho."""
    kx, ky = _corner_centre(j, sj, cj, c, prm)
    return _seg_dist(q, k, kx, ky) - prm[P_RHO]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _sel(t, j):
    """Entry j (0 or 1) of a pair: a tuple indexed by a run-time integer costs tens of ns."""
    return t[1] if j == 1 else t[0]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _trig(x, n):
    """Sines and cosines of the two finger angles of state x (computed once per pass)."""
    return ((math.sin(x[2 * n]), math.sin(x[2 * n + 1])),
            (math.cos(x[2 * n]), math.cos(x[2 * n + 1])))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _con_value(kind, j, idx, x, q, n, prm, sn, cs):
    """Value of constraint (kind, j, idx) only (line searches, candidate checks); ``sn``, ``cs``
    hold the sines and cosines of the finger angles (:func:`_trig`)."""
    if kind == 0:
        return _face_gap(q, idx, j, _sel(sn, j), _sel(cs, j), prm)
    if kind == 1:
        c = idx // n
        return _corner_gap(q, idx - c * n, j, _sel(sn, j), _sel(cs, j), c, prm)
    return x[2 * n + j] - prm[P_THMIN]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _con_eval(kind, j, idx, x, q, n, prm, sn, cs, grad5, hess5, dofs, want_hess=True):
    """Evaluate constraint; returns (value, number of local dofs); fills natural-order dofs."""
    th = x[2 * n + j]
    if kind == 0:
        g = _face_eval(q, idx, j, _sel(sn, j), _sel(cs, j), prm, grad5, hess5, want_hess)
        dofs[0] = 2 * idx
        dofs[1] = 2 * idx + 1
        dofs[2] = 2 * n + j
        return g, 3
    if kind == 1:
        c = idx // n
        k = idx - c * n
        g = _corner_eval(q, k, j, _sel(sn, j), _sel(cs, j), c, prm, grad5, hess5, want_hess)
        k1 = k + 1 if k + 1 < n else 0
        dofs[0] = 2 * k
        dofs[1] = 2 * k + 1
        dofs[2] = 2 * k1
        dofs[3] = 2 * k1 + 1
        dofs[4] = 2 * n + j
        return g, 5
    for a in range(5):
        grad5[a] = 0.0
        for b in range(5):
            hess5[a, b] = 0.0
    grad5[0] = 1.0
    dofs[0] = 2 * n + j
    return th - prm[P_THMIN], 1


@njit(cache=True, error_model="numpy", _nrt=False)
def _all_gaps(x, n, prm, kinds, fj, fidx, gout):
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(kinds.shape[0]):
        gout[m] = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)


# --------------------------------------------------------------------------------------------
# banded Cholesky with a 2x2 bordered Schur complement


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _times_inv_lt(lb, c0, s00, s01, s10, s11):
    """S L_c^-T for the 2x2 block S and the diagonal factor block L_c of the point whose rows
    start at c0 (reciprocal pivots as :func:`_chol_band` keeps them)."""
    r0 = lb[c0, 0]
    l10 = lb[c0 + 1, 1]
    r1 = lb[c0 + 1, 0]
    x00 = s00 * r0
    x10 = s10 * r0
    return x00, (s01 - x00 * l10) * r1, x10, (s11 - x10 * l10) * r1


@njit(cache=True, error_model="numpy", _nrt=False)
def _chol_band(ab, lb, nb, shift):
    """Banded Cholesky of A + shift I (lower band of A in ``ab``) by 2x2 blocks, one block a
    point (the band ordering couples a point with the two before it); ``lb`` gets the scalar
    factor with the reciprocal of each diagonal entry in column 0 (multiplications, not
    divisions, in the dependent chains of the solves). Returns False if the matrix is not
    positive definite."""
    for b in range(nb // 2):
        p0 = 2 * b
        p1 = p0 + 1
        # block (b, b-2) of the factor: X = A_{b,b-2} L_{b-2,b-2}^-T
        x00 = 0.0
        x01 = 0.0
        x10 = 0.0
        x11 = 0.0
        if b >= 2:
            x00, x01, x10, x11 = _times_inv_lt(lb, p0 - 4, ab[p0, 4], ab[p0, 3], ab[p1, 5],
                                               ab[p1, 4])
        # block (b, b-1): Y = (A_{b,b-1} - X L_{b-1,b-2}^T) L_{b-1,b-1}^-T
        y00 = 0.0
        y01 = 0.0
        y10 = 0.0
        y11 = 0.0
        if b >= 1:
            c0 = p0 - 2
            s00 = ab[p0, 2]
            s01 = ab[p0, 1]
            s10 = ab[p1, 3]
            s11 = ab[p1, 2]
            if b >= 2:
                m00 = lb[c0, 2]
                m01 = lb[c0, 1]
                m10 = lb[c0 + 1, 3]
                m11 = lb[c0 + 1, 2]
                s00 -= x00 * m00 + x01 * m01
                s01 -= x00 * m10 + x01 * m11
                s10 -= x10 * m00 + x11 * m01
                s11 -= x10 * m10 + x11 * m11
            y00, y01, y10, y11 = _times_inv_lt(lb, c0, s00, s01, s10, s11)
        # diagonal block: A_bb - X X^T - Y Y^T, its own 2x2 Cholesky
        d00 = ab[p0, 0] + shift - ((x00 * x00 + x01 * x01) + (y00 * y00 + y01 * y01))
        if not d00 > 0.0:
            return False
        r0 = 1.0 / math.sqrt(d00)
        l10 = (ab[p1, 1] - ((x10 * x00 + x11 * x01) + (y10 * y00 + y11 * y01))) * r0
        d11 = ab[p1, 0] + shift - ((x10 * x10 + x11 * x11) + (y10 * y10 + y11 * y11)) - l10 * l10
        if not d11 > 0.0:
            return False
        lb[p0, 0] = r0
        lb[p0, 1] = y01
        lb[p0, 2] = y00
        lb[p0, 3] = x01
        lb[p0, 4] = x00
        lb[p0, 5] = 0.0
        lb[p1, 0] = 1.0 / math.sqrt(d11)
        lb[p1, 1] = l10
        lb[p1, 2] = y11
        lb[p1, 3] = y10
        lb[p1, 4] = x11
        lb[p1, 5] = x10
    return True


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _eliminate(v, w, ybuf, out, m, a0, a1, a2, e0, e1, e2):
    """Take row m of the three solution columns, times v and w, off the two rows (a, e) of a
    block in :func:`_solve_band3`."""
    y0 = ybuf[m, 0]
    y1 = ybuf[m, 1]
    z = out[m]
    return a0 - v * y0, a1 - v * y1, a2 - v * z, e0 - w * y0, e1 - w * y1, e2 - w * z


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _finish_block(lb, ybuf, out, pf, ps, a0, a1, a2, e0, e1, e2):
    """Solve a 2x2 diagonal block of :func:`_solve_band3`: row ``pf`` (sums a) first, then row
    ``ps`` (sums e) less the block's off-diagonal entry times it."""
    p1 = max(pf, ps)
    d = lb[pf, 0]
    a0 *= d
    a1 *= d
    a2 *= d
    ybuf[pf, 0] = a0
    ybuf[pf, 1] = a1
    out[pf] = a2
    l10 = lb[p1, 1]
    d = lb[ps, 0]
    ybuf[ps, 0] = (e0 - l10 * a0) * d
    ybuf[ps, 1] = (e1 - l10 * a1) * d
    out[ps] = (e2 - l10 * a2) * d


@njit(cache=True, error_model="numpy", _nrt=False)
def _solve_band3(lb, nb, bb, rb, ybuf, out):
    """Solve L L^T [Y | z] = [B | r] for the two border columns B and the right-hand side r in
    one sweep (three independent chains), by the 2x2 blocks of :func:`_chol_band`."""
    for b in range(nb // 2):
        p0 = 2 * b
        p1 = p0 + 1
        a0, a1, a2 = bb[p0, 0], bb[p0, 1], rb[p0]
        e0, e1, e2 = bb[p1, 0], bb[p1, 1], rb[p1]
        # the two blocks before: row p0 reaches back 4 entries, row p1 (besides p0) 4 too
        for m in range(max(0, p0 - 4), p0):
            a0, a1, a2, e0, e1, e2 = _eliminate(lb[p0, p0 - m], lb[p1, p1 - m], ybuf, out, m,
                                                a0, a1, a2, e0, e1, e2)
        _finish_block(lb, ybuf, out, p0, p1, a0, a1, a2, e0, e1, e2)
    for b in range(nb // 2 - 1, -1, -1):
        p0 = 2 * b
        p1 = p0 + 1
        a0, a1, a2 = ybuf[p0, 0], ybuf[p0, 1], out[p0]
        e0, e1, e2 = ybuf[p1, 0], ybuf[p1, 1], out[p1]
        # the two blocks after (rows p1 + 1 .. p1 + 4)
        for m in range(p1 + 1, min(nb, p1 + 5)):
            a0, a1, a2, e0, e1, e2 = _eliminate(lb[m, m - p0], lb[m, m - p1], ybuf, out, m,
                                                a0, a1, a2, e0, e1, e2)
        # backwards the odd row of the block comes first
        _finish_block(lb, ybuf, out, p1, p0, e0, e1, e2, a0, a1, a2)


@njit(cache=True, error_model="numpy", _nrt=False)
def _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, out_b, out_t):
    """Solve [[A, B], [B^T, D]] + shift I; returns False if not positive definite."""
    if not _chol_band(ab, lb, nb, shift):
        return False
    _solve_band3(lb, nb, bb, rb, ybuf, out_b)
    s00 = dd[0, 0] + shift
    s11 = dd[1, 1] + shift
    s01 = dd[0, 1]
    for p in range(nb):
        s00 -= bb[p, 0] * ybuf[p, 0]
        s11 -= bb[p, 1] * ybuf[p, 1]
        s01 -= bb[p, 0] * ybuf[p, 1]
    det = s00 * s11 - s01 * s01
    if not (s00 > 0.0 and det > 1e-300 * max(1.0, s00 * s11) and det > 0.0):
        return False
    r0 = rt[0]
    r1 = rt[1]
    for p in range(nb):
        r0 -= bb[p, 0] * out_b[p]
        r1 -= bb[p, 1] * out_b[p]
    t0 = (s11 * r0 - s01 * r1) / det
    t1 = (s00 * r1 - s01 * r0) / det
    out_t[0] = t0
    out_t[1] = t1
    for p in range(nb):
        out_b[p] -= ybuf[p, 0] * t0 + ybuf[p, 1] * t1
    return True


# --------------------------------------------------------------------------------------------
# candidate constraints


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_centre(j, sj, cj, c, prm):
    """Centre of the rounded corner c of finger j (disk-centred, units of r)."""
    ex, ey, nx, ny = _frame(j, sj, cj)
    sc = prm[P_LMAX] if c % 2 == 0 else 0.0
    hc = prm[P_HW] - prm[P_RHO]
    if c >= 2:
        hc = -hc
    return (-prm[P_C0X + 2 * j] + sc * ex + hc * nx,
            -prm[P_C0X + 2 * j + 1] + sc * ey + hc * ny)


@njit(cache=True, error_model="numpy", _nrt=False)
def _inside(q, n, px, py):
    """Crossing-number test: is (px, py) inside the contour polygon?"""
    inside = False
    for k in range(n):
        k1 = k + 1 if k + 1 < n else 0
        ax, ay, bx, by = q[k, 0], q[k, 1], q[k1, 0], q[k1, 1]
        if (ay > py) != (by > py):
            xc = ax + (py - ay) * (bx - ax) / (by - ay)
            if xc > px:
                inside = not inside
    return inside


@njit(cache=True, error_model="numpy", _nrt=False)
def _bar_crossed(q, n, j, sj, cj, prm):
    """Does a contour edge cross the axis of finger j (the bar runs right through the disk)?

    Every point outside the bar and every corner outside the contour do not exclude an edge
    with one end in front of the bar and the other behind it.
    """
    ex, ey, _, _ = _frame(j, sj, cj)
    ax = -prm[P_C0X + 2 * j]
    ay = -prm[P_C0X + 2 * j + 1]
    bx = ax + prm[P_LMAX] * ex
    by = ay + prm[P_LMAX] * ey
    for k in range(n):
        k1 = k + 1 if k + 1 < n else 0
        px, py, rx, ry = q[k, 0], q[k, 1], q[k1, 0], q[k1, 1]
        d1 = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        d2 = (bx - ax) * (ry - ay) - (by - ay) * (rx - ax)
        if d1 * d2 >= 0.0:
            continue
        d3 = (rx - px) * (ay - py) - (ry - py) * (ax - px)
        d4 = (rx - px) * (by - py) - (ry - py) * (bx - px)
        if d3 * d4 < 0.0:
            return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _crossed_through(x, n, prm):
    """Has a finger gone right through the disk in state x (an edge across its bar, or one
    of its corners inside the contour), where every gap is positive again?"""
    sn, cs = _trig(x, n)
    return _crossed_through_sc(x, n, prm, sn, cs)


@njit(cache=True, error_model="numpy", _nrt=False)
def _crossed_through_sc(x, n, prm, sn, cs):
    """:func:`_crossed_through` with the finger sines and cosines given.

    The contour lies in the circle about the pin through its farthest point: a corner or a bar
    outside that circle is skipped without the O(N) tests.
    """
    nb = 2 * n
    q = x[:nb].reshape(n, 2)
    r2 = 0.0
    for i in range(n):
        r2 = max(r2, x[2 * i] * x[2 * i] + x[2 * i + 1] * x[2 * i + 1])
    for j in range(2):
        # distance from the pin to the axis segment of the bar
        ex, ey, _, _ = _frame(j, _sel(sn, j), _sel(cs, j))
        ax = -prm[P_C0X + 2 * j]
        ay = -prm[P_C0X + 2 * j + 1]
        t = min(max(-(ax * ex + ay * ey), 0.0), prm[P_LMAX])
        px = ax + t * ex
        py = ay + t * ey
        if px * px + py * py <= r2 and _bar_crossed(q, n, j, _sel(sn, j), _sel(cs, j), prm):
            return True
        for c in range(4):
            kx, ky = _corner_centre(j, _sel(sn, j), _sel(cs, j), c, prm)
            if kx * kx + ky * ky <= r2 and _inside(q, n, kx, ky):
                return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _tunnels(x, xt, n, prm):
    """Would the step x -> xt carry a corner or a point right through the contour or a finger?

    The corner gaps are distances to segments and the bar of a finger is thin, so a long step
    can jump across a constraint and land where every gap is positive again. Rejected: a corner
    ending inside the contour, a point crossing a finger's axis line along the bar.
    """
    sn1, cs1 = _trig(xt, n)
    if _crossed_through_sc(xt, n, prm, sn1, cs1):
        return True
    sn0, cs0 = _trig(x, n)
    for j in range(2):
        ex0, ey0, nx0, ny0 = _frame(j, _sel(sn0, j), _sel(cs0, j))
        ex1, ey1, nx1, ny1 = _frame(j, _sel(sn1, j), _sel(cs1, j))
        cx = prm[P_C0X + 2 * j]
        cy = prm[P_C0X + 2 * j + 1]
        lmax = prm[P_LMAX]
        for i in range(n):
            vx0, vy0 = x[2 * i] + cx, x[2 * i + 1] + cy
            vx1, vy1 = xt[2 * i] + cx, xt[2 * i + 1] + cy
            m0 = nx0 * vx0 + ny0 * vy0
            m1 = nx1 * vx1 + ny1 * vy1
            if m0 * m1 < 0.0:
                s0 = ex0 * vx0 + ey0 * vy0
                s1 = ex1 * vx1 + ey1 * vy1
                if (0.0 <= s0 <= lmax) or (0.0 <= s1 <= lmax):
                    return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _build_constraints(face, corner, n, kinds, fj, fidx):
    m = 0
    for j in range(2):
        for i in range(n):
            if face[j, i]:
                kinds[m] = 0
                fj[m] = j
                fidx[m] = i
                m += 1
    for j in range(2):
        for c in range(4):
            for k in range(n):
                if corner[j, c, k]:
                    kinds[m] = 1
                    fj[m] = j
                    fidx[m] = k + n * c
                    m += 1
    for j in range(2):
        kinds[m] = 2
        fj[m] = j
        fidx[m] = 0
        m += 1
    return m


# --------------------------------------------------------------------------------------------
# the interior-point Newton solve for a fixed candidate set


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _scatter(kind, j, dofs, bidx, nb, blk, ab, bb, dd):
    """Add a constraint's block ``blk`` (lower triangle over its dofs) to the Newton matrix."""
    if kind == 0:
        # point i: its 2x2 diagonal block and its coupling to theta_j
        p = bidx[dofs[0] // 2]
        _add_point(ab, p, blk[0, 0], blk[1, 1], blk[1, 0])
        bb[p, j] += blk[2, 0]
        bb[p + 1, j] += blk[2, 1]
        dd[j, j] += blk[2, 2]
    elif kind == 1:
        # edge k -> k1: two diagonal blocks, their coupling, and theta_j
        p = bidx[dofs[0] // 2]
        r = bidx[dofs[2] // 2]
        _add_point(ab, p, blk[0, 0], blk[1, 1], blk[1, 0])
        _add_point(ab, r, blk[2, 2], blk[3, 3], blk[3, 2])
        for a in range(2, 4):
            for b in range(2):
                _add(ab, bb, dd, nb, r + a - 2, p + b, blk[a, b])
        bb[p, j] += blk[4, 0]
        bb[p + 1, j] += blk[4, 1]
        bb[r, j] += blk[4, 2]
        bb[r + 1, j] += blk[4, 3]
        dd[j, j] += blk[4, 4]
    else:
        dd[j, j] += blk[0, 0]


@njit(cache=True, error_model="numpy", _nrt=False)
def _drop_curvature(x, n, prm, bidx, kinds, fj, mcount, cd, ch, blk, dofs, ab, bb, dd):
    """Turn the exact Newton matrix of :func:`_newton_matrix` into its convexified fallback
    (``psd=True``) in place: the springs' negative geometric stiffness and the constraint
    curvature (kept in ``ch``) taken out, without evaluating the constraints again."""
    nb = 2 * n
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    for i in range(n):
        qx, qy = x[2 * i], x[2 * i + 1]
        lr = math.sqrt(qx * qx + qy * qy)
        tt = kr * (1.0 - 1.0 / lr)
        if tt < 0.0:
            ux, uy = qx / lr, qy / lr
            _add_point(ab, bidx[i], -tt * (1.0 - ux * ux), -tt * (1.0 - uy * uy), tt * ux * uy)
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        dx, dy = x[2 * i1] - x[2 * i], x[2 * i1 + 1] - x[2 * i + 1]
        lc = math.sqrt(dx * dx + dy * dy)
        tt = kc * (1.0 - h / lc)
        if tt < 0.0:
            ux, uy = dx / lc, dy / lc
            _add_spring(ab, bb, dd, nb, bidx[i], bidx[i1], -tt * (1.0 - ux * ux),
                        -tt * (1.0 - uy * uy), tt * ux * uy)
    for m in range(mcount):
        if ch[m, CH_BLOCK] == 0.0:
            continue
        nd = 3 if kinds[m] == 0 else (5 if kinds[m] == 1 else 1)
        t = 0
        for a in range(nd):
            dofs[a] = cd[m, a]
            for b in range(a + 1):
                blk[a, b] = ch[m, t]
                t += 1
        _scatter(kinds[m], fj[m], dofs, bidx, nb, blk, ab, bb, dd)


@njit(cache=True, error_model="numpy", _nrt=False)
def _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd,
                   g_out, grad5, hess5, dofs, barrier_mu, psd, gb, res, cg, cd, ch):
    """Assemble W = Hess(Pi) - sum lam Hess(g) + sum sig grad g grad g^T and the merit gradient.

    With barrier_mu > 0 the returned gradient is that of Pi - mu sum log g; with barrier_mu = 0
    it is grad Pi - sum lam grad g (used by the augmented-Lagrangian polish, where lam already
    holds lam_k - rho g). Also returns, in the same pass, ``gb = sum grad g / g`` (so the
    barrier gradient for another mu is grad + (barrier_mu - mu) gb) and the stationarity
    residual ``res = grad Pi - sum lam grad g``. ``cg``, ``cd`` get each constraint's gradient
    and its dofs, ``ch`` the curvature terms it put into the matrix (lower triangle, row by
    row) and whether it put in any (column ``CH_BLOCK``).
    """
    nb = 2 * n
    grad[:] = 0.0
    ab[:, :] = 0.0
    bb[:, :] = 0.0
    dd[:, :] = 0.0
    _spring_terms(x, n, prm, bidx, grad, ab, bb, dd, True, psd)
    for d in range(nb + 2):
        res[d] = grad[d]
        gb[d] = 0.0
    kmax = max(prm[P_KC], prm[P_KR])
    blk = hess5  # the block is built in place of the constraint Hessian (lower triangle)
    q = x[:nb].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(mcount):
        # a far constraint: its matrix block is below round-off of the springs (g_out holds
        # the gaps at x on entry: every caller evaluates them just before)
        block = sig[m] + abs(lam[m]) / max(g_out[m], 1e-300) >= 1e-9 * kmax
        g, nd = _con_eval(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs, grad5, hess5, dofs,
                          block)
        g_out[m] = g
        for a in range(nd):
            cg[m, a] = grad5[a]
            cd[m, a] = dofs[a]
        inv_g = 1.0 / g
        w = barrier_mu * inv_g if barrier_mu > 0.0 else lam[m]
        lm = lam[m]
        for a in range(nd):
            d = dofs[a]
            ga = grad5[a]
            grad[d] -= w * ga
            res[d] -= lm * ga
            gb[d] += ga * inv_g
        ch[m, CH_BLOCK] = 0.0
        if not block:
            continue
        # constraint curvature; dropped in the convexified fallback, where the curved
        # (corner-distance) gaps would make the matrix badly indefinite (kept in ``ch`` so
        # that the fallback can take it out again without a new pass, _drop_curvature)
        curv = 0.0 if psd else lam[m]
        t = 0
        for a in range(nd):
            for b in range(a + 1):
                ch[m, t] = curv * hess5[a, b]
                blk[a, b] = sig[m] * grad5[a] * grad5[b] - ch[m, t]
                t += 1
        ch[m, CH_BLOCK] = 1.0
        _scatter(kinds[m], fj[m], dofs, bidx, nb, blk, ab, bb, dd)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _rhs_to_band(grad, bidx, nb, rb, rt):
    """Right-hand side -grad of the Newton system in band order (points) and angles."""
    for d in range(nb):
        i = d // 2
        rb[bidx[i] + (d - 2 * i)] = -grad[d]
    rt[0] = -grad[nb]
    rt[1] = -grad[nb + 1]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _step_from_band(ob, ot, bidx, nb, grad, step):
    """Newton step in natural order from the banded solve; returns its slope grad . step."""
    for d in range(nb):
        i = d // 2
        step[d] = ob[bidx[i] + (d - 2 * i)]
    step[nb] = ot[0]
    step[nb + 1] = ot[1]
    slope = 0.0
    for d in range(nb + 2):
        slope += grad[d] * step[d]
    return slope


@njit(cache=True, error_model="numpy", _nrt=False)
def _merit(x, n, prm, kinds, fj, fidx, mcount, gbuf):
    """Parts (Pi(x), sum log g) of the barrier merit Pi - mu sum log g ((inf, 0) outside the
    constraints); gaps into ``gbuf``.

    The logarithms are taken of products of up to 8 gaps (a gap lies between about 1e-20 and
    10, so a product neither under- nor overflows): half the cost of the merit was ``log``.
    """
    e = _energy(x, n, prm)
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    logs = 0.0
    prod = 1.0
    cnt = 0
    for m in range(mcount):
        g = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)
        gbuf[m] = g
        if not g > 0.0:
            return math.inf, 0.0
        prod *= g
        cnt += 1
        if cnt == 8 or prod < 1e-200 or prod > 1e200:
            logs += math.log(prod)
            prod = 1.0
            cnt = 0
    return e, logs + math.log(prod)


@njit(cache=True, error_model="numpy", _nrt=False)
def _stationarity(x, n, prm, kinds, fj, fidx, mcount, lam, gbuf, grad5, hess5, dofs, res):
    res[:] = 0.0
    # gradient only: the matrix arguments are not touched
    _spring_terms(x, n, prm, dofs, res, hess5, hess5, hess5, False)
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(mcount):
        g, nd = _con_eval(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs, grad5, hess5, dofs,
                          False)
        gbuf[m] = g
        for a in range(nd):
            res[dofs[a]] -= lam[m] * grad5[a]
    r = 0.0
    for a in range(res.shape[0]):
        r = max(r, abs(res[a]))
    return r


@njit(cache=True, error_model="numpy")
def _ipm(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it):
    """Primal-dual interior point on a fixed constraint set. Returns (status, iterations).

    Allocates the work arrays; the iterations run in :func:`_ipm_core`, compiled without
    reference counting (array views and helper calls inside it then cost nothing extra).
    """
    nb = 2 * n
    nx = nb + 2
    grad = np.zeros(nx)
    step = np.zeros(nx)
    xt = np.zeros(nx)
    res = np.zeros(nx)
    ab = np.zeros((nb, BW + 1))
    lb = np.zeros((nb, BW + 1))
    bb = np.zeros((nb, 2))
    dd = np.zeros((2, 2))
    ybuf = np.zeros((nb, 2))
    rb = np.zeros(nb)
    ob = np.zeros(nb)
    rt = np.zeros(2)
    ot = np.zeros(2)
    g = np.zeros(mcount)
    gt = np.zeros(mcount)
    sig = np.zeros(mcount)
    dlam = np.zeros(mcount)
    grad5 = np.zeros(5)
    hess5 = np.zeros((5, 5))
    dofs = np.zeros(5, dtype=np.int64)
    gb = np.zeros(nx)
    cg = np.zeros((mcount, 5))
    cd = np.zeros((mcount, 5), dtype=np.int64)
    ch = np.zeros((mcount, CH_BLOCK + 1))
    return _ipm_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it,
                     grad, step, xt, res, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, gt, sig,
                     dlam, grad5, hess5, dofs, gb, cg, cd, ch)


@njit(cache=True, error_model="numpy", _nrt=False)
def _ipm_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it,
              grad, step, xt, res, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, gt, sig, dlam,
              grad5, hess5, dofs, gb, cg, cd, ch):
    nb = 2 * n
    nx = nb + 2
    tol = max(opts[O_TOL] * fscale, 1e-15 * max(prm[P_KC], prm[P_KR]))
    maxit = int(opts[O_MAXIT])
    mu = mu0
    mu_min = 1e-3 * tol
    shrink = 0.01
    shift_last = 0.0
    kreg = 1e-10 * max(prm[P_KC], prm[P_KR])
    it = 0
    n_neg = 0
    n_walled = 0
    have_acc = False  # merit parts at x known (from the line search that reached x)
    e_acc = 0.0
    l_acc = 0.0
    _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, g)
    while it < maxit:
        # exact Hessian first; where it is indefinite (compressed springs), the Hessian with the
        # springs' negative geometric stiffness and the constraint curvature removed (made from
        # the exact one in place, _drop_curvature); a diagonal shift only as a last resort.
        # The same pass gives the stationarity residual (sig = lam / g does not depend on mu).
        for m in range(mcount):
            sig[m] = lam[m] / g[m]
        _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd,
                       g, grad5, hess5, dofs, mu, False, gb, res, cg, cd, ch)
        kkt = 0.0
        for d in range(nx):
            kkt = max(kkt, abs(res[d]))
        # convergence test; reduce mu while the barrier subproblem is solved
        done = False
        while True:
            cmax = 0.0
            for m in range(mcount):
                cmax = max(cmax, abs(lam[m] * g[m] - mu))
            if mu <= mu_min and kkt <= 10.0 * tol and cmax <= 10.0 * tol:
                done = True
                break
            if mu > mu_min and kkt <= 10.0 * max(mu, tol) and cmax <= 10.0 * max(mu, tol):
                mu_new = max(mu_min, min(0.2 * mu, mu ** 1.5))
                # active gaps scale with mu: let them shrink by that factor in one step
                shrink = min(0.01, 0.1 * mu_new / mu)
                for d in range(nx):
                    grad[d] += (mu - mu_new) * gb[d]
                mu = mu_new
                continue
            break
        if done:
            work_it[0] += it
            return OK, it
        it += 1
        _rhs_to_band(grad, bidx, nb, rb, rt)
        shift = kreg
        ok = _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, ob, ot)
        if ok:
            n_neg = 0
        else:
            if mu < 1e-7 * fscale:
                n_neg += 1
                if n_neg >= 6:
                    # negative curvature at a nearly converged barrier problem: a saddle that
                    # descent from a symmetric start cannot leave; the caller perturbs and retries
                    work_it[0] += it
                    return SADDLE, it
            _drop_curvature(x, n, prm, bidx, kinds, fj, mcount, cd, ch, hess5, dofs, ab, bb,
                            dd)
            ok = _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, ob, ot)
        if not ok:
            shift = max(shift_last / 3.0, 1e-8 * max(prm[P_KC], prm[P_KR]))
            while not ok:
                ok = _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, ob, ot)
                if ok:
                    break
                shift *= 8.0
                if shift > 1e12 * max(prm[P_KC], 1.0):
                    work_it[0] += it
                    return LINALG_FAIL, it
            shift_last = shift
        slope = _step_from_band(ob, ot, bidx, nb, grad, step)
        # damp huge finger rotations (a full step can jump a finger past a vertex)
        smax = 0.0
        for d in range(nb):
            smax = max(smax, abs(step[d]))
        alpha = 1.0
        lim = max(smax / 0.1, abs(step[nb]) / 0.05, abs(step[nb + 1]) / 0.05)
        if lim > 1.0:
            alpha = 1.0 / lim
        if not have_acc:
            e_acc, l_acc = _merit(x, n, prm, kinds, fj, fidx, mcount, gt)
            have_acc = True
        # the merit at x from its parts (kept from the step that reached x; mu may have moved)
        phi0 = e_acc - mu * l_acc
        accepted = False
        walled = False
        for _ls in range(60):
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
            e_t, l_t = _merit(xt, n, prm, kinds, fj, fidx, mcount, gt)
            phi = e_t - mu * l_t
            if phi < math.inf:
                feasible = True
                for m in range(mcount):
                    if gt[m] < shrink * g[m]:
                        feasible = False
                        break
                if feasible and _tunnels(x, xt, n, prm):
                    feasible = False
                    walled = True
                if feasible and phi <= phi0 + 1e-4 * alpha * slope + 1e-15 * abs(phi0):
                    accepted = True
                    e_acc = e_t
                    l_acc = l_t
                    break
            alpha *= 0.5
        # a corner or a point held back only by the anti-tunnelling tests (a contact the
        # candidate set lacks): hand back to the caller, which adds what is touched
        n_walled = n_walled + 1 if (walled and alpha < 1e-2) else 0
        if n_walled >= 3:
            work_it[0] += it
            return BLOCKED, it
        if not accepted:
            # tiny progress is impossible at this mu: accept if already stationary to round-off
            if kkt <= 1e3 * tol:
                mu = max(mu_min, 0.2 * mu)
                if mu <= mu_min:
                    work_it[0] += it
                    return OK, it
                continue
            work_it[0] += it
            return LINESEARCH_FAIL, it
        # multiplier step: Newton direction at the old point, its own fraction-to-boundary step
        # (constraint gradients at x kept by _newton_matrix)
        alpha_d = 1.0
        for m in range(mcount):
            nd = 3 if kinds[m] == 0 else (5 if kinds[m] == 1 else 1)
            dl = 0.0
            for a in range(nd):
                dl += cg[m, a] * step[cd[m, a]]
            dlam[m] = mu / g[m] - lam[m] - sig[m] * dl
            if dlam[m] < 0.0:
                alpha_d = min(alpha_d, -0.99 * lam[m] / dlam[m])
        for m in range(mcount):
            lam_new = lam[m] + alpha_d * dlam[m]
            gm = gt[m]
            lam[m] = min(max(lam_new, mu / (1e10 * gm)), 1e10 * mu / gm)
        if opts.shape[0] > N_OPTIONS:
            print("ipm", it, mu / fscale, kkt / fscale, alpha, shift, ok, mcount)
        for d in range(nx):
            x[d] = xt[d]
        for m in range(mcount):
            g[m] = gt[m]  # the gaps at the accepted point, from its merit evaluation
    work_it[0] += it
    return ITER_LIMIT, it


@njit(cache=True, error_model="numpy", _nrt=False)
def _al_merit(x, n, prm, kinds, fj, fidx, mcount, lam, active, rho, g_ref):
    """Augmented Lagrangian E - sum lam g + rho/2 sum g^2 over the active constraints.

    Infinite where an inactive constraint is violated more than at the reference gaps
    ``g_ref`` (the polish walks along the active set; it must not run through another contact).
    """
    e = _energy(x, n, prm)
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(mcount):
        gm = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)
        if active[m]:
            e += gm * (0.5 * rho * gm - lam[m])
        elif gm < min(g_ref[m], 0.0) - 1e-12:
            return math.inf
    return e


@njit(cache=True, error_model="numpy")
def _polish(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active, work_it):
    """Augmented-Lagrangian Newton on the active set: contacts hold to round-off.

    Allocates the work arrays for :func:`_polish_core` (compiled without reference counting).

    Returns (ok, stable) where stable means the final Newton matrix needed no shift.
    """
    nb = 2 * n
    nx = nb + 2
    grad = np.zeros(nx)
    ab = np.zeros((nb, BW + 1))
    lb = np.zeros((nb, BW + 1))
    bb = np.zeros((nb, 2))
    dd = np.zeros((2, 2))
    ybuf = np.zeros((nb, 2))
    rb = np.zeros(nb)
    ob = np.zeros(nb)
    rt = np.zeros(2)
    ot = np.zeros(2)
    g = np.zeros(mcount)
    sig = np.zeros(mcount)
    lam_eff = np.zeros(mcount)
    res = np.zeros(nx)
    res_p = np.zeros(nx)
    gbuf_p = np.zeros(nx)
    xt = np.zeros(nx)
    step = np.zeros(nx)
    grad5 = np.zeros(5)
    hess5 = np.zeros((5, 5))
    dofs = np.zeros(5, dtype=np.int64)
    cg = np.zeros((mcount, 5))
    cd = np.zeros((mcount, 5), dtype=np.int64)
    ch = np.zeros((mcount, CH_BLOCK + 1))
    return _polish_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                        work_it, grad, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, sig, lam_eff,
                        res, res_p, gbuf_p, xt, step, grad5, hess5, dofs, cg, cd, ch)


@njit(cache=True, error_model="numpy", _nrt=False)
def _polish_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active, work_it,
                 grad, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, sig, lam_eff, res, res_p,
                 gbuf_p, xt, step, grad5, hess5, dofs, cg, cd, ch):
    nb = 2 * n
    nx = nb + 2
    kscale = max(prm[P_KC], prm[P_KR], prm[P_KAPPA])
    rho = 1e2 * kscale
    tol = max(opts[O_TOL] * fscale, 1e-15 * max(prm[P_KC], prm[P_KR]))
    q = x[:nb].reshape(n, 2)
    for m in range(mcount):
        if not active[m]:
            lam[m] = 0.0
    stable = True
    kreg = 1e-10 * max(prm[P_KC], prm[P_KR])
    for _outer in range(40):
        work_it[0] += 1
        sn, cs = _trig(x, n)
        for m in range(mcount):
            gm = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)
            g[m] = gm
            if active[m]:
                sig[m] = rho
                lam_eff[m] = lam[m] - rho * gm
            else:
                sig[m] = 0.0
                lam_eff[m] = 0.0
        _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam_eff, sig, grad, ab, bb,
                       dd, g, grad5, hess5, dofs, 0.0, False, gbuf_p, res_p, cg, cd, ch)
        _rhs_to_band(grad, bidx, nb, rb, rt)
        shift = kreg
        ok = _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, ob, ot)
        stable = ok
        while not ok:
            shift = max(shift * 8.0, 1e-8 * kscale)
            if shift > 1e6 * kscale:
                return False, False
            ok = _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, ob, ot)
        # backtracking on the augmented Lagrangian (its Hessian, possibly shifted, gave the
        # step): a plain Newton step from an indefinite matrix can throw the iterate far off
        slope = _step_from_band(ob, ot, bidx, nb, grad, step)
        # the merit at x from the gaps above (what _al_merit would evaluate again)
        m0 = _energy(x, n, prm)
        for m in range(mcount):
            if active[m]:
                m0 += g[m] * (0.5 * rho * g[m] - lam[m])
        alpha = 1.0
        hit = False
        for _ls in range(40):
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
            mt = _al_merit(xt, n, prm, kinds, fj, fidx, mcount, lam, active, rho, g)
            if mt <= m0 + 1e-4 * alpha * slope + 1e-13 * abs(m0):
                break
            hit = hit or mt == math.inf
            alpha *= 0.5
        if hit:
            # the full step ran through contacts left out of the set: take them in (the
            # caller drops them again should they come out pulling)
            for d in range(nx):
                xt[d] = x[d] + 2.0 * alpha * step[d]
            qt = xt[:nb].reshape(n, 2)
            snt, cst = _trig(xt, n)
            for m in range(mcount):
                if not active[m]:
                    gm = _con_value(kinds[m], fj[m], fidx[m], xt, qt, n, prm, snt, cst)
                    if gm < min(g[m], 0.0):
                        active[m] = True
                        lam[m] = 0.0
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
        for d in range(nx):
            x[d] = xt[d]
        # multiplier update
        sn, cs = _trig(x, n)
        for m in range(mcount):
            if active[m]:
                gm = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)
                lam[m] = lam[m] - rho * gm
        kkt = _stationarity(x, n, prm, kinds, fj, fidx, mcount, lam, g, grad5, hess5, dofs,
                            res)
        viol = 0.0
        for m in range(mcount):
            if active[m]:
                viol = max(viol, abs(g[m]))
        if kkt <= 10.0 * tol and viol <= 1e-13:
            return True, stable
        if _outer >= 8 and kkt <= 100.0 * tol and viol <= 1e-12:
            # stagnating at round-off level: good enough (the independent check has the say)
            return True, stable
    return False, stable


@njit(cache=True, error_model="numpy")
def _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                work_it, gbuf, stable_out):
    """Polish on a contact set, correcting the set (primal-dual active set) a few times.

    Drops contacts that come out with a pulling force and adds constraints that come out
    violated. On success ``xs`` and ``lam`` hold the polished answer; returns a status.
    """
    nb = 2 * n
    for _attempt in range(6):
        xp = xs.copy()
        lp = lam[:mcount].copy()
        okp, stable = _polish(xp, lp, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale,
                              active, work_it)
        stable_out[0] = stable
        if not okp:
            return POLISH_FAIL
        _all_gaps(xp, n, prm, kinds[:mcount], fj, fidx, gbuf)
        good = True
        for m in range(mcount):
            if active[m] and lp[m] < -1e-12 * fscale:
                active[m] = False
                good = False
            elif (not active[m]) and gbuf[m] < -1e-10:
                active[m] = True
                good = False
        if good:
            for d in range(nb + 2):
                xs[d] = xp[d]
            for m in range(mcount):
                lam[m] = max(lp[m], 0.0) if active[m] else 0.0
            return OK
    return POLISH_FAIL


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_force(x, prm):
    """Magnitude of the gauge spring's force on point 0 at state x (scaled units)."""
    _, _, ut = _gauge_stretch(x, prm)
    return abs(prm[P_GAUGE] * ut)


@njit(cache=True, error_model="numpy", _nrt=False)
def _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, attempt, gbuf, opening=0.01):
    """New start point near a saddle: rotate the contour about the pin, open the fingers."""
    nb = 2 * n
    angle = (0.25 if attempt % 2 == 1 else -0.25) * attempt * 2.0 * math.pi / n
    c = math.cos(angle)
    s = math.sin(angle)
    for i in range(n):
        qx, qy = xs[2 * i], xs[2 * i + 1]
        x0[2 * i] = c * qx - s * qy
        x0[2 * i + 1] = s * qx + c * qy
    for _k in range(16):
        for j in range(2):
            x0[nb + j] = min(xs[nb + j] + opening, prm[P_TH0])
        _all_gaps(x0, n, prm, kinds[:mcount], fj, fidx, gbuf)
        ok = True
        for m in range(mcount):
            if not gbuf[m] > 1e-8:
                ok = False
        # corner gaps are distances to segments: a corner inside the contour has them positive
        if ok and _crossed_through(x0, n, prm):
            ok = False
        if ok:
            return True
        opening *= 2.0
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _initial_candidates(x0, n, prm, face_cand, corner_cand, edges, sweep):
    """Candidate constraints at the start point ``x0`` (see :func:`solve_one` for the policies).

    Every point against each finger body; each corner against the contour edges near the arc
    it sweeps as its finger closes (all edges clear of it for the tip corners of policy 1).
    Work arrays: ``edges`` float (n, 4), ``sweep`` float (CORNER_SWEEP, 2).
    """
    nb = 2 * n
    q0 = x0[:nb].reshape(n, 2)
    sn, cs = _trig(x0, n)
    for k in range(n):
        # each edge's bounding circle grown by the corner radius and the band: a cheap reject
        k1 = k + 1 if k + 1 < n else 0
        ex = q0[k1, 0] - q0[k, 0]
        ey = q0[k1, 1] - q0[k, 1]
        edges[k, 0] = 0.5 * (q0[k, 0] + q0[k1, 0])
        edges[k, 1] = 0.5 * (q0[k, 1] + q0[k1, 1])
        far = 0.5 * math.sqrt(ex * ex + ey * ey) + prm[P_RHO] + CORNER_NEAR
        edges[k, 2] = far * far
    for j in range(2):
        th = x0[nb + j]
        for i in range(n):
            # every point: a far one costs a little, a late one a whole extra round
            face_cand[j, i] = _face_gap(q0, i, j, _sel(sn, j), _sel(cs, j), prm) > 1e-12
        # edges near the arc each corner sweeps as the finger closes (policy 1: every edge
        # clear of the tip corners at the start), sampled; the samples lie on a circle about
        # the joint, so an edge whose bounding circle misses that circle's ring is skipped
        for t in range(CORNER_SWEEP):
            ths = th + (prm[P_THMIN] - th) * t / (CORNER_SWEEP - 1)
            sweep[t, 0] = math.sin(ths)
            sweep[t, 1] = math.cos(ths)
        jx = -prm[P_C0X + 2 * j]
        jy = -prm[P_C0X + 2 * j + 1]
        for k in range(n):
            mx = edges[k, 0] - jx
            my = edges[k, 1] - jy
            edges[k, 3] = math.sqrt(mx * mx + my * my)
        for c in range(4):
            swept = not (c % 2 == 0 and prm[P_POLICY] > 0.0)
            kx, ky = _corner_centre(j, sweep[0, 0], sweep[0, 1], c, prm)
            rc = math.sqrt((kx - jx) * (kx - jx) + (ky - jy) * (ky - jy))
            for k in range(n):
                corner_cand[j, c, k] = False
                if swept:
                    dr = edges[k, 3] - rc
                    if dr * dr >= edges[k, 2] * (1.0 + 1e-12):
                        continue
                # an edge already crossed at the start is left out
                if not _corner_gap(q0, k, j, _sel(sn, j), _sel(cs, j), c, prm) > 1e-12:
                    continue
                if not swept:
                    corner_cand[j, c, k] = True
                    continue
                for t in range(CORNER_SWEEP):
                    kx, ky = _corner_centre(j, sweep[t, 0], sweep[t, 1], c, prm)
                    mx = edges[k, 0] - kx
                    my = edges[k, 1] - ky
                    if mx * mx + my * my < edges[k, 2]:
                        if _seg_dist(q0, k, kx, ky) - prm[P_RHO] < CORNER_NEAR:
                            corner_cand[j, c, k] = True
                            break


@njit(cache=True, error_model="numpy", _nrt=False)
def _grow_candidates(xs, x0, n, prm, face_cand, corner_cand, blocked, commit=True):
    """Add the constraints left out at the start point ``x0`` that the answer ``xs`` of a round
    touches or has crossed (and, after a blocked run, the corner edges just short of it).
    Returns whether any was added; with ``commit=False`` only whether any would be (the sets
    are left as they are)."""
    nb = 2 * n
    changed = False
    q = xs[:nb].reshape(n, 2)
    q0 = x0[:nb].reshape(n, 2)
    sn, cs = _trig(xs, n)
    sn0, cs0 = _trig(x0, n)
    for j in range(2):
        for i in range(n):
            if not face_cand[j, i]:
                g = _face_gap(q, i, j, _sel(sn, j), _sel(cs, j), prm)
                if g < 1e-9:
                    g0 = _face_gap(q0, i, j, _sel(sn0, j), _sel(cs0, j), prm)
                    if g0 > 1e-12:
                        if not commit:
                            return True
                        face_cand[j, i] = True
                        changed = True
        for c in range(4):
            # edges left out at the start that the corner now touches or crossed
            kx, ky = _corner_centre(j, _sel(sn, j), _sel(cs, j), c, prm)
            crossed = _inside(q, n, kx, ky)
            # a blocked interior-point run stopped short of the edge that holds it back
            near_hit = CORNER_NEAR if crossed else 0.02
            for k in range(n):
                if corner_cand[j, c, k]:
                    continue
                g = _corner_gap(q, k, j, _sel(sn, j), _sel(cs, j), c, prm)
                if g < 1e-9 or ((crossed or blocked) and g < near_hit):
                    g0 = _corner_gap(q0, k, j, _sel(sn0, j), _sel(cs0, j), c, prm)
                    if g0 > 1e-12:
                        if not commit:
                            return True
                        corner_cand[j, c, k] = True
                        changed = True
    return changed


@njit(cache=True, error_model="numpy")
def solve_one(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand, face_cand, info):
    """Solve one grasp in place, trying up to two contact policies.

    Policy 0 (fast): corner-edge constraints for the edges near the arc each corner sweeps as
    its finger closes. Policy 1: every contour edge for the tip corners. In both, line-search
    steps that would carry a corner or a point right through the contour or a finger are
    refused (the gaps are distances, positive again on the far side). Policy 1 starts again
    from the given start point and runs only when policy 0 failed (an inverted fan, a property
    of the model, is not retried). Arguments as in :func:`_solve_attempt`; ``info[1]`` counts
    the iterations of both attempts.
    """
    x_in = x.copy()
    lam_in = lam_face.copy()
    total = 0.0
    for policy in range(2):
        if policy > 0:
            x[:] = x_in
            lam_face[:, :] = lam_in
        _solve_attempt(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand,
                       face_cand, info, float(policy))
        total += info[1]
        if info[0] == OK or info[0] == INVERTED:
            break
    info[1] = total


@njit(cache=True, error_model="numpy")
def _solve_attempt(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand, face_cand,
                   info, policy):
    """Solve one grasp in place.

    Parameters
    ----------
    n : int
        Number of triangles.
    prm : float64[14]
        Scaled problem parameters (:func:`envs.psm.scaled_problem`).
    opts : float64[5]
        Options (:func:`default_options`).
    x : float64[2n + 2]
        In: start point (contour points relative to the centre in units of r, then the finger
        angles); must be strictly feasible. Out: the solution.
    lam_face : float64[2, n]
        In: multipliers of the previous solution (warm start) or zeros; out: scaled face contact
        forces.
    lam_corner : float64[2, 4, n]
        Out: scaled force of each corner (finger; face tip, face root, back tip, back root) on
        each contour edge k -> k+1.
    lam_stop : float64[2]
        Out: scaled joint-stop torques.
    corner_cand : bool[2, 4, n]
        Work/out: corner-edge constraints considered.
    face_cand : bool[2, n]
        Work/out: face constraints considered.
    info : float64[8]
        Out: status, Newton iterations, rounds, stable flag, stationarity, max |gap| of contacts,
        min gap, number of inverted fan triangles.
    """
    nb = 2 * n
    prm = np.zeros(P_POLICY + 1)
    npr = min(prm_in.shape[0], P_GAUGE)
    prm[:npr] = prm_in[:npr]
    # the gauge spring holds the nearly free turn of the polygon about its pin while the
    # contacts form (released once the contact set settles). Fine fans need it most: without
    # it the interior-point iterates swung the polygon to and fro at N = 500 and ran into the
    # iteration limit at nearly every torque of the paper sweep
    prm[P_GAUGE] = opts[O_GAUGE] * max(prm[P_KC], prm[P_KR])
    prm[P_POLICY] = policy
    bidx = _band_index(n)
    x0 = x.copy()
    mmax = 10 * n + 2
    kinds = np.zeros(mmax, dtype=np.int64)
    fj = np.zeros(mmax, dtype=np.int64)
    fidx = np.zeros(mmax, dtype=np.int64)
    lam = np.zeros(mmax)
    gbuf = np.zeros(mmax)
    grad5 = np.zeros(5)
    hess5 = np.zeros((5, 5))
    dofs = np.zeros(5, dtype=np.int64)
    work_it = np.zeros(1, dtype=np.int64)
    tau = prm[P_TAU]
    fscale = max(tau, prm[P_KAPPA] * abs(prm[P_TH0] - prm[P_THMIN]), 1e-300)
    tol = max(opts[O_TOL] * fscale, 1e-15 * max(prm[P_KC], prm[P_KR]))
    # initial candidate sets, evaluated at the start point (the same band for every N: with
    # the gauge on fine fans too, a band twice as wide at N > 100 was slower and no safer in
    # the paper sweep; an edge met outside it joins in a later round)
    _initial_candidates(x0, n, prm, face_cand, corner_cand, np.zeros((n, 4)),
                        np.zeros((CORNER_SWEEP, 2)))
    lam_guess_face = lam_face.copy()
    stable_out = np.ones(1, dtype=np.bool_)
    last_kinds = np.zeros(mmax, dtype=np.int64)
    last_fj = np.zeros(mmax, dtype=np.int64)
    last_fidx = np.zeros(mmax, dtype=np.int64)
    last_m = 0
    saddle = False
    status = OK
    escapes = 0
    rounds = 0
    stable = True
    xs = x0.copy()
    for rnd in range(int(opts[O_MAXROUND]) + 3):
        rounds = rnd + 1
        mcount = _build_constraints(face_cand, corner_cand, n, kinds, fj, fidx)
        for d in range(nb + 2):
            xs[d] = x0[d]
        _all_gaps(xs, n, prm, kinds[:mcount], fj, fidx, gbuf)
        # initial barrier parameter: from warm-start multipliers when given, else a force scale
        mu0 = abs(opts[O_MU0]) * fscale * 0.05
        have_warm = False
        acc = 0.0
        cnt = 0
        for m in range(mcount):
            if kinds[m] == 0 and lam_guess_face[fj[m], fidx[m]] > 0.0:
                acc += lam_guess_face[fj[m], fidx[m]] * gbuf[m]
                cnt += 1
                have_warm = True
        if have_warm:
            mu0 = max(acc / cnt, 1e-6 * mu0)
        feasible = True
        for m in range(mcount):
            if not gbuf[m] > 0.0:
                feasible = False
            lam[m] = mu0 / gbuf[m]
            if kinds[m] == 0 and lam_guess_face[fj[m], fidx[m]] > 0.0:
                lam[m] = lam_guess_face[fj[m], fidx[m]]
        if not feasible:
            status = INFEASIBLE_START
            break
        if work_it[0] > 2 * int(opts[O_MAXIT]):
            # bound the cost of a hopeless solve over all rounds
            status = ITER_LIMIT
            break
        status, _ = _ipm(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0,
                         work_it)
        last_m = mcount
        last_kinds[:mcount] = kinds[:mcount]
        last_fj[:mcount] = fj[:mcount]
        last_fidx[:mcount] = fidx[:mcount]
        if status == SADDLE and escapes < 3:
            escapes += 1
            if _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, escapes, gbuf):
                for m in range(mcount):
                    if kinds[m] == 0:
                        lam_guess_face[fj[m], fidx[m]] = lam[m]
                continue
        if status == SADDLE:
            # escapes exhausted: polish where we are; the answer is reported as not stable
            status = OK
            saddle = True
        blocked = status == BLOCKED
        if status != OK and not blocked:
            break
        # identify the contact set and polish
        _all_gaps(xs, n, prm, kinds[:mcount], fj, fidx, gbuf)
        active = np.zeros(mcount, dtype=np.bool_)
        for m in range(mcount):
            active[m] = lam[m] > gbuf[m] * fscale and gbuf[m] < 1e-5
        skip_gauge_polish = False
        if (opts[O_POLISH] > 0.0 and not blocked and prm[P_GAUGE] > 0.0
                and _gauge_force(xs, prm) <= tol):
            # the gauge holds nothing (a mirror-symmetric answer): the polish with it would
            # solve the same equations as the one without it below; go straight there unless
            # the candidate set changes (then polish as usual, for the next round's start)
            skip_gauge_polish = not _grow_candidates(xs, x0, n, prm, face_cand, corner_cand,
                                                     blocked, False)
        if opts[O_POLISH] > 0.0 and not blocked and not skip_gauge_polish:
            status = _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount,
                                 fscale, active, work_it, gbuf, stable_out)
            stable = stable_out[0]
        # check the candidate set against the solution
        changed = False
        if not skip_gauge_polish:
            changed = _grow_candidates(xs, x0, n, prm, face_cand, corner_cand, blocked)
        if status == POLISH_FAIL or (blocked and not changed):
            # keep the interior-point answer; the caller reports the reason
            break
        if not changed and prm[P_GAUGE] > 0.0:
            # release the rotation gauge: Newton on the contact set without it (its reaction is
            # zero for a mirror-symmetric answer, small otherwise)
            prm[P_GAUGE] = 0.0
            if not skip_gauge_polish:
                for m in range(mcount):
                    active[m] = lam[m] > 0.0
            xkeep = xs.copy()
            lkeep = lam.copy()
            good = _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount,
                               fscale, active, work_it, gbuf, stable_out) == OK
            stable = stable_out[0]
            if not good:
                for d in range(nb + 2):
                    xs[d] = xkeep[d]
                for m in range(mcount):
                    lam[m] = lkeep[m]
                changed = True
                if not _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, 0, gbuf):
                    status = POLISH_FAIL
                    break
        if not changed and not stable and escapes < 3:
            # converged to a saddle (e.g. a symmetric squeeze past a bifurcation): perturb
            escapes += 1
            if _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, escapes, gbuf):
                for m in range(mcount):
                    if kinds[m] == 0:
                        lam_guess_face[fj[m], fidx[m]] = lam[m]
                continue
        if not changed:
            break
        # warm start the next round from this round's answer (fingers opened slightly so that
        # the new candidate set is strictly feasible) and its multipliers
        for m in range(mcount):
            if kinds[m] == 0:
                lam_guess_face[fj[m], fidx[m]] = lam[m]
        mnew = _build_constraints(face_cand, corner_cand, n, kinds, fj, fidx)
        xprev = x0.copy()
        if not _escape(xs, x0, n, prm, kinds, fj, fidx, mnew, 0, gbuf, 1e-4):
            for d in range(nb + 2):
                x0[d] = xprev[d]
        if rnd >= int(opts[O_MAXROUND]) + escapes - 1:
            status = CONTACT_CYCLE
            break
    # outputs, on the constraint list the last solve used (the loop may have changed the
    # candidate sets after it)
    for d in range(nb + 2):
        x[d] = xs[d]
    lam_face[:, :] = 0.0
    lam_corner[:, :, :] = 0.0
    lam_stop[:] = 0.0
    mcount = last_m
    kinds[:mcount] = last_kinds[:mcount]
    fj[:mcount] = last_fj[:mcount]
    fidx[:mcount] = last_fidx[:mcount]
    _all_gaps(xs, n, prm, kinds[:mcount], fj, fidx, gbuf)
    if status == POLISH_FAIL:
        # keep the interior-point answer with the multipliers of open gaps dropped; the
        # independent check decides whether it is an equilibrium
        for m in range(mcount):
            if gbuf[m] > 1e-9:
                lam[m] = 0.0
        status = OK
    gmin = 1e300
    gact = 0.0
    for m in range(mcount):
        gmin = min(gmin, gbuf[m])
        if lam[m] > 0.0:
            gact = max(gact, abs(gbuf[m]))
        if kinds[m] == 0:
            lam_face[fj[m], fidx[m]] = lam[m]
        elif kinds[m] == 1:
            c = fidx[m] // n
            lam_corner[fj[m], c, fidx[m] - c * n] = lam[m]
        else:
            lam_stop[fj[m]] = lam[m]
    res = np.zeros(nb + 2)
    kkt = _stationarity(xs, n, prm, kinds, fj, fidx, mcount, lam, gbuf, grad5, hess5, dofs,
                        res)
    # a fan triangle (centre, q_i, q_i+1) turned over: the springs allow this fold at finite
    # energy, the material does not; the answer is an equilibrium of the model but not a grasp
    inverted = 0
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        if xs[2 * i] * xs[2 * i1 + 1] - xs[2 * i + 1] * xs[2 * i1] <= 0.0:
            inverted += 1
    if status == OK:
        # final guard over every point and corner, candidates or not
        q = xs[:nb].reshape(n, 2)
        sn, cs = _trig(xs, n)
        for j in range(2):
            for i in range(n):
                if _face_gap(q, i, j, _sel(sn, j), _sel(cs, j), prm) < -1e-9:
                    status = PENETRATION
        if _crossed_through(xs, n, prm):
            status = PENETRATION
    if status == OK and kkt > 1e-9 * fscale + 1e-13 * max(prm[P_KC], prm[P_KR]):
        # the interior-point answer kept after a failed polish is not an equilibrium to the
        # required accuracy: let the caller try another policy
        status = POLISH_FAIL
    if status == OK and inverted > 0:
        # reported as a fold only once it is known to be an equilibrium
        status = INVERTED
    info[0] = status
    info[1] = work_it[0]
    info[2] = rounds
    info[3] = 1.0 if (stable and not saddle) else 0.0
    info[4] = kkt / fscale
    info[5] = gact
    info[6] = gmin
    info[7] = inverted


@njit(cache=True, error_model="numpy", parallel=True)
def solve_batch(n, prms, opts, xs, lam_face, lam_corner, lam_stop, corner_cand, face_cand, infos):
    """:func:`solve_one` over a batch (first axis), in parallel threads."""
    for b in prange(prms.shape[0]):
        solve_one(n, prms[b], opts, xs[b], lam_face[b], lam_corner[b], lam_stop[b],
                  corner_cand[b], face_cand[b], infos[b])
