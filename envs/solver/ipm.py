"""Primal-dual interior-point Newton iterations on a fixed constraint set, with exact Hessians,
inertia correction and a backtracking line search on the barrier merit.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..model.layout import (
    GAUGE_AT_REST,
    GAUGE_PROXIMAL,
    N_OPTIONS,
    O_MAXIT,
    O_TOL,
    P_GAUGE,
    P_GPROX,
    P_KC,
    P_KR,
)
from .assembly import (
    CH_BLOCK,
    _drop_curvature,
    _merit,
    _newton_matrix,
    _rhs_to_band,
    _step_from_band,
)
from .banded import (
    _factor_solve,
    _solve_factored,
    band_shape,
)
from .contact import (
    _all_gaps,
    _tunnels,
    constraint_dofs,
)
from .curvature import _negative_curvature_step, _smallest_pd_shift
from .gauge import (
    _gauge_reanchor,
    _leave_saddle,
)
from .status import (
    BLOCKED,
    ITER_LIMIT,
    LINALG_FAIL,
    LINESEARCH_FAIL,
    OK,
    SADDLE,
)

MAX_CURVATURE_STEPS = 2  # steps along a saddle's unstable mode per interior-point call
MAX_SOC = 1  # second-order corrections of a rejected full step
STALL_STEPS = 2  # stalled steps on the modified matrix before a shifted exact one
MAX_POINT_STEP = 0.1  # largest point move of one step [scaled by the radius]
MAX_FINGER_STEP = 0.05  # largest finger turn of one step [rad]
GAP_TARGET = 0.05  # a shrinking gap's share left after a step cut back for it
# mu is cut once the barrier problem is solved to CENTRALITY * mu (stationarity and every
# lam g - mu). Measured on 4000 random fan designs and 2000 of the default model per paper disk:
# 100 against 10 takes the mean iterations from 24.0-24.6 to 19.6-20.9 (fan) and from 16.7-17.3
# to 13.1-13.6 (default; its asymmetric answers 71-80 -> 37), convergence unchanged; 30 and 300
# cost 1-2 iterations more, 1000 undoes the gain on the fan
CENTRALITY = 100.0


class IpmWork(NamedTuple):
    """Work arrays of the interior point (allocated once per call of :func:`_ipm`).

    State-order vectors (2 N M + 2): ``grad`` (merit gradient), ``step``, ``xt`` (trial
    state), ``res`` (stationarity residual), ``gb`` (gradient scratch). Band-ordered Newton
    matrix: ``ab`` (band, 2 N M rows, half bandwidth + 1 columns), its factor ``lb``, the
    border ``bb`` (2 N M x 2) and corner ``dd`` (2 x 2), the solve's ``ybuf``, right-hand sides
    ``rb``/``rt`` and solutions ``ob``/``ot``. Per constraint: gaps ``g``/``gt`` (current,
    trial), ``sig`` (multiplier over gap), ``dlam`` (multiplier step), cached gradients ``cg``,
    their dofs ``cd`` and curvature ``ch``. One constraint's scratch: ``grad5``, ``hess5``,
    ``dofs``. The gauge's saddle test (:mod:`envs.solver.gauge`): ``wb`` (band order) and
    ``wt`` (2) get ``W^-1 t``. The second-order correction: ``corr`` (state order) and ``qs``
    (per constraint, the gaps' change beyond their linearization); ``gf`` (per constraint):
    the gaps at a rejected first trial point, for the next step length (:func:`_gap_limited`).
    """

    grad: np.ndarray
    step: np.ndarray
    xt: np.ndarray
    res: np.ndarray
    ab: np.ndarray
    lb: np.ndarray
    bb: np.ndarray
    dd: np.ndarray
    ybuf: np.ndarray
    rb: np.ndarray
    ob: np.ndarray
    rt: np.ndarray
    ot: np.ndarray
    g: np.ndarray
    gt: np.ndarray
    sig: np.ndarray
    dlam: np.ndarray
    grad5: np.ndarray
    hess5: np.ndarray
    dofs: np.ndarray
    gb: np.ndarray
    cg: np.ndarray
    cd: np.ndarray
    ch: np.ndarray
    wb: np.ndarray
    wt: np.ndarray
    corr: np.ndarray
    qs: np.ndarray
    gf: np.ndarray


@njit(cache=True, error_model="numpy", inline="always")
def _ipm(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it):
    """Primal-dual interior point on a fixed constraint set. Returns (status, iterations).

    Allocates the work arrays; the iterations run in :func:`_ipm_core`, compiled without
    reference counting (array views and helper calls inside it then cost nothing extra).
    """
    nx = x.shape[0]
    nbb, bw = band_shape(n, prm)
    grad = np.zeros(nx)
    step = np.zeros(nx)
    xt = np.zeros(nx)
    res = np.zeros(nx)
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
    wb = np.zeros(nbb)
    wt = np.zeros(2)
    corr = np.zeros(nx)
    qs = np.zeros(mcount)
    gf = np.zeros(mcount)
    work = IpmWork(grad, step, xt, res, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, gt, sig, dlam,
                   grad5, hess5, dofs, gb, cg, cd, ch, wb, wt, corr, qs, gf)
    return _ipm_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it,
                     work)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _restart_barrier(mu, mu0, shrink, lam, g, mcount, lift):
    """After a step off a saddle (it moves contacts): the barrier back at its first ``mu0``
    and every multiplier at least ``mu / g`` (also when ``mu`` stays, with ``lift``).
    Returns ``(mu, shrink)``."""
    restart = mu < mu0
    if restart:
        mu = mu0
        shrink = 0.01
    if restart or lift:
        for m in range(mcount):
            lam[m] = max(lam[m], mu / g[m])
    return mu, shrink


@njit(cache=True, error_model="numpy", _nrt=False)
def _trial(x, xt, n, prm, kinds, fj, fidx, mcount, g, gt, shrink, mu, bound):
    """Line-search test of the trial point ``xt``: every gap positive and shrunk by at most
    ``shrink``, no tunnelling, barrier merit at most ``bound``. Returns (accepted, walled,
    energy, sum of log gaps); ``walled``: rejected by the anti-tunnelling test only."""
    e_t, l_t = _merit(xt, n, prm, kinds, fj, fidx, mcount, gt)
    phi = e_t - mu * l_t
    if not phi < math.inf:
        return False, False, e_t, l_t
    for m in range(mcount):
        if gt[m] < shrink * g[m]:
            return False, False, e_t, l_t
    if _tunnels(x, xt, n, prm):
        return False, True, e_t, l_t
    return phi <= bound, False, e_t, l_t


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gap_limited(g, gf, mcount):
    """Factor of the next trial step after the first was rejected with the gaps ``gf``: the
    secant of each shrinking gap between ``x`` and the trial brought to GAP_TARGET of its
    value (not a blind half, which can only halve an overshooting gap per iteration); 0.5 if
    no gap limits it (the merit's decrease failed)."""
    fac = 1.0
    for m in range(mcount):
        if gf[m] < GAP_TARGET * g[m]:
            fac = min(fac, (1.0 - GAP_TARGET) * g[m] / (g[m] - gf[m]))
    return fac if fac < 1.0 else 0.5


@njit(cache=True, error_model="numpy", _nrt=False)
def _second_order(x, xt, step, n, prm, bidx, kinds, fj, fidx, mcount, g, gt, lam, sig, mu, cg,
                  cd, qs, corr, lb, bb, dd, ybuf, shift, rb, rt, ob, ot):
    """Second-order correction of the rejected full step ``x -> xt = x + step``.

    The Newton step linearizes each gap and the complementarity ``lam g = mu``. Right after a
    cut of mu both fail where a contact's force must grow (its predicted gap is
    ``(mu - g dlam) / lam``: negative once dlam is comparable to lam), and against a turning
    finger the gaps curve (bilinear in a point's position and the finger's angle). With ``q``
    a gap's change beyond its linearization at ``xt`` and the product ``dlam dg`` of the step
    (Mehrotra's corrector term), the rows ``lam (dg + q) + g dlam + dlam_p dg_p = mu - lam g``
    give the same matrix and the extra right-hand side ``-sum sig qs grad g`` with
    ``qs = q + dlam_p dg_p / lam``: one more solve with the factor ``lb`` of the step (IPOPT's
    second-order correction, for inequality gaps). ``gt``: the gaps at ``xt``, which becomes
    ``x + step + corr``.
    Returns False if the solve fails.
    """
    nb = 2 * n
    corr[:] = 0.0
    for m in range(mcount):
        nd = constraint_dofs(kinds[m])
        lin = 0.0
        for a in range(nd):
            lin += cg[m, a] * step[cd[m, a]]
        # beyond the linearization: the gap's curvature, and the product of the multiplier's
        # and the gap's steps in lam g = mu (Mehrotra's corrector term)
        dlp = mu / g[m] - lam[m] - sig[m] * lin
        qs[m] = gt[m] - g[m] - lin + dlp * lin / lam[m]
        w = sig[m] * qs[m]
        for a in range(nd):
            corr[cd[m, a]] += w * cg[m, a]
    _rhs_to_band(corr, bidx, nb, rb, rt)
    if not _solve_factored(lb, bb, dd, ybuf, lb.shape[0], shift, rb, rt, ob, ot):
        return False
    _step_from_band(ob, ot, bidx, nb, corr, corr)
    for d in range(x.shape[0]):
        xt[d] = x[d] + step[d] + corr[d]
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _step_excess(step, nb):
    """How far ``step`` exceeds the step limits (above 1: by that factor):
    :data:`MAX_POINT_STEP` for every point coordinate, :data:`MAX_FINGER_STEP` for the two
    finger angles at ``nb`` and ``nb + 1`` (a full step can jump a finger past a vertex)."""
    smax = 0.0
    for d in range(step.shape[0]):
        if d != nb and d != nb + 1:
            smax = max(smax, abs(step[d]))
    return max(smax / MAX_POINT_STEP, abs(step[nb]) / MAX_FINGER_STEP,
               abs(step[nb + 1]) / MAX_FINGER_STEP)


@njit(cache=True, error_model="numpy", _nrt=False)
def _ipm_core(x, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, mu0, work_it, work):
    (grad, step, xt, res, ab, lb, bb, dd, ybuf, rb, ob, rt, ot, g, gt, sig, dlam, grad5, hess5,
     dofs, gb, cg, cd, ch, _, _, corr, qs, gf) = work
    nb = 2 * n
    nx = x.shape[0]
    nbb = ab.shape[0]
    tol = max(opts[O_TOL] * fscale, 1e-15 * max(prm[P_KC], prm[P_KR]))
    maxit = int(opts[O_MAXIT])
    mu = mu0
    mu_min = 1e-3 * tol
    shrink = 0.01
    shift_last = 0.0
    kreg = 1e-10 * max(prm[P_KC], prm[P_KR])
    it = 0
    n_neg = 0
    kkt_prev = math.inf
    mu_prev = -1.0
    n_stall = 0
    curvature_steps = 0
    n_walled = 0
    have_acc = False  # merit parts at x known (from the line search that reached x)
    e_acc = 0.0
    l_acc = 0.0
    alpha = -1.0  # length of the last accepted step (none yet): the proximal gauge follows it
    check_gauge = False  # test whether the gauge holds up a saddle (after each decrease of mu)
    _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, g)
    while it < maxit:
        if prm[P_GAUGE] > 0.0 and prm[P_GPROX] == GAUGE_PROXIMAL:
            # the merit at x loses the gauge spring's energy there (anchored at x, it is zero)
            e_acc -= _gauge_reanchor(x, prm, alpha)
        # exact Hessian first; where it is indefinite (compressed springs), the Hessian with the
        # springs' negative geometric stiffness and the constraint curvature removed (made from
        # the exact one in place, _drop_curvature); a diagonal shift only as a last resort.
        # The same pass gives the stationarity residual (sig = lam / g does not depend on mu).
        for m in range(mcount):
            sig[m] = lam[m] / g[m]
        # psd=False as a runtime value, not a literal: the Hessian kernels compile once
        # (assembly._spring_terms)
        exact = n < 0
        _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd,
                       g, grad5, hess5, dofs, mu, exact, gb, res, cg, cd, ch)
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
            if (mu > mu_min and kkt <= CENTRALITY * max(mu, tol)
                    and cmax <= CENTRALITY * max(mu, tol)):
                mu_new = max(mu_min, min(0.2 * mu, mu ** 1.5))
                # active gaps scale with mu: let them shrink by that factor in one step
                shrink = min(0.01, 0.1 * mu_new / mu)
                for d in range(nx):
                    grad[d] += (mu - mu_new) * gb[d]
                mu = mu_new
                check_gauge = True
                continue
            break
        if done:
            work_it[0] += it
            return OK, it
        # no progress at this mu (e.g. a crawl down a soft mode that the modified matrix
        # below makes stiff: full steps, the residual growing a few per cent a step)
        stalled = mu == mu_prev and kkt >= 0.9 * kkt_prev
        mu_prev = mu
        kkt_prev = kkt
        it += 1
        _rhs_to_band(grad, bidx, nb, rb, rt)
        shift = kreg
        ok = _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rb, rt, ob, ot)
        modified = not ok
        if ok:
            n_neg = 0
            n_stall = 0
            if check_gauge and prm[P_GAUGE] > 0.0 and prm[P_GPROX] == GAUGE_AT_REST:
                check_gauge = False
                # tested after each decrease of mu: the saddle shows as soon as the barrier
                # problem has it. Off it, the gauge is proximal (it damps the turn without
                # holding it) and the barrier goes back to the first mu: the turn moves contacts
                if _leave_saddle(x, n, prm, bidx, kinds, fj, fidx, mcount, shift, work):
                    mu, shrink = _restart_barrier(mu, mu0, shrink, lam, g, mcount, False)
                    have_acc = False
                    alpha = -1.0
                    continue
        else:
            if mu < 1e-7 * fscale:
                n_neg += 1
                if n_neg >= 6:
                    # negative curvature at a nearly converged barrier problem: a saddle that
                    # descent from a symmetric start cannot leave. Step along its unstable mode
                    # (twice at most), then the barrier restarts as after the gauge's turn;
                    # failing that, the caller perturbs and retries
                    if curvature_steps < MAX_CURVATURE_STEPS and _negative_curvature_step(
                            x, n, prm, bidx, kinds, fj, fidx, mcount, g, kreg, ab, bb, dd, lb,
                            ybuf, rb, ob, rt, ot, grad, step, xt, gt):
                        curvature_steps += 1
                        n_neg = 0
                        # the gaps changed: the multipliers are lifted even where mu stays
                        mu, shrink = _restart_barrier(mu, mu0, shrink, lam, g, mcount, True)
                        have_acc = False
                        alpha = -1.0
                        continue
                    work_it[0] += it
                    return SADDLE, it
            n_stall = n_stall + 1 if stalled else 0
            if n_stall >= STALL_STEPS:
                # descent on the modified matrix stalls: it makes a soft mode stiff, and the
                # iterate crawls down it (full steps, the residual growing a few per cent a
                # step). The exact matrix shifted just past its most negative curvature takes
                # the long step along that mode (the line search and the step caps bound it)
                hi = _smallest_pd_shift(ab, bb, dd, lb, ybuf, nbb, kreg, rb, rt, ob, ot)
                if hi > 0.0:
                    shift = 2.0 * hi
                    ok = _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rb, rt, ob, ot)
            if not ok:
                shift = kreg
                _drop_curvature(x, n, prm, bidx, kinds, fj, mcount, cd, ch, hess5, dofs, ab,
                                bb, dd)
                ok = _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rb, rt, ob, ot)
        if not ok:
            shift = max(shift_last / 3.0, 1e-8 * max(prm[P_KC], prm[P_KR]))
            while not ok:
                ok = _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rb, rt, ob, ot)
                if ok:
                    break
                shift *= 8.0
                if shift > 1e12 * max(prm[P_KC], 1.0):
                    work_it[0] += it
                    return LINALG_FAIL, it
            shift_last = shift
        slope = _step_from_band(ob, ot, bidx, nb, grad, step)
        # damp huge finger rotations (a full step can jump a finger past a vertex)
        alpha = 1.0
        lim = _step_excess(step, nb)
        if lim > 1.0:
            alpha = 1.0 / lim
        if not have_acc:
            e_acc, l_acc = _merit(x, n, prm, kinds, fj, fidx, mcount, gt)
            have_acc = True
        # the merit at x from its parts (kept from the step that reached x; mu may have moved)
        phi0 = e_acc - mu * l_acc
        accepted = False
        walled = False
        soc = False
        for _ls in range(60):
            for d in range(nx):
                xt[d] = x[d] + alpha * step[d]
            # the round-off allowance is relative to the merit's value: it assumes every
            # energy term is evaluated to round-off relative to itself (no cancellation of
            # large parts, envs.model.energy.cst_energy); on a contact-free answer the merit
            # is nearly zero and so is the allowance
            bound = phi0 + 1e-4 * alpha * slope + 1e-15 * abs(phi0)
            accepted, wall, e_t, l_t = _trial(x, xt, n, prm, kinds, fj, fidx, mcount, g, gt,
                                              shrink, mu, bound)
            walled = walled or wall
            if accepted or wall or _ls > 0:
                if accepted:
                    e_acc = e_t
                    l_acc = l_t
                    break
                alpha *= 0.5
                continue
            # the first trial failed: its gaps tell how far the step may go
            _all_gaps(xt, n, prm, kinds[:mcount], fj, fidx, gf)
            if alpha == 1.0 and MAX_SOC > 0:
                # the full step left the linearization of the gaps and of lam g = mu (right after
                # a cut of mu, a point whose contact force must grow is predicted through the
                # finger): correct it with the same factor before backtracking
                if _second_order(x, xt, step, n, prm, bidx, kinds, fj, fidx, mcount, g, gf,
                                 lam, sig, mu, cg, cd, qs, corr, lb, bb, dd, ybuf, shift, rb,
                                 rt, ob, ot):
                    accepted, wall, e_t, l_t = _trial(x, xt, n, prm, kinds, fj, fidx, mcount,
                                                      g, gt, shrink, mu, bound)
                    walled = walled or wall
                    soc = accepted
            if accepted:
                e_acc = e_t
                l_acc = l_t
                break
            alpha *= _gap_limited(g, gf, mcount)
        if soc:
            for d in range(nx):
                step[d] += corr[d]
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
            nd = constraint_dofs(kinds[m])
            dl = 0.0
            for a in range(nd):
                dl += cg[m, a] * step[cd[m, a]]
            if soc:
                dl += qs[m]  # the corrected step's gap change beyond its linear part
            dlam[m] = mu / g[m] - lam[m] - sig[m] * dl
            if dlam[m] < 0.0:
                alpha_d = min(alpha_d, -0.99 * lam[m] / dlam[m])
        for m in range(mcount):
            lam_new = lam[m] + alpha_d * dlam[m]
            gm = gt[m]
            lam[m] = min(max(lam_new, mu / (1e10 * gm)), 1e10 * mu / gm)
        if opts.shape[0] > N_OPTIONS:
            print("ipm", it, mu / fscale, kkt / fscale, alpha, shift, modified, soc, mcount)
        for d in range(nx):
            x[d] = xt[d]
        for m in range(mcount):
            g[m] = gt[m]  # the gaps at the accepted point, from its merit evaluation
    work_it[0] += it
    return ITER_LIMIT, it
