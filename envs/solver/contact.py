"""Contact constraints of the compiled solver: gaps of contour points to the finger bars, of the
rounded corners to contour edges, their gradients and Hessians, and the anti-tunnelling tests.

A finger with a jaw groove takes its points' gaps from the shared kernel
:func:`envs.model.jaw.jaw_gap` (:func:`_solver_jaw_gap`), and its groove's two rounded mouth
edges are corners 4 and 5 (``C_MOUTH_TIP``, ``C_MOUTH_ROOT``); a straight bar keeps its own
fast path and never has those corners as candidates.

Constraint m has a kind (0 face, 1 corner, 2 stop), a finger j and an index (point i, or corner
c and edge k packed as c n + k). The gaps are distances, positive again on the far side of a
thin bar or an edge, so line-search steps that would jump across one are refused.
"""

from __future__ import annotations

import math

from numba import njit

from ..model.geometry import finger_axes
from ..model.jaw import corner_centre_local, jaw_gap
from ..model.layout import (
    G_CENTRE,
    G_COS,
    G_DEPTH,
    G_POSITION,
    G_SIN,
    KIND_CORNER,
    KIND_FACE,
    N_BAR_CORNERS,
    N_CORNERS,
    N_GROOVE,
    P_C0X,
    P_GROOVE0,
    P_HW,
    P_LMAX,
    P_RHO,
    P_THMIN,
)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _groove_base(j):
    """Offset of finger j's packed groove in the parameter vector (slots ``G_*``)."""
    return P_GROOVE0 + N_GROOVE * j


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _grooved(j, prm):
    """Whether finger j's jaw has a groove (depth > 0; else the straight bar)."""
    return prm[_groove_base(j) + G_DEPTH] > 0.0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_active(j, c, prm):
    """Whether corner c of finger j exists: the bar's four always, the groove's two mouth
    edges only on a grooved jaw (never candidates on a straight one)."""
    return c < N_BAR_CORNERS or _grooved(j, prm)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_local(j, c, prm):
    """Centre (s, m) of the rounded corner c of finger j in finger coordinates
    (:func:`envs.model.jaw.corner_centre_local` of the scaled finger and groove)."""
    return corner_centre_local(c, prm[P_LMAX], prm[P_HW], prm[P_RHO], prm, _groove_base(j))


