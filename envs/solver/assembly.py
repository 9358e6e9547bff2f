"""Assembly of the barrier merit, the Newton matrix (band order) and the stationarity residual
from the model's energy terms and the contact constraints.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.energy import (
    _cst_triangle,
    area_curvature,
    area_slope,
    cst_hessian_column,
    mesh_energy,
    mesh_gradient,
    quad_area,
    spring_hessian,
    tri_area,
)
from ..model.layout import (
    P_GAUGE,
    P_GREF,
    P_KA,
    P_KAPPA,
    P_KC,
    P_KR,
    P_LAM,
    P_MU,
    P_PHASE,
    P_QUAD,
    P_RINGS,
)
from ..model.rings import (
    edge_constants,
    edge_ends,
    edge_xy,
    n_edge_types,
    n_tri_types,
    quad_corners,
    quad_rest_area_at,
    quad_xy,
    tri_corners,
    tri_rest_area,
    tri_xy,
)
from .contact import (
    _con_eval,
    _con_value,
    _trig,
    constraint_dofs,
)

CH_BLOCK = 15  # column of the constraint curvature cache: 1 where the constraint has a block


@njit(cache=True, error_model="numpy", _nrt=False)
def _energy(x, n, prm):
    """The model's energy plus the solver's rotation gauge spring (when on)."""
    e = mesh_energy(x, n, prm)
    kg = prm[P_GAUGE]
    if kg > 0.0:
        _, _, ut = _gauge_stretch(x, prm)
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
def _add_edge(ab, bb, dd, nb, pa, pb, kxx, kyy, kxy):
    """:func:`_add_spring` for an edge whose first end may be fixed (``pa < 0``)."""
    if pa < 0:
        _add_point(ab, pb, kxx, kyy, kxy)
    else:
        _add_spring(ab, bb, dd, nb, pa, pb, kxx, kyy, kxy)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _band_of(bidx, n, m, k, i):
    """Band row of point ``(k, i)`` of the mesh (-1 for a fixed point)."""
    if k == m:
        return bidx[i]
    if k == 0:
        return -1
    return bidx[n + (k - 1) * n + i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_stretch(x, prm):
    """Tangent (tx, ty) of the contour at point 0's rest position and the gauge spring's
    stretch along it: point 0's displacement along the tangent less the spring's anchor (slot
    ``P_GREF``: zero while the gauge holds the rest position; a parameter vector without that
    slot, as in the derivative tests, has no anchor)."""
    tx, ty = -math.sin(prm[P_PHASE]), math.cos(prm[P_PHASE])
    ref = prm[P_GREF] if prm.shape[0] > P_GREF else 0.0
    return tx, ty, (x[0] - ty) * tx + (x[1] + tx) * ty - ref


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _tri_pair(ab, bb, dd, nb, pu, pv, gxu, gyu, gxv, gyv, curv, half_slope):
    """Coupling block of two free corners u, v of a triangle: ``E'' g_u g_v^T`` plus the area's
    bilinear term (``half_slope = +-E'/2``: + when v follows u counter-clockwise)."""
    _add(ab, bb, dd, nb, pu, pv, curv * gxu * gxv)
    _add(ab, bb, dd, nb, pu, pv + 1, curv * gxu * gyv + half_slope)
    _add(ab, bb, dd, nb, pu + 1, pv, curv * gyu * gxv - half_slope)
    _add(ab, bb, dd, nb, pu + 1, pv + 1, curv * gyu * gyv)


@njit(cache=True, error_model="numpy", _nrt=False)
def _area_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign=1.0):
    """Hessian (band order) of the area energy of every triangle of the mesh.

    ``H = E'' g g^T + E' d2A`` with ``g = dA/dq`` and ``d2A`` the constant bilinear coupling of
    two corners (``+1/2`` between ``x_u`` and ``y_v`` when v follows u counter-clockwise,
    ``-1/2`` the other way). ``psd`` keeps only a non-negative ``E'' g g^T`` (the indefinite
    coupling and a negative curvature dropped) for the interior point's convexified fallback.
    ``sign = -1`` takes a Hessian out again.
    """
    nb = ab.shape[0]
    m = int(prm[P_RINGS])
    for t in range(n_tri_types(m)):
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            xa, ya, xb, yb, xc, yc = tri_xy(x, n, m, prm, t, i)
            area = tri_area(xa, ya, xb, yb, xc, yc)
            a0 = tri_rest_area(prm, t, i, m)
            curv = area_curvature(area, prm[P_KA], a0)
            slope = area_slope(area, prm[P_KA], a0)
            if psd:
                curv = max(curv, 0.0)
                slope = 0.0
            curv *= sign
            slope *= sign
            half = 0.5 * slope
            gxa, gya = 0.5 * (yb - yc), 0.5 * (xc - xb)
            gxb, gyb = 0.5 * (yc - ya), 0.5 * (xa - xc)
            gxc, gyc = 0.5 * (ya - yb), 0.5 * (xb - xa)
            pa = _band_of(bidx, n, m, ka, ia)
            pb = _band_of(bidx, n, m, kb, ib)
            pc = _band_of(bidx, n, m, kc, ic)
            if pa >= 0:
                _add_point(ab, pa, curv * gxa * gxa, curv * gya * gya, curv * gxa * gya)
            if pb >= 0:
                _add_point(ab, pb, curv * gxb * gxb, curv * gyb * gyb, curv * gxb * gyb)
            if pc >= 0:
                _add_point(ab, pc, curv * gxc * gxc, curv * gyc * gyc, curv * gxc * gyc)
            if pa >= 0 and pb >= 0:
                _tri_pair(ab, bb, dd, nb, pa, pb, gxa, gya, gxb, gyb, curv, half)
            if pa >= 0 and pc >= 0:
                _tri_pair(ab, bb, dd, nb, pa, pc, gxa, gya, gxc, gyc, curv, -half)
            if pb >= 0 and pc >= 0:
                _tri_pair(ab, bb, dd, nb, pb, pc, gxb, gyb, gxc, gyc, curv, half)


