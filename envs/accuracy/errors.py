"""Closing-angle errors of the PSM against a reference curve (:class:`ErrorReport`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .curves import PsmCurve, psm_curve
from .reference import ReferenceCurve, _as_reference


@dataclass(frozen=True)
class ErrorReport:
    """Jaw closing-angle error of the PSM against a reference curve.

    Attributes
    ----------
    scene_disk_radius_m
        Radius of the disk of the case [m].
    stiffness_scale
        Stiffness scale used by the PSM [-].
    n_triangles, method
        PSM discretisation and solver.
    torques_nm
        Torques of the reference [N·m].
    reference_closing_rad, model_closing_rad
        Closing angles ``theta_a0 - theta`` [rad] (model: NaN where not converged).
    relative_errors
        ``model / reference - 1`` per torque [-] (NaN where not converged).
    converged
        PSM convergence per torque.
    rms_rel_error, max_rel_error
        RMS and largest absolute relative error over the converged torques [-] (NaN if none).
    range_rel_error
        Largest absolute closing-angle difference divided by the largest reference closing
        angle [-] (an error relative to the range of the curve).
    n_failed
        Number of torques where the PSM did not converge.
    n_retried
        Number of torques answered by a retry at a torque 0.1-0.3 % away (see
        :func:`psm_curve`).
    time_per_solve_s
        PSM ramp wall time divided by the number of torques [s] (retries included).
    contour_stiffness_ratio
        Contour-only stiffness factor used by the PSM [-].
    """

    scene_disk_radius_m: float
    stiffness_scale: float
    n_triangles: int
    method: str
    torques_nm: tuple[float, ...]
    reference_closing_rad: tuple[float, ...]
    model_closing_rad: tuple[float, ...]
    relative_errors: tuple[float, ...]
    converged: tuple[bool, ...]
    rms_rel_error: float
    max_rel_error: float
    range_rel_error: float
    n_failed: int
    n_retried: int
    time_per_solve_s: float
    contour_stiffness_ratio: float = 1.0

    def to_dict(self) -> dict:
        """JSON-friendly copy (NaN is written as ``None``)."""
        def clean(v):
            if isinstance(v, tuple):
                return [clean(x) for x in v]
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v

        return {k: clean(getattr(self, k)) for k in self.__dataclass_fields__}


def _error_report(scene: Scene, ref: ReferenceCurve, curve: PsmCurve, n: int,
                  method: str) -> ErrorReport:
    c_ref = ref.closing_rad(scene)
    c_mod = scene.gripper.rest_angle_rad - np.asarray(curve.jaw_angles_rad)
    rel = c_mod / c_ref - 1.0
    ok = np.isfinite(rel)
    if ok.any():
        rms = float(np.sqrt(np.mean(rel[ok] ** 2)))
        mx = float(np.max(np.abs(rel[ok])))
        rng = float(np.max(np.abs(c_mod[ok] - c_ref[ok])) / np.max(np.abs(c_ref)))
    else:
        rms = mx = rng = math.nan
    return ErrorReport(
        scene_disk_radius_m=scene.disk.radius_m,
        stiffness_scale=scene.disk.stiffness_scale,
        n_triangles=int(n),
        method=method,
        torques_nm=ref.torques_nm,
        reference_closing_rad=tuple(float(v) for v in c_ref),
        model_closing_rad=tuple(float(v) for v in c_mod),
        relative_errors=tuple(float(v) for v in rel),
        converged=curve.converged,
        rms_rel_error=rms,
        max_rel_error=mx,
        range_rel_error=rng,
        n_failed=curve.n_failed,
        n_retried=curve.n_retried,
        time_per_solve_s=curve.time_per_solve_s,
        contour_stiffness_ratio=scene.disk.contour_stiffness_ratio,
    )


def closing_errors(
    scene: Scene,
    reference_curve,
    n_triangles: int = 20,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    time_limit_s: float = 30.0,
    retry: bool = True,
) -> ErrorReport:
    """Closing-angle error of the PSM of ``scene`` (its own calibration factors) on a reference.

    Parameters
    ----------
    scene
        Gripper and disk; the PSM uses ``scene.disk.stiffness_scale`` and
        ``scene.disk.contour_stiffness_ratio`` as they are.
    reference_curve
        A :class:`ReferenceCurve`, a list of :class:`envs.fem.FemResult` or a pair
        ``(torques_nm, jaw_angles_rad)``.
    n_triangles, method, stiffness_rule, time_limit_s
        PSM settings (see :func:`envs.solver.simulate`).
    retry
        Retry isolated solver failures at a torque 0.1-0.3 % away (see :func:`psm_curve`).
    """
    ref = _as_reference(reference_curve)
    curve = psm_curve(scene, ref.torques_nm, n_triangles, method,
                      stiffness_rule=stiffness_rule, time_limit_s=time_limit_s, retry=retry)
    return _error_report(scene, ref, curve, n_triangles, method)
