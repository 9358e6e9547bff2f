"""Jaw profiles: the cutout in a finger's gripping face (a cradle, a V-groove, or between).

A finger is a bar of length ``l`` and width ``w`` whose gripping face, ``w/2`` from its axis,
may carry a groove: a *rounded V* of depth ``h`` (below the face), bottom radius ``R_b``, full
opening angle ``phi`` between its flanks, centred ``a`` along the finger from the joint. Its two
limits are the shapes gripper designers cut:

* the **cradle**, a circular arc of radius ``R`` (``R_b = R``, ``phi = 0``, ``h <= R``): the arc
  reaches the face before any flank begins, so no flank is left;
* the **V-groove** (``R_b = 0``): two straight flanks meeting at a sharp bottom.

The straight bar is the groove of depth 0. The finger's solid is the bar minus the groove, its
convex edges (the bar's end corners and the groove's two mouth edges) rounded with the corner
radius ``rho`` of :data:`envs.model.defaults.CORNER_ROUNDING`, so the gap to it is continuous.

How the gap is computed (one definition for both fidelities; the independent check of
:mod:`envs.check` keeps its own copy). Rounding the convex edges of a solid ``S`` by ``rho`` is
its opening ``(S - rho) + rho`` (erode, then dilate): the solid is the set within ``rho`` of its
*core* ``K = B' \\ G'``, with ``B'`` the bar shrunk by ``rho`` (the core rectangle of the
straight bar) and ``G'`` the groove grown by ``rho`` (a rounded V of bottom radius ``R_b + rho``
with the same centre and flank angle). The gap of a point is its distance to ``K`` minus
``rho``. ``K``'s boundary near the groove is the grown groove's wall below the core face and the
two *mouth corners* ``E`` where that wall meets the core face: the centres of the rounded mouth
edges, which the solver also treats as corners against the contour's edges.

Coordinates: ``s`` along the finger from its joint, ``m`` along the gripping face's inward
normal (the face at ``m = w/2``); for the groove ``u = s - a`` and ``v = w/2 - m`` (depth below
the face, into the finger). The scaled solver keeps per finger the :data:`GROOVE_FIELDS` of
:func:`pack_groove` (lengths in units of the disk radius).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from numba import njit

from ..validation import check_range
from .layout import (
    C_MOUTH_TIP,
    G_CENTRE,
    G_COS,
    G_DEPTH,
    G_MOUTH,
    G_POSITION,
    G_RADIUS,
    G_SIN,
    N_BAR_CORNERS,
    N_GROOVE,
)

__all__ = [
    "MAX_OPENING_RAD",
    "groove_mouth",
    "JawProfile",
    "STRAIGHT",
    "GROOVE_FIELDS",
    "G_POSITION",
    "G_DEPTH",
    "G_CENTRE",
    "G_RADIUS",
    "G_COS",
    "G_SIN",
    "G_MOUTH",
    "N_GROOVE",
    "pack_groove",
    "jaw_gap",
    "jaw_row",
    "jaws_of_row",
    "JAW_FIELDS",
    "LEFT_JAW_FIELDS",
    "DESIGN_WIDTHS",
    "mouth_half_width_m",
    "MAX_DEPTH_OF_WIDTH",
    "corner_centre_local",
]

# the scaled groove of one finger (pack_groove, layout G_* of envs.model.layout), lengths in
# the unit of the caller
GROOVE_FIELDS = ("position", "depth", "centre_depth", "grown_radius", "cos_half_opening",
                 "sin_half_opening", "mouth_half_width")

# a groove may cut at most this share of the finger's width (the rest is the jaw's back wall)
MAX_DEPTH_OF_WIDTH = 0.75
# largest full opening angle of a V [rad]: at 180 deg its flanks would lie in the face
MAX_OPENING_RAD = math.radians(170.0)


@dataclass(frozen=True)
class JawProfile:
    """The groove cut into one finger's gripping face, SI units.

    Parameters
    ----------
    depth_m
        Depth ``h`` of the groove below the gripping face [m]; 0 is the straight bar (the
        other fields are then ignored).
    bottom_radius_m
        Radius ``R_b`` of the groove's rounded bottom [m]: the cradle's radius, 0 for a sharp
        V-groove. A pure cradle needs ``depth_m <= bottom_radius_m``.
    opening_angle_rad
        Full angle ``phi`` between the groove's flanks [rad], in [0, 170 deg]: 0 for a cradle
        (whose arc reaches the face before any flank begins).
    position_m
        Distance ``a`` of the groove's centre line from the joint, along the finger [m].

    The groove must lie within the gripping face and keep a back wall: checked against the
    finger by :meth:`check_fits` (the gripper calls it).
    """

    depth_m: float = 0.0
    bottom_radius_m: float = 0.0
    opening_angle_rad: float = 0.0
    position_m: float = 0.0

    def __post_init__(self) -> None:
        check_range("depth_m", self.depth_m, 0.0, math.inf)
        check_range("bottom_radius_m", self.bottom_radius_m, 0.0, math.inf)
        check_range("opening_angle_rad", self.opening_angle_rad, 0.0, MAX_OPENING_RAD)
        check_range("position_m", self.position_m, 0.0, math.inf)
        for name in ("depth_m", "bottom_radius_m", "opening_angle_rad", "position_m"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if self.depth_m > 0.0:
            if self.bottom_radius_m == 0.0 and self.opening_angle_rad == 0.0:
                raise ValueError("a groove with depth_m > 0 needs bottom_radius_m > 0 (a cradle) "
                                 "or opening_angle_rad > 0 (a V-groove)")
            if self.opening_angle_rad == 0.0 and self.depth_m > self.bottom_radius_m:
                raise ValueError(
                    f"a cradle (opening_angle_rad = 0) needs depth_m = {self.depth_m!r} <= "
                    f"bottom_radius_m = {self.bottom_radius_m!r} (deeper would undercut)")

    @classmethod
    def cradle(cls, radius_m: float, depth_m: float, position_m: float) -> JawProfile:
        """A circular-arc cradle of radius ``radius_m`` and depth ``depth_m <= radius_m``
        centred ``position_m`` from the joint [m]."""
        return cls(depth_m, radius_m, 0.0, position_m)

    @classmethod
    def vee(cls, opening_angle_rad: float, depth_m: float, position_m: float) -> JawProfile:
        """A sharp V-groove of full opening angle ``opening_angle_rad`` and depth ``depth_m``
        centred ``position_m`` from the joint."""
        return cls(depth_m, 0.0, opening_angle_rad, position_m)

    @property
    def kind(self) -> str:
        """``"straight"``, ``"cradle"``, ``"vee"`` or ``"rounded vee"``."""
        if self.depth_m == 0.0:
            return "straight"
        if self.bottom_radius_m == 0.0:
            return "vee"
        if self.opening_angle_rad == 0.0 or _arc_reaches_face(
                self.depth_m, self.bottom_radius_m, self.opening_angle_rad):
            return "cradle"
        return "rounded vee"

    @property
    def mouth_half_width_m(self) -> float:
        """Half-width of the groove's mouth in the gripping face (sharp edges) [m]."""
        return mouth_half_width_m(self.depth_m, self.bottom_radius_m, self.opening_angle_rad)

    def check_fits(self, finger_length_m: float, finger_width_m: float,
                   rounding_m: float = 0.0) -> None:
        """Raise ``ValueError`` unless the groove lies within the gripping face (its mouth
        between the joint end and the tip, rounded edges included) and at most
        :data:`MAX_DEPTH_OF_WIDTH` of the finger's width deep."""
        if self.depth_m == 0.0:
            return
        limit = MAX_DEPTH_OF_WIDTH * finger_width_m
        if self.depth_m > limit:
            raise ValueError(f"jaw depth_m = {self.depth_m!r} must be at most "
                             f"{MAX_DEPTH_OF_WIDTH} x finger_width_m = {limit!r}")
        half = self.mouth_half_width_m + rounding_m
        lo, hi = half, finger_length_m - half
        if not lo <= self.position_m <= hi:
            raise ValueError(
                f"jaw position_m = {self.position_m!r} must be within [{lo!r}, {hi!r}] so that "
                f"the groove's mouth (half-width {self.mouth_half_width_m!r} m) lies on the "
                f"gripping face of a finger of length {finger_length_m!r} m")