@njit(cache=True, error_model="numpy", _nrt=False)
def _solver_jaw_gap(s, m, j, prm):
    """Gap of the point (s, m) to grooved finger j for the solver: the shared kernel
    :func:`envs.model.jaw.jaw_gap`, (g, g_s, g_m, g_ss, g_sm, g_mm), with the ridge of a V's
    centre line smoothed.

    Why: inside a V-groove (or a rounded V, above its bottom arc's centre) the distance to the
    solid is the smaller of the two flanks' distances, ``S - cb |u|`` with ``u = s - a`` across
    the centre line, ``S`` the mean of the two and ``cb`` the cosine of the half opening
    angle: its gradient flips on the centre line. A contour point hovering above a V's bottom
    (a disk resting on both flanks) sits there, and its barrier term made the interior-point
    steps zig-zag across the ridge. Within ``cb |u| < w`` of the centre line, ``w = sb H / 2``
    (``sb`` the sine of the half angle, ``H`` the height above the arc's centre), ``|t|``
    (``t = cb u``) is replaced by its C1 upper bound ``t^2 / (2 w) + w / 2`` (Huber's): the
    gap there is a lower bound of the distance, above ``R_g + sb H / 2 - rho > 0``, so no
    admissible point is lost and no answer penetrates; a point touching a flank
    (``cb |u| = S > w``) is outside that cone, so contacts and their normals are exact. ``w``
    vanishes at the arc's centre (where the bottom arc takes over) and the cone stays clear of
    the mouth (``cb u_E >= sb h``), so the gap stays continuous with a continuous gradient.
    """
    base = _groove_base(j)
    hw = prm[P_HW]
    g, g_s, g_m, g_ss, g_sm, g_mm = jaw_gap(s, m, prm[P_LMAX], hw, prm[P_RHO], prm, base)
    sb = prm[base + G_SIN]
    height = prm[base + G_CENTRE] - (hw - m)  # H: above the bottom arc's centre
    if not (sb > 0.0 and height > 0.0):
        return g, g_s, g_m, g_ss, g_sm, g_mm
    cb = prm[base + G_COS]
    if g_ss != 0.0 or g_sm != 0.0 or g_mm != 0.0 or g_m != sb or abs(g_s) != cb:
        return g, g_s, g_m, g_ss, g_sm, g_mm  # not on a flank's side of the ridge
    w = 0.5 * sb * height
    t = cb * (s - prm[base + G_POSITION])
    if not abs(t) < w:
        return g, g_s, g_m, g_ss, g_sm, g_mm
    # the flank distance is S - |t|, S = g + rho + |t|; S depends on the depth v = w/2 - m
    # alone (dS/dv = -sb), w too (dw/dv = -sb / 2)
    huber = t * t / (2.0 * w) + 0.5 * w
    f_t = t / w
    f_w = 0.5 - t * t / (2.0 * w * w)
    value = g + abs(t) - huber
    # derivatives in (u, v), then (s, m): d/ds = d/du, d/dm = -d/dv
    d_u = -f_t * cb
    d_v = -sb + 0.5 * sb * f_w
    d_uu = -cb * cb / w
    d_uv = 0.5 * sb * cb * (-t / (w * w))
    d_vv = -0.25 * sb * sb * t * t / (w * w * w)
    return value, d_u, -d_v, d_uu, -d_uv, d_vv


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _axis_offset(j, prm):
    """Offset along the inward normal of the line that the anti-tunnelling tests treat as the
    finger's spine: the axis (0) for a straight bar; for a grooved jaw of depth h, m = -h / 2,
    half-way between the groove's bottom (w/2 - h) and the back (-w/2), so it stays inside
    the solid along the whole finger (h <= 3/4 w) while a point resting in the groove, which
    may lie beyond the axis, is in front of it."""
    return -0.5 * prm[_groove_base(j) + G_DEPTH]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _finger_coords(q, i, j, sj, cj, prm):
    """Frame of finger j and the coordinates (s along the bar, m along the inward normal) of
    point i relative to its joint."""
    ex, ey, nx, ny = finger_axes(j, sj, cj)
    vx = q[i, 0] + prm[P_C0X + 2 * j]
    vy = q[i, 1] + prm[P_C0X + 2 * j + 1]
    return ex, ey, nx, ny, ex * vx + ey * vy, nx * vx + ny * vy


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _face_eval(q, i, j, sj, cj, prm, grad, hess, want_hess):
    """Gap of point i to the body of finger j: value, local grad/Hessian over (qx, qy, theta).

    The body is the bar 0 <= s <= l, |m| <= w/2 in finger coordinates (s along the axis, m
    along the inward normal) with its four corners rounded to the radius rho: the rectangle
    R = [0, l] x [-(w/2 - rho), w/2 - rho] grown by rho. The gap is dist(p, R) - rho, C1
    outside the body: the gripping face (m = w/2), the tip and root ends and the back of the
    bar, which a disk wrapping round a finger tip can reach.
    """
    ex, ey, nx, ny, s, m = _finger_coords(q, i, j, sj, cj, prm)
    rho = prm[P_RHO]
    if _grooved(j, prm):
        # a jaw groove: the shared gap kernel, then the chain rule to (qx, qy, theta)
        g, g_s, g_m, g_ss, g_sm, g_mm = _solver_jaw_gap(s, m, j, prm)
        if g_s == 0.0 and g_m == 0.0:
            # inside the core: deep penetration (never at a feasible point)
            for a in range(3):
                grad[a] = 0.0
                if want_hess:
                    for b in range(3):
                        hess[a, b] = 0.0
            return g
        _chain_rule(ex, ey, nx, ny, s, m, g_s, g_m, g_ss, g_sm, g_mm, grad, hess, want_hess)
        return g
    hc = prm[P_HW] - rho
    ds = s - min(max(s, 0.0), prm[P_LMAX])
    dm = m - min(max(m, -hc), hc)
    if ds == 0.0 and dm != 0.0:
        # the common case, beside a long side of the bar: the gap is |m| - w/2
        g_m = 1.0 if dm > 0.0 else -1.0
        grad[0] = g_m * nx
        grad[1] = g_m * ny
        grad[2] = g_m * s
        if want_hess:
            hx = g_m * ex
            hy = g_m * ey
            hess[0, 0] = 0.0
            hess[0, 1] = 0.0
            hess[1, 0] = 0.0
            hess[1, 1] = 0.0
            hess[0, 2] = hx
            hess[2, 0] = hx
            hess[1, 2] = hy
            hess[2, 1] = hy
            hess[2, 2] = -g_m * m
        return abs(dm) - rho
    for a in range(3):
        grad[a] = 0.0
        if want_hess:
            for b in range(3):
                hess[a, b] = 0.0
    # derivatives of s and m: ds/dq = e, dm/dq = n, ds/dth = -m, dm/dth = s,
    # d2s/dq dth = -n, d2m/dq dth = e, d2s/dth2 = -s, d2m/dth2 = -m
    if ds != 0.0 and dm != 0.0:
        dist = math.sqrt(ds * ds + dm * dm)
        g_s = ds / dist
        g_m = dm / dist
        d3 = dist * dist * dist
        g_ss = dm * dm / d3
        g_mm = ds * ds / d3
        g_sm = -ds * dm / d3
    elif dm != 0.0:
        dist = abs(dm)
        g_s = 0.0
        g_m = 1.0 if dm > 0.0 else -1.0
        g_ss = 0.0
        g_mm = 0.0
        g_sm = 0.0
    elif ds != 0.0:
        dist = abs(ds)
        g_s = 1.0 if ds > 0.0 else -1.0
        g_m = 0.0
        g_ss = 0.0
        g_mm = 0.0
        g_sm = 0.0
    else:
        return -rho  # inside the core rectangle: deep penetration (never at a feasible point)
    _chain_rule(ex, ey, nx, ny, s, m, g_s, g_m, g_ss, g_sm, g_mm, grad, hess, want_hess)
    return dist - rho


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _chain_rule(ex, ey, nx, ny, s, m, g_s, g_m, g_ss, g_sm, g_mm, grad, hess, want_hess):
    """Gradient and Hessian over (qx, qy, theta) of a gap given by its derivatives in finger
    coordinates (s, m) of a point with finger axes e, n.

    ds/dq = e, dm/dq = n, ds/dth = -m, dm/dth = s, d2s/dq dth = -n, d2m/dq dth = e,
    d2s/dth2 = -s, d2m/dth2 = -m.
    """
    # first derivatives: grad = g_s grad(s) + g_m grad(m)
    as0, as1, as2 = ex, ey, -m
    am0, am1, am2 = nx, ny, s
    grad[0] = g_s * as0 + g_m * am0
    grad[1] = g_s * as1 + g_m * am1
    grad[2] = g_s * as2 + g_m * am2
    if not want_hess:
        return
    # second derivatives: sum of g_ab grad(a) grad(b)^T plus g_s Hess(s) + g_m Hess(m)
    sv = (as0, as1, as2)
    mv = (am0, am1, am2)
    for a in range(3):
        for b in range(3):
            hess[a, b] = (g_ss * sv[a] * sv[b] + g_mm * mv[a] * mv[b]
                          + g_sm * (sv[a] * mv[b] + mv[a] * sv[b]))
    # Hess(s): (q, th) entries -n, (th, th) -s ; Hess(m): (q, th) entries e, (th, th) -m
    hx = -g_s * nx + g_m * ex
    hy = -g_s * ny + g_m * ey
    hess[0, 2] += hx
    hess[2, 0] += hx
    hess[1, 2] += hy
    hess[2, 1] += hy
    hess[2, 2] += -g_s * s - g_m * m


