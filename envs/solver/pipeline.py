"""The one batch pipeline: scenes in, checked grasps out.

``simulate``, ``simulate_ramp``, ``evaluate_designs`` (and through it the environments, the
optimizers, rendering and charts) all solve through :func:`solve_columns`:

1. pack the scenes (:func:`envs.model.problem.pack_params`);
2. solve every row with the compiled interior point (:func:`envs.solver.driver.solve_batch`,
   rows in parallel threads; one row without the thread pool);
3. measure each state (:func:`envs.model.metrics.state_metrics`) and check it independently
   (:func:`envs.check.check_one`), in SI units, compiled and row-parallel like the solve;
4. give each row one public status: ``converged`` means the solver claimed an equilibrium, the
   check confirmed it and no fan triangle is turned over.
"""

from __future__ import annotations

import functools
import time
from typing import NamedTuple

import numpy as np
from numba import njit

from envs import check
from envs.model.holding import (
    H_PIN_X,
    H_PIN_Y,
    N_HOLD,
    holding_fields,
)
from envs.model.layout import (
    I_ITERATIONS,
    I_ROUNDS,
    I_STABLE,
    I_STATUS,
    J_BOTTOM_RADIUS,
    J_DEPTH,
    J_OPENING,
    J_POSITION,
    N_CORNERS,
    N_INFO,
    N_JAW,
    N_OUTLINE,
    P_A0,
    P_H,
    P_KA,
    P_KC,
    P_KR,
    P_LAM,
    P_MU,
    P_PHASE,
    P_QUAD,
    P_RHO,
    P_RINGS,
    P_SPACING,
    P_THMIN,
    S_CONTOUR_RATIO,
    S_JAW0,
    S_JAW1,
    S_JOINT_OFFSET,
    S_LENGTH,
    S_OFFSET_X,
    S_ORIENT,
    S_OUTLINE,
    S_RADIUS,
    S_REST_ANGLE,
    S_SHAPE,
    S_TORQUE,
    S_TORSION,
    S_WIDTH,
    default_options,
)
from envs.model.loads import DEFAULT_LOAD_SET, load_set_code
from envs.model.metrics import (
    M_COMPRESSION,
    M_DISPLACEMENT,
    M_ENERGY,
    M_INVERTED,
    M_PEAK_LOG_STRAIN,
    M_PEAK_STRAIN,
    N_METRICS,
    state_metrics,
)
from envs.model.problem import (
    SceneColumns,
    pack_params,
    rest_state,
    scene_centre_y_m,
    stiffness_unit,
)
from envs.model.rings import HUB_RADIUS, kernel_copy, kernel_copy_into, mesh_band_index

from ..parallel import run_rows
from . import driver, follow
from .loaded import response_work
from .reaction import holding_one, max_contacts
from .result import GraspResult
from .status import BLOCKED, CHECK_FAILED, INVERTED, LINESEARCH_FAIL, OK, STATUS_MESSAGES
from .warmup import announce_compile

__all__ = ["BatchSolution", "solve_columns", "checked_solution", "row_message", "grasp_result"]


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
    corner_forces_n: np.ndarray  # (B, 2, N_CORNERS, N)
    corner_totals_n: np.ndarray  # (B, 2, N_CORNERS): total force of each corner
    corner_edges: np.ndarray  # (B, 2, N_CORNERS): edge with most of each corner's force, -1: none
    stop_torques_nm: np.ndarray  # (B, 2)
    peak_strain: np.ndarray  # (B,) max |spring strain|
    peak_log_strain: np.ndarray  # (B,) max over triangles of the largest principal |ln lambda|
    peak_compression: np.ndarray  # (B,) largest shortening of a radius over r
    max_displacement_ratio: np.ndarray  # (B,)
    energy_j: np.ndarray  # (B,) total potential energy [J]
    inverted: np.ndarray  # (B,) int
    check: np.ndarray  # (B, check.N_OUT): the independent check's verdict
    state_scaled: np.ndarray  # (B, 2 N M + 2) solver state (warm starts)
    interior_points_m: np.ndarray  # (B, (M - 1) N, 2) interior points of a ring mesh
    face_scaled: np.ndarray  # (B, 2, N) scaled face multipliers (warm starts)
    holding: np.ndarray  # (B, N_HOLD): layout H_* of envs.model.holding
    solve_time_s: float  # compiled solve time of the whole batch


