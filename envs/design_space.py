"""The design space relative to the object: :class:`DesignBounds` maps actions in [-1, 1] to
SI designs for any object (lengths in radii, the torque in ``s E t r^2``), with straight bars
or shaped jaws (a cradle, a V-groove, or either: :data:`JAW_KINDS`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numba import vectorize

from .model.defaults import MAX_TORQUE_UNITS
from .model.geometry import corner_radius
from .model.jaw import MAX_DEPTH_OF_WIDTH, MAX_OPENING_RAD, groove_mouth
from .scene import (
    N_DESIGN,
    RELATIVE_FIELDS,
    SoftDisk,
    design_fields,
    design_from_relative,
    placement_support,
    relative_from_design,
)
from .validation import check_range, check_sequence

__all__ = [
    "DesignBounds",
    "JAW_KINDS",
    "JAW_RELATIVE_FIELDS",
    "JAW_COLUMNS",
    "JAW_BOUNDS",
    "jaw_mouth_half_width",
    "fitting_depth",
    "RELATIVE_LIMITS",
    "touch_foot_r",
]

# what the jaws of a design space may be: straight bars (today's six columns), a circular
# cradle, a sharp V-groove, or the rounded V between them (envs.model.jaw.JawProfile)
JAW_KINDS = ("straight", "cradle", "vee", "any")
# the relative columns of one finger's groove: depth over the finger width, bottom radius over
# the disk radius, the full opening angle [rad], and the groove's centre as a fraction of the
# span it may take on the finger (DesignBounds)
JAW_RELATIVE_FIELDS = ("jaw_depth_w", "jaw_radius_r", "jaw_opening_rad", "jaw_position")
_DEPTH, _RADIUS, _OPENING, _POSITION = JAW_RELATIVE_FIELDS
# the columns each kind varies (the others are fixed: a cradle's opening 0, a V's radius 0)
JAW_COLUMNS: dict[str, tuple[str, ...]] = {
    "straight": (),
    "cradle": (_DEPTH, _RADIUS, _POSITION),
    "vee": (_DEPTH, _OPENING, _POSITION),
    "any": JAW_RELATIVE_FIELDS,
}
# default (low, high) of each varied column: every point is a groove that fits (DesignBounds)
JAW_BOUNDS: dict[str, dict[str, tuple[float, float]]] = {
    "straight": {},
    "cradle": {_DEPTH: (0.0, MAX_DEPTH_OF_WIDTH), _RADIUS: (0.8, 3.0), _POSITION: (0.0, 1.0)},
    "vee": {_DEPTH: (0.0, MAX_DEPTH_OF_WIDTH), _OPENING: (math.radians(60.0),
                                                          math.radians(150.0)),
            _POSITION: (0.0, 1.0)},
    # an opening of 0 would need depth <= radius (a cradle): the rounded V keeps 10 deg
    "any": {_DEPTH: (0.0, MAX_DEPTH_OF_WIDTH), _RADIUS: (0.0, 3.0),
            _OPENING: (math.radians(10.0), math.radians(150.0)), _POSITION: (0.0, 1.0)},
}
# the largest value each column may take at all (a groove's own limits, JawProfile)
_COLUMN_LIMITS = {_DEPTH: MAX_DEPTH_OF_WIDTH, _RADIUS: math.inf, _OPENING: MAX_OPENING_RAD,
                  _POSITION: 1.0}
# the groove is kept this share of the finger length inside its feasible span, so that the
# rest check (in SI, rounded otherwise) finds the span's ends inside too
_INSET = 1e-9


@vectorize(["float64(float64, float64, float64)"], cache=True)
def jaw_mouth_half_width(depth, bottom_radius, opening_angle_rad):
    """Half-width of a groove's mouth in the gripping face (sharp edges), in the unit of
    ``depth`` and ``bottom_radius`` (0 for depth 0); elementwise (a ufunc) with
    :func:`envs.model.jaw.groove_mouth`, the rule the rest check applies."""
    if not depth > 0.0:
        return 0.0
    half = 0.5 * opening_angle_rad
    return groove_mouth(depth, depth - bottom_radius, bottom_radius, math.cos(half),
                        math.sin(half), 0.0)


@vectorize(["float64(float64, float64, float64)"], cache=True)
def fitting_depth(mouth_half_width, bottom_radius, opening_angle_rad):
    """The largest depth of a rounded V (bottom radius, full opening angle) whose mouth is at
    most ``mouth_half_width`` wide on each side (one unit for the lengths; a ufunc): the
    inverse of :func:`jaw_mouth_half_width`, which grows with the depth.

    Within the arc's reach (mouth ``M <= R_b cos(phi/2)``) the mouth is ``sqrt(h (2 R_b -
    h))``, so ``h = M^2 / (R_b + sqrt(R_b^2 - M^2))``; beyond it a flank sets it, ``M = (R_b
    (1 - sin(phi/2)) + h sin(phi/2)) / cos(phi/2)``. A cradle (``phi = 0``) has no flank: its
    mouth never exceeds ``R_b`` (inf then; its depth is bounded by ``R_b`` instead). 0 for
    ``M <= 0``.
    """
    if not mouth_half_width > 0.0:
        return 0.0
    half = 0.5 * opening_angle_rad
    cb, sb = math.cos(half), math.sin(half)
    m = mouth_half_width
    r = bottom_radius
    if m <= r * cb:
        return m * m / (r + math.sqrt(max(r * r - m * m, 0.0)))
    if sb == 0.0:
        return math.inf
    return (m * cb - r * (1.0 - sb)) / sb


def touch_foot_r(relative) -> np.ndarray:
    """Where a gripper's straight gripping face first meets the undeformed disk as the finger
    closes from rest: the foot of the disk's centre on the finger's axis, its distance from the
    joint in disk radii, of relative designs (..., 6 or more; :data:`~envs.scene.RELATIVE_FIELDS`).

    In radii, with the joint at ``(d_3, 0)`` and the centre at ``(0, d_1 + 1)`` (``d_1`` of the
    rest clearance, :func:`~envs.scene.design_from_relative`), the face's distance from the
    centre is ``d_3 cos theta + (d_1 + 1) sin theta - w / 2``; it meets the disk at the angle
    where that is 1, and the foot lies ``(d_1 + 1) cos theta - d_3 sin theta`` along the axis.
    A face that clears the disk at every angle gives the foot at its closest angle.
    """
    rel = np.asarray(relative, dtype=np.float64)
    one = np.ones(rel.shape[:-1])
    distance = design_from_relative(rel[..., :N_DESIGN], one, one)[..., 5]
    offset, width = rel[..., _OFFSET_R], rel[..., _WIDTH_R]
    above = distance + 1.0
    reach = np.hypot(offset, above)
    theta = np.arcsin(np.clip((1.0 + 0.5 * width) / reach, -1.0, 1.0)) - np.arctan2(offset,
                                                                                     above)
    return above * np.cos(theta) - offset * np.sin(theta)


def _scales(disks, batch: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Radius [m] and torque unit ``s E t r^2`` [N·m] of one disk (scalars) or of a sequence of
    ``batch`` disks (arrays (batch,))."""
    if isinstance(disks, SoftDisk):
        return np.float64(disks.radius_m), np.float64(disks.torque_unit_nm)
    if not isinstance(disks, Sequence) or (batch is not None and len(disks) != batch):
        raise ValueError(f"disks must be a SoftDisk or a sequence of {batch} SoftDisks, got "
                         f"{type(disks).__name__}")
    for i, d in enumerate(disks):
        if not isinstance(d, SoftDisk):
            raise ValueError(f"disks[{i}] must be a SoftDisk, got {type(d).__name__}")
    return (np.array([d.radius_m for d in disks], dtype=np.float64),
            np.array([d.torque_unit_nm for d in disks], dtype=np.float64))


