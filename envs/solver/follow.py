"""A grasp solved from a neighbour's answer on the neighbour's contact set: the fast path of a
scenario batch.

Why: the scenarios of one design (the object displaced by a few millimetres, a slightly larger
or stiffer object) end within a few percent of each other's answers, mostly on the same contact
set. The interior point cannot profit from that (its barrier starts over wherever it starts:
a warm start saved few of its iterations), but the active-set polish
(:func:`envs.solver.polish._polish_set`) solves the equilibrium on a known contact set directly,
a few Newton steps from a near start, and corrects the set where a contact comes out pulling or
a considered point comes out penetrating.

The answer is only a proposal: :func:`follow_one` reports a status other than ``OK``, or an
unstable answer, whenever the polish fails (or is not tried: a neighbour pressed by a bar corner,
:func:`_corner_pressed`), a point outside the neighbour's candidate sets
reaches a finger, or a final guard of :func:`envs.solver.driver._finish` fails (penetration,
stationarity, fold); the caller (:func:`envs.solver.pipeline.solve_columns`) then checks every
answer independently and solves each row the fast path did not settle from rest, as if it had
never been tried.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model.layout import (
    GAUGE_HELD,
    I_ITERATIONS,
    I_ROUNDS,
    I_STABLE,
    I_STATUS,
    KIND_CORNER,
    KIND_FACE,
    KIND_STOP,
    N_CORNERS,
    O_POLISH,
    O_POLISH_STEPS,
    P_GAUGE,
    P_GMAX,
    P_GPROX,
    P_HW,
    P_KAPPA,
    P_LMAX,
    P_POLICY,
    P_RHO,
    P_RINGS,
    P_TAU,
    P_TH0,
    P_THMIN,
)
from ..model.rings import kernel_copy, mesh_band_index
from ..parallel import run_rows
from .candidates import _grow_candidates
from .contact import (
    _all_gaps,
    _build_constraints,
    _corner_on_edge,
    _finger_coords,
    _grooved,
    _sel,
    _trig,
)
from .driver import _finish
from .polish import _polish_set
from .status import CONTACT_CYCLE, OK

__all__ = ["follow_one", "follow_rows", "follow_batch"]


@njit(cache=True, error_model="numpy", _nrt=False)
def _known_multipliers(kinds, fj, fidx, mcount, n, lam_face, lam_corner, lam_stop, lam,
                       active):
    """The neighbour's multipliers on the constraint list (layout of
    :func:`envs.solver.contact._build_constraints`); a constraint is active where it carries
    a force."""
    for m in range(mcount):
        if kinds[m] == KIND_FACE:
            lam[m] = lam_face[fj[m], fidx[m]]
        elif kinds[m] == KIND_CORNER:
            c = fidx[m] // n
            lam[m] = lam_corner[fj[m], c, fidx[m] - c * n]
        else:
            lam[m] = lam_stop[fj[m]]
        active[m] = lam[m] > 0.0


FOLLOW_POLISH_STEPS = 10.0  # Newton steps of one polish on the fast path (the solver's: 40)
# chord steps (polish.CHORD_RATE) only once a full step has shrunk the residual a thousandfold:
# with Newton's multipliers (polish._newton_multipliers) the full steps converge quadratically
# (e.g. 6.6e9, 1.4e7, 1.2e2 times the tolerance), and a chord step contracts only by about the
# size of the last full step
FOLLOW_CHORD_RATE = 1e-3
SEAT_SECANTS = 2  # secant steps on each finger's angle when seating it on its contacts
SEAT_OPENING = 1e-3  # first opening step of a finger that starts inside its contacts [rad]
SEAT_STEP = 1e-6  # finger-angle step of the secant's slope [rad]
# the fast path's polish considers only the constraints within this gap of the seated start [r]
# (and every contact): the neighbour's candidate sets reach one radius from the fingers, and a
# few millimetres of displacement (2 mm is 0.03 r of the paper's disk) move a contact patch's
# ends far less. A left-out point that the answer reaches makes the answer a failure
# (_grow_candidates), solved from rest. Measured on 956 followers of 128 random designs under
# +-2 mm placements: 5 % of the fast path's time, the same rows settled
FOLLOW_NEAR = 0.1


@njit(cache=True, error_model="numpy", _nrt=False)
def _finger_gaps(x, n, prm, kinds, fj, fidx, mcount, active, gbuf, j):
    """The mean gap of finger ``j``'s active contacts, their count, and the smallest gap of
    any of its contact constraints (the joint stops left out)."""
    _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, gbuf)
    total, count, lowest = 0.0, 0, math.inf
    for m in range(mcount):
        if fj[m] == j and kinds[m] != KIND_STOP:
            lowest = min(lowest, gbuf[m])
            if active[m]:
                total += gbuf[m]
                count += 1
    return total / max(count, 1), count, lowest


@njit(cache=True, error_model="numpy", _nrt=False)
def _seat_fingers(x, n, prm, kinds, fj, fidx, mcount, active, gbuf):
    """Turn each finger so that its active contacts' gaps average zero.

    Why: the neighbour's fingers meet this scene's object elsewhere (a displaced object: by
    the displacement); a finger pressed deeper than its corner rounding ``rho`` into the
    contour has a flat gap there (no gradient), and the polish cannot start from it. Each
    finger is first opened until no constraint of it is violated, then closed by secant
    steps on the mean gap of its active contacts.
    """
    nb = 2 * n
    for j in range(2):
        opening = SEAT_OPENING
        mean, count, lowest = _finger_gaps(x, n, prm, kinds, fj, fidx, mcount, active, gbuf, j)
        for _ in range(30):
            if lowest >= 0.0 or count == 0:
                break
            x[nb + j] = min(x[nb + j] + opening, prm[P_TH0])
            opening *= 2.0
            mean, count, lowest = _finger_gaps(x, n, prm, kinds, fj, fidx, mcount, active,
                                               gbuf, j)
        for _ in range(SEAT_SECANTS if count > 0 else 0):
            x[nb + j] += SEAT_STEP
            moved, count, lowest = _finger_gaps(x, n, prm, kinds, fj, fidx, mcount, active,
                                                gbuf, j)
            x[nb + j] -= SEAT_STEP
            slope = (moved - mean) / SEAT_STEP
            if not slope > 0.0:
                break
            x[nb + j] -= mean / slope
            mean, count, lowest = _finger_gaps(x, n, prm, kinds, fj, fidx, mcount, active,
                                               gbuf, j)


@njit(cache=True, error_model="numpy", _nrt=False)
def _place_on_contacts(x, n, prm, kinds, fj, fidx, mcount, active):
    """Move the contour points of each active contact onto its finger: a point pressed by a
    straight face (and any point inside one) onto the face along its normal, the edge under
    a pressing corner onto the corner's rounding (both its points along the normal).

    Why: seated at a mean gap of zero, a finger at another angle than the neighbour's still
    leaves the ends of a long contact patch inside it (beyond the rounding: no gradient) or
    off it; on its finger the patch starts the polish from the contact set's own geometry.
    A grooved jaw's face is left as it is (its gap has no closed-form foot point).
    """
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(mcount):
        j = fj[m]
        if kinds[m] == KIND_CORNER and active[m]:
            kx, ky, k, k1, ex, ey, t = _corner_on_edge(q, fidx[m], j, sn, cs, prm)
            t = min(1.0, max(0.0, t))
            wx, wy = kx - q[k, 0] - t * ex, ky - q[k, 1] - t * ey
            dist = math.sqrt(wx * wx + wy * wy)
            if dist > 0.0:
                shift = (dist - prm[P_RHO]) / dist
                for p in (k, k1):
                    q[p, 0] += shift * wx
                    q[p, 1] += shift * wy
        elif kinds[m] == KIND_FACE and not _grooved(j, prm):
            i = fidx[m]
            _, _, nx, ny, along, depth = _finger_coords(q, i, j, _sel(sn, j), _sel(cs, j), prm)
            if (0.0 <= along <= prm[P_LMAX] and depth > 0.0
                    and (active[m] or depth < prm[P_HW])):
                q[i, 0] += (prm[P_HW] - depth) * nx
                q[i, 1] += (prm[P_HW] - depth) * ny


@njit(cache=True, error_model="numpy", _nrt=False)
def _near_constraints(x, n, prm, kinds, fj, fidx, mcount, active, lam, gbuf, face_cand,
                      corner_cand):
    """Keep the contacts, the joint stops and the constraints within :data:`FOLLOW_NEAR` of
    the start ``x`` (in place, in their order); the others are taken out of the candidate sets
    ``face_cand`` and ``corner_cand`` (the caller's copies). Returns the new count."""
    _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, gbuf)
    keep = 0
    for m in range(mcount):
        if active[m] or kinds[m] == KIND_STOP or gbuf[m] < FOLLOW_NEAR:
            kinds[keep] = kinds[m]
            fj[keep] = fj[m]
            fidx[keep] = fidx[m]
            lam[keep] = lam[m]
            active[keep] = active[m]
            keep += 1
        elif kinds[m] == KIND_FACE:
            face_cand[fj[m], fidx[m]] = False
        else:
            c = fidx[m] // n
            corner_cand[fj[m], c, fidx[m] - c * n] = False
    return keep


