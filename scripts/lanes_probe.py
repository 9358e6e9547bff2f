"""What lanes of designs solved in lockstep could buy: a measured ceiling, not a solver.

A lane solver would hold K designs' arrays lane-major (structure of arrays, the lane index
innermost), so that every loop over the mesh runs once for K designs and the compiler turns
its body into vector instructions. This probe measures the two parts of an interior-point
iteration that such a solver would run most, on the real arrays of random designs' answers
(paper-r070, the default model, one thread), and what the lockstep costs:

1. the banded factor and solve of the Newton matrix (the scalar banded Cholesky
   :func:`envs.solver.banded._chol_general`, its three-column solve and the 2x2 border of the
   finger angles, :func:`envs.solver.banded._factor_solve`) at the answers of the batch's
   first designs (the convexified matrix, as ``scripts/solver_profile.py`` times it): K
   sequential calls of the package's routine against the same algorithm written lane-major
   here, for K = 4 and 8;
2. the element assembly (the nh-quad element energy's gradient and Hessian into the banded
   matrix, :func:`envs.solver.assembly._spring_terms`) the same way; its lane version calls
   the package's own element functions (:func:`envs.model.energy.cst_gradient`,
   :func:`envs.model.energy.cst_hessian_column`, the quad's area energy) inside the lane loops;
3. the lockstep loss: a group of K designs runs until its slowest lane has converged, so
   from the batch's own Newton iteration counts, the group's maximum against its mean; and
   with a finished lane refilled at once by the next design (per-lane state machines across
   the interior point, the polish and the candidate sets), the loss at the batch's end;
4. the ceiling: the batch's solve share sped up by the measured parts' speed-ups, with and
   without the lockstep loss, as designs per second against today's (:func:`ceiling`).

Both lane versions are compiled without ``fastmath`` and must give the sequential answers to
1e-12 relative (they perform the same operations in the same order per lane; the probe
refuses to report otherwise). They are compiled with every array argument ``noalias`` and
with LLVM's SLP vectorizer on (:func:`_slp_vectorized`); numba has no vector math library
(SVML) here, so the element energies' logarithms stay scalar calls inside the vector code. A
lane solver in the package would need the same two compiler settings. Times are CPU time of
the probe's thread (the fastest of several samples), so the other processes of a shared
machine do not count.

Usage: ``python scripts/lanes_probe.py [--batch 2048] [--seed 1] [--out out/lanes.json]``
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit
from numba.core.compiler import CompilerBase, DefaultPassBuilder

sys.path.insert(0, str(Path(__file__).resolve().parent))

from solver_profile import (  # noqa: E402
    DISK,
    _load,
    _time_newton,
    batch_breakdown,
    newton_state,
)

from envs.evaluate import DesignBounds  # noqa: E402
from envs.model.energy import (  # noqa: E402
    area_curvature,
    area_slope,
    cst_gradient,
    cst_hessian_column,
    cst_rest,
    joint_gradient,
    quad_area,
)
from envs.model.layout import (  # noqa: E402
    P_GAUGE,
    P_KAPPA,
    P_LAM,
    P_MU,
    P_QUAD,
    P_RINGS,
    P_TAU,
    P_TH0,
)
from envs.model.rings import (  # noqa: E402
    R_AIN,
    R_AOUT,
    R_RHO,
    _dir_slot,
    _row,
    n_tri_types,
    point_dof,
    quad_corners,
    tri_corners,
)
from envs.parallel import set_solver_threads, solver_threads  # noqa: E402
from envs.solver import pipeline as pl  # noqa: E402
from envs.solver.assembly import _band_of, _cst_block, _spring_terms  # noqa: E402
from envs.solver.banded import BW, _factor_solve  # noqa: E402

LANE_COUNTS = (4, 8)
GROUP_SIZES = (2, 4, 8)
SHIFT = 1e-3  # the diagonal shift of the timed factor (as scripts/solver_profile.py)
RTOL = 1e-12  # lane answers against the sequential ones, relative to each array's largest entry
TIMING_S = 0.1  # CPU seconds of calls per timing sample
SAMPLES = 5  # samples per timing, interleaved; the fastest is kept (the least disturbed)
ITERATION_ROWS = 128  # designs of the timed solve that gives the time of an iteration
NEWTON_REPS = 20  # assemblies of one design per call of the whole Newton matrix's timing

# lane point tables pts[point, axis, lane] of every mesh point, ring 0 (the hub) included:
# point (k, i) at row k n + i
AX_X, AX_Y = 0, 1
N_AXES = 2
# flat scratch vectors, slot s of lane l at s K + l:
# one constant-strain triangle: the gradient dE/dDs by rows (cst_gradient), the sums of its
# rows (corner a's gradient, negated) and the Hessian d2E/dDs2 by columns (cst_hessian_column,
# column c = 2 r + e, entry 2 r' + e')
T_G00, T_G01, T_G10, T_G11, T_SA, T_SB = range(6)
T_COL0 = 6
N_TRI_SLOTS = T_COL0 + 16
# one quad: the area energy's curvature and half its slope, and the area's gradient over
# each corner (a, b, c, d counter-clockwise, x then y; times the slope in the gradient pass)
Q_CURV, Q_HALF = range(2)
Q_G0 = 2
N_QUAD_SLOTS = Q_G0 + 8
# the factor's running sums: the Cholesky's two partial sums (even and odd terms, as the
# package's) and a pivot, the solve's three columns, the angles' Schur complement, its
# right-hand side and determinant
W_S0, W_S1, W_T, W_A0, W_A1, W_A2, W_S00, W_S11, W_S01, W_R0, W_R1, W_DET = range(12)
N_W = 12


# --- the lane-major versions (K lanes, a compile-time constant) ---


class _NoAliasCompiler(CompilerBase):
    """numba's nopython pipeline with every array argument marked ``noalias`` (C's
    ``restrict``): the lane kernels' arrays never overlap, and without that promise LLVM may
    not reorder their loads and stores into vector instructions."""

    def define_pipelines(self):
        self.state.flags.noalias = True
        return [DefaultPassBuilder.define_nopython_pipeline(self.state)]


@contextlib.contextmanager
def _slp_vectorized():
    """Compile with LLVM's straight-line (SLP) vectorizer on.

    A lane loop of a fixed count is unrolled before the loop vectorizer sees it, so only the
    SLP vectorizer can pack its K copies into vector instructions; numba leaves it off by
    default (numba#8705, a miscompilation), so the lane kernels are compiled with it on
    here and their answers are checked against the package's. The package's kernels and the
    sequential side are compiled as always.
    """
    old = numba.config.SLP_VECTORIZE
    numba.config.SLP_VECTORIZE = 1
    try:
        yield
    finally:
        numba.config.SLP_VECTORIZE = old


# The lane kernels are made for a lane count K, a compile-time constant, by the factories
# below. Their loops are written for the vectorizer: each lane loop stores into one array (a
# vector store) and reads no other row of it (no store can then overlap a load of another
# lane); running sums live in flat scratch vectors ``w[slot K + lane]`` (slots ``W_*``, ``T_*``,
# ``Q_*``), whose constant offsets LLVM can tell apart.


def _cholesky_lanes(lanes: int):
    """The lane-major banded Cholesky for ``lanes`` lanes."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    @njit(error_model="numpy", inline="always")
    def chol(ab, lb, nb, shift, ok, w):
        """:func:`envs.solver.banded._chol_general` lane-major (``ab[j, d, lane]``): the same
        two partial sums, the same order; ``ok`` gets each lane's positive definiteness."""
        bw = ab.shape[1] - 1
        s0, s1, tt = W_S0 * K, W_S1 * K, W_T * K
        for lane in range(K):
            ok[lane] = True
        for j in range(nb):
            j0 = max(0, j - bw)
            oj = bw - j
            for i in range(j0, j):
                oi = bw - i
                for lane in range(K):
                    w[s0 + lane] = ab[j, j - i, lane]
                for lane in range(K):
                    w[s1 + lane] = 0.0
                k = max(j0, i - bw)
                while k + 1 < i:
                    for lane in range(K):
                        w[s0 + lane] -= lb[j, oj + k, lane] * lb[i, oi + k, lane]
                    for lane in range(K):
                        w[s1 + lane] -= lb[j, oj + k + 1, lane] * lb[i, oi + k + 1, lane]
                    k += 2
                if k < i:
                    for lane in range(K):
                        w[s0 + lane] -= lb[j, oj + k, lane] * lb[i, oi + k, lane]
                for lane in range(K):
                    w[tt + lane] = lb[i, bw, lane]
                for lane in range(K):
                    lb[j, oj + i, lane] = (w[s0 + lane] + w[s1 + lane]) * w[tt + lane]
            for lane in range(K):
                w[s0 + lane] = ab[j, 0, lane] + shift
            for lane in range(K):
                w[s1 + lane] = 0.0
            k = j0
            while k + 1 < j:
                for lane in range(K):
                    v0 = lb[j, oj + k, lane]
                    w[s0 + lane] -= v0 * v0
                for lane in range(K):
                    v1 = lb[j, oj + k + 1, lane]
                    w[s1 + lane] -= v1 * v1
                k += 2
            if k < j:
                for lane in range(K):
                    v0 = lb[j, oj + k, lane]
                    w[s0 + lane] -= v0 * v0
            for lane in range(K):
                ok[lane] &= w[s0 + lane] + w[s1 + lane] > 0.0
            for lane in range(K):
                lb[j, bw, lane] = 1.0 / math.sqrt(w[s0 + lane] + w[s1 + lane])

    return chol


def _solve_lanes(lanes: int):
    """The lane-major three-column solve and angle border for ``lanes`` lanes."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    @njit(error_model="numpy", inline="always")
    def solve3(lb, nb, bb, rb, ybuf, out, w):
        """:func:`envs.solver.banded._solve_general3` lane-major."""
        bw = lb.shape[1] - 1
        a0, a1, a2 = W_A0 * K, W_A1 * K, W_A2 * K
        for j in range(nb):
            oj = bw - j
            for lane in range(K):
                w[a0 + lane] = bb[j, 0, lane]
            for lane in range(K):
                w[a1 + lane] = bb[j, 1, lane]
            for lane in range(K):
                w[a2 + lane] = rb[j, lane]
            for k in range(max(0, j - bw), j):
                for lane in range(K):
                    w[a0 + lane] -= lb[j, oj + k, lane] * ybuf[k, 0, lane]
                for lane in range(K):
                    w[a1 + lane] -= lb[j, oj + k, lane] * ybuf[k, 1, lane]
                for lane in range(K):
                    w[a2 + lane] -= lb[j, oj + k, lane] * out[k, lane]
            for lane in range(K):
                ybuf[j, 0, lane] = w[a0 + lane] * lb[j, bw, lane]
            for lane in range(K):
                ybuf[j, 1, lane] = w[a1 + lane] * lb[j, bw, lane]
            for lane in range(K):
                out[j, lane] = w[a2 + lane] * lb[j, bw, lane]
        for j in range(nb - 1, -1, -1):
            for lane in range(K):
                w[a0 + lane] = ybuf[j, 0, lane] * lb[j, bw, lane]
            for lane in range(K):
                w[a1 + lane] = ybuf[j, 1, lane] * lb[j, bw, lane]
            for lane in range(K):
                w[a2 + lane] = out[j, lane] * lb[j, bw, lane]
            for lane in range(K):
                ybuf[j, 0, lane] = w[a0 + lane]
            for lane in range(K):
                ybuf[j, 1, lane] = w[a1 + lane]
            for lane in range(K):
                out[j, lane] = w[a2 + lane]
            # column j of L^T done: take it off the rows above
            oj = bw - j
            for k in range(max(0, j - bw), j):
                for lane in range(K):
                    ybuf[k, 0, lane] -= lb[j, oj + k, lane] * w[a0 + lane]
                for lane in range(K):
                    ybuf[k, 1, lane] -= lb[j, oj + k, lane] * w[a1 + lane]
                for lane in range(K):
                    out[k, lane] -= lb[j, oj + k, lane] * w[a2 + lane]

    @njit(error_model="numpy", inline="always")
    def border(bb, dd, ybuf, nb, shift, rt, out_b, out_t, ok, w):
        """The angles' 2x2 Schur complement and the border's back-substitution of
        :func:`envs.solver.banded._solve_factored`, lane-major."""
        s00, s11, s01 = W_S00 * K, W_S11 * K, W_S01 * K
        r0, r1, det = W_R0 * K, W_R1 * K, W_DET * K
        for lane in range(K):
            w[s00 + lane] = dd[0, 0, lane] + shift
        for lane in range(K):
            w[s11 + lane] = dd[1, 1, lane] + shift
        for lane in range(K):
            w[s01 + lane] = dd[0, 1, lane]
        for p in range(nb):
            for lane in range(K):
                w[s00 + lane] -= bb[p, 0, lane] * ybuf[p, 0, lane]
            for lane in range(K):
                w[s11 + lane] -= bb[p, 1, lane] * ybuf[p, 1, lane]
            for lane in range(K):
                w[s01 + lane] -= bb[p, 0, lane] * ybuf[p, 1, lane]
        for lane in range(K):
            w[det + lane] = w[s00 + lane] * w[s11 + lane] - w[s01 + lane] * w[s01 + lane]
        for lane in range(K):
            d = w[det + lane]
            ok[lane] &= ((w[s00 + lane] > 0.0)
                         & (d > 1e-300 * max(1.0, w[s00 + lane] * w[s11 + lane])) & (d > 0.0))
        for lane in range(K):
            w[r0 + lane] = rt[0, lane]
        for lane in range(K):
            w[r1 + lane] = rt[1, lane]
        for p in range(nb):
            for lane in range(K):
                w[r0 + lane] -= bb[p, 0, lane] * out_b[p, lane]
            for lane in range(K):
                w[r1 + lane] -= bb[p, 1, lane] * out_b[p, lane]
        for lane in range(K):
            out_t[0, lane] = (w[s11 + lane] * w[r0 + lane] - w[s01 + lane] * w[r1 + lane]) / w[
                det + lane]
        for lane in range(K):
            out_t[1, lane] = (w[s00 + lane] * w[r1 + lane] - w[s01 + lane] * w[r0 + lane]) / w[
                det + lane]
        for p in range(nb):
            for lane in range(K):
                out_b[p, lane] -= (ybuf[p, 0, lane] * out_t[0, lane]
                                   + ybuf[p, 1, lane] * out_t[1, lane])

    return solve3, border


def factor_lanes(lanes: int):
    """The lane-major factor and solve for ``lanes`` lanes (the entry point)."""
    chol = _cholesky_lanes(lanes)
    solve3, border = _solve_lanes(lanes)

    @njit(error_model="numpy", pipeline_class=_NoAliasCompiler)
    def factor_solve(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, out_b, out_t, ok, w):
        """:func:`envs.solver.banded._factor_solve` lane-major: the band's Cholesky, the
        three-column solve and the angles' 2x2 border; ``ok`` per lane, ``w`` scratch
        (``W_*`` slots)."""
        chol(ab, lb, nb, shift, ok, w)
        solve3(lb, nb, bb, rb, ybuf, out_b, w)
        border(bb, dd, ybuf, nb, shift, rt, out_b, out_t, ok, w)

    return factor_solve


def _point_lanes(lanes: int):
    """The lane-major point tables and the scatter helpers for ``lanes`` lanes."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    @njit(error_model="numpy", inline="always")
    def point_tables(xl, prml, n, m, pts, rest):
        """Current and rest positions of every mesh point, lane-major (what
        :func:`envs.model.rings.point_xy` and :func:`envs.model.rings.rest_xy` read)."""
        base = _dir_slot(m)
        for k in range(m + 1):
            rho_slot = _row(k) + R_RHO
            for i in range(n):
                p = k * n + i
                for lane in range(K):
                    rest[p, AX_X, lane] = prml[rho_slot, lane] * prml[base + 2 * i, lane]
                for lane in range(K):
                    rest[p, AX_Y, lane] = prml[rho_slot, lane] * prml[base + 2 * i + 1, lane]
                d = point_dof(n, m, k, i)
                if d >= 0:
                    for lane in range(K):
                        pts[p, AX_X, lane] = xl[d, lane]
                    for lane in range(K):
                        pts[p, AX_Y, lane] = xl[d + 1, lane]
                else:  # the hub (a ring mesh's ring 0) at rest
                    for lane in range(K):
                        pts[p, AX_X, lane] = prml[rho_slot, lane] * prml[base + 2 * i, lane]
                    for lane in range(K):
                        pts[p, AX_Y, lane] = prml[rho_slot, lane] * prml[base + 2 * i + 1,
                                                                          lane]

    @njit(error_model="numpy", inline="always")
    def triangle(pts, rest, pa, pb, pc, lane):
        """:func:`envs.model.energy._cst_triangle` of one lane from the point tables."""
        xa, ya = pts[pa, AX_X, lane], pts[pa, AX_Y, lane]
        m00, m01, m10, m11, a0 = cst_rest(rest[pa, AX_X, lane], rest[pa, AX_Y, lane],
                                          rest[pb, AX_X, lane], rest[pb, AX_Y, lane],
                                          rest[pc, AX_X, lane], rest[pc, AX_Y, lane])
        return (pts[pb, AX_X, lane] - xa, pts[pc, AX_X, lane] - xa, pts[pb, AX_Y, lane] - ya,
                pts[pc, AX_Y, lane] - ya, m00, m01, m10, m11, a0)

    @njit(error_model="numpy", inline="always")
    def add_grad(grad, d, ws, sx, sy, sign):
        """Add ``sign`` times the scratch slots ``sx``, ``sy`` of the lanes to the point whose x
        row is ``d`` (fixed: d < 0); ``sign = -1`` adds ``-(slot sx)``."""
        if d >= 0:
            for lane in range(K):
                grad[d, lane] += sign * ws[sx * K + lane]
            for lane in range(K):
                grad[d + 1, lane] += sign * ws[sy * K + lane]

    @njit(error_model="numpy", inline="always")
    def band_entry(p, r):
        """Row and diagonal of the symmetric band entry (p, r) of two point rows."""
        return (p, p - r) if p >= r else (r, r - p)

    @njit(error_model="numpy", inline="always")
    def cst_cols(ts, lane):
        """The four Hessian columns of a triangle's lane from its scratch (``T_COL0``)."""
        c = T_COL0 * K + lane
        return ((ts[c], ts[c + K], ts[c + 2 * K], ts[c + 3 * K]),
                (ts[c + 4 * K], ts[c + 5 * K], ts[c + 6 * K], ts[c + 7 * K]),
                (ts[c + 8 * K], ts[c + 9 * K], ts[c + 10 * K], ts[c + 11 * K]),
                (ts[c + 12 * K], ts[c + 13 * K], ts[c + 14 * K], ts[c + 15 * K]))

    return point_tables, triangle, add_grad, band_entry, cst_cols


def _cst_lanes(lanes: int):
    """The lane-major constant-strain triangles for ``lanes`` lanes."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    _, triangle, add_grad, band_entry, cst_cols = _point_lanes(lanes)

    @njit(error_model="numpy", inline="always")
    def cst_gradients(pts, rest, prml, n, m, grad, ts):
        """Every constant-strain triangle's gradient (as
        :func:`envs.model.energy._cst_gradient_all`), lane-major."""
        for t in range(n_tri_types(m)):
            for i in range(n):
                ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
                pa, pb, pc = ka * n + ia, kb * n + ib, kc * n + ic
                for lane in range(K):
                    ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0 = triangle(pts, rest, pa,
                                                                              pb, pc, lane)
                    h00, h01, h10, h11 = cst_gradient(ds00, ds01, ds10, ds11, m00, m01, m10,
                                                      m11, a0, prml[P_MU, lane],
                                                      prml[P_LAM, lane])
                    ts[T_G00 * K + lane] = h00
                    ts[T_G01 * K + lane] = h01
                    ts[T_G10 * K + lane] = h10
                    ts[T_G11 * K + lane] = h11
                    ts[T_SA * K + lane] = h00 + h01
                    ts[T_SB * K + lane] = h10 + h11
                add_grad(grad, point_dof(n, m, ka, ia), ts, T_SA, T_SB, -1.0)
                add_grad(grad, point_dof(n, m, kb, ib), ts, T_G00, T_G10, 1.0)
                add_grad(grad, point_dof(n, m, kc, ic), ts, T_G01, T_G11, 1.0)

    @njit(error_model="numpy", inline="always")
    def cst_hessians(pts, rest, prml, n, m, bidx, ab, ts):
        """Every constant-strain triangle's exact Hessian into the band (as
        :func:`envs.solver.assembly._cst_hessian`), lane-major."""
        psd = False  # the exact Hessian (a constant: no branch inside the lane loops)
        for t in range(n_tri_types(m)):
            for i in range(n):
                ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
                pa, pb, pc = ka * n + ia, kb * n + ib, kc * n + ic
                for lane in range(K):
                    ds00, ds01, ds10, ds11, m00, m01, m10, m11, a0 = triangle(pts, rest, pa,
                                                                              pb, pc, lane)
                    mu, lam = prml[P_MU, lane], prml[P_LAM, lane]
                    for c in range(4):
                        col = cst_hessian_column(ds00, ds01, ds10, ds11, m00, m01, m10, m11,
                                                 a0, mu, lam, c // 2, c % 2, psd)
                        base = (T_COL0 + 4 * c) * K + lane
                        ts[base] = col[0]
                        ts[base + K] = col[1]
                        ts[base + 2 * K] = col[2]
                        ts[base + 3 * K] = col[3]
                corners = (_band_of(bidx, n, m, ka, ia), _band_of(bidx, n, m, kb, ib),
                           _band_of(bidx, n, m, kc, ic))
                # how a corner enters the two edges (a: (-1, -1), b: (1, 0), c: (0, 1))
                enter = ((-1.0, -1.0), (1.0, 0.0), (0.0, 1.0))
                for u in range(3):
                    pu = corners[u]
                    if pu < 0:
                        continue
                    tu0, tu1 = enter[u]
                    for v in range(u, 3):
                        pv = corners[v]
                        if pv < 0:
                            continue
                        tv0, tv1 = enter[v]
                        # :func:`envs.solver.assembly._cst_pair` (a diagonal block when u == v)
                        for r in range(2):
                            for rp in range(2):
                                if u == v and rp > r:
                                    continue
                                row, diag = band_entry(pu + r, pv + rp)
                                for lane in range(K):
                                    ab[row, diag, lane] += 1.0 * _cst_block(
                                        cst_cols(ts, lane), tu0, tu1, tv0, tv1, r, rp)

    return cst_gradients, cst_hessians


def _quad_lanes(lanes: int):
    """The lane-major quads' area energy for ``lanes`` lanes."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    _, _, add_grad, band_entry, _ = _point_lanes(lanes)

    @njit(error_model="numpy", inline="always")
    def quad_values(pts, prml, k, ps, hessian, qs):
        """A quad's lanes into its scratch: the area's gradient times the energy's slope
        (``hessian`` false), or the area's gradient, the curvature and half the slope."""
        row = _row(k)
        for lane in range(K):
            xa, ya = pts[ps[0], AX_X, lane], pts[ps[0], AX_Y, lane]
            xb, yb = pts[ps[1], AX_X, lane], pts[ps[1], AX_Y, lane]
            xc, yc = pts[ps[2], AX_X, lane], pts[ps[2], AX_Y, lane]
            xd, yd = pts[ps[3], AX_X, lane], pts[ps[3], AX_Y, lane]
            a0 = prml[row + R_AOUT, lane] + prml[row + R_AIN, lane]
            area = quad_area(xa, ya, xb, yb, xc, yc, xd, yd)
            kq = prml[P_QUAD, lane]
            if hessian:
                qs[Q_CURV * K + lane] = area_curvature(area, kq, a0) * 1.0
                qs[Q_HALF * K + lane] = 0.5 * area_slope(area, kq, a0) * 1.0
                f = 0.5
            else:
                f = 0.5 * area_slope(area, kq, a0)
            # (y_next - y_prev, x_prev - x_next) of each corner, times f
            g = Q_G0 * K + lane
            qs[g] = f * (yb - yd)
            qs[g + K] = f * (xd - xb)
            qs[g + 2 * K] = f * (yc - ya)
            qs[g + 3 * K] = f * (xa - xc)
            qs[g + 4 * K] = f * (yd - yb)
            qs[g + 5 * K] = f * (xb - xd)
            qs[g + 6 * K] = f * (ya - yc)
            qs[g + 7 * K] = f * (xc - xa)

    @njit(error_model="numpy", inline="always")
    def quad_block(ab, qs, pu, u, pw, w, hs):
        """The block between corners u and w of a quad (:func:`envs.solver.assembly._tri_pair`
        with ``hs`` times half the slope, or the diagonal block of
        :func:`envs.solver.assembly._add_point` when u == w)."""
        gu, gw = Q_G0 + 2 * u, Q_G0 + 2 * w
        for r in range(2):
            for rp in range(2):
                if u == w and rp > r:
                    continue
                # a diagonal block's off-diagonal entry is curv gx gy (the package's order)
                ia, ib = (gu + rp, gw + r) if u == w else (gu + r, gw + rp)
                # the area's bilinear term couples x of one corner with y of the other
                bil = hs if (r == 0 and rp == 1) else (-hs if (r == 1 and rp == 0) else 0.0)
                row, diag = band_entry(pu + r, pw + rp)
                if bil != 0.0:
                    for lane in range(K):
                        ab[row, diag, lane] += (qs[Q_CURV * K + lane] * qs[ia * K + lane]
                                                * qs[ib * K + lane]
                                                + bil * qs[Q_HALF * K + lane])
                else:
                    for lane in range(K):
                        ab[row, diag, lane] += (qs[Q_CURV * K + lane] * qs[ia * K + lane]
                                                * qs[ib * K + lane])

    @njit(error_model="numpy", inline="always")
    def quads(pts, prml, n, m, bidx, grad, ab, qs, hessian):
        """Every quad's area energy: its gradient (as
        :func:`envs.model.energy._quad_gradient_all`) or its exact Hessian into the band (as
        :func:`envs.solver.assembly._quad_hessian`), lane-major."""
        for k in range(1, m + 1):
            for i in range(n):
                ka, ia, kb, ib, kc, ic, kd, id_ = quad_corners(k, i, n)
                ps = (ka * n + ia, kb * n + ib, kc * n + ic, kd * n + id_)
                corners = ((ka, ia), (kb, ib), (kc, ic), (kd, id_))
                quad_values(pts, prml, k, ps, hessian, qs)
                if not hessian:
                    for u in range(4):
                        add_grad(grad, point_dof(n, m, corners[u][0], corners[u][1]), qs,
                                 Q_G0 + 2 * u, Q_G0 + 2 * u + 1, 1.0)
                    continue
                for u in range(4):
                    pu = _band_of(bidx, n, m, corners[u][0], corners[u][1])
                    if pu < 0:
                        continue
                    quad_block(ab, qs, pu, u, pu, u, 0.0)
                    for w in range(u + 1, 4):
                        pw = _band_of(bidx, n, m, corners[w][0], corners[w][1])
                        if pw < 0:
                            continue
                        # w follows u (+), precedes it (the pair d, a: -), or is opposite
                        hs = 1.0 if w == u + 1 else (-1.0 if w - u == 3 else 0.0)
                        quad_block(ab, qs, pu, u, pw, w, hs)

    return quads


