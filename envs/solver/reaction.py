"""The pin reaction and the required friction of a solved point-spring grasp.

Each contact force of the solver is its multiplier times the gradient of its gap
(:mod:`envs.solver.contact`): on a contour point for a face contact (the rounded finger bar:
the gripping face, its ends, its back), on the two end points of a contour edge for a corner.
The gradient's direction is the contact's normal, so the contact list and the net force and
moment on the object come from the solver's own contact geometry, written once. The fixed
centre carries what they leave unbalanced (:mod:`envs.model.holding`).

Jaw grooves need nothing more: a face contact's normal is its gap's gradient on the grooved
finger too (:func:`envs.model.jaw.jaw_gap`), and a groove's two mouth edges are corners like
the bar's ends. The pressure shift of :mod:`envs.model.loads` groups a
straight finger's contacts that share a normal and a line across it as one face; on a grooved
finger a run of consecutive pressed contour points (with a mouth edge pressing an edge of the
run) is one patch, the rule the FEM applies to its runs of rim nodes.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model.holding import NO_PATCH, hertz_half_width
from ..model.layout import (
    N_BAR_CORNERS,
    N_CORNERS,
    P_RINGS,
    S_JOINT_OFFSET,
    S_OFFSET_X,
    S_POISSON,
    S_RADIUS,
    S_SCALE,
    S_THICKNESS,
    S_TORSION,
    S_YOUNG,
)
from ..model.loads import N_RESPONSE, loaded_holding, patch_constraints, patch_response
from ..model.problem import scene_centre_y_m, stiffness_unit
from .contact import _corner_eval, _face_eval, _grooved, _sel, _trig
from .loaded import contact_compliance

__all__ = ["max_contacts", "holding_one", "loaded_contacts"]


@njit(cache=True, inline="always")
def max_contacts(n):
    """Largest number of contacts of a grasp with N contour points: every point on each
    finger's bar, and every corner against every edge."""
    return 2 * n * (1 + N_CORNERS)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _run_label(lam_face, j, i, n):
    """Pressure-patch label of face contact i on grooved finger j: the run of consecutive
    pressed contour points it belongs to, named by the run's first point (``j n + first``;
    ``j n`` for a contour pressed all round)."""
    first = i
    for _ in range(n):
        before = first - 1 if first > 0 else n - 1
        if not lam_face[j, before] > 0.0:
            return j * n + first
        first = before
    return j * n


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _corner_label(lam_face, j, c, k, k1, n):
    """Pressure-patch label of corner c of finger j on contour edge (k, k1): a groove's mouth
    edge joins the run of a pressed end point of its edge (the rounded edge continues the
    jaw's surface), else it is a patch of its own; the bar's corners keep the flat-face rule
    (:data:`envs.model.holding.NO_PATCH`)."""
    if c < N_BAR_CORNERS:
        return NO_PATCH
    if lam_face[j, k] > 0.0:
        return _run_label(lam_face, j, k, n)
    if lam_face[j, k1] > 0.0:
        return _run_label(lam_face, j, k1, n)
    return 2 * n + (j * N_CORNERS + c) * n + k


