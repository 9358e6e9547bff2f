"""What the compiled solver is given: scenes as columns of numbers, checked and packed.

A :class:`SceneColumns` holds B scenes (gripper, disk and actuation torque) as float64 columns
in SI units. :func:`rest_codes` is the one check that a scene is valid at rest (used by
:class:`envs.scene.Scene`, which raises, and by the batch, which reports), and
:func:`pack_params` the one packing into the solver's scaled parameter rows (layout
:mod:`envs.model.layout`): lengths in units of the radius r, forces in units of ``s E t r``,
torques in units of ``s E t r^2``, so that tolerances do not depend on the physical size.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit, vectorize

from .defaults import CORNER_ROUNDING, DEFAULT_PHASE_RAD
from .energy import bulk_modulus_2d, lame_per_e
from .family import ELEMENTS
from .geometry import bar_distance, closed_angle_of, rest_points_into
from .jaw import MAX_DEPTH_OF_WIDTH, MAX_OPENING_RAD, groove_mouth, pack_groove
from .layout import (
    J_BOTTOM_RADIUS,
    J_DEPTH,
    J_OPENING,
    J_POSITION,
    N_JAW,
    N_KERNEL_PARAMS,
    N_OUTLINE,
    N_PARAMS,
    N_SCENE,
    N_SCENE_SCALARS,
    P_A0,
    P_C0X,
    P_C0Y,
    P_C1X,
    P_C1Y,
    P_GROOVE0,
    P_GROOVE1,
    P_H,
    P_HW,
    P_KA,
    P_KAPPA,
    P_KC,
    P_KR,
    P_LAM,
    P_LMAX,
    P_MU,
    P_ORIENT,
    P_OUTLINE,
    P_PHASE,
    P_QUAD,
    P_RHO,
    P_RINGS,
    P_SHAPE,
    P_SPACING,
    P_TAU,
    P_TH0,
    P_THMIN,
    S_AREA_SCALE,
    S_CONTOUR_RATIO,
    S_DISTANCE,
    S_JAW0,
    S_JAW1,
    S_JOINT_OFFSET,
    S_LENGTH,
    S_OFFSET_X,
    S_ORIENT,
    S_OUTLINE,
    S_POISSON,
    S_RADIUS,
    S_REST_ANGLE,
    S_SCALE,
    S_SHAPE,
    S_THICKNESS,
    S_TORQUE,
    S_TORSION,
    S_WIDTH,
    S_YOUNG,
    SHAPE_DISK,
    SPACING_EVEN,
    SPACING_GEOMETRIC,
)
from .outline import ARC_STEPS_PER_KNOT, outline_lowest, outline_point
from .rings import (
    N_RING_COLS,
    R_AIN,
    R_AOUT,
    R_LCIRC,
    R_LRAD,
    fill_ring_table,
    rest_xy,
    ring_rest_state_into,
    ring_table_size,
)
from .stiffness import spring_stiffness

__all__ = [
    "SceneColumns",
    "REST_OK",
    "REST_NOT_FINITE",
    "REST_GRIPPER",
    "REST_WIDTH",
    "REST_BEHIND_FACE",
    "REST_OVERLAP",
    "REST_OFFSET",
    "REST_JAW",
    "REST_MESSAGES",
    "rest_codes",
    "pack_params",
    "stiffness_unit",
    "rest_state",
    "spring_strains",
    "scaled_params",
]

# why a scene is invalid at rest (0: valid); REST_OFFSET: the disk's lateral displacement alone
# (the centred disk would be clear)
REST_OK, REST_NOT_FINITE, REST_GRIPPER, REST_WIDTH, REST_BEHIND_FACE, REST_OVERLAP = range(6)
REST_OFFSET = 6
REST_JAW = 7
REST_MESSAGES = {
    REST_OK: "valid",
    REST_NOT_FINITE: "a design value is not a finite number",
    REST_GRIPPER: "the gripper is out of range (finger_length_m > 0, 0 < rest_angle_rad < pi/2, "
                  "joint_offset_m >= 0, 0 < finger_width_m < finger_length_m, torque_nm >= 0)",
    REST_WIDTH: "finger_width_m must be smaller than the disk diameter 2 * radius_m",
    REST_BEHIND_FACE: "the disk centre lies behind the fingers' gripping faces at rest: "
                      "decrease joint_offset_m or increase rest_angle_rad/distance_m",
    REST_OVERLAP: "the fingers overlap the disk at rest: increase rest_angle_rad or distance_m "
                  "(allowed: clearance > 0)",
    REST_JAW: "a jaw's groove does not fit its finger (depth <= 0.75 finger_width_m, its mouth "
              "on the gripping face, a cradle's depth <= its radius, opening angle <= 170 deg)",
    REST_OFFSET: "the disk, displaced across the gripper's axis by offset_x_m, overlaps a finger "
                 "or lies behind its gripping face at rest (the centred disk would be clear): "
                 "decrease |offset_x_m| (allowed: clearance > 0 to both fingers)",
}


class SceneColumns(NamedTuple):
    """B scenes and torques as float64 columns of shape (B,) [SI units]."""

    finger_length_m: np.ndarray
    rest_angle_rad: np.ndarray
    joint_offset_m: np.ndarray
    finger_width_m: np.ndarray
    torsion_stiffness_nm_per_rad: np.ndarray
    radius_m: np.ndarray
    distance_m: np.ndarray
    youngs_modulus_pa: np.ndarray
    poisson_ratio: np.ndarray
    thickness_m: np.ndarray
    stiffness_scale: np.ndarray
    contour_stiffness_ratio: np.ndarray
    area_stiffness_scale: np.ndarray
    torque_nm: np.ndarray
    offset_x_m: np.ndarray
    # the jaw profile of each finger (envs.model.jaw.JawProfile); None: straight bars
    jaw_depth_m: np.ndarray | None = None  # (B, 2): right, left finger
    jaw_bottom_radius_m: np.ndarray | None = None  # (B, 2)
    jaw_opening_angle_rad: np.ndarray | None = None  # (B, 2)
    jaw_position_m: np.ndarray | None = None  # (B, 2)
    # the object's shape (envs.model.outline); None: disks
    shape: np.ndarray | None = None  # (B,) SHAPE_DISK or SHAPE_OUTLINE
    orientation_rad: np.ndarray | None = None  # (B,) an outline's psi
    outline: np.ndarray | None = None  # (B, N_OUTLINE) its B-spline coefficients

    def take(self, rows) -> SceneColumns:
        """The scenes of some rows."""
        return SceneColumns(*(None if c is None else c[rows] for c in self))

    @property
    def size(self) -> int:
        return int(self.radius_m.shape[0])

    @property
    def has_outlines(self) -> bool:
        """Whether a row's object is an outline (not a disk)."""
        return self.shape is not None and bool(np.any(self.shape != SHAPE_DISK))

    def rows(self) -> np.ndarray:
        """The scenes as a (B, N_SCENE) float64 matrix (layout ``S_*``)."""
        out = np.zeros((self.size, N_SCENE))
        for k, column in enumerate(self[:N_SCENE_SCALARS]):
            out[:, k] = column
        for k, column in enumerate(self[N_SCENE_SCALARS : N_SCENE_SCALARS + N_JAW]):
            if column is not None:
                out[:, S_JAW0 + k] = column[:, 0]
                out[:, S_JAW1 + k] = column[:, 1]
        if self.shape is not None:
            out[:, S_SHAPE] = self.shape
            out[:, S_ORIENT] = self.orientation_rad
            out[:, S_OUTLINE : S_OUTLINE + N_OUTLINE] = self.outline
        return out

    @classmethod
    def from_rows(cls, rows: np.ndarray) -> SceneColumns:
        """Columns of a (B, N_SCENE) scene matrix (views, the jaws' copies)."""
        table = np.asarray(rows, dtype=np.float64)
        jaws = (np.stack([table[:, S_JAW0 + k], table[:, S_JAW1 + k]], axis=1)
                for k in range(N_JAW))
        return cls(*table[:, :N_SCENE_SCALARS].T, *jaws, table[:, S_SHAPE], table[:, S_ORIENT],
                   table[:, S_OUTLINE : S_OUTLINE + N_OUTLINE])