@njit(cache=True, error_model="numpy", _nrt=False)
def _quad_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign=1.0):
    """Hessian (band order) of the volumetric energy of every quad (the nh-quad element).

    As :func:`_area_hessian` on the quad's area: ``E'' g g^T`` over its four corners plus
    ``E' d2A``, the bilinear coupling of neighbouring corners (opposite corners have none).
    """
    nb = ab.shape[0]
    m = int(prm[P_RINGS])
    for k in range(1, m + 1):
        for i in range(n):
            a0 = quad_rest_area_at(prm, n, m, k, i)
            ka, ia, kb, ib, kc, ic, kd, id_ = quad_corners(k, i, n)
            xa, ya, xb, yb, xc, yc, xd, yd = quad_xy(x, n, m, prm, k, i)
            area = quad_area(xa, ya, xb, yb, xc, yc, xd, yd)
            curv = area_curvature(area, prm[P_QUAD], a0)
            slope = area_slope(area, prm[P_QUAD], a0)
            if psd:
                curv = max(curv, 0.0)
                slope = 0.0
            curv *= sign
            half = 0.5 * slope * sign
            # corners a, b, c, d counter-clockwise: gradient (y_next - y_prev, x_prev - x_next)/2
            ps = (_band_of(bidx, n, m, ka, ia), _band_of(bidx, n, m, kb, ib),
                  _band_of(bidx, n, m, kc, ic), _band_of(bidx, n, m, kd, id_))
            gs = ((0.5 * (yb - yd), 0.5 * (xd - xb)), (0.5 * (yc - ya), 0.5 * (xa - xc)),
                  (0.5 * (yd - yb), 0.5 * (xb - xd)), (0.5 * (ya - yc), 0.5 * (xc - xa)))
            for u in range(4):
                pu = ps[u]
                if pu < 0:
                    continue
                gxu, gyu = gs[u]
                _add_point(ab, pu, curv * gxu * gxu, curv * gyu * gyu, curv * gxu * gyu)
                for v in range(u + 1, 4):
                    pv = ps[v]
                    if pv < 0:
                        continue
                    gxv, gyv = gs[v]
                    # v follows u (+), precedes it (the pair d, a: -), or is opposite (0)
                    hs = half if v == u + 1 else (-half if v - u == 3 else 0.0)
                    _tri_pair(ab, bb, dd, nb, pu, pv, gxu, gyu, gxv, gyv, curv, hs)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _cst_block(cols, tu0, tu1, tv0, tv1, r, rp):
    """Entry (r, r') of the 2x2 block between corners u and v of a constant-strain triangle:
    ``sum_e sum_e' T_u[e] T_v[e'] d2E / dDs[r, e] dDs[r', e']`` (``T``: how a corner enters
    the two edges, a: (-1, -1), b: (1, 0), c: (0, 1))."""
    return (tu0 * (tv0 * cols[2 * r][2 * rp] + tv1 * cols[2 * r][2 * rp + 1])
            + tu1 * (tv0 * cols[2 * r + 1][2 * rp] + tv1 * cols[2 * r + 1][2 * rp + 1]))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _cst_pair(ab, bb, dd, nb, cols, pu, tu0, tu1, pv, tv0, tv1, sign):
    """Add the block between two free corners (the diagonal block when pu == pv)."""
    if pu == pv:
        _add_point(ab, pu, sign * _cst_block(cols, tu0, tu1, tu0, tu1, 0, 0),
                   sign * _cst_block(cols, tu0, tu1, tu0, tu1, 1, 1),
                   sign * _cst_block(cols, tu0, tu1, tu0, tu1, 1, 0))
        return
    for r in range(2):
        for rp in range(2):
            _add(ab, bb, dd, nb, pu + r, pv + rp,
                 sign * _cst_block(cols, tu0, tu1, tv0, tv1, r, rp))


