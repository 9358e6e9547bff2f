"""Each finger as a part: its outline in its own frame, the pivot hole, the boss around it.

A finger's own frame: ``x`` along the finger from the pivot's centre (0) to the tip (``l``),
``y`` across it, the gripping face at ``y = w/2``, the back at ``y = -w/2``, millimetres in the
files (metres here). The left finger is drawn the same way, face up: the part seen from the
other side (turned over it is the right one when both have the same jaw).

The joint end is a boss about the pivot: a half disk of radius ``w/2`` when the boss fits the
finger's width (the default pin, :func:`optim.parts.joint.default_pin_diameter`), else a disk
of the boss radius joined to the bar. The model's bar ends at ``x = 0``; the boss lies behind
it, within the circle the joint end sweeps (:func:`optim.sheet.assembly_of`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from envs.model.jaw import JawProfile
from envs.render import V_BULGE, V_X, V_Y, finger_outline, finger_to_drawing, outline_polygon

__all__ = ["FingerPart", "ARC_STEP_RAD", "finger_in_gripper"]

ARC_STEP_RAD = math.radians(2.0)  # the arcs of a mesh and of the volume's polygon, sampled
HOLE_SEGMENTS = 90  # the pivot hole's polygon (the volume's and the mesh's alike)


@dataclass(frozen=True)
class FingerPart:
    """One finger as a part, SI units.

    Attributes
    ----------
    side
        ``"right"`` or ``"left"``.
    length_m, width_m
        Finger length ``l`` (pivot to tip) and width ``w`` [m].
    jaw
        The finger's jaw profile (:class:`envs.model.jaw.JawProfile`).
    pin_diameter_m, boss_radius_m
        The pivot hole's diameter and the boss's outer radius about it [m].
    plate_thickness_m
        The plate's thickness out of the plane [m].
    lap_length_m
        The half-lap: from the joint end to ``x = lap_length_m`` the plate is half as thick
        (its underside removed in its own frame); 0: no lap.
    """

    side: str
    length_m: float
    width_m: float
    jaw: JawProfile
    pin_diameter_m: float
    boss_radius_m: float
    plate_thickness_m: float
    lap_length_m: float = 0.0

    @property
    def round_end(self) -> bool:
        """Whether the boss is the finger's own half-disk end (radius ``w/2``)."""
        return self.boss_radius_m <= self.width_m / 2 * (1 + 1e-12)

    def outline(self) -> np.ndarray:
        """The outline without the hole [m]: rows ``x``, ``y``, bulge of the segment to the
        next vertex (counterclockwise; a DXF polyline's); exact arcs with a half-disk end, the
        union with the boss's disk sampled otherwise."""
        local = finger_outline(self.length_m, math.pi / 2, 0.0, self.width_m, 0, self.jaw)
        if self.round_end:
            local[-1, V_BULGE] = 1.0  # the closing segment: a half circle behind the pivot
            return local
        from shapely.geometry import Point, Polygon

        union = Polygon(outline_polygon(local, ARC_STEP_RAD)).union(
            Point(0.0, 0.0).buffer(self.boss_radius_m, quad_segs=HOLE_SEGMENTS // 4))
        ring = np.asarray(union.exterior.coords)[:-1]
        return np.column_stack([ring, np.zeros(len(ring))])

    def polygon(self):
        """The part's plan as a shapely polygon [m]: the outline (arcs sampled every
        :data:`ARC_STEP_RAD`) with the pivot hole."""
        from shapely.geometry import Point, Polygon

        hole = Point(0.0, 0.0).buffer(self.pin_diameter_m / 2, quad_segs=HOLE_SEGMENTS // 4)
        plan = Polygon(outline_polygon(self.outline(), ARC_STEP_RAD))
        return plan.difference(hole)

    def lap_region(self):
        """The plan's part within the half-lap (``x <= lap_length_m``), shapely; empty without
        one."""
        from shapely.geometry import box

        plan = self.polygon()
        if self.lap_length_m <= 0.0:
            return plan.intersection(box(0, 0, 0, 0))
        x0, y0, _, y1 = plan.bounds
        return plan.intersection(box(x0 - 1.0, y0 - 1.0, self.lap_length_m, y1 + 1.0))

    @property
    def volume_m3(self) -> float:
        """The part's volume [m^3]: the plan's area times the plate, less half the plate over
        the half-lap."""
        t = self.plate_thickness_m
        return self.polygon().area * t - self.lap_region().area * t / 2


def finger_in_gripper(part: FingerPart, angle_rad: float, joint_offset_m: float):
    """The part's plan (hole filled, arcs sampled) in the gripper frame at ``angle_rad`` from
    the symmetry axis, its pivot ``joint_offset_m`` from the axis on its side: a shapely
    polygon [m]."""
    from shapely.geometry import Polygon

    ring = outline_polygon(part.outline(), ARC_STEP_RAD)
    side = 0 if part.side == "right" else 1
    return Polygon(finger_to_drawing(ring[:, [V_X, V_Y]], angle_rad, joint_offset_m, side))