@njit(cache=True, error_model="numpy", _nrt=False)
def _corner_pressed(kinds, mcount, active):
    """Whether a rounded corner (a bar's end corner; on a grooved jaw also a mouth edge, but
    grooved designs lead no scenario) carries a force in the neighbour's answer.

    Why the fast path is not tried then: a corner pressing the contour slides over its edges
    when the object is displaced, and the polish from the neighbour's set rarely follows it.
    Of 956 followers of 128 random designs under +-2 mm placements on paper-r070, 80 led by a
    corner contact took 570 of the fast path's 4,405 Newton steps and 59 of them still fell
    back to a solve from rest (21 settled); the other 876 fell back 7 times.
    """
    for m in range(mcount):
        if active[m] and kinds[m] == KIND_CORNER:
            return True
    return False


@njit(cache=True, error_model="numpy")
def follow_one(n, prm_in, opts, x, lam_face, lam_corner, lam_stop, corner_cand, face_cand,
               info):
    """Solve one grasp in place from a neighbour's answer on its contact set.

    Parameters
    ----------
    n, prm_in, opts
        As in :func:`envs.solver.driver.solve_one`.
    x : float64[2 N M + 2]
        In: the neighbour's answer (scaled: points relative to the centre in units of r, then
        the finger angles); out: the answer.
    lam_face, lam_corner, lam_stop
        In: the neighbour's scaled contact forces (face (2, N), corner (2, N_CORNERS, N), joint
        stop (2,)); out: this grasp's.
    corner_cand, face_cand
        The neighbour's candidate sets (bool (2, N_CORNERS, N) and (2, N)); left unchanged.
    info : float64[N_INFO]
        Out: the ``I_*`` slots; ``I_STATUS`` is ``OK`` only for a polished equilibrium that
        passed every guard, ``I_STABLE`` 1.0 for a strict local minimum.
    """
    prm = kernel_copy(prm_in, n)
    # no gauge: the polish of a settled contact set runs without it (driver._release_gauge)
    prm[P_GAUGE] = 0.0
    prm[P_GMAX] = 0.0
    prm[P_POLICY] = 0.0
    prm[P_GPROX] = GAUGE_HELD
    bidx = mesh_band_index(n, int(prm[P_RINGS]))
    mmax = 2 * n * (1 + N_CORNERS) + 2
    kinds = np.zeros(mmax, dtype=np.int64)
    fj = np.zeros(mmax, dtype=np.int64)
    fidx = np.zeros(mmax, dtype=np.int64)
    lam = np.zeros(mmax)
    gbuf = np.zeros(mmax)
    work_it = np.zeros(1, dtype=np.int64)
    stable_out = np.ones(1, dtype=np.bool_)
    fscale = max(prm[P_TAU], prm[P_KAPPA] * abs(prm[P_TH0] - prm[P_THMIN]), 1e-300)
    mcount = _build_constraints(face_cand, corner_cand, n, kinds, fj, fidx)
    active = np.zeros(mcount, dtype=np.bool_)
    _known_multipliers(kinds, fj, fidx, mcount, n, lam_face, lam_corner, lam_stop, lam, active)
    tried = opts[O_POLISH] > 0.0 and not _corner_pressed(kinds, mcount, active)
    near_face, near_corner = face_cand.copy(), corner_cand.copy()
    if tried:
        # the neighbour's answer placed against this scene's fingers
        _seat_fingers(x, n, prm, kinds, fj, fidx, mcount, active, gbuf)
        _place_on_contacts(x, n, prm, kinds, fj, fidx, mcount, active)
        mcount = _near_constraints(x, n, prm, kinds, fj, fidx, mcount, active, lam, gbuf,
                                   near_face, near_corner)
    x0 = x.copy()
    # without the polish (an option) there is no fast path: the caller solves from rest. A
    # polish from a good start takes 3 to 5 steps; one that has not converged in 10 rarely does
    # (its fallback, a solve from rest, is what the steps beyond would cost)
    status = CONTACT_CYCLE
    fast = opts.copy()
    fast[O_POLISH_STEPS] = min(opts[O_POLISH_STEPS], FOLLOW_POLISH_STEPS)
    if tried:
        # Newton's multipliers and chord steps; each correction of the set goes on from the
        # last polished point
        status = _polish_set(x, lam, n, prm, fast, bidx, kinds, fj, fidx, mcount, fscale,
                             active, work_it, gbuf, stable_out, FOLLOW_CHORD_RATE, n > 0, n > 0)
    # a point or corner edge the neighbour's sets left out now touches a finger: the set is
    # not this grasp's (commit=False as a runtime value: one compiled specialization)
    if status == OK and _grow_candidates(x, x0, n, prm, near_face, near_corner, n < 0, n < 0):
        status = CONTACT_CYCLE
    _finish(x, n, prm, kinds, fj, fidx, mcount, lam, gbuf, fscale, status, lam_face,
            lam_corner, lam_stop, info)
    # _finish turns a failed polish into OK where the start itself is an equilibrium; the
    # fast path claims only what it polished
    if status != OK:
        info[I_STATUS] = status
    info[I_ITERATIONS] = work_it[0]
    info[I_ROUNDS] = 1
    info[I_STABLE] = 1.0 if stable_out[0] else 0.0


@njit(cache=True, error_model="numpy", nogil=True)
def follow_rows(start, stop, n, prms, opts, xs, lam_face, lam_corner, lam_stop, corner_cand,
                face_cand, infos):
    """:func:`follow_one` over the rows ``start <= b < stop`` of a batch (first axis)."""
    for b in range(start, stop):
        follow_one(n, prms[b], opts, xs[b], lam_face[b], lam_corner[b], lam_stop[b],
                   corner_cand[b], face_cand[b], infos[b])


def follow_batch(n, prms, opts, xs, lam_face, lam_corner, lam_stop, corner_cand, face_cand,
                 infos):
    """:func:`follow_one` over a batch (first axis), on :func:`envs.parallel.run_rows`'s
    threads."""
    run_rows(follow_rows, prms.shape[0], n, prms, opts, xs, lam_face, lam_corner, lam_stop,
             corner_cand, face_cand, infos)
