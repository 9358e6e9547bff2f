"""The calibration objective and its fits: the scale alone, or the scale and the contour ratio.

:class:`_Objective` caches the relative closing-angle errors per parameters; :func:`_fit_scale`
(bracket, grid scan, bounded Brent) and :func:`_fit_scale_and_ratio` (ratio profile, then
least squares) are the two fits behind :func:`~envs.accuracy.calibration.calibrate`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import least_squares, minimize_scalar

from ..scene import Scene
from .curves import psm_curve
from .reference import ReferenceCurve

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