@njit(cache=True, error_model="numpy", _nrt=False)
def _cst_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign=1.0):
    """Hessian (band order) of every constant-strain neo-Hookean triangle (``psd``: the
    tangent at rest, see :func:`envs.model.energy.cst_hessian_column`; ``sign = -1`` takes a
    Hessian out again)."""
    nb = ab.shape[0]
    m = int(prm[P_RINGS])
    mu, lam = prm[P_MU], prm[P_LAM]
    for t in range(n_tri_types(m)):
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0 = _cst_triangle(x, n, m, prm, t, i)
            cols = (cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam,
                                       0, 0, psd),
                    cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam,
                                       0, 1, psd),
                    cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam,
                                       1, 0, psd),
                    cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0, mu, lam,
                                       1, 1, psd))
            pa = _band_of(bidx, n, m, ka, ia)
            pb = _band_of(bidx, n, m, kb, ib)
            pc = _band_of(bidx, n, m, kc, ic)
            if pa >= 0:
                _cst_pair(ab, bb, dd, nb, cols, pa, -1.0, -1.0, pa, -1.0, -1.0, sign)
                if pb >= 0:
                    _cst_pair(ab, bb, dd, nb, cols, pa, -1.0, -1.0, pb, 1.0, 0.0, sign)
                if pc >= 0:
                    _cst_pair(ab, bb, dd, nb, cols, pa, -1.0, -1.0, pc, 0.0, 1.0, sign)
            if pb >= 0:
                _cst_pair(ab, bb, dd, nb, cols, pb, 1.0, 0.0, pb, 1.0, 0.0, sign)
                if pc >= 0:
                    _cst_pair(ab, bb, dd, nb, cols, pb, 1.0, 0.0, pc, 0.0, 1.0, sign)
            if pc >= 0:
                _cst_pair(ab, bb, dd, nb, cols, pc, 0.0, 1.0, pc, 0.0, 1.0, sign)


@njit(cache=True, error_model="numpy", _nrt=False)
def _gauge_gradient(x, prm, grad):
    """Add the gauge spring's gradient: a stiff tangential spring on point 0 removes the free
    rotation of the contour about the pin; its reaction must vanish at the answer (checked by
    the caller)."""
    kg = prm[P_GAUGE]
    if kg > 0.0:
        tx, ty, ut = _gauge_stretch(x, prm)
        grad[0] += kg * ut * tx
        grad[1] += kg * ut * ty


