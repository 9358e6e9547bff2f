"""The design space relative to the object: :class:`DesignBounds` maps actions in [-1, 1] to
SI designs for any object (lengths in radii, the torque in ``s E t r^2``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .scene import (
    N_DESIGN,
    RELATIVE_FIELDS,
    SoftDisk,
    design_from_relative,
    relative_from_design,
)
from .validation import check_range


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

    Parameters
    ----------
    low, high
        Lower and upper bound of each relative column, ``low < high``.
    joints_apart
        Keep the joints at least half a finger width from the axis (``d_3 >= w / 2``); needs
        ``high`` of ``joint_offset_r`` at least half ``high`` of ``finger_width_r``.
    """

    low: tuple[float, ...] = (1.5, math.radians(10.0), 0.0, 0.05, 0.0, 0.005)
    high: tuple[float, ...] = (8.0, math.radians(60.0), 0.6, 0.4, 0.3, 1.2)
    joints_apart: bool = False

    def __post_init__(self) -> None:
        for name in ("low", "high"):
            given = tuple(getattr(self, name))
            if len(given) != N_DESIGN:
                raise ValueError(f"DesignBounds.{name} needs {N_DESIGN} values, got {len(given)}")
            # checked as given, not after float(): "0.2" and True are not bounds
            vals = tuple(check_range(f"DesignBounds.{name}[{field_name}]", v)
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

    @property
    def low_array(self) -> np.ndarray:
        """Lower bounds (relative units) as a float64 array (6,)."""
        return np.array(self.low, dtype=np.float64)

    @property
    def high_array(self) -> np.ndarray:
        """Upper bounds (relative units) as a float64 array (6,)."""
        return np.array(self.high, dtype=np.float64)

    def _offset_floor(self, width_r: np.ndarray) -> np.ndarray:
        """Lowest relative joint offset of rows of relative finger width ``width_r``: the
        box's, or with :attr:`joints_apart` at least half the width."""
        return np.maximum(self.low[_OFFSET_R], 0.5 * width_r)

    def relative(self, action) -> np.ndarray:
        """Map normalized actions in [-1, 1] (shape (..., 6)) to relative designs."""
        a = np.asarray(action, dtype=np.float64)
        lo, hi = self.low_array, self.high_array
        rel = lo + 0.5 * (a + 1.0) * (hi - lo)
        if self.joints_apart:
            floor = self._offset_floor(rel[..., _WIDTH_R])
            rel[..., _OFFSET_R] = floor + 0.5 * (a[..., _OFFSET_R] + 1.0) * (
                hi[_OFFSET_R] - floor)
        return rel

    def scale(self, action, disks) -> np.ndarray:
        """Map normalized actions (shape (B, 6) or (6,)) to SI designs for their objects.

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
        return design_from_relative(self.relative(a), radius, unit)

    def unscale(self, designs, disks) -> np.ndarray:
        """Map SI designs (shape (B, 6) or (6,)) to normalized actions (inverse of
        :meth:`scale` where the placement was not raised to 0)."""
        d = np.asarray(designs, dtype=np.float64)
        radius, unit = _scales(disks, d.shape[0] if d.ndim == 2 else None)
        rel = relative_from_design(d, radius, unit)
        lo, hi = self.low_array, self.high_array
        action = 2.0 * (rel - lo) / (hi - lo) - 1.0
        if self.joints_apart:
            floor = self._offset_floor(rel[..., _WIDTH_R])
            span = hi[_OFFSET_R] - floor
            # a finger as wide as the box allows leaves one joint offset: its middle coordinate
            share = np.divide(rel[..., _OFFSET_R] - floor, span, out=np.full_like(span, 0.5),
                              where=span > 0)
            action[..., _OFFSET_R] = 2.0 * share - 1.0
        return action

    def sample(self, rng: np.random.Generator, size: int, disks) -> np.ndarray:
        """Draw ``size`` SI designs uniformly in the box for the object(s), shape (size, 6)."""
        return self.scale(rng.uniform(-1.0, 1.0, size=(int(size), N_DESIGN)), disks)
