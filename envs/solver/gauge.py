"""The rotation gauge of the fast attempt: a test for a saddle the gauge holds up, the turn off
it, and the proximal gauge that damps the turn without holding it.

Why: for even N at phase pi/2 the start and the scene are mirror images and the gauge spring
holds point 0 at rest, so every interior-point step stays mirror-symmetric and the iterates
converge to the symmetric equilibrium. Once the barrier parameter is small that equilibrium is
unstable for most random designs (the contour would rather turn about the pin); the plain
sequence found it only after the gauge's release and left it by an escape costing a whole
second round. Here the saddle is seen as soon as the barrier problem has it (after a decrease
of mu) and left at once.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.layout import (
    GAUGE_PROXIMAL,
    P_GAUGE,
    P_GMAX,
    P_GPROX,
    P_GREF,
)
from .assembly import (
    _gauge_stretch,
)
from .banded import (
    _solve_factored,
)
from .contact import (
    _all_gaps,
    _tunnels,
)

SADDLE_TURN = 0.25  # a turn off a saddle moves point 0 by this fraction of the point spacing
SADDLE_MARGIN = 1e-6  # a saddle: k t^T W^-1 t above 1 by this (see _gauge_holds_saddle)
TURN_HALVINGS = 8  # a turn is halved at most this many times to keep the gaps


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _gauge_reanchor(x, prm, alpha):
    """Proximal gauge: move the gauge spring's anchor to state ``x`` and adapt its stiffness.

    Like a Levenberg-Marquardt damping of the turn, the stiffness follows the last accepted
    step length ``alpha`` (negative: no step yet): 4x softer after a full step, 4x stiffer (at
    most the starting stiffness ``P_GMAX``) after a step cut below a quarter. It never vanishes,
    so the Newton matrix keeps the turn about the pin regular.

    Returns
    -------
    float
        The spring's energy at ``x`` before the move (the caller's merit at ``x`` loses it).
    """
    _, _, ut = _gauge_stretch(x, prm)
    kg = prm[P_GAUGE]
    e = 0.5 * kg * ut * ut
    prm[P_GREF] += ut
    if alpha == 1.0:
        kg = max(0.25 * kg, 1e-12 * prm[P_GMAX])
    elif 0.0 <= alpha < 0.25:
        kg = min(prm[P_GMAX], 4.0 * max(kg, 1e-6 * prm[P_GMAX]))
    prm[P_GAUGE] = kg
    return e


@njit(cache=True, error_model="numpy", _nrt=False)
def _gauge_holds_saddle(x, n, prm, bidx, bb, dd, lb, ybuf, shift, rb, rt, wb, wt):
    """Does the gauge spring hold up a mode that is unstable without it?

    With W the Newton matrix (gauge included, positive definite with this ``shift``) and t the
    gauge's direction (point 0 along the contour's tangent), ``W - k t t^T`` is not positive
    definite exactly when ``k t^T W^-1 t > 1`` (a rank-one downdate): one more solve with the
    factor ``lb`` of W the caller has just made (with the same ``shift``).

    Returns
    -------
    float
        The ratio ``k t^T W^-1 t`` (0 if W cannot be factored). ``wb``, ``wt`` get
        ``W^-1 t`` (points in band order, then the angles): the response to a tangential push
        on point 0, the shape of the unstable mode. ``rb``, ``rt`` are overwritten.
    """
    nb = lb.shape[0]  # the fan's 2N rows (the gauge holds only the fan)
    tx, ty, _ = _gauge_stretch(x, prm)
    for p in range(nb):
        rb[p] = 0.0
    rb[bidx[0]] = tx
    rb[bidx[0] + 1] = ty
    rt[0] = 0.0
    rt[1] = 0.0
    if not _solve_factored(lb, bb, dd, ybuf, nb, shift, rb, rt, wb, wt):
        return 0.0
    return prm[P_GAUGE] * (tx * wb[bidx[0]] + ty * wb[bidx[0] + 1])


@njit(cache=True, error_model="numpy", _nrt=False)
def _turn_candidate(x, xt, n, prm, bidx, kinds, fj, fidx, mcount, g, gt, wb, wt, c):
    """Trial state ``xt = x + c W^-1 t`` (gaps into ``gt``); is it admissible?

    Admissible: every gap keeps a tenth of its value (the barrier still sees the contacts) and
    nothing tunnels through the contour or a finger.
    """
    nb = 2 * n
    for i in range(n):
        p = bidx[i]
        xt[2 * i] = x[2 * i] + c * wb[p]
        xt[2 * i + 1] = x[2 * i + 1] + c * wb[p + 1]
    xt[nb] = x[nb] + c * wt[0]
    xt[nb + 1] = x[nb + 1] + c * wt[1]
    _all_gaps(xt, n, prm, kinds[:mcount], fj, fidx, gt)
    for m in range(mcount):
        if not gt[m] >= 0.1 * g[m]:
            return False
    return not _tunnels(x, xt, n, prm)


@njit(cache=True, error_model="numpy", _nrt=False)
def _turn_from_saddle(x, xt, n, prm, bidx, kinds, fj, fidx, mcount, g, gt, wb, wt):
    """Step off a saddle the gauge holds up, along its unstable mode (``wb``, ``wt`` from
    :func:`_gauge_holds_saddle`), and make the gauge proximal.

    The step moves point 0 by ``SADDLE_TURN`` of the point spacing along the tangent,
    counter-clockwise first (as the plain sequence's first escape; for a mirror-symmetric
    scene the other sense gives the mirror image), halved until it is admissible
    (:func:`_turn_candidate`). No descent is asked of it: along a straight line the energy
    rises even where it falls along the curved contact surface; the caller raises mu so that
    the interior point takes the contacts along.

    Returns
    -------
    bool
        Whether a step was taken (then ``x`` and the gaps ``g`` are those after it).
    """
    tx, ty, _ = _gauge_stretch(x, prm)
    push = tx * wb[bidx[0]] + ty * wb[bidx[0] + 1]
    if not push > 0.0:
        return False
    for sgn in (1.0, -1.0):
        c = sgn * SADDLE_TURN * 2.0 * math.pi / n / push
        for _k in range(TURN_HALVINGS):
            if _turn_candidate(x, xt, n, prm, bidx, kinds, fj, fidx, mcount, g, gt, wb, wt, c):
                for d in range(2 * n + 2):
                    x[d] = xt[d]
                for m in range(mcount):
                    g[m] = gt[m]
                prm[P_GPROX] = GAUGE_PROXIMAL
                return True
            c *= 0.5
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _leave_saddle(x, n, prm, bidx, kinds, fj, fidx, mcount, shift, work):
    """Test the Newton matrix just built and factored (``work``, an ``IpmWork``) for a saddle
    the gauge holds up and, if there is one, turn off it (:func:`_turn_from_saddle`).

    Returns whether ``x`` was moved (the gauge is then proximal).
    """
    ratio = _gauge_holds_saddle(x, n, prm, bidx, work.bb, work.dd, work.lb, work.ybuf,
                                shift, work.rb, work.rt, work.wb, work.wt)
    if not ratio > 1.0 + SADDLE_MARGIN:
        return False
    return _turn_from_saddle(x, work.xt, n, prm, bidx, kinds, fj, fidx, mcount, work.g,
                             work.gt, work.wb, work.wt)