_OPTIONS = default_options()  # shared by every solve: the kernels only read it

# per-row columns the finish writes for BatchSolution: counts (int64) and flags (bool)
C_ITERATIONS, C_ROUNDS, C_INVERTED = range(3)
N_COUNTS = 3
F_CONVERGED, F_FOLDED, F_STABLE = range(3)
N_FLAGS = 3


@functools.cache
def _prepare_kernels() -> None:
    """Once per process, before the first solve: on a cold cache a notice and the compile split
    over two processes (:func:`envs.solver.warmup.announce_compile`), for library callers as
    for the command line."""
    announce_compile()


class _Answers(NamedTuple):
    """The compiled solver's raw answers of B rows (scaled), before the finish."""

    infos: np.ndarray  # (B, N_INFO), layout I_*
    lam_corner: np.ndarray  # (B, 2, N_CORNERS, N)
    lam_stop: np.ndarray  # (B, 2)
    corner_cand: np.ndarray  # (B, 2, N_CORNERS, N) bool: the corner constraints considered
    face_cand: np.ndarray  # (B, 2, N) bool: the face constraints considered


def _solve(n: int, prm: np.ndarray, xs: np.ndarray, lam_face: np.ndarray) -> _Answers:
    """Run the compiled solver in place on ``xs`` and ``lam_face``; returns the other
    answers."""
    _prepare_kernels()
    b = prm.shape[0]
    out = _Answers(np.zeros((b, N_INFO)), np.zeros((b, 2, N_CORNERS, n)), np.zeros((b, 2)),
                   np.zeros((b, 2, N_CORNERS, n), dtype=np.bool_),
                   np.zeros((b, 2, n), dtype=np.bool_))
    # dynamic schedule in small blocks (envs.parallel.run_rows): solve times vary by 100x
    # between rows (a row hitting the iteration limit); one row runs in the calling thread
    driver.solve_batch(n, prm, _OPTIONS, xs, lam_face, out.lam_corner, out.lam_stop,
                       out.corner_cand, out.face_cand, out.infos)
    return out


MIRROR_TOLERANCE_RAD = 1e-7  # finger angles of a mirror-symmetric answer agree within this


def _settled(ans: _Answers, scene: np.ndarray, xs: np.ndarray, n: int,
             rows: np.ndarray) -> np.ndarray:
    """Which of ``rows`` may lead their followers: the solver ended on a stable equilibrium
    it claims, and, for a mirror-symmetric scene, on the mirror-symmetric grasp.

    Why the second: past a bifurcation a symmetric scene has two mirror-image grasps of equal
    energy (the disk turned one way or the other); a solve from rest picks one by its escape
    from the symmetric saddle, a follower would continue the leader's, and a scenario that
    breaks the symmetry a little (a displacement) may end on either branch. Such designs are
    solved from rest in every scenario, so that the answers stay those of independent solves.
    """
    info = ans.infos[rows]
    claimed = (info[:, I_STATUS] == OK) & (info[:, I_STABLE] == 1.0)
    s = scene[rows]
    mirrored = (s[:, S_OFFSET_X] == 0.0) & np.all(
        s[:, S_JAW0 : S_JAW0 + N_JAW] == s[:, S_JAW1 : S_JAW1 + N_JAW], axis=1)
    angles = xs[rows, 2 * n : 2 * n + 2]
    turned = np.abs(angles[:, 0] - angles[:, 1]) > MIRROR_TOLERANCE_RAD
    return claimed & ~(mirrored & turned)


