"""Scene description: the angular gripper, the soft disk and the named paper presets.

All quantities are SI (metres, radians, newtons, N·m, pascals). The frame and the sign
conventions are those of ``shared/CONVENTIONS.md``: x to the right, y up, the gripper's symmetry
axis is the y axis, the right joint is at ``(+d_3, 0)`` and the left one at ``(-d_3, 0)``, finger
angles are measured from +y, positive when opening.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

__all__ = [
    "Gripper",
    "SoftDisk",
    "Scene",
    "PRESETS",
    "check_range",
    "closed_angle_rad",
    "finger_frame",
]


def check_range(
    name: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Validate that ``value`` is a finite real number inside an interval.

    Parameters
    ----------
    name
        Name of the parameter, used in the error message.
    value
        The value to check.
    low, high
        Interval bounds.
    low_open, high_open
        Whether the bounds are excluded.

    Returns
    -------
    float
        ``value`` converted to ``float``.

    Raises
    ------
    ValueError
        If ``value`` is not a finite number or lies outside the interval; the message names the
        parameter, the value and the allowed range.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    lo_b = "(" if low_open else "["
    hi_b = ")" if high_open else "]"
    allowed = f"{lo_b}{low:g}, {high:g}{hi_b}"
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite and in {allowed}, got {v!r}")
    below = v <= low if low_open else v < low
    above = v >= high if high_open else v > high
    if below or above:
        raise ValueError(f"{name} = {v!r} is outside the allowed range {allowed}")
    return v


@dataclass(frozen=True)
class Gripper:
    """Symmetric angular gripper with two rigid fingers on revolute joints.

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
    """

    finger_length_m: float
    rest_angle_rad: float
    joint_offset_m: float
    finger_width_m: float
    torsion_stiffness_nm_per_rad: float

    def __post_init__(self) -> None:
        check_range("finger_length_m", self.finger_length_m, 0.0, math.inf, low_open=True)
        check_range(
            "rest_angle_rad", self.rest_angle_rad, 0.0, math.pi / 2, low_open=True, high_open=True
        )
        check_range("joint_offset_m", self.joint_offset_m, 0.0, math.inf)
        check_range(
            "finger_width_m", self.finger_width_m, 0.0, self.finger_length_m, low_open=True,
            high_open=True,
        )
        check_range(
            "torsion_stiffness_nm_per_rad", self.torsion_stiffness_nm_per_rad, 0.0, math.inf,
            low_open=True,
        )
        for f in fields(self):
            object.__setattr__(self, f.name, float(getattr(self, f.name)))


@dataclass(frozen=True)
class SoftDisk:
    """Soft 2-D disk (extruded by a thickness) whose centre is pinned.

    Parameters
    ----------
    radius_m
        Disk radius ``r`` [m].
    distance_m
        Distance ``d_1`` from the joints' line (y = 0) to the nearest point of the undeformed disk
        [m]; the centre sits at ``(0, d_1 + r)``.
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
    """

    radius_m: float
    distance_m: float
    youngs_modulus_pa: float = 100e3
    poisson_ratio: float = 0.45
    thickness_m: float = 0.01
    stiffness_scale: float = 1.0
    contour_stiffness_ratio: float = 1.0

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
        for f in fields(self):
            object.__setattr__(self, f.name, float(getattr(self, f.name)))

    @property
    def center_m(self) -> np.ndarray:
        """Position of the pinned centre ``(0, d_1 + r)`` [m]."""
        return np.array([0.0, self.distance_m + self.radius_m])


def finger_frame(gripper: Gripper, side: int, angle_rad: float):
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
    s, c = np.sin(angle_rad), np.cos(angle_rad)
    if side == 0:
        return np.array([gripper.joint_offset_m, 0.0]), np.array([s, c]), np.array([-c, s])
    return np.array([-gripper.joint_offset_m, 0.0]), np.array([-s, c]), np.array([c, s])


def closed_angle_rad(gripper: Gripper) -> float:
    """Finger angle at which the gripping-face tip reaches the symmetry axis [rad].

    The jaws cannot close past it (the two faces would meet); the solver treats it as a joint
    stop. Solves ``d_3 + l sin(theta) - (w/2) cos(theta) = 0`` for ``theta`` in (-pi/2, 0].
    """
    d3, ln, hw = gripper.joint_offset_m, gripper.finger_length_m, gripper.finger_width_m / 2
    # l sin t - hw cos t = R sin(t - phi), R = hypot(l, hw), phi = atan2(hw, l)
    rr = math.hypot(ln, hw)
    return math.atan2(hw, ln) - math.asin(min(1.0, d3 / rr))


def _distance_to_finger_bar(gripper: Gripper, side: int, angle_rad, point):
    """Distance from ``point`` to the rectangular finger bar (negative inside is reported as 0).

    ``angle_rad`` may be an array of finger angles: one distance per angle.
    """
    joint, axis, normal = finger_frame(gripper, side, angle_rad)
    rx = float(point[0]) - joint[0]
    ry = float(point[1]) - joint[1]
    s = axis[0] * rx + axis[1] * ry  # along the axis e
    m = normal[0] * rx + normal[1] * ry  # along the inward normal n
    hw = gripper.finger_width_m / 2
    ds = np.maximum(0.0, np.maximum(-s, s - gripper.finger_length_m))
    dm = np.maximum(0.0, np.maximum(m - hw, -hw - m))
    dist = np.hypot(ds, dm)
    return float(dist) if np.ndim(dist) == 0 else dist


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
        if g.finger_width_m >= 2 * d.radius_m:
            raise ValueError(
                f"finger_width_m = {g.finger_width_m!r} must be smaller than the disk diameter "
                f"2 * radius_m = {2 * d.radius_m!r}"
            )
        centre = d.center_m
        for side, name in ((0, "right"), (1, "left")):
            joint, _, normal = finger_frame(g, side, g.rest_angle_rad)
            if normal @ (centre - joint) - g.finger_width_m / 2 <= 0:
                raise ValueError(
                    f"disk centre lies behind the {name} finger's gripping face at rest: "
                    "decrease joint_offset_m or increase rest_angle_rad/distance_m"
                )
            clearance = _distance_to_finger_bar(g, side, g.rest_angle_rad, centre) - d.radius_m
            if clearance <= 0:
                raise ValueError(
                    f"the {name} finger overlaps the disk at rest (clearance {clearance:.3g} m): "
                    "increase rest_angle_rad or distance_m (allowed: clearance > 0)"
                )
        object.__setattr__(self, "warnings", self._reach_warnings())

    def _reach_warnings(self) -> tuple[str, ...]:
        g, d = self.gripper, self.disk
        # right finger over 64 angles from closed to rest (the left one mirrors it), in one
        # vectorized call: this runs for every Scene an optimizer builds
        angles = np.linspace(closed_angle_rad(g), g.rest_angle_rad, 64)
        reach = float(np.min(_distance_to_finger_bar(g, 0, angles, d.center_m)))
        if reach > d.radius_m:
            return (
                f"the fingers cannot reach the disk even fully closed (closest approach "
                f"{reach - d.radius_m:.3g} m): no grasp is possible",
            )
        return ()

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

    def with_changes(self, **changes) -> Scene:
        """Return a copy with gripper or disk fields replaced by name."""
        gk = {k: v for k, v in changes.items() if k in Gripper.__dataclass_fields__}
        dk = {k: v for k, v in changes.items() if k in SoftDisk.__dataclass_fields__}
        unknown = set(changes) - set(gk) - set(dk)
        if unknown:
            raise ValueError(f"unknown scene fields {sorted(unknown)}")
        return Scene(replace(self.gripper, **gk), replace(self.disk, **dk))


PAPER_GRIPPER = Gripper(
    finger_length_m=0.2,
    rest_angle_rad=math.radians(45.0),
    joint_offset_m=0.025,
    finger_width_m=0.01,
    torsion_stiffness_nm_per_rad=0.073,
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
    "paper-r050": (PAPER_GRIPPER, SoftDisk(0.05, 0.004)),
    "paper-r070": (PAPER_GRIPPER, SoftDisk(0.07, 0.013)),
    "paper-r100": (PAPER_GRIPPER, SoftDisk(0.10, 0.025)),
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
        ),
    )