STRAIGHT = JawProfile()


# the jaw columns a design row may carry after the six of envs.scene.DESIGN_FIELDS: none (straight
# bars, 6 wide), JAW_FIELDS (both fingers alike, 10 wide) or both tuples (14 wide: the right
# finger's, then the left finger's), each in the J_* order of envs.model.layout
JAW_FIELDS = ("jaw_depth_m", "jaw_bottom_radius_m", "jaw_opening_angle_rad", "jaw_position_m")
LEFT_JAW_FIELDS = tuple("left_" + name for name in JAW_FIELDS)
DESIGN_WIDTHS = (6, 6 + len(JAW_FIELDS), 6 + 2 * len(JAW_FIELDS))


def jaws_of_row(row) -> tuple[JawProfile, JawProfile | None]:
    """The jaw (both fingers, or the right one's) and the left finger's jaw (``None``: the
    same) of a design row 6, 10 or 14 wide (see :data:`JAW_FIELDS`); ``ValueError`` for
    another width or a groove out of range."""
    values = [float(v) for v in row]
    if len(values) not in DESIGN_WIDTHS:
        raise ValueError(f"a design row has {DESIGN_WIDTHS} values, got {len(values)}")
    jaws = [JawProfile(*values[k:k + 4]) for k in range(6, len(values), 4)]
    return (jaws[0] if jaws else STRAIGHT), (jaws[1] if len(jaws) > 1 else None)