@vectorize(["float64(float64, float64, float64, float64, float64, float64)"], cache=True)
def _front_m(rest_angle_rad, joint_offset_m, finger_width_m, radius_m, distance_m, centre_x_m):
    """Signed distance of the disk centre in front of the right gripping face [m] (a ufunc).

    The left face's is this at ``-centre_x_m``: the left finger is the right one's mirror image
    about the axis, so a centre displaced by ``x_c`` sits before it as before the right one
    displaced by ``-x_c``.
    """
    s, c = math.sin(rest_angle_rad), math.cos(rest_angle_rad)
    # centre (x_c, d_1 + r) relative to the right joint (d_3, 0); right finger n = (-c, s)
    across = c * (joint_offset_m - centre_x_m) + s * (distance_m + radius_m)
    return across - finger_width_m / 2


@vectorize(["float64(float64, float64, float64, float64, float64, float64, float64)"],
           cache=True)
def _clearance_m(finger_length_m, rest_angle_rad, joint_offset_m, finger_width_m, radius_m,
                 distance_m, centre_x_m):
    """Rest clearance between the disk and the right finger bar [m] (a ufunc); the left
    finger's is this at ``-centre_x_m`` (see :func:`_front_m`)."""
    s, c = math.sin(rest_angle_rad), math.cos(rest_angle_rad)
    rel_x = centre_x_m - joint_offset_m
    rel_y = distance_m + radius_m
    along = s * rel_x + c * rel_y  # right finger: e = (s, c), n = (-c, s)
    across = -c * rel_x + s * rel_y
    return bar_distance(along, across, finger_length_m, finger_width_m) - radius_m