def _solve_rows_of(n: int, prm: np.ndarray, xs: np.ndarray, lam_face: np.ndarray,
                   rows: np.ndarray, ans: _Answers, kernel=None) -> None:
    """Solve ``rows`` of the batch in place (``xs``, ``lam_face`` and ``ans``): from their
    start with :func:`_solve`, or with ``kernel`` (a batch function of the solver's
    arguments, :func:`envs.solver.follow.follow_batch`) from what those rows hold."""
    x, lam = xs[rows], lam_face[rows]  # (copies: written back below)
    if kernel is None:
        part = _solve(n, prm[rows], x, lam)
    else:
        part = _Answers(*(a[rows] for a in ans))
        kernel(n, prm[rows], _OPTIONS, x, lam, part.lam_corner, part.lam_stop,
               part.corner_cand, part.face_cand, part.infos)
    xs[rows], lam_face[rows] = x, lam
    for whole, piece in zip(ans, part, strict=True):
        whole[rows] = piece


def _straight_leaders(scene: np.ndarray, leaders) -> np.ndarray | None:
    """``leaders`` of :func:`solve_columns` checked, without the rows led by a design with a
    groove in either jaw (``None`` where no row is led).

    Why: the fast path (:mod:`envs.solver.follow`) seats the fingers and places the contacts
    on a straight face only; on grooved designs it fell back more often than it settled (96
    random designs of the ``any`` jaw box on paper-r070 under +-2 mm placements took 0.70x
    the CPU time of the solves from rest, where straight jaws take 1.24x less), so their
    scenarios are solved from rest, with the rows that lead."""
    if leaders is None:
        return None
    leaders = np.asarray(leaders, dtype=np.int64)
    if leaders.shape != (scene.shape[0],):
        raise ValueError(f"leaders must have shape ({scene.shape[0]},), got {leaders.shape}")
    if (np.any(leaders < -1) or np.any(leaders >= scene.shape[0])
            or np.any(leaders[leaders[leaders >= 0]] >= 0)):
        raise ValueError("leaders must be -1 or the index of a row of the batch that has no "
                         "leader itself")
    grooved = (scene[:, S_JAW0 + J_DEPTH] != 0.0) | (scene[:, S_JAW1 + J_DEPTH] != 0.0)
    leaders = np.where((leaders >= 0) & grooved[np.maximum(leaders, 0)], -1, leaders)
    return leaders if np.any(leaders >= 0) else None


def _solve_following(n: int, scene: np.ndarray, prm: np.ndarray, xs: np.ndarray,
                     lam_face: np.ndarray, leaders: np.ndarray
                     ) -> tuple[_Answers, np.ndarray, np.ndarray]:
    """Solve the rows without a leader, then each follower from its leader's answer on its
    contact set (:mod:`envs.solver.follow`), in place on ``xs`` and ``lam_face``.

    Returns the answers of every row, the followers the fast path ran on and those it did not
    (their leader leads none, :func:`_settled`: they still hold their start)."""
    b = prm.shape[0]
    ans = _Answers(np.zeros((b, N_INFO)), np.zeros((b, 2, N_CORNERS, n)), np.zeros((b, 2)),
                   np.zeros((b, 2, N_CORNERS, n), dtype=np.bool_),
                   np.zeros((b, 2, n), dtype=np.bool_))
    _solve_rows_of(n, prm, xs, lam_face, np.flatnonzero(leaders < 0), ans)
    followers = np.flatnonzero(leaders >= 0)
    good = _settled(ans, scene, xs, n, leaders[followers])
    fast, slow = followers[good], followers[~good]
    if fast.size:
        lead = leaders[fast]
        xs[fast], lam_face[fast] = xs[lead], lam_face[lead]
        for a in ans:
            a[fast] = a[lead]
        _solve_rows_of(n, prm, xs, lam_face, fast, ans, follow.follow_batch)
    return ans, fast, slow