def jaw_row(jaw: JawProfile) -> tuple[float, float, float, float]:
    """A jaw profile as its scene-row slots, in the ``J_*`` order of :mod:`envs.model.layout`
    (depth, bottom radius, opening angle, position)."""
    return jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m


def _arc_reaches_face(depth, radius, opening):
    """Whether a rounded V's bottom arc meets the face before its flanks begin."""
    return radius * (1.0 - math.sin(opening / 2)) >= depth


@njit(cache=True, error_model="numpy", _nrt=False)
def groove_mouth(depth, centre, radius, cb, sb, level):
    """Half-width ``u > 0`` at which a rounded V (centre depth ``centre``, bottom radius
    ``radius``, flank half-angle of cosine ``cb`` and sine ``sb``) meets the depth ``level``."""
    wv = level - centre
    if wv >= 0.0:
        ua = math.sqrt(max(radius * radius - wv * wv, 0.0))
        if wv * cb >= ua * sb:
            return ua
    return (radius - sb * wv) / cb


def mouth_half_width_m(depth_m: float, bottom_radius_m: float, opening_angle_rad: float
                       ) -> float:
    """Half-width of a groove's mouth in the face (sharp edges) [m]; 0 for depth 0."""
    if depth_m <= 0.0:
        return 0.0
    half = opening_angle_rad / 2
    return float(groove_mouth(depth_m, depth_m - bottom_radius_m, bottom_radius_m, math.cos(half),
                        math.sin(half), 0.0))


@njit(cache=True, error_model="numpy", _nrt=False)
def pack_groove(depth, bottom_radius, opening, position, rho, unit, out, base):
    """Write one finger's scaled groove (:data:`GROOVE_FIELDS`) into ``out[base:base + 7]``.

    ``depth``, ``bottom_radius``, ``position`` and the corner radius ``rho`` in metres (or any
    one unit), ``opening`` the full opening angle [rad]; ``unit`` divides the lengths (the disk
    radius for the scaled solver, 1 for SI). Depth 0 writes zeros: the straight bar.
    """
    for k in range(N_GROOVE):
        out[base + k] = 0.0
    if not depth > 0.0:
        return
    half = 0.5 * opening
    cb, sb = math.cos(half), math.sin(half)
    centre = (depth - bottom_radius) / unit
    grown = (bottom_radius + rho) / unit
    out[base + G_POSITION] = position / unit
    out[base + G_DEPTH] = depth / unit
    out[base + G_CENTRE] = centre
    out[base + G_RADIUS] = grown
    out[base + G_COS] = cb
    out[base + G_SIN] = sb
    # the mouth corners: where the grown groove meets the core face (depth rho)
    out[base + G_MOUTH] = groove_mouth(depth / unit, centre, grown, cb, sb, rho / unit)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def corner_centre_local(c, lmax, hw, rho, groove, base):
    """Centre ``(s, m)`` of a finger's rounded convex corner ``c`` in finger coordinates (one
    unit with the arguments): the centres of the roundings the contour's edges meet.

    The bar's corners (``c < N_BAR_CORNERS``, ``C_*`` of :mod:`envs.model.layout`) sit at
    ``s = l`` (tip, even ``c``) or 0 (root), ``m = +-(w/2 - rho)`` (the gripping face for
    ``c < 2``, else the back); a groove's mouth edges at ``s = a +- u_E`` (the tip side for
    ``C_MOUTH_TIP``), ``m = w/2 - rho``, from the packed groove at ``groove[base:]``
    (:func:`pack_groove`).
    """
    hc = hw - rho
    if c >= N_BAR_CORNERS:
        ue = groove[base + G_MOUTH]
        return groove[base + G_POSITION] + (ue if c == C_MOUTH_TIP else -ue), hc
    sc = lmax if c % 2 == 0 else 0.0
    if c >= 2:
        hc = -hc
    return sc, hc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _point(du, dv):
    """Distance to a point and its derivatives: (d, d_u, d_v, d_uu, d_uv, d_vv)."""
    d = math.sqrt(du * du + dv * dv)
    if d == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    gu, gv = du / d, dv / d
    return d, gu, gv, (1.0 - gu * gu) / d, -gu * gv / d, (1.0 - gv * gv) / d


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _inside(u, v, centre, radius, cb, sb):
    """Whether ``(u, v)`` lies strictly inside the grown groove, and whether in its arc's
    sector (below the flanks' tangent points)."""
    wv = v - centre
    sector = wv * cb >= abs(u) * sb
    if sector:
        return u * u + wv * wv < radius * radius, True
    return cb * abs(u) + sb * wv < radius, False


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _bar(s, m, lmax, hc, rho):
    """Gap to the rounded bar (core rectangle ``[0, l] x [-hc, hc]`` grown by ``rho``) and its
    derivatives in ``(s, m)``: (g, g_s, g_m, g_ss, g_sm, g_mm); ``-rho`` inside the core."""
    ds = s - min(max(s, 0.0), lmax)
    dm = m - min(max(m, -hc), hc)
    if ds == 0.0 and dm == 0.0:
        return -rho, 0.0, 0.0, 0.0, 0.0, 0.0
    if ds == 0.0:
        return abs(dm) - rho, 0.0, (1.0 if dm > 0.0 else -1.0), 0.0, 0.0, 0.0
    if dm == 0.0:
        return abs(ds) - rho, (1.0 if ds > 0.0 else -1.0), 0.0, 0.0, 0.0, 0.0
    d, gs, gm, gss, gsm, gmm = _point(ds, dm)
    return d - rho, gs, gm, gss, gsm, gmm


