"""Contact candidate sets: which face and corner constraints a solve considers, at the start and
after each round (constraints the solution reaches that were left out are added).
"""

from __future__ import annotations

import math

from numba import njit

from ..model.layout import (
    N_BAR_CORNERS,
    N_CORNERS,
    P_C0X,
    P_POLICY,
    P_RHO,
    P_THMIN,
)
from .contact import (
    _corner_active,
    _corner_centre,
    _corner_gap,
    _face_gap,
    _inside,
    _seg_dist,
    _sel,
    _trig,
)

CORNER_NEAR = 0.25  # corner-edge constraints for edges this close to a corner's path (units of r)
# point-finger constraints for points this close to a finger at the start [r]: a point farther
# off would need the disk squeezed by a whole radius to touch it (the polygon's far half). On
# 4000 random fan designs (N = 20) per paper disk the far half's 20 constraints cost 15-20 % of
# the solve (each is evaluated in every Newton matrix and merit); an edge met later joins in
# the next round (_grow_candidates), which costs 0.3 iterations on the mean
FACE_NEAR = 1.0
CORNER_SWEEP = 12  # samples of the arc a corner sweeps from its start to the closed jaws


@njit(cache=True, error_model="numpy", _nrt=False)
def _initial_candidates(x0, n, prm, face_cand, corner_cand, edges, sweep):
    """Candidate constraints at the start point ``x0`` (see :func:`solve_one` for the policies).

    Every point within FACE_NEAR of a finger body; each corner against the contour edges near
    the arc it sweeps as its finger closes (all edges clear of it for the bar's tip corners of
    policy 1); a groove's mouth corners only on a grooved jaw. Both use the jaw's own gap, so a
    point resting in a groove, behind the straight face's line, is near the finger.
    Work arrays: ``edges`` float (n, 4), ``sweep`` float (CORNER_SWEEP, 2).
    """
    nb = 2 * n
    q0 = x0[:nb].reshape(n, 2)
    sn, cs = _trig(x0, n)
    for k in range(n):
        # each edge's bounding circle grown by the corner radius and the band: a cheap reject
        k1 = k + 1 if k + 1 < n else 0
        ex = q0[k1, 0] - q0[k, 0]
        ey = q0[k1, 1] - q0[k, 1]
        edges[k, 0] = 0.5 * (q0[k, 0] + q0[k1, 0])
        edges[k, 1] = 0.5 * (q0[k, 1] + q0[k1, 1])
        far = 0.5 * math.sqrt(ex * ex + ey * ey) + prm[P_RHO] + CORNER_NEAR
        edges[k, 2] = far * far
    for j in range(2):
        th = x0[nb + j]
        for i in range(n):
            # every point that a squeeze can bring to the finger (a late one costs a whole
            # extra round, a far one a little in every iteration)
            gap = _face_gap(q0, i, j, _sel(sn, j), _sel(cs, j), prm)
            face_cand[j, i] = 1e-12 < gap < FACE_NEAR
        # edges near the arc each corner sweeps as the finger closes (policy 1: every edge
        # clear of the tip corners at the start), sampled; the samples lie on a circle about
        # the joint, so an edge whose bounding circle misses that circle's ring is skipped
        for t in range(CORNER_SWEEP):
            ths = th + (prm[P_THMIN] - th) * t / (CORNER_SWEEP - 1)
            sweep[t, 0] = math.sin(ths)
            sweep[t, 1] = math.cos(ths)
        jx = -prm[P_C0X + 2 * j]
        jy = -prm[P_C0X + 2 * j + 1]
        for k in range(n):
            mx = edges[k, 0] - jx
            my = edges[k, 1] - jy
            edges[k, 3] = math.sqrt(mx * mx + my * my)
        for c in range(N_CORNERS):
            if not _corner_active(j, c, prm):
                for k in range(n):
                    corner_cand[j, c, k] = False
                continue
            swept = not (c % 2 == 0 and c < N_BAR_CORNERS and prm[P_POLICY] > 0.0)
            kx, ky = _corner_centre(j, sweep[0, 0], sweep[0, 1], c, prm)
            rc = math.sqrt((kx - jx) * (kx - jx) + (ky - jy) * (ky - jy))
            for k in range(n):
                corner_cand[j, c, k] = False
                if swept:
                    dr = edges[k, 3] - rc
                    if dr * dr >= edges[k, 2] * (1.0 + 1e-12):
                        continue
                # an edge already crossed at the start is left out
                if not _corner_gap(q0, k, j, _sel(sn, j), _sel(cs, j), c, prm) > 1e-12:
                    continue
                if not swept:
                    corner_cand[j, c, k] = True
                    continue
                for t in range(CORNER_SWEEP):
                    kx, ky = _corner_centre(j, sweep[t, 0], sweep[t, 1], c, prm)
                    mx = edges[k, 0] - kx
                    my = edges[k, 1] - ky
                    if mx * mx + my * my < edges[k, 2]:
                        if _seg_dist(q0, k, kx, ky) - prm[P_RHO] < CORNER_NEAR:
                            corner_cand[j, c, k] = True
                            break


@njit(cache=True, error_model="numpy", _nrt=False)
def _grow_candidates(xs, x0, n, prm, face_cand, corner_cand, blocked, commit=True):
    """Add the constraints left out at the start point ``x0`` that the answer ``xs`` of a round
    touches or has crossed (and, after a blocked run, the corner edges just short of it).
    Returns whether any was added; with ``commit=False`` only whether any would be (the sets
    are left as they are)."""
    nb = 2 * n
    changed = False
    q = xs[:nb].reshape(n, 2)
    q0 = x0[:nb].reshape(n, 2)
    sn, cs = _trig(xs, n)
    sn0, cs0 = _trig(x0, n)
    for j in range(2):
        for i in range(n):
            if not face_cand[j, i]:
                g = _face_gap(q, i, j, _sel(sn, j), _sel(cs, j), prm)
                if g < 1e-9:
                    g0 = _face_gap(q0, i, j, _sel(sn0, j), _sel(cs0, j), prm)
                    if g0 > 1e-12:
                        if not commit:
                            return True
                        face_cand[j, i] = True
                        changed = True
        for c in range(N_CORNERS):
            if not _corner_active(j, c, prm):
                continue
            # edges left out at the start that the corner now touches or crossed
            kx, ky = _corner_centre(j, _sel(sn, j), _sel(cs, j), c, prm)
            crossed = _inside(q, n, kx, ky)
            # a blocked interior-point run stopped short of the edge that holds it back
            near_hit = CORNER_NEAR if crossed else 0.02
            for k in range(n):
                if corner_cand[j, c, k]:
                    continue
                g = _corner_gap(q, k, j, _sel(sn, j), _sel(cs, j), c, prm)
                if g < 1e-9 or ((crossed or blocked) and g < near_hit):
                    g0 = _corner_gap(q0, k, j, _sel(sn0, j), _sel(cs0, j), c, prm)
                    if g0 > 1e-12:
                        if not commit:
                            return True
                        corner_cand[j, c, k] = True
                        changed = True
    return changed