# the range each relative column's bounds may take at all: (low, high, low_open, high_open).
# Lengths up to 100 radii (the default box reaches 8), a finger narrower than the object's
# diameter, the rest angle in (0, 90 deg) as for a Gripper (in radians: 60 is degrees typed),
# the torque up to MAX_TORQUE_UNITS (as envs.scene.check_torque), a rest clearance down to
# an overlap of one radius (a box reaching into overlaps gets the graded invalid penalty)
RELATIVE_LIMITS: dict[str, tuple[float, float, bool, bool]] = {
    "finger_length_r": (0.0, 100.0, True, False),
    "rest_angle_rad": (0.0, math.pi / 2, True, True),
    "joint_offset_r": (0.0, 100.0, False, False),
    "finger_width_r": (0.0, 2.0, True, True),
    "torque_rel": (0.0, MAX_TORQUE_UNITS, False, False),
    "rest_clearance_r": (-1.0, 100.0, False, False),
}

# the relative columns the joints-apart option couples (DesignBounds.joints_apart)
_OFFSET_R = RELATIVE_FIELDS.index("joint_offset_r")
_WIDTH_R = RELATIVE_FIELDS.index("finger_width_r")


@dataclass(frozen=True)
class DesignBounds:
    """Box of the design space relative to the object; maps actions in [-1, 1] to designs.

    The box is in the units of :data:`envs.scene.RELATIVE_FIELDS`: finger length, joint offset
    and finger width in disk radii, the rest angle in radians, the torque in the disk's torque
    unit ``s E t r^2`` (:attr:`~envs.scene.SoftDisk.torque_unit_nm`) and, for the placement, the
    rest clearance between the disk and the gripping faces in radii
    (:func:`~envs.scene.design_from_relative`). The model is invariant under this scaling, so
    a box means the same for every object: the paper's foam disks and the forceps' 2 mm TPU
    beads alike. Every design of the default box is valid at rest (its clearance is positive),
    and most of its random designs grasp with both fingers, on every preset.

    | # | field | meaning | low | high |
    |---|---|---|---|---|
    | 0 | ``finger_length_r`` | finger length ``l / r`` | 1.5 | 8 |
    | 1 | ``rest_angle_rad`` | rest angle ``theta_a0`` | 10 deg | 60 deg |
    | 2 | ``joint_offset_r`` | joint offset ``d_3 / r`` | 0 | 0.6 |
    | 3 | ``finger_width_r`` | finger width ``w / r`` | 0.05 | 0.4 |
    | 4 | ``torque_rel`` | ``T_a / (s E t r^2)`` | 0 | 0.3 |
    | 5 | ``rest_clearance_r`` | rest clearance / ``r`` | 0.005 | 1.2 |

    The box holds the paper's grippers (``l / r`` = 2 to 4, 45 deg, clearance 0.01 to 0.02, the
    paper's torques 0.05 to 0.5 N·m at 0.005 to 0.2 units) and the forceps (``l / r`` = 5.3 to 8,
    15 deg, clearance 0.6 to 1.2).

    With ``joints_apart`` the joint offset's coordinate spans ``[max(low, w / 2), high]``
    instead of ``[low, high]`` (``w`` the row's own finger width), so every design keeps
    ``d_3 >= w / 2``: each finger's joint end, a square end of half-width ``w / 2``, sweeps a
    circle of radius ``w / 2`` about its joint as the finger turns, and with ``d_3 >= w / 2`` the
    two circles do not overlap, so the fingers can be built side by side in one plane. Without
    it (the default) a design may have ``d_3 < w / 2``, fingers that overlap at the joints and
    must be built stacked, one above the other, like forceps jaws. The box stays ``[-1, 1]^6``
    either way: only the map from it changes.

    **Shaped jaws.** With ``jaw`` other than ``"straight"`` the box gains the groove cut into
    the gripping faces (:class:`~envs.model.jaw.JawProfile`), after the six columns above, and
    the SI designs are 10 wide (:data:`~envs.model.jaw.JAW_FIELDS`); with ``jaw_per_finger``
    each finger has its own columns (the left finger's prefixed ``left_``, SI 14 wide). The
    columns of each kind (:data:`JAW_COLUMNS`) and their default ranges (:data:`JAW_BOUNDS`):

    | field | meaning | cradle | vee | any |
    |---|---|---|---|---|
    | ``jaw_depth_w`` | depth ``h / w`` (0: the straight bar) | 0 - 0.75 | 0 - 0.75 | 0 - 0.75 |
    | ``jaw_radius_r`` | bottom radius ``R_b / r`` | 0.8 - 3 | (0) | 0 - 3 |
    | ``jaw_opening_rad`` | full opening angle ``phi`` | (0) | 60 - 150 deg | 10 - 150 deg |
    | ``jaw_position`` | the groove's centre in its span | 0 - 1 | 0 - 1 | 0 - 1 |

    (a value in parentheses is fixed: the cradle's flanks and the V's bottom radius). The
    position is the fraction of the span the groove's centre may take on the finger, ``a``
    from ``u_m + rho`` to ``l - u_m - rho`` (``u_m`` the mouth's half-width,
    :attr:`~envs.model.jaw.JawProfile.mouth_half_width_m`; ``rho`` the corner rounding), so the
    mouth lies on the gripping face. The depth's coordinate spans ``[low, min(high, h_fit /
    w)]``, ``h_fit`` the deepest groove of the row's radius and opening whose mouth fits the
    row's finger (:func:`fitting_depth`; for a cradle at most its radius): like the joint
    offset with ``joints_apart``, a coupling that keeps every point of the box a groove that
    fits, whatever the finger length. A depth whose ``low`` does not fit the finger gives a
    design invalid at rest (:data:`~envs.model.problem.REST_JAW`), not an error. The bottom
    radius is in disk radii (a cradle of ``R_b / r`` near 1 conforms to the object); the depth
    in finger widths, at most :data:`~envs.model.jaw.MAX_DEPTH_OF_WIDTH` (the jaw keeps a back
    wall). Relative designs stay scale-invariant.

    Parameters
    ----------
    low, high
        Lower and upper bound of each of the six relative columns, ``low < high``, each
        within :data:`RELATIVE_LIMITS` (lengths up to 100 radii, the finger narrower than the
        object's diameter, the rest angle in (0, pi/2) radians, the torque up to 10 units, the
        clearance from -1 to 100 radii).
    joints_apart
        Keep the joints at least half a finger width from the axis (``d_3 >= w / 2``); needs
        ``high`` of ``joint_offset_r`` at least half ``high`` of ``finger_width_r``.
    jaw
        The jaws designed: one of :data:`JAW_KINDS` (default ``"straight"``: six columns,
        straight bars).
    jaw_per_finger
        Each finger its own groove (needs a ``jaw`` other than ``"straight"``).
    jaw_low, jaw_high
        Bounds of one finger's jaw columns (:data:`JAW_COLUMNS` of ``jaw``, in that order;
        default ``None``: the kind's :data:`JAW_BOUNDS`, filled in), the same for both
        fingers; ``low < high``. :meth:`with_jaw` changes the jaws with their bounds.
    """

    low: tuple[float, ...] = (1.5, math.radians(10.0), 0.0, 0.05, 0.0, 0.005)
    high: tuple[float, ...] = (8.0, math.radians(60.0), 0.6, 0.4, 0.3, 1.2)
    joints_apart: bool = False
    jaw: str = "straight"
    jaw_per_finger: bool = False
    jaw_low: tuple[float, ...] | None = None
    jaw_high: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        for name in ("low", "high"):
            given = check_sequence(f"DesignBounds.{name}", getattr(self, name), N_DESIGN)
            # checked as given, not after float(): "0.2" and True are not bounds
            vals = tuple(check_range(f"DesignBounds.{name}[{field_name}]", v,
                                     *RELATIVE_LIMITS[field_name][:2],
                                     low_open=RELATIVE_LIMITS[field_name][2],
                                     high_open=RELATIVE_LIMITS[field_name][3])
                         for field_name, v in zip(RELATIVE_FIELDS, given, strict=True))
            object.__setattr__(self, name, vals)
        for field_name, lo, hi in zip(RELATIVE_FIELDS, self.low, self.high, strict=True):
            if not lo < hi:
                raise ValueError(
                    f"DesignBounds for {field_name}: low = {lo!r} must be smaller than "
                    f"high = {hi!r}"
                )
        if not isinstance(self.joints_apart, bool):
            raise ValueError(f"DesignBounds.joints_apart must be True or False, got "
                             f"{self.joints_apart!r}")
        if self.joints_apart and self.high[_OFFSET_R] < self.high[_WIDTH_R] / 2:
            raise ValueError(
                f"DesignBounds with joints_apart: high joint_offset_r = {self.high[_OFFSET_R]!r}"
                f" must be at least half of high finger_width_r = {self.high[_WIDTH_R]!r}, so "
                f"that d_3 >= w / 2 has room")
        self._check_jaw()

    def _check_jaw(self) -> None:
        """Validate the jaw options and fill the jaw bounds (the kind's defaults for None)."""
        if not isinstance(self.jaw, str) or self.jaw not in JAW_KINDS:
            raise ValueError(f"DesignBounds.jaw must be one of {JAW_KINDS}, got {self.jaw!r}")
        if not isinstance(self.jaw_per_finger, bool):
            raise ValueError(f"DesignBounds.jaw_per_finger must be True or False, got "
                             f"{self.jaw_per_finger!r}")
        if self.jaw_per_finger and self.jaw == "straight":
            raise ValueError("DesignBounds.jaw_per_finger needs a jaw other than 'straight' "
                             f"(one of {JAW_KINDS[1:]})")
        columns = JAW_COLUMNS[self.jaw]
        for index, name in enumerate(("jaw_low", "jaw_high")):
            given = getattr(self, name)
            if given is None:
                given = tuple(JAW_BOUNDS[self.jaw][c][index] for c in columns)
            given = check_sequence(f"DesignBounds.{name}", given)
            if len(given) != len(columns):
                raise ValueError(f"DesignBounds.{name} needs {len(columns)} values for jaw "
                                 f"{self.jaw!r} ({', '.join(columns)}), got {len(given)}")
            vals = tuple(check_range(f"DesignBounds.{name}[{c}]", v, 0.0, _COLUMN_LIMITS[c])
                         for c, v in zip(columns, given, strict=True))
            object.__setattr__(self, name, vals)
        for c, lo, hi in zip(columns, self.jaw_low, self.jaw_high, strict=True):
            if not lo < hi:
                raise ValueError(f"DesignBounds for {c}: low = {lo!r} must be smaller than "
                                 f"high = {hi!r}")
        low = dict(zip(columns, self.jaw_low, strict=True))
        # a groove with depth needs a bottom radius or an opening (JawProfile)
        if low.get(_RADIUS, 0.0) == 0.0 and low.get(_OPENING, 0.0) == 0.0 and columns:
            raise ValueError(f"DesignBounds for jaw {self.jaw!r}: the low "
                             + " or ".join(c for c in (_RADIUS, _OPENING) if c in columns)
                             + " must be > 0 (a groove needs a bottom radius or an opening)")

    def with_jaw(self, jaw: str | None = None, jaw_per_finger: bool | None = None
                 ) -> DesignBounds:
        """This box with other jaws (``None``: this box's): its jaw bounds kept where the
        kind stays, the new kind's defaults otherwise (``dataclasses.replace`` with another
        ``jaw`` would keep bounds of the old kind's columns)."""
        jaw = self.jaw if jaw is None else jaw
        same = jaw == self.jaw
        return replace(self, jaw=jaw,
                       jaw_per_finger=(self.jaw_per_finger if jaw_per_finger is None
                                       else jaw_per_finger),
                       jaw_low=self.jaw_low if same else None,
                       jaw_high=self.jaw_high if same else None)

    # --- the columns --------------------------------------------------------------------------

    @property
    def jaw_fields(self) -> tuple[str, ...]:
        """The relative jaw columns after the six: one finger's (:data:`JAW_COLUMNS` of
        :attr:`jaw`), then with :attr:`jaw_per_finger` the left finger's (``left_...``)."""
        columns = JAW_COLUMNS[self.jaw]
        if self.jaw_per_finger:
            return (*columns, *("left_" + c for c in columns))
        return columns

    @property
    def fields(self) -> tuple[str, ...]:
        """Names of the relative columns (and of the action's coordinates)."""
        return (*RELATIVE_FIELDS, *self.jaw_fields)

    @property
    def n_var(self) -> int:
        """Width of an action and of a relative design: 6, plus the jaw columns."""
        return len(self.fields)

    @property
    def design_width(self) -> int:
        """Width of the SI designs: 6 (straight), 10 (a jaw) or 14 (a jaw per finger)."""
        if self.jaw == "straight":
            return N_DESIGN
        return N_DESIGN + 4 * (2 if self.jaw_per_finger else 1)

    @property
    def design_fields(self) -> tuple[str, ...]:
        """Names of the SI design columns (:data:`envs.scene.ALL_DESIGN_FIELDS`)."""
        return design_fields(self.design_width)

    @property
    def low_array(self) -> np.ndarray:
        """Lower bounds (relative units) as a float64 array (:attr:`n_var`,)."""
        return np.array((*self.low, *self._jaw_bounds(self.jaw_low)), dtype=np.float64)

    @property
    def high_array(self) -> np.ndarray:
        """Upper bounds (relative units) as a float64 array (:attr:`n_var`,)."""
        return np.array((*self.high, *self._jaw_bounds(self.jaw_high)), dtype=np.float64)

    def _jaw_bounds(self, one: tuple[float, ...]) -> tuple[float, ...]:
        return one * (2 if self.jaw_per_finger else 1)

    def _fingers(self) -> list[dict[str, int]]:
        """For each designed groove, the relative column index of each of its fields."""
        columns = JAW_COLUMNS[self.jaw]
        count = (2 if self.jaw_per_finger else 1) if columns else 0
        return [{c: N_DESIGN + k * len(columns) + j for j, c in enumerate(columns)}
                for k in range(count)]

    def _check_width(self, arr: np.ndarray, width: int, what: str) -> None:
        if arr.ndim < 1 or arr.shape[-1] != width:
            raise ValueError(f"{what} must have shape (B, {width}) or ({width},) for this "
                             f"design space (jaw {self.jaw!r}"
                             + (", per finger" if self.jaw_per_finger else "")
                             + f"), got {arr.shape}")

    # --- the maps -----------------------------------------------------------------------------

    def _offset_floor(self, width_r: np.ndarray) -> np.ndarray:
        """Lowest relative joint offset of rows of relative finger width ``width_r``: the
        box's, or with :attr:`joints_apart` at least half the width."""
        return np.maximum(self.low[_OFFSET_R], 0.5 * width_r)

    def _depth_ceiling(self, rel: np.ndarray, cols: dict[str, int]) -> np.ndarray:
        """Highest relative depth ``h / w`` of a groove of each row's radius and opening that
        fits the row's finger (the box's high where it is lower, never below the box's low)."""
        length, width = rel[..., 0], rel[..., _WIDTH_R]
        radius, opening = self._jaw_value(rel, cols, _RADIUS), self._jaw_value(rel, cols,
                                                                             _OPENING)
        # mouth + rounding within half the finger, with room for the position's inset
        room = 0.5 * length - corner_radius(width, 1.0) - 4.0 * _INSET * length
        fit = fitting_depth(room, radius, opening)
        fit = np.where(opening == 0.0, np.minimum(fit, radius), fit)
        k = JAW_COLUMNS[self.jaw].index(_DEPTH)
        lo, hi = self.jaw_low[k], self.jaw_high[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.maximum(lo, np.minimum(hi, fit / width))

    def _jaw_value(self, rel: np.ndarray, cols: dict[str, int], name: str) -> np.ndarray:
        """A jaw column of relative rows, or its fixed value for this kind (0)."""
        return rel[..., cols[name]] if name in cols else np.zeros(rel.shape[:-1])

    def relative(self, action) -> np.ndarray:
        """Map normalized actions in [-1, 1] (shape (..., :attr:`n_var`)) to relative
        designs (the columns of :attr:`fields`)."""
        a = np.asarray(action, dtype=np.float64)
        self._check_width(a, self.n_var, "action")
        lo, hi = self.low_array, self.high_array
        rel = lo + 0.5 * (a + 1.0) * (hi - lo)
        if self.joints_apart:
            floor = self._offset_floor(rel[..., _WIDTH_R])
            rel[..., _OFFSET_R] = floor + 0.5 * (a[..., _OFFSET_R] + 1.0) * (
                hi[_OFFSET_R] - floor)
        for cols in self._fingers():
            k = cols[_DEPTH]
            ceiling = self._depth_ceiling(rel, cols)
            rel[..., k] = lo[k] + 0.5 * (a[..., k] + 1.0) * (ceiling - lo[k])
        return rel

    def _jaws_si(self, rel: np.ndarray, radius: np.ndarray) -> list[np.ndarray]:
        """The SI jaw columns (:data:`~envs.model.jaw.JAW_FIELDS` order) of each designed
        groove of relative rows."""
        length, width = rel[..., 0], rel[..., _WIDTH_R]
        out = []
        for cols in self._fingers():
            depth = rel[..., cols[_DEPTH]] * width
            bottom = self._jaw_value(rel, cols, _RADIUS)
            opening = self._jaw_value(rel, cols, _OPENING)
            start = (jaw_mouth_half_width(depth, bottom, opening) + corner_radius(width, 1.0)
                     + _INSET * length)
            centre = start + rel[..., cols[_POSITION]] * (length - 2.0 * start)
            out.append(np.stack([depth * radius, bottom * radius, opening, centre * radius],
                                axis=-1))
        return out

    def scale(self, action, disks) -> np.ndarray:
        """Map normalized actions (shape (B, :attr:`n_var`) or (:attr:`n_var`,)) to SI
        designs for their objects, :attr:`design_width` wide.

        Parameters
        ----------
        action
            Normalized actions in [-1, 1].
        disks
            One :class:`~envs.scene.SoftDisk` for every row or a sequence of one per row (its
            radius and torque unit set the scale; its ``distance_m`` is not used).
        """
        a = np.asarray(action, dtype=np.float64)
        radius, unit = _scales(disks, a.shape[0] if a.ndim == 2 else None)
        rel = self.relative(a)
        base = design_from_relative(rel[..., :N_DESIGN], radius, unit,
                                    placement_support(disks))
        if self.jaw == "straight":
            return base
        return np.concatenate([base, *self._jaws_si(rel, radius)], axis=-1)

    def unscale(self, designs, disks) -> np.ndarray:
        """Map SI designs (shape (B, :attr:`design_width`) or (:attr:`design_width`,)) to
        normalized actions (inverse of :meth:`scale` where the placement was not raised to 0;
        a jaw column this kind fixes is not read)."""
        d = np.asarray(designs, dtype=np.float64)
        self._check_width(d, self.design_width, "designs")
        radius, unit = _scales(disks, d.shape[0] if d.ndim == 2 else None)
        rel = np.concatenate([relative_from_design(d[..., :N_DESIGN], radius, unit,
                                                   placement_support(disks)),
                              self._jaws_relative(d, np.asarray(radius))], axis=-1)
        lo, hi = self.low_array, self.high_array
        action = 2.0 * (rel - lo) / (hi - lo) - 1.0
        if self.joints_apart:
            floor = self._offset_floor(rel[..., _WIDTH_R])
            span = hi[_OFFSET_R] - floor
            # a finger as wide as the box allows leaves one joint offset: its middle coordinate
            share = np.divide(rel[..., _OFFSET_R] - floor, span, out=np.full_like(span, 0.5),
                              where=span > 0)
            action[..., _OFFSET_R] = 2.0 * share - 1.0
        for cols in self._fingers():
            k = cols[_DEPTH]
            span = self._depth_ceiling(rel, cols) - lo[k]
            share = np.divide(rel[..., k] - lo[k], span, out=np.full_like(span, 0.5),
                              where=span > 0)
            action[..., k] = 2.0 * share - 1.0
        return action

    def _jaws_relative(self, d: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """The relative jaw columns (:attr:`jaw_fields`) of SI design rows."""
        length, width = d[..., 0], d[..., 3]
        parts = []
        for k, _ in enumerate(self._fingers()):
            depth, bottom, opening, centre = np.moveaxis(d[..., N_DESIGN + 4 * k:
                                                          N_DESIGN + 4 * k + 4], -1, 0)
            start = (jaw_mouth_half_width(depth, bottom, opening) + corner_radius(width, radius)
                     + _INSET * length)
            span = length - 2.0 * start
            share = np.divide(centre - start, span, out=np.full_like(span, 0.5),
                              where=span > 0)
            values = {_DEPTH: depth / width, _RADIUS: bottom / radius, _OPENING: opening,
                      _POSITION: share}
            parts.extend(values[c] for c in JAW_COLUMNS[self.jaw])
        if not parts:
            return np.zeros((*d.shape[:-1], 0))
        return np.stack(parts, axis=-1)

    def aligned(self, action, reach_r: float = 1.0) -> np.ndarray:
        """Actions of this box from actions whose groove-position coordinates are offsets from
        where the object meets the finger: ``-1`` to ``1`` put the groove's centre ``reach_r``
        disk radii below to ``reach_r`` above the *touch foot* (:func:`touch_foot_r`), clipped
        to the span the groove may take. The other coordinates pass unchanged; straight jaws
        pass whole.

        A groove away from where the object meets the finger leaves a straight bar's grasp,
        so a search in these coordinates meets useful grooves far more often than one in the
        box's own, where the position is a share of a span that moves with the finger length
        and the groove's mouth (:mod:`optim.portfolio`).
        """
        a = np.array(action, dtype=np.float64)
        self._check_width(a, self.n_var, "action")
        if not self._fingers():
            return a
        rel = self.relative(a)
        foot = touch_foot_r(rel)
        length, width = rel[..., 0], rel[..., _WIDTH_R]
        for cols in self._fingers():
            depth = rel[..., cols[_DEPTH]] * width
            bottom = self._jaw_value(rel, cols, _RADIUS)
            opening = self._jaw_value(rel, cols, _OPENING)
            start = (jaw_mouth_half_width(depth, bottom, opening) + corner_radius(width, 1.0)
                     + _INSET * length)
            k = cols[_POSITION]
            centre = foot + reach_r * a[..., k]
            with np.errstate(divide="ignore", invalid="ignore"):
                share = np.clip((centre - start) / (length - 2.0 * start), 0.0, 1.0)
            a[..., k] = 2.0 * np.nan_to_num(share, nan=0.5) - 1.0
        return a

    def unaligned(self, action, reach_r: float = 1.0) -> np.ndarray:
        """The inverse of :meth:`aligned` (search coordinates of this box's actions), where
        the groove's centre lies within ``reach_r`` radii of the touch foot; farther grooves
        are brought to that reach."""
        a = np.array(action, dtype=np.float64)
        self._check_width(a, self.n_var, "action")
        if not self._fingers():
            return a
        rel = self.relative(a)
        foot = touch_foot_r(rel)
        centres = self._jaws_si(rel, np.ones(rel.shape[:-1]))
        for cols, jaw in zip(self._fingers(), centres, strict=True):
            a[..., cols[_POSITION]] = np.clip((jaw[..., 3] - foot) / reach_r, -1.0, 1.0)
        return a

    def sample(self, rng: np.random.Generator, size: int, disks) -> np.ndarray:
        """Draw ``size`` SI designs uniformly in the box for the object(s), shape (size,
        :attr:`design_width`)."""
        return self.scale(rng.uniform(-1.0, 1.0, size=(int(size), self.n_var)), disks)