def assembly_lanes(lanes: int):
    """The lane-major element assembly for ``lanes`` lanes (the entry point)."""
    K = lanes  # noqa: N806 - the lane count, a compile-time constant of the kernels below

    point_tables = _point_lanes(lanes)[0]
    cst_gradients, cst_hessians = _cst_lanes(lanes)
    quads = _quad_lanes(lanes)

    @njit(error_model="numpy", pipeline_class=_NoAliasCompiler)
    def assembly(xl, prml, n, m, bidx, grad, ab, bb, dd, pts, rest, ts, qs):
        """:func:`envs.solver.assembly._spring_terms` of the nh-quad element lane-major: the
        gradient (state order) and the exact Hessian (band order) of the constant-strain
        triangles, the quads' area energy and the joints, from zero, in the package's order
        of the sums."""
        grad[:, :] = 0.0
        ab[:, :, :] = 0.0
        bb[:, :, :] = 0.0
        dd[:, :, :] = 0.0
        point_tables(xl, prml, n, m, pts, rest)
        cst_gradients(pts, rest, prml, n, m, grad, ts)
        quads(pts, prml, n, m, bidx, grad, ab, qs, False)
        for j in range(2):
            for lane in range(K):
                grad[2 * n + j, lane] += joint_gradient(xl[2 * n + j, lane], prml[P_TAU, lane],
                                                        prml[P_KAPPA, lane],
                                                        prml[P_TH0, lane])
        cst_hessians(pts, rest, prml, n, m, bidx, ab, ts)
        quads(pts, prml, n, m, bidx, grad, ab, qs, True)
        for j in range(2):
            for lane in range(K):
                dd[j, j, lane] += prml[P_KAPPA, lane]

    return assembly


