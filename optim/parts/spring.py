"""The joint spring as built, and the stops the model assumes.

The model's spring moment on a finger is ``k_f (theta_a0 - theta)``: zero at the rest angle.
So the spring is built **relaxed at rest**: its free angle is the rest angle ``theta_a0`` and
its preload there 0 (a preloaded spring would hold the finger until the torque exceeds the
preload, which the model does not have). A **rest stop** at ``theta_a0`` keeps the finger from
opening beyond it (it carries no load in a grasp). A **closing stop** keeps the fingers from
closing into each other: the model's own is the angle at which the gripping faces' tips meet on
the axis (:func:`envs.model.geometry.closed_angle_of`); stacked fingers, whose joint ends
overlap, get theirs halfway between it and the smallest grasp angle of any scenario, never
reached in a grasp (:func:`stops_of`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from envs.model.geometry import closed_angle_of

__all__ = ["Stops", "stops_of", "smallest_grasp_angle"]


@dataclass(frozen=True)
class Stops:
    """The stops and the spring, SI units.

    Attributes
    ----------
    rest_rad
        The rest stop's angle (the rest angle).
    closing_rad
        The closing stop's angle.
    faces_meet_rad
        The angle at which the gripping faces' tips meet on the axis (the model's stop).
    smallest_grasp_rad
        The smallest finger angle of the grasp over the scenarios, or NaN.
    spring_nm_per_rad
        The spring rate ``k_f``.
    """

    rest_rad: float
    closing_rad: float
    faces_meet_rad: float
    smallest_grasp_rad: float
    spring_nm_per_rad: float

    @property
    def free_angle_rad(self) -> float:
        """The spring's free angle: the rest angle (relaxed at rest)."""
        return self.rest_rad

    @property
    def preload_nm(self) -> float:
        """The spring's moment at rest: 0."""
        return 0.0

    def moment_nm(self, angle_rad: float) -> float:
        """The spring's opening moment at a finger angle [N·m]."""
        return self.spring_nm_per_rad * (self.rest_rad - angle_rad)


def smallest_grasp_angle(metrics: dict[str, Any] | None,
                         scenario_rows: list[dict[str, Any]] | None) -> float:
    """The smallest finger angle of a converged grasp over the scenario rows (or the one
    grasp's metrics) [rad]; NaN without one."""
    rows = scenario_rows or ([metrics] if metrics else [])
    angles = [float(a) for row in rows if row.get("converged")
              for a in (row.get("jaw_angles_rad") or []) if a is not None]
    return min(angles) if angles else math.nan


def stops_of(design: dict[str, Any], spring_nm_per_rad: float, smallest_grasp_rad: float,
             stacked: bool, angle_step_rad: float | None = None) -> Stops:
    """The stops of a design: the rest stop at its rest angle, the closing stop where the
    faces' tips meet, or for stacked fingers halfway from there to ``smallest_grasp_rad``
    (rounded down to ``angle_step_rad``)."""
    rest = float(design["rest_angle_rad"])
    meet = closed_angle_of(float(design["finger_length_m"]), float(design["joint_offset_m"]),
                           float(design["finger_width_m"]))
    closing = meet
    if stacked and math.isfinite(smallest_grasp_rad) and smallest_grasp_rad > meet:
        closing = meet + 0.5 * (smallest_grasp_rad - meet)
        if angle_step_rad:
            closing = max(meet, math.floor(closing / angle_step_rad) * angle_step_rad)
    return Stops(rest, float(closing), float(meet), float(smallest_grasp_rad),
                 float(spring_nm_per_rad))
