"""Holding: what the fixed centre of the object carries, and the friction that could carry it.

The model fixes the object's centre ``C`` (the fan's pin; the ring meshes' and the FEM's rigid
hub). At a frictionless equilibrium the contacts push the object with a net force and moment;
the centre carries the rest, the *pin reaction*: a force ``F`` (x, y in the gripper frame) and,
for a hub, a moment ``M`` about ``C``. A free object in inclined jaws would be pushed out by it.

With Coulomb friction ``mu``, each contact ``i`` (normal force ``N_i`` on the object, unit
normal ``nu_i``, at the point ``p_i``) may also carry a tangential force ``t_i`` along its
tangent ``tau_i`` (perpendicular to ``nu_i``: along the finger axis on a finger face), with
``|t_i| <= mu N_i``. The grasp holds the object without the pin when tangential forces within
these cones carry the reaction instead::

    sum_i t_i tau_i = F,     sum_i t_i (p_i - C) x tau_i = M,     |t_i| <= mu N_i.

The *required friction* is the smallest such ``mu``: 0 when nothing is carried, infinite when
no tangential forces can carry it (one finger touching: its tangent cannot balance its own
normal force). It is the gauge of ``b = (F, M / L)`` with respect to the zonotope ``Z = {sum_i
s_i g_i : |s_i| <= 1}`` of the generators ``g_i = N_i (tau_i, m_i / L)``, ``m_i = (p_i - C) x
tau_i`` and ``L`` a length scale (the gauge does not depend on it; it only balances the
numbers). By linear-programming duality ``mu = max_u (u . b) / sum_i |u . g_i|`` over the
facet normals ``u`` of ``Z`` in the span of the generators, a closed form over pairs of
generators; ``b`` outside that span needs infinite friction.

Closed form for a symmetric grasp on the two gripping faces at finger angle ``theta``: the
faces push the object away from the joints with ``(N_R + N_L) sin theta``, and the tangential
forces along the finger axes can hold it with ``mu = tan theta``.

One implementation for both fidelities: :mod:`envs.solver.reaction` (the point-spring model's
contacts, in the solver's own contact geometry) and :mod:`envs.fem.grasp` (the FEM's rim nodes
and tip corners) build the contact list and call :func:`required_friction`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "H_PIN_X",
    "H_PIN_Y",
    "H_PIN_MOMENT",
    "H_MU",
    "N_HOLD",
    "SPAN_TOL",
    "required_friction",
    "holding_of_contacts",
]

# layout of a holding row: the pin force on the object (x, y) [N], its moment about the centre
# [N·m] (the hub's; ~0 for a pin, which carries none) and the required friction [-]
H_PIN_X, H_PIN_Y, H_PIN_MOMENT, H_MU = range(4)
N_HOLD = 4
# a reaction whose part outside the span of the contacts' tangential forces is below this share
# of the total normal force counts as inside it: the equilibria are solved to ~1e-8 (the
# point-spring model) and ~1e-6 (the FEM's Newton), while a reaction no friction can carry (one
# finger touching) lies outside by a share of order 1
SPAN_TOL = 1e-5
_PARALLEL = 1e-12  # generators this close to parallel (sine of their angle) are merged


@njit(cache=True, error_model="numpy", _nrt=False)
def _merge(gens, count):
    """Merge parallel generators in place (their segments add up to one longer segment: the
    same zonotope); returns the new count. Collinear contacts on a finger face are one."""
    m = 0
    for a in range(count):
        ax, ay, az = gens[a, 0], gens[a, 1], gens[a, 2]
        na = math.sqrt(ax * ax + ay * ay + az * az)
        if na == 0.0:
            continue
        merged = False
        for b in range(m):
            bx, by, bz = gens[b, 0], gens[b, 1], gens[b, 2]
            nb = math.sqrt(bx * bx + by * by + bz * bz)
            cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
            if math.sqrt(cx * cx + cy * cy + cz * cz) <= _PARALLEL * na * nb:
                sign = 1.0 if ax * bx + ay * by + az * bz >= 0.0 else -1.0
                gens[b, 0] = bx + sign * ax
                gens[b, 1] = by + sign * ay
                gens[b, 2] = bz + sign * az
                merged = True
                break
        if not merged:
            gens[m, 0], gens[m, 1], gens[m, 2] = ax, ay, az
            m += 1
    return m


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _support(gens, count, ux, uy, uz):
    """Support function of the zonotope, ``sum_i |u . g_i|``."""
    h = 0.0
    for i in range(count):
        h += abs(ux * gens[i, 0] + uy * gens[i, 1] + uz * gens[i, 2])
    return h


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _ratio(gens, count, ux, uy, uz, bx, by, bz):
    """``|u . b| / h(u)`` (inf where h vanishes and u . b does not)."""
    ub = abs(ux * bx + uy * by + uz * bz)
    h = _support(gens, count, ux, uy, uz)
    if h > 0.0:
        return ub / h
    return math.inf if ub > 0.0 else 0.0


@njit(cache=True, error_model="numpy", _nrt=False)
def required_friction(gens, count, bx, by, bz, tol):
    """The smallest Coulomb coefficient whose cones carry ``b`` (see the module docstring).

    Parameters
    ----------
    gens
        Generators ``N_i (tau_i, m_i / L)``, (>= count, 3); overwritten (merged).
    count
        Generators in use.
    bx, by, bz
        The reaction to carry: force x, y and moment / L.
    tol
        Absolute tolerance of "inside the span" (the force scale times :data:`SPAN_TOL`).

    Returns
    -------
    float
        0 for ``b = 0``, ``inf`` when ``b`` lies outside the span of the generators.
    """
    if bx == 0.0 and by == 0.0 and bz == 0.0:
        return 0.0
    m = _merge(gens, count)
    bnorm = math.sqrt(bx * bx + by * by + bz * bz)
    if m == 0:
        return 0.0 if bnorm <= tol else math.inf
    # the span: a plane normal (rank 2) or full space (rank 3) from the pairs' cross products
    best_pair = -1.0
    px = py = pz = 0.0
    for a in range(m):
        for c in range(a + 1, m):
            cx = gens[a, 1] * gens[c, 2] - gens[a, 2] * gens[c, 1]
            cy = gens[a, 2] * gens[c, 0] - gens[a, 0] * gens[c, 2]
            cz = gens[a, 0] * gens[c, 1] - gens[a, 1] * gens[c, 0]
            size = math.sqrt(cx * cx + cy * cy + cz * cz)
            if size > best_pair:
                best_pair, px, py, pz = size, cx, cy, cz
    rank3 = False
    if best_pair > 0.0:
        inv = 1.0 / best_pair
        px, py, pz = px * inv, py * inv, pz * inv
        for c in range(m):
            gn = math.sqrt(gens[c, 0] ** 2 + gens[c, 1] ** 2 + gens[c, 2] ** 2)
            if abs(px * gens[c, 0] + py * gens[c, 1] + pz * gens[c, 2]) > 1e-9 * gn:
                rank3 = True
                break
    mu = 0.0
    if rank3:
        for a in range(m):
            for c in range(a + 1, m):
                ux = gens[a, 1] * gens[c, 2] - gens[a, 2] * gens[c, 1]
                uy = gens[a, 2] * gens[c, 0] - gens[a, 0] * gens[c, 2]
                uz = gens[a, 0] * gens[c, 1] - gens[a, 1] * gens[c, 0]
                if ux == 0.0 and uy == 0.0 and uz == 0.0:
                    continue
                mu = max(mu, _ratio(gens, m, ux, uy, uz, bx, by, bz))
        return mu
    if best_pair > 0.0:
        # rank 2: b must lie in the plane (normal p); in it, the facet normals are p x g_i
        if abs(px * bx + py * by + pz * bz) > tol:
            return math.inf
        for a in range(m):
            ux = py * gens[a, 2] - pz * gens[a, 1]
            uy = pz * gens[a, 0] - px * gens[a, 2]
            uz = px * gens[a, 1] - py * gens[a, 0]
            mu = max(mu, _ratio(gens, m, ux, uy, uz, bx, by, bz))
        return mu
    # rank 1: b must be parallel to the one direction
    gx, gy, gz = gens[0, 0], gens[0, 1], gens[0, 2]
    gn = math.sqrt(gx * gx + gy * gy + gz * gz)
    along = (bx * gx + by * gy + bz * gz) / gn
    off = math.sqrt(max(0.0, bnorm * bnorm - along * along))
    if off > tol:
        return math.inf
    return abs(along) / _support(gens, m, gx / gn, gy / gn, gz / gn)


@njit(cache=True, error_model="numpy", _nrt=False)
def holding_of_contacts(normals, points, forces, count, centre_x, centre_y, length_scale,
                        pin_x, pin_y, pin_moment, gens, out):
    """The holding row of a contact list and a pin reaction.

    Parameters
    ----------
    normals, points, forces
        Contact ``i < count``: unit normal on the object (2,), the point where a tangential
        force would act [m] (2,), and its normal force [N] (>= 0; zero forces are skipped).
    centre_x, centre_y
        The fixed centre ``C`` [m].
    length_scale
        ``L`` [m] of the moment row (the object's radius).
    pin_x, pin_y, pin_moment
        The reaction of the fixed centre on the object [N, N, N·m].
    gens
        Scratch, (>= count, 3).
    out
        The holding row (layout ``H_*``), written.
    """
    total = 0.0
    m = 0
    for i in range(count):
        f = forces[i]
        if not f > 0.0:
            continue
        total += f
        tx, ty = -normals[i, 1], normals[i, 0]
        arm = (points[i, 0] - centre_x) * ty - (points[i, 1] - centre_y) * tx
        gens[m, 0] = f * tx
        gens[m, 1] = f * ty
        gens[m, 2] = f * arm / length_scale
        m += 1
    out[H_PIN_X] = pin_x
    out[H_PIN_Y] = pin_y
    out[H_PIN_MOMENT] = pin_moment
    scale = max(total, math.sqrt(pin_x * pin_x + pin_y * pin_y))
    out[H_MU] = required_friction(gens, m, pin_x, pin_y, pin_moment / length_scale,
                                  SPAN_TOL * scale)


def holding_row(normals, points, forces, centre_m, length_scale_m, pin_force_n,
                pin_moment_nm) -> np.ndarray:
    """:func:`holding_of_contacts` of plain arrays (the FEM's contact list), a row (N_HOLD,)."""
    normals = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 2)
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    forces = np.ascontiguousarray(forces, dtype=np.float64).reshape(-1)
    count = forces.size
    gens = np.zeros((max(count, 1), 3))
    out = np.empty(N_HOLD)
    holding_of_contacts(normals, points, forces, count, float(centre_m[0]), float(centre_m[1]),
                        float(length_scale_m), float(pin_force_n[0]), float(pin_force_n[1]),
                        float(pin_moment_nm), gens, out)
    return out
