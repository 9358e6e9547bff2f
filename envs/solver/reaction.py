"""The pin reaction and the required friction of a solved point-spring grasp.

Each contact force of the solver is its multiplier times the gradient of its gap
(:mod:`envs.solver.contact`): on a contour point for a face contact (the rounded finger bar:
the gripping face, its ends, its back), on the two end points of a contour edge for a corner.
The gradient's direction is the contact's normal, so the contact list and the net force and
moment on the object come from the solver's own contact geometry, written once. The fixed
centre carries what they leave unbalanced (:mod:`envs.model.holding`).

Jaw grooves need nothing more: a face contact's normal is its gap's gradient on the grooved
finger too (:func:`envs.model.jaw.jaw_gap`), and a groove's two mouth edges are corners like
the bar's ends. The pressure shift of :func:`envs.model.holding.holding_of_contacts` groups a
straight finger's contacts that share a normal and a line across it as one face; on a grooved
finger a run of consecutive pressed contour points (with a mouth edge pressing an edge of the
run) is one patch, the rule the FEM applies to its runs of rim nodes.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model.holding import NO_PATCH, hertz_half_width, holding_of_contacts
from ..model.layout import (
    N_BAR_CORNERS,
    N_CORNERS,
    S_OFFSET_X,
    S_POISSON,
    S_RADIUS,
    S_SCALE,
    S_THICKNESS,
    S_YOUNG,
)
from ..model.problem import scene_centre_y_m, stiffness_unit
from .contact import _corner_eval, _face_eval, _grooved, _sel, _trig

__all__ = ["max_contacts", "holding_one"]


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


@njit(cache=True, error_model="numpy", _nrt=False)
def holding_one(s, prm, n, x, lam_face, lam_corner, payload, grad5, hess5, normals, points,
                forces, patches, gens, out):
    """The holding row (layout ``H_*`` of :mod:`envs.model.holding`) of one scaled answer.

    Parameters
    ----------
    s, prm, n
        The scene row (SI), its packed parameters and N.
    x, lam_face, lam_corner
        The scaled state and the face (2, N) and corner (2, N_CORNERS, N) multipliers.
    payload
        The payload ``W`` [N] the grasp must carry in every direction of the load set
        (:mod:`envs.model.holding`), >= 0.
    grad5, hess5, normals, points, forces, patches, gens
        Scratch: (5,), (5, 5), and (max_contacts(n), 2 / 2 / - / - (int) / 3).
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
    # np.int64, not a literal 0 (see holding_of_contacts: one compilation of it, not two)
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
                count += 1
    # the centre carries what the contacts leave unbalanced
    # the faces' contact patches with the solved model's stiffness (its scale times E)
    half_width = hertz_half_width(r, s[S_THICKNESS], s[S_SCALE] * s[S_YOUNG], s[S_POISSON])
    holding_of_contacts(normals, points, forces, patches, count, xc, yc, r, -fx, -fy, -moment,
                        payload, half_width, gens, out)
    return count
