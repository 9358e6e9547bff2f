"""The contact measure written again in numpy, from its definition (envs.model.contact_width):
an independent reading for the tests of the compiled metric loop."""

from __future__ import annotations

import math

import numpy as np

from envs.model.contact_width import EDGE_STIFFNESS_FACTOR


def _bar_gaps(points_m: np.ndarray, gripper, side: int, angle_rad: float) -> np.ndarray:
    """Distance of each point to the rectangular bar of one finger (0 inside), with the axes of
    the model's conventions: right e = (sin, cos), n = (-cos, sin); left mirrored."""
    s, c = math.sin(angle_rad), math.cos(angle_rad)
    sign = 1.0 if side == 0 else -1.0
    axis = np.array([sign * s, c])
    normal = np.array([-sign * c, s])
    rel = points_m - np.array([sign * gripper.joint_offset_m, 0.0])
    along, across = rel @ axis, rel @ normal
    hw = gripper.finger_width_m / 2
    ds = np.maximum(0.0, np.maximum(-along, along - gripper.finger_length_m))
    dm = np.maximum(0.0, np.maximum(across - hw, -hw - across))
    return np.hypot(ds, dm)


def face_extent_shares(points_m: np.ndarray, face_forces_n: np.ndarray, gripper,
                       jaw_angles_rad, disk, factor: float = EDGE_STIFFNESS_FACTOR
                       ) -> np.ndarray:
    """Each face's share of a contour of N evenly spaced points in contact, (2,): per segment
    between neighbours, the part where the linear interpolation of the points' indicators
    (pressed: ``F / (t c E*)``, free: minus the gap to the finger's bar) is positive; ``c``:
    ``factor``."""
    n = points_m.shape[0]
    e_star = disk.stiffness_scale * disk.youngs_modulus_pa / (1 - disk.poisson_ratio**2)
    out = np.empty(2)
    for side in range(2):
        f = face_forces_n[side]
        gaps = _bar_gaps(points_m, gripper, side, float(jaw_angles_rad[side]))
        phi = np.where(f > 0, f / (disk.thickness_m * factor * e_star), -gaps)
        a, b = phi, np.roll(phi, -1)
        both = (a > 0) & (b > 0)
        one = (a > 0) != (b > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            part = np.where(one, np.maximum(a, b) / (np.abs(a) + np.abs(b)), 0.0)
        out[side] = (np.count_nonzero(both) + part.sum()) / n
    return out