@njit(cache=True, error_model="numpy", _nrt=False)
def _corner_eval(q, k, j, sj, cj, c, prm, grad, hess, want_hess):
    """Rounded corner c of finger j vs contour edge k -> k+1.

    Corners (``C_*`` of :mod:`envs.model.layout`): 0 tip and 1 root of the gripping face, 2 tip
    and 3 root of the back of the bar, 4 and 5 the mouth edges of a jaw groove (tip and root
    side; only on a grooved jaw).

    Local variables (ax, ay, bx, by, theta). Value: distance from the centre of the rounded
    corner to the segment, minus the corner radius: the distance to the edge line where the foot
    lies on the edge, to the nearer end point beyond it. The distance to a segment is C1 away
    from the segment, so a corner may slide from one edge to the next through their common
    vertex with every nearby edge kept as its own constraint.
    """
    n = q.shape[0]
    k1 = k + 1 if k + 1 < n else 0
    ex, ey, nx, ny = finger_axes(j, sj, cj)
    rho = prm[P_RHO]
    sc, hw = _corner_local(j, c, prm)  # centre of the rounded corner, finger coordinates
    cx = prm[P_C0X + 2 * j]
    cy = prm[P_C0X + 2 * j + 1]
    kx = -cx + sc * ex + hw * nx
    ky = -cy + sc * ey + hw * ny
    k1x = -sc * nx + hw * ex
    k1y = -sc * ny + hw * ey
    k2x = -sc * ex - hw * nx
    k2y = -sc * ey - hw * ny
    ax, ay = q[k, 0], q[k, 1]
    ux, uy = kx - ax, ky - ay
    dx, dy = q[k1, 0] - ax, q[k1, 1] - ay
    tpar = (ux * dx + uy * dy) / (dx * dx + dy * dy)
    if tpar < 0.0 or tpar > 1.0:
        # beyond an end: distance between the end point v and the corner K
        for a in range(5):
            grad[a] = 0.0
            for b in range(5):
                hess[a, b] = 0.0
        off = 0 if tpar < 0.0 else 2
        vx, vy = q[k, 0], q[k, 1]
        if off == 2:
            vx, vy = q[k1, 0], q[k1, 1]
        wx, wy = kx - vx, ky - vy
        g = math.sqrt(wx * wx + wy * wy)
        if g < 1e-300:
            return -rho
        ux_, uy_ = wx / g, wy / g
        pxx, pxy, pyy = (1.0 - ux_ * ux_) / g, -ux_ * uy_ / g, (1.0 - uy_ * uy_) / g
        grad[off] = -ux_
        grad[off + 1] = -uy_
        grad[4] = ux_ * k1x + uy_ * k1y
        hess[off, off] = pxx
        hess[off, off + 1] = pxy
        hess[off + 1, off] = pxy
        hess[off + 1, off + 1] = pyy
        hx = -(pxx * k1x + pxy * k1y)
        hy = -(pxy * k1x + pyy * k1y)
        hess[off, 4] = hx
        hess[4, off] = hx
        hess[off + 1, 4] = hy
        hess[4, off + 1] = hy
        hess[4, 4] = (k1x * (pxx * k1x + pxy * k1y) + k1y * (pxy * k1x + pyy * k1y)
                      + ux_ * k2x + uy_ * k2y)
        return g - rho
    L = math.sqrt(dx * dx + dy * dy)
    cr = ux * dy - uy * dx
    g = cr / L
    # first derivatives in (u, d)
    jdx, jdy = dy, -dx  # J d
    jux, juy = uy, -ux  # J u
    gux, guy = jdx / L, jdy / L
    L3 = L * L * L
    gdx = -jux / L - cr * dx / L3
    gdy = -juy / L - cr * dy / L3
    # M_ud[a, b] = J[a, b]/L - (Jd)_a d_b / L^3 ; J = [[0, 1], [-1, 0]]
    m00 = -jdx * dx / L3
    m01 = 1.0 / L - jdx * dy / L3
    m10 = -1.0 / L - jdy * dx / L3
    m11 = -jdy * dy / L3
    L5 = L3 * L * L
    d00 = 2.0 * jux * dx / L3 - cr / L3 + 3.0 * cr * dx * dx / L5
    d11 = 2.0 * juy * dy / L3 - cr / L3 + 3.0 * cr * dy * dy / L5
    d01 = (jux * dy + dx * juy) / L3 + 3.0 * cr * dx * dy / L5
    # chain rule to z = (ax, ay, bx, by, theta): u = K(theta) - a, d = b - a
    grad[0] = -gux - gdx
    grad[1] = -guy - gdy
    grad[2] = gdx
    grad[3] = gdy
    grad[4] = gux * k1x + guy * k1y
    sgn = 1.0 if cr >= 0.0 else -1.0
    if not want_hess:
        # the corner on the inner side of this edge's line: the distance is -cr / L
        for a in range(5):
            grad[a] *= sgn
        return sgn * g - rho
    # per-z columns of du and dd (du for z = bx, by is zero; dd for theta is zero)
    u0 = (-1.0, 0.0, 0.0, 0.0, k1x)
    u1 = (0.0, -1.0, 0.0, 0.0, k1y)
    e0 = (-1.0, 0.0, 1.0, 0.0, 0.0)
    e1 = (0.0, -1.0, 0.0, 1.0, 0.0)
    for a in range(5):
        ua0, ua1, da0, da1 = u0[a], u1[a], e0[a], e1[a]
        # (M t_a) components: Mu = M_ud d, Md = M_du u + M_dd d
        mu0 = m00 * da0 + m01 * da1
        mu1 = m10 * da0 + m11 * da1
        md0 = m00 * ua0 + m10 * ua1 + d00 * da0 + d01 * da1
        md1 = m01 * ua0 + m11 * ua1 + d01 * da0 + d11 * da1
        for b in range(5):
            hess[a, b] = u0[b] * mu0 + u1[b] * mu1 + e0[b] * md0 + e1[b] * md1
    hess[4, 4] += gux * k2x + guy * k2y
    if cr < 0.0:
        # the corner lies on the inner side of this edge's line: the distance to the segment
        # is -cr / L (every edge near the corner is a constraint, not only the one it faces)
        for a in range(5):
            grad[a] = -grad[a]
            for b in range(5):
                hess[a, b] = -hess[a, b]
        return -g - rho
    return g - rho


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _face_gap(q, i, j, sj, cj, prm):
    """Value of :func:`_face_eval` only."""
    ex, ey, nx, ny, s, m = _finger_coords(q, i, j, sj, cj, prm)
    rho = prm[P_RHO]
    if _grooved(j, prm):
        return _solver_jaw_gap(s, m, j, prm)[0]
    hc = prm[P_HW] - rho
    ds = s - min(max(s, 0.0), prm[P_LMAX])
    dm = m - min(max(m, -hc), hc)
    return math.sqrt(ds * ds + dm * dm) - rho


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _seg_dist(q, k, px, py):
    """Distance from (px, py) to the contour edge k -> k+1."""
    n = q.shape[0]
    k1 = k + 1 if k + 1 < n else 0
    ax, ay = q[k, 0], q[k, 1]
    dx, dy = q[k1, 0] - ax, q[k1, 1] - ay
    t = ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)
    t = min(1.0, max(0.0, t))
    wx = px - ax - t * dx
    wy = py - ay - t * dy
    return math.sqrt(wx * wx + wy * wy)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_gap(q, k, j, sj, cj, c, prm):
    """Value of :func:`_corner_eval` only: corner centre to segment distance minus rho."""
    kx, ky = _corner_centre(j, sj, cj, c, prm)
    return _seg_dist(q, k, kx, ky) - prm[P_RHO]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _sel(t, j):
    """Entry j (0 or 1) of a pair: a tuple indexed by a run-time integer costs tens of ns."""
    return t[1] if j == 1 else t[0]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _trig(x, n):
    """Sines and cosines of the two finger angles of state x (computed once per pass)."""
    return ((math.sin(x[2 * n]), math.sin(x[2 * n + 1])),
            (math.cos(x[2 * n]), math.cos(x[2 * n + 1])))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _con_value(kind, j, idx, x, q, n, prm, sn, cs):
    """Value of constraint (kind, j, idx) only (line searches, candidate checks); ``sn``, ``cs``
    hold the sines and cosines of the finger angles (:func:`_trig`)."""
    if kind == 0:
        return _face_gap(q, idx, j, _sel(sn, j), _sel(cs, j), prm)
    if kind == 1:
        c = idx // n
        return _corner_gap(q, idx - c * n, j, _sel(sn, j), _sel(cs, j), c, prm)
    return x[2 * n + j] - prm[P_THMIN]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _con_eval(kind, j, idx, x, q, n, prm, sn, cs, grad5, hess5, dofs, want_hess=True):
    """Evaluate constraint; returns (value, number of local dofs); fills natural-order dofs."""
    th = x[2 * n + j]
    if kind == 0:
        g = _face_eval(q, idx, j, _sel(sn, j), _sel(cs, j), prm, grad5, hess5, want_hess)
        dofs[0] = 2 * idx
        dofs[1] = 2 * idx + 1
        dofs[2] = 2 * n + j
        return g, 3
    if kind == 1:
        c = idx // n
        k = idx - c * n
        g = _corner_eval(q, k, j, _sel(sn, j), _sel(cs, j), c, prm, grad5, hess5, want_hess)
        k1 = k + 1 if k + 1 < n else 0
        dofs[0] = 2 * k
        dofs[1] = 2 * k + 1
        dofs[2] = 2 * k1
        dofs[3] = 2 * k1 + 1
        dofs[4] = 2 * n + j
        return g, 5
    for a in range(5):
        grad5[a] = 0.0
        for b in range(5):
            hess5[a, b] = 0.0
    grad5[0] = 1.0
    dofs[0] = 2 * n + j
    return th - prm[P_THMIN], 1


