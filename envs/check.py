"""Compiled independent equilibrium check of a grasp (KKT conditions in physical units).

The compiled version of the numpy reference check kept in ``tests/kkt_reference.py``, with the
same semantics (same tolerances, same residual definitions, same reason strings). It
recomputes, from the returned contour points, finger angles and contact forces only, the spring
forces, the force balance at every contour point, the moment balance at each joint, the gaps to
the finite fingers (bar with rounded corners) and their corners, the sign of every contact
force and complementarity.

It is independent of the solver on purpose: nothing here comes from the solver's code; the
finger frames, the rounded-bar distance, the corners, the closed-jaw angle and the polygon tests
are written again from ``docs/model.md``. Only the Python wrapper (:func:`check_params`)
takes two things from the model, because they define the model being checked rather than how it
is solved: the spring stiffness rule and the corner rounding radius (``spring_stiffness`` and
``corner_radius`` of :mod:`envs.model`). The compiled core gets plain numbers; the batch
pipeline (:mod:`envs.solver.pipeline`) fills the same vector from the packed model parameters.

The compiled core works on plain float64 arrays; the problem is packed in a parameter vector
and the verdict comes back in an output vector, both laid out by the named offsets below:

Parameter vector (``N_CK`` floats, SI units)

==================  ===========================================================  =====
offset              meaning                                                      unit
==================  ===========================================================  =====
``CK_RADIUS``       disk radius ``r``                                            m
``CK_CENTRE_X/Y``   pinned centre ``C``                                          m
``CK_JOINT_OFFSET`` joint distance ``d_3`` from the symmetry axis                m
``CK_LENGTH``       finger length ``l``                                          m
``CK_HALF_WIDTH``   half finger width ``w/2``                                    m
``CK_RHO``          rounding radius of the finger's end corners                  m
``CK_KF``           torsion spring ``k_f`` of each joint                         N·m/rad
``CK_TH0``          rest angle ``theta_a0``                                      rad
``CK_THMIN``        closed-jaw angle (joint stop)                                rad
``CK_TORQUE``       actuation torque ``T_a``                                     N·m
``CK_KINT``         radial spring stiffness                                      N/m
``CK_KEXT``         contour spring stiffness                                     N/m
``CK_REST_CONTOUR`` rest length ``h = 2 r sin(pi/N)`` of the contour springs     m
``CK_AREA_STIFF``   area stiffness ``kappa t`` of the area energy (0: none)      N/m
``CK_REST_AREA``    rest area ``A0`` of a fan triangle                           m^2
``CK_JAW0/1``       each finger's jaw groove (right, left): ``JW_*`` slots of    m, rad
                    depth, bottom radius, full opening angle and position from
                    the joint; depth 0 is the straight bar
``CK_SHAPE``        0 for a disk, else an outline (``CK_RADIUS`` its ``r_eq``;  -
                    its coefficients an argument of :func:`check_mesh_one`)
``CK_ORIENT``       the outline's orientation ``psi``                           rad
==================  ===========================================================  =====

A grooved finger's solid is the bar minus its groove with every convex edge rounded by
``rho``: the points within ``rho`` of the core ``K``, the core rectangle
``[0, l] x [-(w/2 - rho), w/2 - rho]`` less the groove grown by ``rho``. The check writes the
grown groove in its own way, as the points within ``R_b + rho`` of a solid cone (apex at the
bottom arc's centre, opening out of the face, half-angle half the opening angle), and measures
the distance to ``K`` as the nearest of its boundary pieces (straight segments and one arc).

Output vector (``N_OUT`` floats): ``OUT_PASSED`` (1.0 or 0.0), ``OUT_FORCE_RES`` and
``OUT_MOMENT_RES`` (relative residuals), ``OUT_PENETRATION`` [m], ``OUT_CONTACT_GAP`` (largest gap
of a loaded contact) [m], ``OUT_MIN_FORCE`` [N] and ``OUT_REASONS``, a bit field of the
``FAIL_*`` flags.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

# the outline is the model's definition of the object (like the stiffness rule), not how the
# grasp is solved: its contour points are the model's own
from .model.outline import outline_contour_into

__all__ = [
    "KKTReport",
    "FORCE_TOL",
    "GAP_TOL",
    "CK_RADIUS",
    "CK_CENTRE_X",
    "CK_CENTRE_Y",
    "CK_JOINT_OFFSET",
    "CK_LENGTH",
    "CK_HALF_WIDTH",
    "CK_RHO",
    "CK_KF",
    "CK_TH0",
    "CK_THMIN",
    "CK_TORQUE",
    "CK_KINT",
    "CK_KEXT",
    "CK_REST_CONTOUR",
    "CK_AREA_STIFF",
    "CK_REST_AREA",
    "CK_QUAD",
    "CK_SPACING",
    "CK_JAW0",
    "CK_JAW1",
    "JW_DEPTH",
    "JW_BOTTOM_RADIUS",
    "JW_OPENING",
    "JW_POSITION",
    "N_CK",
    "OUT_PASSED",
    "OUT_FORCE_RES",
    "OUT_MOMENT_RES",
    "OUT_PENETRATION",
    "OUT_CONTACT_GAP",
    "OUT_MIN_FORCE",
    "OUT_REASONS",
    "N_OUT",
    "FAIL_FORCE",
    "FAIL_MOMENT",
    "FAIL_PENETRATION",
    "FAIL_GAP",
    "FAIL_NEGATIVE",
    "check_params",
    "check_one",
    "check_batch",
    "check_mesh_one",
    "report_from_output",
    "check_grasp",
]

FORCE_TOL = 1e-8  # relative force and moment residual
GAP_TOL = 1e-9  # contact gap tolerance, in units of the radius

# parameter vector layout
CK_RADIUS = 0
CK_CENTRE_X = 1
CK_CENTRE_Y = 2
CK_JOINT_OFFSET = 3
CK_LENGTH = 4
CK_HALF_WIDTH = 5
CK_RHO = 6
CK_KF = 7
CK_TH0 = 8
CK_THMIN = 9
CK_TORQUE = 10
CK_KINT = 11
CK_KEXT = 12
CK_REST_CONTOUR = 13
CK_AREA_STIFF = 14
CK_REST_AREA = 15
CK_RINGS = 16  # rings M of the point mesh (1: the fan; the fields below serve M >= 2)
CK_HUB = 17  # hub radius of a ring mesh [m]
CK_UNIT = 18  # s E t [N/m]: the area rule's stiffness unit
CK_CRATIO = 19  # contour stiffness ratio (the contour ring's springs)
CK_MU = 20  # constant-strain neo-Hookean triangles: s mu t [N/m] (0: springs and area energy)
CK_LAM = 21  # and s lambda t [N/m]
CK_PHASE = 22  # angle of the first point of every ring [rad]
CK_QUAD = 23  # nh-quad: s lambda t [N/m] of the volumetric energy of each quad (0: none)
CK_SPACING = 24  # ring radii: 0 geometric from the hub, 1 evenly spaced
# each finger's jaw groove, SI: depth [m], bottom radius [m], full opening angle [rad] and
# position of its centre line from the joint [m] at CK_JAW0 + JW_* (right finger), CK_JAW1 (left)
JW_DEPTH, JW_BOTTOM_RADIUS, JW_OPENING, JW_POSITION = range(4)
CK_JAW0 = 25
CK_JAW1 = 29
# the object's outline (0: a disk; CK_RADIUS is then its equivalent radius) and its
# orientation [rad]; its B-spline coefficients of r(phi) / r (envs.model.outline) are an
# argument of check_mesh_one
CK_SHAPE = 33
CK_ORIENT = 34
N_CK = 35

# output vector layout
OUT_PASSED = 0
OUT_FORCE_RES = 1
OUT_MOMENT_RES = 2
OUT_PENETRATION = 3
OUT_CONTACT_GAP = 4
OUT_MIN_FORCE = 5
OUT_REASONS = 6
N_OUT = 7

# failure bits of OUT_REASONS, in the order the reasons are written
FAIL_FORCE = 1
FAIL_MOMENT = 2
FAIL_PENETRATION = 4
FAIL_GAP = 8
FAIL_NEGATIVE = 16

# accumulator layout of the core's work vector (internal)
_ACC_PEN = 0  # largest penetration [m]
_ACC_GAP = 1  # largest |gap| of a loaded contact [m]
_ACC_FMIN = 2  # smallest contact force or stop torque (inf: none)
_ACC_SCALE = 3  # largest contact moment scale [N·m]
_ACC_MOMENT = 4  # net moment on finger j at _ACC_MOMENT + j [N·m]
_N_ACC = 6

_FLAGS = dict(cache=True, error_model="numpy", _nrt=False)

# corners of a finger: the bar's four (face tip, face root, back tip, back root), then a jaw
# groove's two mouth edges (tip side, root side); a corner array may carry the bar's only
_BAR_CORNERS = 4
_ALL_CORNERS = 6


@njit(inline="always", **_FLAGS)
def _corner_count_ok(count):
    """Whether a corner array's corner axis has a valid length (4 or 6)."""
    return count == _BAR_CORNERS or count == _ALL_CORNERS