@njit(cache=True, error_model="numpy")
def holding_one(s, prm, kprm, n, x, lam_face, lam_corner, lam_stop, payload, load_set, bidx,
                work, grad5, hess5, normals, points, forces, patches, nodes, share, fingers,
                groups, cons, weights, out):
    """The holding row (layout ``H_*`` of :mod:`envs.model.holding`) of one scaled answer:
    the fixed centre's reaction, then the free object's grasp over the load set
    (:func:`envs.model.loads.loaded_holding`, the normal forces moved by the patch-level
    model with the point-spring model's compliance, :func:`envs.solver.loaded`).

    Parameters
    ----------
    s, prm, kprm, n
        The scene row (SI), its packed parameters, the kernels' copy of them
        (:func:`envs.model.rings.kernel_copy_into`) and N.
    x, lam_face, lam_corner, lam_stop
        The scaled state and the face (2, N), corner (2, N_CORNERS, N) and joint-stop (2,)
        multipliers.
    payload, load_set
        The payload ``W`` [N] (>= 0) and the load set's code (``LOAD_*`` of
        :mod:`envs.model.loads`).
    bidx, work
        The band index and :func:`envs.solver.loaded.response_work`'s scratch.
    grad5, hess5, normals, points, forces, patches, nodes, share, fingers, groups, cons,
    weights
        Scratch: (5,), (5, 5), and per contact (max_contacts(n) rows): 2 / 2 / - / - (int) /
        2 (int) / - / - (int) / 2 (int) / 2 (int) / 2.
    out
        The holding row (layout ``H_*``), written: the pin force on the object [N], its
        moment about the centre [N·m], the required friction [-], the payload and the grip
        [N], what limits the friction.

    Returns
    -------
    int
        The number of contacts written to ``normals``, ``points`` and ``forces``.
    """
    r = s[S_RADIUS]
    force_unit = stiffness_unit(s) * r
    xc, yc = s[S_OFFSET_X], scene_centre_y_m(s)
    q = x[: 2 * n].reshape(n, 2)
    sn, cs = _trig(x, n)
    # np.int64, not a literal 0: numba would compile the callees once more for Literal[int](0)
    count = np.int64(0)
    fx = fy = moment = 0.0
    for j in range(2):
        sj, cj = _sel(sn, j), _sel(cs, j)
        for i in range(n):
            lam = lam_face[j, i]
            if not lam > 0.0:
                continue
            _face_eval(q, i, j, sj, cj, prm, grad5, hess5, False)
            f = lam * force_unit
            nx, ny = grad5[0], grad5[1]
            px, py = q[i, 0] * r, q[i, 1] * r
            normals[count, 0], normals[count, 1] = nx, ny
            points[count, 0], points[count, 1] = px + xc, py + yc
            forces[count] = f
            patches[count] = _run_label(lam_face, j, i, n) if _grooved(j, prm) else NO_PATCH
            nodes[count, 0], nodes[count, 1], share[count] = i, -1, 1.0
            fingers[count] = j
            fx += f * nx
            fy += f * ny
            moment += f * (px * ny - py * nx)
            count += 1
        for c in range(N_CORNERS):
            for k in range(n):
                lam = lam_corner[j, c, k]
                if not lam > 0.0:
                    continue
                # no Hessian, as a runtime flag (n < 0): a literal False would compile
                # _corner_eval a second time beside the solver's runtime-flag calls
                _corner_eval(q, k, j, sj, cj, c, prm, grad5, hess5, n < 0)
                k1 = k + 1 if k + 1 < n else 0
                # the force on the edge's two points, lam times the gap's gradient at each
                ax, ay, bx, by = grad5[0], grad5[1], grad5[2], grad5[3]
                tx, ty = ax + bx, ay + by
                size = math.sqrt(tx * tx + ty * ty)
                if size == 0.0:
                    continue
                f = lam * force_unit
                moment += f * ((q[k, 0] * ay - q[k, 1] * ax) + (q[k1, 0] * by - q[k1, 1] * bx)
                               ) * r
                fx += f * tx
                fy += f * ty
                # where a tangential force would act: the edge point the force is shared from
                # (weights |grad| of each end: 1 - t and t on the edge, 1 at an end point)
                wa = math.sqrt(ax * ax + ay * ay)
                wb = math.sqrt(bx * bx + by * by)
                px = (wa * q[k, 0] + wb * q[k1, 0]) / (wa + wb) * r
                py = (wa * q[k, 1] + wb * q[k1, 1]) / (wa + wb) * r
                normals[count, 0], normals[count, 1] = tx / size, ty / size
                points[count, 0], points[count, 1] = px + xc, py + yc
                forces[count] = f * size
                patches[count] = _corner_label(lam_face, j, c, k, k1, n)
                nodes[count, 0], nodes[count, 1] = k, k1
                share[count] = wa / (wa + wb)
                fingers[count] = j
                count += 1
    # the faces' contact patches with the solved model's stiffness (its scale times E)
    half_width = hertz_half_width(r, s[S_THICKNESS], s[S_SCALE] * s[S_YOUNG], s[S_POISSON])
    # how the free object's normal forces move under a load (zero where the body's Hessian or
    # the patch-level system is singular: the forces as solved)
    mn, mc = patch_constraints(normals, points, forces, patches, nodes, fingers, count, r,
                               groups, cons, weights)
    g = contact_compliance(kprm, n, x, bidx, work, nodes, share, normals, count, cons,
                           weights, mc, r, force_unit)
    locked = (lam_stop[0] > 0.0, lam_stop[1] > 0.0)
    response, coupling = np.zeros((max(mc, 1), N_RESPONSE)), np.zeros((max(mc, 1), max(mc, 1)))
    if not (g.shape[0] == mc and patch_response(g, mn, mc, normals, points, fingers, count,
                                                cons, weights, xc, yc, s[S_JOINT_OFFSET],
                                                s[S_TORSION], locked, r, force_unit, response,
                                                coupling)):
        mc = 0  # the forces as solved
    # the centre carries what the contacts leave unbalanced
    loaded_holding(normals, points, forces, patches, (cons, weights, response, coupling), mn,
                   mc, count, xc, yc, r, -fx, -fy, -moment, payload, load_set, half_width, out)
    return count