# --- the package's routines, called once a design ---


@njit(error_model="numpy", _nrt=False)
def _sequential_factor(ab, bb, dd, lb, ybuf, nb, shift, rb, rt, out_b, out_t, ok):
    """:func:`envs.solver.banded._factor_solve` of each design in turn (arrays design-major,
    ``ab[design, j, d]``)."""
    for r in range(ab.shape[0]):
        ok[r] = _factor_solve(ab[r], bb[r], dd[r], lb[r], ybuf[r], nb, shift, rb[r], rt[r],
                              out_b[r], out_t[r])


@njit(error_model="numpy", _nrt=False)
def _sequential_assembly(x, prm, n, bidx, grad, ab, bb, dd):
    """:func:`envs.solver.assembly._spring_terms` (exact Hessian) of each design in turn, from
    zero (as :func:`envs.solver.assembly._newton_matrix` calls it)."""
    psd = n < 0  # a runtime flag, as the package passes it
    for r in range(x.shape[0]):
        grad[r, :] = 0.0
        ab[r, :, :] = 0.0
        bb[r, :, :] = 0.0
        dd[r, :, :] = 0.0
        _spring_terms(x[r], n, prm[r], bidx, grad[r], ab[r], bb[r], dd[r], psd)


def _lane_major(a: np.ndarray) -> np.ndarray:
    """A design-major stack ``a[design, ...]`` as a lane-major copy ``[..., lane]``."""
    return np.ascontiguousarray(np.moveaxis(a, 0, -1))