class KKTReport(NamedTuple):
    """Outcome of :func:`check_grasp` (relative residuals are dimensionless)."""

    passed: bool
    force_residual_rel: float
    moment_residual_rel: float
    max_penetration_m: float
    max_contact_gap_m: float
    min_contact_force_n: float
    reason: str


# --------------------------------------------------------------------------------------------
# scalar helpers. The reference check mixes Python's max/min (``max(a, b)`` keeps ``a`` unless
# ``b > a``, so a NaN ``b`` is dropped) with numpy's max/min over arrays (a NaN anywhere wins);
# both are kept so that even a state with NaN gets the same verdict.


@njit(inline="always", **_FLAGS)
def _pymax(a, b):
    """Python's ``max(a, b)``."""
    return b if b > a else a


@njit(inline="always", **_FLAGS)
def _pymin(a, b):
    """Python's ``min(a, b)``."""
    return b if b < a else a


@njit(inline="always", **_FLAGS)
def _npmax(a, b):
    """Running ``numpy.max``: NaN propagates."""
    if a != a:
        return a
    return b if (b > a or b != b) else a


@njit(inline="always", **_FLAGS)
def _npmin(a, b):
    """Running ``numpy.min``: NaN propagates."""
    if a != a:
        return a
    return b if (b < a or b != b) else a


# --------------------------------------------------------------------------------------------
# Python's math.hypot. The reference check measures every length with it; it is correctly
# rounded (CPython's vector_norm: power-of-two scaling, exact squares, compensated sum and one
# Newton correction of the root) while the C library's hypot, which numba calls, is off by one
# ulp now and then. One ulp of a spring length shows in the residual of an unloaded disk at
# 1e-10 (its spring forces are cancellation noise judged against a 1e-6 strain), so the same
# algorithm is used here: the reference's residuals are then reproduced to round-off.


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (LLVM's fma: the instruction, or the C library's fma)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        dbl = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [dbl], ir.FunctionType(dbl, [dbl] * 3))
        return builder.call(fn, args)

    return sig, codegen


@intrinsic
def _bits(typingctx, x):
    """The IEEE 754 bits of a float64, as an int64."""
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _from_bits(typingctx, i):
    """The float64 with the given IEEE 754 bits."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


@njit(inline="always", **_FLAGS)
def _hypot_scaled(x, y, scale):
    """CPython's ``vector_norm`` of (x, y) >= 0 with ``max(x, y) * scale`` in [0.5, 1).

    Exact squares (fma), a compensated sum that starts at 1 so that it is always the larger
    addend, then one Newton step on ``h**2 = sum`` in the same arithmetic.
    """
    x, y = x * scale, y * scale
    hx, hy = x * x, y * y
    frac1 = _fma(x, x, -hx) + _fma(y, y, -hy)
    csum = 1.0 + hx
    frac2 = (1.0 - csum) + hx
    total = csum + hy
    frac2 += (csum - total) + hy
    csum = total
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hh = -h * h
    frac1 += _fma(-h, h, -hh)
    total = csum + hh
    frac2 += (csum - total) + hh
    h += (total - 1.0 + (frac1 + frac2)) / (2.0 * h)
    return h / scale


@njit(**_FLAGS)
def _hypot(x, y):
    """``sqrt(x**2 + y**2)`` as Python's ``math.hypot`` computes it.

    The algorithm of CPython 3.12+ (3.10 and 3.11 square exactly with Veltkamp's split rather
    than fma: the same squares, summed in another order; both round correctly in all but
    vanishingly rare cases and agreed bit for bit on millions of pairs under 3.11), and 3.11's
    path for subnormal inputs.
    """
    x, y = abs(x), abs(y)
    if x == math.inf or y == math.inf:  # even with a NaN beside it
        return math.inf
    if x != x or y != y:
        return math.nan
    if x == 0.0 or y == 0.0:
        return x + y  # exact, as CPython's is: the common case of a point facing a flat side
    big = x if x > y else y
    biased = (_bits(big) >> 52) & 0x7FF  # big = 1.f * 2**(biased - 1023)
    if 0 < biased < 2045:
        # 2**-(biased - 1022): the power of two that takes big into [0.5, 1)
        return _hypot_scaled(x, y, _from_bits((2045 - biased) << 52))
    e = math.frexp(big)[1]
    if e >= -1023:  # huge, or not too small a subnormal
        return _hypot_scaled(x, y, math.ldexp(1.0, -e))
    # tiny: the scale would overflow; CPython 3.11 divides by the largest instead
    qx, qy = x / big, y / big
    csum = 1.0 + qx * qx
    frac = (1.0 - csum) + qx * qx
    total = csum + qy * qy
    frac += (csum - total) + qy * qy
    return big * math.sqrt(total - 1.0 + frac)


@njit(inline="always", **_FLAGS)
def _npclip(a, lo, hi):
    """``numpy.clip(a, lo, hi)`` of a scalar: NaN propagates."""
    if a != a:
        return a
    return lo if a < lo else (hi if a > hi else a)


@njit(inline="always", **_FLAGS)
def _frame(prm, j, theta):
    """Joint, unit axis ``e`` and inward face normal ``n`` of finger j (docs/model.md).

    Returns ``jx, jy, ex, ey, nx, ny``; j = 0 is the right finger, 1 the left one.
    """
    s, c = math.sin(theta), math.cos(theta)
    d3 = prm[CK_JOINT_OFFSET]
    if j == 0:
        return d3, 0.0, s, c, -c, s
    return -d3, 0.0, -s, c, c, s


# --------------------------------------------------------------------------------------------
# polygon geometry (the deformed contour, counter-clockwise)


@njit(**_FLAGS)
def _inside(p, x, y):
    """Whether ``(x, y)`` lies inside the contour polygon (even-odd ray casting along +x)."""
    n = p.shape[0]
    inside = False
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        x1, y1 = p[i, 0], p[i, 1]
        x2, y2 = p[i1, 0], p[i1, 1]
        if (y1 > y) != (y2 > y):
            xc = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            if xc > x:
                inside = not inside
    return inside


@njit(**_FLAGS)
def _dist_polygon(p, x, y):
    """Distance from ``(x, y)`` to the contour polygon's boundary [m]."""
    n = p.shape[0]
    best = math.inf  # smallest squared distance: the root is monotone, so taken once
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        ax, ay = p[i, 0], p[i, 1]
        dx, dy = p[i1, 0] - ax, p[i1, 1] - ay
        t = _npclip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
        vx, vy = x - (ax + t * dx), y - (ay + t * dy)
        best = _npmin(best, vx * vx + vy * vy)
    return math.sqrt(best)