def _merge(sol: BatchSolution, rows: np.ndarray, part: BatchSolution) -> BatchSolution:
    """``sol`` with its ``rows`` replaced by the rows of ``part`` (in that order)."""
    fields = {}
    for name, whole in sol._asdict().items():
        if name == "solve_time_s":
            fields[name] = whole + part.solve_time_s
            continue
        whole = whole.copy()
        whole[rows] = getattr(part, name)
        fields[name] = whole
    return BatchSolution(**fields)


@njit(cache=True, error_model="numpy", _nrt=False)
def _check_row(s, prm, n, ck):
    """Parameters of the independent check for one scene row (SI units)."""
    r = s[S_RADIUS]
    k_unit = stiffness_unit(s)
    ck[check.CK_RADIUS] = r
    ck[check.CK_CENTRE_X] = s[S_OFFSET_X]
    ck[check.CK_CENTRE_Y] = scene_centre_y_m(s)
    ck[check.CK_JOINT_OFFSET] = s[S_JOINT_OFFSET]
    ck[check.CK_LENGTH] = s[S_LENGTH]
    ck[check.CK_HALF_WIDTH] = s[S_WIDTH] / 2
    ck[check.CK_RHO] = prm[P_RHO] * r
    ck[check.CK_KF] = s[S_TORSION]
    ck[check.CK_TH0] = s[S_REST_ANGLE]
    ck[check.CK_THMIN] = prm[P_THMIN]
    ck[check.CK_TORQUE] = s[S_TORQUE]
    ck[check.CK_KINT] = prm[P_KR] * k_unit
    ck[check.CK_KEXT] = prm[P_KC] * k_unit
    ck[check.CK_REST_CONTOUR] = prm[P_H] * r
    ck[check.CK_AREA_STIFF] = prm[P_KA] * k_unit
    ck[check.CK_REST_AREA] = prm[P_A0] * r * r
    ck[check.CK_RINGS] = prm[P_RINGS]
    ck[check.CK_HUB] = HUB_RADIUS * r
    ck[check.CK_UNIT] = k_unit
    ck[check.CK_CRATIO] = s[S_CONTOUR_RATIO]
    ck[check.CK_PHASE] = prm[P_PHASE]
    # constant-strain triangles: Lame moduli times s t [N/m] (0: springs)
    ck[check.CK_MU] = prm[P_MU] * k_unit
    ck[check.CK_LAM] = prm[P_LAM] * k_unit
    # nh-quad: the volumetric modulus of the quads, and the ring spacing the mesh was built with
    ck[check.CK_QUAD] = prm[P_QUAD] * k_unit
    ck[check.CK_SPACING] = prm[P_SPACING]
    # the object's outline (0: a disk), as the scene row gives it (its coefficients: an
    # argument of the check)
    ck[check.CK_SHAPE] = s[S_SHAPE]
    ck[check.CK_ORIENT] = s[S_ORIENT]
    # each finger's jaw groove, SI, as the scene row gives it (the check grows it itself)
    for base, jaw in ((check.CK_JAW0, S_JAW0), (check.CK_JAW1, S_JAW1)):
        ck[base + check.JW_DEPTH] = s[jaw + J_DEPTH]
        ck[base + check.JW_BOTTOM_RADIUS] = s[jaw + J_BOTTOM_RADIUS]
        ck[base + check.JW_OPENING] = s[jaw + J_OPENING]
        ck[base + check.JW_POSITION] = s[jaw + J_POSITION]


@njit(cache=True, error_model="numpy", _nrt=False)
def _to_si(s, n, x, lam_face, lam_corner, lam_stop, points, interior, face, corner, stop):
    """Points [m] (the contour; a ring mesh's interior points, which follow the angles in the
    state) and forces [N, N·m] of one scaled answer."""
    r = s[S_RADIUS]
    force_unit = stiffness_unit(s) * r
    xc, yc = s[S_OFFSET_X], scene_centre_y_m(s)
    for i in range(n):
        points[i, 0] = x[2 * i] * r + xc
        points[i, 1] = x[2 * i + 1] * r + yc
    for p in range(interior.shape[0]):
        interior[p, 0] = x[2 * n + 2 + 2 * p] * r + xc
        interior[p, 1] = x[2 * n + 3 + 2 * p] * r + yc
    for j in range(2):
        stop[j] = lam_stop[j] * force_unit * r
        for i in range(n):
            face[j, i] = lam_face[j, i] * force_unit
            for c in range(N_CORNERS):
                corner[j, c, i] = lam_corner[j, c, i] * force_unit