def _rel_diff(lane: np.ndarray, seq: np.ndarray) -> float:
    """Largest difference of the lane answers from the sequential ones (design-major),
    relative to the largest sequential entry."""
    ref = np.abs(seq).max()
    return float(np.abs(_lane_major(seq) - lane).max() / (ref if ref > 0.0 else 1.0))


def _best_us(calls: tuple, per: int) -> list[float]:
    """CPU microseconds of one call of each of ``calls`` divided by ``per``: the fastest of
    :data:`SAMPLES` samples of about :data:`TIMING_S` seconds each, the calls' samples
    interleaved. CPU time of this thread, not wall time: on a shared machine the wall time
    counts the other processes' turns too."""
    reps = []
    for call in calls:
        call()
        t0 = time.thread_time()
        call()
        reps.append(max(1, int(TIMING_S / max(time.thread_time() - t0, 1e-6))))
    best = [float("inf")] * len(calls)
    for _ in range(SAMPLES):
        for c, call in enumerate(calls):
            t0 = time.thread_time()
            for _ in range(reps[c]):
                call()
            best[c] = min(best[c], (time.thread_time() - t0) / reps[c])
    return [1e6 * b / per for b in best]


def _states(seen: dict, lanes: int) -> list[dict]:
    """The solver's arrays at the answers of the first ``lanes`` designs that were valid at
    rest and converged (:func:`solver_profile.newton_state`)."""
    rows = np.flatnonzero(seen["valid"] & seen["converged"])[:lanes]
    states = [newton_state(seen, int(r)) for r in rows]
    prm = states[0]["prm"]
    if not (prm[P_MU] > 0.0 and prm[P_QUAD] > 0.0 and prm[P_RINGS] >= 2):
        raise ValueError("model: the probe's lane assembly is the nh-quad element's (ring "
                         "mesh, P_MU > 0, P_QUAD > 0); got another element")
    if states[0]["ab"].shape[1] == BW + 1:
        raise ValueError("model: the fan's 2x2-block factor is not probed (needs a ring mesh)")
    if any(st["prm"][P_GAUGE] != 0.0 for st in states):
        raise ValueError("gauge: the probe's assembly leaves out the gauge spring (its slot "
                         "must be 0 at the answers)")
    return states