@njit(inline="always", **_FLAGS)
def _orient(ux, uy, vx, vy, wx, wy):
    """Twice the signed area of the triangle (u, v, w)."""
    return (vx - ux) * (wy - uy) - (vy - uy) * (wx - ux)


@njit(**_FLAGS)
def _segment_crosses(p, ax, ay, bx, by):
    """Whether a contour edge properly crosses the segment a-b."""
    n = p.shape[0]
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        px, py, qx, qy = p[i, 0], p[i, 1], p[i1, 0], p[i1, 1]
        d1 = _orient(ax, ay, bx, by, px, py)
        d2 = _orient(ax, ay, bx, by, qx, qy)
        d3 = _orient(px, py, qx, qy, ax, ay)
        d4 = _orient(px, py, qx, qy, bx, by)
        if d1 * d2 < 0 and d3 * d4 < 0:
            return True
    return False


# --------------------------------------------------------------------------------------------
# the grooved finger (a finger's own coordinates: s along it from the joint, m along the inward
# face normal; for the groove u = s - a across it and v = w/2 - m, the depth below the face)


@njit(inline="always", **_FLAGS)
def _groove_depth(prm, j):
    """Depth of finger j's groove [m] (0: the straight bar)."""
    return prm[(CK_JAW0 if j == 0 else CK_JAW1) + JW_DEPTH]


@njit(**_FLAGS)
def _groove_shape(prm, j):
    """Finger j's grown groove: ``a`` (centre line), ``vc`` (depth of the cone's apex, the
    bottom arc's centre), ``grow`` (``R_b + rho``), ``sb``, ``cb`` (sine and cosine of the
    half opening angle) and ``ue``, the half-width at which the grown groove meets the core's
    face line ``v = rho`` (the centres of the rounded mouth edges)."""
    base = CK_JAW0 if j == 0 else CK_JAW1
    rho = prm[CK_RHO]
    vc = prm[base + JW_DEPTH] - prm[base + JW_BOTTOM_RADIUS]
    grow = prm[base + JW_BOTTOM_RADIUS] + rho
    half = 0.5 * prm[base + JW_OPENING]
    sb, cb = math.sin(half), math.cos(half)
    # on v = rho the axis height above the apex is h = vc - rho; a flank's offset line
    # |u| cb - h sb = grow holds where the foot on the cone's edge ray is beyond the apex
    # (|u| sb + h cb > 0), else the arc about the apex
    h = vc - rho
    ue = (grow + h * sb) / cb
    if not ue * sb + h * cb > 0.0:
        ue = math.sqrt(max(grow * grow - h * h, 0.0))
    return prm[base + JW_POSITION], vc, grow, sb, cb, ue


@njit(**_FLAGS)
def _cone_distance(u, v, vc, sb, cb):
    """Distance from (u, v) to the solid cone with apex (0, vc), axis towards -v (out of the
    face) and half-angle of sine ``sb``, cosine ``cb`` (a ray for a zero angle)."""
    wu, wv = abs(u), vc - v  # wv: height above the apex along the axis
    if wv >= 0.0 and wv * sb >= wu * cb:
        return 0.0
    if wu * sb + wv * cb <= 0.0:
        return _hypot(wu, wv)  # nearest the apex
    return wu * cb - wv * sb  # nearest the edge ray


@njit(inline="always", **_FLAGS)
def _nearer_segment(px, py, ax, ay, bx, by, best, qx, qy):
    """Nearest point to (px, py) of segment a-b if nearer than ``best``: (best, qx, qy)."""
    dx, dy = bx - ax, by - ay
    den = dx * dx + dy * dy
    t = 0.0 if den == 0.0 else _npclip(((px - ax) * dx + (py - ay) * dy) / den, 0.0, 1.0)
    cx, cy = ax + t * dx, ay + t * dy
    d = _hypot(px - cx, py - cy)
    if d < best:
        return d, cx, cy
    return best, qx, qy


@njit(**_FLAGS)
def _groove_nearest(prm, j, s, m):
    """Nearest point (s, m) of a grooved finger's core ``K`` to the point (s, m) and whether the
    point lies in ``K``; the nearest of ``K``'s boundary pieces for a point outside."""
    rho, ln = prm[CK_RHO], prm[CK_LENGTH]
    hw = prm[CK_HALF_WIDTH]
    core = hw - rho
    a, vc, grow, sb, cb, ue = _groove_shape(prm, j)
    u, v = s - a, hw - m
    in_groove = _cone_distance(u, v, vc, sb, cb) < grow
    qs, qm = _npclip(s, 0.0, ln), _npclip(m, -core, core)
    if not in_groove and qs == s and qm == m:
        return s, m, True
    if not _cone_distance(qs - a, hw - qm, vc, sb, cb) < grow:
        return qs, qm, False  # the core rectangle's nearest point is outside the groove
    # pieces in (u, v): the core's back and ends, its face on either side of the mouth
    back, face = hw + core, rho
    best, bu, bv = math.inf, 0.0, 0.0
    best, bu, bv = _nearer_segment(u, v, -a, back, ln - a, back, best, bu, bv)
    best, bu, bv = _nearer_segment(u, v, -a, face, -a, back, best, bu, bv)
    best, bu, bv = _nearer_segment(u, v, ln - a, face, ln - a, back, best, bu, bv)
    best, bu, bv = _nearer_segment(u, v, -a, face, -ue, face, best, bu, bv)
    best, bu, bv = _nearer_segment(u, v, ue, face, ln - a, face, best, bu, bv)
    # the grown groove's flanks below the face line: the cone's edge rays offset by grow
    tmax = (vc + grow * sb - face) / cb
    if tmax > 0.0:
        for side in (-1.0, 1.0):
            x0, y0 = side * grow * cb, vc + grow * sb
            best, bu, bv = _nearer_segment(u, v, x0, y0, x0 + side * tmax * sb, y0 - tmax * cb,
                                           best, bu, bv)
    # its bottom arc about the apex, between the flanks and above the face line
    lim = 0.5 * math.pi - math.asin(sb)
    lim = min(lim, math.acos(_npclip((face - vc) / grow, -1.0, 1.0)))
    ang = math.atan2(u, v - vc)
    if abs(ang) <= lim:
        rad = _hypot(u, v - vc)
        if abs(rad - grow) < best and rad > 0.0:
            best = abs(rad - grow)
            bu, bv = grow * u / rad, vc + grow * (v - vc) / rad
    for side in (-1.0, 1.0):
        ex, ey = side * grow * math.sin(lim), vc + grow * math.cos(lim)
        d = _hypot(u - ex, v - ey)
        if d < best:
            best, bu, bv = d, ex, ey
    return bu + a, hw - bv, False


# --------------------------------------------------------------------------------------------
# forces and moments


@njit(**_FLAGS)
def _area_forces(prm, p, force):
    """Add the forces of the area energy ``E = kappa t A0 / 2 (ln(A / A0))^2`` of every fan
    triangle (centre, p_i, p_i+1) to ``force``; return the largest |force| on a point [N].

    A folded triangle (``A <= 0``) lies outside the model: its force is NaN, so the verdict
    fails.
    """
    n = p.shape[0]
    cx, cy = prm[CK_CENTRE_X], prm[CK_CENTRE_Y]
    kt, a0 = prm[CK_AREA_STIFF], prm[CK_REST_AREA]
    biggest = 0.0
    for i in range(n):
        i1 = i + 1 if i + 1 < n else 0
        ax, ay = p[i, 0] - cx, p[i, 1] - cy
        bx, by = p[i1, 0] - cx, p[i1, 1] - cy
        area = 0.5 * (ax * by - ay * bx)
        slope = kt * a0 * math.log(area / a0) / area  # NaN for a folded triangle
        # dA/dp_i = (by, -bx) / 2, dA/dp_i+1 = (-ay, ax) / 2
        force[i, 0] -= 0.5 * slope * by
        force[i, 1] += 0.5 * slope * bx
        force[i1, 0] += 0.5 * slope * ay
        force[i1, 1] -= 0.5 * slope * ax
        biggest = _npmax(biggest, 0.5 * abs(slope) * _npmax(_hypot(ax, ay), _hypot(bx, by)))
    return biggest


