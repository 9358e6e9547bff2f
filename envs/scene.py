"""Scene description: the angular gripper, the soft disk and the named paper presets.

All quantities are SI (metres, radians, newtons, N·m, pascals). The frame and the sign
conventions are those of ``docs/model.md``: x to the right, y up, the gripper's symmetry
axis is the y axis, the right joint is at ``(+d_3, 0)`` and the left one at ``(-d_3, 0)``, finger
angles are measured from +y, positive when opening.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from .model.defaults import (
    DEFAULT_AREA_STIFFNESS_SCALE,
    DEFAULT_CONTOUR_STIFFNESS_RATIO,
    DEFAULT_DENSITY_KG_M3,
    DEFAULT_POISSON_RATIO,
    DEFAULT_STIFFNESS_SCALE,
    DEFAULT_THICKNESS_M,
    DEFAULT_YOUNGS_MODULUS_PA,
    FOAM_DENSITY_KG_M3,
    GRAVITY_M_S2,
    MAX_PAYLOAD_FACTOR,
    MAX_SPRING_REL,
    MAX_TORQUE_UNITS,
    PAPER_TORSION_STIFFNESS_NM_PER_RAD,
    PAPER_TORSION_STIFFNESS_REL,
    TPU_DENSITY_KG_M3,
)
from .model.energy import bulk_modulus_2d
from .model.geometry import closed_angle_rad, corner_radius, distance_to_finger_bar
from .model.jaw import (
    DESIGN_WIDTHS,
    JAW_FIELDS,
    LEFT_JAW_FIELDS,
    STRAIGHT,
    JawProfile,
    jaw_row,
    jaws_of_row,
)
from .model.layout import N_OUTLINE, SHAPE_DISK, SHAPE_OUTLINE
from .model.problem import (
    REST_MESSAGES,
    REST_OFFSET,
    REST_OK,
    REST_OVERLAP,
    REST_WIDTH,
    SceneColumns,
    _clearance,
    rest_codes,
)
from .validation import check_plausible, check_range, check_real, slip_hint

__all__ = [
    "Gripper",
    "SoftDisk",
    "Scene",
    "Design",
    "DESIGN_FIELDS",
    "RELATIVE_FIELDS",
    "ALL_DESIGN_FIELDS",
    "design_fields",
    "design_row",
    "design_mapping",
    "PRESETS",
    "design_from_relative",
    "relative_from_design",
    "placement_support",
    "joint_spring",
    "joint_spring_kwargs",
    "joint_spring_nm_per_rad",
    "check_torque",
]

# A design is six numbers in SI units, in this column order.
DESIGN_FIELDS = (
    "finger_length_m",
    "rest_angle_rad",
    "joint_offset_m",
    "finger_width_m",
    "torque_nm",
    "distance_m",
)
N_DESIGN = len(DESIGN_FIELDS)
# A design row may carry jaw profiles after those six (envs.model.jaw.DESIGN_WIDTHS): 6 wide
# (straight bars), 10 (+ JAW_FIELDS: both fingers alike) or 14 (+ LEFT_JAW_FIELDS: the left
# finger's own); the fields of the widest row, in order.
ALL_DESIGN_FIELDS = (*DESIGN_FIELDS, *JAW_FIELDS, *LEFT_JAW_FIELDS)


def design_fields(width: int) -> tuple[str, ...]:
    """The column names of a design row ``width`` wide (one of
    :data:`~envs.model.jaw.DESIGN_WIDTHS`: 6, 10 or 14); ``ValueError`` for another width."""
    if isinstance(width, bool) or width not in DESIGN_WIDTHS:
        raise ValueError(f"a design row has {' or '.join(map(str, DESIGN_WIDTHS))} columns "
                         f"({N_DESIGN} of DESIGN_FIELDS, then JAW_FIELDS, then "
                         f"LEFT_JAW_FIELDS), got {width!r}")
    return ALL_DESIGN_FIELDS[:width]


def design_row(design) -> np.ndarray:
    """A design given by name (``{field: value}``, SI: a result JSON's ``design``) as a row
    6, 10 or 14 wide: the six :data:`DESIGN_FIELDS`, then the jaw fields it has
    (:data:`~envs.model.jaw.JAW_FIELDS`, and :data:`~envs.model.jaw.LEFT_JAW_FIELDS` after
    them).

    Raises
    ------
    ValueError
        A missing design field, left-finger jaw fields without the jaw fields, a partial set
        of jaw fields, or a value that is not a number.
    """
    if not hasattr(design, "keys"):
        raise ValueError(f"a design must be a mapping of its fields, got {type(design).__name__}")
    names = list(DESIGN_FIELDS)
    for group in (JAW_FIELDS, LEFT_JAW_FIELDS):
        present = [k for k in group if k in design]
        if not present:
            break
        if len(present) != len(group):
            missing = [k for k in group if k not in design]
            raise ValueError(f"a design with {present[0]!r} needs all of {group}, missing "
                             f"{missing[0]!r}")
        names.extend(group)
    missing = [k for k in ALL_DESIGN_FIELDS if k not in names and k in design]
    if missing:
        raise ValueError(f"a design with {missing[0]!r} needs the jaw fields {JAW_FIELDS}")
    absent = [k for k in DESIGN_FIELDS if k not in design]
    if absent:
        raise ValueError(f"a design needs the fields {DESIGN_FIELDS}, missing {absent[0]!r}")
    return np.array([check_real(k, design[k]) for k in names], dtype=np.float64)


def design_mapping(row) -> dict[str, float]:
    """A design row 6, 10 or 14 wide as ``{field: value}`` (the inverse of
    :func:`design_row`)."""
    values = np.asarray(row, dtype=np.float64).reshape(-1)
    return dict(zip(design_fields(values.size), values.tolist(), strict=True))


# The same design relative to its object, in this column order: lengths in disk radii, the
# torque in the disk's torque unit ``s E t r^2`` and, instead of the placement ``d_1``, the
# clearance between the disk and the gripping faces at rest. The model is invariant under this
# scaling (the solver works in these units), so one box of relative designs means the same for
# a 70 mm foam disk and a 2 mm TPU bead; and a positive clearance is valid at rest by
# construction, which an independent placement ``d_1 / r`` is not (a third of such a box
# overlaps the fingers at small rest angles).
# the fields of a SoftDisk with a plausible range (envs.model.defaults.PLAUSIBLE_RANGES)
PLAUSIBLE_DISK_FIELDS = ("radius_m", "distance_m", "thickness_m", "youngs_modulus_pa",
                         "stiffness_scale", "offset_x_m", "density_kg_m3")

RELATIVE_FIELDS = (
    "finger_length_r",
    "rest_angle_rad",
    "joint_offset_r",
    "finger_width_r",
    "torque_rel",
    "rest_clearance_r",
)


@dataclass(frozen=True)
class Gripper:
    """Symmetric angular gripper with two rigid fingers on revolute joints.

    A length or a joint spring outside its plausible range
    (:data:`~envs.model.defaults.PLAUSIBLE_RANGES`: ``finger_length_m = 200`` was most likely
    typed in millimetres) is refused, naming the likely unit.

    Parameters
    ----------
    finger_length_m
        Length ``l`` of each finger from its joint to its tip [m].
    rest_angle_rad
        Rest angle ``theta_a0`` of each finger, measured from the +y axis [rad], in (0, pi/2).
    joint_offset_m
        Distance ``d_3`` of each joint from the symmetry axis [m].
    finger_width_m
        Width ``w`` of each finger bar [m]; the gripping face is ``w/2`` from the bar axis.
    torsion_stiffness_nm_per_rad
        Torsion spring ``k_f`` at each joint [N·m/rad]; must be positive so that the jaw position
        is unique before contact.
    jaw
        The groove cut into the gripping faces (:class:`envs.model.jaw.JawProfile`: a cradle,
        a V-groove; default the straight bar), both fingers alike.
    left_jaw
        The left finger's groove where it differs from the right one's (default ``None``: the
        same as ``jaw``).
    """

    finger_length_m: float
    rest_angle_rad: float
    joint_offset_m: float
    finger_width_m: float
    torsion_stiffness_nm_per_rad: float
    jaw: JawProfile = STRAIGHT
    left_jaw: JawProfile | None = None

    def __post_init__(self) -> None:
        check_range("finger_length_m", self.finger_length_m, 0.0, math.inf, low_open=True)
        check_range(
            "rest_angle_rad", self.rest_angle_rad, 0.0, math.pi / 2, low_open=True, high_open=True
        )
        check_range("joint_offset_m", self.joint_offset_m, 0.0, math.inf)
        check_range("finger_width_m", self.finger_width_m, 0.0, math.inf, low_open=True)
        if not self.finger_width_m < self.finger_length_m:
            # a relation of two given values: name both, not a range derived from one
            raise ValueError(
                f"finger_length_m = {self.finger_length_m!r} must be larger than "
                f"finger_width_m = {self.finger_width_m!r} (a finger is longer than it is "
                "wide)")
        check_range(
            "torsion_stiffness_nm_per_rad", self.torsion_stiffness_nm_per_rad, 0.0, math.inf,
            low_open=True,
        )
        for f in fields(self):
            if f.name not in ("jaw", "left_jaw"):
                check_plausible(f.name, getattr(self, f.name))
                object.__setattr__(self, f.name, float(getattr(self, f.name)))
        for name in ("jaw", "left_jaw"):
            value = getattr(self, name)
            if value is None and name == "left_jaw":
                continue
            if not isinstance(value, JawProfile):
                raise ValueError(f"{name} must be a JawProfile, got {type(value).__name__}")
            value.check_fits(self.finger_length_m, self.finger_width_m)

    @property
    def jaws(self) -> tuple[JawProfile, JawProfile]:
        """The right and the left finger's jaw profiles."""
        return self.jaw, self.jaw if self.left_jaw is None else self.left_jaw


@dataclass(frozen=True)
class SoftDisk:
    """Soft 2-D disk (extruded by a thickness) whose centre is pinned where it was placed.

    An object that is not a disk is an :class:`envs.objects.SoftObject`, this class with an
    ``outline`` and an ``orientation_rad`` (built by :func:`envs.objects.soft_object`); a
    disk's ``outline`` is ``None``.

    A radius, thickness, modulus, density, stiffness scale or placement outside its plausible
    range (:data:`~envs.model.defaults.PLAUSIBLE_RANGES`: most likely typed in another unit)
    is refused, naming the likely unit (:func:`~envs.validation.check_plausible`).

    Parameters
    ----------
    radius_m
        Disk radius ``r`` [m].
    distance_m
        Distance ``d_1`` from the joints' line (y = 0) to the nearest point of the undeformed disk
        [m]; the centre sits at ``(x_c, d_1 + r)``.
    youngs_modulus_pa
        Young's modulus ``E`` [Pa].
    poisson_ratio
        Poisson's ratio ``nu`` [-], in (-1, 0.5).
    thickness_m
        Out-of-plane thickness ``t`` [m].
    stiffness_scale
        Calibration scale ``s`` multiplying every spring stiffness [-].
    contour_stiffness_ratio
        Second calibration factor ``rho_c`` multiplying only the contour (external) springs,
        on top of ``stiffness_scale`` [-], in (0, 1e3]: ``k_ext = rho_c s E t A / h^2`` while
        ``k_int = 2 s E t A / r^2`` (van Gelder rule). Default 1 (the plain stiffness rule).
    area_stiffness_scale
        Scale ``c_A`` of the area energy of the model family [-], in [0, 1e3]: every fan
        triangle resists area change with ``E_A = 1/2 kappa t A0 (ln(A / A0))^2``, ``kappa =
        c_A K`` and ``K`` the plane-strain bulk modulus ``lambda + mu`` of E and nu
        (:attr:`bulk_modulus_pa`). Any ``c_A > 0`` keeps every triangle's area positive: the fan
        cannot fold. Default 0: springs only, the paper's model.
    offset_x_m
        Lateral placement ``x_c`` of the centre across the gripper's axis [m], any finite
        number: the centre sits at ``(x_c, d_1 + r)``. Default 0, on the axis. A displaced
        object is held where it was placed (its centre stays fixed while the jaws close): a
        conservative bench, where a free object on a slippery surface would be pushed towards
        the middle. A displacement that brings the disk onto a finger at rest makes the scene
        invalid (:data:`~envs.model.problem.REST_OFFSET`).
    density_kg_m3
        Density ``rho`` of the object [kg/m^3], > 0: its mass ``rho pi r^2 t`` is the payload
        a grasp must carry (:meth:`payload_n`). Default 1000, water-like, as in an object file
        (:data:`~envs.model.defaults.DEFAULT_DENSITY_KG_M3`); soft tissue ~1060, fruit
        950-1050, silicone ~1100; the paper's presets are soft foam, 50
        (:data:`~envs.model.defaults.FOAM_DENSITY_KG_M3`). A radius, thickness, modulus or
        density outside the plausible range of a graspable object
        (:data:`~envs.model.defaults.PLAUSIBLE_RANGES`: most likely typed in another unit)
        gives a :class:`~envs.validation.UnitSlipWarning` naming the likely unit.
    """

    radius_m: float
    distance_m: float
    youngs_modulus_pa: float = DEFAULT_YOUNGS_MODULUS_PA
    poisson_ratio: float = DEFAULT_POISSON_RATIO
    thickness_m: float = DEFAULT_THICKNESS_M
    stiffness_scale: float = DEFAULT_STIFFNESS_SCALE
    contour_stiffness_ratio: float = DEFAULT_CONTOUR_STIFFNESS_RATIO
    area_stiffness_scale: float = DEFAULT_AREA_STIFFNESS_SCALE
    offset_x_m: float = 0.0
    density_kg_m3: float = DEFAULT_DENSITY_KG_M3
    # a disk has no outline (not fields: envs.objects.SoftObject adds them as its own)
    outline = None
    orientation_rad = 0.0

    def __post_init__(self) -> None:
        check_range("radius_m", self.radius_m, 0.0, math.inf, low_open=True)
        check_range("distance_m", self.distance_m)
        check_range("youngs_modulus_pa", self.youngs_modulus_pa, 0.0, math.inf, low_open=True)
        check_range("poisson_ratio", self.poisson_ratio, -1.0, 0.5, low_open=True, high_open=True)
        check_range("thickness_m", self.thickness_m, 0.0, math.inf, low_open=True)
        check_range("stiffness_scale", self.stiffness_scale, 0.0, math.inf, low_open=True)
        check_range(
            "contour_stiffness_ratio", self.contour_stiffness_ratio, 0.0, 1e3, low_open=True
        )
        check_range("area_stiffness_scale", self.area_stiffness_scale, 0.0, 1e3)
        check_range("offset_x_m", self.offset_x_m)
        check_range("density_kg_m3", self.density_kg_m3, 0.0, math.inf, low_open=True)
        for name in PLAUSIBLE_DISK_FIELDS:  # (as given: quoted as the caller wrote it)
            check_plausible(name, getattr(self, name))
        for f in fields(SoftDisk):  # (a SoftObject's outline is not a number)
            object.__setattr__(self, f.name, float(getattr(self, f.name)))

    @property
    def mass_kg(self) -> float:
        """Mass ``rho pi r^2 t`` of the object [kg]."""
        return self.density_kg_m3 * math.pi * self.radius_m**2 * self.thickness_m

    def payload_n(self, payload_factor: float) -> float:
        """The payload ``W = f m g`` a grasp must carry [N] (g = 9.81 m/s^2).

        Parameters
        ----------
        payload_factor
            ``f`` [-], in [0, 100]: 2 (the default of the evaluators) is the weight plus a lift
            at 1 g, 0 no payload.
        """
        f = check_range("payload_factor", payload_factor, 0.0, MAX_PAYLOAD_FACTOR)
        return f * self.mass_kg * GRAVITY_M_S2

    @property
    def bulk_modulus_pa(self) -> float:
        """Plane-strain 2-D bulk modulus ``K = lambda + mu = E / (2 (1 + nu) (1 - 2 nu))`` [Pa]
        (the plane of the FEM reference)."""
        return bulk_modulus_2d(self.youngs_modulus_pa, self.poisson_ratio)

    @property
    def torque_unit_nm(self) -> float:
        """Torque unit ``s E t r^2`` of this disk [N·m]: the solver's unit of torque. A torque of
        a few hundredths of it squeezes the disk by a few percent whatever its size and
        stiffness (0.2 N·m on the paper's r = 0.07 m foam disk is 0.04 units)."""
        return (self.stiffness_scale * self.youngs_modulus_pa * self.thickness_m
                * self.radius_m**2)

    @property
    def center_m(self) -> np.ndarray:
        """Position of the pinned centre ``(x_c, d_1 + r)`` [m] (an outline's centroid:
        ``d_1`` plus how far its lowest point lies below it, :attr:`lift_m`)."""
        return np.array([self.offset_x_m, self.distance_m + self.lift_m])

    @property
    def lift_m(self) -> float:
        """Height of the centre above the object's lowest point [m]: ``r`` for a disk, for
        an outline at its orientation its own."""
        if self.outline is None:
            return self.radius_m
        return self.radius_m * self.outline.lowest(self.orientation_rad)

    @property
    def shape(self) -> str:
        """The object's shape: ``"disk"``, or its outline's kind (``"ellipse"``, ...)."""
        return "disk" if self.outline is None else self.outline.kind

    def outline_columns(self) -> tuple[float, float, np.ndarray]:
        """The scene row's shape code, orientation and outline coefficients (layout
        ``S_SHAPE``.. of :mod:`envs.model.layout`; zeros for a disk)."""
        if self.outline is None:
            return SHAPE_DISK, 0.0, np.zeros(N_OUTLINE)
        return SHAPE_OUTLINE, self.orientation_rad, self.outline.coefficients()

    def contour_m(self, n: int = 256) -> np.ndarray:
        """``n`` points of the undeformed outline in the gripper frame [m], counter-
        clockwise from the top, spaced evenly by arc length (a disk's by angle), (n, 2)."""
        if self.outline is None:
            ang = math.pi / 2 + 2 * math.pi * np.arange(n) / n
            unit = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        else:
            unit = self.outline.contour(n, self.orientation_rad)
        return self.center_m + self.radius_m * unit


@dataclass(frozen=True)
class Scene:
    """A gripper and the soft disk it grasps.

    Construction checks that the disk lies between the fingers and does not overlap them at rest
    (``ValueError`` otherwise). A disk the fingers cannot reach even fully closed is allowed and
    listed in :attr:`warnings`.
    """

    gripper: Gripper
    disk: SoftDisk
    warnings: tuple[str, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        g, d = self.gripper, self.disk
        if not isinstance(g, Gripper):
            raise ValueError(f"gripper must be a Gripper, got {type(g).__name__}")
        if not isinstance(d, SoftDisk):
            raise ValueError(f"disk must be a SoftDisk, got {type(d).__name__}")
        code = int(rest_codes(self.rows(0.0))[0])
        if code == REST_OVERLAP:
            _, clearance = _clearance(self.columns(0.0))
            raise ValueError(
                f"the fingers overlap the disk at rest (clearance {float(clearance[0]):.3g} m): "
                "increase rest_angle_rad or distance_m (allowed: clearance > 0)")
        if code == REST_OFFSET:
            front, clearance = _clearance(self.columns(0.0))
            raise ValueError(
                f"the disk displaced by offset_x_m = {d.offset_x_m!r} m "
                + (f"overlaps a finger at rest (clearance {float(clearance[0]):.3g} m)"
                   if front[0] > 0 else "lies behind a gripping face at rest")
                + ", where the centred disk would be clear: decrease |offset_x_m| (allowed: "
                "clearance > 0 to both fingers)")
        if code == REST_WIDTH:
            raise ValueError(
                f"finger_width_m = {g.finger_width_m!r} must be smaller than the disk diameter "
                f"2 * radius_m = {2 * d.radius_m!r}")
        if code != REST_OK:
            raise ValueError(REST_MESSAGES[code])
        object.__setattr__(self, "warnings", self._reach_warnings())

    def _reach_warnings(self) -> tuple[str, ...]:
        g, d = self.gripper, self.disk
        # each finger over 64 angles from closed to rest, in one vectorized call per finger:
        # this runs for every Scene an optimizer builds; the farther finger decides (a displaced
        # disk may be in reach of one finger only)
        angles = np.linspace(closed_angle_rad(g), g.rest_angle_rad, 64)
        rounding = corner_radius(g.finger_width_m, d.radius_m)
        reach = max(float(np.min(distance_to_finger_bar(g, side, angles, d.center_m, jaw,
                                                        rounding)))
                    for side, jaw in zip((0, 1), g.jaws, strict=True))
        # an outline: its farthest point from the centroid
        farthest = d.radius_m if d.outline is None else d.radius_m * d.outline.radius_range()[1]
        if reach > farthest:
            return (
                f"the fingers cannot reach the disk even fully closed (closest approach "
                f"{reach - farthest:.3g} m): no grasp is possible",
            )
        return ()

    def columns(self, torque_nm: float = 0.0) -> SceneColumns:
        """This scene at an actuation torque [N·m] as one row of :class:`SceneColumns`."""
        return SceneColumns.from_rows(self.rows(torque_nm))

    def rows(self, torque_nm: float = 0.0) -> np.ndarray:
        """This scene at an actuation torque [N·m] as a (1, N_SCENE) scene matrix (layout
        ``S_*`` of :mod:`envs.model.layout`)."""
        g, d = self.gripper, self.disk
        shape, orientation, outline = d.outline_columns()
        return np.array([[g.finger_length_m, g.rest_angle_rad, g.joint_offset_m,
                          g.finger_width_m, g.torsion_stiffness_nm_per_rad, d.radius_m,
                          d.distance_m, d.youngs_modulus_pa, d.poisson_ratio, d.thickness_m,
                          d.stiffness_scale, d.contour_stiffness_ratio, d.area_stiffness_scale,
                          float(torque_nm), d.offset_x_m, shape, orientation, *outline,
                          *(v for jaw in g.jaws for v in jaw_row(jaw))]])

    @property
    def reachable(self) -> bool:
        """Whether the fingers can touch the disk at some closing angle."""
        return not self.warnings

    @classmethod
    def preset(cls, name: str) -> Scene:
        """Build a named scene.

        Parameters
        ----------
        name
            One of :data:`PRESETS`: ``paper-r050``, ``paper-r070``, ``paper-r100`` (paper
            Tables 1 and 2 with the default material) and ``forceps-a`` ... ``forceps-f``
            (Tables 3 and 4, TPU with ``s = 0.033``, rest angle 15 degrees and
            ``k_f = 1e-3`` N·m/rad chosen here since the paper leaves them to the user).
        """
        if name not in PRESETS:
            raise ValueError(f"unknown scene preset {name!r}; allowed: {sorted(PRESETS)}")
        gripper, disk = PRESETS[name]
        return cls(gripper, disk)

    def check_torque(self, torque_nm, name: str = "torque_nm") -> float:
        """Validate an actuation torque on this scene [N·m] (:func:`check_torque`: at most
        :data:`~envs.model.defaults.MAX_TORQUE_UNITS` torque units of the disk beyond its
        joint springs); returns it as ``float``."""
        return check_torque(name, torque_nm, self.disk.torque_unit_nm,
                            self.gripper.torsion_stiffness_nm_per_rad)

    def with_changes(self, **changes) -> Scene:
        """Return a copy with gripper or disk fields replaced by name."""
        gk = {k: v for k, v in changes.items() if k in Gripper.__dataclass_fields__}
        dk = {k: v for k, v in changes.items() if k in type(self.disk).__dataclass_fields__}
        unknown = set(changes) - set(gk) - set(dk)
        if unknown:
            raise ValueError(f"unknown scene fields {sorted(unknown)}")
        return Scene(replace(self.gripper, **gk), replace(self.disk, **dk))


@dataclass(frozen=True)
class Design:
    """One gripper design and object placement, in SI units.

    A design may be physically impossible (fingers overlapping the disk, width larger than the
    length, a groove that does not fit its finger, ...): :func:`evaluate_designs` reports it
    with ``valid_at_rest=False`` and the invalid penalty instead of raising, so that optimizers
    can explore freely.

    Parameters
    ----------
    finger_length_m
        Finger length ``l`` from joint to tip [m].
    rest_angle_rad
        Rest angle ``theta_a0`` of both fingers, from the +y axis [rad].
    joint_offset_m
        Joint distance ``d_3`` from the symmetry axis [m].
    finger_width_m
        Finger width ``w`` [m].
    torque_nm
        Actuation torque ``T_a`` on each finger [N·m].
    distance_m
        Distance ``d_1`` from the joints' line to the nearest point of the undeformed disk [m].
    jaw
        The groove cut into the gripping faces (:class:`~envs.model.jaw.JawProfile`; default
        the straight bar), both fingers alike.
    left_jaw
        The left finger's groove where it differs (default ``None``: the same as ``jaw``).
    """

    finger_length_m: float
    rest_angle_rad: float
    joint_offset_m: float
    finger_width_m: float
    torque_nm: float
    distance_m: float
    jaw: JawProfile = STRAIGHT
    left_jaw: JawProfile | None = None

    def __post_init__(self) -> None:
        # any number (an impossible design is the evaluator's to report), but a number
        for name in DESIGN_FIELDS:
            object.__setattr__(self, name, check_real(name, getattr(self, name)))
        if not isinstance(self.jaw, JawProfile):
            raise ValueError(f"jaw must be a JawProfile, got {type(self.jaw).__name__}")
        if self.left_jaw is not None and not isinstance(self.left_jaw, JawProfile):
            raise ValueError(f"left_jaw must be a JawProfile, got "
                             f"{type(self.left_jaw).__name__} (None: the same as jaw)")

    @property
    def width(self) -> int:
        """Columns of :meth:`to_array`: 6 with straight bars, 10 with one jaw profile for both
        fingers, 14 with the left finger's own."""
        if self.left_jaw is not None:
            return DESIGN_WIDTHS[2]
        return DESIGN_WIDTHS[0] if self.jaw == STRAIGHT else DESIGN_WIDTHS[1]

    def to_scene(self, disk: SoftDisk, torsion_stiffness_nm_per_rad: float | None = None, *,
                 torsion_stiffness_rel: float | None = None) -> Scene:
        """The scene of this design with a disk (its ``distance_m`` replaced by the design's).

        The joint spring is relative to the disk unless given in N·m/rad
        (:func:`joint_spring`; default: the paper gripper's ratio to its r = 0.07 m disk's
        torque unit). The gripper carries the design's jaws. The batch evaluator maps design
        rows to scenes the same way (:func:`envs.evaluate.evaluate_designs`); raises
        ``ValueError`` for a design invalid at rest, as :class:`Scene` does.
        """
        kf = joint_spring_nm_per_rad(disk, torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
        gripper = Gripper(self.finger_length_m, self.rest_angle_rad, self.joint_offset_m,
                          self.finger_width_m, kf, jaw=self.jaw, left_jaw=self.left_jaw)
        return Scene(gripper, replace(disk, distance_m=self.distance_m))

    @classmethod
    def from_scene(cls, scene: Scene, torque_nm: float) -> Design:
        """The design of a scene's gripper (its jaws included) and disk placement at an
        actuation torque."""
        g = scene.gripper
        return cls(g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m,
                   torque_nm, scene.disk.distance_m, g.jaw, g.left_jaw)

    def to_array(self, width: int | None = None) -> np.ndarray:
        """The design as a float64 row in :data:`ALL_DESIGN_FIELDS` order, :attr:`width`
        wide (6, 10 or 14), or ``width`` wide when given and at least :attr:`width` (a
        straight design as 10 columns has depth 0; the left jaw repeats the jaw)."""
        width = self.width if width is None else width
        design_fields(width)
        if width < self.width:
            raise ValueError(f"this design needs {self.width} columns, got width={width!r}")
        jaws = [self.jaw, self.jaw if self.left_jaw is None else self.left_jaw]
        values = [getattr(self, name) for name in DESIGN_FIELDS]
        for jaw in jaws[: (width - N_DESIGN) // len(JAW_FIELDS)]:
            values.extend(jaw_row(jaw))
        return np.array(values, dtype=np.float64)

    @classmethod
    def from_array(cls, values) -> Design:
        """Build a design from a row of 6, 10 or 14 numbers in :data:`ALL_DESIGN_FIELDS`
        order (``ValueError`` for another shape or a groove out of the ranges of
        :class:`~envs.model.jaw.JawProfile`)."""
        arr = np.asarray(values, dtype=np.float64)
        if arr.ndim != 1 or arr.size not in DESIGN_WIDTHS:
            raise ValueError(f"a design needs shape (n,) with n in {DESIGN_WIDTHS}, got "
                             f"{arr.shape}")
        jaw, left = jaws_of_row(arr)
        return cls(*arr[:N_DESIGN].tolist(), jaw, left)


SPRING_TWICE = ("give the joint spring once: torsion_stiffness_rel (relative to the object) or "
                "torsion_stiffness_nm_per_rad (absolute), not both")


def check_torque(name: str, torque_nm, torque_unit_nm: float,
                 torsion_stiffness_nm_per_rad: float) -> float:
    """Validate an actuation torque [N·m] on an object and gripper: a real number >= 0 and
    at most :data:`~envs.model.defaults.MAX_TORQUE_UNITS` of the object's torque unit ``s E t
    r^2`` (``torque_unit_nm``, :attr:`SoftDisk.torque_unit_nm`) beyond the moment of the joint
    springs when the fingers close fully (``k_f pi / 2``); returns it as ``float``.

    Raises
    ------
    ValueError
        One line naming ``name``, the value, the plausible range and the unit it was most
        likely typed in (N·mm for N·m).
    """
    t = check_range(name, torque_nm, 0.0, math.inf)
    springs = torsion_stiffness_nm_per_rad * math.pi / 2.0
    ceiling = MAX_TORQUE_UNITS * torque_unit_nm + springs
    if t > ceiling:
        raise ValueError(
            f"{name} = {torque_nm!r} is outside the plausible range [0, {ceiling:.4g}] N·m of "
            f"this object and gripper ({MAX_TORQUE_UNITS:g} of the object's torque unit s E t "
            f"r^2 = {torque_unit_nm:.4g} N·m beyond the joint springs' {springs:.4g} N·m at "
            "full closing)" + slip_hint(name, t, lambda x: x <= ceiling))
    return t


def joint_spring(torsion_stiffness_rel=None, torsion_stiffness_nm_per_rad=None
                 ) -> tuple[float | None, float | None]:
    """The joint torsion spring of a design problem, validated: ``(rel, None)`` or
    ``(None, nm_per_rad)``.

    A design space relative to its object needs a joint spring that scales like its torque:
    ``torsion_stiffness_rel`` is ``k_f`` in the object's torque unit ``s E t r^2`` per radian
    [1/rad] (:attr:`SoftDisk.torque_unit_nm`), the default (both ``None``) the paper gripper's
    ``0.073 N·m/rad`` over its r = 0.07 m disk's 4.9 N·m
    (:data:`~envs.model.defaults.PAPER_TORSION_STIFFNESS_REL`), at most
    :data:`~envs.model.defaults.MAX_SPRING_REL`. An absolute spring is asked for by name,
    ``torsion_stiffness_nm_per_rad`` [N·m/rad], in its plausible range (up to 1e4 N·m/rad).
    Both must be positive and finite.

    Raises
    ------
    ValueError
        When both are given, or a value is not a positive finite number.
    """
    if torsion_stiffness_nm_per_rad is not None:
        if torsion_stiffness_rel is not None:
            raise ValueError(SPRING_TWICE)
        check_range("torsion_stiffness_nm_per_rad", torsion_stiffness_nm_per_rad, 0.0,
                    math.inf, low_open=True)
        return None, check_plausible("torsion_stiffness_nm_per_rad",
                                     torsion_stiffness_nm_per_rad)
    rel = PAPER_TORSION_STIFFNESS_REL if torsion_stiffness_rel is None else torsion_stiffness_rel
    return check_range("torsion_stiffness_rel", rel, 0.0, MAX_SPRING_REL, low_open=True), None


def joint_spring_kwargs(torsion_stiffness_rel=None, torsion_stiffness_nm_per_rad=None
                        ) -> dict[str, float]:
    """The joint spring, validated, as the one keyword argument that gives it
    (``torsion_stiffness_rel`` or ``torsion_stiffness_nm_per_rad``; see :func:`joint_spring`)."""
    rel, absolute = joint_spring(torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
    if rel is None:
        return {"torsion_stiffness_nm_per_rad": absolute}
    return {"torsion_stiffness_rel": rel}


def joint_spring_nm_per_rad(disk: SoftDisk, torsion_stiffness_rel=None,
                            torsion_stiffness_nm_per_rad=None) -> float:
    """The joint spring ``k_f`` [N·m/rad] for a disk (see :func:`joint_spring`)."""
    rel, absolute = joint_spring(torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
    return absolute if rel is None else rel * disk.torque_unit_nm


def placement_support(disks):
    """How objects that are not disks sit before the faces, for :func:`design_from_relative`:
    ``None`` when every object is a disk, else a function of the rows' rest angles [rad]
    returning ``(h, lift)`` in each object's radii: how far it reaches towards either
    gripping face (:meth:`envs.objects.Outline.face_support`; 1 for a disk) and how far its
    centre lies above its lowest point (:attr:`SoftDisk.lift_m` over r; 1 for a disk).

    ``disks``: one :class:`SoftDisk` (any row shape) or a sequence of one per row.
    """
    one = isinstance(disks, SoftDisk)
    objects = [disks] if one else list(disks)
    if all(d.outline is None for d in objects):
        return None

    def support(angle):
        angle = np.asarray(angle, dtype=np.float64)
        if one:
            d = objects[0]
            return (d.outline.face_support(angle, d.orientation_rad),
                    np.full(angle.shape, d.lift_m / d.radius_m))
        h, lift = np.ones(angle.shape), np.ones(angle.shape)
        for i, d in enumerate(objects):
            if d.outline is not None:
                h[i] = d.outline.face_support(angle[i], d.orientation_rad)
                lift[i] = d.lift_m / d.radius_m
        return h, lift

    return support


def design_from_relative(relative, radius_m, torque_unit_nm, support=None) -> np.ndarray:
    """SI designs of relative ones (columns of :data:`RELATIVE_FIELDS`), shape (..., 6).

    The placement is chosen so that the gripping faces clear the disk at rest by the relative
    clearance ``g``: ``d_1 = (r (1 + g) + w / 2 - d_3 cos theta_a0) / sin theta_a0 - r``, but never
    below 0 (the disk does not sit below the joints' line; a larger ``d_1`` only widens the
    clearance). When the disk centre lies beyond a fingertip the clearance to the finger bar
    is larger than ``g r``, so a design with ``g > 0`` is always clear of the fingers at rest.

    Parameters
    ----------
    relative
        Relative designs, shape (..., 6).
    radius_m
        Disk radius ``r`` [m], scalar or broadcastable to the rows (...).
    torque_unit_nm
        The disk's torque unit ``s E t r^2`` [N·m] (:attr:`SoftDisk.torque_unit_nm`), same shape
        rules.
    support
        For objects that are not disks, :func:`placement_support` of them: the faces then
        clear the outline (its reach ``h r`` towards them) by ``g r`` and ``d_1`` is measured
        to its lowest point, ``d_1 = (r (g + h) + w / 2 - d_3 cos theta_a0) / sin theta_a0 -
        lift r``; ``None``: disks.
    """
    rel = np.asarray(relative, dtype=np.float64)
    r = np.asarray(radius_m, dtype=np.float64)
    length, angle, offset, width = rel[..., 0] * r, rel[..., 1], rel[..., 2] * r, rel[..., 3] * r
    torque = rel[..., 4] * np.asarray(torque_unit_nm, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        if support is None:
            distance = (r * (1.0 + rel[..., 5]) + width / 2 - offset * np.cos(angle)) / np.sin(
                angle) - r
        else:
            reach, lift = support(angle)
            distance = (r * (reach + rel[..., 5]) + width / 2 - offset * np.cos(angle)) / np.sin(
                angle) - r * lift
    return np.stack([length, angle, offset, width, torque, np.maximum(distance, 0.0)], axis=-1)


def relative_from_design(designs, radius_m, torque_unit_nm, support=None) -> np.ndarray:
    """Relative designs (columns of :data:`RELATIVE_FIELDS`) of SI ones, shape (..., 6).

    The inverse of :func:`design_from_relative` where its placement was not raised to 0; the
    clearance is that of the gripping-face line, ``(d_3 cos theta_a0 + (d_1 + r) sin theta_a0
    - w / 2) / r - 1`` (objects that are not disks: ``support`` as there, ``lift r`` in place
    of the second ``r`` and ``h`` of the ``1``).
    """
    des = np.asarray(designs, dtype=np.float64)
    r = np.asarray(radius_m, dtype=np.float64)
    length, angle, offset, width, torque, distance = np.moveaxis(des, -1, 0)
    if support is None:
        clearance = (offset * np.cos(angle) + (distance + r) * np.sin(angle) - width / 2) / r - 1.0
    else:
        reach, lift = support(angle)
        clearance = (offset * np.cos(angle) + (distance + r * lift) * np.sin(angle)
                     - width / 2) / r - reach
    return np.stack([length / r, angle, offset / r, width / r,
                     torque / np.asarray(torque_unit_nm, dtype=np.float64), clearance], axis=-1)


PAPER_GRIPPER = Gripper(
    finger_length_m=0.2,
    rest_angle_rad=math.radians(45.0),
    joint_offset_m=0.025,
    finger_width_m=0.01,
    torsion_stiffness_nm_per_rad=PAPER_TORSION_STIFFNESS_NM_PER_RAD,
)
FORCEPS_GRIPPER = Gripper(
    finger_length_m=0.016,
    rest_angle_rad=math.radians(15.0),
    joint_offset_m=0.0001,
    finger_width_m=0.0003,
    torsion_stiffness_nm_per_rad=1e-3,
)
TPU_MODULUS_PA = 29e6
TPU_SCALE = 0.033

PRESETS: dict[str, tuple[Gripper, SoftDisk]] = {
    "paper-r050": (PAPER_GRIPPER, SoftDisk(0.05, 0.004, density_kg_m3=FOAM_DENSITY_KG_M3)),
    "paper-r070": (PAPER_GRIPPER, SoftDisk(0.07, 0.013, density_kg_m3=FOAM_DENSITY_KG_M3)),
    "paper-r100": (PAPER_GRIPPER, SoftDisk(0.10, 0.025, density_kg_m3=FOAM_DENSITY_KG_M3)),
}
for _tag, (_r_mm, _d_mm) in zip(
    "abcdef", [(2, 11), (2, 15), (2.5, 13), (2.5, 16), (3, 13), (3, 15)], strict=True
):
    PRESETS[f"forceps-{_tag}"] = (
        FORCEPS_GRIPPER,
        SoftDisk(
            _r_mm * 1e-3,
            _d_mm * 1e-3,
            youngs_modulus_pa=TPU_MODULUS_PA,
            stiffness_scale=TPU_SCALE,
            density_kg_m3=TPU_DENSITY_KG_M3,
        ),
    )