def factor_probe(states: list[dict], lanes: int) -> dict:
    """The banded factor and solve of ``lanes`` designs' convexified Newton matrices: the
    package's routine once a design against the lane-major one; us a design and the lane
    answers' largest relative difference."""
    factor_kernel = factor_lanes(lanes)
    nb = states[0]["nbb"]
    stack = {key: np.stack([st[key] for st in states]) for key in ("ab", "bb", "dd")}
    rb = np.stack([np.linspace(1.0, -1.0, nb) for _ in states])  # a right-hand side a design
    rt = np.ones((lanes, 2))
    seq = {"lb": np.zeros_like(stack["ab"]), "ybuf": np.zeros((lanes, nb, 2)),
           "out_b": np.zeros((lanes, nb)), "out_t": np.zeros((lanes, 2)),
           "ok": np.zeros(lanes, np.bool_)}
    lane = {key: _lane_major(v) for key, v in seq.items() if key != "ok"}
    lane_ok = np.zeros(lanes, np.bool_)
    w = np.zeros(N_W * lanes)
    lane_in = {key: _lane_major(v) for key, v in stack.items()}
    rbl, rtl = _lane_major(rb), _lane_major(rt)

    def run_seq():
        _sequential_factor(stack["ab"], stack["bb"], stack["dd"], seq["lb"], seq["ybuf"], nb,
                           SHIFT, rb, rt, seq["out_b"], seq["out_t"], seq["ok"])

    def run_lanes():
        factor_kernel(lane_in["ab"], lane_in["bb"], lane_in["dd"], lane["lb"], lane["ybuf"], nb,
                     SHIFT, rbl, rtl, lane["out_b"], lane["out_t"], lane_ok, w)

    with _slp_vectorized():
        run_lanes()  # compiles the lane kernel
    seq_us, lane_us = _best_us((run_seq, run_lanes), lanes)
    if not (seq["ok"].all() and lane_ok.all()):
        raise RuntimeError("factor: a matrix was not positive definite")
    diff = max(_rel_diff(lane[key], seq[key]) for key in ("out_b", "out_t", "lb"))
    return {"sequential_us": seq_us, "lanes_us": lane_us, "speedup": seq_us / lane_us,
            "max_rel_diff": diff}