@njit(cache=True, error_model="numpy", _nrt=False)
def _spring_terms(x, n, prm, bidx, grad, ab, bb, dd, psd):
    """Energy gradient (state order) and Hessian (band order) of the model's terms and the
    gauge spring.

    Every flag passed to the Hessian kernels here and in :func:`_drop_curvature` is a runtime
    value of the same type (never a literal ``True``/``False`` nor an omitted default): numba
    compiles a callee once per argument type, and a literal is a type of its own, so each
    kernel compiles once instead of three times (a first run compiles ~40 s less).
    """
    mesh_gradient(x, n, prm, grad)
    _gauge_gradient(x, prm, grad)
    sign = 1.0  # passed, not omitted: an omitted default is a type of its own
    if prm[P_MU] > 0.0:
        _cst_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign)
        if prm[P_QUAD] > 0.0:
            _quad_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign)
        for j in range(2):
            dd[j, j] += prm[P_KAPPA]
    else:
        nb = ab.shape[0]
        m = int(prm[P_RINGS])
        for t in range(n_edge_types(m)):
            for i in range(n):
                ka, ia, kb, ib = edge_ends(t, i, n, m)
                xa, ya, xb, yb = edge_xy(x, n, m, prm, t, i)
                k, rest = edge_constants(prm, t, i, n, m)
                kxx, kyy, kxy = spring_hessian(xb - xa, yb - ya, k, rest, psd)
                _add_edge(ab, bb, dd, nb, _band_of(bidx, n, m, ka, ia),
                          _band_of(bidx, n, m, kb, ib), kxx, kyy, kxy)
        for j in range(2):
            dd[j, j] += prm[P_KAPPA]
        if prm[P_KA] > 0.0:
            _area_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign)
    kg = prm[P_GAUGE]
    if kg > 0.0:
        tx, ty, _ = _gauge_stretch(x, prm)
        _add_point(ab, bidx[0], kg * tx * tx, kg * ty * ty, kg * tx * ty)


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
    nb = ab.shape[0]
    m = int(prm[P_RINGS])
    # runtime flags, not literals: the kernels below then reuse the compilation of
    # _spring_terms' calls (see its docstring)
    convex = m > 0
    exact = not convex
    if prm[P_MU] > 0.0:
        # constant-strain triangles: their exact Hessian out, the tangent at rest in
        _cst_hessian(x, n, prm, bidx, ab, bb, dd, exact, -1.0)
        _cst_hessian(x, n, prm, bidx, ab, bb, dd, convex, 1.0)
        if prm[P_QUAD] > 0.0:
            _quad_hessian(x, n, prm, bidx, ab, bb, dd, exact, -1.0)
            _quad_hessian(x, n, prm, bidx, ab, bb, dd, convex, 1.0)
    for t in range(n_edge_types(m) if prm[P_MU] == 0.0 else 0):
        for i in range(n):
            ka, ia, kb, ib = edge_ends(t, i, n, m)
            xa, ya, xb, yb = edge_xy(x, n, m, prm, t, i)
            k, rest = edge_constants(prm, t, i, n, m)
            dx, dy = xb - xa, yb - ya
            lc = math.sqrt(dx * dx + dy * dy)
            tt = k * (1.0 - rest / lc)
            if tt < 0.0:
                ux, uy = dx / lc, dy / lc
                _add_edge(ab, bb, dd, nb, _band_of(bidx, n, m, ka, ia),
                          _band_of(bidx, n, m, kb, ib), -tt * (1.0 - ux * ux),
                          -tt * (1.0 - uy * uy), tt * ux * uy)
    if prm[P_KA] > 0.0 and prm[P_MU] == 0.0:
        # the area energy: its exact Hessian out, its convexified one in
        _area_hessian(x, n, prm, bidx, ab, bb, dd, exact, -1.0)
        _area_hessian(x, n, prm, bidx, ab, bb, dd, convex, 1.0)
    for m in range(mcount):
        if ch[m, CH_BLOCK] == 0.0:
            continue
        nd = constraint_dofs(kinds[m])
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
    _spring_terms(x, n, prm, bidx, grad, ab, bb, dd, psd)
    for d in range(x.shape[0]):
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
        _scatter(kinds[m], fj[m], dofs, bidx, ab.shape[0], blk, ab, bb, dd)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _rhs_to_band(grad, bidx, nb, rb, rt):
    """Right-hand side -grad of the Newton system in band order (points) and angles (``nb``:
    the contour's 2N rows; a ring mesh's interior points follow the two angles)."""
    for d in range(nb):
        i = d // 2
        rb[bidx[i] + (d - 2 * i)] = -grad[d]
    for d in range(nb + 2, grad.shape[0]):
        p = (d - 2) // 2
        rb[bidx[p] + (d - 2 - 2 * p)] = -grad[d]
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
    for d in range(nb + 2, step.shape[0]):
        p = (d - 2) // 2
        step[d] = ob[bidx[p] + (d - 2 - 2 * p)]
    slope = 0.0
    for d in range(step.shape[0]):
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
    # gradient only
    mesh_gradient(x, n, prm, res)
    _gauge_gradient(x, prm, res)
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(mcount):
        # no Hessian, as a runtime flag: a literal False would compile _con_eval again
        g, nd = _con_eval(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs, grad5, hess5, dofs,
                          n < 0)
        gbuf[m] = g
        for a in range(nd):
            res[dofs[a]] -= lam[m] * grad5[a]
    r = 0.0
    for a in range(res.shape[0]):
        r = max(r, abs(res[a]))
    return r


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_force(x, prm):
    """Magnitude of the gauge spring's force on point 0 at state x (scaled units)."""
    _, _, ut = _gauge_stretch(x, prm)
    return abs(prm[P_GAUGE] * ut)