@njit(cache=True, error_model="numpy", _nrt=False)
def _corner_summary(corner, totals, edges):
    """Total force of each corner and the edge carrying most of it (-1 for none)."""
    for j in range(2):
        for c in range(N_CORNERS):
            total = 0.0
            best = -1
            for k in range(corner.shape[2]):
                total += corner[j, c, k]
                if corner[j, c, k] > 0.0 and (best < 0 or corner[j, c, k] > corner[j, c, best]):
                    best = k
            totals[j, c] = total
            edges[j, c] = best if total > 0.0 else -1


@njit(cache=True, error_model="numpy")
def _public_status(raw, passed, inverted):
    """One public status: the check and the fold count have the final say."""
    claimed = raw == OK or raw == INVERTED
    if inverted > 0 and passed:
        # a fold the check confirms is reported as such, even where the solver stopped short
        # of its own (tighter) tolerance
        return INVERTED
    if claimed and passed:
        return OK
    if claimed:
        return CHECK_FAILED
    return LINESEARCH_FAIL if raw == BLOCKED else raw


@njit(cache=True, error_model="numpy", inline="always")
def _finish_one(s, prm, n, x, lam_face, lam_corner, lam_stop, info, points, interior, face,
                corner, stop, totals, edges, metrics, ck, verdict):
    state_metrics(x, n, kernel_copy(prm, n), metrics)
    # energy in J: the scaled energy is in units of s E t r^2
    metrics[M_ENERGY] *= stiffness_unit(s) * s[S_RADIUS] ** 2
    _to_si(s, n, x, lam_face, lam_corner, lam_stop, points, interior, face, corner, stop)
    _corner_summary(corner, totals, edges)
    _check_row(s, prm, n, ck)
    if prm[P_RINGS] == 1 and prm[P_MU] == 0.0:
        check.check_one(ck, points, x[2 * n : 2 * n + 2], face, corner, stop, verdict)
    else:
        check.check_mesh_one(ck, points, interior, x[2 * n : 2 * n + 2], face, corner, stop,
                             verdict, s[S_OUTLINE : S_OUTLINE + N_OUTLINE])
    return _public_status(int(info[I_STATUS]), verdict[check.OUT_PASSED] > 0.0,
                          int(metrics[M_INVERTED]))