def assembly_probe(states: list[dict], lanes: int) -> dict:
    """The nh-quad element assembly (gradient and exact Hessian into the band) of ``lanes``
    designs' answers: the package's once a design against the lane-major one."""
    assembly_kernel = assembly_lanes(lanes)
    n, bidx = states[0]["n"], states[0]["bidx"]
    m = int(states[0]["prm"][P_RINGS])
    x = np.stack([st["x"] for st in states])
    prm = np.stack([st["prm"] for st in states])
    seq = {"grad": np.zeros_like(x), "ab": np.zeros((lanes, *states[0]["ab"].shape)),
           "bb": np.zeros((lanes, *states[0]["bb"].shape)), "dd": np.zeros((lanes, 2, 2))}
    lane = {key: _lane_major(v) for key, v in seq.items()}
    xl, prml = _lane_major(x), _lane_major(prm)
    points = (m + 1) * n
    work = (np.zeros((points, N_AXES, lanes)), np.zeros((points, N_AXES, lanes)),
            np.zeros(N_TRI_SLOTS * lanes), np.zeros(N_QUAD_SLOTS * lanes))

    def run_seq():
        _sequential_assembly(x, prm, n, bidx, seq["grad"], seq["ab"], seq["bb"], seq["dd"])

    def run_lanes():
        assembly_kernel(xl, prml, n, m, bidx, lane["grad"], lane["ab"], lane["bb"],
                       lane["dd"], *work)

    with _slp_vectorized():
        run_lanes()  # compiles the lane kernel
    seq_us, lane_us = _best_us((run_seq, run_lanes), lanes)
    diff = max(_rel_diff(lane[key], seq[key]) for key in seq)
    return {"sequential_us": seq_us, "lanes_us": lane_us, "speedup": seq_us / lane_us,
            "max_rel_diff": diff}


