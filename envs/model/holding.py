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

The normal forces are those of the solved grasp, with one freedom a free object has: on a face
pressed at several points, the pressure may shift between them (their total fixed), which moves
the face's normal force along the face and changes its moment about ``C`` within ``N_f [c_min -
c, c_max - c]`` (``c`` the moment arm of the face's resultant, ``c_min``, ``c_max`` those of its
outermost contact points). Without it, the two faces' tangential forces could balance the
reaction's force but, in general, not its moment too, and a grasp turned a hair off its mirror
symmetry would need infinite friction; with it, the required friction changes continuously with
the grasp.

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
def _span(gens, m):
    """Rank of the merged generators and, for rank 2, the unit normal of their plane (for
    rank 1: the unit direction)."""
    best = -1.0
    px = py = pz = 0.0
    for a in range(m):
        for c in range(a + 1, m):
            cx = gens[a, 1] * gens[c, 2] - gens[a, 2] * gens[c, 1]
            cy = gens[a, 2] * gens[c, 0] - gens[a, 0] * gens[c, 2]
            cz = gens[a, 0] * gens[c, 1] - gens[a, 1] * gens[c, 0]
            size = math.sqrt(cx * cx + cy * cy + cz * cz)
            if size > best:
                best, px, py, pz = size, cx, cy, cz
    if best > 0.0:
        px, py, pz = px / best, py / best, pz / best
        for c in range(m):
            gn = math.sqrt(gens[c, 0] ** 2 + gens[c, 1] ** 2 + gens[c, 2] ** 2)
            if abs(px * gens[c, 0] + py * gens[c, 1] + pz * gens[c, 2]) > 1e-9 * gn:
                return 3, 0.0, 0.0, 0.0
        return 2, px, py, pz
    if m == 0:
        return 0, 0.0, 0.0, 0.0
    gn = math.sqrt(gens[0, 0] ** 2 + gens[0, 1] ** 2 + gens[0, 2] ** 2)
    return 1, gens[0, 0] / gn, gens[0, 1] / gn, gens[0, 2] / gn


@njit(cache=True, error_model="numpy", _nrt=False)
def _gauge_full(gens, m, bx, by, bz):
    """The gauge of b for a full-rank zonotope: the largest ratio over its facet normals."""
    mu = 0.0
    for a in range(m):
        for c in range(a + 1, m):
            ux = gens[a, 1] * gens[c, 2] - gens[a, 2] * gens[c, 1]
            uy = gens[a, 2] * gens[c, 0] - gens[a, 0] * gens[c, 2]
            uz = gens[a, 0] * gens[c, 1] - gens[a, 1] * gens[c, 0]
            if ux == 0.0 and uy == 0.0 and uz == 0.0:
                continue
            mu = max(mu, _ratio(gens, m, ux, uy, uz, bx, by, bz))
    return mu


@njit(cache=True, error_model="numpy", _nrt=False)
def _gauge_plane(gens, m, px, py, pz, bx, by, bz):
    """The gauge of b (in the plane of normal p) for a zonotope of rank 2: its facet normals in
    the plane are p x g_a."""
    mu = 0.0
    for a in range(m):
        ux = py * gens[a, 2] - pz * gens[a, 1]
        uy = pz * gens[a, 0] - px * gens[a, 2]
        uz = px * gens[a, 1] - py * gens[a, 0]
        mu = max(mu, _ratio(gens, m, ux, uy, uz, bx, by, bz))
    return mu


_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)
_SEARCH_STEPS = 60  # golden-section steps: the interval shrinks by 0.618^60 ~ 3e-13


@njit(cache=True, error_model="numpy", _nrt=False)
def _least_over_z(gens, m, plane, px, py, pz, bx, by, zlo, zhi):
    """The least gauge of (bx, by, z) over z in [zlo, zhi]: a convex piecewise-linear function
    of z (a maximum of |linear| terms), found by golden-section search."""
    a, b = zlo, zhi
    for _ in range(_SEARCH_STEPS):
        if b - a <= 1e-15 * (1.0 + abs(a) + abs(b)):
            break
        z1 = b - _GOLDEN * (b - a)
        z2 = a + _GOLDEN * (b - a)
        if plane:
            f1 = _gauge_plane(gens, m, px, py, pz, bx, by, z1)
            f2 = _gauge_plane(gens, m, px, py, pz, bx, by, z2)
        else:
            f1 = _gauge_full(gens, m, bx, by, z1)
            f2 = _gauge_full(gens, m, bx, by, z2)
        if f1 <= f2:
            b = z2
        else:
            a = z1
    z = 0.5 * (a + b)
    if plane:
        return _gauge_plane(gens, m, px, py, pz, bx, by, z)
    return _gauge_full(gens, m, bx, by, z)


