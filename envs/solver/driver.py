"""Driver of the compiled solve: contact policies, outer rounds over the candidate sets, the
rotation gauge, saddle escapes, the final guards; one grasp (solve_one) or a range of a batch's
rows without the GIL (solve_rows; :func:`solve_batch` runs them on threads).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model.energy import folded_triangles
from ..model.layout import (
    GAUGE_AT_REST,
    GAUGE_HELD,
    I_CONTACT_GAP,
    I_INVERTED,
    I_ITERATIONS,
    I_MIN_GAP,
    I_ROUNDS,
    I_STABLE,
    I_STATIONARITY,
    I_STATUS,
    KIND_CORNER,
    KIND_FACE,
    N_CORNERS,
    O_GAUGE,
    O_MAXIT,
    O_MAXROUND,
    O_MU0,
    O_POLISH,
    O_TOL,
    P_GAUGE,
    P_GMAX,
    P_GPROX,
    P_KAPPA,
    P_KC,
    P_KR,
    P_POLICY,
    P_RINGS,
    P_TAU,
    P_TH0,
    P_THMIN,
)
from ..model.rings import kernel_copy, mesh_band_index
from ..parallel import run_rows
from .assembly import (
    _gauge_force,
    _stationarity,
)
from .candidates import (
    CORNER_SWEEP,
    _grow_candidates,
    _initial_candidates,
)
from .contact import (
    _all_gaps,
    _build_constraints,
    _crossed_through,
    _face_gap,
    _grooved,
    _sel,
    _trig,
)
from .ipm import (
    _ipm,
)
from .polish import (
    FULL_STEPS,
    _polish_set,
)
from .start import (
    _close_to_contact,
)
from .status import (
    BLOCKED,
    CONTACT_CYCLE,
    INFEASIBLE_START,
    INVERTED,
    ITER_LIMIT,
    OK,
    PENETRATION,
    POLISH_FAIL,
    SADDLE,
)

FAST_BUDGET = 1.0 / 3.0  # iteration limit of the fast attempt, as a fraction of the option's
ESCAPE_OPENING = 0.01  # first opening step of the fingers when leaving a saddle or a stall [scaled]


@njit(cache=True, error_model="numpy", _nrt=False)
def _copy_into(dst, src, count):
    """The first ``count`` elements of ``src`` into ``dst`` (C-contiguous, in flat order).

    Element by element rather than ``dst[:] = src``: numba compiles a slice assignment's shape
    check with an error message that formats both shapes, a few seconds of the cold start for
    each number of dimensions (``scripts/compile_profile.py``).
    """
    flat_dst = dst.reshape(dst.size)
    flat_src = src.reshape(src.size)
    for i in range(count):
        flat_dst[i] = flat_src[i]


@njit(cache=True, error_model="numpy", _nrt=False)
def _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, attempt, gbuf, opening):
    """New start point near a saddle: rotate the contour about the pin, open the fingers."""
    nb = 2 * n
    angle = (0.25 if attempt % 2 == 1 else -0.25) * attempt * 2.0 * math.pi / n
    c = math.cos(angle)
    s = math.sin(angle)
    for i in range(n):
        qx, qy = xs[2 * i], xs[2 * i + 1]
        x0[2 * i] = c * qx - s * qy
        x0[2 * i + 1] = s * qx + c * qy
    # a ring mesh's interior points turn with the contour (only its hub stays)
    for d in range(nb + 2, xs.shape[0], 2):
        qx, qy = xs[d], xs[d + 1]
        x0[d] = c * qx - s * qy
        x0[d + 1] = s * qx + c * qy
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


@njit(cache=True, error_model="numpy", inline="always")
def solve_one(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand, face_cand, info):
    """Solve one grasp in place: a fast attempt, then the plain ones as a fallback.

    Contact policy 0: corner-edge constraints for the edges near the arc each corner sweeps as
    its finger closes. Policy 1: every contour edge for the tip corners. In both, line-search
    steps that would carry a corner or a point right through the contour or a finger are
    refused (the gaps are distances, positive again on the far side).

    The fast attempt (policy 0, a third of the iteration limit) closes the fingers of the
    start to just short of the first contact (:mod:`envs.solver.start`) and leaves a saddle
    held up by the gauge as soon as the interior point meets it (:mod:`envs.solver.gauge`).
    Unless it ends on a stable equilibrium, the plain attempts run from the given start as the
    solver did before those two steps: policy 0, then policy 1 unless policy 0 converged or
    ended on an inverted fan (a property of the model). So no grasp the plain sequence solves
    is lost.

    Which answer is kept (the arbitration): the model's grasp is the stable equilibrium
    reached by ramping the torque from 0, but a direct solve at one torque cannot tell which
    of several stable equilibria the ramp would follow; the fast attempt's turn off a saddle
    may end in another one than the plain sequence's escape (mirror images of equal energy
    for a symmetric scene, and a few of lower or higher energy; a torque ramp reaches the
    fast answer for some of the higher-energy ones and the plain answer for others). Hence:
    a stable converged fast answer is kept without running the plain sequence (running it to
    compare energies would cost the whole gain); a converged but unstable fast answer (a
    saddle its escapes could not leave, rare) is replaced by the plain answer if that is
    converged and stable, and kept otherwise; a fast attempt that did not converge, or ended
    on an inverted fan, gives way to the plain answer whatever it is (the solver's answer
    before the fast attempt existed).

    Arguments as in :func:`_solve_attempt`; ``info[I_ITERATIONS]`` counts the iterations of
    every attempt.
    """
    x_in = x.copy()
    lam_in = lam_face.copy()
    fast = opts.copy()
    fast[O_MAXIT] = opts[O_MAXIT] * FAST_BUDGET
    total = 0.0
    keep_fast = False
    # attempt 0 is the fast one, 1 and 2 the plain ones with contact policies 0 and 1: one call
    # site, so that _solve_attempt compiles into this function once (envs.solver.warmup)
    for attempt in range(3):
        if attempt > 0:
            _copy_into(x, x_in, x.size)
            _copy_into(lam_face, lam_in, lam_face.size)
        # flags as runtime values (n < 0 is False, n > 0 True): a literal True/False would
        # compile _solve_attempt and its callees once per value (assembly._spring_terms)
        _solve_attempt(n, prm_in, fast if attempt == 0 else opts, x, lam_face, lam_corner,
                       lam_stop, corner_cand, face_cand, info, float(max(attempt - 1, 0)),
                       n < 0 if attempt == 0 else n > 0)
        total += info[I_ITERATIONS]
        if attempt == 0:
            if info[I_STATUS] == OK and info[I_STABLE] == 1.0:
                return
            keep_fast = info[I_STATUS] == OK
            if keep_fast:
                kept = (x.copy(), lam_face.copy(), lam_corner.copy(), lam_stop.copy(),
                        corner_cand.copy(), face_cand.copy(), info.copy())
        elif info[I_STATUS] == OK or info[I_STATUS] == INVERTED:
            break
    if keep_fast and not (info[I_STATUS] == OK and info[I_STABLE] == 1.0):
        _copy_into(x, kept[0], x.size)
        _copy_into(lam_face, kept[1], lam_face.size)
        _copy_into(lam_corner, kept[2], lam_corner.size)
        _copy_into(lam_stop, kept[3], lam_stop.size)
        _copy_into(corner_cand, kept[4], corner_cand.size)
        _copy_into(face_cand, kept[5], face_cand.size)
        _copy_into(info, kept[6], info.size)
    info[I_ITERATIONS] = total


@njit(cache=True, error_model="numpy", _nrt=False)
def _start_round(xs, n, prm, opts, kinds, fj, fidx, mcount, fscale, lam_guess_face, lam, gbuf):
    """Initial barrier parameter and multipliers of a round at the start point ``xs``.

    Warm-start face multipliers (when given) set the barrier parameter from their
    complementarity; otherwise a force scale does. Returns ``(mu0, feasible)``: the start must
    be strictly inside every considered constraint.
    """
    _all_gaps(xs, n, prm, kinds[:mcount], fj, fidx, gbuf)
    mu0 = abs(opts[O_MU0]) * fscale * 0.05
    have_warm = False
    acc = 0.0
    cnt = 0
    for m in range(mcount):
        if kinds[m] == KIND_FACE and lam_guess_face[fj[m], fidx[m]] > 0.0:
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
        if kinds[m] == KIND_FACE and lam_guess_face[fj[m], fidx[m]] > 0.0:
            lam[m] = lam_guess_face[fj[m], fidx[m]]
    return mu0, feasible


@njit(cache=True, error_model="numpy", inline="always")
def _release_gauge(xs, x0, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                   work_it, gbuf, stable_out, skipped_polish):
    """Release the rotation gauge and polish the contact set without it.

    Returns ``(status, stable, changed)``: a failed polish restores the state and asks for
    another round from an escape start (``changed``), or fails when no such start exists.
    """
    prm[P_GAUGE] = 0.0
    if not skipped_polish:
        for m in range(mcount):
            active[m] = lam[m] > 0.0
    xkeep = xs.copy()
    lkeep = lam.copy()
    # full steps, from the start each correction, the augmented Lagrangian's multipliers
    # (runtime values: one compilation)
    good = _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount,
                       fscale, active, work_it, gbuf, stable_out, FULL_STEPS, n < 0,
                       n < 0) == OK
    stable = stable_out[0]
    if good:
        return OK, stable, False
    for d in range(xs.shape[0]):
        xs[d] = xkeep[d]
    for m in range(mcount):
        lam[m] = lkeep[m]
    if not _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, n - n, gbuf, ESCAPE_OPENING):
        return POLISH_FAIL, stable, True
    return OK, stable, True


@njit(cache=True, error_model="numpy")
def _finish(xs, n, prm, kinds, fj, fidx, mcount, lam, gbuf, fscale, status, lam_face,
            lam_corner, lam_stop, info):
    """Forces, final guards and the status of a finished attempt, written to the outputs.

    The guards: a penetration of any point or corner (candidate or not), a stationarity
    residual short of the required accuracy (after a failed polish), and a fold.
    """
    nb = 2 * n
    lam_face[:, :] = 0.0
    lam_corner[:, :, :] = 0.0
    lam_stop[:] = 0.0
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
        if kinds[m] == KIND_FACE:
            lam_face[fj[m], fidx[m]] = lam[m]
        elif kinds[m] == KIND_CORNER:
            c = fidx[m] // n
            lam_corner[fj[m], c, fidx[m] - c * n] = lam[m]
        else:
            lam_stop[fj[m]] = lam[m]
    res = np.zeros(xs.shape[0])
    grad5 = np.zeros(5)
    hess5 = np.zeros((5, 5))
    dofs = np.zeros(5, dtype=np.int64)
    kkt = _stationarity(xs, n, prm, kinds, fj, fidx, mcount, lam, gbuf, grad5, hess5, dofs,
                        res)
    # a triangle turned over: springs alone allow this fold at finite energy, the material
    # does not; the answer is an equilibrium of the model but not a grasp (with the area
    # energy it cannot happen)
    inverted = folded_triangles(xs, n, prm)
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
    info[I_STATUS] = status
    info[I_STATIONARITY] = kkt / fscale
    info[I_CONTACT_GAP] = gact
    info[I_MIN_GAP] = gmin
    info[I_INVERTED] = inverted


@njit(cache=True, error_model="numpy", _nrt=False)
def _keep_face_guess(lam, kinds, fj, fidx, mcount, lam_guess_face):
    """Keep the face multipliers of a round as the next round's warm start."""
    for m in range(mcount):
        if kinds[m] == KIND_FACE:
            lam_guess_face[fj[m], fidx[m]] = lam[m]


