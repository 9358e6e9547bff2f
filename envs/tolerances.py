"""Manufacturing tolerances: the design as built, a scenario dimension beside the object's.

A gripper is built to a tolerance: its lengths within ``+- length_m``, its rest angle within
``+- angle_rad``, its joint spring and actuation torque within ``+-`` a share of their values.
:class:`Tolerances` holds them; :mod:`envs.scenarios` adds one scenario dimension per toleranced
quantity (:func:`tolerance_dimensions`) and :func:`apply_tolerances` moves design rows and
springs to a scenario's corner.

The dimensions:

- ``finger_length_m``, ``finger_width_m``, ``joint_offset_m``: each by ``+- length_m``. Both
  fingers move together (the model's gripper is symmetric; an asymmetric build is not checked).
  A joint offset of 0 is a common pivot (both fingers on one pin) and stays 0; an offset never
  goes below 0, a length or width never below a tenth of its value.
- ``rest_angle_rad``: by ``+- angle_rad``.
- ``closing_moment``: the torque by ``+- torque_rel`` and the spring by ``-+ spring_rel``
  together. The net closing moment ``T_a - k_f (theta_a0 - theta)`` is linear in both with
  ``theta <= theta_a0`` throughout a grasp, so its extremes over the torque-spring rectangle at
  every angle are the corners (T low, k_f high), the weakest closing, and (T high, k_f low), the
  strongest: one dimension covers the rectangle's extremes exactly.

The jaws' grooves keep their designed dimensions (a stated limitation: docs/limitations.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from .scene import DESIGN_FIELDS
from .validation import check_range

__all__ = ["Tolerances", "TOLERANCE_KEYS", "LENGTH_DIMENSIONS", "ANGLE_DIMENSION",
           "CLOSING_DIMENSION", "tolerance_dimensions", "apply_tolerances",
           "parse_tolerances"]

# the quantities that vary by the length tolerance, in this order
LENGTH_DIMENSIONS = ("finger_length_m", "finger_width_m", "joint_offset_m")
ANGLE_DIMENSION = "rest_angle_rad"
CLOSING_DIMENSION = "closing_moment"
# the keys of an object file's [gripper.tolerances] table and of --tolerances: user units
TOLERANCE_KEYS = {"length_mm": ("length_m", 1e-3), "angle_deg": ("angle_rad", math.pi / 180),
                  "torque_percent": ("torque_rel", 1e-2),
                  "spring_percent": ("spring_rel", 1e-2)}
MAX_SHARE = 0.5  # a torque or spring tolerance of +-50 % at most
MAX_LENGTH_M = 0.01  # a length tolerance of +-10 mm at most (a unit slip beyond)
MAX_ANGLE_RAD = math.radians(10.0)
MIN_LENGTH_SHARE = 0.1  # a toleranced length or width never below this share of its value
_COLUMN = {name: DESIGN_FIELDS.index(name) for name in (*LENGTH_DIMENSIONS, ANGLE_DIMENSION,
                                                         "torque_nm")}


@dataclass(frozen=True)
class Tolerances:
    """How far a built gripper may differ from its design, ``+-`` each (SI units).

    Parameters
    ----------
    length_m
        Finger length, width and joint offset [m], in [0, 0.01] (a workshop: about 1e-4).
    angle_rad
        Rest angle [rad], in [0, 10 deg].
    torque_rel
        Actuation torque, as a share of its value [-], in [0, 0.5].
    spring_rel
        Joint spring ``k_f``, as a share of its value [-], in [0, 0.5] (a torsion spring:
        about 0.1).
    """

    length_m: float = 0.0
    angle_rad: float = 0.0
    torque_rel: float = 0.0
    spring_rel: float = 0.0

    def __post_init__(self) -> None:
        highs = {"length_m": MAX_LENGTH_M, "angle_rad": MAX_ANGLE_RAD,
                 "torque_rel": MAX_SHARE, "spring_rel": MAX_SHARE}
        for f in fields(self):
            object.__setattr__(self, f.name, check_range(f"tolerances.{f.name}",
                                                         getattr(self, f.name), 0.0,
                                                         highs[f.name]))

    @property
    def is_zero(self) -> bool:
        """Whether nothing is toleranced."""
        return not any(getattr(self, f.name) for f in fields(self))

    def as_dict(self) -> dict[str, float]:
        """Plain data in SI units (what a result JSON records)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def as_user_units(self) -> dict[str, float]:
        """The tolerances in the object file's units (:data:`TOLERANCE_KEYS`: mm, deg, %)."""
        return {key: getattr(self, name) / scale for key, (name, scale) in TOLERANCE_KEYS.items()}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> Tolerances:
        """The inverse of :meth:`as_dict` (``None``: no tolerance)."""
        if data is None:
            return cls()
        if not isinstance(data, Mapping):
            raise ValueError(f"tolerances must be a table, got {data!r}")
        unknown = sorted(set(data) - {f.name for f in fields(cls)})
        if unknown:
            raise ValueError(f"tolerances: unknown key {unknown[0]!r}; allowed: "
                             f"{[f.name for f in fields(cls)]}")
        return cls(**data)


def parse_tolerances(data: Mapping[str, Any], where: str = "tolerances") -> Tolerances:
    """Tolerances in user units (:data:`TOLERANCE_KEYS`: ``length_mm``, ``angle_deg``,
    ``torque_percent``, ``spring_percent``; a missing key is 0), each a number >= 0;
    ``ValueError`` naming ``where`` and the key otherwise."""
    if not isinstance(data, Mapping):
        raise ValueError(f"{where} must be a table of {', '.join(TOLERANCE_KEYS)}, got {data!r}")
    unknown = sorted(set(data) - set(TOLERANCE_KEYS))
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r}; allowed: "
                         f"{', '.join(TOLERANCE_KEYS)} (mm, degrees, percent, percent)")
    values = {}
    for key, value in data.items():
        name, scale = TOLERANCE_KEYS[key]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{where}: {key} must be a number, got {value!r}")
        values[name] = float(value) * scale
    try:
        return Tolerances(**values)
    except ValueError as exc:
        # the message in the user's units
        name = str(exc).split(" ")[0].removeprefix("tolerances.")
        key = next(k for k, (n, _) in TOLERANCE_KEYS.items() if n == name)
        high = {"length_m": MAX_LENGTH_M * 1e3, "angle_rad": math.degrees(MAX_ANGLE_RAD),
                "torque_rel": MAX_SHARE * 100, "spring_rel": MAX_SHARE * 100}[name]
        raise ValueError(f"{where}: {key} = {data[key]!r} is outside [0, {high:g}]") from None


def tolerance_dimensions(tolerances: Tolerances) -> tuple[str, ...]:
    """The scenario dimensions of the tolerances that are not zero, in a fixed order."""
    names: list[str] = []
    if tolerances.length_m > 0.0:
        names += LENGTH_DIMENSIONS
    if tolerances.angle_rad > 0.0:
        names.append(ANGLE_DIMENSION)
    if tolerances.torque_rel > 0.0 or tolerances.spring_rel > 0.0:
        names.append(CLOSING_DIMENSION)
    return tuple(names)


def tolerance_changes(tolerances: Tolerances, name: str, u: float) -> dict[str, float]:
    """The changes of a dimension at ``u`` in [-1, 1]: a length or the angle by ``u`` times
    its tolerance [m or rad]; the closing moment as ``torque_rel`` (``+u``) and
    ``spring_rel`` (``-u``) shares."""
    if name in LENGTH_DIMENSIONS:
        return {name: u * tolerances.length_m}
    if name == ANGLE_DIMENSION:
        return {name: u * tolerances.angle_rad}
    if name == CLOSING_DIMENSION:
        return {"torque_rel": u * tolerances.torque_rel, "spring_rel": -u * tolerances.spring_rel}
    raise ValueError(f"not a tolerance dimension: {name!r}")


def apply_tolerances(rows: np.ndarray, springs: np.ndarray,
                     changes: list[Mapping[str, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Design rows (B, n) and joint springs (B,) [N·m/rad] as built: each row ``i`` changed by
    ``changes[i]`` (:func:`tolerance_changes`, merged); returns new arrays.

    A joint offset of 0 (a common pivot) stays 0 and an offset never goes below 0; a length or
    a width never below :data:`MIN_LENGTH_SHARE` of its value.
    """
    rows = np.array(rows, dtype=np.float64, copy=True)
    springs = np.array(springs, dtype=np.float64, copy=True)
    for i, change in enumerate(changes):
        for name, delta in change.items():
            if name == "torque_rel":
                rows[i, _COLUMN["torque_nm"]] *= 1.0 + delta
            elif name == "spring_rel":
                springs[i] *= 1.0 + delta
            elif name == "joint_offset_m":
                col = _COLUMN[name]
                if rows[i, col] > 0.0:
                    rows[i, col] = max(0.0, rows[i, col] + delta)
            elif name == ANGLE_DIMENSION:
                rows[i, _COLUMN[name]] += delta
            else:
                col = _COLUMN[name]
                rows[i, col] = max(MIN_LENGTH_SHARE * rows[i, col], rows[i, col] + delta)
    return rows, springs
