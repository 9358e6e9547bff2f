"""A step off a saddle along the Newton matrix's most negative curvature.

Why: past a symmetry-breaking bifurcation (a pitchfork: the default model on paper-r070 near
0.888 N·m, where the symmetric (5, 5) contact set gives way to an asymmetric (6, 5) one) the
interior point converges to the symmetric equilibrium, a saddle whose exact Newton matrix is
indefinite. The escapes of :mod:`envs.solver.driver` (a rigid turn of the contour, the fingers
opened) lead back to it. The unstable mode itself is the eigenvector of the most negative
eigenvalue of that matrix: inverse iteration with the smallest diagonal shift that makes the
matrix positive definite finds it with a few banded factorizations, and a short step along it
(either sense: the energy falls both ways to second order) leaves the saddle.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.energy import folded_triangles
from .assembly import _energy, _step_from_band
from .banded import _factor_solve
from .contact import _all_gaps, _tunnels

CURVATURE_STEP = 0.25  # largest point move of the step, in point spacings (2 pi r / N)
INVERSE_ITERATIONS = 12
SHIFT_REFINEMENTS = 6  # bisections (in log) of the positive-definite shift
STEP_HALVINGS = 8


@njit(cache=True, error_model="numpy", _nrt=False)
def _smallest_pd_shift(ab, bb, dd, lb, ybuf, nbb, start, rb, rt, ob, ot):
    """The smallest diagonal shift (within a factor 2^(8/2^k)) that makes the matrix positive
    definite, from ``start`` up; 0 when none up to ``start * 8^40``."""
    lo, hi = 0.0, start
    for _k in range(40):
        if _factor_solve(ab, bb, dd, lb, ybuf, nbb, hi, rb, rt, ob, ot):
            break
        lo, hi = hi, hi * 8.0
    else:
        return 0.0
    for _k in range(SHIFT_REFINEMENTS):
        mid = math.sqrt(lo * hi) if lo > 0.0 else 0.125 * hi
        if _factor_solve(ab, bb, dd, lb, ybuf, nbb, mid, rb, rt, ob, ot):
            hi = mid
        else:
            lo = mid
    return hi


@njit(cache=True, error_model="numpy", _nrt=False)
def _negative_curvature_step(x, n, prm, bidx, kinds, fj, fidx, mcount, g, kreg, ab, bb, dd,
                             lb, ybuf, rb, ob, rt, ot, grad, step, xt, gt):
    """Move ``x`` off a saddle along the most negative curvature of the Newton matrix in
    ``ab``/``bb``/``dd`` (exact, indefinite; not modified). Returns whether it moved (then
    ``x`` and the gaps ``g`` are those after the step).

    The step moves no point more than :data:`CURVATURE_STEP` point spacings and keeps every
    gap above a tenth of its value, with nothing tunnelling and no triangle turned over
    (halved until it does, either sense).
    """
    nbb = ab.shape[0]
    nb = 2 * n
    for p in range(nbb):
        rb[p] = 0.0
    rt[0] = 0.0
    rt[1] = 0.0
    shift = _smallest_pd_shift(ab, bb, dd, lb, ybuf, nbb, kreg, rb, rt, ob, ot)
    if shift == 0.0:
        return False
    # inverse iteration from a start without mirror symmetry (a symmetric start would stay
    # orthogonal to the antisymmetric unstable mode)
    for p in range(nbb):
        rb[p] = math.sin(1.7 * p + 0.3)
    rt[0] = 0.3
    rt[1] = -0.2
    for _k in range(INVERSE_ITERATIONS):
        if not _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rb, rt, ob, ot):
            return False
        norm = 0.0
        for p in range(nbb):
            norm += ob[p] * ob[p]
        norm = math.sqrt(norm + ot[0] * ot[0] + ot[1] * ot[1])
        if not norm > 0.0:
            return False
        for p in range(nbb):
            rb[p] = ob[p] / norm
        rt[0] = ot[0] / norm
        rt[1] = ot[1] / norm
    _step_from_band(rb, rt, bidx, nb, grad, step)
    biggest = 0.0
    for d in range(nb):
        biggest = max(biggest, abs(step[d]))
    for d in range(nb + 2, step.shape[0]):
        biggest = max(biggest, abs(step[d]))
    if not biggest > 0.0:
        return False
    folded = folded_triangles(x, n, prm)
    for sgn in (1.0, -1.0):
        c = sgn * CURVATURE_STEP * 2.0 * math.pi / n / biggest
        for _k in range(STEP_HALVINGS):
            for d in range(x.shape[0]):
                xt[d] = x[d] + c * step[d]
            _all_gaps(xt, n, prm, kinds[:mcount], fj, fidx, gt)
            ok = True
            for m in range(mcount):
                if not gt[m] >= 0.1 * g[m]:
                    ok = False
                    break
            # nothing tunnels and no triangle turns over (the energy of an nh-quad or
            # area-energy mesh is infinite there; the springs-only fan must not be stepped
            # into a fold)
            if (ok and not _tunnels(x, xt, n, prm) and math.isfinite(_energy(xt, n, prm))
                    and folded_triangles(xt, n, prm) <= folded):
                for d in range(x.shape[0]):
                    x[d] = xt[d]
                for m in range(mcount):
                    g[m] = gt[m]
                return True
            c *= 0.5
    return False