def _clearance(cols: SceneColumns) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance of the disk centre in front of the gripping faces, and the rest
    clearance between the disk and the finger bars [m]: each the smaller of the two fingers'
    (the finger the displaced disk is nearer to; both alike for a centred disk). An
    outline's rows: its centroid's, and its own clearance (:func:`outline_clearance_m`)."""
    front = [_front_m(cols.rest_angle_rad, cols.joint_offset_m, cols.finger_width_m,
                      cols.radius_m, cols.distance_m, x) for x in _mirrored(cols.offset_x_m)]
    clear = [_clearance_m(cols.finger_length_m, cols.rest_angle_rad, cols.joint_offset_m,
                          cols.finger_width_m, cols.radius_m, cols.distance_m, x)
             for x in _mirrored(cols.offset_x_m)]
    front, clear = np.minimum(*front), np.minimum(*clear)
    if cols.has_outlines:
        table = cols.rows()
        for i in np.flatnonzero(cols.shape != SHAPE_DISK):
            s = table[i]
            lift = scene_centre_y_m(s) - s[S_DISTANCE]
            xc = s[S_OFFSET_X]
            front[i] = min(_front_m(s[S_REST_ANGLE], s[S_JOINT_OFFSET], s[S_WIDTH], lift,
                                    s[S_DISTANCE], x) for x in (xc, -xc))
            clear[i] = min(outline_clearance_m(s, 1.0, xc), outline_clearance_m(s, -1.0, xc))
    return front, clear


def _mirrored(centre_x_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The centre's x as the right finger sees it, for the right finger and for the left one
    (its mirror image)."""
    return centre_x_m, -centre_x_m