@njit(cache=True, error_model="numpy", inline="always")
def _solve_attempt(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand, face_cand,
                   info, policy, plain):
    """Solve one grasp in place.

    Parameters
    ----------
    n : int
        Number of triangles.
    prm_in : float64[N_PARAMS]
        Scaled problem parameters (``P_*`` slots of :mod:`envs.model.layout`).
    opts : float64[N_OPTIONS]
        Options (:func:`envs.model.layout.default_options`).
    policy : float
        Contact policy of this attempt (see :func:`solve_one`).
    x : float64[2n + 2]
        In: start point (contour points relative to the centre in units of r, then the finger
        angles); must be strictly feasible. Out: the solution.
    lam_face : float64[2, n]
        In: multipliers of the previous solution (warm start) or zeros; out: scaled face contact
        forces.
    lam_corner : float64[2, N_CORNERS, n]
        Out: scaled force of each corner (finger; face tip, face root, back tip, back root) on
        each contour edge k -> k+1.
    lam_stop : float64[2]
        Out: scaled joint-stop torques.
    corner_cand : bool[2, N_CORNERS, n]
        Work/out: corner-edge constraints considered.
    face_cand : bool[2, n]
        Work/out: face constraints considered.
    info : float64[N_INFO]
        Out: the ``I_*`` slots of :mod:`envs.model.layout`.
    plain : bool
        Start from ``x`` as given, the gauge held at rest until released (no saddle test); else
        the fast attempt's start and gauge (see :func:`solve_one`).
    """
    prm = kernel_copy(prm_in, n)
    # the gauge spring holds the nearly free turn of the polygon about its pin while the
    # contacts form (released once the contact set settles, or made proximal once it is found
    # holding up a saddle). Fine fans need it most: without it the interior-point iterates
    # swung the polygon to and fro at N = 500 and ran into the iteration limit at nearly every
    # torque of the paper sweep. A ring mesh's hub holds the turn itself
    if prm[P_RINGS] == 1:
        prm[P_GAUGE] = opts[O_GAUGE] * max(prm[P_KC], prm[P_KR])
    prm[P_GMAX] = prm[P_GAUGE]
    prm[P_POLICY] = policy
    bidx = mesh_band_index(n, int(prm[P_RINGS]))
    if plain:
        prm[P_GPROX] = GAUGE_HELD
    else:
        prm[P_GPROX] = GAUGE_AT_REST
        # fingers closed freely up to just short of the first contact (from rest, a third of
        # the Newton iterations closed them at the line search's limit of 0.05 rad a step)
        _close_to_contact(x, n, prm)
    x0 = x.copy()
    mmax = 2 * n * (1 + N_CORNERS) + 2  # every point on each finger, every corner-edge pair
    kinds = np.zeros(mmax, dtype=np.int64)
    fj = np.zeros(mmax, dtype=np.int64)
    fidx = np.zeros(mmax, dtype=np.int64)
    lam = np.zeros(mmax)
    gbuf = np.zeros(mmax)
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
        for d in range(xs.shape[0]):
            xs[d] = x0[d]
        mu0, feasible = _start_round(xs, n, prm, opts, kinds, fj, fidx, mcount, fscale,
                                     lam_guess_face, lam, gbuf)
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
        _copy_into(last_kinds, kinds, mcount)
        _copy_into(last_fj, fj, mcount)
        _copy_into(last_fidx, fidx, mcount)
        if status == SADDLE and escapes < 3:
            escapes += 1
            if _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, escapes, gbuf, ESCAPE_OPENING):
                _keep_face_guess(lam, kinds, fj, fidx, mcount, lam_guess_face)
                continue
        if status == SADDLE:
            # escapes exhausted: polish where we are; the answer is reported as not stable
            status = OK
            saddle = True
        rescue = (status == ITER_LIMIT and opts[O_POLISH] > 0.0
                  and (_grooved(0, prm) or _grooved(1, prm)))
        if rescue:
            # a grooved jaw's interior point can wander about a touch that two constraints
            # describe (a contour point at a groove's mouth edge, see
            # polish._one_constraint_per_touch) without closing on it: polish the contact set
            # it ended near, which keeps one of the two; the iteration limit stands unless
            # that polish reaches an equilibrium
            status = OK
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
                                                     blocked, n < 0)
        if opts[O_POLISH] > 0.0 and not blocked and not skip_gauge_polish:
            status = _polish_set(xs, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount,
                                 fscale, active, work_it, gbuf, stable_out, FULL_STEPS, n < 0,
                                 n < 0)
            stable = stable_out[0]
        if rescue and status != OK:
            status = ITER_LIMIT
            break
        # check the candidate set against the solution
        changed = False
        if not skip_gauge_polish:
            changed = _grow_candidates(xs, x0, n, prm, face_cand, corner_cand, blocked, n > 0)
        if status == POLISH_FAIL or (blocked and not changed):
            # keep the interior-point answer; the caller reports the reason
            break
        if not changed and prm[P_GAUGE] > 0.0:
            # release the rotation gauge: Newton on the contact set without it (its reaction is
            # zero for a mirror-symmetric answer, small otherwise)
            rel_status, stable, changed = _release_gauge(
                xs, x0, lam, n, prm, opts, bidx, kinds, fj, fidx, mcount, fscale, active,
                work_it, gbuf, stable_out, skip_gauge_polish)
            if rel_status != OK:
                status = ITER_LIMIT if rescue else rel_status
                break
        if not changed and not stable and escapes < 3:
            # converged to a saddle (e.g. a symmetric squeeze past a bifurcation): perturb
            escapes += 1
            if _escape(xs, x0, n, prm, kinds, fj, fidx, mcount, escapes, gbuf, ESCAPE_OPENING):
                _keep_face_guess(lam, kinds, fj, fidx, mcount, lam_guess_face)
                continue
        if not changed:
            break
        # warm start the next round from this round's answer (fingers opened slightly so that
        # the new candidate set is strictly feasible) and its multipliers
        _keep_face_guess(lam, kinds, fj, fidx, mcount, lam_guess_face)
        mnew = _build_constraints(face_cand, corner_cand, n, kinds, fj, fidx)
        xprev = x0.copy()
        if not _escape(xs, x0, n, prm, kinds, fj, fidx, mnew, n - n, gbuf, 1e-4):
            for d in range(x0.shape[0]):
                x0[d] = xprev[d]
        if rnd >= int(opts[O_MAXROUND]) + escapes - 1:
            status = CONTACT_CYCLE
            break
    # outputs, on the constraint list the last solve used (the loop may have changed the
    # candidate sets after it)
    for d in range(x.shape[0]):
        x[d] = xs[d]
    mcount = last_m
    _copy_into(kinds, last_kinds, mcount)
    _copy_into(fj, last_fj, mcount)
    _copy_into(fidx, last_fidx, mcount)
    _finish(xs, n, prm, kinds, fj, fidx, mcount, lam, gbuf, fscale, status, lam_face,
            lam_corner, lam_stop, info)
    info[I_ITERATIONS] = work_it[0]
    info[I_ROUNDS] = rounds
    info[I_STABLE] = 1.0 if (stable and not saddle) else 0.0


@njit(cache=True, error_model="numpy", nogil=True)
def solve_rows(start, stop, n, prms, opts, xs, lam_face, lam_corner, lam_stop, corner_cand,
               face_cand, infos):
    """:func:`solve_one` over the rows ``start <= b < stop`` of a batch (first axis)."""
    for b in range(start, stop):
        solve_one(n, prms[b], opts, xs[b], lam_face[b], lam_corner[b], lam_stop[b],
                  corner_cand[b], face_cand[b], infos[b])


def solve_batch(n, prms, opts, xs, lam_face, lam_corner, lam_stop, corner_cand, face_cand,
                infos):
    """:func:`solve_one` over a batch (first axis), on :func:`envs.parallel.run_rows`'s
    threads."""
    run_rows(solve_rows, prms.shape[0], n, prms, opts, xs, lam_face, lam_corner, lam_stop,
             corner_cand, face_cand, infos)
