"""Accuracy of the point-spring model (PSM): stiffness calibration and choice of ``N``.

The paper (section 3) calibrates the spring stiffnesses of the PSM on one finite-element grasp
and then studies how the jaw angle depends on the number of triangles ``N``. This module
provides the two tools behind those studies:

* :func:`calibrate` fits the stiffness scale ``s`` of the disk (``SoftDisk.stiffness_scale``),
  and optionally (``fit="scale_and_ratio"``) also the contour-only factor
  ``SoftDisk.contour_stiffness_ratio``, so that the PSM jaw angle along a torque ramp matches a
  reference curve (usually the FEM of :func:`envs.fem.fem_grasp`, see :func:`fem_reference`),
  and reports the error of the jaw *closing* angle ``theta_a0 - theta`` on the fitted curve and
  on held-out cases (other torques, other objects; see :func:`paper_heldout_cases`);
  :meth:`CalibrationResult.errors_on` evaluates any further case;
* :func:`choose_n_triangles` picks the smallest ``N`` whose closing angle and peak strain stay
  within a relative tolerance of a fine PSM reference over a torque range (cached per scene).

Conventions (``shared/CONVENTIONS.md``): the jaw angle of a reference curve is the finger angle
``theta`` from the +y axis [rad] (mean of the right and left fingers); the closing angle is
``theta_a0 - theta`` with ``theta_a0`` the gripper's rest angle; relative errors are
``closing_psm / closing_ref - 1``. Every PSM curve is solved as a loading ramp
(:func:`envs.solver.simulate_ramp`), as in the paper; a torque whose solve does not converge is
reported (``converged=False``, NaN values) and left out of the error statistics. The accuracy
functions first retry such a torque at a torque 0.1-0.3 % away (``retry=True``, see
:func:`psm_curve`; the number of retried torques is reported), because the Newton solver's
failures are isolated and not a property of the model; pass ``retry=False`` to measure the
solver as it is.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares, minimize_scalar

from .scene import Scene
from .solver import GraspResult, simulate, simulate_ramp

__all__ = [
    "PAPER_SCENES",
    "PAPER_TORQUES_NM",
    "HELDOUT_TORQUES_NM",
    "RETRY_FACTORS",
    "ReferenceCurve",
    "PsmCurve",
    "ErrorReport",
    "CalibrationResult",
    "CALIBRATION_FITS",
    "NChoiceRow",
    "NChoice",
    "fem_reference",
    "psm_curve",
    "closing_errors",
    "calibrate",
    "paper_heldout_cases",
    "choose_n_triangles",
    "clear_n_cache",
    "pareto_front",
    "jsonable",
]

#: The paper's three disks (Tables 1 and 2).
PAPER_SCENES = ("paper-r050", "paper-r070", "paper-r100")
#: Torque ramp used for the calibrations of the paper disks [N·m] (peak strain ~3 % to ~27 %).
PAPER_TORQUES_NM = tuple(round(0.05 * k, 10) for k in range(1, 11))
#: Torques not used in the calibration [N·m]: the midpoints of :data:`PAPER_TORQUES_NM` and two
#: extrapolated torques beyond its range.
HELDOUT_TORQUES_NM = tuple(round(0.025 + 0.05 * k, 10) for k in range(1, 10)) + (0.6, 0.75)
#: Torque factors of the retries of :func:`psm_curve` (``retry=True``).
RETRY_FACTORS = (1.001, 0.999, 1.003, 0.997)


# --------------------------------------------------------------------------------------------
# Curves
# --------------------------------------------------------------------------------------------


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
    from .fem import default_mesh_size_m, fem_grasp

    r = scene.disk.radius_m
    h = default_mesh_size_m(r) if mesh_size_m is None else float(mesh_size_m)
    physical = scene.with_changes(stiffness_scale=1.0, contour_stiffness_ratio=1.0)
    results = fem_grasp(physical, list(torques_nm), mesh_size_m=h, plane=plane)
    rings = max(2, math.ceil(r / h - 1e-9))
    return ReferenceCurve.from_fem(results, source=f"fem rings={rings} plane={plane}")


@dataclass(frozen=True)
class PsmCurve:
    """PSM results along a torque ramp (in the order of the requested torques).

    Attributes
    ----------
    torques_nm
        Requested torques [N·m].
    jaw_angles_rad
        Mean finger angle [rad], NaN where the solve did not converge.
    peak_strains
        Peak spring strain [-], NaN where the solve did not converge.
    converged
        Convergence flag of each solve.
    messages
        Solver message of each solve.
    solve_times_s
        Solver-reported wall time of each solve [s].
    wall_time_s
        Wall time of the whole ramp [s] (retries included).
    retried
        Per torque, 1.0 when the ramp solve converged, otherwise the factor ``f`` of the
        perturbed torque ``f T`` whose independent solve answered in its place (``nan`` when
        no retry converged, or retries were off).
    results
        The raw :class:`envs.solver.GraspResult` objects (not compared, not serialised).
    """

    torques_nm: tuple[float, ...]
    jaw_angles_rad: tuple[float, ...]
    peak_strains: tuple[float, ...]
    converged: tuple[bool, ...]
    messages: tuple[str, ...]
    solve_times_s: tuple[float, ...]
    wall_time_s: float
    retried: tuple[float, ...] = ()
    results: tuple[GraspResult, ...] = field(default=(), compare=False, repr=False)

    @property
    def n_retried(self) -> int:
        """Number of torques answered by a retry at a slightly perturbed torque."""
        return int(sum(1 for f in self.retried if math.isfinite(f) and f != 1.0))

    @property
    def n_failed(self) -> int:
        """Number of torques whose solve did not converge."""
        return int(len(self.converged) - sum(self.converged))

    @property
    def time_per_solve_s(self) -> float:
        """Ramp wall time divided by the number of torques [s] (failures and retries count)."""
        return self.wall_time_s / max(1, len(self.torques_nm))

    @property
    def median_converged_solve_s(self) -> float:
        """Median solver-reported time of the converged solves [s] (NaN if none)."""
        t = [dt for dt, ok in zip(self.solve_times_s, self.converged, strict=True) if ok]
        return float(np.median(t)) if t else math.nan


def psm_curve(
    scene: Scene,
    torques_nm: Sequence[float],
    n_triangles: int = 20,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    time_limit_s: float = 30.0,
    retry: bool = False,
) -> PsmCurve:
    """Solve the PSM along a loading ramp through ``torques_nm`` (any order, solved sorted).

    Non-converged solves give NaN angles and strains with ``converged=False``; nothing raises
    for a solver failure.

    The Newton solver occasionally fails at an isolated torque of a ramp while it converges at a
    torque 0.1 % away (its failures are not a property of the model). With ``retry=True`` a
    failed torque ``T`` is re-solved independently (from rest) at ``f T`` for ``f`` in
    :data:`RETRY_FACTORS`, and the first converged answer is used in its place, which changes
    the closing angle by less than 0.3 % of its value (unless the solve from rest reaches
    another equilibrium branch than the ramp); the factor is recorded in ``retried``. Use
    ``retry=False`` (default) to measure the solver itself.

    Parameters
    ----------
    scene
        Gripper and disk (its ``stiffness_scale`` is used as is).
    torques_nm
        Torques [N·m], >= 0.
    n_triangles, method, stiffness_rule, time_limit_s
        See :func:`envs.solver.simulate`.
    retry
        Retry failed torques as described above.

    Returns
    -------
    PsmCurve
        Results in the order of ``torques_nm``.
    """
    torques = np.asarray(torques_nm, dtype=float).ravel()
    order = np.argsort(torques, kind="stable")
    t0 = time.perf_counter()
    raw = simulate_ramp(scene, torques[order], n_triangles, method,
                        stiffness_rule=stiffness_rule, time_limit_s=time_limit_s)
    res: list[GraspResult] = [None] * len(torques)  # type: ignore[list-item]
    for k, i in enumerate(order):
        res[i] = raw[k]
    retried = [1.0 if r.converged else math.nan for r in res]
    if retry:
        for i, r in enumerate(res):
            if r.converged or torques[i] <= 0:
                continue
            for f in RETRY_FACTORS:
                alt = simulate(scene, float(torques[i] * f), n_triangles, method,
                               stiffness_rule=stiffness_rule, time_limit_s=time_limit_s)
                if alt.converged:
                    res[i], retried[i] = alt, f
                    break
    wall = time.perf_counter() - t0
    angles = tuple(float(np.mean(r.jaw_angles_rad)) if r.converged else math.nan for r in res)
    strains = tuple(float(r.peak_strain) if r.converged else math.nan for r in res)
    return PsmCurve(
        torques_nm=tuple(float(t) for t in torques),
        jaw_angles_rad=angles,
        peak_strains=strains,
        converged=tuple(bool(r.converged) for r in res),
        messages=tuple(str(r.message) for r in res),
        solve_times_s=tuple(float(r.solve_time_s) for r in res),
        wall_time_s=wall,
        retried=tuple(retried),
        results=tuple(res),
    )


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


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


# --------------------------------------------------------------------------------------------
# Calibration
# --------------------------------------------------------------------------------------------

#: Parameter sets :func:`calibrate` can fit: the stiffness scale ``s`` alone, or ``s`` and the
#: contour-only factor ``SoftDisk.contour_stiffness_ratio``.
CALIBRATION_FITS = ("scale", "scale_and_ratio")


@dataclass(frozen=True)
class CalibrationResult:
    """Fitted calibration factors and the closing-angle errors of the fit and held-out cases.

    Attributes
    ----------
    scale
        Fitted ``SoftDisk.stiffness_scale`` (absolute, not relative to the input scene) [-].
    initial_scale
        The scene's scale before the fit [-].
    n_triangles, method, stiffness_rule
        PSM settings of the fit (reused by :meth:`errors_on`).
    fit
        :class:`ErrorReport` on the fitted reference curve.
    reference
        The reference curve of the fit.
    evaluations
        Number of PSM ramps solved during the fit.
    fit_time_s
        Wall time of the fit [s] (held-out evaluations not included).
    retry
        Whether isolated solver failures were retried (see :func:`psm_curve`).
    contour_stiffness_ratio
        ``SoftDisk.contour_stiffness_ratio`` of the calibrated model [-]: fitted when
        ``fit_mode == "scale_and_ratio"``, otherwise the scene's value, kept fixed.
    initial_contour_stiffness_ratio
        The scene's ratio before the fit [-].
    fit_mode
        Which parameters were fitted, one of :data:`CALIBRATION_FITS`.
    heldout
        :class:`ErrorReport` of the calibrated model (both factors reused as they are) on each
        held-out case, by label (see ``heldout`` of :func:`calibrate`).
    profile
        For ``"scale_and_ratio"``: the scan that precedes the two-parameter refinement, as
        ``(contour_stiffness_ratio, best scale at that ratio, fitted RMS relative error)``
        rows; it shows how much the ratio matters.
    """

    scale: float
    initial_scale: float
    n_triangles: int
    method: str
    stiffness_rule: str
    fit: ErrorReport
    reference: ReferenceCurve
    evaluations: int
    fit_time_s: float
    retry: bool = True
    contour_stiffness_ratio: float = 1.0
    initial_contour_stiffness_ratio: float = 1.0
    fit_mode: str = "scale"
    heldout: dict[str, ErrorReport] = field(default_factory=dict, compare=False)
    profile: tuple[tuple[float, float, float], ...] = ()

    @property
    def rms_rel_error(self) -> float:
        """RMS relative closing-angle error on the fitted curve [-]."""
        return self.fit.rms_rel_error

    @property
    def max_rel_error(self) -> float:
        """Largest relative closing-angle error on the fitted curve [-]."""
        return self.fit.max_rel_error

    def _heldout_errors(self) -> np.ndarray:
        rel = [np.asarray(r.relative_errors, dtype=float) for r in self.heldout.values()]
        rel = np.concatenate(rel) if rel else np.zeros(0)
        return rel[np.isfinite(rel)]

    @property
    def heldout_rms_rel_error(self) -> float:
        """RMS relative closing-angle error over all converged held-out torques [-]."""
        rel = self._heldout_errors()
        return float(np.sqrt(np.mean(rel**2))) if rel.size else math.nan

    @property
    def heldout_max_rel_error(self) -> float:
        """Largest relative closing-angle error over all converged held-out torques [-]."""
        rel = self._heldout_errors()
        return float(np.max(np.abs(rel))) if rel.size else math.nan

    def calibrated(self, scene: Scene) -> Scene:
        """``scene`` with the fitted stiffness scale and contour stiffness ratio."""
        return scene.with_changes(stiffness_scale=self.scale,
                                  contour_stiffness_ratio=self.contour_stiffness_ratio)

    def errors_on(
        self, scene: Scene, reference_curve, n_triangles: int | None = None,
        method: str | None = None,
    ) -> ErrorReport:
        """Closing-angle error of the calibrated PSM on a case not used in the fit.

        Parameters
        ----------
        scene
            Gripper and disk of the case (e.g. another object); its ``stiffness_scale`` and
            ``contour_stiffness_ratio`` are replaced by the calibrated ones.
        reference_curve
            Reference of that case (other torques, other object), as in :func:`calibrate`.
        n_triangles, method
            PSM settings; default: those of the fit.
        """
        return closing_errors(
            self.calibrated(scene), reference_curve,
            self.n_triangles if n_triangles is None else n_triangles,
            self.method if method is None else method,
            stiffness_rule=self.stiffness_rule,
            retry=self.retry,
        )

    def with_heldout(self, cases: Mapping) -> CalibrationResult:
        """A copy whose :attr:`heldout` also holds the errors on ``cases``.

        Parameters
        ----------
        cases
            ``{label: (scene, reference_curve)}``, see ``heldout`` of :func:`calibrate`.
        """
        reports = dict(self.heldout)
        for label, case in cases.items():
            try:
                case_scene, case_ref = case
            except (TypeError, ValueError):
                raise ValueError(
                    f"held-out case {label!r} must be a pair (scene, reference_curve)"
                ) from None
            reports[str(label)] = self.errors_on(case_scene, case_ref)
        return replace(self, heldout=reports)

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {
            "fit_mode": self.fit_mode,
            "scale": self.scale,
            "contour_stiffness_ratio": self.contour_stiffness_ratio,
            "initial_scale": self.initial_scale,
            "initial_contour_stiffness_ratio": self.initial_contour_stiffness_ratio,
            "n_triangles": self.n_triangles,
            "method": self.method,
            "stiffness_rule": self.stiffness_rule,
            "rms_rel_error": self.rms_rel_error,
            "max_rel_error": self.max_rel_error,
            "heldout_rms_rel_error": self.heldout_rms_rel_error,
            "heldout_max_rel_error": self.heldout_max_rel_error,
            "evaluations": self.evaluations,
            "fit_time_s": self.fit_time_s,
            "retry": self.retry,
            "fit": self.fit.to_dict(),
            "heldout": {k: v.to_dict() for k, v in self.heldout.items()},
            "profile": [list(row) for row in self.profile],
            "reference": self.reference.to_dict(),
        }


_PENALTY = 1e6  # objective when fewer than half of the torques converge
_FAILED_ERROR = 1.0  # relative error charged to a torque whose PSM solve failed


class _Objective:
    """Relative closing-angle errors of the PSM along the reference ramp, cached per parameters.

    The parameters are ``log s`` and ``log rho_c`` (stiffness scale and contour stiffness
    ratio). A failed torque is charged :data:`_FAILED_ERROR`, so that a fit cannot improve by
    moving to parameters where a badly matched torque happens to fail; fewer than half
    converged torques cost :data:`_PENALTY`.
    """

    def __init__(self, scene: Scene, ref: ReferenceCurve, n_triangles: int, method: str,
                 stiffness_rule: str, retry: bool) -> None:
        self.scene, self.ref = scene, ref
        self.c_ref = ref.closing_rad(scene)
        self.n_triangles, self.method = n_triangles, method
        self.stiffness_rule, self.retry = stiffness_rule, retry
        self.cache: dict[tuple[float, float], np.ndarray] = {}

    def rel(self, log_s: float, log_rho: float) -> np.ndarray:
        """Relative closing-angle errors (NaN where the PSM did not converge) [-]."""
        key = (round(float(log_s), 12), round(float(log_rho), 12))
        if key not in self.cache:
            sc = self.scene.with_changes(stiffness_scale=math.exp(key[0]),
                                         contour_stiffness_ratio=math.exp(key[1]))
            curve = psm_curve(sc, self.ref.torques_nm, self.n_triangles, self.method,
                              stiffness_rule=self.stiffness_rule, retry=self.retry)
            c_mod = sc.gripper.rest_angle_rad - np.asarray(curve.jaw_angles_rad)
            self.cache[key] = c_mod / self.c_ref - 1.0
        return self.cache[key]

    def residuals(self, x) -> np.ndarray:
        """Residual vector of the least-squares fit at ``x = (log s, log rho_c)``."""
        rel = self.rel(x[0], x[1])
        ok = np.isfinite(rel)
        if 2 * ok.sum() < len(rel):
            return np.full(len(rel), math.sqrt(_PENALTY))
        return np.where(ok, rel, _FAILED_ERROR)

    def cost(self, log_s: float, log_rho: float) -> float:
        """Mean squared residual [-]."""
        return float(np.mean(self.residuals((log_s, log_rho)) ** 2))

    def mean_rel(self, log_s: float, log_rho: float) -> float:
        """Mean relative error over the converged torques (NaN if too few converged) [-]."""
        rel = self.rel(log_s, log_rho)
        ok = np.isfinite(rel)
        return float(np.mean(rel[ok])) if 2 * ok.sum() >= len(rel) else math.nan


def _fit_scale(obj: _Objective, log_rho: float, s_start: float, *, xatol: float,
               max_factor: float, grid_points: int, step_factor: float) -> float:
    """``log s`` minimising the objective at a fixed contour stiffness ratio.

    Brackets the sign change of the mean relative error by multiplying or dividing ``s`` by
    ``step_factor`` from ``s_start``, scans the bracket on ``grid_points`` points, then refines
    around the best one with a bounded Brent search (tolerance ``xatol`` on ``log s``).
    """
    seen: dict[float, float] = {}

    def evaluate(log_s: float) -> tuple[float, float]:
        log_s = round(float(log_s), 12)
        seen[log_s] = obj.cost(log_s, log_rho)
        return seen[log_s], obj.mean_rel(log_s, log_rho)

    # bracket the sign change of the mean relative error (closing decreases as s grows)
    x0 = math.log(s_start)
    _, m0 = evaluate(x0)
    step = math.log(step_factor)
    if not math.isfinite(m0):
        # try the neighbours before giving up on the starting point
        for x in (x0 + step, x0 - step):
            _, m0 = evaluate(x)
            if math.isfinite(m0):
                x0 = x
                break
    direction = 1.0 if (not math.isfinite(m0) or m0 > 0) else -1.0
    x_min = math.log(s_start) - math.log(max_factor)
    x_max = math.log(s_start) + math.log(max_factor)
    x = x_new = x0
    while x_min < x < x_max:
        x_new = min(x_max, max(x_min, x + direction * step))
        _, m = evaluate(x_new)
        if math.isfinite(m) and (m < 0 if direction > 0 else m > 0):
            break
        x = x_new
    # the last step crossed the sign change (or hit the bound): search between its ends,
    # widened by half a step so that a minimum at either end stays interior
    lo = max(x_min, min(x, x_new) - 0.5 * step)
    hi = min(x_max, max(x, x_new) + 0.5 * step)
    # the PSM curve has small jumps where a contour point enters the contact, so the objective
    # is only piecewise smooth: scan a grid first, then refine around its best point
    grid = np.linspace(lo, hi, int(grid_points))
    values = [evaluate(float(g))[0] for g in grid]
    k = int(np.argmin(values))
    lo, hi = float(grid[max(k - 1, 0)]), float(grid[min(k + 1, len(grid) - 1)])
    res = minimize_scalar(lambda v: evaluate(v)[0], bounds=(lo, hi), method="bounded",
                          options={"xatol": xatol, "maxiter": 200})
    best = min(seen, key=seen.get)
    return float(res.x) if evaluate(float(res.x))[0] <= seen[best] else best


def _fit_scale_and_ratio(
    obj: _Objective, *, xatol: float, max_factor: float, grid_points: int, step_factor: float,
    ratio_bounds: tuple[float, float], ratio_factors: Sequence[float], max_evaluations: int,
) -> tuple[float, float, tuple[tuple[float, float, float], ...]]:
    """``(log s, log rho_c)`` of the two-parameter fit and the ratio profile that seeds it."""
    d = obj.scene.disk
    s0, rho0 = d.stiffness_scale, d.contour_stiffness_ratio
    lr_lo, lr_hi = (math.log(v) for v in ratio_bounds)
    ls_lo, ls_hi = math.log(s0) - math.log(max_factor), math.log(s0) + math.log(max_factor)
    # profile: the best scale at a few ratios (each fit warm-started from the previous one)
    ratios = sorted({min(max(rho0 * float(f), ratio_bounds[0]), ratio_bounds[1])
                     for f in ratio_factors} | {min(max(rho0, ratio_bounds[0]),
                                                    ratio_bounds[1])})
    profile = []
    s_start = s0
    for k, rho in enumerate(ratios):
        log_s = _fit_scale(obj, math.log(rho), s_start, xatol=max(xatol, 1e-4),
                           max_factor=max_factor * max(s0 / s_start, s_start / s0),
                           grid_points=grid_points,
                           step_factor=step_factor if k == 0 else min(step_factor, 1.25))
        log_s = min(max(log_s, ls_lo), ls_hi)
        cost = obj.cost(log_s, math.log(rho))
        profile.append((float(rho), math.exp(log_s), math.sqrt(cost)))
        s_start = math.exp(log_s)
    k = int(np.argmin([row[2] for row in profile]))
    x0 = np.array([math.log(profile[k][1]), math.log(profile[k][0])])
    x0 = np.clip(x0, [ls_lo, lr_lo], [ls_hi, lr_hi])
    budget = max(10, int(max_evaluations) - len(obj.cache))
    least_squares(obj.residuals, x0, bounds=([ls_lo, lr_lo], [ls_hi, lr_hi]), method="trf",
                  diff_step=1e-4, xtol=xatol, ftol=1e-12, gtol=1e-12, max_nfev=budget)
    # the objective is only piecewise smooth: keep the best parameters evaluated anywhere
    inside = [k for k in obj.cache if lr_lo - 1e-9 <= k[1] <= lr_hi + 1e-9]
    best = min(inside, key=lambda k: obj.cost(*k))
    return best[0], best[1], tuple(profile)


def calibrate(
    scene: Scene,
    reference_curve,
    n_triangles: int = 20,
    *,
    fit: str = "scale",
    separate: bool = False,
    method: str = "newton",
    stiffness_rule: str = "van_gelder",
    xatol: float = 1e-6,
    max_factor: float = 100.0,
    retry: bool = True,
    grid_points: int = 9,
    step_factor: float = 2.0,
    ratio_bounds: tuple[float, float] = (0.1, 10.0),
    ratio_factors: Sequence[float] = (0.1, 0.3, 3.0, 10.0),
    max_evaluations: int = 400,
    heldout: Mapping | None = None,
) -> CalibrationResult:
    """Fit the PSM stiffness calibration so that its jaw angle matches a reference curve.

    The paper calibrates the spring stiffnesses on one finite-element grasp. Two parameter sets
    are offered (``fit``):

    * ``"scale"`` (default): ``SoftDisk.stiffness_scale`` ``s`` alone, which multiplies every
      spring of the stiffness rule (the disk's ``contour_stiffness_ratio`` is kept as is);
    * ``"scale_and_ratio"``: ``s`` and ``SoftDisk.contour_stiffness_ratio`` ``rho_c``, which
      multiplies the contour (external) springs only, i.e. separate radial and contour scales
      ``s`` and ``rho_c s``.

    The objective is the mean squared relative error of the closing angle ``theta_a0 - theta``
    over the reference torques, the PSM being solved as a loading ramp through them.

    The scale-only fit brackets the sign change of the mean relative error by doubling or
    halving ``s`` from the scene's value, scans the bracket on a grid of ``grid_points`` (the
    objective is only piecewise smooth: the PSM curve jumps slightly when a contour point enters
    the contact), then minimises the objective in ``log s`` with
    :func:`scipy.optimize.minimize_scalar` (bounded Brent) between the neighbours of the best
    grid point. The two-parameter fit first runs that scale fit at the ratios
    ``rho_c0 * ratio_factors`` and ``rho_c0`` (the scene's ratio; this profile is reported),
    then refines the best profile point with :func:`scipy.optimize.least_squares` on
    ``(log s, log rho_c)`` over the relative errors, and returns the best parameters evaluated.

    A torque where the PSM does not converge is charged a 100 % error in the objective (and
    left out of the reported statistics, its failure being counted in ``fit.n_failed``);
    parameters for which fewer than half of the torques converge get a large penalty.

    Parameters
    ----------
    scene
        Gripper and disk; the fit starts from ``scene.disk.stiffness_scale`` and
        ``scene.disk.contour_stiffness_ratio``.
    reference_curve
        A :class:`ReferenceCurve`, a list of :class:`envs.fem.FemResult` or a pair
        ``(torques_nm, jaw_angles_rad)`` with ``jaw_angles_rad`` the finger angle ``theta``
        from the +y axis [rad].
    n_triangles
        Number of triangles of the PSM used for the fit.
    fit
        ``"scale"`` or ``"scale_and_ratio"`` (:data:`CALIBRATION_FITS`).
    separate
        Fit separate contour and radial scales: ``True`` is the same as
        ``fit="scale_and_ratio"`` (kept for backward compatibility).
    method
        PSM solver (``"newton"``; the baselines are far too slow for a fit).
    stiffness_rule
        PSM stiffness rule (``"van_gelder"`` or the Poisson-aware ``"cst_fit"``; with the
        two-parameter fit both rules span the same radial and contour stiffnesses).
    xatol
        Tolerance on ``log s`` of the bounded Brent search and ``xtol`` of the least-squares
        refinement (relative to the norm of ``(log s, log rho_c)``).
    max_factor
        The scale is searched within ``[s0 / max_factor, s0 * max_factor]`` (``s0`` the scene's
        scale); a fit that ends on that bound (e.g. ``N = 4``, whose square cannot follow the
        FEM at all) is reported as is.
    retry
        Retry isolated solver failures at a torque 0.1-0.3 % away (see :func:`psm_curve`).
    grid_points
        Points of the scan of the bracket that precedes the Brent refinement (>= 3).
    step_factor
        Factor by which ``s`` is multiplied or divided at each bracketing step (> 1); use a
        small one (e.g. 1.1) when the scene's scale is already a good guess, e.g. the scale
        fitted with fewer triangles.
    ratio_bounds
        ``(rho_min, rho_max)``: search interval of ``rho_c``, within (0, 1e3]
        (two-parameter fit only). The default (0.1, 10) keeps the fan away from its
        degenerate ends: with ``rho_c`` of a few hundredths the contour hardly resists and the
        fit overfits (measured on ``paper-r070``, N = 20, ``cst_fit`` rule: ``rho_c = 0.032``,
        i.e. 0.026 in van Gelder terms, fitted 1.8 % RMS but gave 19 % on held-out torques
        and 56 % on the r = 0.05 disk), and from about 100 on the
        Newton solver fails on many torques of the r = 0.05 and 0.07 disks.
    ratio_factors
        Factors of the scene's ratio at which the profile is computed (two-parameter fit).
    max_evaluations
        Budget of PSM ramps of the two-parameter fit; the least-squares refinement gets what
        the profile left (at least 10).
    heldout
        Cases not used in the fit, ``{label: (scene, reference_curve)}``: the calibrated
        factors are applied to each scene as they are (the paper's "fit once, reuse") and the
        errors are stored in :attr:`CalibrationResult.heldout`. See
        :func:`paper_heldout_cases` for the paper disks.

    Returns
    -------
    CalibrationResult
        The fitted factors, the error report on the fitted curve and on the held-out cases,
        and :meth:`CalibrationResult.errors_on` for further cases.

    Raises
    ------
    ValueError
        For an invalid reference curve, fit name or option.
    """
    if separate:
        fit = "scale_and_ratio"
    if fit not in CALIBRATION_FITS:
        raise ValueError(f"fit must be one of {CALIBRATION_FITS}, got {fit!r}")
    if int(grid_points) < 3:
        raise ValueError(f"grid_points must be >= 3, got {grid_points!r}")
    if not (math.isfinite(max_factor) and max_factor > 1):
        raise ValueError(f"max_factor must be > 1, got {max_factor!r}")
    if not (math.isfinite(step_factor) and step_factor > 1):
        raise ValueError(f"step_factor must be > 1, got {step_factor!r}")
    try:
        r_lo, r_hi = (float(v) for v in ratio_bounds)
    except (TypeError, ValueError):
        raise ValueError("ratio_bounds must be a pair (rho_min, rho_max)") from None
    if not (0 < r_lo < r_hi <= 1e3):
        raise ValueError(
            f"ratio_bounds must satisfy 0 < rho_min < rho_max <= 1e3, got {ratio_bounds!r}"
        )
    if not all(math.isfinite(float(f)) and float(f) > 0 for f in ratio_factors):
        raise ValueError(f"ratio_factors must be positive numbers, got {ratio_factors!r}")
    ref = _as_reference(reference_curve)
    c_ref = ref.closing_rad(scene)
    if np.any(c_ref <= 0):
        raise ValueError(
            "the reference jaw angles must be below the rest angle theta_a0 (positive closing)"
        )
    t_start = time.perf_counter()
    s0 = scene.disk.stiffness_scale
    rho0 = scene.disk.contour_stiffness_ratio
    obj = _Objective(scene, ref, int(n_triangles), method, stiffness_rule, bool(retry))
    profile: tuple[tuple[float, float, float], ...] = ()
    if fit == "scale":
        log_rho = math.log(rho0)
        log_s = _fit_scale(obj, log_rho, s0, xatol=xatol, max_factor=max_factor,
                           grid_points=int(grid_points), step_factor=step_factor)
    else:
        log_s, log_rho, profile = _fit_scale_and_ratio(
            obj, xatol=xatol, max_factor=max_factor, grid_points=int(grid_points),
            step_factor=step_factor, ratio_bounds=(r_lo, r_hi), ratio_factors=ratio_factors,
            max_evaluations=max_evaluations,
        )
    scale, ratio = math.exp(log_s), math.exp(log_rho)
    fitted = scene.with_changes(stiffness_scale=scale, contour_stiffness_ratio=ratio)
    curve = psm_curve(fitted, ref.torques_nm, n_triangles, method,
                      stiffness_rule=stiffness_rule, retry=retry)
    report = _error_report(fitted, ref, curve, n_triangles, method)
    result = CalibrationResult(
        scale=scale,
        initial_scale=s0,
        n_triangles=int(n_triangles),
        method=method,
        stiffness_rule=stiffness_rule,
        fit=report,
        reference=ref,
        evaluations=len(obj.cache) + 1,
        fit_time_s=time.perf_counter() - t_start,
        retry=bool(retry),
        contour_stiffness_ratio=ratio,
        initial_contour_stiffness_ratio=rho0,
        fit_mode=fit,
        profile=profile,
    )
    return result.with_heldout(heldout) if heldout else result


def paper_heldout_cases(
    fitted_preset: str = "paper-r070",
    *,
    torques_nm: Sequence[float] = PAPER_TORQUES_NM,
    heldout_torques_nm: Sequence[float] = HELDOUT_TORQUES_NM,
    rings: int | None = None,
) -> dict[str, tuple[Scene, ReferenceCurve]]:
    """Held-out FEM cases of a calibration on one paper disk (for ``calibrate(heldout=...)``).

    Parameters
    ----------
    fitted_preset
        The paper preset the calibration is fitted on (one of :data:`PAPER_SCENES`).
    torques_nm
        Torque ramp of the other disks [N·m] (default: the fitting ramp
        :data:`PAPER_TORQUES_NM`, so that their FEM curves are shared with their own fits).
    heldout_torques_nm
        Torques of the fitted disk not used in the fit [N·m].
    rings
        FEM element size ``r / rings``; default :func:`envs.fem.default_mesh_size_m`.

    Returns
    -------
    dict
        ``"<preset> held-out torques"``: the fitted disk at ``heldout_torques_nm``, and
        ``"<other preset>"``: each other paper disk at ``torques_nm`` (FEM, disk-cached).
    """
    if fitted_preset not in PAPER_SCENES:
        raise ValueError(f"fitted_preset must be one of {PAPER_SCENES}, got {fitted_preset!r}")
    if rings is not None and (isinstance(rings, bool) or int(rings) != rings or rings < 2):
        raise ValueError(f"rings must be an integer >= 2, got {rings!r}")

    def ref(sc: Scene, torques) -> ReferenceCurve:
        h = None if rings is None else sc.disk.radius_m / int(rings)
        return fem_reference(sc, torques, mesh_size_m=h)

    own = Scene.preset(fitted_preset)
    cases = {f"{fitted_preset} held-out torques": (own, ref(own, heldout_torques_nm))}
    for name in PAPER_SCENES:
        if name != fitted_preset:
            other = Scene.preset(name)
            cases[name] = (other, ref(other, torques_nm))
    return cases


# --------------------------------------------------------------------------------------------
# Choice of N
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NChoiceRow:
    """One candidate ``N`` of :func:`choose_n_triangles`.

    Attributes
    ----------
    n_triangles
        Candidate ``N``.
    closing_rel_error
        Largest relative closing-angle difference to the reference over the torques [-]
        (NaN if a solve failed).
    strain_rel_error
        Largest relative peak-strain difference to the reference [-] (NaN if a solve failed).
    n_failed
        Torques where the candidate did not converge.
    n_retried
        Torques answered by a retry at a torque 0.1-0.3 % away (see :func:`psm_curve`).
    time_per_solve_s
        Ramp wall time divided by the number of torques [s] (failures and retries count).
    median_solve_s
        Median solver-reported time of the converged solves [s].
    within_tolerance
        All torques converged and both errors are within the tolerance.
    """

    n_triangles: int
    closing_rel_error: float
    strain_rel_error: float
    n_failed: int
    n_retried: int
    time_per_solve_s: float
    median_solve_s: float
    within_tolerance: bool

    def to_dict(self) -> dict:
        """JSON-friendly copy (NaN as ``None``)."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in ((k, getattr(self, k)) for k in self.__dataclass_fields__)}


@dataclass(frozen=True)
class NChoice:
    """Outcome of :func:`choose_n_triangles`.

    Attributes
    ----------
    n_triangles
        The smallest candidate within tolerance (the largest candidate when none is, with
        ``within_tolerance=False``).
    within_tolerance
        Whether the chosen ``N`` meets the tolerance.
    tolerance
        Relative tolerance on the closing angle and the peak strain [-].
    torques_nm
        Torques compared [N·m] (those where the reference converged).
    reference_n
        Requested ``N`` of the reference.
    reference_ns
        ``N`` of the reference actually used at each torque (a nearby ``N`` where the requested
        one did not converge).
    reference_closing_rad, reference_peak_strains
        Reference values at ``torques_nm``.
    dropped_torques_nm
        Sampled torques left out because no reference converged there.
    rows
        Candidates evaluated, in increasing ``N`` (the search stops at the first one within
        tolerance unless ``full_table=True``).
    reference_time_per_solve_s
        Reference ramp wall time divided by the number of torques [s] (failed solves and
        retries included: a fine mesh that struggles costs that time).
    time_per_solve_s
        Same for the chosen ``N`` [s].
    reference_median_solve_s, median_solve_s
        Median solver-reported time of the converged solves of the reference and of the chosen
        ``N`` [s] (the cost without failures).
    """

    n_triangles: int
    within_tolerance: bool
    tolerance: float
    torques_nm: tuple[float, ...]
    reference_n: int
    reference_ns: tuple[int, ...]
    reference_closing_rad: tuple[float, ...]
    reference_peak_strains: tuple[float, ...]
    dropped_torques_nm: tuple[float, ...]
    rows: tuple[NChoiceRow, ...]
    reference_time_per_solve_s: float
    time_per_solve_s: float
    reference_median_solve_s: float = math.nan
    median_solve_s: float = math.nan

    @property
    def speedup(self) -> float:
        """Reference time per solve divided by the chosen ``N``'s [-]."""
        return self.reference_time_per_solve_s / max(self.time_per_solve_s, 1e-12)

    @property
    def median_speedup(self) -> float:
        """Ratio of the median converged solve times, reference over chosen ``N`` [-]."""
        return self.reference_median_solve_s / max(self.median_solve_s, 1e-12)

    def row(self, n_triangles: int) -> NChoiceRow:
        """The table row of a candidate (``KeyError`` if it was not evaluated)."""
        for r in self.rows:
            if r.n_triangles == n_triangles:
                return r
        raise KeyError(n_triangles)

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {
            "n_triangles": self.n_triangles,
            "within_tolerance": self.within_tolerance,
            "tolerance": self.tolerance,
            "torques_nm": list(self.torques_nm),
            "reference_n": self.reference_n,
            "reference_ns": list(self.reference_ns),
            "reference_closing_rad": list(self.reference_closing_rad),
            "reference_peak_strains": list(self.reference_peak_strains),
            "dropped_torques_nm": list(self.dropped_torques_nm),
            "rows": [r.to_dict() for r in self.rows],
            "reference_time_per_solve_s": self.reference_time_per_solve_s,
            "time_per_solve_s": self.time_per_solve_s,
            "speedup": self.speedup,
            "reference_median_solve_s": self.reference_median_solve_s,
            "median_solve_s": self.median_solve_s,
            "median_speedup": self.median_speedup,
        }


_N_CACHE: dict[tuple, NChoice] = {}
_CURVE_CACHE: dict[tuple, PsmCurve] = {}  # ramps of choose_n_triangles, shared by its calls
DEFAULT_CANDIDATES = (4, 6, 8, 10, 12, 16, 20, 24, 32, 40, 60, 80)


def clear_n_cache() -> None:
    """Forget the results (and the solved ramps) of :func:`choose_n_triangles`."""
    _N_CACHE.clear()
    _CURVE_CACHE.clear()


def _cached_curve(scene: Scene, torques: np.ndarray, n: int, method: str, stiffness_rule: str,
                  retry: bool) -> PsmCurve:
    key = (scene, tuple(float(t) for t in torques), int(n), method, stiffness_rule, bool(retry))
    if key not in _CURVE_CACHE:
        _CURVE_CACHE[key] = psm_curve(scene, torques, n, method, stiffness_rule=stiffness_rule,
                                      retry=retry)
    return _CURVE_CACHE[key]


def _reference_values(
    scene: Scene, torques: np.ndarray, reference_n: int, method: str, stiffness_rule: str,
    retry: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Fine reference at each torque; a failed torque is retried on nearby meshes."""
    curve = _cached_curve(scene, torques, reference_n, method, stiffness_rule, retry)
    angles = np.asarray(curve.jaw_angles_rad, dtype=float)
    strains = np.asarray(curve.peak_strains, dtype=float)
    used_n = np.full(len(torques), reference_n)
    for dn in (4, -4, 8, -8):
        bad = ~np.isfinite(angles)
        if not bad.any():
            break
        alt = _cached_curve(scene, torques[bad], reference_n + dn, method, stiffness_rule,
                            retry)
        angles[bad] = alt.jaw_angles_rad
        strains[bad] = alt.peak_strains
        used_n[bad] = reference_n + dn
    return angles, strains, used_n, curve.time_per_solve_s, curve.median_converged_solve_s


def choose_n_triangles(
    scene: Scene,
    torque_range: tuple[float, float],
    tolerance: float = 0.01,
    *,
    candidates: Sequence[int] = DEFAULT_CANDIDATES,
    reference_n: int = 160,
    n_torques: int = 5,
    method: str = "newton",
    stiffness_rule: str = "van_gelder",
    full_table: bool = False,
    retry: bool = True,
) -> NChoice:
    """Smallest ``N`` whose closing angle and peak strain match a fine PSM within a tolerance.

    ``n_torques`` torques evenly spaced over ``torque_range`` are solved as a ramp with the
    reference ``N`` and with each candidate in increasing order; a candidate is accepted when it
    converges at every torque and its closing angle ``theta_a0 - theta`` and peak strain are
    within ``tolerance`` (relative) of the reference at every torque. The first accepted
    candidate is returned, so the one before it (if any) violates the tolerance.

    A reference torque that does not converge is retried with ``reference_n`` +- 4 and +- 8
    triangles (recorded in ``reference_n``) and dropped if none converges.

    Results are cached per (scene, arguments) in memory, and so are the solved ramps (calls
    that differ only by the tolerance reuse them, so their times per solve are the same
    measurements); see :func:`clear_n_cache`.

    Parameters
    ----------
    scene
        Gripper and disk (its ``stiffness_scale`` is used as is).
    torque_range
        ``(T_min, T_max)`` [N·m], ``0 < T_min <= T_max``.
    tolerance
        Relative tolerance on the closing angle and the peak strain [-], > 0.
    candidates
        Candidate ``N`` values (sorted here; each >= 4).
    reference_n
        ``N`` of the fine reference (larger than every candidate).
    n_torques
        Number of torques sampled in ``torque_range``.
    method, stiffness_rule
        PSM settings.
    full_table
        Evaluate every candidate (the choice is the same; the table is complete).
    retry
        Retry isolated solver failures at a torque 0.1-0.3 % away (see :func:`psm_curve`);
        a candidate must still answer at every torque.

    Returns
    -------
    NChoice
        The chosen ``N`` with the errors table and the time per solve.

    Raises
    ------
    ValueError
        For an invalid range, tolerance or candidate list.
    """
    try:
        t_lo, t_hi = (float(v) for v in torque_range)
    except (TypeError, ValueError):
        raise ValueError("torque_range must be a pair (T_min, T_max) of numbers") from None
    if not (math.isfinite(t_lo) and math.isfinite(t_hi) and 0 < t_lo <= t_hi):
        raise ValueError(f"torque_range must satisfy 0 < T_min <= T_max, got {torque_range!r}")
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be > 0, got {tolerance!r}")
    cands = tuple(sorted({int(c) for c in candidates}))
    if not cands or cands[0] < 4:
        raise ValueError("candidates must be a non-empty list of integers >= 4")
    if int(reference_n) <= cands[-1]:
        raise ValueError(
            f"reference_n = {reference_n} must be larger than every candidate (max {cands[-1]})"
        )
    if int(n_torques) < 1:
        raise ValueError("n_torques must be >= 1")
    key = (scene, t_lo, t_hi, float(tolerance), cands, int(reference_n), int(n_torques), method,
           stiffness_rule, bool(full_table), bool(retry))
    if key in _N_CACHE:
        return _N_CACHE[key]

    torques = np.linspace(t_lo, t_hi, int(n_torques))
    th0 = scene.gripper.rest_angle_rad
    angles, strains, used_n, ref_time, ref_median = _reference_values(
        scene, torques, int(reference_n), method, stiffness_rule, bool(retry)
    )
    keep = np.isfinite(angles)
    dropped = tuple(float(t) for t in torques[~keep])
    torques, angles, strains, used_n = torques[keep], angles[keep], strains[keep], used_n[keep]
    c_ref = th0 - angles
    rows: list[NChoiceRow] = []
    chosen: NChoiceRow | None = None
    if torques.size:
        for n in cands:
            curve = _cached_curve(scene, torques, n, method, stiffness_rule, retry)
            c = th0 - np.asarray(curve.jaw_angles_rad)
            s = np.asarray(curve.peak_strains)
            e_c = float(np.max(np.abs(c / c_ref - 1))) if curve.n_failed == 0 else math.nan
            e_s = float(np.max(np.abs(s / strains - 1))) if curve.n_failed == 0 else math.nan
            ok = curve.n_failed == 0 and e_c <= tolerance and e_s <= tolerance
            row = NChoiceRow(n, e_c, e_s, curve.n_failed, curve.n_retried,
                             curve.time_per_solve_s, curve.median_converged_solve_s, bool(ok))
            rows.append(row)
            if ok and chosen is None:
                chosen = row
                if not full_table:
                    break
    if chosen is None:
        chosen = rows[-1] if rows else NChoiceRow(cands[-1], math.nan, math.nan, 0, 0,
                                                  math.nan, math.nan, False)
    out = NChoice(
        n_triangles=chosen.n_triangles,
        within_tolerance=chosen.within_tolerance,
        tolerance=float(tolerance),
        torques_nm=tuple(float(t) for t in torques),
        reference_n=int(reference_n),
        reference_ns=tuple(int(v) for v in used_n),
        reference_closing_rad=tuple(float(v) for v in c_ref),
        reference_peak_strains=tuple(float(v) for v in strains),
        dropped_torques_nm=dropped,
        rows=tuple(rows),
        reference_time_per_solve_s=float(ref_time),
        time_per_solve_s=float(chosen.time_per_solve_s),
        reference_median_solve_s=float(ref_median),
        median_solve_s=float(chosen.median_solve_s),
    )
    _N_CACHE[key] = out
    return out


# --------------------------------------------------------------------------------------------
# Small helpers for the study scripts
# --------------------------------------------------------------------------------------------


def pareto_front(costs: Sequence[float], errors: Sequence[float]) -> list[int]:
    """Indices of the non-dominated points when minimising both ``costs`` and ``errors``.

    A point is dominated when another one is no worse in both and better in one. Points with a
    non-finite value are never on the front. The indices are returned by increasing cost.
    """
    c = np.asarray(costs, dtype=float)
    e = np.asarray(errors, dtype=float)
    idx = [i for i in range(len(c)) if math.isfinite(c[i]) and math.isfinite(e[i])]
    front = []
    for i in idx:
        dominated = any(
            c[j] <= c[i] and e[j] <= e[i] and (c[j] < c[i] or e[j] < e[i]) for j in idx
        )
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: (c[i], e[i]))


def jsonable(obj):
    """Recursively convert numpy values, tuples and dataclass reports to JSON-safe objects.

    Non-finite floats become ``None`` (strict JSON has no NaN).
    """
    if hasattr(obj, "to_dict"):
        return jsonable(obj.to_dict())
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer | int):
        return int(obj)
    if isinstance(obj, np.floating | float):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj
