"""The pivot of each finger: pin, boss, common pivot, plate thickness and stacking.

- **Pin.** Its diameter is an option (:class:`~optim.parts.options.PartOptions`); by default
  half the finger width rounded down to the resolution, at least one resolution step
  (:func:`default_pin_diameter`): the boss about it is then the finger's own half-disk end of
  radius ``w/2``, a wall of ``w/4`` around the pin. A larger pin gets a boss of radius
  ``d/2 + max(d/4, resolution)`` (:func:`boss_radius`).
- **Assembly.** Joints at least a boss radius from the axis: the fingers turn **side by side**
  in one plane, each on its own pin. Closer: their joint ends overlap and the fingers are
  **stacked** at the joints, each on its own pin; a joint offset that rounds to 0 is a
  **common pivot**, both fingers on one pin.
- **Plate and stacking.** Each finger is a plate as thick as the object's slice (the model
  grasps a slice of thickness ``t``: its faces must cover it), rounded up to the resolution.
  Stacked fingers keep their gripping faces in one plane with a **half-lap**: from the joint end
  to where the other finger can no longer reach it between the closing stop and the rest angle
  (:func:`lap_length`), each plate is half as thick, the right finger's upper half and the left
  finger's lower half (the right finger on top at the pivot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from envs.model.jaw import JawProfile

from .profile import FingerPart, finger_in_gripper
from .resolution import Resolution

__all__ = ["Pivot", "default_pin_diameter", "boss_radius", "pivot_of", "lap_length",
           "PIN_RULE", "ASSEMBLIES"]

ASSEMBLIES = ("side by side", "stacked", "common pivot")
PIN_RULE = ("pin diameter: half the finger width rounded down to the resolution, at least one "
            "resolution step (the boss is then the finger's half-disk end, a wall of w/4 around "
            "the pin); a larger pin given as an option gets a boss of radius d/2 + max(d/4, "
            "resolution)")
LAP_ANGLES = 41  # angles from the closing stop to the rest angle at which the overlap is found


def default_pin_diameter(width_m: float, resolution_m: float) -> float:
    """Half the finger width rounded down to ``resolution_m``, at least ``resolution_m`` (and
    at most half the width for a finger narrower than two steps) [m]."""
    steps = math.floor(width_m / 2 / resolution_m + 1e-9)
    return round(max(steps, 1) * resolution_m, 12) if width_m >= 2 * resolution_m else (
        width_m / 2)


def boss_radius(width_m: float, pin_diameter_m: float, resolution_m: float) -> float:
    """The boss's outer radius about the pivot [m]: ``w/2`` when that leaves a wall of at least
    ``max(d/4, resolution)`` around the pin, else ``d/2 + max(d/4, resolution)``."""
    wall = max(pin_diameter_m / 4, min(resolution_m, pin_diameter_m / 2))
    return max(width_m / 2, pin_diameter_m / 2 + wall)


@dataclass(frozen=True)
class Pivot:
    """How the fingers turn.

    Attributes
    ----------
    assembly
        One of :data:`ASSEMBLIES`.
    pin_diameter_m, boss_radius_m
        The pin and the boss about it [m].
    pin_x_m
        The pins' positions across the axis [m] (one for a common pivot).
    plate_thickness_m
        Each finger's plate [m].
    lap_length_m
        The half-lap's length from the pivot along each finger [m] (0 side by side).
    pin_rule
        How the pin was chosen (the option, or :data:`PIN_RULE`).
    """

    assembly: str
    pin_diameter_m: float
    boss_radius_m: float
    pin_x_m: tuple[float, ...]
    plate_thickness_m: float
    lap_length_m: float
    pin_rule: str

    @property
    def stacking(self) -> str:
        """The stacking order in words."""
        if self.assembly == "side by side":
            return "one plane: each finger a full plate on its own pin"
        pins = "one pin through both" if self.assembly == "common pivot" else "each on its pin"
        return (f"right finger on top at the pivot ({pins}): from the joint end to "
                f"{self.lap_length_m * 1e3:.4g} mm along each finger the right finger keeps its "
                "upper half of the plate, the left finger its lower half (a half-lap); beyond "
                "it both are full plates with their gripping faces in one plane")


def lap_length(parts: tuple[FingerPart, FingerPart], joint_offset_m: float,
               angles_rad: np.ndarray, step_m: float) -> float:
    """How far from the pivot along a finger the other finger reaches it at any of
    ``angles_rad`` (both fingers at each angle), rounded up to ``step_m`` and one step more;
    only the overlap connected to the joints counts (the faces meeting at the tips at the
    closing stop is the stop itself) [m]; 0 when they never overlap."""
    from shapely.geometry import Point

    near = Point(0.0, 0.0).buffer(2 * joint_offset_m + 2 * parts[0].boss_radius_m)
    reach = 0.0
    for angle in np.asarray(angles_rad, dtype=float).tolist():
        right = finger_in_gripper(parts[0], angle, joint_offset_m)
        left = finger_in_gripper(parts[1], angle, joint_offset_m)
        overlap = right.intersection(left)
        pieces = getattr(overlap, "geoms", [overlap])
        axis = np.array([math.sin(angle), math.cos(angle)])
        for piece in pieces:
            if piece.is_empty or piece.area <= 1e-12 * parts[0].width_m ** 2 or not (
                    piece.intersects(near)):
                continue
            coords = np.asarray(piece.exterior.coords) - np.array([joint_offset_m, 0.0])
            reach = max(reach, float((coords @ axis).max()))
    if reach <= 0.0:
        return 0.0
    return round((math.ceil(reach / step_m - 1e-9) + 1) * step_m, 12)


def pivot_of(design: dict[str, Any], jaws: tuple[JawProfile, JawProfile],
             thickness_m: float, resolution: Resolution | None,
             pin_diameter_m: float | None, smallest_grasp_rad: float
             ) -> tuple[Pivot, tuple[FingerPart, FingerPart]]:
    """The pivot and the two finger parts of a design (SI units, the fields of
    :data:`envs.scene.DESIGN_FIELDS`) with its jaws, for an object slice ``thickness_m``
    thick; ``resolution`` (``None``: 0.1 mm for the pin rule), an optional pin diameter [m],
    and the smallest grasp angle over the scenarios [rad] (the half-lap covers the overlap
    from the closing stop, :func:`optim.parts.spring.stops_of`, to the rest angle)."""
    from .spring import stops_of

    step = 1e-4 if resolution is None else resolution.length_m
    length, width = float(design["finger_length_m"]), float(design["finger_width_m"])
    d3, rest = float(design["joint_offset_m"]), float(design["rest_angle_rad"])
    pin = default_pin_diameter(width, step) if pin_diameter_m is None else pin_diameter_m
    rule = PIN_RULE if pin_diameter_m is None else "pin diameter: as given (--pin-diameter)"
    radius = boss_radius(width, pin, step)
    plate = round(math.ceil(thickness_m / step - 1e-9) * step, 12)
    assembly = ("common pivot" if d3 == 0.0 else "stacked" if d3 < radius else "side by side")
    parts = tuple(FingerPart(side, length, width, jaw, pin, radius, plate)
                  for side, jaw in zip(("right", "left"), jaws, strict=True))
    lap = 0.0
    if assembly != "side by side":
        stop = stops_of(design, 1.0, smallest_grasp_rad, True,
                        None if resolution is None else resolution.angle_rad).closing_rad
        lap = lap_length(parts, d3, np.linspace(min(stop, rest), rest, LAP_ANGLES), step)
        parts = tuple(FingerPart(p.side, p.length_m, p.width_m, p.jaw, pin, radius, plate,
                                 min(lap, length)) for p in parts)
    pins = (0.0,) if assembly == "common pivot" else (d3, -d3)
    return Pivot(assembly, pin, radius, pins, plate, min(lap, length), rule), parts