# --- the lockstep loss and the ceiling ---


def lockstep(iterations: np.ndarray, sizes: tuple[int, ...] = GROUP_SIZES) -> dict:
    """What lockstep costs on the batch's Newton iteration counts (in batch order).

    ``fixed``: groups of K consecutive designs, each run until its slowest lane is done:
    the groups' summed maximum over the summed iterations (the factor of lane-iterations
    over useful ones). ``refill``: K lanes, a finished lane taking the next design at once;
    the lane-iterations until the last lane is done over the useful ones (only the batch's
    end is lost).
    """
    its = np.asarray(iterations, dtype=np.int64)
    total = float(its.sum())
    out: dict[str, float] = {"designs": float(its.size), "mean_iterations": float(its.mean())}
    for k in sizes:
        groups = its[: its.size // k * k].reshape(-1, k)
        out[f"fixed_{k}"] = float(groups.max(axis=1).sum() * k / groups.sum())
        finish = np.zeros(k, dtype=np.int64)
        for it in its:
            finish[np.argmin(finish)] += it
        out[f"refill_{k}"] = float(finish.max() * k / total)
    return out


def newton_matrix_us(states: list[dict]) -> float:
    """Mean microseconds of the whole assembly of a design's Newton matrix (the gaps, the
    elements and the contact constraints: :func:`solver_profile._time_newton`), the context
    of the element part that the lanes replace."""
    calls = []
    for st in states:
        args = (st["x"], st["n"], st["prm"], st["bidx"], st["kinds"], st["fj"], st["fidx"],
                st["mcount"], st["lam"], st["sig"], st["grad"], st["ab"].copy(),
                st["bb"].copy(), st["dd"].copy(), st["g"], st["grad5"], st["hess5"],
                st["dofs"], st["gb"], st["res"], st["cg"], st["cd"], st["ch"])
        calls.append(lambda args=args: _time_newton(NEWTON_REPS, *args))
    return float(np.mean(_best_us(tuple(calls), NEWTON_REPS)))


def iteration_us(seen: dict, rows: int) -> float:
    """Microseconds of the compiled solve a Newton iteration on the batch's first ``rows``
    designs (one thread; timed as the parts, the fastest of :data:`SAMPLES`), for the parts'
    shares of an iteration."""
    n = seen["n"]
    prm, x0, lam0 = seen["prm"][:rows], seen["x0"][:rows], seen["lam0"][:rows]
    iterations = float(seen["iterations"][:rows].sum())

    def solve():
        pl._solve(n, prm, x0.copy(), lam0.copy())

    return _best_us((solve,), 1)[0] / iterations


def ceiling(batch: dict, per_iteration_us: float, part: dict, losses: dict,
            lanes: int) -> dict:
    """Designs per second of a lane solver against today's, from the batch's stage times.

    The finish and the Python around the solve stay as they are (their share of the batch's
    wall time). ``all``: the optimistic ceiling, the whole compiled solve sped up as the two
    measured parts together (every part of an iteration vectorizes as they do); ``parts``:
    only the measured parts sped up, at their share of an iteration's time (the rest, the
    contacts, the line search and the occasional work, as today). Each with a free lane
    refill (``free``), the refill's measured end loss (``refill``) and groups run to their
    slowest lane (``fixed``).
    """
    seq = part["factor"]["sequential_us"] + part["assembly"]["sequential_us"]
    lane = part["factor"]["lanes_us"] + part["assembly"]["lanes_us"]
    share = min(seq / per_iteration_us, 1.0)
    solve_factor = {"all": lane / seq, "parts": 1.0 - share + share * lane / seq}
    solve_share = batch["solve_s"] / batch["wall_s"]
    out = {"parts_share_of_iteration": share}
    for model, factor in solve_factor.items():
        for mode in ("free", "refill", "fixed"):
            loss = 1.0 if mode == "free" else losses[f"{mode}_{lanes}"]
            out[f"{model}_{mode}"] = 1.0 / (solve_share * factor * loss + 1.0 - solve_share)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=2048)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if args.batch < max(LANE_COUNTS):
        raise ValueError(f"batch: at least {max(LANE_COUNTS)} designs, got {args.batch}")
    start = time.perf_counter()
    report: dict = {"cores": os.cpu_count(), "load_before": _load()}
    designs = DesignBounds().sample(np.random.default_rng(args.seed), args.batch, DISK)
    default = solver_threads()
    set_solver_threads(1)
    try:
        report["batch"], seen = batch_breakdown(designs, {})
        report["iteration_us"] = iteration_us(seen, min(ITERATION_ROWS, args.batch))
    finally:
        set_solver_threads(None if default == 1 else default)
    print("batch (one thread):", {k: round(v, 4) for k, v in report["batch"].items()},
          flush=True)
    print(f"the compiled solve a Newton iteration (first {ITERATION_ROWS} designs, fastest "
          f"of {SAMPLES}): {report['iteration_us']:.2f} us", flush=True)
    states = _states(seen, max(LANE_COUNTS))
    report["newton_matrix_us"] = newton_matrix_us(states)
    print(f"the whole Newton matrix (gaps, elements, contacts): "
          f"{report['newton_matrix_us']:.2f} us a design", flush=True)
    for lanes in LANE_COUNTS:
        part = {"factor": factor_probe(states[:lanes], lanes),
                "assembly": assembly_probe(states[:lanes], lanes)}
        seq = part["factor"]["sequential_us"] + part["assembly"]["sequential_us"]
        lane = part["factor"]["lanes_us"] + part["assembly"]["lanes_us"]
        part["combined"] = seq / lane
        worst = max(part["factor"]["max_rel_diff"], part["assembly"]["max_rel_diff"])
        if not worst <= RTOL:
            raise RuntimeError(f"lanes of {lanes}: answers differ by {worst:.2e} relative "
                               f"(allowed {RTOL:.0e})")
        report[f"lanes_{lanes}"] = part
        print(f"lanes of {lanes} (us a design-iteration):",
              {name: {k: float(f"{v:.4g}") for k, v in p.items()}
               for name, p in part.items() if isinstance(p, dict)},
              f"combined speed-up {part['combined']:.2f}x", flush=True)
    valid = seen["valid"]
    report["lockstep"] = lockstep(seen["iterations"][valid])
    print("lockstep (lane-iterations over useful ones):",
          {k: round(v, 3) for k, v in report["lockstep"].items()}, flush=True)
    for lanes in LANE_COUNTS:
        report[f"ceiling_{lanes}"] = ceiling(report["batch"], report["iteration_us"],
                                             report[f"lanes_{lanes}"], report["lockstep"],
                                             lanes)
        print(f"ceiling, lanes of {lanes} (designs/s against today):",
              {k: round(v, 3) for k, v in report[f"ceiling_{lanes}"].items()}, flush=True)
    report["load_after"] = _load()
    print(f"load {report['load_before']} -> {report['load_after']}; "
          f"{time.perf_counter() - start:.0f} s wall, {time.process_time():.0f} s CPU")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