@njit(cache=True, error_model="numpy", _nrt=False)
def _rest_codes_into(table, codes):
    """:func:`rest_codes` of a (B, N_SCENE) scene matrix into ``codes``; the first failed test
    in the order not finite, gripper out of range, fingers too wide, centre behind a face,
    overlap names the row."""
    for i in range(table.shape[0]):
        finite = True
        for k in range(N_SCENE):
            finite = finite and math.isfinite(table[i, k])
        ln, th0, d3 = table[i, S_LENGTH], table[i, S_REST_ANGLE], table[i, S_JOINT_OFFSET]
        w, r, d1 = table[i, S_WIDTH], table[i, S_RADIUS], table[i, S_DISTANCE]
        xc = table[i, S_OFFSET_X]
        if not finite:
            codes[i] = REST_NOT_FINITE
        elif not (ln > 0 and 0 < th0 < math.pi / 2 and d3 >= 0 and 0 < w < ln
                  and table[i, S_TORQUE] >= 0):
            codes[i] = REST_GRIPPER
        elif not w < 2 * r:
            codes[i] = REST_WIDTH
        elif not (_jaw_fits(table[i], S_JAW0, ln, w, r) and _jaw_fits(table[i], S_JAW1, ln, w, r)):
            codes[i] = REST_JAW
        elif table[i, S_SHAPE] != SHAPE_DISK:
            codes[i] = _outline_placement_code(table[i])
        else:
            codes[i] = _placement_code(ln, th0, d3, w, r, d1, xc)


@njit(cache=True, error_model="numpy", _nrt=False)
def _jaw_fits(row, base, ln, w, r):
    """Whether the jaw groove at ``row[base + J_*]`` fits its finger (the rules of
    :meth:`envs.model.jaw.JawProfile.check_fits`)."""
    depth = row[base + J_DEPTH]
    if depth == 0.0:
        return True
    radius, opening = row[base + J_BOTTOM_RADIUS], row[base + J_OPENING]
    if not (depth > 0.0 and radius >= 0.0 and 0.0 <= opening <= MAX_OPENING_RAD
            and (radius > 0.0 or opening > 0.0) and (opening > 0.0 or depth <= radius)
            and depth <= MAX_DEPTH_OF_WIDTH * w):
        return False
    half = 0.5 * opening
    mouth = groove_mouth(depth, depth - radius, radius, math.cos(half), math.sin(half), 0.0)
    margin = mouth + min(CORNER_ROUNDING * r, 0.05 * w)
    return margin <= row[base + J_POSITION] <= ln - margin


