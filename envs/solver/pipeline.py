"""The one batch pipeline: scenes in, checked grasps out.

``simulate``, ``simulate_ramp``, ``evaluate_designs`` (and through it the environments, the
optimizers, rendering and charts) all solve through :func:`solve_columns`:

1. pack the scenes (:func:`envs.model.problem.pack_params`);
2. solve every row with the compiled interior point (:func:`envs.solver.driver.solve_batch`,
   rows in parallel threads; one row without the thread pool);
3. measure each state (:func:`envs.model.metrics.state_metrics_batch`);
4. check each answer independently (:func:`envs.check.check_batch`), in SI units;
5. give each row one public status: ``converged`` means the solver claimed an equilibrium, the
   check confirmed it and no fan triangle is turned over.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numba
import numpy as np

from envs import check
from envs.model.layout import (
    I_ITERATIONS,
    I_ROUNDS,
    I_STABLE,
    I_STATUS,
    N_CORNERS,
    N_INFO,
    P_KC,
    P_KR,
    P_RHO,
    default_options,
)
from envs.model.metrics import (
    M_DISPLACEMENT,
    M_ENERGY,
    M_INVERTED,
    M_PEAK_STRAIN,
    N_METRICS,
    state_metrics,
    state_metrics_batch,
)
from envs.model.problem import SceneColumns, pack_params, rest_state, units

from . import driver
from .status import BLOCKED, CHECK_FAILED, INVERTED, LINESEARCH_FAIL, OK, STATUS_MESSAGES

__all__ = ["BatchSolution", "solve_columns", "checked_solution", "row_message"]


class BatchSolution(NamedTuple):
    """Checked grasps of B scenes (first axis), SI units unless named ``_scaled``."""

    status: np.ndarray  # (B,) public status (envs.solver.status)
    converged: np.ndarray  # (B,) bool
    folded: np.ndarray  # (B,) bool: a checked equilibrium with turned-over fan triangles
    iterations: np.ndarray  # (B,) Newton iterations
    rounds: np.ndarray  # (B,) outer rounds
    stable: np.ndarray  # (B,) bool: strict local minimum
    jaw_angles_rad: np.ndarray  # (B, 2)
    points_m: np.ndarray  # (B, N, 2)
    face_forces_n: np.ndarray  # (B, 2, N)
    corner_forces_n: np.ndarray  # (B, 2, 4, N)
    stop_torques_nm: np.ndarray  # (B, 2)
    peak_strain: np.ndarray  # (B,)
    max_displacement_ratio: np.ndarray  # (B,)
    energy_j: np.ndarray  # (B,)
    inverted: np.ndarray  # (B,) int
    check: np.ndarray  # (B, check.N_OUT): the independent check's verdict
    state_scaled: np.ndarray  # (B, 2N + 2) solver state (warm starts)
    face_scaled: np.ndarray  # (B, 2, N) scaled face multipliers (warm starts)
    solve_time_s: float  # compiled solve time of the whole batch


def _solve(n: int, prm: np.ndarray, xs: np.ndarray, lam_face: np.ndarray):
    """Run the compiled solver in place; returns the info rows and the corner/stop forces."""
    b = prm.shape[0]
    lam_corner = np.zeros((b, 2, N_CORNERS, n))
    lam_stop = np.zeros((b, 2))
    corner_cand = np.zeros((b, 2, N_CORNERS, n), dtype=np.bool_)
    face_cand = np.zeros((b, 2, n), dtype=np.bool_)
    infos = np.zeros((b, N_INFO))
    opts = default_options()
    if b == 1:
        # one row needs no thread pool (and stays fork-safe in process-based vector envs)
        driver.solve_one(n, prm[0], opts, xs[0], lam_face[0], lam_corner[0], lam_stop[0],
                         corner_cand[0], face_cand[0], infos[0])
    else:
        # dynamic scheduling, one row at a time: solve times vary by 100x between rows (a row
        # hitting the iteration limit), so static blocks would leave threads idle
        with numba.parallel_chunksize(1):
            driver.solve_batch(n, prm, opts, xs, lam_face, lam_corner, lam_stop, corner_cand,
                               face_cand, infos)
    return infos, lam_corner, lam_stop


def _metrics(n: int, prm: np.ndarray, xs: np.ndarray) -> np.ndarray:
    out = np.zeros((prm.shape[0], N_METRICS))
    if prm.shape[0] == 1:
        state_metrics(xs[0], n, prm[0], out[0])
    else:
        state_metrics_batch(xs, n, prm, out)
    return out


def _check_rows(cols: SceneColumns, prm: np.ndarray, n: int, force_unit: np.ndarray
                ) -> np.ndarray:
    """Parameter rows of the independent check (its own closed-jaw angle)."""
    r = cols.radius_m
    k_unit = force_unit / r
    ck = np.zeros((cols.size, check.N_CK))
    ck[:, check.CK_RADIUS] = r
    ck[:, check.CK_CENTRE_Y] = cols.distance_m + r
    ck[:, check.CK_JOINT_OFFSET] = cols.joint_offset_m
    ck[:, check.CK_LENGTH] = cols.finger_length_m
    ck[:, check.CK_HALF_WIDTH] = cols.finger_width_m / 2
    ck[:, check.CK_RHO] = prm[:, P_RHO] * r
    ck[:, check.CK_KF] = cols.torsion_stiffness_nm_per_rad
    ck[:, check.CK_TH0] = cols.rest_angle_rad
    ck[:, check.CK_THMIN] = [
        check._closed_angle(d3, ln, hw) for d3, ln, hw in zip(
            cols.joint_offset_m.tolist(), cols.finger_length_m.tolist(),
            (cols.finger_width_m / 2).tolist(), strict=True)]
    ck[:, check.CK_TORQUE] = cols.torque_nm
    ck[:, check.CK_KINT] = prm[:, P_KR] * k_unit
    ck[:, check.CK_KEXT] = prm[:, P_KC] * k_unit
    ck[:, check.CK_REST_CONTOUR] = 2 * r * np.sin(np.pi / n)
    return ck


def _run_check(ck, points, angles, face, corner, stop) -> np.ndarray:
    out = np.zeros((ck.shape[0], check.N_OUT))
    if ck.shape[0] == 1:
        check.check_one(ck[0], points[0], angles[0], face[0], corner[0], stop[0], out[0])
    else:
        check.check_batch(ck, points, angles, face, corner, stop, out)
    return out


def _public_status(raw: np.ndarray, passed: np.ndarray, inverted: np.ndarray) -> np.ndarray:
    """One public status per row: the check and the fold count have the final say."""
    status = np.where(raw == BLOCKED, LINESEARCH_FAIL, raw)
    claimed = (raw == OK) | (raw == INVERTED)
    status = np.where(claimed & ~passed, CHECK_FAILED, status)
    # a fold the check confirms is reported as such, even where the solver stopped short of
    # its own (tighter) tolerance
    status = np.where((inverted > 0) & passed, INVERTED, status)
    return np.where(claimed & passed & (inverted == 0), OK, status)


def solve_columns(cols: SceneColumns, n_triangles: int, *, stiffness_rule: str = "van_gelder",
                  phase_rad: float, x0: np.ndarray | None = None,
                  lam0: np.ndarray | None = None) -> BatchSolution:
    """Solve and check the grasps of B valid scenes with N fan triangles.

    Parameters
    ----------
    cols
        The scenes and torques (valid at rest, see :func:`envs.model.problem.rest_codes`).
    n_triangles
        Number of fan triangles ``N``.
    stiffness_rule, phase_rad
        As in :func:`envs.simulate`.
    x0, lam0
        Scaled start states (B, 2N + 2) and face multipliers (B, 2, N) of a warm start
        (default: rest, no multipliers). The start must be strictly feasible.
    """
    n = int(n_triangles)
    prm = pack_params(cols, n, stiffness_rule, phase_rad)
    xs = rest_state(prm, n) if x0 is None else np.array(x0, dtype=np.float64, ndmin=2)
    lam_face = (np.zeros((cols.size, 2, n)) if lam0 is None
                else np.array(lam0, dtype=np.float64, ndmin=3))
    t0 = time.perf_counter()
    infos, lam_corner, lam_stop = _solve(n, prm, xs, lam_face)
    elapsed = time.perf_counter() - t0
    return checked_solution(cols, n, prm, xs, lam_face, lam_corner, lam_stop, infos, elapsed)


def checked_solution(cols: SceneColumns, n: int, prm: np.ndarray, xs: np.ndarray,
                     lam_face: np.ndarray, lam_corner: np.ndarray, lam_stop: np.ndarray,
                     infos: np.ndarray, elapsed: float) -> BatchSolution:
    """Measure, convert to SI, check and give a public status to solver answers.

    Parameters
    ----------
    cols, n, prm
        The scenes, N and their packed parameters.
    xs, lam_face, lam_corner, lam_stop
        Scaled states (B, 2N + 2) and multipliers: face (B, 2, N), corner (B, 2, 4, N), joint
        stop (B, 2).
    infos
        Solver info rows (B, N_INFO) (layout ``I_*``): its claim in ``I_STATUS``.
    elapsed
        Solver time of the batch [s].
    """
    metrics = _metrics(n, prm, xs)
    r, force_unit, torque_unit = units(cols)
    points = xs[:, : 2 * n].reshape(-1, n, 2) * r[:, None, None]
    points[:, :, 1] += (cols.distance_m + r)[:, None]
    face = lam_face * force_unit[:, None, None]
    corner = lam_corner * force_unit[:, None, None, None]
    stop = lam_stop * torque_unit[:, None]
    angles = xs[:, 2 * n :].copy()
    verdict = _run_check(_check_rows(cols, prm, n, force_unit), points, angles, face, corner,
                         stop)
    passed = verdict[:, check.OUT_PASSED] > 0.0
    inverted = metrics[:, M_INVERTED].astype(np.int64)
    status = _public_status(infos[:, I_STATUS].astype(np.int64), passed, inverted)
    return BatchSolution(
        status=status, converged=status == OK, folded=(inverted > 0) & passed,
        iterations=infos[:, I_ITERATIONS].astype(np.int64),
        rounds=infos[:, I_ROUNDS].astype(np.int64), stable=infos[:, I_STABLE] != 0.0,
        jaw_angles_rad=angles, points_m=points, face_forces_n=face, corner_forces_n=corner,
        stop_torques_nm=stop, peak_strain=metrics[:, M_PEAK_STRAIN],
        max_displacement_ratio=metrics[:, M_DISPLACEMENT],
        energy_j=metrics[:, M_ENERGY] * torque_unit, inverted=inverted, check=verdict,
        state_scaled=xs, face_scaled=lam_face, solve_time_s=elapsed,
    )


def row_message(sol: BatchSolution, i: int) -> str:
    """The human-readable outcome of row ``i``."""
    status = int(sol.status[i])
    if status == CHECK_FAILED:
        return f"independent KKT check failed: {check.report_from_output(sol.check[i]).reason}"
    return STATUS_MESSAGES[status]
