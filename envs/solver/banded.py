"""Banded linear algebra of the Newton matrix: interleaved point ordering, banded Cholesky,
bordered solve for the two finger angles.

The Newton matrix is a cyclic block-tridiagonal matrix (springs) bordered by the two finger
angles; ordering the angles 0, N-1, 1, N-2, ... makes it banded (half bandwidth 5 for the fan,
``6 M - 1`` for a mesh of M rings: :func:`envs.model.rings.mesh_band_index`), so each
factorization is a banded Cholesky plus a 2x2 Schur complement: O(N) work. The fan's band is
factored by 2x2 point blocks (unrolled); a ring mesh's by the plain scalar banded Cholesky
with the half bandwidth of its array.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.layout import P_RINGS
from ..model.rings import mesh_band_index, mesh_half_bandwidth

BW = 5  # half bandwidth of the fan's interleaved point ordering (mesh_half_bandwidth(1))


@njit(cache=True, error_model="numpy")
def _band_index(n):
    """Band row of each fan point's x component (the one-ring case of
    :func:`envs.model.rings.mesh_band_index`)."""
    return mesh_band_index(n, 1)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def band_shape(n, prm):
    """Rows and half bandwidth of the Newton matrix's point block for the mesh of ``prm``."""
    m = int(prm[P_RINGS])
    return 2 * n * m, mesh_half_bandwidth(m)


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
def _chol_general(ab, lb, nb, shift):
    """Scalar banded Cholesky of A + shift I (lower band of A in ``ab``: ``ab[j, d] =
    A[j, j - d]``, half bandwidth ``bw = ab.shape[1] - 1``). The factor is stored left-aligned,
    ``lb[j, bw - d] = L[j, j - d]`` with the reciprocal of the diagonal in ``lb[j, bw]``, so that
    the dot products of two rows run forwards over contiguous memory (they vectorize). Returns
    False if the matrix is not positive definite."""
    bw = ab.shape[1] - 1
    for j in range(nb):
        j0 = max(0, j - bw)
        oj = bw - j  # lb[j, oj + k] = L[j, k]
        for i in range(j0, j):
            oi = bw - i
            # two partial sums (even and odd k): one running sum is a chain of dependent
            # subtractions, latency-bound (the factor of a 2-ring mesh took 18.7 us, 12.3 with
            # two)
            s0 = ab[j, j - i]
            s1 = 0.0
            k = max(j0, i - bw)
            while k + 1 < i:
                s0 -= lb[j, oj + k] * lb[i, oi + k]
                s1 -= lb[j, oj + k + 1] * lb[i, oi + k + 1]
                k += 2
            if k < i:
                s0 -= lb[j, oj + k] * lb[i, oi + k]
            lb[j, oj + i] = (s0 + s1) * lb[i, bw]
        d0 = ab[j, 0] + shift
        d1 = 0.0
        k = j0
        while k + 1 < j:
            v0 = lb[j, oj + k]
            v1 = lb[j, oj + k + 1]
            d0 -= v0 * v0
            d1 -= v1 * v1
            k += 2
        if k < j:
            v0 = lb[j, oj + k]
            d0 -= v0 * v0
        d = d0 + d1
        if not d > 0.0:
            return False
        lb[j, bw] = 1.0 / math.sqrt(d)
    return True


@njit(cache=True, error_model="numpy", _nrt=False)
def _solve_general3(lb, nb, bb, rb, ybuf, out):
    """Solve L L^T [Y | z] = [B | r] with the factor of :func:`_chol_general`."""
    bw = lb.shape[1] - 1
    for j in range(nb):
        a0, a1, a2 = bb[j, 0], bb[j, 1], rb[j]
        oj = bw - j
        for k in range(max(0, j - bw), j):
            v = lb[j, oj + k]
            a0 -= v * ybuf[k, 0]
            a1 -= v * ybuf[k, 1]
            a2 -= v * out[k]
        r = lb[j, bw]
        ybuf[j, 0] = a0 * r
        ybuf[j, 1] = a1 * r
        out[j] = a2 * r
    for j in range(nb - 1, -1, -1):
        r = lb[j, bw]
        a0, a1, a2 = ybuf[j, 0] * r, ybuf[j, 1] * r, out[j] * r
        ybuf[j, 0] = a0
        ybuf[j, 1] = a1
        out[j] = a2
        # column j of L^T done: take it off the rows above (row j's entries L[j, k], k < j)
        oj = bw - j
        for k in range(max(0, j - bw), j):
            v = lb[j, oj + k]
            ybuf[k, 0] -= v * a0
            ybuf[k, 1] -= v * a1
            out[k] -= v * a2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _angle_schur(dd, bb, ybuf, nb, shift):
    """The finger angles' 2 x 2 Schur complement ``D + shift I - B^T A^-1 B`` of the bordered
    matrix, from ``ybuf = A^-1 B`` over its first ``nb`` rows: its entries (0, 0), (1, 1) and
    (0, 1)."""
    s00 = dd[0, 0] + shift
    s11 = dd[1, 1] + shift
    s01 = dd[0, 1]
    for p in range(nb):
        s00 -= bb[p, 0] * ybuf[p, 0]
        s11 -= bb[p, 1] * ybuf[p, 1]
        s01 -= bb[p, 0] * ybuf[p, 1]
    return s00, s11, s01


@njit(cache=True, error_model="numpy", _nrt=False)
def _solve_factored(lb, bb, dd, ybuf, nb, shift, rb, rt, out_b, out_t):
    """Solve [[A, B], [B^T, D]] + shift I with A + shift I already factored into ``lb`` (by
    :func:`_factor_solve` with the same ``shift``); returns False if the angles' Schur
    complement is not positive definite. The border's columns are solved again with the
    right-hand side (the same sweep), so ``ybuf`` need not be kept between calls."""
    if lb.shape[1] == BW + 1:
        _solve_band3(lb, nb, bb, rb, ybuf, out_b)
    else:
        _solve_general3(lb, nb, bb, rb, ybuf, out_b)
    s00, s11, s01 = _angle_schur(dd, bb, ybuf, nb, shift)
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


@njit(cache=True, error_model="numpy", _nrt=False)
def _factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, out_b, out_t):
    """Solve [[A, B], [B^T, D]] + shift I; returns False if not positive definite."""
    if ab.shape[1] == BW + 1:
        if not _chol_band(ab, lb, nb, shift):
            return False
    elif not _chol_general(ab, lb, nb, shift):
        return False
    return _solve_factored(lb, bb, dd, ybuf, nb, shift, rb, rt, out_b, out_t)


@njit(cache=True, error_model="numpy", _nrt=False)
def _forward_from(lb, nb, r, z, start):
    """``z = L^-1 r`` (the forward half of a solve with the point block's factor, either
    layout) for a right-hand side that is zero above row ``start``: only rows from ``start`` on
    are swept and written (a contact constraint's gradient touches one or two points, so its
    sweep starts there)."""
    if lb.shape[1] == BW + 1:
        # 2x2-block layout of _chol_band: lb[j, d] = L[j, j - d], lb[j, 0] = 1 / L[j, j]
        for j in range(start, nb):
            a = r[j]
            for d in range(1, min(j - start, BW) + 1):
                a -= lb[j, d] * z[j - d]
            z[j] = a * lb[j, 0]
        return
    bw = lb.shape[1] - 1
    for j in range(start, nb):
        a = r[j]
        oj = bw - j
        for k in range(max(start, j - bw), j):
            a -= lb[j, oj + k] * z[k]
        z[j] = a * lb[j, bw]
