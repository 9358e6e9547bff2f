"""The FEM's loaded grasp: its compliance at the contacts, and the holding row over a load set.

The same patch-level model of the loaded grasp as the point-spring model's
(:mod:`envs.model.loads`): the object moves rigidly and deforms with its own compliance, the
fingers turn against their springs, each normal group and each pressure patch sticks, rolling
is free. What is the FEM's own is the compliance: the body's tangent stiffness at the solved
grasp (its elastic part, the hub held), solved for a unit force along each constraint shared by
the constraint's contacts in proportion to their forces (a contact's own force by the rim nodes
it acts on, :meth:`envs.fem.system._System.contact_list`'s carriers).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from envs.model.holding import N_HOLD
from envs.model.loads import (
    N_RESPONSE,
    load_set_code,
    loaded_holding,
    patch_constraints,
    patch_response,
)

__all__ = ["fem_holding"]


def _compliance(body, rim, free_body: np.ndarray, x_body: np.ndarray, carriers: list,
                normals: np.ndarray, cons: np.ndarray, weights: np.ndarray, mc: int
                ) -> np.ndarray | None:
    """``G`` [m/N] between the constraints (``None`` where the body's tangent cannot be
    factored): ``A^T K^-1 A`` over the body's free dofs, column c of ``A`` a unit force along
    constraint c."""
    out = body.evaluate(x_body)
    if out is None:
        return None
    k_ff = out[2][free_body][:, free_body].tocsc()
    place = np.full(body.n, -1)
    place[free_body] = np.arange(free_body.size)
    a = np.zeros((free_body.size, mc))
    for i, (_, nodes, shares) in enumerate(carriers):
        for kind in range(2):
            c = cons[i, kind]
            if c < 0:
                continue
            d = (np.array([-normals[i, 1], normals[i, 0]]) if kind == 1 else normals[i])
            for node, share in zip(nodes, shares, strict=True):
                rows = place[rim.dofs[node]]
                a[rows, c] += weights[i, kind] * share * d
    try:
        sol = spla.splu(k_ff).solve(a)
    except RuntimeError:  # a singular factor
        return None
    g = a.T @ sol
    return 0.5 * (g + g.T)


def fem_holding(system, body, rim, x: np.ndarray, load: float, centre: np.ndarray,
                radius_m: float, joint_offset_m: float, torsion_nm_per_rad: float,
                locked: tuple[bool, bool], payload_n: float, load_set: str,
                half_width: float, force_scale_n: float) -> np.ndarray:
    """The FEM grasp's holding row (layout ``H_*``): the hub's reaction, then the free
    object's grasp over the load set (:func:`envs.model.loads.loaded_holding`, the normal
    forces moved by the patch-level model with the FEM's compliance).

    Parameters
    ----------
    system, body, rim
        The solved grasp's :class:`~envs.fem.system._System`, its body and rim.
    x, load
        The converged state and torque.
    centre, radius_m
        The disk's centre (the hub) [m] and radius [m].
    joint_offset_m, torsion_nm_per_rad, locked
        ``d_3``, ``k_f`` and whether each finger is on its closed stop.
    payload_n, load_set
        The payload [N] and the load set's name.
    half_width
        The contact patches' ``c`` [m N^-1/2].
    force_scale_n
        A force [N] that scales the patch-level system (``E t r``).
    """
    carriers: list = []
    normals, points, forces, net, moment, patches = system.contact_list(
        x, load, with_patches=True, carriers=carriers)
    # the hub carries what the contacts leave unbalanced (moment about the disk's centre)
    moment_c = moment - (centre[0] * net[1] - centre[1] * net[0])
    count = forces.size
    rows = max(count, 1)
    groups = np.zeros((rows, 2), dtype=np.int64)
    cons = np.zeros((rows, 2), dtype=np.int64)
    weights = np.zeros((rows, 2))
    normals = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 2)
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    forces = np.ascontiguousarray(forces, dtype=np.float64)
    patches = np.ascontiguousarray(patches, dtype=np.int64)
    fingers = np.array([c[0] for c in carriers], dtype=np.int64).reshape(-1)
    # each contact's two main rim nodes (a corner's by its share)
    nodes = np.full((rows, 2), -1, dtype=np.int64)
    for i, (_, on, shares) in enumerate(carriers):
        main = on[np.argsort(-shares, kind="stable")[:2]]
        nodes[i, : main.size] = main
    mn, mc = patch_constraints(normals, points, forces, patches, nodes,
                               np.resize(fingers, rows), count, radius_m, groups, cons,
                               weights)
    response, coupling = np.zeros((max(mc, 1), N_RESPONSE)), np.zeros((max(mc, 1), max(mc, 1)))
    n_free = system.free[system.free < body.n]
    g = _compliance(body, rim, n_free, x[: body.n], carriers, normals, cons, weights, mc)
    if not (g is not None and count and patch_response(
            np.ascontiguousarray(g), mn, mc, normals, points, np.resize(fingers, rows), count,
            cons, weights, float(centre[0]), float(centre[1]), float(joint_offset_m),
            float(torsion_nm_per_rad), locked, float(radius_m), float(force_scale_n), response,
            coupling)):
        mc = 0  # the forces as solved
    out = np.empty(N_HOLD)
    loaded_holding(normals, points, forces, patches, (cons, weights, response, coupling), mn,
                   mc, count, float(centre[0]), float(centre[1]), float(radius_m),
                   float(-net[0]), float(-net[1]), float(-moment_c), float(payload_n),
                   load_set_code(load_set), float(half_width), out)
    return out
