"""Augmented-Lagrangian Newton polish on the identified contact set, so that contacts hold to
round-off.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model.layout import (
    KIND_CORNER,
    KIND_FACE,
    O_POLISH_STEPS,
    O_TOL,
    P_KAPPA,
    P_KC,
    P_KR,
    P_RHO,
)
from .assembly import (
    CH_BLOCK,
    _energy,
    _newton_matrix,
    _rhs_to_band,
    _stationarity,
    _step_from_band,
)
from .banded import (
    _angle_schur,
    _factor_solve,
    _forward_from,
    _solve_factored,
    band_shape,
)
from .contact import (
    _all_gaps,
    _con_value,
    _corner_on_edge,
    _face_gap,
    _grooved,
    _sel,
    _trig,
)
from .status import (
    OK,
    POLISH_FAIL,
)

# An answer is stable when its Newton matrix plus NEUTRAL times the stiffness scale is positive
# definite: a mode softer than that is neutral, not unstable. The one-ring fans' turn about the
# pin is nearly free (the frictionless contacts hold it only through the polygon's facets); at
# N = 1000-2000 its curvature is decided by round-off, and the stress grid's constant-strain
# fans there (3 of 27 ramps) failed only because every polished answer came out "unstable" and
# each fallback repeated it. Random designs (12,000 fans, 3,000 of the default model) and the
# regression corpus keep every answer and flag
NEUTRAL = 1e-8

# The polish's steps: a fresh factor each (FULL_STEPS), or the last factor again (a chord step:
# a gradient and a solve, not an assembly and a factor) after a full step that shrank the
# residual by at least the rate given. Why: from a neighbour's answer
# (:mod:`envs.solver.follow`) the polish takes 5 to 6 steps, and once its full steps shrink the
# residual fast the matrix changes little from one to the next. A chord step that is not a
# descent direction, that the line search cuts, or that shrinks the residual less than the
# rate is followed by a fresh factor; the tests of convergence, stability and the line search
# are the same for both.
FULL_STEPS = 0.0
CHORD_RATE = 0.1
# Newton multipliers (``exact_multipliers``): the augmented Lagrangian's multiplier update
# lam - rho g converges linearly, by about kappa / rho = 1e-2 a step, whatever the start; from
# a start a few percent off (a neighbour's answer, envs.solver.follow) that rate, not Newton's,
# set the step count (7.0 steps, 88 % settled within 10, on 128 designs x 8 displaced
# placements of +-2 mm). Each step can instead take the multipliers of the KKT system's Newton
# step on the active set: the change ``delta`` for which the step meets the active constraints
# to first order (``S delta = -g - J dx`` with ``S = J W^-1 J^T``), at the price of one forward
# sweep per active contact and one more solve. Both converge to the same equilibrium; the
# solver's own polish keeps the plain update (its answers stay bit for bit).
POLISH_ATTEMPTS = 6  # polishes on a corrected contact set before giving up
# A point's gap counts as its distance to a corner's rounding when within this of it [r]
# (round-off: a point beside the rounding, on the face next to it, is nearer the face by
# u^2 / (2 rho) at a distance u from the corner's line)
TOUCH_TOL = 1e-14
# Largest gap [r] of an active constraint that a polish in equilibrium may end with once its
# steps are spent (rather than the round-off it aims for)
TOUCH_GAP = 1e-10


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


@njit(cache=True, error_model="numpy", _nrt=False)
def _contact_schur(lb, bb, dd, ybuf, nbb, shift, bidx, nb, cg, cd, active, mcount, act, first,
                   zc, zt, sch, rwork):
    """Cholesky factor (lower, in ``sch``) of ``S = J W^-1 J^T`` over the active constraints,
    with ``W`` the bordered matrix factored in ``lb``, ``bb``, ``dd`` (and ``ybuf = A^-1 B``,
    as the last solve with that factor left it). Returns the count ``k`` of active constraints
    (their indices in ``act``), or -1 where S is not positive definite.

    Why forward sweeps only: with the full factor ``L_W``, ``S = Z^T Z`` for
    ``Z = L_W^-1 J^T``; a constraint's gradient touches one or two points and a finger angle,
    so its column of ``Z`` is a forward sweep from its first point (row ``first``) plus two
    angle entries ``Lc^-1 (j_t - (A^-1 B)^T j_b)``, ``Lc`` the Cholesky factor of the angles'
    Schur complement.
    """
    s00, s11, s01 = _angle_schur(dd, bb, ybuf, nbb, shift)
    if not s00 > 0.0:
        return -1
    c00 = math.sqrt(s00)
    c10 = s01 / c00
    c11 = s11 - c10 * c10
    if not c11 > 0.0:
        return -1
    c11 = math.sqrt(c11)
    k = 0
    for m in range(mcount):
        if not active[m]:
            continue
        act[k] = m
        rwork[:] = 0.0
        start = nbb
        t0 = 0.0
        t1 = 0.0
        for a in range(cd.shape[1]):
            d = cd[m, a]
            v = cg[m, a]
            if v == 0.0:
                continue
            if d == nb:
                t0 += v
            elif d == nb + 1:
                t1 += v
            else:
                p = bidx[d // 2] + d % 2
                rwork[p] += v
                start = min(start, p)
                t0 -= ybuf[p, 0] * v
                t1 -= ybuf[p, 1] * v
        first[k] = start
        if start < nbb:
            _forward_from(lb, nbb, rwork, zc[k], start)
        zt[k, 0] = t0 / c00
        zt[k, 1] = (t1 - c10 * zt[k, 0]) / c11
        k += 1
    diag_max = 0.0
    for i in range(k):
        for j in range(i + 1):
            v = zt[i, 0] * zt[j, 0] + zt[i, 1] * zt[j, 1]
            for p in range(max(first[i], first[j]), nbb):
                v += zc[i, p] * zc[j, p]
            sch[i, j] = v
        diag_max = max(diag_max, sch[i, i])
    # in place; a floor of round-off size for dependent constraints (a corner and the faces
    # of the same points)
    for i in range(k):
        for j in range(i + 1):
            v = sch[i, j] + (1e-12 * diag_max if i == j else 0.0)
            for t in range(j):
                v -= sch[i, t] * sch[j, t]
            if i == j:
                if not v > 0.0:
                    return -1
                sch[i, i] = math.sqrt(v)
            else:
                sch[i, j] = v / sch[j, j]
    return k


@njit(cache=True, error_model="numpy", _nrt=False)
def _newton_multipliers(k, act, sch, cg, cd, g, step, delta, lb, bb, dd, ybuf, nbb, shift, bidx,
                        nb, ework, rb, rt, ob, ot, swork):
    """The multipliers' change ``delta`` (of the ``k`` active constraints ``act``) that makes
    ``step`` meet them to first order, ``S delta = -g - J step`` (``sch``: the factor of
    :func:`_contact_schur`), and ``step`` changed by ``W^-1 J^T delta``. Returns False where
    the solve fails."""
    for i in range(k):
        m = act[i]
        v = -g[m]
        for a in range(cd.shape[1]):
            v -= cg[m, a] * step[cd[m, a]]
        delta[i] = v
    for i in range(k):
        v = delta[i]
        for t in range(i):
            v -= sch[i, t] * delta[t]
        delta[i] = v / sch[i, i]
    for i in range(k - 1, -1, -1):
        v = delta[i]
        for t in range(i + 1, k):
            v -= sch[t, i] * delta[t]
        delta[i] = v / sch[i, i]
    ework[:] = 0.0
    for i in range(k):
        m = act[i]
        for a in range(cd.shape[1]):
            ework[cd[m, a]] -= cg[m, a] * delta[i]  # (_rhs_to_band takes the negative)
    _rhs_to_band(ework, bidx, nb, rb, rt)
    if not _solve_factored(lb, bb, dd, ybuf, nbb, shift, rb, rt, ob, ot):
        return False
    _step_from_band(ob, ot, bidx, nb, ework, swork)
    for d in range(step.shape[0]):
        step[d] += swork[d]
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _polish(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active, work_it,
            chord_rate, exact_multipliers):
    """Augmented-Lagrangian Newton on the active set: contacts hold to round-off.

    Allocates the work arrays for :func:`_polish_core` (compiled without reference counting).
    ``chord_rate``: :data:`FULL_STEPS` (a fresh factor every step) or a rate such as
    :data:`CHORD_RATE` (chord steps while full steps shrink the residual that fast).
    ``exact_multipliers``: each step with Newton's multipliers (:func:`_newton_multipliers`)
    instead of the augmented Lagrangian's update.

    Returns (ok, stable) where stable means the final Newton matrix is positive definite up to
    :data:`NEUTRAL` of the stiffness scale.
    """
    nx = x.shape[0]
    nbb, bw = band_shape(n, prm)
    grad = np.zeros(nx)
    ab = np.zeros((nbb, bw + 1))
    lb = np.zeros((nbb, bw + 1))
    bb = np.zeros((nbb, 2))
    dd = np.zeros((2, 2))
    ybuf = np.zeros((nbb, 2))
    rb = np.zeros(nbb)
    ob = np.zeros(nbb)
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
    lam_step = np.zeros(mcount)
    # the Newton multipliers' work arrays (one row where they are not used)
    kdim = mcount if exact_multipliers else 1
    act = np.zeros(kdim, dtype=np.int64)
    first = np.zeros(kdim, dtype=np.int64)
    zc = np.empty((kdim, nbb))
    zt = np.zeros((kdim, 2))
    sch = np.zeros((kdim, kdim))
    delta = np.zeros(kdim)
    return _polish_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                        work_it, chord_rate, grad, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, sig,
                        lam_eff, res, res_p, gbuf_p, xt, step, grad5, hess5, dofs, cg, cd, ch,
                        exact_multipliers, lam_step, act, first, zc, zt, sch, delta)


@njit(cache=True, error_model="numpy", _nrt=False)
def _polish_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active, work_it,
                 chord_rate, grad, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, sig, lam_eff, res,
                 res_p, gbuf_p, xt, step, grad5, hess5, dofs, cg, cd, ch, exact_multipliers,
                 lam_step, act, first, zc, zt, sch, delta):
    nb = 2 * n
    nx = x.shape[0]
    kscale = max(prm[P_KC], prm[P_KR], prm[P_KAPPA])
    rho = 1e2 * kscale
    tol = max(opts[O_TOL] * fscale, 1e-15 * max(prm[P_KC], prm[P_KR]))
    q = x[:nb].reshape(n, 2)
    for m in range(mcount):
        if not active[m]:
            lam[m] = 0.0
    stable = True
    kreg = 1e-10 * max(prm[P_KC], prm[P_KR])
    kkt_best = math.inf
    fresh = True
    shift = kreg
    slope = 0.0
    k_active = -1  # active constraints in the factor of _contact_schur (-1: none)
    kkt = viol = math.inf  # (no step taken: not converged)
    for _outer in range(int(opts[O_POLISH_STEPS])):
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
        chord = False
        if not fresh:
            # a chord step: the last factor with this point's gradient (the augmented
            # Lagrangian's: the stationarity residual at the effective multipliers)
            _stationarity(x, n, prm, kinds, fj, fidx, mcount, lam_eff, gbuf_p, grad5, hess5,
                          dofs, grad)
            _rhs_to_band(grad, bidx, nb, rb, rt)
            chord = _solve_factored(lb, bb, dd, ybuf, ab.shape[0], shift, rb, rt, ob, ot)
            if chord:
                slope = _step_from_band(ob, ot, bidx, nb, grad, step)
                chord = slope < 0.0
        if not chord:
            # psd=False as a runtime value, not a literal: the Hessian kernels compile once
            # (assembly._spring_terms)
            exact = n < 0
            _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam_eff, sig, grad, ab,
                           bb, dd, g, grad5, hess5, dofs, 0.0, exact, gbuf_p, res_p, cg, cd, ch)
            _rhs_to_band(grad, bidx, nb, rb, rt)
            shift = kreg
            ok = _factor_solve(ab, bb, dd, lb, ybuf, ab.shape[0], shift, rb, rt, ob, ot)
            if not ok:
                # the first shifted factor is also the stability test's
                shift = NEUTRAL * kscale
                ok = _factor_solve(ab, bb, dd, lb, ybuf, ab.shape[0], shift, rb, rt, ob, ot)
            stable = ok
            while not ok:
                shift *= 8.0
                if shift > 1e6 * kscale:
                    return False, False
                ok = _factor_solve(ab, bb, dd, lb, ybuf, ab.shape[0], shift, rb, rt, ob, ot)
            slope = _step_from_band(ob, ot, bidx, nb, grad, step)
        # the multipliers of this step's merit and update: lam, or Newton's (a chord step
        # keeps the last full step's S, as it keeps its factor)
        for m in range(mcount):
            lam_step[m] = lam[m]
        if exact_multipliers:
            if not chord:
                k_active = _contact_schur(lb, bb, dd, ybuf, ab.shape[0], shift, bidx, nb, cg, cd,
                                          active, mcount, act, first, zc, zt, sch, rb)
            if k_active > 0 and _newton_multipliers(k_active, act, sch, cg, cd, g, step, delta,
                                                    lb, bb, dd, ybuf, ab.shape[0], shift, bidx,
                                                    nb, res_p, rb, rt, ob, ot, xt):
                # the slope of the merit at the new multipliers along the new step
                slope = 0.0
                for d in range(nx):
                    slope += grad[d] * step[d]
                for i in range(k_active):
                    m = act[i]
                    lam_step[m] += delta[i]
                    for a in range(cd.shape[1]):
                        slope -= delta[i] * cg[m, a] * step[cd[m, a]]
        # the merit at x from the gaps above (what _al_merit would evaluate again)
        m0 = _energy(x, n, prm)
        for m in range(mcount):
            if active[m]:
                m0 += g[m] * (0.5 * rho * g[m] - lam_step[m])
        alpha = 1.0
        hit = False
        for _ls in range(40):
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
            mt = _al_merit(xt, n, prm, kinds, fj, fidx, mcount, lam_step, active, rho, g)
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
                        lam_step[m] = 0.0
            # (a touch of a corner taken in where its point's constraint holds it already, or
            # the other way round: one of the two, judged where the step ran through it; the
            # multipliers moved are the step's, from which the update below starts)
            _one_constraint_per_touch(xt, n, prm, kinds, fj, fidx, mcount, active, lam_step)
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
        for d in range(nx):
            x[d] = xt[d]
        # multiplier update
        sn, cs = _trig(x, n)
        for m in range(mcount):
            if active[m]:
                gm = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)
                lam[m] = lam_step[m] - rho * gm
            else:
                # lam_step holds lam's value here, but for a constraint the step's
                # _one_constraint_per_touch dropped (its force passed to the one kept: counted
                # in the stationarity below once, not twice)
                lam[m] = lam_step[m]
        kkt = _stationarity(x, n, prm, kinds, fj, fidx, mcount, lam, g, grad5, hess5, dofs,
                            res)
        viol = 0.0
        for m in range(mcount):
            if active[m]:
                viol = max(viol, abs(g[m]))
        if kkt <= 10.0 * tol and viol <= 1e-13:
            return True, stable
        if viol <= 1e-12 and ((_outer >= 8 and kkt <= 100.0 * tol)
                              or (kkt >= 0.5 * kkt_best and kkt <= 1e3 * tol)):
            # stagnating at round-off level: good enough (the independent check has the say).
            # The floor grows with the mesh (N = 1000: ~1e-10 of the force scale, where the
            # plain test spent 9 Newton steps on round-off)
            return True, stable
        # keep the factor while full steps shrink the residual fast; a fresh one otherwise
        # (with Newton's multipliers not after the first step: its factor is the start's, a
        # few percent off, and a chord step from it converges only at that rate)
        fresh = not (alpha == 1.0 and not hit and kkt <= chord_rate * kkt_best
                     and (_outer > 0 or not exact_multipliers))
        kkt_best = min(kkt_best, kkt)
    if (_grooved(0, prm) or _grooved(1, prm)) and kkt <= 10.0 * tol and viol <= TOUCH_GAP:
        # the steps spent on a touch whose two constraints meet to second order (see
        # _one_constraint_per_touch), in equilibrium with the gaps at round-off of the unit
        # length: the answer stands, the independent check has the say (gaps within 1e-9 r)
        return True, stable
    return False, stable


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _face_constraint(kinds, fj, fidx, mcount, j, i):
    """Index of the face constraint of point ``i`` on finger ``j`` in the list, -1 if it is
    not a candidate."""
    for m in range(mcount):
        if kinds[m] == KIND_FACE and fj[m] == j and fidx[m] == i:
            return m
    return -1


@njit(cache=True, error_model="numpy", _nrt=False)
def _one_constraint_per_touch(x, n, prm, kinds, fj, fidx, mcount, active, lam):
    """Keep one constraint of each touch that two describe, on grooved fingers: in place on
    ``active`` and ``lam`` (the dropped one's multiplier passes to the kept one).

    Why: a contour point against a rounded corner (a groove's mouth edge, where a contact
    slides off the face into the groove) is one touch with two gaps, the point's gap to the
    finger and the corner's gap to a contour edge at that point. Where the corner's foot on
    the edge is the edge's end point, the corner's gap is that point's distance to it, never
    below the point's gap to the whole finger: the point's constraint implies it. Where the
    foot lies inside the edge and the point's nearest surface is that corner, the point's gap
    is never below the edge's: the corner's constraint implies it. Returns whether the set
    changed. Both active, the polish
    solved for both gaps at round-off, which holds only with the foot exactly at the point
    (the two gaps meet to second order there), and stalled 1e-9 short (status 5 on cradles
    whose contact ends at the groove's mouth). A corner pressing inside an edge whose end
    point presses another surface keeps both: two touches.
    """
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    changed = False
    # first the corners whose foot is an end point (their touch passes to that point), then
    # those inside an edge (a point's touch on the same corner passes to them), so that a
    # point a corner's foot lies beyond is judged against the corner's inner edge too
    for inner in range(2):
        for m in range(mcount):
            if not (active[m] and kinds[m] == KIND_CORNER and _grooved(fj[m], prm)):
                continue
            j = fj[m]
            kx, ky, k, k1, _, _, foot = _corner_on_edge(q, fidx[m], j, sn, cs, prm)
            at_end = foot <= 0.0 or foot >= 1.0
            if at_end and inner == 0:
                f = _face_constraint(kinds, fj, fidx, mcount, j, k if foot <= 0.0 else k1)
                if f >= 0:
                    active[f] = True
                    lam[f] = max(lam[f], 0.0) + max(lam[m], 0.0)
                    active[m] = False
                    lam[m] = 0.0
                    changed = True
            elif not at_end and inner == 1:
                for v in (k, k1):
                    f = _face_constraint(kinds, fj, fidx, mcount, j, v)
                    if f < 0 or not active[f]:
                        continue
                    corner = math.sqrt((q[v, 0] - kx) ** 2 + (q[v, 1] - ky) ** 2) - prm[P_RHO]
                    if _face_gap(q, v, j, _sel(sn, j), _sel(cs, j), prm) >= corner - TOUCH_TOL:
                        lam[m] = max(lam[m], 0.0) + max(lam[f], 0.0)
                        active[f] = False
                        lam[f] = 0.0
                        changed = True
    return changed


@njit(cache=True, error_model="numpy")
def _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                work_it, gbuf, stable_out, chord_rate, carry, exact_multipliers):
    """Polish on a contact set, correcting the set (primal-dual active set) a few times.

    Drops contacts that come out with a pulling force and adds constraints that come out
    violated. On success ``xs`` and ``lam`` hold the polished answer; returns a status.
    ``chord_rate`` as :func:`_polish`. ``carry``: each correction goes on from the last
    polished point rather than from ``xs`` (the scenario fast path of
    :mod:`envs.solver.follow`: from a start a few millimetres off, a constraint added after the
    first polish can be far open at the start, and a polish restarted there diverged).
    ``exact_multipliers`` as :func:`_polish`.
    """
    _one_constraint_per_touch(xs, n, prm, kinds, fj, fidx, mcount, active, lam)
    for _attempt in range(POLISH_ATTEMPTS):
        xp = xs.copy()
        lp = lam[:mcount].copy()
        okp, stable = _polish(xp, lp, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale,
                              active, work_it, chord_rate, exact_multipliers)
        stable_out[0] = stable
        if not okp:
            # a polish that crossed a corner's touch ends near it with both of its
            # constraints: once more with one of them, else it failed
            if _one_constraint_per_touch(xp, n, prm, kinds, fj, fidx, mcount, active, lam):
                continue
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
        if good or carry:
            for d in range(xs.shape[0]):
                xs[d] = xp[d]
            for m in range(mcount):
                lam[m] = max(lp[m], 0.0) if active[m] else 0.0
        if good:
            return OK
        # the corrected set, judged where its corrections were found (after the copy above,
        # so that a multiplier it moves to the constraint it keeps stays moved)
        _one_constraint_per_touch(xp, n, prm, kinds, fj, fidx, mcount, active, lam)
    return POLISH_FAIL