@njit(**_FLAGS)
def _spring_forces(prm, p, force):
    """Add the radial and contour spring forces to ``force``; return the largest |force| [N].

    Lengths are exact (geometrically nonlinear springs), as in the model.
    """
    n = p.shape[0]
    r, cx, cy = prm[CK_RADIUS], prm[CK_CENTRE_X], prm[CK_CENTRE_Y]
    k_int, k_ext, h = prm[CK_KINT], prm[CK_KEXT], prm[CK_REST_CONTOUR]
    biggest = 0.0
    for i in range(n):
        vx, vy = p[i, 0] - cx, p[i, 1] - cy
        length = _hypot(vx, vy)
        f = k_int * (length - r)
        force[i, 0] -= f * vx / length
        force[i, 1] -= f * vy / length
        # the reference takes Python's max over a list that starts with this first spring
        biggest = abs(f) if i == 0 else _pymax(biggest, abs(f))
        i1 = i + 1 if i + 1 < n else 0
        wx, wy = p[i1, 0] - p[i, 0], p[i1, 1] - p[i, 1]
        length = _hypot(wx, wy)
        f = k_ext * (length - h)
        fx, fy = f * wx / length, f * wy / length
        force[i, 0] += fx
        force[i, 1] += fy
        force[i1, 0] -= fx
        force[i1, 1] -= fy
        biggest = _pymax(biggest, abs(f))
    return biggest


@njit(**_FLAGS)
def _face_contacts(prm, p, face, j, theta, force, acc):
    """Gaps of every point to the body of finger j, and the forces its face contacts carry.

    The body is the bar ``0 <= s <= l``, ``|m| <= w/2`` with its corners rounded to ``rho``: the
    rectangle ``[0, l] x [-(w/2 - rho), w/2 - rho]`` grown by ``rho``, less a jaw groove
    (:func:`_groove_nearest`). A point's force acts along
    the outward normal of the body at the nearest surface point, about which the moment is
    taken.
    """
    jx, jy, ex, ey, nx, ny = _frame(prm, j, theta)
    ln, rho = prm[CK_LENGTH], prm[CK_RHO]
    core = prm[CK_HALF_WIDTH] - rho
    grooved = _groove_depth(prm, j) > 0.0
    for i in range(p.shape[0]):
        rx, ry = p[i, 0] - jx, p[i, 1] - jy
        s = rx * ex + ry * ey
        m = rx * nx + ry * ny
        if grooved:
            ks, km, _ = _groove_nearest(prm, j, s, m)
            ds, dm = s - ks, m - km
        else:
            ds = s - _npclip(s, 0.0, ln)
            dm = m - _npclip(m, -core, core)
        dist = _hypot(ds, dm)
        gap = dist - rho
        acc[_ACC_PEN] = _pymax(acc[_ACC_PEN], -gap)
        lam = face[j, i]
        if lam != 0.0:
            if dist > 0:
                ux, uy = (ds * ex + dm * nx) / dist, (ds * ey + dm * ny) / dist
            else:
                ux, uy = nx, ny  # inside the core: push along the face normal
            acc[_ACC_FMIN] = _pymin(acc[_ACC_FMIN], lam)
            acc[_ACC_GAP] = _pymax(acc[_ACC_GAP], abs(gap))
            force[i, 0] += lam * ux
            force[i, 1] += lam * uy
            # arm from the joint to the touching point of the finger surface
            armx = (p[i, 0] - gap * ux) - jx
            army = (p[i, 1] - gap * uy) - jy
            acc[_ACC_MOMENT + j] += armx * (-lam * uy) - army * (-lam * ux)
            acc[_ACC_SCALE] = _pymax(acc[_ACC_SCALE], abs(lam) * _hypot(armx, army))


@njit(**_FLAGS)
def _corner_contacts(prm, p, corner, j, c, theta, force, acc):
    """Depth of corner c of finger j in the contour, and the forces it bears on the edges.

    Corners: 0 tip and 1 root of the gripping face, 2 tip and 3 root of the back, 4 and 5 the
    rounded mouth edges of a jaw groove (tip side, root side). A corner's force on edge
    ``(k, k+1)`` acts along the shortest segment from the edge to the corner's centre and is
    shared by the two points in proportion to where it bears. A force on the mouth of a
    finger without a groove is a loaded contact at an infinite gap.
    """
    jx, jy, ex, ey, nx, ny = _frame(prm, j, theta)
    rho = prm[CK_RHO]
    if c >= _BAR_CORNERS:
        if not _groove_depth(prm, j) > 0.0:
            for k in range(p.shape[0]):
                if corner[j, c, k] != 0.0:
                    acc[_ACC_GAP] = math.inf
            return
        a, _, _, _, _, ue = _groove_shape(prm, j)
        sc = a + ue if c == _BAR_CORNERS else a - ue
        off = prm[CK_HALF_WIDTH] - rho
    else:
        sc = prm[CK_LENGTH] if c % 2 == 0 else 0.0
        off = (1.0 if c < 2 else -1.0) * (prm[CK_HALF_WIDTH] - rho)
    kx = (jx + sc * ex) + off * nx
    ky = (jy + sc * ey) + off * ny
    depth = _dist_polygon(p, kx, ky)
    depth = rho + depth if _inside(p, kx, ky) else rho - depth
    acc[_ACC_PEN] = _pymax(acc[_ACC_PEN], depth)
    n = p.shape[0]
    armx, army = kx - jx, ky - jy
    for k in range(n):
        lam = corner[j, c, k]
        if lam == 0.0:
            continue
        k1 = k + 1 if k + 1 < n else 0
        ax, ay = p[k, 0], p[k, 1]
        dx, dy = p[k1, 0] - ax, p[k1, 1] - ay
        t = _pymin(1.0, _pymax(0.0, ((kx - ax) * dx + (ky - ay) * dy) / (dx * dx + dy * dy)))
        vx, vy = kx - (ax + t * dx), ky - (ay + t * dy)
        dist = _hypot(vx, vy)
        gap = dist - rho
        ux, uy = (vx / dist, vy / dist) if dist > 0 else (0.0, 0.0)
        acc[_ACC_FMIN] = _pymin(acc[_ACC_FMIN], lam)
        acc[_ACC_GAP] = _pymax(acc[_ACC_GAP], abs(gap))
        w0, w1 = (1 - t) * lam, t * lam
        force[k, 0] -= w0 * ux
        force[k, 1] -= w0 * uy
        force[k1, 0] -= w1 * ux
        force[k1, 1] -= w1 * uy
        acc[_ACC_MOMENT + j] += armx * (lam * uy) - army * (lam * ux)
        acc[_ACC_SCALE] = _pymax(acc[_ACC_SCALE], abs(lam) * _hypot(armx, army))