def loaded_contacts(scene_row: np.ndarray, prm_row: np.ndarray, n: int, x: np.ndarray,
                    lam_face: np.ndarray, lam_corner: np.ndarray, lam_stop: np.ndarray,
                    payload_n: float = 0.0, load_set: int = 2) -> dict:
    """:func:`holding_one` of one scaled answer as plain arrays (tests, scripts): the contact
    list (``normals``, ``points`` [m], ``forces`` [N], ``fingers``, ``patches``), its loaded
    grasp (``model``, a :class:`envs.model.loads.Response`) and each contact's linear
    ``response`` (k, N_RESPONSE: its normal force's change per unit load on the freed object,
    a force along x, y [N/N] and a moment [N/(N·m)], before any contact is released), and the
    holding ``row``."""
    from ..model.holding import N_HOLD
    from ..model.loads import Response
    from ..model.rings import kernel_copy, mesh_band_index
    from .loaded import response_work

    k = max_contacts(n)
    prm_row = np.ascontiguousarray(prm_row, dtype=np.float64)
    scene_row = np.ascontiguousarray(scene_row, dtype=np.float64)
    x = np.ascontiguousarray(x, dtype=np.float64)
    kprm = kernel_copy(prm_row, n)
    normals, points, forces = np.zeros((k, 2)), np.zeros((k, 2)), np.zeros(k)
    fingers, patches = np.zeros(k, dtype=np.int64), np.zeros(k, dtype=np.int64)
    nodes, share = np.zeros((k, 2), dtype=np.int64), np.zeros(k)
    groups, cons, weights = (np.zeros((k, 2), dtype=np.int64),
                             np.zeros((k, 2), dtype=np.int64), np.zeros((k, 2)))
    row = np.empty(N_HOLD)
    bidx = mesh_band_index(n, int(prm_row[P_RINGS]))
    work = response_work(n, kprm)
    count = holding_one(
        scene_row, prm_row, kprm, n, x, np.ascontiguousarray(lam_face),
        np.ascontiguousarray(lam_corner), np.ascontiguousarray(lam_stop, dtype=np.float64),
        float(payload_n), int(load_set), bidx, work, np.empty(5), np.empty((5, 5)), normals,
        points, forces, patches, nodes, share, fingers, groups, cons, weights, row)
    # the loaded grasp again, kept (holding_one keeps only its row)
    r, unit = scene_row[S_RADIUS], stiffness_unit(scene_row) * scene_row[S_RADIUS]
    mn, mc = patch_constraints(normals, points, forces, patches, nodes, fingers, count, r,
                               groups, cons, weights)
    g = contact_compliance(kprm, n, x, bidx, work, nodes, share, normals, count, cons,
                           weights, mc, r, unit)
    response, coupling = np.zeros((max(mc, 1), N_RESPONSE)), np.zeros((max(mc, 1), max(mc, 1)))
    ok = g.shape[0] == mc and patch_response(
        g, mn, mc, normals, points, fingers, count, cons, weights, scene_row[S_OFFSET_X],
        scene_centre_y_m(scene_row), scene_row[S_JOINT_OFFSET], scene_row[S_TORSION],
        (lam_stop[0] > 0.0, lam_stop[1] > 0.0), r, unit, response, coupling)
    model = Response(cons[:count].copy(), weights[:count].copy(), mn, mc if ok else 0,
                     response, coupling)
    linear = np.zeros((count, N_RESPONSE))
    for i in range(count):
        if ok and cons[i, 0] >= 0:
            linear[i] = weights[i, 0] * response[cons[i, 0]]
    return {"normals": normals[:count], "points": points[:count], "forces": forces[:count],
            "fingers": fingers[:count], "patches": patches[:count], "model": model,
            "response": linear, "row": row}
