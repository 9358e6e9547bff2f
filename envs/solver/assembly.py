"""Assembly of the barrier merit, the Newton matrix (band order) and the stationarity residual
from the model's energy terms and the contact constraints.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.energy import (
    area_curvature,
    area_slope,
    fan_area,
    fan_energy,
    fan_gradient,
    spring_hessian,
)
from ..model.layout import (
    P_A0,
    P_GAUGE,
    P_GREF,
    P_H,
    P_KA,
    P_KAPPA,
    P_KC,
    P_KR,
    P_PHASE,
)
from .contact import (
    _con_eval,
    _con_value,
    _trig,
)

CH_BLOCK = 15  # column of the constraint curvature cache: 1 where the constraint has a block


@njit(cache=True, error_model="numpy", _nrt=False)
def _energy(x, n, prm):
    """The model's energy plus the solver's rotation gauge spring (when on)."""
    e = fan_energy(x, n, prm)
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
def _gauge_stretch(x, prm):
    """Tangent (tx, ty) of the contour at point 0's rest position and the gauge spring's
    stretch along it: point 0's displacement along the tangent less the spring's anchor (slot
    ``P_GREF``: zero while the gauge holds the rest position; a parameter vector without that
    slot, as in the derivative tests, has no anchor)."""
    tx, ty = -math.sin(prm[P_PHASE]), math.cos(prm[P_PHASE])
    ref = prm[P_GREF] if prm.shape[0] > P_GREF else 0.0
    return tx, ty, (x[0] - ty) * tx + (x[1] + tx) * ty - ref


@njit(cache=True, error_model="numpy", _nrt=False)
def _area_hessian(x, n, prm, bidx, ab, bb, dd, psd, sign=1.0):
    """Hessian (band order) of the area energy of every fan triangle.

    ``H = E'' g g^T + E' d2A`` with ``g = dA/dq`` and ``d2A`` the constant bilinear coupling
    of the two points (``+1/2`` between ``x_i`` and ``y_j``, ``-1/2`` between ``y_i`` and
    ``x_j``). ``psd`` keeps only a non-negative ``E'' g g^T`` (the indefinite coupling and a
    negative curvature dropped) for the interior point's convexified fallback. ``sign = -1``
    takes a Hessian out again.
    """
    nb = 2 * n
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        xi, yi, xj, yj = x[2 * i], x[2 * i + 1], x[2 * i1], x[2 * i1 + 1]
        area = fan_area(xi, yi, xj, yj)
        curv = area_curvature(area, prm[P_KA], prm[P_A0])
        slope = area_slope(area, prm[P_KA], prm[P_A0])
        if psd:
            curv = max(curv, 0.0)
            slope = 0.0
        curv *= sign
        slope *= sign
        gxi, gyi, gxj, gyj = 0.5 * yj, -0.5 * xj, -0.5 * yi, 0.5 * xi
        pa, pb = bidx[i], bidx[i1]
        _add_point(ab, pa, curv * gxi * gxi, curv * gyi * gyi, curv * gxi * gyi)
        _add_point(ab, pb, curv * gxj * gxj, curv * gyj * gyj, curv * gxj * gyj)
        _add(ab, bb, dd, nb, pa, pb, curv * gxi * gxj)
        _add(ab, bb, dd, nb, pa, pb + 1, curv * gxi * gyj + 0.5 * slope)
        _add(ab, bb, dd, nb, pa + 1, pb, curv * gyi * gxj - 0.5 * slope)
        _add(ab, bb, dd, nb, pa + 1, pb + 1, curv * gyi * gyj)


@njit(cache=True, error_model="numpy", _nrt=False)
def _spring_terms(x, n, prm, bidx, grad, ab, bb, dd, want_hess, psd=False):
    """Energy gradient (natural order) and Hessian (band order) of the model's terms and the
    gauge spring."""
    kr, kc, h = prm[P_KR], prm[P_KC], prm[P_H]
    nb = 2 * n
    fan_gradient(x, n, prm, grad)
    if want_hess:
        for i in range(n):
            kxx, kyy, kxy = spring_hessian(x[2 * i], x[2 * i + 1], kr, 1.0, psd)
            _add_point(ab, bidx[i], kxx, kyy, kxy)
        for i in range(n):
            i1 = i + 1 if i + 1 < n else 0
            kxx, kyy, kxy = spring_hessian(x[2 * i1] - x[2 * i], x[2 * i1 + 1] - x[2 * i + 1],
                                           kc, h, psd)
            _add_spring(ab, bb, dd, nb, bidx[i], bidx[i1], kxx, kyy, kxy)
        for j in range(2):
            dd[j, j] += prm[P_KAPPA]
        if prm[P_KA] > 0.0:
            _area_hessian(x, n, prm, bidx, ab, bb, dd, psd)
    kg = prm[P_GAUGE]
    if kg > 0.0:
        # gauge: a stiff tangential spring on point 0 removes the free rotation of the contour
        # about the pin; its reaction must vanish at the answer (checked by the caller)
        tx, ty, ut = _gauge_stretch(x, prm)
        grad[0] += kg * ut * tx
        grad[1] += kg * ut * ty
        if want_hess:
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
    if prm[P_KA] > 0.0:
        # the area energy: its exact Hessian out, its convexified one in
        _area_hessian(x, n, prm, bidx, ab, bb, dd, False, -1.0)
        _area_hessian(x, n, prm, bidx, ab, bb, dd, True, 1.0)
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


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_force(x, prm):
    """Magnitude of the gauge spring's force on point 0 at state x (scaled units)."""
    _, _, ut = _gauge_stretch(x, prm)
    return abs(prm[P_GAUGE] * ut)