@njit(cache=True, error_model="numpy", _nrt=False)
def _placement_code(ln, th0, d3, w, r, d1, xc):
    """The rest code of a disk placed at ``(xc, d1 + r)`` before a valid gripper: the centre
    behind a gripping face, then a finger overlapping the disk (the worse finger); where the
    centred disk would be clear, :data:`REST_OFFSET` instead (the displacement is to blame)."""
    front = min(_front_m(th0, d3, w, r, d1, xc), _front_m(th0, d3, w, r, d1, -xc))
    clear = min(_clearance_m(ln, th0, d3, w, r, d1, xc), _clearance_m(ln, th0, d3, w, r, d1, -xc))
    if front > 0 and clear > 0:
        return REST_OK
    if xc != 0.0 and _front_m(th0, d3, w, r, d1, 0.0) > 0 and (
            _clearance_m(ln, th0, d3, w, r, d1, 0.0) > 0):
        return REST_OFFSET
    return REST_BEHIND_FACE if not front > 0 else REST_OVERLAP


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _bar_signed_distance(along, across, length_m, width_m):
    """Signed distance [m] of a point from a finger bar (its coordinates along the bar axis
    and along the inward normal, relative to the joint): :func:`bar_distance` outside, minus
    the depth to the nearest side inside."""
    hw = 0.5 * width_m
    if 0.0 <= along <= length_m and -hw <= across <= hw:
        return -min(min(along, length_m - along), hw - abs(across))
    return bar_distance(along, across, length_m, width_m)


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_clearance_m(s, sign, offset_x_m):
    """Rest clearance [m] between an outline (scene row ``s``, its centroid at ``offset_x_m``
    across the axis) and the right finger bar (``sign`` 1) or the left one (``sign`` -1: the
    right one's mirror image sees the outline mirrored), signed: negative where the bar
    reaches into it, by the depth of its deepest point. On the outline's dense scan
    (:data:`~envs.model.outline.ARC_STEPS_PER_KNOT` points a knot interval): exact to the
    scan's chord sag, ~1e-5 r_eq."""
    return outline_bar_distance_m(s, sign, offset_x_m, s[S_REST_ANGLE])


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_bar_distance_m(s, sign, offset_x_m, angle_rad):
    """:func:`outline_clearance_m` with the finger at ``angle_rad`` [rad] instead of at rest:
    the signed distance [m] between the undeformed outline and the finger bar."""
    r = s[S_RADIUS]
    sn, cs = math.sin(angle_rad), math.cos(angle_rad)
    xc = sign * offset_x_m
    yc = scene_centre_y_m(s)
    steps = N_OUTLINE * ARC_STEPS_PER_KNOT
    best = math.inf
    for j in range(steps):
        ux, uy = outline_point(s, S_OUTLINE, 2.0 * math.pi * j / steps, s[S_ORIENT])
        rel_x = xc + sign * r * ux - s[S_JOINT_OFFSET]
        rel_y = yc + r * uy
        along = sn * rel_x + cs * rel_y  # right finger: e = (s, c), n = (-c, s)
        across = -cs * rel_x + sn * rel_y
        best = min(best, _bar_signed_distance(along, across, s[S_LENGTH], s[S_WIDTH]))
    return best


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def scene_centre_y_m(s):
    """Height of the object's centre above the joints' line [m] of scene row ``s``: ``d_1 +
    r`` for a disk, ``d_1`` plus how far an outline's lowest point lies below its centroid at
    its orientation (:func:`envs.model.outline.outline_lowest`) for an outline."""
    if s[S_SHAPE] == SHAPE_DISK:
        return s[S_DISTANCE] + s[S_RADIUS]
    return s[S_DISTANCE] + s[S_RADIUS] * outline_lowest(s, S_OUTLINE, s[S_ORIENT])


@njit(cache=True, error_model="numpy", _nrt=False)
def _outline_placement_code(s):
    """:func:`_placement_code` of an outline: its centroid in front of both gripping faces,
    the fingers clear of it (:func:`outline_clearance_m`); where the outline centred on the
    axis would be clear, :data:`REST_OFFSET` instead."""
    th0, d3, w = s[S_REST_ANGLE], s[S_JOINT_OFFSET], s[S_WIDTH]
    # _front_m of the centroid: the distance from it to each face line
    lift = scene_centre_y_m(s) - s[S_DISTANCE]
    xc = s[S_OFFSET_X]
    front = min(_front_m(th0, d3, w, lift, s[S_DISTANCE], xc),
                _front_m(th0, d3, w, lift, s[S_DISTANCE], -xc))
    clear = min(outline_clearance_m(s, 1.0, xc), outline_clearance_m(s, -1.0, xc))
    if front > 0 and clear > 0:
        return REST_OK
    if xc != 0.0 and _front_m(th0, d3, w, lift, s[S_DISTANCE], 0.0) > 0 and min(
            outline_clearance_m(s, 1.0, 0.0), outline_clearance_m(s, -1.0, 0.0)) > 0:
        return REST_OFFSET
    return REST_BEHIND_FACE if not front > 0 else REST_OVERLAP