@njit(cache=True, error_model="numpy", _nrt=False)
def jaw_gap(s, m, lmax, hw, rho, groove, base):
    """Gap of a point to a finger's solid and its derivatives in finger coordinates.

    Parameters
    ----------
    s, m
        The point along the finger axis from the joint and along the face's inward normal.
    lmax, hw, rho
        Finger length, half-width and corner radius (one unit with ``s``, ``m``).
    groove, base
        The finger's packed groove (:func:`pack_groove`, same unit) at ``groove[base:]``.

    Returns
    -------
    tuple
        ``(g, g_s, g_m, g_ss, g_sm, g_mm)``: the gap (distance to the rounded solid, ``-rho``
        deep inside its core) and its first and second derivatives. The gradient
        ``(g_s, g_m)`` is the unit normal of the nearest surface point, pointing to the point.
    """
    hc = hw - rho
    bar = _bar(s, m, lmax, hc, rho)
    depth = groove[base + G_DEPTH]
    if not depth > 0.0:
        return bar
    a = groove[base + G_POSITION]
    centre = groove[base + G_CENTRE]
    radius = groove[base + G_RADIUS]
    cb = groove[base + G_COS]
    sb = groove[base + G_SIN]
    ue = groove[base + G_MOUTH]
    u, v = s - a, hw - m
    # the nearest point of the core rectangle: the groove matters if it or the point lies in
    # the grown groove
    qs = min(max(s, 0.0), lmax)
    qm = min(max(m, -hc), hc)
    q_in, _ = _inside(qs - a, hw - qm, centre, radius, cb, sb)
    p_in, sector = _inside(u, v, centre, radius, cb, sb)
    if not (q_in or p_in):
        return bar
    # the candidates are distances to points of the core K; the nearest is among them: the
    # nearer mouth corner E = (+-ue, rho) in (u, v), the core rectangle's nearest point where it
    # lies outside the groove, the groove's wall below the core face where the point is inside
    side = 1.0 if u >= 0.0 else -1.0
    d, du, dv, duu, duv, dvv = _point(u - side * ue, v - rho)
    if not q_in and bar[0] + rho < d:
        # (s, m) -> (u, v): d/du = d/ds, d/dv = -d/dm
        d, du, dv, duu, duv, dvv = bar[0] + rho, bar[1], -bar[2], bar[3], -bar[4], bar[5]
    if p_in:
        # the grown groove's wall, from inside: its bottom arc or a flank
        if sector:
            wv = v - centre
            dist, pu, pv, puu, puv, pvv = _point(u, wv)
            inner = radius - dist
            foot = centre + radius * (wv / dist if dist > 0.0 else 1.0)
            if foot >= rho and inner < d:
                d, du, dv, duu, duv, dvv = inner, -pu, -pv, -puu, -puv, -pvv
        else:
            inner = radius - (cb * side * u + sb * (v - centre))
            foot = v + inner * sb
            if foot >= rho and inner < d:
                d, du, dv, duu, duv, dvv = inner, -cb * side, -sb, 0.0, 0.0, 0.0
    # (u, v) -> (s, m): d/ds = d/du, d/dm = -d/dv
    return d - rho, du, -dv, duu, -duv, dvv
