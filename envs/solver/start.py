"""Start of the fast attempt: each finger closed freely to just short of its first contact.

Why: from rest the first 5 to 13 interior-point iterations only closed the fingers through
free space, at the line search's limit of 0.05 rad a step. Where the finger first touches the
undeformed contour is exact geometry (a box turning about its joint), so the start is closed
there directly, ``CLOSE_MARGIN`` short of it.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.layout import (
    N_CORNERS,
    P_C0X,
    P_HW,
    P_KAPPA,
    P_LMAX,
    P_RHO,
    P_TAU,
    P_TH0,
    P_THMIN,
)
from .contact import (
    _corner_active,
    _corner_gap,
    _crossed_through_sc,
    _face_gap,
    _sel,
    _trig,
)

CLOSE_MARGIN = 0.02  # a start closed to the first contact stops this short of it [rad]
CLEAR_GAP = 1e-12  # the closed start must keep every gap above this (scaled length)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _wrap(b):
    """Angle ``b`` wrapped into [-pi, pi)."""
    return b - 2.0 * math.pi * math.floor((b + math.pi) / (2.0 * math.pi))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _first_touch(th, psi, r_pt, lo, hw, lmax):
    """Largest finger angle below ``th`` at which a point meets the finger's box.

    The point lies at distance ``r_pt`` from the joint and polar angle ``psi`` (from +y,
    positive away from the axis, as the finger angle); the box is 0 <= s <= lmax, |m| <= hw
    about the joint, turning with the finger. Returns -inf if the point is not met before
    ``lo``, nan if it lies within ``hw`` of the joint (no closed start then).
    """
    if r_pt <= hw:
        return math.nan
    # relative angle b = theta - psi: s = r cos b, m = r sin b; closing lowers b
    b0 = _wrap(th - psi)
    up = math.asin(hw / r_pt)
    hit = -math.inf
    if r_pt <= lmax:
        if b0 > up:
            hit = psi + up  # the gripping face (or the joint end) meets it
    elif r_pt * r_pt <= lmax * lmax + hw * hw:
        # beyond the finger's length along its axis: only the two corners of its tip end reach
        tip = math.acos(lmax / r_pt)
        if b0 > up:
            hit = psi + up
        elif -tip < b0 < tip:
            hit = psi - tip
    if hit < lo:
        return -math.inf
    return hit


@njit(cache=True, error_model="numpy", _nrt=False)
def _points_touch(q, n, th, sgn, jx, jy, lo, hw, lmax):
    """First touch (:func:`_first_touch`) over the contour points ``q`` for a finger at angle
    ``th`` with its joint at (jx, jy) (``sgn`` mirrors polar angles for the left finger)."""
    hit = -math.inf
    for i in range(n):
        vx = q[i, 0] - jx
        vy = q[i, 1] - jy
        t = _first_touch(th, math.atan2(sgn * vx, vy), math.sqrt(vx * vx + vy * vy), lo, hw,
                         lmax)
        if math.isnan(t):
            return math.nan
        hit = max(hit, t)
    return hit


@njit(cache=True, error_model="numpy", _nrt=False)
def _tip_touch(q, n, th, sgn, jx, jy, hw, lmax):
    """Largest finger angle below ``th`` at which a corner of the box's tip end (polar angles
    ``th -+ atan(hw / lmax)`` at distance ``sqrt(lmax^2 + hw^2)``) meets a contour edge."""
    rk = math.sqrt(lmax * lmax + hw * hw)
    bk = math.atan2(hw, lmax)
    hit = -math.inf
    for k in range(n):
        k1 = k + 1 if k + 1 < n else 0
        ax = q[k, 0] - jx
        ay = q[k, 1] - jy
        dx = q[k1, 0] - q[k, 0]
        dy = q[k1, 1] - q[k, 1]
        # the edge's points a + t d (0 <= t <= 1) at the corners' distance: |a + t d| = rk
        aa = dx * dx + dy * dy
        bb = ax * dx + ay * dy
        disc = bb * bb - aa * (ax * ax + ay * ay - rk * rk)
        if disc < 0.0:
            continue
        sq = math.sqrt(disc)
        for root in (-1.0, 1.0):
            t = (-bb + root * sq) / aa
            if t < 0.0 or t > 1.0:
                continue
            psi = math.atan2(sgn * (ax + t * dx), ay + t * dy)
            for corner in (bk, -bk):
                # the corner sits at polar angle th - corner; it reaches psi at
                # theta = psi + corner, going down from th
                b0 = _wrap(th - corner - psi)
                if b0 > 0.0:
                    hit = max(hit, th - b0)
    return hit


@njit(cache=True, error_model="numpy", _nrt=False)
def _clear_of_finger(x, n, prm, j):
    """Is finger ``j`` of state ``x`` strictly clear of the contour by the solver's own gaps
    (every point and corner gap above ``CLEAR_GAP``, nothing across the finger)?"""
    q = x[:2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    if _crossed_through_sc(x, n, prm, sn, cs):
        return False
    for i in range(n):
        if not _face_gap(q, i, j, _sel(sn, j), _sel(cs, j), prm) > CLEAR_GAP:
            return False
    for c in range(N_CORNERS):
        if not _corner_active(j, c, prm):
            continue
        for k in range(n):
            if not _corner_gap(q, k, j, _sel(sn, j), _sel(cs, j), c, prm) > CLEAR_GAP:
                return False
    return True


@njit(cache=True, error_model="numpy", _nrt=False)
def _close_to_contact(x, n, prm):
    """Close each finger of the start ``x`` freely (the contour left as it is) to
    ``CLOSE_MARGIN`` short of the angle where it would first touch the contour, or to its
    equilibrium without contact if that comes first; a finger already closer is left alone.

    The finger is taken as the box 0 <= s <= l + rho, |m| <= w/2 about its joint (it holds
    the rounded bar, and a grooved finger too: a groove only removes material, so the box is
    met first and the start stays short of the groove's contact): closing, a contour point
    meets the box, or a corner of the box's tip end meets a contour edge. Nothing is changed
    where a contour point lies within w/2 of a joint or the closed start is not strictly clear
    of the finger (:func:`_clear_of_finger`).
    """
    nb = 2 * n
    hw = prm[P_HW]
    lmax = prm[P_LMAX] + prm[P_RHO]
    q = x[:nb].reshape(n, 2)
    free = prm[P_TH0] - prm[P_TAU] / max(prm[P_KAPPA], 1e-300)
    lo = max(free, prm[P_THMIN] + CLOSE_MARGIN)
    for j in range(2):
        th = x[nb + j]
        if not lo < th - CLOSE_MARGIN:
            continue
        sgn = 1.0 if j == 0 else -1.0  # polar angles mirrored for the left finger
        jx = -prm[P_C0X + 2 * j]  # the joint relative to the disk centre
        jy = -prm[P_C0X + 2 * j + 1]
        hit = _points_touch(q, n, th, sgn, jx, jy, lo, hw, lmax)
        if math.isnan(hit):
            continue
        hit = max(hit, _tip_touch(q, n, th, sgn, jx, jy, hw, lmax))
        new = max(lo, hit + CLOSE_MARGIN)
        if new < th:
            x[nb + j] = new
            if not _clear_of_finger(x, n, prm, j):
                x[nb + j] = th