def rest_codes(cols) -> np.ndarray:
    """Why each scene is invalid at rest (:data:`REST_OK` where it is valid), shape (B,).

    ``cols``: :class:`SceneColumns` or a (B, N_SCENE) scene matrix. The material fields are
    validated where a disk is built (:class:`envs.scene.SoftDisk`); here the geometry of the
    gripper and the disk together, and the torque.
    """
    table = cols.rows() if isinstance(cols, SceneColumns) else np.ascontiguousarray(
        cols, dtype=np.float64)
    codes = np.empty(table.shape[0], dtype=np.int64)
    _rest_codes_into(table, codes)
    return codes


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def stiffness_unit(s):
    """``s E t`` [N/m] of a scene row: the unit of the scaled spring stiffnesses (forces are in
    units of ``s E t r``, torques and energies of ``s E t r^2``)."""
    return s[S_SCALE] * s[S_YOUNG] * s[S_THICKNESS]


def pack_params(cols: SceneColumns, n_triangles: int, stiffness_rule: str = "van_gelder",
                phase_rad: float = DEFAULT_PHASE_RAD, n_rings: int = 1,
                element: str = "spring") -> np.ndarray:
    """Scaled solver parameters of valid scenes, shape (B, N_PARAMS) (layout ``P_*``).

    Parameters
    ----------
    cols
        The scenes (valid at rest: see :func:`rest_codes`), columns or a (B, N_SCENE) matrix.
    n_triangles
        Number of fan triangles ``N`` of every row.
    stiffness_rule
        See :func:`envs.model.stiffness.spring_stiffness` (the Poisson-aware rule uses each
        row's Poisson ratio).
    phase_rad
        Angle of the first contour point [rad].
    n_rings
        Rings ``M`` of the point mesh (1: the paper's fan; :mod:`envs.model.rings`). Ring
        meshes take the area rule on every edge (``stiffness_rule`` must be ``"van_gelder"``).
    element
        ``"spring"`` (springs and the area energy, docs/model.md), ``"cst"`` (the
        constant-strain neo-Hookean triangle of the FEM's material instead, scaled by the
        disk's ``stiffness_scale``) or ``"nhquad"`` (those triangles without their volumetric
        term, which acts once per quad; evenly spaced rings; ``n_rings >= 2``).
    """
    return pack_rows(cols.rows() if isinstance(cols, SceneColumns) else cols, n_triangles,
                     stiffness_rule, phase_rad, n_rings, element)


def pack_rows(scene: np.ndarray, n_triangles: int, stiffness_rule: str = "van_gelder",
              phase_rad: float = DEFAULT_PHASE_RAD, n_rings: int = 1,
              element: str = "spring") -> np.ndarray:
    """:func:`pack_params` of a (B, N_SCENE) scene matrix."""
    if element not in ELEMENTS:
        raise ValueError(f"element must be one of {ELEMENTS}, got {element!r}")
    n = int(n_triangles)
    m = int(n_rings)
    if element == "spring" and np.any(scene[:, S_SHAPE] != SHAPE_DISK):
        raise ValueError(f"an object with an outline (not a disk) needs element 'nhquad' or "
                         f"'cst' (a mesh of elements mapped onto the outline), got element "
                         f"{element!r}: the springs' calibrated scales hold for disks only")
    if element == "nhquad" and m < 2:
        raise ValueError(f"n_rings must be 2 to 16 for element 'nhquad' (its volumetric term "
                         f"acts on the quads between rings), got {m}")
    spacing = SPACING_EVEN if element == "nhquad" else SPACING_GEOMETRIC
    if m > 1:
        if stiffness_rule != "van_gelder":
            raise ValueError(f"stiffness_rule must be 'van_gelder' for a ring mesh (n_rings = "
                             f"{m}), got {stiffness_rule!r}")
        k_int, k_ext = ring_unit_stiffness(n, m, spacing)
        k_int_rows, k_ext_rows = np.full(scene.shape[0], k_int), np.full(scene.shape[0], k_ext)
    elif stiffness_rule == "van_gelder":
        k_int, k_ext = _unit_stiffness(n)
        k_int_rows, k_ext_rows = np.full(scene.shape[0], k_int), np.full(scene.shape[0], k_ext)
    else:
        pairs = [spring_stiffness(n, 1.0, stiffness_rule, nu) for nu in scene[:, S_POISSON]]
        k_int_rows, k_ext_rows = (np.array(v, dtype=np.float64) for v in zip(*pairs, strict=True))
    prm = np.empty((scene.shape[0], N_PARAMS))
    _pack_rows(scene, n, k_int_rows, k_ext_rows, float(phase_rad), prm)
    prm[:, P_RINGS] = m
    prm[:, P_MU] = 0.0
    prm[:, P_LAM] = 0.0
    prm[:, P_QUAD] = 0.0
    prm[:, P_SPACING] = spacing
    if element in ("cst", "nhquad"):
        # Lame moduli per E (the unit s E t r^2 of the energy makes s the calibration scale)
        prm[:, P_LAM], prm[:, P_MU] = lame_per_e(scene[:, S_POISSON])
    if element == "nhquad":
        # the volumetric term moves from the triangles to the quads
        prm[:, P_QUAD] = prm[:, P_LAM]
        prm[:, P_LAM] = 0.0
    return prm




