"""Geometry of the model: the disk's contour points and the two finger bars.

Conventions of ``docs/model.md``: x to the right, y up, the gripper's symmetry axis is
the y axis, the right finger's joint at ``(+d_3, 0)`` and the left one's at ``(-d_3, 0)``, finger
angles from +y, positive when opening. Finger ``j`` (0 right, 1 left) at angle ``theta`` has the
unit axis ``e`` and the inward face normal ``n``::

    right: e = ( sin, cos), n = (-cos, sin)
    left:  e = (-sin, cos), n = ( cos, sin)

:func:`finger_axes` is the one definition: the compiled solver calls it, and the Python helpers
below are built on it. (The independent check of :mod:`envs.check` keeps its own copy on
purpose.)
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numba import njit, vectorize

from .defaults import CORNER_ROUNDING
from .jaw import jaw_gap, pack_groove
from .layout import G_DEPTH, N_GROOVE

__all__ = [
    "FingerBars",
    "finger_axes",
    "finger_axes_array",
    "finger_frame",
    "closed_angle_rad",
    "distance_to_finger_bar",
    "finger_gap_m",
    "jaw_finger_gap",
    "surface_curvature_per_m",
    "rest_points",
    "corner_radius",
]


class FingerBars(Protocol):
    """What the geometry reads of a gripper: an :class:`envs.scene.Gripper` or anything with
    these fields (the model sits below the scene and does not import it)."""

    finger_length_m: float  # l [m]
    joint_offset_m: float  # d_3 [m]
    finger_width_m: float  # w [m]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def finger_axes(j, s, c):
    """Unit axis ``(ex, ey)`` and inward normal ``(nx, ny)`` of finger ``j`` (0 right, 1 left)
    from the sine ``s`` and cosine ``c`` of its angle."""
    if j == 0:
        return s, c, -c, s  # ex, ey, nx, ny
    return -s, c, c, s


def finger_frame(gripper: FingerBars, side: int, angle_rad):
    """Joint position, axis and inward face normal of one finger.

    Parameters
    ----------
    gripper
        The gripper.
    side
        0 for the right finger, 1 for the left finger.
    angle_rad
        Finger angle from the +y axis [rad]; an array of K angles gives ``axis`` and ``normal``
        of shape (2, K).

    Returns
    -------
    joint, axis, normal : numpy.ndarray
        ``J`` [m], the unit vector ``e`` along the finger and the unit inward normal ``n`` of the
        gripping face.
    """
    ex, ey, nx, ny = finger_axes(0 if side == 0 else 1, np.sin(angle_rad), np.cos(angle_rad)) \
        if np.ndim(angle_rad) == 0 else finger_axes_array(side, np.asarray(angle_rad))
    joint = np.array([gripper.joint_offset_m if side == 0 else -gripper.joint_offset_m, 0.0])
    return joint, np.array([ex, ey]), np.array([nx, ny])


def finger_axes_array(side: int, angles: np.ndarray):
    """:func:`finger_axes` elementwise on an array of angles [rad] (the same signs), for numpy
    callers that evaluate many angles (a compiled call per angle costs microseconds)."""
    s, c = np.sin(angles), np.cos(angles)
    return (s, c, -c, s) if side == 0 else (-s, c, c, s)


def closed_angle_rad(gripper: FingerBars) -> float:
    """Finger angle at which the gripping-face tip reaches the symmetry axis [rad].

    The jaws cannot close past it (the two faces would meet); the solver treats it as a joint
    stop. Solves ``d_3 + l sin(theta) - (w/2) cos(theta) = 0`` for ``theta`` in (-pi/2, 0].
    """
    return closed_angle_of(gripper.finger_length_m, gripper.joint_offset_m,
                           gripper.finger_width_m)


@njit(cache=True, error_model="numpy", _nrt=False)
def closed_angle_of(length_m: float, joint_offset_m: float, width_m: float) -> float:
    """:func:`closed_angle_rad` of plain numbers: finger length, joint offset, width [m].

    A jaw groove (:mod:`envs.model.jaw`) leaves it unchanged: the groove lies within the
    gripping face, between its ends (:meth:`envs.model.jaw.JawProfile.check_fits`), so the
    face's tip corner, which meets the axis first, is the straight bar's."""
    hw = width_m / 2
    # l sin t - hw cos t = R sin(t - phi), R = hypot(l, hw), phi = atan2(hw, l)
    rr = math.hypot(length_m, hw)
    return math.atan2(hw, length_m) - math.asin(min(1.0, joint_offset_m / rr))


@vectorize(["float64(float64, float64, float64, float64)"], cache=True)
def bar_distance(along_m, across_m, length_m, width_m):
    """Distance from a point to a finger bar (0 inside) from its coordinates along the bar axis
    and along the inward normal, relative to the joint [m]; a ufunc (elementwise on arrays,
    callable from compiled code; NaN in, NaN out)."""
    if math.isnan(along_m) or math.isnan(across_m) or math.isnan(length_m) or math.isnan(width_m):
        return math.nan
    hw = width_m / 2
    ds = max(0.0, max(-along_m, along_m - length_m))
    dm = max(0.0, max(across_m - hw, -hw - across_m))
    return math.hypot(ds, dm)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def finger_gap_m(x_m, y_m, j, angle_rad, joint_offset_m, length_m, width_m):
    """Distance [m] from the point ``(x_m, y_m)`` (gripper frame) to the bar of finger ``j``
    (0 right, 1 left) at ``angle_rad``, 0 on or inside it (compiled: the design evaluator's
    contact measure calls it per contour point; :func:`distance_to_finger_bar` is its Python
    counterpart for a gripper object)."""
    ex, ey, nx, ny = finger_axes(j, math.sin(angle_rad), math.cos(angle_rad))
    rx = x_m - (joint_offset_m if j == 0 else -joint_offset_m)
    return bar_distance(ex * rx + ey * y_m, nx * rx + ny * y_m, length_m, width_m)


@njit(cache=True, error_model="numpy", _nrt=False)
def jaw_finger_gap(x_m, y_m, j, angle_rad, joint_offset_m, length_m, width_m, rounding_m,
                   groove, base):
    """Gap [m] of the point ``(x_m, y_m)`` (gripper frame) to finger ``j`` at ``angle_rad``
    with a jaw groove, and the curvature of the finger's surface at its nearest point.

    ``groove[base:]`` is the finger's groove packed in metres
    (:func:`envs.model.jaw.pack_groove` with unit 1), ``rounding_m`` the corner radius ``rho``
    it was packed with. The gap is :func:`envs.model.jaw.jaw_gap` (the solver's own), signed;
    for a straight jaw (depth 0) it is :func:`finger_gap_m`, the bar's distance, so straight
    fingers keep their measure.

    Returns
    -------
    tuple
        ``(gap_m, curvature_per_m)``: the curvature of the nearest surface point, positive
        where the surface is concave towards the point (:func:`surface_curvature_per_m`); 0
        for a straight jaw.
    """
    if not groove[base + G_DEPTH] > 0.0:
        return finger_gap_m(x_m, y_m, j, angle_rad, joint_offset_m, length_m, width_m), 0.0
    ex, ey, nx, ny = finger_axes(j, math.sin(angle_rad), math.cos(angle_rad))
    rx = x_m - (joint_offset_m if j == 0 else -joint_offset_m)
    g, g_s, g_m, g_ss, g_sm, g_mm = jaw_gap(ex * rx + ey * y_m, nx * rx + ny * y_m, length_m,
                                            0.5 * width_m, rounding_m, groove, base)
    return g, surface_curvature_per_m(g, g_s, g_m, g_ss, g_sm, g_mm)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def surface_curvature_per_m(g, g_s, g_m, g_ss, g_sm, g_mm):
    """Curvature [1/m] of a surface at the nearest point to a point at distance ``g`` from it,
    from the distance's gradient and Hessian in the plane (the point on the surface's normal).

    Along the surface's tangent ``t = (-g_m, g_s)`` the distance to a surface of curvature
    ``k`` (positive where it is concave towards the point, as a cradle's arc of radius R:
    ``1/R``) has ``g_tt = -k / (1 - k g)``, so ``k = -g_tt / (1 - g g_tt)``: 0 for a flat face,
    ``-1/rho`` on a convex edge rounded by ``rho``. A point inside the solid counts as on it.
    """
    gtt = g_ss * g_m * g_m - 2.0 * g_sm * g_s * g_m + g_mm * g_s * g_s
    gap = g if g > 0.0 else 0.0
    return -gtt / (1.0 - gap * gtt)


def distance_to_finger_bar(gripper: FingerBars, side: int, angle_rad, point, jaw=None,
                           rounding_m: float = 0.0):
    """Distance from ``point`` to the rectangular finger bar (0 inside) [m].

    ``angle_rad`` may be an array of finger angles: one distance per angle. ``jaw``: the
    :class:`~envs.model.jaw.JawProfile` cut into this finger's face, its edges rounded by
    ``rounding_m`` [m] (:func:`corner_radius`); a groove moves the surface away from a point in
    front of it, and the distance is then the grooved finger's
    (:func:`jaw_finger_gap`, 0 inside).
    """
    if jaw is not None and jaw.depth_m > 0.0:
        packed = np.zeros(N_GROOVE)
        pack_groove(jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m,
                    float(rounding_m), 1.0, packed, 0)
        x, y = float(point[0]), float(point[1])
        dist = np.array([max(0.0, jaw_finger_gap(
            x, y, 0 if side == 0 else 1, float(a), gripper.joint_offset_m,
            gripper.finger_length_m, gripper.finger_width_m, float(rounding_m), packed, 0)[0])
            for a in np.atleast_1d(angle_rad)])
        return float(dist[0]) if np.ndim(angle_rad) == 0 else dist
    joint, axis, normal = finger_frame(gripper, side, angle_rad)
    rx = float(point[0]) - joint[0]
    ry = float(point[1]) - joint[1]
    dist = bar_distance(axis[0] * rx + axis[1] * ry, normal[0] * rx + normal[1] * ry,
                        gripper.finger_length_m, gripper.finger_width_m)
    return float(dist) if np.ndim(dist) == 0 else dist


def rest_points(n_triangles: int, phase_rad: float = math.pi / 2) -> np.ndarray:
    """Unit contour points of the fan, counter-clockwise, the first at ``phase_rad``, (N, 2)."""
    out = np.empty(2 * int(n_triangles))
    rest_points_into(int(n_triangles), float(phase_rad), out)
    return out.reshape(-1, 2)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def rest_point(i, n, phase):
    """Unit rest position ``(x, y)`` of contour point ``i`` of ``n``, the first at ``phase``."""
    ang = phase + 2 * math.pi * i / n
    return math.cos(ang), math.sin(ang)


@njit(cache=True, error_model="numpy", _nrt=False)
def rest_points_into(n, phase, out):
    """Write the unit rest contour ``(x_0, y_0, x_1, ...)`` into ``out`` (2N)."""
    for i in range(n):
        out[2 * i], out[2 * i + 1] = rest_point(i, n, phase)


def corner_radius(finger_width_m, radius_m):
    """Rounding radius of the finger end corners [m] (see :data:`CORNER_ROUNDING`); elementwise
    on arrays."""
    return np.minimum(CORNER_ROUNDING * radius_m, 0.05 * finger_width_m) \
        if np.ndim(finger_width_m) or np.ndim(radius_m) \
        else min(CORNER_ROUNDING * radius_m, 0.05 * finger_width_m)
