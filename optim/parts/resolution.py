"""The manufacturing resolution: the design as a workshop states it, and as it is scored.

A workshop builds to a resolution: lengths to 0.1 mm, angles to 0.1 degree, a spring and a
torque to three significant figures. :func:`round_design` rounds a design to a
:class:`Resolution`; the rounded design is the one the build sheet states, the finish
(:mod:`optim.finish`) scores and ``psm-grasp verify`` checks, so that no number the sheet
prints differs from the design that was judged. The joint spring is a property of the design
problem: :func:`apply_resolution` rounds it before the search.

A joint offset below half the resolution rounds to 0: a **common pivot**, both fingers on one
pin (:mod:`optim.parts.joint`). A groove shallower than half the resolution rounds to a straight
face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from envs.validation import check_integer, check_range

__all__ = ["Resolution", "DEFAULT_RESOLUTION", "round_design", "round_significant",
           "round_length", "apply_resolution", "parse_resolution"]


@dataclass(frozen=True)
class Resolution:
    """What a workshop can make.

    Parameters
    ----------
    length_m
        Lengths to this step [m], in [1e-6, 1e-2] (default 1e-4: 0.1 mm).
    angle_rad
        Angles to this step [rad], in [1e-4 deg, 5 deg] (default 0.1 degree).
    significant
        Significant figures of the torque and the joint spring, in [1, 6] (default 3).
    """

    length_m: float = 1e-4
    angle_rad: float = math.radians(0.1)
    significant: int = 3

    def __post_init__(self) -> None:
        check_range("resolution.length_m", self.length_m, 1e-6, 1e-2)
        check_range("resolution.angle_rad", self.angle_rad, math.radians(1e-4),
                    math.radians(5.0))
        check_integer("resolution.significant", self.significant, 1, 6)
        object.__setattr__(self, "length_m", float(self.length_m))
        object.__setattr__(self, "angle_rad", float(self.angle_rad))

    def as_dict(self) -> dict[str, float]:
        """In the sheet's units: ``length_mm``, ``angle_deg``, ``significant``."""
        return {"length_mm": self.length_m * 1e3, "angle_deg": math.degrees(self.angle_rad),
                "significant": self.significant}


DEFAULT_RESOLUTION = Resolution()


def round_significant(value: float, digits: int) -> float:
    """``value`` to ``digits`` significant figures (0 stays 0)."""
    return float(f"{float(value):.{digits}g}")


def round_length(value_m: float, step_m: float) -> float:
    """A length [m] to a multiple of ``step_m`` (the nearest; exact to 1e-12 m)."""
    return round(round(float(value_m) / step_m) * step_m, 12) + 0.0


def round_design(design: dict[str, Any], resolution: Resolution = DEFAULT_RESOLUTION
                 ) -> dict[str, float]:
    """A design (``{field: value}`` in SI units, the jaw fields included) rounded: every
    length (a key ending ``_m``) to ``length_m``, every angle (``_rad``) to ``angle_rad``,
    the torque to ``significant`` figures."""
    out = {}
    for key, value in design.items():
        if key.endswith("_m"):
            out[key] = round_length(value, resolution.length_m)
        elif key.endswith("_rad"):
            out[key] = round(round(float(value) / resolution.angle_rad) * resolution.angle_rad,
                             15)
        elif key == "torque_nm":
            out[key] = round_significant(value, resolution.significant)
        else:
            out[key] = float(value)
    return out


def apply_resolution(problem: Any, resolution: Resolution = DEFAULT_RESOLUTION) -> float:
    """Round the design problem's joint spring to ``significant`` figures, as an absolute
    spring from now on (:meth:`optim.problem.DesignProblem.use_spring_nm`); returns it
    [N·m/rad]."""
    spring = round_significant(problem.torsion_stiffness_nm_per_rad, resolution.significant)
    problem.use_spring_nm(spring)
    return spring


def parse_resolution(text: str) -> Resolution:
    """``--resolution MM[,DEG[,DIGITS]]``: the length step in millimetres, the angle step in
    degrees and the significant figures of torque and spring."""
    parts = [p.strip() for p in str(text).split(",")]
    if not 1 <= len(parts) <= 3:
        raise ValueError(f"must be MM[,DEG[,DIGITS]], got {text!r}")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"must be numbers MM[,DEG[,DIGITS]], got {text!r}") from None
    kwargs: dict[str, Any] = {"length_m": values[0] * 1e-3}
    if len(values) > 1:
        kwargs["angle_rad"] = math.radians(values[1])
    if len(values) > 2:
        if values[2] != int(values[2]):
            raise ValueError(f"DIGITS must be an integer, got {parts[2]!r}")
        kwargs["significant"] = int(values[2])
    return Resolution(**kwargs)