@functools.lru_cache(maxsize=256)
def ring_unit_stiffness(n: int, m: int, spacing: float = SPACING_GEOMETRIC
                        ) -> tuple[float, float]:
    """Area-rule stiffness (per ``s E t``) of the contour springs of an ``m``-ring mesh and the
    largest radial one (the force scale of the solver's tolerances)."""
    prm = np.zeros(N_KERNEL_PARAMS + ring_table_size(n, m))
    prm[P_RINGS] = m
    prm[P_SPACING] = spacing
    fill_ring_table(prm, n)
    table = prm[N_KERNEL_PARAMS:N_KERNEL_PARAMS + (m + 1) * N_RING_COLS].reshape(m + 1, -1)
    outer = table[m]
    k_ext = float(outer[R_AOUT] / outer[R_LCIRC] ** 2)
    k_int = float(np.max(2 * np.maximum(table[1:, R_AOUT], table[1:, R_AIN])
                         / table[1:, R_LRAD] ** 2))
    return k_int, k_ext


@functools.lru_cache(maxsize=256)
def _unit_stiffness(n: int) -> tuple[float, float]:
    # the area rule validates its inputs on every call: tens of us on the simulate path
    return spring_stiffness(n, 1.0, "van_gelder")


@njit(cache=True, error_model="numpy", _nrt=False)
def _pack_rows(scene, n, k_int, k_ext, phase, prm):
    for b in range(scene.shape[0]):
        _pack_row(scene[b], n, k_int[b], k_ext[b], phase, prm[b])