@njit(cache=True, error_model="numpy", _nrt=False)
def required_friction(gens, count, bx, by, zlo, zhi, tol):
    """The smallest Coulomb coefficient whose cones carry the force ``(bx, by)`` and a moment
    (over the length scale) anywhere in ``[zlo, zhi]`` (see the module docstring).

    Parameters
    ----------
    gens
        Generators ``N_i (tau_i, m_i / L)``, (>= count, 3); overwritten (merged).
    count
        Generators in use.
    bx, by
        The force to carry.
    zlo, zhi
        The range of the moment / L the tangential forces must carry (a point where the
        pressure cannot shift).
    tol
        Absolute tolerance of "inside the span" (the force scale times :data:`SPAN_TOL`).

    Returns
    -------
    float
        0 when nothing needs carrying, ``inf`` when no tangential forces can carry it.
    """
    if bx == 0.0 and by == 0.0 and zlo <= 0.0 <= zhi:
        return 0.0
    m = _merge(gens, count)
    rank, px, py, pz = _span(gens, m)
    if rank == 3:
        return _least_over_z(gens, m, False, 0.0, 0.0, 0.0, bx, by, zlo, zhi)
    if rank == 2:
        if abs(pz) > 1e-9:
            # the moment that puts b in the plane of the generators: within reach?
            z = -(px * bx + py * by) / pz
            if z < zlo - tol or z > zhi + tol:
                return math.inf
            return _gauge_plane(gens, m, px, py, pz, bx, by, z)
        if abs(px * bx + py * by) > tol:
            return math.inf
        return _least_over_z(gens, m, True, px, py, pz, bx, by, zlo, zhi)
    if rank == 1:
        # one tangent direction: the force must lie along it, the moment follow with it
        gxy2 = gens[0, 0] ** 2 + gens[0, 1] ** 2
        if not gxy2 > 0.0 or abs(bx * gens[0, 1] - by * gens[0, 0]) > tol * math.sqrt(gxy2):
            return math.inf
        along = (bx * gens[0, 0] + by * gens[0, 1]) / gxy2
        z = along * gens[0, 2]
        if z < zlo - tol or z > zhi + tol:
            return math.inf
        return abs(along)
    return 0.0 if (math.hypot(bx, by) <= tol and zlo - tol <= 0.0 <= zhi + tol) else math.inf


@njit(cache=True, error_model="numpy", _nrt=False)
def _pressure_shift(normals, points, forces, count, centre_x, centre_y, length_scale):
    """How far the normal forces' moment about the centre can change [N·m] when the pressure
    on each face shifts between its contact points, total fixed: (low <= 0, high >= 0).

    A face is the contacts of one normal on one line (a finger's gripping face; a corner is a
    face of one point, with no shift)."""
    low = high = 0.0
    tol = 1e-9 * length_scale
    for i in range(count):
        if not forces[i] > 0.0:
            continue
        leader = True
        for j in range(i):
            if forces[j] > 0.0 and _same_face(normals, points, i, j, tol):
                leader = False
                break
        if not leader:
            continue
        total = moment = 0.0
        c_min, c_max = math.inf, -math.inf
        for k in range(i, count):
            if forces[k] > 0.0 and (k == i or _same_face(normals, points, i, k, tol)):
                c = ((points[k, 0] - centre_x) * normals[k, 1]
                     - (points[k, 1] - centre_y) * normals[k, 0])
                total += forces[k]
                moment += forces[k] * c
                c_min = min(c_min, c)
                c_max = max(c_max, c)
        c_mean = moment / total
        low += total * (c_min - c_mean)
        high += total * (c_max - c_mean)
    return min(low, 0.0), max(high, 0.0)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _same_face(normals, points, i, j, tol):
    """Contacts i and j share a normal and lie on one line across it."""
    if abs(normals[i, 0] - normals[j, 0]) > 1e-9 or abs(normals[i, 1] - normals[j, 1]) > 1e-9:
        return False
    return abs((points[i, 0] - points[j, 0]) * normals[i, 0]
               + (points[i, 1] - points[j, 1]) * normals[i, 1]) <= tol


@njit(cache=True, error_model="numpy", _nrt=False)
def holding_of_contacts(normals, points, forces, count, centre_x, centre_y, length_scale,
                        pin_x, pin_y, pin_moment, gens, out):
    """The holding row of a contact list and a pin reaction.

    Parameters
    ----------
    normals, points, forces
        Contact ``i < count``: unit normal on the object (2,), the point where it acts [m]
        (2,), and its normal force [N] (>= 0; zero forces are skipped).
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
    low, high = _pressure_shift(normals, points, forces, count, centre_x, centre_y,
                                length_scale)
    scale = max(total, math.sqrt(pin_x * pin_x + pin_y * pin_y))
    # the tangential forces carry the pin's moment less what the shifted pressure takes over
    out[H_MU] = required_friction(gens, m, pin_x, pin_y, (pin_moment - high) / length_scale,
                                  (pin_moment - low) / length_scale, SPAN_TOL * scale)


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
