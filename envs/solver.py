"""Quasi-static grasp solver: ``simulate``, ``simulate_ramp`` and :class:`GraspResult`.

The grasp at torque ``T_a`` is the stable equilibrium of the point-spring disk squeezed by the two
torque-driven fingers, with frictionless unilateral contact on the whole of each finger bar
(gripping face, ends, back) and its rounded corners. ``method="newton"`` (default) is the
compiled interior-point Newton solver of :mod:`envs.kernels`; ``"slsqp"`` and ``"nelder-mead"``
are the baselines of :mod:`envs.baselines`. Every result is verified by the independent check of
:mod:`envs.kkt`; a result that fails it is returned with ``converged=False`` and the reason in
``message``, and so is an equilibrium with a turned-over fan triangle.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from . import kernels
from .kkt import KKTReport, kkt_check
from .psm import ScaledProblem, rest_points, scaled_problem, spring_strains
from .scene import Scene, check_range

__all__ = ["GraspResult", "simulate", "simulate_ramp", "METHODS", "result_from_scaled"]

METHODS = ("newton", "slsqp", "nelder-mead")
WARM_OPENING_RAD = 1e-3
NESTED_ABOVE = 160  # meshes finer than this start from a coarser solution
NESTED_FACTOR = 4
CONTINUATION_MAX_N = 500  # finer meshes: continuation costs minutes and does not help


@dataclass(frozen=True)
class GraspResult:
    """Equilibrium grasp of the point-spring disk at one actuation torque.

    Attributes
    ----------
    converged : bool
        True when the solver converged *and* the independent KKT check passed.
    message : str
        ``"converged"`` or the reason for failure.
    jaw_angles_rad : tuple[float, float]
        Right and left finger angles from the +y axis [rad].
    points_m : numpy.ndarray
        Deformed contour points [m], shape (N, 2), counter-clockwise from the top.
    contact_mask : numpy.ndarray
        Whether each point touches each finger (gap ~ 0 and positive force), shape (2, N).
    contact_forces_n : numpy.ndarray
        Normal force of each finger on each point [N], shape (2, N) (thickness included).
    peak_strain : float
        Largest ``|L - L0| / L0`` over all springs [-].
    iterations : int
        Newton iterations (all rounds and the polish) or baseline iterations.
    solve_time_s : float
        Time spent in the solver [s] (all attempts; the independent check is not counted).
    torque_nm, n_triangles, method, stiffness_rule
        The problem solved.
    corner_forces_n : numpy.ndarray
        Total force of each rounded corner of each finger on the contour [N], (2, 4); corners
        in the order: tip and root of the gripping face, tip and root of the back of the bar.
    corner_edges : numpy.ndarray
        Edge ``k`` (from point k to k+1) carrying most of each corner's force, -1 for none,
        (2, 4).
    corner_edge_forces_n : numpy.ndarray
        Force of each corner on each contour edge ``k`` [N], (2, 4, N): a corner pressing on a
        vertex bears on both edges that meet there.
    stop_torques_nm : numpy.ndarray
        Reaction torque of the closed-jaw stop of each finger [N·m] (non-zero: jaws closed).
    energy_j : float
        Total potential energy (springs, actuation, torsion springs) [J].
    max_displacement_ratio : float
        Largest contour-point displacement divided by the radius [-].
    stable : bool
        The Newton matrix of the contact-constrained problem was positive definite (a strict
        local minimum, not a saddle).
    kkt : KKTReport
        The independent equilibrium check.
    rounds : int
        Outer rounds updating the contact candidate set.
    inverted_triangles : int
        Fan triangles (centre, point i, point i+1) turned over in the returned state. The
        springs allow such a fold at finite energy; a result with any is reported as not
        converged (the squeeze is beyond the model's valid range). A failed solve can also end
        on a folded iterate: :attr:`folded` tells the two apart.
    """

    converged: bool
    message: str
    jaw_angles_rad: tuple[float, float]
    points_m: np.ndarray
    contact_mask: np.ndarray
    contact_forces_n: np.ndarray
    peak_strain: float
    iterations: int
    solve_time_s: float
    torque_nm: float = 0.0
    n_triangles: int = 0
    method: str = "newton"
    stiffness_rule: str = "van_gelder"
    corner_forces_n: np.ndarray = field(default_factory=lambda: np.zeros((2, 4)))
    corner_edges: np.ndarray = field(default_factory=lambda: -np.ones((2, 4), dtype=int))
    corner_edge_forces_n: np.ndarray = field(default_factory=lambda: np.zeros((2, 4, 0)))
    stop_torques_nm: np.ndarray = field(default_factory=lambda: np.zeros(2))
    energy_j: float = math.nan
    max_displacement_ratio: float = math.nan
    stable: bool = True
    kkt: KKTReport | None = None
    rounds: int = 1
    inverted_triangles: int = 0

    @property
    def folded(self) -> bool:
        """An equilibrium (the independent check passed) with inverted fan triangles.

        The model's own limit, not a solver failure: such a state is never passed off as a
        grasp (``converged`` is False), but unlike a failed solve it is a correct answer.
        """
        return self.inverted_triangles > 0 and self.kkt is not None and self.kkt.passed

    @property
    def n_contacts(self) -> tuple[int, int]:
        """Number of contour points touching the right and left finger faces."""
        return int(self.contact_mask[0].sum()), int(self.contact_mask[1].sum())

    @property
    def contact_fraction(self) -> float:
        """Fraction of contour points touching a finger [-]."""
        return float(self.contact_mask.any(axis=0).mean())

    @property
    def total_force_n(self) -> tuple[float, float]:
        """Total normal force of each finger on the disk (faces and corners) [N]."""
        tot = self.contact_forces_n.sum(axis=1) + self.corner_forces_n.sum(axis=1)
        return float(tot[0]), float(tot[1])

    @property
    def asymmetry_rad(self) -> float:
        """Difference between the right and left jaw angles [rad] (0 for a symmetric grasp)."""
        return float(self.jaw_angles_rad[0] - self.jaw_angles_rad[1])

    @property
    def jaw_gap_angle_rad(self) -> float:
        """Angle between the two fingers [rad] (the paper's Fig. 4 quantity)."""
        return float(self.jaw_angles_rad[0] + self.jaw_angles_rad[1])

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {
            "converged": self.converged,
            "message": self.message,
            "method": self.method,
            "torque_nm": self.torque_nm,
            "n_triangles": self.n_triangles,
            "jaw_angles_rad": list(self.jaw_angles_rad),
            "peak_strain": self.peak_strain,
            "max_displacement_ratio": self.max_displacement_ratio,
            "n_contacts": list(self.n_contacts),
            "total_force_n": list(self.total_force_n),
            "corner_forces_n": self.corner_forces_n.tolist(),
            "stop_torques_nm": self.stop_torques_nm.tolist(),
            "energy_j": self.energy_j,
            "stable": self.stable,
            "iterations": self.iterations,
            "rounds": self.rounds,
            "inverted_triangles": self.inverted_triangles,
            "folded": self.folded,
            "solve_time_s": self.solve_time_s,
            "kkt": self.kkt._asdict() if self.kkt is not None else None,
            "points_m": self.points_m.tolist(),
        }


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise ValueError(f"method {method!r} is unknown; allowed: {METHODS}")
    return method


def rest_state(prob: ScaledProblem) -> np.ndarray:
    """Scaled start vector: undeformed contour and fingers at their rest angle."""
    x = np.empty(2 * prob.n + 2)
    x[: 2 * prob.n] = rest_points(prob.n, prob.params[kernels.P_PHASE]).ravel()
    x[2 * prob.n :] = prob.params[kernels.P_TH0]
    return x


def result_from_scaled(
    scene: Scene,
    prob: ScaledProblem,
    torque_nm: float,
    x: np.ndarray,
    lam_face: np.ndarray,
    lam_corner: np.ndarray,
    lam_stop: np.ndarray,
    solver_ok: bool,
    message: str,
    iterations: int,
    solve_time_s: float,
    method: str,
    stiffness_rule: str,
    stable: bool = True,
    rounds: int = 1,
) -> GraspResult:
    """Convert a scaled solution to a :class:`GraspResult` and run the independent check.

    ``solver_ok`` means the solver claims an equilibrium (a fold included); ``converged`` is set
    only if the check confirms it and no fan triangle is turned over.
    """
    from .psm import energy_scaled

    n, r = prob.n, prob.length_m
    q = x[: 2 * n].reshape(n, 2)
    points = scene.disk.center_m + r * q
    angles = (float(x[2 * n]), float(x[2 * n + 1]))
    face = np.asarray(lam_face, dtype=float) * prob.force_n
    corner = np.asarray(lam_corner, dtype=float).reshape(2, 4, n) * prob.force_n
    stop = np.asarray(lam_stop, dtype=float) * prob.torque_nm
    report = kkt_check(scene, torque_nm, n, stiffness_rule, points, angles, face, corner, stop)
    corner_total = corner.sum(axis=2)
    edges = np.where(corner_total > 0.0, np.argmax(corner, axis=2), -1)
    radial, contour = spring_strains(q, prob.rest_contour)
    peak = float(max(np.max(np.abs(radial)), np.max(np.abs(contour))))
    rest = rest_points(n, prob.params[kernels.P_PHASE])
    disp = float(np.max(np.linalg.norm(q - rest, axis=1)))
    mask = face > 0.0
    inverted = int(np.count_nonzero(
        q[:, 0] * np.roll(q[:, 1], -1) - q[:, 1] * np.roll(q[:, 0], -1) <= 0.0))
    converged = bool(solver_ok and report.passed and inverted == 0)
    if solver_ok and not report.passed:
        message = f"independent KKT check failed: {report.reason}"
    elif inverted and report.passed:
        # a fold the check confirms is reported as such, even where the solver stopped short of
        # its own (tighter) tolerance: the check has the final say
        message = kernels.STATUS_MESSAGES[kernels.INVERTED]
    return GraspResult(
        converged=converged,
        message=message,
        jaw_angles_rad=angles,
        points_m=points,
        contact_mask=mask,
        contact_forces_n=face,
        peak_strain=peak,
        iterations=int(iterations),
        solve_time_s=float(solve_time_s),
        torque_nm=float(torque_nm),
        n_triangles=n,
        method=method,
        stiffness_rule=stiffness_rule,
        corner_forces_n=corner_total,
        corner_edges=edges,
        corner_edge_forces_n=corner,
        stop_torques_nm=stop,
        energy_j=energy_scaled(x, prob) * prob.torque_nm,
        max_displacement_ratio=disp,
        stable=bool(stable),
        kkt=report,
        rounds=int(rounds),
        inverted_triangles=inverted,
    )


def _newton(
    scene: Scene,
    prob: ScaledProblem,
    torque_nm: float,
    stiffness_rule: str,
    x0: np.ndarray,
    lam0: np.ndarray | None,
    options: np.ndarray,
) -> GraspResult:
    n = prob.n
    x = x0.copy()
    lam_face = np.zeros((2, n)) if lam0 is None else lam0.copy()
    lam_corner = np.zeros((2, 4, n))
    lam_stop = np.zeros(2)
    corner_cand = np.zeros((2, 4, n), dtype=np.bool_)
    cand = np.zeros((2, n), dtype=np.bool_)
    info = np.zeros(8)
    t0 = time.perf_counter()
    kernels.solve_one(n, prob.params, options, x, lam_face, lam_corner, lam_stop, corner_cand,
                      cand, info)
    elapsed = time.perf_counter() - t0
    status = int(info[0])
    return result_from_scaled(
        # a fold is the kernel's answer too (an equilibrium): the check has the final say
        scene, prob, torque_nm, x, lam_face, lam_corner, lam_stop,
        status in (kernels.OK, kernels.INVERTED),
        kernels.STATUS_MESSAGES[status], int(info[1]), elapsed, "newton", stiffness_rule,
        stable=bool(info[3]), rounds=int(info[2]),
    )


def _prolong(
    scene: Scene, coarse: GraspResult, prob: ScaledProblem
) -> tuple[np.ndarray, np.ndarray]:
    """Fine-mesh start from a coarse solution: points on the coarse chords, forces spread."""
    n, nc, r = prob.n, coarse.n_triangles, prob.length_m
    qc = (coarse.points_m - scene.disk.center_m) / r
    u = np.arange(n) * nc / n
    k = np.floor(u).astype(int) % nc
    k1 = (k + 1) % nc
    t = (u - np.floor(u))[:, None]
    x = np.empty(2 * n + 2)
    x[: 2 * n] = ((1 - t) * qc[k] + t * qc[k1]).ravel()
    x[2 * n :] = np.asarray(coarse.jaw_angles_rad) + WARM_OPENING_RAD
    lam_c = coarse.contact_forces_n / prob.force_n
    lam = ((1 - t.T) * lam_c[:, k] + t.T * lam_c[:, k1]) * nc / n
    return x, lam


def _solve_newton(
    scene: Scene, prob: ScaledProblem, torque_nm: float, stiffness_rule: str, phase_rad: float
) -> GraspResult:
    """Newton solve from rest; fine meshes start from a coarser solution (nested iteration).

    A solve that fails is retried by continuation: the torque is ramped from zero with
    adaptive steps, each started from the previous equilibrium.
    """
    options = kernels.default_options()
    spent = 0.0  # compiled-solver time of every attempt (the KKT checks are not counted)
    if prob.n <= NESTED_ABOVE:
        res = _newton(scene, prob, torque_nm, stiffness_rule, rest_state(prob), None, options)
        extra = 0
    else:
        nc = max(NESTED_ABOVE // 2, prob.n // NESTED_FACTOR)
        coarse_prob = scaled_problem(scene, torque_nm, nc, stiffness_rule, phase_rad)
        coarse = _solve_newton(scene, coarse_prob, torque_nm, stiffness_rule, phase_rad)
        extra, spent = coarse.iterations, coarse.solve_time_s
        res = None
        if coarse.converged:
            x0, lam0 = _prolong(scene, coarse, prob)
            res = _newton(scene, prob, torque_nm, stiffness_rule, x0, lam0, options)
        if res is None or not res.converged:
            if res is not None:
                spent += res.solve_time_s
            res = _newton(scene, prob, torque_nm, stiffness_rule, rest_state(prob), None, options)
    # no continuation after a fold, nor after a failed solve that ended on a folded iterate:
    # measured on the solver sweep, continuation rescued none of the latter (N = 200 - 500)
    # and cost up to 10 s each
    if (not res.converged and torque_nm > 0 and prob.n <= CONTINUATION_MAX_N
            and res.inverted_triangles == 0):
        failed = res
        spent += failed.solve_time_s
        res = _continuation(scene, prob.n, torque_nm, stiffness_rule, phase_rad, options)
        extra += failed.iterations
        if not res.converged:
            res = replace(res, message=f"{failed.message}; continuation: {res.message}")
    return replace(res, solve_time_s=spent + res.solve_time_s, iterations=res.iterations + extra)


def _continuation(
    scene: Scene, n: int, torque_nm: float, stiffness_rule: str, phase_rad: float,
    options: np.ndarray, first_step: float = 0.125, min_step: float = 1e-4,
) -> GraspResult:
    """Ramp the torque from 0 to ``torque_nm`` with adaptive steps and warm starts."""
    done, step = 0.0, first_step * torque_nm
    prev: GraspResult | None = None
    iterations = 0
    spent = 0.0
    last = None
    while done < torque_nm:
        t = min(torque_nm, done + step)
        prob = scaled_problem(scene, t, n, stiffness_rule, phase_rad)
        if prev is None:
            x0, lam0 = rest_state(prob), None
        else:
            x0, lam0 = _warm_start(scene, prob, prev)
        last = _newton(scene, prob, t, stiffness_rule, x0, lam0, options)
        iterations += last.iterations
        spent += last.solve_time_s
        if last.converged:
            prev, done, step = last, t, step * 1.5
        else:
            step /= 4.0
            if step < min_step * torque_nm:
                return replace(last, message=f"failed at T = {t:.4g} N·m: {last.message}",
                               iterations=iterations, solve_time_s=spent)
    return replace(last, iterations=iterations, solve_time_s=spent)


def simulate(
    scene: Scene,
    torque_nm: float,
    n_triangles: int = 20,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    phase_rad: float = math.pi / 2,
    time_limit_s: float = 30.0,
) -> GraspResult:
    """Solve the grasp at one actuation torque, starting from the rest configuration.

    Parameters
    ----------
    scene
        Gripper and disk.
    torque_nm
        Actuation torque ``T_a`` applied on each finger [N·m], >= 0.
    n_triangles
        Number of fan triangles ``N`` (4 to 20000).
    method
        ``"newton"`` (default), ``"slsqp"`` or ``"nelder-mead"``.
    stiffness_rule
        ``"van_gelder"`` (default) or ``"cst_fit"``.
    phase_rad
        Angle of the first contour point [rad]; pi/2 (top) is mirror-symmetric for even N.
    time_limit_s
        Wall-time budget for the baselines [s] (the Newton solver needs none).

    Returns
    -------
    GraspResult
        ``converged`` is False, with the reason in ``message``, when the solver failed or the
        independent KKT check rejected its answer.
    """
    _check_method(method)
    check_range("time_limit_s", time_limit_s, 0.0, math.inf, low_open=True)
    prob = scaled_problem(scene, torque_nm, n_triangles, stiffness_rule, phase_rad)
    if method == "newton":
        return _solve_newton(scene, prob, torque_nm, stiffness_rule, phase_rad)
    from . import baselines

    return baselines.solve(scene, prob, torque_nm, stiffness_rule, method, time_limit_s)


def simulate_ramp(
    scene: Scene,
    torques_nm,
    n_triangles: int = 20,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    phase_rad: float = math.pi / 2,
    time_limit_s: float = 30.0,
) -> list[GraspResult]:
    """Follow the grasp along an increasing torque ramp (the paper's Fig. 4 curve).

    Each step starts from the previous equilibrium with the fingers opened by a small angle
    (so that the start is strictly inside the contact constraints), which follows the branch of
    equilibria the ramp reaches. A step whose warm start fails is retried from rest.

    Parameters
    ----------
    torques_nm
        Non-decreasing actuation torques [N·m].
    Other parameters
        As in :func:`simulate`.
    """
    _check_method(method)
    torques = np.asarray(torques_nm, dtype=float).ravel()
    if torques.size == 0:
        raise ValueError("torques_nm must contain at least one torque")
    for t in torques:
        check_range("torques_nm[i]", t, 0.0, math.inf)
    if np.any(np.diff(torques) < 0):
        raise ValueError("torques_nm must be non-decreasing (a loading ramp)")
    if method != "newton":
        return [
            simulate(scene, t, n_triangles, method, stiffness_rule=stiffness_rule,
                     phase_rad=phase_rad, time_limit_s=time_limit_s)
            for t in torques
        ]
    options = kernels.default_options()
    out: list[GraspResult] = []
    prev: GraspResult | None = None
    for t in torques:
        prob = scaled_problem(scene, t, n_triangles, stiffness_rule, phase_rad)
        res = None
        if prev is not None and prev.converged:
            x0, lam0 = _warm_start(scene, prob, prev)
            res = _newton(scene, prob, t, stiffness_rule, x0, lam0, options)
        if res is None or not res.converged:
            res = _solve_newton(scene, prob, t, stiffness_rule, phase_rad)
        out.append(res)
        prev = res
    return out


def _warm_start(
    scene: Scene, prob: ScaledProblem, prev: GraspResult
) -> tuple[np.ndarray, np.ndarray]:
    n, r = prob.n, prob.length_m
    x = np.empty(2 * n + 2)
    x[: 2 * n] = ((prev.points_m - scene.disk.center_m) / r).ravel()
    # open the fingers slightly so that every contact gap is strictly positive
    x[2 * n :] = np.asarray(prev.jaw_angles_rad) + WARM_OPENING_RAD
    return x, prev.contact_forces_n / prob.force_n