@njit(cache=True, error_model="numpy", _nrt=False)
def _pack_row(s, n, k_int, k_ext, phase, p):
    r = s[S_RADIUS]
    torque_unit = stiffness_unit(s) * r * r
    p[P_KR] = k_int
    p[P_KC] = k_ext * s[S_CONTOUR_RATIO]
    p[P_H] = 2 * math.sin(math.pi / n)
    yc = scene_centre_y_m(s) / r
    # the centre (x_c, d_1 + r) relative to each joint (+-d_3, 0)
    p[P_C0X], p[P_C0Y] = (s[S_OFFSET_X] - s[S_JOINT_OFFSET]) / r, yc
    p[P_C1X], p[P_C1Y] = (s[S_OFFSET_X] + s[S_JOINT_OFFSET]) / r, yc
    p[P_HW] = s[S_WIDTH] / (2 * r)
    p[P_LMAX] = s[S_LENGTH] / r
    p[P_TAU] = s[S_TORQUE] / torque_unit
    p[P_KAPPA] = s[S_TORSION] / torque_unit
    p[P_TH0] = s[S_REST_ANGLE]
    p[P_THMIN] = closed_angle_of(s[S_LENGTH], s[S_JOINT_OFFSET], s[S_WIDTH])
    p[P_PHASE] = phase
    p[P_RHO] = min(CORNER_ROUNDING * r, 0.05 * s[S_WIDTH]) / r
    # area energy: kappa t A0 ln^2 / 2 with kappa = c_A K, in units of s E t r^2
    p[P_KA] = s[S_AREA_SCALE] * bulk_modulus_2d(s[S_YOUNG], s[S_POISSON]) * s[S_THICKNESS] / (
        stiffness_unit(s))
    p[P_A0] = 0.5 * math.sin(2 * math.pi / n)
    for base, slot in ((S_JAW0, P_GROOVE0), (S_JAW1, P_GROOVE1)):
        pack_groove(s[base + J_DEPTH], s[base + J_BOTTOM_RADIUS], s[base + J_OPENING],
                    s[base + J_POSITION], p[P_RHO] * r, r, p, slot)
    p[P_SHAPE] = s[S_SHAPE]
    p[P_ORIENT] = s[S_ORIENT]
    for k in range(N_OUTLINE):
        p[P_OUTLINE + k] = s[S_OUTLINE + k]


def rest_state(params: np.ndarray, n_triangles: int) -> np.ndarray:
    """Scaled start states of parameter rows (one mesh for all): undeformed mesh, fingers at
    rest, (B, 2 N M + 2) (layout :mod:`envs.model.rings`)."""
    params = np.atleast_2d(params)
    n = int(n_triangles)
    m = int(params[0, P_RINGS]) if params.shape[0] else 1
    x = np.empty((params.shape[0], 2 * n * m + 2))
    work = np.zeros(N_KERNEL_PARAMS + ring_table_size(n, m))
    _rest_rows(params, n, x, work)
    return x


@njit(cache=True, error_model="numpy", _nrt=False)
def _rest_rows(params, n, x, work):
    for b in range(params.shape[0]):
        outline = params[b, P_SHAPE] != SHAPE_DISK
        if not outline:
            rest_points_into(n, params[b, P_PHASE], x[b])
        x[b, 2 * n] = params[b, P_TH0]
        x[b, 2 * n + 1] = params[b, P_TH0]
        if params[b, P_RINGS] > 1 or outline:
            for j in range(N_PARAMS):
                work[j] = params[b, j]
            fill_ring_table(work, n)
            ring_rest_state_into(work, n, x[b])
        if outline:
            # the contour: the outline's points, as the ring table holds them
            m = int(params[b, P_RINGS])
            for i in range(n):
                x[b, 2 * i], x[b, 2 * i + 1] = rest_xy(work, n, m, m, i)


def spring_strains(q: np.ndarray, h) -> tuple[np.ndarray, np.ndarray]:
    """Engineering strains ``(L - L0) / L0`` of the radial and contour springs.

    Parameters
    ----------
    q
        Contour points relative to the centre, in units of ``r``, shape (..., N, 2).
    h
        Contour rest length in units of ``r``: a scalar or shape (...,).
    """
    radial = np.sqrt(q[..., 0] ** 2 + q[..., 1] ** 2) - 1.0
    d = np.roll(q, -1, axis=-2) - q
    contour = np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2) / np.asarray(h)[..., None] - 1.0
    return radial, contour


def scaled_params(scene, torque_nm: float, n_triangles: int,
                  stiffness_rule: str = "van_gelder",
                  phase_rad: float = DEFAULT_PHASE_RAD, n_rings: int = 1,
                element: str = "spring") -> np.ndarray:
    """The solver's parameter row of one scene at one torque, float64[N_PARAMS]."""
    return pack_params(scene.columns(torque_nm), int(n_triangles), stiffness_rule,
                       float(phase_rad), int(n_rings))[0]