@njit(**_FLAGS)
def _finger(prm, p, theta, j, face, corner, stop, force, acc):
    """All the terms of finger j: joint moments, face and corner contacts, stop, bar crossing."""
    sign = 1.0 if j == 0 else -1.0  # closing is +z for the right finger, -z for the left
    closing = prm[CK_TORQUE] - prm[CK_KF] * (prm[CK_TH0] - theta)
    acc[_ACC_MOMENT + j] += sign * closing
    acc[_ACC_MOMENT + j] -= sign * stop[j]
    acc[_ACC_SCALE] = _pymax(acc[_ACC_SCALE], abs(closing))
    _face_contacts(prm, p, face, j, theta, force, acc)
    jx, jy, ex, ey, nx, ny = _frame(prm, j, theta)
    ln = prm[CK_LENGTH]
    # the bar's spine: its axis, or for a groove the line midway between the groove's bottom
    # and the back, inside the solid all along (a disk in a deep groove may reach the axis)
    spine = 0.0
    depth = _groove_depth(prm, j)
    if depth > 0.0:
        spine = 0.5 * ((prm[CK_HALF_WIDTH] - depth) - prm[CK_HALF_WIDTH])
    sx, sy = jx + spine * nx, jy + spine * ny
    if _segment_crosses(p, sx, sy, sx + ln * ex, sy + ln * ey):
        # the bar runs right through the disk: points and corners are all outside it
        acc[_ACC_PEN] = _pymax(acc[_ACC_PEN], prm[CK_HALF_WIDTH])
    for c in range(corner.shape[1]):
        _corner_contacts(prm, p, corner, j, c, theta, force, acc)
    if stop[j] != 0.0:
        acc[_ACC_FMIN] = _pymin(acc[_ACC_FMIN], stop[j])
        off = abs(theta - prm[CK_THMIN])
        if off > GAP_TOL:
            # a stop that pushes while the jaws are open: a loaded contact with a gap
            acc[_ACC_GAP] = _pymax(acc[_ACC_GAP], off * prm[CK_RADIUS])


@njit(**_FLAGS)
def _verdict(prm, face, corner, force, spring_max, acc, out):
    """Relative residuals, the accumulated extremes and the failure bits, into ``out``."""
    r = prm[CK_RADIUS]
    # floor: the spring force of a 1e-4 strain, so that an unloaded disk is judged absolutely
    # (FORCE_TOL of it: 1e-12 of a unit strain's force, the solver's own tolerance). Lower, it
    # judged roundoff: on a ring mesh with 40 points the coordinates' rounding (1e-16 of the
    # disk's distance from the origin, over cells r / 20 wide) alone gives strains of 1e-14
    f_floor = 1e-4 * prm[CK_KEXT] * r
    f_face = 0.0
    for j in range(2):
        for i in range(face.shape[1]):
            f_face = _npmax(f_face, abs(face[j, i]))
    f_corner = 0.0
    for j in range(2):
        for c in range(corner.shape[1]):
            for k in range(corner.shape[2]):
                f_corner = _npmax(f_corner, abs(corner[j, c, k]))
    f_ref = _pymax(_pymax(spring_max, f_face), f_floor)
    f_ref = _pymax(f_ref, f_corner)
    m_ref = _pymax(_pymax(acc[_ACC_SCALE], prm[CK_TORQUE]), f_floor * prm[CK_LENGTH])
    f_max = 0.0
    for i in range(force.shape[0]):
        f_max = _npmax(_npmax(f_max, abs(force[i, 0])), abs(force[i, 1]))
    m_max = _npmax(abs(acc[_ACC_MOMENT]), abs(acc[_ACC_MOMENT + 1]))
    f_res, m_res = f_max / f_ref, m_max / m_ref
    pen, gap = acc[_ACC_PEN], acc[_ACC_GAP]
    fmin = 0.0 if acc[_ACC_FMIN] == math.inf else acc[_ACC_FMIN]
    bits = 0
    if not f_res <= FORCE_TOL:  # written so that NaN fails
        bits |= FAIL_FORCE
    if not m_res <= FORCE_TOL:
        bits |= FAIL_MOMENT
    if not pen <= GAP_TOL * r:
        bits |= FAIL_PENETRATION
    if not gap <= GAP_TOL * r:
        bits |= FAIL_GAP
    if fmin < 0:
        bits |= FAIL_NEGATIVE
    out[OUT_PASSED] = 1.0 if bits == 0 else 0.0
    out[OUT_FORCE_RES] = f_res
    out[OUT_MOMENT_RES] = m_res
    out[OUT_PENETRATION] = pen
    out[OUT_CONTACT_GAP] = gap
    out[OUT_MIN_FORCE] = fmin
    out[OUT_REASONS] = float(bits)


# --------------------------------------------------------------------------------------------
# entry points


@njit(cache=True, error_model="numpy")
def check_one(prm, points, angles, face, corner, stop, out):
    """Check one grasp (compiled core of :func:`check_grasp`).

    Parameters
    ----------
    prm : float64[N_CK]
        Problem parameters, laid out by the ``CK_*`` offsets (:func:`check_params`).
    points : float64[N, 2]
        Contour points [m], counter-clockwise.
    angles : float64[2]
        Right and left finger angles [rad].
    face : float64[2, N]
        Normal force of each finger's body on each point [N].
    corner : float64[2, 4, N] or float64[2, 6, N]
        Force of each finger's rounded corners (face tip, face root, back tip, back root, and
        a groove's two mouth edges, tip side and root side) on each contour edge ``(k, k+1)``
        [N].
    stop : float64[2]
        Torques of the closed-jaw stops [N·m].
    out : float64[N_OUT]
        Out: the verdict, laid out by the ``OUT_*`` offsets.
    """
    n = points.shape[0]
    if face.shape[1] != n or corner.shape[2] != n or not _corner_count_ok(corner.shape[1]):
        raise ValueError("check_one: face must be (2, N) and corner (2, 4 or 6, N)")
    force = np.zeros((n, 2))  # net force on each contour point
    acc = np.zeros(_N_ACC)
    acc[_ACC_FMIN] = math.inf
    spring_max = _spring_forces(prm, points, force)
    if prm[CK_AREA_STIFF] > 0.0:
        spring_max = _npmax(spring_max, _area_forces(prm, points, force))
    for j in range(2):
        _finger(prm, points, angles[j], j, face, corner, stop, force, acc)
    _verdict(prm, face, corner, force, spring_max, acc, out)


@njit(**_FLAGS)
def _ring_radius(prm, k):
    """Rest radius of ring k of a ring mesh [m]: from the hub (k = 0) to the rim, geometric or
    evenly spaced."""
    m = prm[CK_RINGS]
    r, hub = prm[CK_RADIUS], prm[CK_HUB]
    if m == 1:
        return 0.0 if k == 0 else r  # the fan: centre and contour
    if prm[CK_SPACING] == 1.0:
        return hub + (r - hub) * k / m
    return r * (hub / r) ** ((m - k) / m)


@njit(**_FLAGS)
def _ring_corner(prm, points, interior, rest_rim, k, i, rest):
    """Point ``(k, i)`` of a ring mesh (N points a ring, ring M the contour, ring 0 the fixed
    hub): its rest or current position [m], and its row in the force array (-1: fixed)."""
    n = points.shape[0]
    m = int(prm[CK_RINGS])
    i %= n
    ang = prm[CK_PHASE] + 2 * math.pi * i / n
    rho = _ring_radius(prm, k)
    if rest or k == 0:
        row = -1 if k == 0 else (i if k == m else n + (k - 1) * n + i)
        cx, cy = prm[CK_CENTRE_X], prm[CK_CENTRE_Y]
        if prm[CK_SHAPE] != 0.0:
            # an outline: the mesh scaled about the centroid onto its contour point i
            return cx + rho * rest_rim[i, 0], cy + rho * rest_rim[i, 1], row
        return cx + rho * math.cos(ang), cy + rho * math.sin(ang), row
    if k == m:
        return points[i, 0], points[i, 1], i
    row = (k - 1) * n + i
    return interior[row, 0], interior[row, 1], n + row


@njit(**_FLAGS)
def _edge_force(prm, force, ax, ay, bx, by, ra, rb, stiff, rest):
    """Spring of stiffness ``stiff`` and rest length ``rest`` between a (row ra) and b (row
    rb); returns |force|."""
    wx, wy = bx - ax, by - ay
    length = _hypot(wx, wy)
    f = stiff * (length - rest)
    fx, fy = f * wx / length, f * wy / length
    if ra >= 0:
        force[ra, 0] += fx
        force[ra, 1] += fy
    if rb >= 0:
        force[rb, 0] -= fx
        force[rb, 1] -= fy
    return abs(f)