@njit(cache=True, error_model="numpy", _nrt=False)
def _all_gaps(x, n, prm, kinds, fj, fidx, gout):
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    for m in range(kinds.shape[0]):
        gout[m] = _con_value(kinds[m], fj[m], fidx[m], x, q, n, prm, sn, cs)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_centre(j, sj, cj, c, prm):
    """Centre of the rounded corner c of finger j (disk-centred, units of r)."""
    ex, ey, nx, ny = finger_axes(j, sj, cj)
    sc, hc = _corner_local(j, c, prm)
    return (-prm[P_C0X + 2 * j] + sc * ex + hc * nx,
            -prm[P_C0X + 2 * j + 1] + sc * ey + hc * ny)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_on_edge(q, idx, j, sn, cs, prm):
    """Corner constraint ``idx`` of finger ``j`` (its corner ``idx // n`` against the contour
    edge ``k = idx % n``): the corner's centre, the edge's end points ``k``, ``k1``, the edge
    vector and the centre's foot on the edge's line as a fraction ``t`` of it from ``k`` (not
    clamped: outside [0, 1] the foot lies beyond an end point)."""
    n = q.shape[0]
    c = idx // n
    k = idx - c * n
    k1 = k + 1 if k + 1 < n else 0
    kx, ky = _corner_centre(j, _sel(sn, j), _sel(cs, j), c, prm)
    ex, ey = q[k1, 0] - q[k, 0], q[k1, 1] - q[k, 1]
    t = ((kx - q[k, 0]) * ex + (ky - q[k, 1]) * ey) / (ex * ex + ey * ey)
    return kx, ky, k, k1, ex, ey, t