@njit(cache=True, error_model="numpy", nogil=True)
def _finish_rows(start, stop_row, scene, prm, n, xs, lam_face, lam_corner, lam_stop, infos,
                 points, interior, face, corner, stop, totals, edges, metrics, ck, verdict,
                 status, counts, flags, jaw, payload, load_set, holding):
    """Finish rows ``start .. stop_row - 1``: SI answers, metrics, the check, the public
    status, the pin reaction and required friction (:mod:`envs.solver.reaction`), and the
    per-row columns of :class:`BatchSolution` (``counts`` and ``flags`` one row a column,
    layouts ``C_*`` and ``F_*``; here rather than in numpy: a one-row call paid ~5 us for a
    dozen small array operations)."""
    # the contact list's and the loaded grasp's scratch, once per block of rows
    k = max_contacts(n)
    grad5, hess5 = np.empty(5), np.empty((5, 5))
    normals, contact_points = np.empty((k, 2)), np.empty((k, 2))
    forces = np.empty(k)
    patches, fingers = np.empty(k, dtype=np.int64), np.empty(k, dtype=np.int64)
    nodes, share = np.empty((k, 2), dtype=np.int64), np.empty(k)
    groups, cons = np.empty((k, 2), dtype=np.int64), np.empty((k, 2), dtype=np.int64)
    weights = np.empty((k, 2))
    kprm = kernel_copy(prm[start], n)
    bidx = mesh_band_index(n, int(prm[start, P_RINGS]))
    work = response_work(n, kprm)
    for b in range(start, stop_row):
        kernel_copy_into(prm[b], n, kprm)
        holding_one(scene[b], prm[b], kprm, n, xs[b], lam_face[b], lam_corner[b], lam_stop[b],
                    payload[b], load_set[b], bidx, work, grad5, hess5, normals, contact_points,
                    forces, patches, nodes, share, fingers, groups, cons, weights, holding[b])
        st = _finish_one(scene[b], prm[b], n, xs[b], lam_face[b], lam_corner[b], lam_stop[b],
                         infos[b], points[b], interior[b], face[b], corner[b], stop[b],
                         totals[b], edges[b], metrics[b], ck[b], verdict[b])
        status[b] = st
        inverted = int(metrics[b, M_INVERTED])
        counts[C_ITERATIONS, b] = int(infos[b, I_ITERATIONS])
        counts[C_ROUNDS, b] = int(infos[b, I_ROUNDS])
        counts[C_INVERTED, b] = inverted
        flags[F_CONVERGED, b] = st == OK
        flags[F_FOLDED, b] = inverted > 0 and verdict[b, check.OUT_PASSED] > 0.0
        flags[F_STABLE, b] = infos[b, I_STABLE] != 0.0
        jaw[b, 0] = xs[b, 2 * n]
        jaw[b, 1] = xs[b, 2 * n + 1]


def solve_columns(cols: SceneColumns | np.ndarray, n_triangles: int, *,
                  stiffness_rule: str = "van_gelder",
                  phase_rad: float, x0: np.ndarray | None = None,
                  lam0: np.ndarray | None = None, n_rings: int = 1,
                  element: str = "spring", payload_n: np.ndarray | None = None,
                  leaders: np.ndarray | None = None,
                  load_set: str = DEFAULT_LOAD_SET) -> BatchSolution:
    """Solve and check the grasps of B valid scenes with N fan triangles.

    Parameters
    ----------
    cols
        The scenes and torques (valid at rest, see :func:`envs.model.problem.rest_codes`), as
        columns or a (B, N_SCENE) scene matrix.
    n_triangles
        Number of fan triangles ``N``.
    stiffness_rule, phase_rad
        As in :func:`envs.simulate`.
    x0, lam0
        Scaled start states (B, 2 N M + 2) and face multipliers (B, 2, N) of a warm start
        (default: rest, no multipliers). The start must be strictly feasible.
    n_rings
        Rings ``M`` of the point mesh (1: the paper's fan).
    element
        ``"spring"``, ``"cst"`` or ``"nhquad"`` (:func:`envs.model.problem.pack_params`).
    payload_n
        The payload ``W`` [N] of each row (B,) that holding judges (:mod:`envs.model.holding`);
        default 0: the reaction of the fixed centre alone.
    load_set
        How the gripper picks: the payload's directions that holding checks, ``"top-down"``,
        ``"side"`` or ``"any"`` (:mod:`envs.model.loads`).
    leaders
        Optional (B,) int: for each row the row of this batch whose answer starts it (its
        *leader*, a scene a few percent away: the same design in another scenario), -1 for
        none. A leader must have none itself. A row with a leader is solved from the leader's
        answer on the leader's contact set (:mod:`envs.solver.follow`) and keeps that answer
        where it is a stable equilibrium the independent check confirms; otherwise it is
        solved from its start like a row without a leader (its ``iterations`` count both).
        A leader with a groove in either jaw leads none (:func:`_straight_leaders`).
    """
    n = int(n_triangles)
    scene = cols.rows() if isinstance(cols, SceneColumns) else cols
    prm = pack_params(scene, n, stiffness_rule, phase_rad, int(n_rings), element)
    # C order: the kernels are compiled for it (another layout compiles the solver again)
    xs = (rest_state(prm, n) if x0 is None
          else np.array(x0, dtype=np.float64, ndmin=2, order="C"))
    lam_face = (np.zeros((scene.shape[0], 2, n)) if lam0 is None
                else np.array(lam0, dtype=np.float64, ndmin=3, order="C"))
    t0 = time.perf_counter()
    leaders = _straight_leaders(scene, leaders)
    if leaders is None:
        ans = _solve(n, prm, xs, lam_face)
        return checked_solution(scene, n, prm, xs, lam_face, ans.lam_corner, ans.lam_stop,
                                ans.infos, time.perf_counter() - t0, payload_n, load_set)
    start_x, start_lam = xs.copy(), lam_face.copy()
    ans, fast, slow = _solve_following(n, scene, prm, xs, lam_face, leaders)
    elapsed = time.perf_counter() - t0
    payload = None if payload_n is None else np.broadcast_to(payload_n, (scene.shape[0],))
    sol = checked_solution(scene, n, prm, xs, lam_face, ans.lam_corner, ans.lam_stop, ans.infos,
                           elapsed, payload, load_set)
    # the fast path's answers stand where the check confirms a stable equilibrium; the rest
    # are solved from their own start, as without a leader
    retry = np.concatenate([slow, fast[~(sol.converged[fast] & sol.stable[fast])]])
    if not retry.size:
        return sol
    t0 = time.perf_counter()
    x, lam = start_x[retry], start_lam[retry]
    part = _solve(n, prm[retry], x, lam)
    part.infos[:, I_ITERATIONS] += ans.infos[retry, I_ITERATIONS] * np.isin(retry, fast)
    redo = checked_solution(scene[retry], n, prm[retry], x, lam, part.lam_corner,
                            part.lam_stop, part.infos, time.perf_counter() - t0,
                            None if payload is None else payload[retry], load_set)
    return _merge(sol, retry, redo)