@njit(**_FLAGS)
def _triangle_edge(prm, force, m, ka, kb, q, p, ra, rb, a0):
    """Triangle's share ``s E t A0 / L0^2`` of the spring on its edge a -> b (the area rule,
    summed over the triangles sharing an edge, is this sum); ``q``/``p``: rest/current ends."""
    rest = _hypot(q[2] - q[0], q[3] - q[1])
    stiff = prm[CK_UNIT] * a0 / (rest * rest)
    if ka == m and kb == m:
        stiff *= prm[CK_CRATIO]
    return _edge_force(prm, force, p[0], p[1], p[2], p[3], ra, rb, stiff, rest)


@njit(**_FLAGS)
def _area_push(force, row, slope, gx, gy):
    """Force ``-E'(A) dA/dp`` of the area energy on a corner (row < 0: fixed); its size."""
    if row >= 0:
        force[row, 0] -= slope * gx
        force[row, 1] -= slope * gy
    return abs(slope) * _hypot(gx, gy)


@njit(**_FLAGS)
def _cst_forces(prm, force, q, p, ra, rb, rc, a0):
    """Forces of a constant-strain neo-Hookean triangle (energy ``A0 t W(F)``, ``W = mu/2
    (I1 - 2) - mu ln J + lam/2 (ln J)^2``): with ``F = Ds Dm^-1`` the gradient over the edge
    matrix is ``A0 P Dm^-T``, ``P = mu F + (lam ln J - mu) F^-T``. Returns the largest force."""
    dm00, dm01, dm10, dm11 = q[2] - q[0], q[4] - q[0], q[3] - q[1], q[5] - q[1]
    det_m = dm00 * dm11 - dm01 * dm10
    i00, i01, i10, i11 = dm11 / det_m, -dm01 / det_m, -dm10 / det_m, dm00 / det_m
    ds00, ds01, ds10, ds11 = p[2] - p[0], p[4] - p[0], p[3] - p[1], p[5] - p[1]
    f00, f01 = ds00 * i00 + ds01 * i10, ds00 * i01 + ds01 * i11
    f10, f11 = ds10 * i00 + ds11 * i10, ds10 * i01 + ds11 * i11
    jac = f00 * f11 - f01 * f10
    mu, lam = prm[CK_MU], prm[CK_LAM]
    c = (lam * math.log(jac) - mu) / jac  # NaN for an inverted triangle: the check fails
    p00, p01, p10, p11 = mu * f00 + c * f11, mu * f01 - c * f10, mu * f10 - c * f01, \
        mu * f11 + c * f00
    # G = A0 P Dm^-T: column 0 acts on corner b, column 1 on c, minus their sum on a
    g00, g01 = a0 * (p00 * i00 + p01 * i01), a0 * (p00 * i10 + p01 * i11)
    g10, g11 = a0 * (p10 * i00 + p11 * i01), a0 * (p10 * i10 + p11 * i11)
    big = 0.0
    for row, gx, gy in ((ra, -(g00 + g01), -(g10 + g11)), (rb, g00, g10), (rc, g01, g11)):
        if row >= 0:
            force[row, 0] -= gx
            force[row, 1] -= gy
        big = _npmax(big, _hypot(gx, gy))
    return big


@njit(**_FLAGS)
def _mesh_triangle(prm, points, interior, rest_rim, ka, ia, kb, ib, kc, ic, force):
    """Forces of one triangle (corners (ring, index) counter-clockwise) of a ring mesh: its
    share of its three edges' springs and its area energy. Returns the largest force [N]."""
    m = int(prm[CK_RINGS])
    # rest/current as runtime flags, not literals: _ring_corner then compiles once
    rest, now = m > 0, m < 0
    qax, qay, _ = _ring_corner(prm, points, interior, rest_rim, ka, ia, rest)
    qbx, qby, _ = _ring_corner(prm, points, interior, rest_rim, kb, ib, rest)
    qcx, qcy, _ = _ring_corner(prm, points, interior, rest_rim, kc, ic, rest)
    pax, pay, ra = _ring_corner(prm, points, interior, rest_rim, ka, ia, now)
    pbx, pby, rb = _ring_corner(prm, points, interior, rest_rim, kb, ib, now)
    pcx, pcy, rc = _ring_corner(prm, points, interior, rest_rim, kc, ic, now)
    a0 = 0.5 * ((qbx - qax) * (qcy - qay) - (qcx - qax) * (qby - qay))
    if prm[CK_MU] > 0.0:
        return _cst_forces(prm, force, (qax, qay, qbx, qby, qcx, qcy),
                           (pax, pay, pbx, pby, pcx, pcy), ra, rb, rc, a0)
    big = _triangle_edge(prm, force, m, ka, kb, (qax, qay, qbx, qby), (pax, pay, pbx, pby),
                         ra, rb, a0)
    big = _npmax(big, _triangle_edge(prm, force, m, kb, kc, (qbx, qby, qcx, qcy),
                                     (pbx, pby, pcx, pcy), rb, rc, a0))
    big = _npmax(big, _triangle_edge(prm, force, m, kc, ka, (qcx, qcy, qax, qay),
                                     (pcx, pcy, pax, pay), rc, ra, a0))
    if prm[CK_AREA_STIFF] > 0.0:
        area = 0.5 * ((pbx - pax) * (pcy - pay) - (pcx - pax) * (pby - pay))
        slope = prm[CK_AREA_STIFF] * a0 * math.log(area / a0) / area  # NaN when folded
        # dA/dp_a = (y_b - y_c, x_c - x_b) / 2, cyclically
        big = _npmax(big, _area_push(force, ra, slope, 0.5 * (pby - pcy), 0.5 * (pcx - pbx)))
        big = _npmax(big, _area_push(force, rb, slope, 0.5 * (pcy - pay), 0.5 * (pax - pcx)))
        big = _npmax(big, _area_push(force, rc, slope, 0.5 * (pay - pby), 0.5 * (pbx - pax)))
    return big


@njit(**_FLAGS)
def _quad_forces(prm, points, interior, rest_rim, k, i, force):
    """Forces of the volumetric energy ``kappa A0 / 2 (ln(A / A0))^2`` of the quad between
    rings k - 1 and k and angles i, i + 1 (the nh-quad element), ``kappa = prm[CK_QUAD]``. Its
    corners counter-clockwise are a = (k - 1, i), b = (k, i), c = (k, i + 1), d = (k - 1, i + 1)
    and its area the shoelace sum, whose gradient over a corner is (y_next - y_prev,
    x_prev - x_next) / 2. Returns the largest force [N]."""
    rest, now = k > 0, k < 0  # runtime flags (see _mesh_triangle)
    qax, qay, _ = _ring_corner(prm, points, interior, rest_rim, k - 1, i, rest)
    qbx, qby, _ = _ring_corner(prm, points, interior, rest_rim, k, i, rest)
    qcx, qcy, _ = _ring_corner(prm, points, interior, rest_rim, k, i + 1, rest)
    qdx, qdy, _ = _ring_corner(prm, points, interior, rest_rim, k - 1, i + 1, rest)
    pax, pay, ra = _ring_corner(prm, points, interior, rest_rim, k - 1, i, now)
    pbx, pby, rb = _ring_corner(prm, points, interior, rest_rim, k, i, now)
    pcx, pcy, rc = _ring_corner(prm, points, interior, rest_rim, k, i + 1, now)
    pdx, pdy, rd = _ring_corner(prm, points, interior, rest_rim, k - 1, i + 1, now)
    a0 = 0.5 * ((qax * qby - qbx * qay) + (qbx * qcy - qcx * qby) + (qcx * qdy - qdx * qcy)
                + (qdx * qay - qax * qdy))
    area = 0.5 * ((pax * pby - pbx * pay) + (pbx * pcy - pcx * pby) + (pcx * pdy - pdx * pcy)
                  + (pdx * pay - pax * pdy))
    slope = prm[CK_QUAD] * a0 * math.log(area / a0) / area  # NaN when folded
    big = _area_push(force, ra, slope, 0.5 * (pby - pdy), 0.5 * (pdx - pbx))
    big = _npmax(big, _area_push(force, rb, slope, 0.5 * (pcy - pay), 0.5 * (pax - pcx)))
    big = _npmax(big, _area_push(force, rc, slope, 0.5 * (pdy - pby), 0.5 * (pbx - pdx)))
    return _npmax(big, _area_push(force, rd, slope, 0.5 * (pay - pcy), 0.5 * (pcx - pax)))