@njit(cache=True, error_model="numpy", _nrt=False)
def _inside(q, n, px, py):
    """Crossing-number test: is (px, py) inside the contour polygon?"""
    inside = False
    for k in range(n):
        k1 = k + 1 if k + 1 < n else 0
        ax, ay, bx, by = q[k, 0], q[k, 1], q[k1, 0], q[k1, 1]
        if (ay > py) != (by > py):
            xc = ax + (py - ay) * (bx - ax) / (by - ay)
            if xc > px:
                inside = not inside
    return inside


@njit(cache=True, error_model="numpy", _nrt=False)
def _bar_crossed(q, n, j, sj, cj, prm):
    """Does a contour edge cross the spine of finger j (the bar runs right through the disk)?
    The spine is the axis, moved behind a jaw groove's bottom (:func:`_axis_offset`).

    Every point outside the bar and every corner outside the contour do not exclude an edge
    with one end in front of the bar and the other behind it.
    """
    ex, ey, nx, ny = finger_axes(j, sj, cj)
    mline = _axis_offset(j, prm)
    ax = -prm[P_C0X + 2 * j] + mline * nx
    ay = -prm[P_C0X + 2 * j + 1] + mline * ny
    bx = ax + prm[P_LMAX] * ex
    by = ay + prm[P_LMAX] * ey
    for k in range(n):
        k1 = k + 1 if k + 1 < n else 0
        px, py, rx, ry = q[k, 0], q[k, 1], q[k1, 0], q[k1, 1]
        d1 = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        d2 = (bx - ax) * (ry - ay) - (by - ay) * (rx - ax)
        if d1 * d2 >= 0.0:
            continue
        d3 = (rx - px) * (ay - py) - (ry - py) * (ax - px)
        d4 = (rx - px) * (by - py) - (ry - py) * (bx - px)
        if d3 * d4 < 0.0:
            return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _crossed_through(x, n, prm):
    """Has a finger gone right through the disk in state x (an edge across its bar, or one
    of its corners inside the contour), where every gap is positive again?"""
    sn, cs = _trig(x, n)
    return _crossed_through_sc(x, n, prm, sn, cs)


