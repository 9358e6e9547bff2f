"""Baseline solvers on the same point-spring model, for honest comparisons.

* ``"slsqp"``: SciPy's SLSQP minimising the potential energy subject to the contact gaps (face
  constraints of every contour point on each finger, finger stops), with analytic gradients.
  It does not model the corner-against-edge contact (the KKT check flags a penetrating corner).
  Contact forces are recovered afterwards by non-negative least squares on the active gaps.
* ``"nelder-mead"``: the paper's approach, a Nelder-Mead simplex minimising the squared residual
  of the equilibrium equations, contact represented by a stiff penalty on penetration.

Both return a :class:`envs.solver.result.GraspResult` through the same pipeline tail as the
Newton solver (:func:`envs.solver.pipeline.checked_solution`: metrics, independent check,
status), so a baseline that stops short is reported as not converged.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize, nnls

from envs.model.energy import energy_scaled, gradient_scaled
from envs.model.geometry import finger_axes_array, rest_points
from envs.model.layout import (
    I_ITERATIONS,
    I_STATUS,
    N_CORNERS,
    N_INFO,
    P_C0X,
    P_HW,
    P_KC,
    P_KR,
    P_LMAX,
    P_PHASE,
    P_TAU,
    P_TH0,
    P_THMIN,
)
from envs.model.problem import pack_params
from envs.scene import Scene

from .pipeline import checked_solution, grasp_result
from .status import ITER_LIMIT, OK

__all__ = ["solve", "face_gaps", "face_gap_jacobian"]


class _Scaled(NamedTuple):
    """A scaled problem as the baselines see it: N and its parameter row."""

    n: int
    params: np.ndarray


class _Timeout(Exception):
    pass


def _frames(theta: np.ndarray):
    """Axes ``e`` and inward normals ``n`` of both fingers, rows right then left."""
    axes = [finger_axes_array(j, theta[j]) for j in range(2)]
    e = np.array([[a[0], a[1]] for a in axes])
    nrm = np.array([[a[2], a[3]] for a in axes])
    return e, nrm


def face_gaps(x: np.ndarray, prob: _Scaled, idx: np.ndarray) -> np.ndarray:
    """Scaled distance of points ``idx[j]`` to the gripping-face segment of finger ``j``.

    Returns the concatenation over the two fingers (right first).
    """
    p, n = prob.params, prob.n
    q = x[: 2 * n].reshape(n, 2)
    e, nrm = _frames(x[2 * n : 2 * n + 2])
    out = []
    for j in range(2):
        v = q[idx[j]] + p[P_C0X + 2 * j : P_C0X + 2 * j + 2]
        s = v @ e[j]
        m = v @ nrm[j] - p[P_HW]
        sc = np.clip(s, 0.0, p[P_LMAX])
        out.append(np.where(s == sc, m, np.hypot(s - sc, m)))
    return np.concatenate(out)


def face_gap_jacobian(x: np.ndarray, prob: _Scaled, idx: np.ndarray) -> np.ndarray:
    """Jacobian of :func:`face_gaps` with respect to ``x``."""
    p, n = prob.params, prob.n
    q = x[: 2 * n].reshape(n, 2)
    e, nrm = _frames(x[2 * n : 2 * n + 2])
    rows = []
    for j in range(2):
        ii = idx[j]
        jac = np.zeros((len(ii), 2 * n + 2))
        v = q[ii] + p[P_C0X + 2 * j : P_C0X + 2 * j + 2]
        s = v @ e[j]
        m = v @ nrm[j] - p[P_HW]
        sc = np.clip(s, 0.0, p[P_LMAX])
        inside = s == sc
        dist = np.hypot(s - sc, m)
        dist = np.where(dist > 0, dist, 1.0)
        # gradient in world coordinates: n on the face, unit vector from the corner beyond it
        gx = np.where(inside, nrm[j, 0], ((s - sc) * e[j, 0] + m * nrm[j, 0]) / dist)
        gy = np.where(inside, nrm[j, 1], ((s - sc) * e[j, 1] + m * nrm[j, 1]) / dist)
        # d/dtheta: face -> s; beyond -> u . (sc n - hw e)
        dth_face = s
        dwx = sc * nrm[j, 0] - p[P_HW] * e[j, 0]
        dwy = sc * nrm[j, 1] - p[P_HW] * e[j, 1]
        dth_end = gx * dwx + gy * dwy
        jac[np.arange(len(ii)), 2 * ii] = gx
        jac[np.arange(len(ii)), 2 * ii + 1] = gy
        jac[:, 2 * n + j] = np.where(inside, dth_face, dth_end)
        rows.append(jac)
    return np.vstack(rows)


def _candidates(x0: np.ndarray, prob: _Scaled) -> list[np.ndarray]:
    n = prob.n
    q = x0[: 2 * n].reshape(n, 2)
    _, nrm = _frames(x0[2 * n :])
    idx = []
    for j in range(2):
        near = q @ nrm[j] < 0.6
        idx.append(np.flatnonzero(near))
    gaps = face_gaps(x0, prob, idx)
    k = 0
    out = []
    for j in range(2):
        m = len(idx[j])
        out.append(idx[j][gaps[k : k + m] > 0])
        k += m
    return out


def _forces(x: np.ndarray, prob: _Scaled, idx: list[np.ndarray], tol: float):
    """Contact forces by NNLS on the active constraints: grad Pi = sum lam grad g."""
    n = prob.n
    g = face_gaps(x, prob, idx)
    jac = face_gap_jacobian(x, prob, idx)
    stop_g = x[2 * n :] - prob.params[P_THMIN]
    active = np.flatnonzero(g < tol)
    stop_active = np.flatnonzero(stop_g < tol)
    cols = [jac[active].T]
    for j in stop_active:
        col = np.zeros(2 * n + 2)
        col[2 * n + j] = 1.0
        cols.append(col[:, None])
    a = np.hstack(cols) if cols else np.zeros((2 * n + 2, 0))
    lam_face = np.zeros((2, n))
    lam_stop = np.zeros(2)
    if a.shape[1]:
        sol, _ = nnls(a, gradient_scaled(x, prob.params, prob.n))
        split = np.concatenate([np.zeros(len(idx[0]), int), np.ones(len(idx[1]), int)])
        pts = np.concatenate(idx)
        for lam, m in zip(sol[: len(active)], active, strict=True):
            lam_face[split[m], pts[m]] = lam
        for lam, j in zip(sol[len(active) :], stop_active, strict=True):
            lam_stop[j] = lam
    return lam_face, lam_stop


def _start(prob: _Scaled) -> np.ndarray:
    x = np.empty(2 * prob.n + 2)
    x[: 2 * prob.n] = rest_points(prob.n, prob.params[P_PHASE]).ravel()
    x[2 * prob.n :] = prob.params[P_TH0]
    return x


def _slsqp(prob: _Scaled, time_limit_s: float):
    x0 = _start(prob)
    idx = _candidates(x0, prob)
    n = prob.n
    t_end = time.perf_counter() + time_limit_s
    scale = max(prob.params[P_TAU], 1e-12)

    def callback(_xk):
        if time.perf_counter() > t_end:
            raise _Timeout

    cons = [
        {"type": "ineq", "fun": lambda x: face_gaps(x, prob, idx),
         "jac": lambda x: face_gap_jacobian(x, prob, idx)},
        {"type": "ineq", "fun": lambda x: x[2 * n :] - prob.params[P_THMIN],
         "jac": lambda x: np.hstack([np.zeros((2, 2 * n)), np.eye(2)])},
    ]
    try:
        res = minimize(
            lambda x: energy_scaled(x, prob.params, prob.n) / scale, x0,
            jac=lambda x: gradient_scaled(x, prob.params, prob.n) / scale, method="SLSQP",
            constraints=cons, callback=callback, options={"maxiter": 2000, "ftol": 1e-14},
        )
        x, ok, msg, nit = res.x, bool(res.success), f"slsqp: {res.message}", int(res.nit)
    except _Timeout:
        return x0, idx, False, f"slsqp: time limit {time_limit_s:g} s reached", -1
    return x, idx, ok, msg, nit


def _nelder_mead(prob: _Scaled, time_limit_s: float):
    x0 = _start(prob)
    idx = _candidates(x0, prob)
    k_pen = 1e4 * max(prob.params[P_KC], prob.params[P_KR])
    scale = max(prob.params[P_TAU], 1e-12)
    t_end = time.perf_counter() + time_limit_s
    count = [0]

    def residual_sq(x):
        count[0] += 1
        g = face_gaps(x, prob, idx)
        pen = np.minimum(g, 0.0)
        r = gradient_scaled(x, prob.params, prob.n)
        r += face_gap_jacobian(x, prob, idx).T @ (k_pen * pen)
        return float(r @ r) / scale**2

    def callback(_xk):
        if time.perf_counter() > t_end:
            raise _Timeout

    try:
        res = minimize(
            residual_sq, x0, method="Nelder-Mead", callback=callback,
            options={"maxfev": 10**9, "maxiter": 10**9, "xatol": 1e-13, "fatol": 1e-22,
                     "adaptive": True},
        )
        x, ok, msg = res.x, bool(res.success), f"nelder-mead: {res.message}"
    except _Timeout:
        return x0, idx, False, f"nelder-mead: time limit {time_limit_s:g} s reached", count[0]
    return x, idx, ok, msg, count[0]


def solve(scene: Scene, torque_nm: float, n_triangles: int, stiffness_rule: str,
          phase_rad: float, method: str, time_limit_s: float, payload_n: float = 0.0,
          load_set: str = "any"):
    """Run a baseline and return its answer as a checked :class:`GraspResult`."""
    cols = scene.columns(torque_nm)
    prm = pack_params(cols, n_triangles, stiffness_rule, phase_rad)
    prob = _Scaled(int(n_triangles), prm[0])
    t0 = time.perf_counter()
    if method == "slsqp":
        x, idx, ok, msg, nit = _slsqp(prob, time_limit_s)
    elif method == "nelder-mead":
        x, idx, ok, msg, nit = _nelder_mead(prob, time_limit_s)
    else:
        raise ValueError(f"baseline method {method!r} is unknown; allowed: slsqp, nelder-mead")
    elapsed = time.perf_counter() - t0
    lam_face, lam_stop = _forces(x, prob, idx, tol=1e-8)
    n = prob.n
    info = np.zeros((1, N_INFO))
    info[0, I_STATUS] = OK if ok else ITER_LIMIT
    info[0, I_ITERATIONS] = nit
    sol = checked_solution(cols.rows(), n, prm, x[None, :], lam_face[None],
                           np.zeros((1, 2, N_CORNERS, n)), lam_stop[None], info, elapsed,
                           np.array([payload_n]), load_set)
    # the baseline's own reason where it gave up; otherwise the pipeline's (check, fold)
    message = None if (ok or sol.folded[0]) else msg
    return grasp_result(sol, 0, torque_nm, method, stiffness_rule, message=message,
                        load_set=load_set)