@njit(**_FLAGS)
def _ring_forces(prm, points, interior, rest_rim, force):
    """Spring and area forces of a ring mesh: between rings k - 1 and k each quad (i, i + 1)
    is cut by the diagonal (k - 1, i) - (k, i + 1) for even i and (k - 1, i + 1) - (k, i) for
    odd i. Returns the largest force on a point [N]."""
    n = points.shape[0]
    m = int(prm[CK_RINGS])
    big = 0.0
    if m == 1:
        # the fan: triangles (centre, p_i, p_i+1); ring numbers as runtime values (a literal
        # 0 or 1 would compile _mesh_triangle again)
        centre, rim = m - 1, m
        for i in range(n):
            big = _npmax(big, _mesh_triangle(prm, points, interior, rest_rim, centre, i, rim,
                                             i, rim, i + 1, force))
        return big
    for k in range(1, m + 1):
        for i in range(n):
            if i % 2 == 0:
                big = _npmax(big, _mesh_triangle(prm, points, interior, rest_rim, k - 1, i, k,
                                                 i, k, i + 1, force))
                big = _npmax(big, _mesh_triangle(prm, points, interior, rest_rim, k - 1, i, k,
                                                 i + 1, k - 1, i + 1, force))
            else:
                big = _npmax(big, _mesh_triangle(prm, points, interior, rest_rim, k - 1, i, k,
                                                 i, k - 1, i + 1, force))
                big = _npmax(big, _mesh_triangle(prm, points, interior, rest_rim, k, i, k,
                                                 i + 1, k - 1, i + 1, force))
            if prm[CK_QUAD] > 0.0:
                big = _npmax(big, _quad_forces(prm, points, interior, rest_rim, k, i, force))
    return big


@njit(cache=True, error_model="numpy")
def check_mesh_one(prm, points, interior, angles, face, corner, stop, out, outline):
    """:func:`check_one` for a ring mesh (``prm[CK_RINGS] >= 2``) or constant-strain triangles
    (``prm[CK_MU] > 0``): equilibrium of every free point, the contour's contacts as for the
    fan. ``interior``: the interior points [m], ``((M - 1) N, 2)``, ring by ring from the hub
    out (empty for the fan). ``outline``: where ``prm[CK_SHAPE]`` is not 0, the object's
    B-spline coefficients of ``r(phi) / r`` (:mod:`envs.model.outline`; read for an outline
    only)."""
    n = points.shape[0]
    if face.shape[1] != n or corner.shape[2] != n or not _corner_count_ok(corner.shape[1]):
        raise ValueError("check_mesh_one: face must be (2, N) and corner (2, 4 or 6, N)")
    if interior.shape[0] != (int(prm[CK_RINGS]) - 1) * n:
        raise ValueError("check_mesh_one: interior must hold (M - 1) N points")
    force = np.zeros((n + interior.shape[0], 2))
    acc = np.zeros(_N_ACC)
    acc[_ACC_FMIN] = math.inf
    # an outline's contour points at rest, per unit of ring radius (the model's definition of
    # the outline: evenly spaced by arc length, envs.model.outline)
    rest_rim = np.zeros((n, 2))
    if prm[CK_SHAPE] != 0.0:
        flat = np.empty(2 * n)
        outline_contour_into(outline, 0, prm[CK_ORIENT], n, flat, 0)
        for i in range(n):
            rest_rim[i, 0] = flat[2 * i]
            rest_rim[i, 1] = flat[2 * i + 1]
    spring_max = _ring_forces(prm, points, interior, rest_rim, force)
    contour = force[:n]
    for j in range(2):
        _finger(prm, points, angles[j], j, face, corner, stop, contour, acc)
    _verdict(prm, face, corner, force, spring_max, acc, out)


@njit(cache=True, error_model="numpy", nogil=True)
def _check_rows(start, stop_row, prms, points, angles, face, corner, stop, out):
    for b in range(start, stop_row):
        check_one(prms[b], points[b], angles[b], face[b], corner[b], stop[b], out[b])


def check_batch(prms, points, angles, face, corner, stop, out):
    """:func:`check_one` over a batch (first axis of every argument), rows on threads
    (:func:`envs.parallel.run_rows`).

    Shapes: ``prms`` (B, N_CK), ``points`` (B, N, 2), ``angles`` (B, 2), ``face`` (B, 2, N),
    ``corner`` (B, 2, 4 or 6, N), ``stop`` (B, 2), ``out`` (B, N_OUT); all float64.
    """
    from envs.parallel import run_rows  # threads only: no physics of the solver

    nb, n = prms.shape[0], points.shape[1]
    for size in (points.shape[0], angles.shape[0], face.shape[0], corner.shape[0],
                 stop.shape[0], out.shape[0]):
        if size != nb:
            raise ValueError("check_batch: every argument needs the same batch size")
    if face.shape[2] != n or corner.shape[3] != n or not _corner_count_ok(corner.shape[2]):
        raise ValueError("check_batch: face must be (B, 2, N) and corner (B, 2, 4 or 6, N)")
    run_rows(_check_rows, nb, prms, points, angles, face, corner, stop, out)


def check_params(scene, torque_nm: float, n_triangles: int, stiffness_rule: str,
                 n_rings: int = 1, element: str = "spring") -> np.ndarray:
    """Pack a problem into the parameter vector of :func:`check_one`.

    Parameters
    ----------
    scene : envs.scene.Scene
        Gripper and disk.
    torque_nm
        Actuation torque ``T_a`` [N·m].
    n_triangles
        Number of contour points ``N`` (sets the spring stiffnesses and the rest contour length).
    stiffness_rule
        Stiffness rule of the model (``"van_gelder"`` or ``"cst_fit"``).
    n_rings
        Rings of the point mesh (1: the fan; ring meshes are checked by
        :func:`check_mesh_one`).
    element
        ``"spring"``, ``"cst"`` (constant-strain neo-Hookean triangles) or ``"nhquad"``
        (those triangles without their volumetric term, which acts per quad; even rings).

    Returns
    -------
    numpy.ndarray
        float64[N_CK].
    """
    g, d = scene.gripper, scene.disk
    r = float(d.radius_m)
    n = int(n_triangles)
    k_unit = d.stiffness_scale * d.youngs_modulus_pa * d.thickness_m
    unit = _unit_stiffness(n, r, stiffness_rule, float(d.poisson_ratio))
    k_int, k_ext = (k * k_unit for k in unit)
    k_ext *= getattr(d, "contour_stiffness_ratio", 1.0)
    # filled as a list (cheaper than numpy item assignment: this runs once per check)
    vals = [0.0] * N_CK
    vals[CK_RADIUS] = r
    vals[CK_CENTRE_X] = d.offset_x_m  # the centre sits at (x_c, d_1 + r)
    vals[CK_CENTRE_Y] = d.distance_m + r
    vals[CK_JOINT_OFFSET] = g.joint_offset_m
    vals[CK_LENGTH] = g.finger_length_m
    vals[CK_HALF_WIDTH] = g.finger_width_m / 2
    vals[CK_RHO] = _rounding(g.finger_width_m, r)
    vals[CK_KF] = g.torsion_stiffness_nm_per_rad
    vals[CK_TH0] = g.rest_angle_rad
    vals[CK_THMIN] = _closed_angle(g.joint_offset_m, g.finger_length_m, vals[CK_HALF_WIDTH])
    vals[CK_TORQUE] = float(torque_nm)
    vals[CK_KINT] = k_int
    vals[CK_KEXT] = k_ext
    vals[CK_REST_CONTOUR] = 2 * r * math.sin(math.pi / n)
    # area energy (docs/model.md): kappa = c_A K, K the plane-strain bulk modulus lambda + mu
    nu = float(d.poisson_ratio)
    bulk = d.youngs_modulus_pa / (2 * (1 + nu) * (1 - 2 * nu))
    vals[CK_AREA_STIFF] = getattr(d, "area_stiffness_scale", 0.0) * bulk * d.thickness_m
    vals[CK_REST_AREA] = 0.5 * r * r * math.sin(2 * math.pi / n)
    if getattr(d, "outline", None) is not None:
        vals[CK_CENTRE_Y] = float(d.center_m[1])
        vals[CK_SHAPE] = 1.0
        vals[CK_ORIENT] = float(d.orientation_rad)
    vals[CK_RINGS] = float(n_rings)
    vals[CK_HUB] = 0.1 * r  # the ring meshes' rigid hub (envs.model.rings.HUB_RADIUS)
    vals[CK_UNIT] = k_unit
    vals[CK_CRATIO] = getattr(d, "contour_stiffness_ratio", 1.0)
    vals[CK_PHASE] = math.pi / 2
    if element in ("cst", "nhquad"):
        vals[CK_MU] = k_unit / (2 * (1 + nu))
        vals[CK_LAM] = k_unit * nu / ((1 + nu) * (1 - 2 * nu))
    if element == "nhquad":
        vals[CK_QUAD], vals[CK_LAM] = vals[CK_LAM], 0.0
        vals[CK_SPACING] = 1.0
    for base, jaw in zip((CK_JAW0, CK_JAW1), g.jaws, strict=True):
        vals[base + JW_DEPTH] = jaw.depth_m
        vals[base + JW_BOTTOM_RADIUS] = jaw.bottom_radius_m
        vals[base + JW_OPENING] = jaw.opening_angle_rad
        vals[base + JW_POSITION] = jaw.position_m
    return np.array(vals, dtype=np.float64)



@functools.cache
def _model_rules():
    """The model's ``spring_stiffness`` and ``corner_radius`` functions.

    They define the model being checked (the stiffness rule and the corner rounding), not how
    it is solved, so the check takes them from the model as the reference check does. They live
    in :mod:`envs.model`.
    """
    from .model.geometry import corner_radius
    from .model.stiffness import spring_stiffness

    return spring_stiffness, corner_radius


@functools.lru_cache(maxsize=1024)
def _unit_stiffness(n: int, r: float, rule: str, poisson_ratio: float) -> tuple[float, float]:
    """The model's spring stiffnesses per unit ``s E t``, memoized (the rule validates its
    inputs on every call, and the ``cst_fit`` rule solves a small least-squares problem)."""
    return _model_rules()[0](n, r, rule, poisson_ratio)


@functools.lru_cache(maxsize=1024)
def _rounding(finger_width_m: float, radius_m: float) -> float:
    """The model's rounding radius of the finger end corners [m], memoized."""
    return float(_model_rules()[1](finger_width_m, radius_m))


def _closed_angle(joint_offset_m: float, length_m: float, half_width_m: float) -> float:
    """Finger angle at which the gripping-face tip reaches the symmetry axis [rad].

    The joint stop of closed jaws: the root in (-pi/2, 0] of
    ``d_3 + l sin(theta) - (w/2) cos(theta) = 0``. With ``l sin t - hw cos t = R sin(t - phi)``,
    ``R = hypot(l, hw)`` and ``phi = atan2(hw, l)``.
    """
    rr = math.hypot(length_m, half_width_m)
    return math.atan2(half_width_m, length_m) - math.asin(min(1.0, joint_offset_m / rr))


_REASONS = (
    (FAIL_FORCE, lambda o: f"force residual {o[OUT_FORCE_RES]:.2e} > {FORCE_TOL:g}"),
    (FAIL_MOMENT, lambda o: f"moment residual {o[OUT_MOMENT_RES]:.2e} > {FORCE_TOL:g}"),
    (FAIL_PENETRATION, lambda o: f"penetration {o[OUT_PENETRATION]:.2e} m > {GAP_TOL:g} r"),
    (FAIL_GAP,
     lambda o: f"loaded contact with gap {o[OUT_CONTACT_GAP]:.2e} m > {GAP_TOL:g} r"),
    (FAIL_NEGATIVE, lambda o: f"negative contact force {o[OUT_MIN_FORCE]:.2e} N"),
)


def report_from_output(out: np.ndarray) -> KKTReport:
    """Turn an output vector of :func:`check_one` into a :class:`KKTReport`."""
    bits = int(out[OUT_REASONS])
    reasons = [text(out) for bit, text in _REASONS if bits & bit]
    return KKTReport(
        passed=not reasons,
        force_residual_rel=float(out[OUT_FORCE_RES]),
        moment_residual_rel=float(out[OUT_MOMENT_RES]),
        max_penetration_m=float(out[OUT_PENETRATION]),
        max_contact_gap_m=float(out[OUT_CONTACT_GAP]),
        min_contact_force_n=float(out[OUT_MIN_FORCE]),
        reason="; ".join(reasons) if reasons else "ok",
    )


def _as_f64(name: str, value, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a C-contiguous float64 array of the given shape (ValueError otherwise)."""
    arr = np.ascontiguousarray(value, dtype=np.float64)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def check_grasp(
    scene,
    torque_nm: float,
    n_triangles: int,
    stiffness_rule: str,
    points_m: np.ndarray,
    jaw_angles_rad: tuple[float, float],
    face_forces_n: np.ndarray,
    corner_forces_n: np.ndarray,
    stop_torques_nm: np.ndarray,
) -> KKTReport:
    """Check equilibrium and contact conditions of a grasp (compiled reference check).

    Parameters
    ----------
    scene, torque_nm, n_triangles, stiffness_rule
        The problem that was solved. As in the reference, the number of points is taken from
        ``points_m``; ``n_triangles`` is accepted for the same signature.
    points_m
        Contour points [m], shape (N, 2).
    jaw_angles_rad
        Right and left finger angles [rad].
    face_forces_n
        Normal force of each finger face on each point [N], shape (2, N).
    corner_forces_n
        Force of each finger's rounded corners (tip and root of the gripping face, tip and root
        of the back of the bar, then a jaw groove's two mouth edges) on each contour edge
        ``(k, k+1)`` [N], shape (2, 4, N) or (2, 6, N).
    stop_torques_nm
        Torques of the closed-jaw stops [N·m], (2,).

    Returns
    -------
    KKTReport
        ``passed`` when the relative force and moment residuals are below :data:`FORCE_TOL`,
        the gaps satisfy :data:`GAP_TOL` and all contact forces are non-negative.

    Notes
    -----
    Every input of any float dtype is converted to float64 first, so float32 arrays or numpy
    scalars give the same answer as the same values passed as Python floats.
    """
    points = np.ascontiguousarray(points_m, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2:
        raise ValueError(f"points_m must have shape (N, 2), got {points.shape}")
    n = points.shape[0]
    corner = np.ascontiguousarray(corner_forces_n, dtype=np.float64)
    if corner.shape not in ((2, _BAR_CORNERS, n), (2, _ALL_CORNERS, n)):
        raise ValueError(f"corner_forces_n must have shape (2, 4, {n}) or (2, 6, {n}), "
                         f"got {corner.shape}")
    face = _as_f64("face_forces_n", face_forces_n, (2, n))
    angles = _as_f64("jaw_angles_rad", jaw_angles_rad, (2,))
    stop = _as_f64("stop_torques_nm", stop_torques_nm, (2,))
    prm = check_params(scene, float(torque_nm), n, stiffness_rule)
    out = np.empty(N_OUT)
    check_one(prm, points, angles, face, corner, stop, out)
    return report_from_output(out)