def checked_solution(scene: np.ndarray, n: int, prm: np.ndarray, xs: np.ndarray,
                     lam_face: np.ndarray, lam_corner: np.ndarray, lam_stop: np.ndarray,
                     infos: np.ndarray, elapsed: float,
                     payload_n: np.ndarray | None = None,
                     load_set: str = DEFAULT_LOAD_SET) -> BatchSolution:
    """Measure, convert to SI, check and give a public status to solver answers.

    Parameters
    ----------
    scene, n, prm
        The (B, N_SCENE) scene matrix, N and the packed parameters.
    xs, lam_face, lam_corner, lam_stop
        Scaled states (B, 2N + 2) and multipliers: face (B, 2, N), corner (B, 2, N_CORNERS,
        N), joint stop (B, 2).
    infos
        Solver info rows (B, N_INFO) (layout ``I_*``): its claim in ``I_STATUS``.
    elapsed
        Solver time of the batch [s].
    payload_n
        The payload [N] of each row (B,), default 0 (see :func:`solve_columns`).
    load_set
        The load set's name (see :func:`solve_columns`).
    """
    b = prm.shape[0]
    # a writable C-contiguous copy: the kernel is compiled for that one array type
    payload = (np.zeros(b) if payload_n is None
               else np.array(np.broadcast_to(payload_n, (b,)), dtype=np.float64, order="C"))
    loads = np.full(b, load_set_code(load_set), dtype=np.int64)
    points = np.empty((b, n, 2))
    interior = np.empty((b, (xs.shape[1] - 2 * n - 2) // 2, 2))
    face = np.empty((b, 2, n))
    corner = np.empty((b, 2, N_CORNERS, n))
    stop = np.empty((b, 2))
    totals = np.empty((b, 2, N_CORNERS))
    edges = np.empty((b, 2, N_CORNERS), dtype=np.int64)
    metrics = np.empty((b, N_METRICS))
    ck = np.zeros((b, check.N_CK))
    verdict = np.zeros((b, check.N_OUT))
    status = np.empty(b, dtype=np.int64)
    # one row per column (not per scene), so that each column is a contiguous array
    counts = np.empty((N_COUNTS, b), dtype=np.int64)
    flags = np.empty((N_FLAGS, b), dtype=np.bool_)
    jaw = np.empty((b, 2))
    holding = np.empty((b, N_HOLD))
    run_rows(_finish_rows, b, scene, prm, n, xs, lam_face, lam_corner, lam_stop, infos, points,
             interior, face, corner, stop, totals, edges, metrics, ck, verdict, status, counts,
             flags, jaw, payload, loads, holding)
    return BatchSolution(
        status=status, converged=flags[F_CONVERGED], folded=flags[F_FOLDED],
        iterations=counts[C_ITERATIONS], rounds=counts[C_ROUNDS],
        stable=flags[F_STABLE], jaw_angles_rad=jaw, points_m=points, face_forces_n=face,
        corner_forces_n=corner, corner_totals_n=totals, corner_edges=edges,
        stop_torques_nm=stop, peak_strain=metrics[:, M_PEAK_STRAIN],
        peak_log_strain=metrics[:, M_PEAK_LOG_STRAIN],
        peak_compression=metrics[:, M_COMPRESSION],
        max_displacement_ratio=metrics[:, M_DISPLACEMENT],
        energy_j=metrics[:, M_ENERGY], inverted=counts[C_INVERTED], check=verdict,
        state_scaled=xs, face_scaled=lam_face, solve_time_s=elapsed,
        interior_points_m=interior, holding=holding,
    )


def row_message(sol: BatchSolution, i: int) -> str:
    """The human-readable outcome of row ``i``."""
    status = int(sol.status[i])
    if status == CHECK_FAILED:
        return f"independent KKT check failed: {check.report_from_output(sol.check[i]).reason}"
    return STATUS_MESSAGES[status]


def grasp_result(sol: BatchSolution, i: int, torque_nm: float, method: str = "newton",
                 stiffness_rule: str = "van_gelder", *, message: str | None = None,
                 iterations: int | None = None, solve_time_s: float | None = None,
                 element: str = "spring", model_scale: float = 1.0,
                 load_set: str = DEFAULT_LOAD_SET) -> GraspResult:
    """Row ``i`` of a batch solution as a :class:`GraspResult`."""
    face = sol.face_forces_n[i]
    return GraspResult(
        converged=bool(sol.converged[i]),
        message=row_message(sol, i) if message is None else message,
        jaw_angles_rad=(float(sol.jaw_angles_rad[i, 0]), float(sol.jaw_angles_rad[i, 1])),
        points_m=sol.points_m[i],
        contact_mask=face > 0.0,
        contact_forces_n=face,
        peak_strain=float(sol.peak_strain[i]),
        iterations=int(sol.iterations[i]) if iterations is None else int(iterations),
        solve_time_s=sol.solve_time_s if solve_time_s is None else float(solve_time_s),
        torque_nm=float(torque_nm),
        n_triangles=int(sol.points_m.shape[1]),
        method=method,
        stiffness_rule=stiffness_rule,
        corner_forces_n=sol.corner_totals_n[i],
        corner_edges=sol.corner_edges[i],
        corner_edge_forces_n=sol.corner_forces_n[i],
        stop_torques_nm=sol.stop_torques_nm[i],
        energy_j=float(sol.energy_j[i]),
        max_displacement_ratio=float(sol.max_displacement_ratio[i]),
        stable=bool(sol.stable[i]),
        kkt=check.report_from_output(sol.check[i]),
        rounds=int(sol.rounds[i]),
        inverted_triangles=int(sol.inverted[i]),
        peak_log_strain=float(sol.peak_log_strain[i]),
        n_rings=int((sol.state_scaled.shape[1] - 2) // (2 * sol.points_m.shape[1])),
        element=element,
        model_scale=float(model_scale),
        interior_points_m=sol.interior_points_m[i],
        peak_compression=float(sol.peak_compression[i]),
        load_set=load_set,
        **{**holding_fields(sol.holding[i]),
           "pin_force_n": sol.holding[i, H_PIN_X : H_PIN_Y + 1].copy()},
    )
