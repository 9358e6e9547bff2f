"""Quasi-static grasp solver front end: :func:`simulate` and :func:`simulate_ramp`.

The grasp at torque ``T_a`` is the stable equilibrium of the point-spring disk squeezed by the
two torque-driven fingers, with frictionless unilateral contact on the whole of each finger bar
(gripping face, ends, back) and its rounded corners. ``method="newton"`` (default) solves
through the one batch pipeline (:mod:`envs.solver.pipeline`); ``"slsqp"`` and ``"nelder-mead"``
are the baselines of :mod:`envs.solver.baselines`. Every result is verified by the independent
check of :mod:`envs.check`; a result that fails it is returned with ``converged=False`` and the
reason in ``message``, and so is an equilibrium with a turned-over fan triangle.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from envs.model.defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_PAYLOAD_FACTOR,
    DEFAULT_PHASE_RAD,
    STIFFNESS_RULES,
)
from envs.model.family import ModelSpec, resolve_model
from envs.model.layout import S_SCALE
from envs.model.loads import DEFAULT_LOAD_SET, load_set_code
from envs.model.problem import pack_params, rest_state, stiffness_unit
from envs.scene import Scene
from envs.validation import check_choice, check_range

from .pipeline import BatchSolution, grasp_result, solve_columns
from .result import GraspResult

__all__ = ["METHODS", "simulate", "simulate_ramp", "check_model"]

METHODS = ("newton", "slsqp", "nelder-mead")
WARM_OPENING_RAD = 1e-3
# A prolonged coarse solution's contacts are close to the fine ones: a small opening keeps the
# barrier parameter (set from the start's complementarity) small. Measured (nh-quad, M = 2,
# paper-r070, 0.2 N·m): the N = 1000 solve from N = 250 takes 9 iterations instead of 13 at
# the warm starts' opening, and 18 from rest.
PROLONG_OPENING_RAD = 1e-6
NESTED_ABOVE = 160  # meshes finer than this start from a coarser solution
NESTED_FACTOR = 4
# the baselines' wall-time budget at most (they take seconds; a larger one is a typo)
MAX_TIME_LIMIT_S = 3600.0
CONTINUATION_MAX_N = 500  # finer meshes: continuation costs minutes and does not help
# turned rest starts: these fractions of a point spacing about the pin, in turn (the smaller one
# measured: N = 4, M = 4 on paper-r100 at 5.675 N·m converges from 1/8, not from 1/4)
TURNED_STARTS = (0.25, 0.125)


class _Problem:
    """One scene at one torque and mesh, solved through the pipeline (newton)."""

    def __init__(self, scene: Scene, torque_nm: float, n: int, rule: str, phase_rad: float,
                 m: int = 1, element: str = "spring", model_scale: float = 1.0,
                 payload_n: float = 0.0, load_set: str = DEFAULT_LOAD_SET):
        self.scene, self.torque_nm, self.n, self.rule, self.phase, self.m = (
            scene, float(torque_nm), int(n), rule, float(phase_rad), int(m))
        self.element, self.model_scale = element, float(model_scale)
        self.payload_n = float(payload_n)
        self.load_set = load_set
        self.rows = scene.rows(self.torque_nm)
        # the member's shipped calibration: a factor on the disk's stiffness scale
        self.rows[:, S_SCALE] *= self.model_scale

    def at(self, torque_nm: float, n: int | None = None) -> _Problem:
        return _Problem(self.scene, torque_nm, self.n if n is None else n, self.rule,
                        self.phase, self.m, self.element, self.model_scale, self.payload_n,
                        self.load_set)

    def solve(self, x0: np.ndarray | None = None, lam0: np.ndarray | None = None
              ) -> tuple[GraspResult, BatchSolution]:
        sol = solve_columns(self.rows, self.n, stiffness_rule=self.rule, phase_rad=self.phase,
                            x0=x0, lam0=lam0, n_rings=self.m, element=self.element,
                            payload_n=np.array([self.payload_n]), load_set=self.load_set)
        return grasp_result(sol, 0, self.torque_nm, "newton", self.rule,
                            element=self.element, model_scale=self.model_scale,
                            load_set=self.load_set), sol


def _warm_start(prob: _Problem, prev: GraspResult) -> tuple[np.ndarray, np.ndarray]:
    """Start from a previous equilibrium, fingers opened slightly (every gap strictly
    positive)."""
    n, r = prob.n, prob.scene.disk.radius_m
    centre = prob.scene.disk.center_m
    x = np.empty(2 * n * prob.m + 2)
    x[: 2 * n] = ((prev.points_m - centre) / r).ravel()
    x[2 * n : 2 * n + 2] = np.asarray(prev.jaw_angles_rad) + WARM_OPENING_RAD
    x[2 * n + 2 :] = ((prev.interior_points_m - centre) / r).ravel()
    return x, _scaled_forces(prob, prev)


def _scaled_forces(prob: _Problem, res: GraspResult) -> np.ndarray:
    """The face contact forces of ``res`` in the solver's units (a warm start's multipliers)."""
    return res.contact_forces_n / (stiffness_unit(prob.rows[0]) * prob.scene.disk.radius_m)


def _prolong(prob: _Problem, coarse: GraspResult) -> tuple[np.ndarray, np.ndarray]:
    """Fine-mesh start from a coarse solution of the same rings: every ring's points on the
    coarse ring's chords (a ring mesh's points of one angle share its rest direction, so each
    ring is interpolated like the contour), forces spread."""
    n, nc, r = prob.n, coarse.n_triangles, prob.scene.disk.radius_m
    centre = prob.scene.disk.center_m
    u = np.arange(n) * nc / n
    k = np.floor(u).astype(int) % nc
    k1 = (k + 1) % nc
    t = (u - np.floor(u))[:, None]

    def on_chords(points_m: np.ndarray) -> np.ndarray:
        qc = (points_m - centre) / r
        return ((1 - t) * qc[k] + t * qc[k1]).ravel()

    x = np.empty(2 * n * prob.m + 2)
    x[: 2 * n] = on_chords(coarse.points_m)
    x[2 * n : 2 * n + 2] = np.asarray(coarse.jaw_angles_rad) + PROLONG_OPENING_RAD
    rings = coarse.interior_points_m.reshape(prob.m - 1, nc, 2)  # ring by ring, by angle
    for ring, points_m in enumerate(rings):
        x[2 * n + 2 + 2 * n * ring : 2 * n + 2 + 2 * n * (ring + 1)] = on_chords(points_m)
    lam_c = _scaled_forces(prob, coarse)
    lam = ((1 - t.T) * lam_c[:, k] + t.T * lam_c[:, k1]) * nc / n
    return x, lam


def _turned(prob: _Problem, x: np.ndarray, turn_spacings: float) -> np.ndarray:
    """The scaled state ``x`` turned rigidly about the pin by ``turn_spacings`` point
    spacings (signed: counter-clockwise positive); the fingers stay where they are.

    A start off the mirror plane, on one side of a symmetric saddle that a start on it may not
    leave (a 4-point disk squeezed on two corners turns past about 1 N·m to lay a side on each
    finger; the solver's escapes from the deformed saddle fall back to it). The turn costs no
    energy for the paper's fan and a little for a ring mesh, whose hub stays fixed.
    """
    angle = turn_spacings * 2.0 * math.pi / prob.n
    turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    out = x.copy()
    for part in (slice(0, 2 * prob.n), slice(2 * prob.n + 2, None)):  # contour, interior
        out[part] = (x[part].reshape(-1, 2) @ turn.T).ravel()
    return out


def _rest(prob: _Problem) -> np.ndarray:
    """The scaled rest state of the problem's mesh (fingers open)."""
    prm = pack_params(prob.rows, prob.n, prob.rule, prob.phase, prob.m, prob.element)
    return rest_state(prm, prob.n)[0]


def _from_turned_rests(prob: _Problem, accept) -> tuple[GraspResult | None, int, float]:
    """Solve from the rest shape turned a little about the pin (each of
    :data:`TURNED_STARTS`, one sense then the other) until ``accept(result)``; returns that
    result (or None) and the iterations and compiled time of the attempts it did not take."""
    rest = _rest(prob)
    iterations, spent = 0, 0.0
    for turn in (sense * size for size in TURNED_STARTS for sense in (1.0, -1.0)):
        turned, _ = prob.solve(_turned(prob, rest, turn), np.zeros((2, prob.n)))
        if accept(turned):
            return turned, iterations, spent
        iterations += turned.iterations
        spent += turned.solve_time_s
    return None, iterations, spent


def _leave_unstable(prob: _Problem, res: GraspResult) -> GraspResult:
    """In place of the unstable equilibrium ``res``: the stable one reached from the rest shape
    turned a little about the pin (either sense), or ``res`` if neither start reaches one.

    (The deformed equilibrium itself turned does not fit between the fingers.) The iterations
    and solve time of every attempt are counted.
    """
    found, iterations, spent = _from_turned_rests(prob, lambda r: r.converged and r.stable)
    iterations += res.iterations
    spent += res.solve_time_s
    answer = res if found is None else found
    if found is not None:
        iterations += found.iterations
        spent += found.solve_time_s
    return replace(answer, iterations=iterations, solve_time_s=spent)


def _solve_newton(prob: _Problem) -> GraspResult:
    """Newton solve from rest; fine meshes start from a coarser solution (nested iteration).

    A solve that fails is retried from the rest shape turned a little about the pin, either
    sense (:func:`_turned`), then by continuation: the torque is ramped from zero with
    adaptive steps, each started from the previous equilibrium.
    """
    spent = 0.0  # compiled-solver time of every attempt (the checks are not counted)
    if prob.n <= NESTED_ABOVE:
        res, _ = prob.solve()
        extra = 0
    else:
        nc = max(NESTED_ABOVE // 2, prob.n // NESTED_FACTOR)
        coarse = _solve_newton(prob.at(prob.torque_nm, nc))
        extra, spent = coarse.iterations, coarse.solve_time_s
        res = None
        if coarse.converged:
            res, _ = prob.solve(*_prolong(prob, coarse))
        if res is None or not res.converged:
            if res is not None:
                spent += res.solve_time_s
            res, _ = prob.solve()
    # no retry after a fold, nor after a failed solve that ended on a folded iterate:
    # measured on the solver sweep, continuation rescued none of the latter (N = 200 - 500)
    # and cost up to 10 s each
    retry = (not res.converged and prob.torque_nm > 0 and res.inverted_triangles == 0
             and prob.n <= CONTINUATION_MAX_N)
    if retry:
        # two solves from turned rest shapes cost less than a continuation ramp
        found, its, secs = _from_turned_rests(prob, lambda r: r.converged)
        extra += its
        spent += secs
        if found is not None:
            extra += res.iterations
            spent += res.solve_time_s
            res = found
    if not res.converged and retry:
        failed = res
        spent += failed.solve_time_s
        res = _continuation(prob)
        extra += failed.iterations
        if not res.converged:
            res = replace(res, message=f"{failed.message}; continuation: {res.message}")
    if spent == 0.0 and extra == 0:
        return res  # the usual case: one solve from rest (a replace costs tens of us)
    return replace(res, solve_time_s=spent + res.solve_time_s, iterations=res.iterations + extra)


def _continuation(prob: _Problem, first_step: float = 0.125, min_step: float = 1e-4
                  ) -> GraspResult:
    """Ramp the torque from 0 to the problem's torque with adaptive steps and warm starts."""
    torque = prob.torque_nm
    done, step = 0.0, first_step * torque
    prev: GraspResult | None = None
    iterations = 0
    spent = 0.0
    last = None
    while done < torque:
        t = min(torque, done + step)
        sub = prob.at(t)
        last, _ = sub.solve() if prev is None else sub.solve(*_warm_start(sub, prev))
        iterations += last.iterations
        spent += last.solve_time_s
        if last.converged:
            prev, done, step = last, t, step * 1.5
        else:
            step /= 4.0
            if step < min_step * torque:
                return replace(last, message=f"failed at T = {t:.4g} N·m: {last.message}",
                               iterations=iterations, solve_time_s=spent)
    return replace(last, iterations=iterations, solve_time_s=spent)


#: Validation of a member of the model family (:func:`envs.model.family.resolve_model`).
check_model = resolve_model


def _check_inputs(scene, n_triangles, method, stiffness_rule, phase_rad, time_limit_s,
                  n_rings, element, calibrated) -> ModelSpec:
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be an envs.Scene, got {type(scene).__name__}")
    check_choice("method", method, METHODS)
    check_choice("stiffness_rule", stiffness_rule, STIFFNESS_RULES)
    check_range("phase_rad", phase_rad, -2.0 * math.pi, 2.0 * math.pi)
    check_range("time_limit_s", time_limit_s, 0.0, MAX_TIME_LIMIT_S, low_open=True)
    if element is None:
        # the baselines solve the paper's fan; Newton the default model
        element = DEFAULT_ELEMENT if method == "newton" else "spring"
    spec = resolve_model(n_triangles, n_rings, element, calibrated)
    m, element = spec.n_rings, spec.element
    if (m > 1 or element != "spring") and method != "newton":
        raise ValueError(f"n_rings = {m} and element = {element!r} need method = 'newton' (the "
                         f"baselines solve the paper's spring fan: element = 'spring'), got "
                         f"method = {method!r}")
    if m > 1 and stiffness_rule != "van_gelder":
        raise ValueError(f"n_rings = {m} needs stiffness_rule = 'van_gelder', got "
                         f"{stiffness_rule!r}")
    if method != "newton" and any(jaw.depth_m > 0.0 for jaw in scene.gripper.jaws):
        # the baselines' gaps are the straight bar's: a groove would be ignored
        raise ValueError(f"a grooved jaw (depth_m > 0) needs method = 'newton' (the baselines "
                         f"model straight jaws only), got method = {method!r}")
    return spec


def simulate(
    scene: Scene,
    torque_nm: float,
    n_triangles: int | None = None,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    phase_rad: float = DEFAULT_PHASE_RAD,
    time_limit_s: float = 30.0,
    n_rings: int | None = None,
    element: str | None = None,
    calibrated: bool | None = None,
    payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
    load_set: str = DEFAULT_LOAD_SET,
) -> GraspResult:
    """Solve the grasp at one actuation torque, starting from the rest configuration.

    Parameters
    ----------
    scene
        Gripper and disk.
    torque_nm
        Actuation torque ``T_a`` applied on each finger [N·m], >= 0 and plausible: at most
        :data:`~envs.model.defaults.MAX_TORQUE_UNITS` of the disk's torque unit ``s E t r^2``
        beyond the joint springs' moment at full closing (:meth:`envs.scene.Scene.check_torque`;
        10 units squeeze the paper's disk by 75 %).
    n_triangles, n_rings, element, calibrated
        The member of the model family (:func:`envs.model.family.resolve_model`). The defaults
        are the default model (for the baselines, ``method != "newton"``, the paper's fan):
        ``element="nhquad"`` with ``N = 40`` contour points, ``M = 2`` rings and its shipped
        calibration (within 2 % RMS, 4 % max of the FEM closing angle on
        disks it was not fitted to). ``element="spring"`` alone gives the paper's fan (N = 20,
        one ring, springs only, the disk's own scale). ``n_triangles``: 4 to 500 for the
        springs-only fan, cells 0.4-2.5 times as deep as wide for spring rings
        (:func:`envs.model.family.triangle_range`), to 2000 otherwise; ``n_rings``: 1 to 16
        (rings and a rigid hub, :mod:`envs.model.rings`; 2 or more for ``"nhquad"``);
        ``element``: ``"spring"`` (springs and the area energy), ``"cst"`` (constant-strain
        neo-Hookean triangles of the disk's E and nu) or ``"nhquad"`` (those triangles'
        deviatoric part and a volumetric term per quad, evenly spaced rings); ``calibrated``:
        ``None`` applies the member's shipped scale where it has one, ``True`` requires it,
        ``False`` leaves the disk's scale as is.
        Members other than the fan need ``method="newton"``.
    method
        ``"newton"`` (default), ``"slsqp"`` or ``"nelder-mead"``.
    stiffness_rule
        ``"van_gelder"`` (default) or ``"cst_fit"``.
    phase_rad
        Angle of the first contour point [rad], in [-2 pi, 2 pi]; pi/2 (top) is
        mirror-symmetric for even N.
    time_limit_s
        Wall-time budget for the baselines [s], in (0, 3600] (the Newton solver needs none).
    payload_factor
        ``f`` of the payload ``W = f rho pi r^2 t g`` the required friction includes
        (:meth:`envs.scene.SoftDisk.payload_n`), in [0, 100]: default 2 (the weight plus a
        lift at 1 g), 0 for the reaction of the fixed centre alone.
    load_set
        How the gripper picks, the payload's directions the friction must carry it in
        (:mod:`envs.model.loads`): ``"top-down"`` (along the gripper's axis, towards the tips
        and back), ``"side"`` (out of the plane, both ways) or ``"any"`` (every in-plane
        direction and out of the plane; default). The freed object's grasp is solved under
        each load (its normal forces move as the grasp's stiffness decides).

    Returns
    -------
    GraspResult
        ``converged`` is False, with the reason in ``message``, when the solver failed or the
        independent check rejected its answer.

    Raises
    ------
    ValueError
        For a bad argument, naming it and its allowed range.
    """
    spec = _check_inputs(scene, n_triangles, method, stiffness_rule, phase_rad, time_limit_s,
                         n_rings, element, calibrated)
    n = spec.n_triangles
    torque = scene.check_torque(torque_nm)
    payload = scene.disk.payload_n(payload_factor)
    load_set_code(load_set)
    prob = _Problem(scene, torque, n, stiffness_rule, float(phase_rad), spec.n_rings,
                    spec.element, spec.scale, payload, load_set)
    if method == "newton":
        return _solve_newton(prob)
    from . import baselines

    return baselines.solve(scene, torque, n, stiffness_rule, float(phase_rad), method,
                           float(time_limit_s), payload, load_set)


def simulate_ramp(
    scene: Scene,
    torques_nm,
    n_triangles: int | None = None,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    phase_rad: float = DEFAULT_PHASE_RAD,
    time_limit_s: float = 30.0,
    n_rings: int | None = None,
    element: str | None = None,
    calibrated: bool | None = None,
    until_peak_strain: float | None = None,
    payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
    load_set: str = DEFAULT_LOAD_SET,
) -> list[GraspResult]:
    """Follow the grasp along an increasing torque ramp (the paper's Fig. 4 curve).

    Each step starts from the previous equilibrium with the fingers opened by a small angle
    (so that the start is strictly inside the contact constraints), which follows the branch of
    equilibria the ramp reaches. A step whose warm start fails is retried from rest. A step
    that ends on an unstable equilibrium (the branch the ramp followed has lost its stability,
    e.g. a symmetric squeeze past a bifurcation) is solved again from the rest shape turned a
    little about the pin, either sense, and takes the stable equilibrium that reaches (where
    a slowly loaded disk snaps to).

    Parameters
    ----------
    torques_nm
        Non-decreasing actuation torques [N·m].
    until_peak_strain
        If given, in (0, 10]: stop after the first converged step whose ``peak_strain``
        reaches it (the remaining torques are not solved, so the list may be shorter); a
        ramp "to 40 % strain" without knowing the torque that gives it.
    Other parameters
        As in :func:`simulate`.
    """
    spec = _check_inputs(scene, n_triangles, method, stiffness_rule, phase_rad, time_limit_s,
                         n_rings, element, calibrated)
    n = spec.n_triangles
    try:
        torques = np.asarray(torques_nm, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"torques_nm must be a sequence of numbers, got {torques_nm!r}") from None
    if torques.size == 0:
        raise ValueError("torques_nm must contain at least one torque")
    for i, t in enumerate(torques.tolist()):
        scene.check_torque(t, f"torques_nm[{i}]")
    if np.any(np.diff(torques) < 0):
        raise ValueError("torques_nm must be non-decreasing (a loading ramp)")
    stop = math.inf if until_peak_strain is None else check_range(
        "until_peak_strain", until_peak_strain, 0.0, 10.0, low_open=True)
    if method != "newton":
        if until_peak_strain is not None:
            raise ValueError(f"until_peak_strain needs method = 'newton', got {method!r}")
        return [simulate(scene, t, n, method, stiffness_rule=stiffness_rule,
                         phase_rad=phase_rad, time_limit_s=time_limit_s, n_rings=1,
                         element="spring", calibrated=False, payload_factor=payload_factor,
                         load_set=load_set)
                for t in torques]
    load_set_code(load_set)
    base = _Problem(scene, 0.0, n, stiffness_rule, float(phase_rad), spec.n_rings,
                    spec.element, spec.scale, scene.disk.payload_n(payload_factor), load_set)
    out: list[GraspResult] = []
    prev: GraspResult | None = None
    for t in torques.tolist():
        prob = base.at(t)
        res = None
        if prev is not None and prev.converged:
            res, _ = prob.solve(*_warm_start(prob, prev))
        if res is None or not res.converged:
            res = _solve_newton(prob)
        if res.converged and not res.stable:
            res = _leave_unstable(prob, res)
        out.append(res)
        prev = res
        if res.converged and res.peak_strain >= stop:
            break
    return out