@njit(cache=True, error_model="numpy", _nrt=False)
def _crossed_through_sc(x, n, prm, sn, cs):
    """:func:`_crossed_through` with the finger sines and cosines given.

    The contour lies in the circle about the pin through its farthest point: a corner or a bar
    outside that circle is skipped without the O(N) tests.
    """
    nb = 2 * n
    q = x[:nb].reshape(n, 2)
    r2 = 0.0
    for i in range(n):
        r2 = max(r2, x[2 * i] * x[2 * i] + x[2 * i + 1] * x[2 * i + 1])
    for j in range(2):
        # distance from the pin to the axis segment of the bar
        ex, ey, nx, ny = finger_axes(j, _sel(sn, j), _sel(cs, j))
        mline = _axis_offset(j, prm)
        ax = -prm[P_C0X + 2 * j] + mline * nx
        ay = -prm[P_C0X + 2 * j + 1] + mline * ny
        t = min(max(-(ax * ex + ay * ey), 0.0), prm[P_LMAX])
        px = ax + t * ex
        py = ay + t * ey
        if px * px + py * py <= r2 and _bar_crossed(q, n, j, _sel(sn, j), _sel(cs, j), prm):
            return True
        for c in range(N_CORNERS):
            if not _corner_active(j, c, prm):
                continue
            kx, ky = _corner_centre(j, _sel(sn, j), _sel(cs, j), c, prm)
            if kx * kx + ky * ky <= r2 and _inside(q, n, kx, ky):
                return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _tunnels(x, xt, n, prm):
    """Would the step x -> xt carry a corner or a point right through the contour or a finger?

    The corner gaps are distances to segments and the bar of a finger is thin, so a long step
    can jump across a constraint and land where every gap is positive again. Rejected: a corner
    ending inside the contour, a point crossing a finger's spine (:func:`_axis_offset`) along
    the bar.
    """
    sn1, cs1 = _trig(xt, n)
    if _crossed_through_sc(xt, n, prm, sn1, cs1):
        return True
    sn0, cs0 = _trig(x, n)
    for j in range(2):
        ex0, ey0, nx0, ny0 = finger_axes(j, _sel(sn0, j), _sel(cs0, j))
        ex1, ey1, nx1, ny1 = finger_axes(j, _sel(sn1, j), _sel(cs1, j))
        cx = prm[P_C0X + 2 * j]
        cy = prm[P_C0X + 2 * j + 1]
        lmax = prm[P_LMAX]
        mline = _axis_offset(j, prm)
        for i in range(n):
            vx0, vy0 = x[2 * i] + cx, x[2 * i + 1] + cy
            vx1, vy1 = xt[2 * i] + cx, xt[2 * i + 1] + cy
            m0 = nx0 * vx0 + ny0 * vy0 - mline
            m1 = nx1 * vx1 + ny1 * vy1 - mline
            if m0 * m1 < 0.0:
                s0 = ex0 * vx0 + ey0 * vy0
                s1 = ex1 * vx1 + ey1 * vy1
                if (0.0 <= s0 <= lmax) or (0.0 <= s1 <= lmax):
                    return True
    return False


@njit(cache=True, error_model="numpy", _nrt=False)
def _build_constraints(face, corner, n, kinds, fj, fidx):
    m = 0
    for j in range(2):
        for i in range(n):
            if face[j, i]:
                kinds[m] = 0
                fj[m] = j
                fidx[m] = i
                m += 1
    for j in range(2):
        for c in range(N_CORNERS):
            for k in range(n):
                if corner[j, c, k]:
                    kinds[m] = 1
                    fj[m] = j
                    fidx[m] = k + n * c
                    m += 1
    for j in range(2):
        kinds[m] = 2
        fj[m] = j
        fidx[m] = 0
        m += 1
    return m


@njit(cache=True, inline="always")
def constraint_dofs(kind):
    """How many unknowns a constraint's gap depends on (its columns of ``cd``/``cg``): a face
    gap the point (x, y) and its finger's angle, a corner gap the contour edge's two points and
    the finger's angle, a joint stop the finger's angle alone."""
    if kind == KIND_FACE:
        return 3
    if kind == KIND_CORNER:
        return 5
    return 1
