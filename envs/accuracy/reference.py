"""Reference jaw-angle curves: :class:`ReferenceCurve` and the FEM curve :func:`fem_reference`.

The FEM (:mod:`envs.fem`, optional dependency scikit-fem) is imported only when
:func:`fem_reference` is called.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .paper import PAPER_TORQUES_NM


@dataclass(frozen=True)
class ReferenceCurve:
    """Reference jaw angle against actuation torque.

    Attributes
    ----------
    torques_nm
        Actuation torques ``T_a`` [N·m].
    jaw_angles_rad
        Finger angle ``theta`` from the +y axis at each torque [rad] (mean of both fingers).
    source
        Free text describing where the curve comes from (e.g. ``"fem rings=12 plane=strain"``).
    dropped_torques_nm
        Torques of the source that were left out because the source did not converge there.
    solve_time_s
        Wall time the source needed for the whole curve [s] (NaN when unknown).
    """

    torques_nm: tuple[float, ...]
    jaw_angles_rad: tuple[float, ...]
    source: str = ""
    dropped_torques_nm: tuple[float, ...] = ()
    solve_time_s: float = math.nan

    def __post_init__(self) -> None:
        t = tuple(float(v) for v in self.torques_nm)
        a = tuple(float(v) for v in self.jaw_angles_rad)
        if len(t) != len(a):
            raise ValueError(
                f"torques_nm and jaw_angles_rad must have the same length, got {len(t)} and "
                f"{len(a)}"
            )
        if not t:
            raise ValueError("a reference curve needs at least one (torque, angle) pair")
        if not all(math.isfinite(v) and v >= 0 for v in t):
            raise ValueError("torques_nm must be finite and >= 0")
        if not all(math.isfinite(v) for v in a):
            raise ValueError("jaw_angles_rad must be finite (drop non-converged points first)")
        object.__setattr__(self, "torques_nm", t)
        object.__setattr__(self, "jaw_angles_rad", a)

    @classmethod
    def from_fem(cls, results: Sequence, source: str = "fem") -> ReferenceCurve:
        """Build a curve from :class:`envs.fem.FemResult` objects, dropping non-converged ones."""
        flags = [bool(r.converged and np.all(np.isfinite(r.jaw_angles_rad))) for r in results]
        keep = [r for r, f in zip(results, flags, strict=True) if f]
        dropped = tuple(float(r.torque_nm) for r, f in zip(results, flags, strict=True) if not f)
        return cls(
            tuple(float(r.torque_nm) for r in keep),
            tuple(float(np.mean(r.jaw_angles_rad)) for r in keep),
            source=source,
            dropped_torques_nm=dropped,
            solve_time_s=float(sum(r.solve_time_s for r in results)),
        )

    def closing_rad(self, scene: Scene) -> np.ndarray:
        """Closing angle ``theta_a0 - theta`` of the scene's gripper [rad]."""
        return scene.gripper.rest_angle_rad - np.asarray(self.jaw_angles_rad)

    def to_dict(self) -> dict:
        """JSON-friendly copy."""
        return {
            "torques_nm": list(self.torques_nm),
            "jaw_angles_rad": list(self.jaw_angles_rad),
            "source": self.source,
            "dropped_torques_nm": list(self.dropped_torques_nm),
            "solve_time_s": self.solve_time_s,
        }


def _as_reference(reference) -> ReferenceCurve:
    if isinstance(reference, ReferenceCurve):
        return reference
    if isinstance(reference, Sequence) and reference and hasattr(reference[0], "contour_m"):
        return ReferenceCurve.from_fem(reference)
    try:
        torques, angles = reference
    except (TypeError, ValueError):
        raise ValueError(
            "reference_curve must be a ReferenceCurve, a list of FemResult or a pair "
            "(torques_nm, jaw_angles_rad)"
        ) from None
    return ReferenceCurve(tuple(np.ravel(torques)), tuple(np.ravel(angles)), source="user")


def fem_reference(
    scene: Scene,
    torques_nm: Sequence[float] = PAPER_TORQUES_NM,
    mesh_size_m: float | None = None,
    plane: str = "strain",
) -> ReferenceCurve:
    """FEM jaw-angle curve of a scene (:func:`envs.fem.fem_grasp`, disk-cached).

    Parameters
    ----------
    scene
        Gripper and disk (``stiffness_scale`` and ``contour_stiffness_ratio`` are PSM
        calibration factors: the FEM ignores them, and they are reset to 1 here so that every
        calibration of the same disk shares one FEM cache entry).
    torques_nm
        Non-decreasing torque ramp [N·m]. The FEM cache is keyed by the whole list, so reuse
        the same list to hit it.
    mesh_size_m
        FEM element size [m]; default ``r / 12``.
    plane
        ``"strain"`` (default) or ``"stress"``.

    Returns
    -------
    ReferenceCurve
        Converged FEM points only (the others are listed in ``dropped_torques_nm``).
    """
    from ..fem import default_mesh_size_m, fem_grasp

    r = scene.disk.radius_m
    h = default_mesh_size_m(r) if mesh_size_m is None else float(mesh_size_m)
    physical = scene.with_changes(stiffness_scale=1.0, contour_stiffness_ratio=1.0)
    results = fem_grasp(physical, list(torques_nm), mesh_size_m=h, plane=plane)
    rings = max(2, math.ceil(r / h - 1e-9))
    return ReferenceCurve.from_fem(results, source=f"fem rings={rings} plane={plane}")
