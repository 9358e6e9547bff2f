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

The normal forces are those given (the freed object's loaded ones, :mod:`envs.model.loads`),
with one freedom a free object has: on a face,
the pressure may shift within its contact patch (its total fixed), which moves the face's normal
force along the face and changes its moment about ``C`` within ``N_f [-a, a]``, ``a`` the
patch's half-width, the Hertz line contact of the face's force (:func:`hertz_half_width`: the
physical width, the same at every mesh and at both fidelities, continuous as a contact is
pressed or released). Without it, the two faces' tangential forces could balance the reaction's
force but, in general, not its moment too, and a grasp turned a hair off its mirror symmetry, or
an object placed off the axis, would need infinite friction; with it, the required friction
changes continuously with the grasp. A corner's patch is given the same width (an upper bound:
the rounded corner is more curved than a face). On a grooved jaw a patch is a *run* of contacts
along the object's contour (a cradle's arc, a flank, the rounded mouth edge beside them), one
patch of the run's total force however many nodes the mesh puts in it, the same rule at both
fidelities; the contacts of a run that share a normal (a flat flank) are one generator.

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

The freed object's loaded grasp (:mod:`envs.model.loads`) moves the normal forces under each
load and calls these kernels on them; :func:`envs.model.loads.holding_row` keeps them as
solved (the former rule, a bound). One implementation for both fidelities:
:mod:`envs.solver.reaction` (the point-spring model's contacts, in the solver's own contact
geometry) and :mod:`envs.fem.loaded` (the FEM's
rim nodes and tip corners) build the contact list.
"""

from __future__ import annotations

import math

from numba import njit

from .contact_width import hertz_arc_coefficient

__all__ = [
    "H_PIN_X",
    "H_PIN_Y",
    "H_PIN_MOMENT",
    "H_MU",
    "H_PAYLOAD",
    "H_GRIP",
    "H_LIMIT",
    "H_LIMIT_ANGLE",
    "N_HOLD",
    "LIMIT_NONE",
    "LIMIT_REACTION",
    "LIMIT_OUT_OF_PLANE",
    "LIMIT_IN_PLANE",
    "LIMIT_NAMES",
    "SPAN_TOL",
    "NO_PATCH",
    "in_plane_friction",
    "lift_friction",
    "HOLDING_SCALARS",
    "holding_fields",
]

# layout of a holding row: the pin force on the object (x, y) [N], its moment about the centre
# [N·m] (the hub's; ~0 for a pin, which carries none), the required friction over the whole
# load set [-], the payload W it includes [N], the grip (the sum of the contacts' normal
# forces) [N], the code of the load that sets the required friction (LIMIT_*) and, for an
# in-plane payload, the direction of its pull on the object [rad from +x, gripper frame]
H_PIN_X, H_PIN_Y, H_PIN_MOMENT, H_MU, H_PAYLOAD, H_GRIP, H_LIMIT, H_LIMIT_ANGLE = range(8)
N_HOLD = 8
# what sets the required friction: nothing (0 needed), the reaction of the fixed centre alone
# (no payload, or a reaction no friction can carry), the payload out of the plane (the object
# hanging from a horizontal grasp), the payload in the plane (pulling along H_LIMIT_ANGLE)
LIMIT_NONE, LIMIT_REACTION, LIMIT_OUT_OF_PLANE, LIMIT_IN_PLANE = range(4)
LIMIT_NAMES = ("none", "reaction", "out of plane", "in plane")
# a reaction whose part outside the span of the contacts' tangential forces is below this share
# of the total normal force counts as inside it: the equilibria are solved to ~1e-8 (the
# point-spring model) and ~1e-6 (the FEM's Newton), while a reaction no friction can carry (one
# finger touching) lies outside by a share of order 1
SPAN_TOL = 1e-5
# the patch label of a contact that the flat-face rule groups (one normal on one line): a
# straight finger's contacts and the bar's corners (envs.model.holding._pressure_shift)
NO_PATCH = -1
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


_FLAT = 1e-9  # a facet normal along which the generators extend less (of their total) is flat


@njit(cache=True, error_model="numpy", _nrt=False)
def _facet(gens, m, ux, uy, uz, cx, cy, cz, shift, weight, tol, hscale):
    """The friction one direction ``u`` asks for (see :func:`in_plane_friction`): ``(|u . c| +
    W |u_xy| - h_E |u_z|) / h_Z(u)`` for the unit ``u``; 0 where the load set's support does
    not exceed the shift's, ``inf`` where the zonotope has no extent along ``u``."""
    size = math.sqrt(ux * ux + uy * uy + uz * uz)
    if size == 0.0:
        return 0.0
    ux, uy, uz = ux / size, uy / size, uz / size
    need = abs(ux * cx + uy * cy + uz * cz) + weight * math.hypot(ux, uy) - shift * abs(uz)
    if need <= 0.0:
        return 0.0
    h = _support(gens, m, ux, uy, uz)
    if h > _FLAT * hscale:
        return need / h
    return math.inf if need > tol else 0.0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _off_plane(px, py, pz, cx, cy, cz, weight):
    """How far the load set (centre c, the in-plane disc of radius W) reaches off the plane
    through the origin of unit normal p."""
    return abs(px * cx + py * cy + pz * cz) + weight * math.hypot(px, py)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _generator(gens, m, a):
    """Generator ``a`` of the merged list, or for ``a == m`` the shift's axis e_z."""
    if a < m:
        return gens[a, 0], gens[a, 1], gens[a, 2]
    return 0.0, 0.0, 1.0


@njit(cache=True, error_model="numpy", _nrt=False)
def in_plane_friction(gens, m, cx, cy, cz, shift, weight, tol):
    """The smallest Coulomb coefficient whose in-plane cones carry a load set: the centre ``c
    = (F_x, F_y, z_c)`` (the reaction's force, and its moment over L at the middle of the
    pressure shift's reach ``z_c +- shift``), plus ``weight`` in every in-plane direction.

    The loads ``c + W D`` (D the unit disc of in-plane forces) lie in ``mu Z + [-h_E, h_E]
    e_z`` (Z the zonotope of the merged generators; the segment is the pressure shift, which
    does not grow with mu) exactly when, for every facet normal ``u`` of that sum (the cross
    products of two generators, or of a generator and ``e_z``), ``|u . c| + W |u_xy| <= mu
    h_Z(u) + h_E |u_z|``: a closed form, with no search over the direction or the moment, and
    the moment chosen for each direction on its own.

    Parameters
    ----------
    gens, m
        Merged generators (:func:`_merge`) and their count.
    cx, cy, cz, shift, weight
        The load set (see above) [N].
    tol
        Absolute tolerance of "inside the span" [N].

    Returns
    -------
    tuple
        ``(mu, ux, uy, uz)``: 0 when nothing needs carrying, ``inf`` when no friction can,
        and the unit facet normal that sets it (zeros when none does).
    """
    hscale = 0.0
    for i in range(m):
        hscale += math.sqrt(gens[i, 0] ** 2 + gens[i, 1] ** 2 + gens[i, 2] ** 2)
    axis = 1 if shift > 0.0 else 0
    rank, px, py, pz = _span(gens, m)
    # the rank and plane of the generators with the shift's axis e_z among them
    if axis and (rank == 0 or (rank == 2 and abs(pz) > 1e-9)):
        rank += 1
        px, py, pz = 0.0, 0.0, 1.0  # (rank 1: the direction e_z)
    elif axis and rank == 1:
        size = math.hypot(px, py)
        px, py, pz, rank = py / size, -px / size, 0.0, 2  # d x e_z
    if rank == 0:
        off = math.sqrt(cx * cx + cy * cy + cz * cz) + weight
        return (0.0 if off <= tol else math.inf), 0.0, 0.0, 0.0
    if rank == 1:
        # one direction d: the loads must lie on its line
        for k in range(2):
            qx, qy, qz = _perpendicular(px, py, pz, k)
            if _off_plane(qx, qy, qz, cx, cy, cz, weight) > tol:
                return math.inf, 0.0, 0.0, 0.0
        return _facet(gens, m, px, py, pz, cx, cy, cz, shift, weight, tol, hscale), px, py, pz
    if rank == 2 and _off_plane(px, py, pz, cx, cy, cz, weight) > tol:
        return math.inf, 0.0, 0.0, 0.0
    mu = bx = by = bz = 0.0
    for a in range(m + axis):
        ax, ay, az = _generator(gens, m, a)
        # facet normals: in a plane p x g_a; in space g_a x g_c
        for c in range(a + 1, m + axis + 1):
            if rank == 2:
                if c > a + 1:
                    break
                ux, uy, uz = py * az - pz * ay, pz * ax - px * az, px * ay - py * ax
            elif c < m + axis:
                gx, gy, gz = _generator(gens, m, c)
                ux, uy, uz = ay * gz - az * gy, az * gx - ax * gz, ax * gy - ay * gx
            else:
                break
            ratio = _facet(gens, m, ux, uy, uz, cx, cy, cz, shift, weight, tol, hscale)
            if ratio > mu:
                size = math.sqrt(ux * ux + uy * uy + uz * uz)
                mu, bx, by, bz = ratio, ux / size, uy / size, uz / size
    return mu, bx, by, bz


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _perpendicular(dx, dy, dz, which):
    """One of two unit vectors perpendicular to the unit d and to each other."""
    if abs(dx) < 0.9:
        ax, ay, az = 0.0, dz, -dy  # d x e_x
    else:
        ax, ay, az = -dz, 0.0, dx  # d x e_y
    size = math.sqrt(ax * ax + ay * ay + az * az)
    ax, ay, az = ax / size, ay / size, az / size
    if which == 0:
        return ax, ay, az
    return dy * az - dz * ay, dz * ax - dx * az, dx * ay - dy * ax


_NEWTON_STEPS = 200  # the dual's Newton iterations (a handful converge it from a warm start)
_ROOT_STEPS = 80  # safeguarded Newton steps on mu
_Z_STEPS = 48  # golden-section steps over the moment: the interval shrinks by 0.618^48 ~ 1e-10
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)


@njit(cache=True, error_model="numpy", _nrt=False)
def _lift_value(gens, m, mu, bx, by, bz, l0, l1, l2):
    """The out-of-plane dual (:func:`_lift_dual`) at ``lambda = (l0, l1, l2)``: its value, its
    derivative in ``mu``, its gradient (3) and Hessian (6: xx, xy, xz, yy, yz, zz)."""
    slope = 0.0
    g0, g1, g2 = bx, by, bz
    hxx = hxy = hxz = hyy = hyz = hzz = 0.0
    for i in range(m):
        n_i = math.hypot(gens[i, 0], gens[i, 1])
        ax, ay, az = gens[i, 0] / n_i, gens[i, 1] / n_i, gens[i, 2] / n_i
        c = l0 * ax + l1 * ay + l2 * az
        root = math.sqrt(1.0 + c * c)
        slope += n_i * root
        f = mu * n_i * c / root
        g0 += f * ax
        g1 += f * ay
        g2 += f * az
        w = mu * n_i / (root * root * root)
        hxx += w * ax * ax
        hxy += w * ax * ay
        hxz += w * ax * az
        hyy += w * ay * ay
        hyz += w * ay * az
        hzz += w * az * az
    value = l0 * bx + l1 * by + l2 * bz + mu * slope
    return value, slope, g0, g1, g2, hxx, hxy, hxz, hyy, hyz, hzz


@njit(cache=True, error_model="numpy", _nrt=False)
def _solve_sym3(hxx, hxy, hxz, hyy, hyz, hzz, g0, g1, g2):
    """``H^-1 g`` of a symmetric positive definite 3 x 3 ``H`` (by its cofactors)."""
    c00 = hyy * hzz - hyz * hyz
    c01 = hxz * hyz - hxy * hzz
    c02 = hxy * hyz - hxz * hyy
    c11 = hxx * hzz - hxz * hxz
    c12 = hxy * hxz - hxx * hyz
    c22 = hxx * hyy - hxy * hxy
    det = hxx * c00 + hxy * c01 + hxz * c02
    return ((c00 * g0 + c01 * g1 + c02 * g2) / det, (c01 * g0 + c11 * g1 + c12 * g2) / det,
            (c02 * g0 + c12 * g1 + c22 * g2) / det)


@njit(cache=True, error_model="numpy", _nrt=False)
def _lift_dual(gens, m, mu, bx, by, bz, l0, l1, l2):
    """``D(mu) = min_lambda lambda . b + mu sum_i N_i sqrt(1 + (lambda . a_i)^2)`` (a_i =
    ``g_i / N_i``): the largest out-of-plane force that cones of size mu carry beside the
    in-plane load ``b`` (Lagrange dual of ``max sum_i sqrt(mu^2 N_i^2 - t_i^2)`` over the
    in-plane allocations ``t``), by damped Newton from ``(l0, l1, l2)``.

    Returns ``(D, dD/dmu, converged, l0, l1, l2)``; not converged where mu is below the
    in-plane requirement (the dual is unbounded below: no out-of-plane capacity left)."""
    value, slope, g0, g1, g2, hxx, hxy, hxz, hyy, hyz, hzz = _lift_value(
        gens, m, mu, bx, by, bz, l0, l1, l2)
    scale = mu * _total(gens, m)
    for _ in range(_NEWTON_STEPS):
        ridge = 1e-12 * (hxx + hyy + hzz) + 1e-300
        s0, s1, s2 = _solve_sym3(hxx + ridge, hxy, hxz, hyy + ridge, hyz, hzz + ridge,
                                 g0, g1, g2)
        decrement = g0 * s0 + g1 * s1 + g2 * s2
        if not decrement > 1e-14 * scale:
            return value, slope, True, l0, l1, l2
        alpha = 1.0
        accepted = False
        for _ in range(60):
            t0, t1, t2 = l0 - alpha * s0, l1 - alpha * s1, l2 - alpha * s2
            trial = _lift_value(gens, m, mu, bx, by, bz, t0, t1, t2)
            if trial[0] <= value - 0.25 * alpha * decrement:
                l0, l1, l2 = t0, t1, t2
                value, slope, g0, g1, g2, hxx, hxy, hxz, hyy, hyz, hzz = trial
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            return value, slope, True, l0, l1, l2  # no descent left at rounding level
        if abs(l0) + abs(l1) + abs(l2) > 1e12:
            break
    return value, slope, False, l0, l1, l2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _total(gens, m):
    """The total normal force of the merged generators, ``sum_i N_i`` (``N_i = |g_i,xy|``: the
    tangent is a unit vector)."""
    total = 0.0
    for i in range(m):
        total += math.hypot(gens[i, 0], gens[i, 1])
    return total


@njit(cache=True, error_model="numpy", _nrt=False)
def _lift_at(gens, m, bx, by, bz, weight, tol):
    """The smallest mu whose 3-D cones carry the in-plane load ``(bx, by, bz)`` (its moment
    fixed) and ``weight`` out of the plane: the root of the concave increasing ``D(mu) =
    weight`` (:func:`_lift_dual`), bracketed by ``max(mu_0, W / sum N)`` and ``sqrt(mu_0^2 +
    (W / sum N)^2)`` (out-of-plane shares in proportion to the normal forces), by Newton steps
    from the top of the bracket (they approach the root from below: a concave function lies
    under its tangents), bisecting where a step leaves the bracket."""
    mu0 = in_plane_friction(gens, m, bx, by, bz, 0.0, 0.0, tol)[0]
    total = _total(gens, m)
    if not mu0 < math.inf or total <= 0.0:
        return math.inf
    ratio = weight / total
    lo, hi = max(mu0, ratio), math.sqrt(mu0 * mu0 + ratio * ratio)
    if hi - lo <= 1e-12 * hi:
        return hi
    l0 = l1 = l2 = 0.0
    mu = hi
    for _ in range(_ROOT_STEPS):
        # warm start from the last converged multipliers (near the in-plane limit they lie
        # far out, on the ray of the limiting facet)
        value, slope, ok, k0, k1, k2 = _lift_dual(gens, m, mu, bx, by, bz, l0, l1, l2)
        if ok:
            l0, l1, l2 = k0, k1, k2
        if ok and value >= weight:
            hi = mu
        else:
            lo = mu
        if ok and abs(value - weight) <= 1e-11 * weight:
            return mu
        if hi - lo <= 1e-11 * hi:
            return hi
        if ok and slope > 0.0:
            guess = mu - (value - weight) / slope
            if lo < guess < hi:
                mu = guess
                continue
        mu = 0.5 * (lo + hi)
    return hi


@njit(cache=True, error_model="numpy", _nrt=False)
def lift_friction(gens, m, cx, cy, cz, shift, weight, tol):
    """The smallest Coulomb coefficient whose 3-D cones (``t_i^2 + s_i^2 <= mu^2 N_i^2``,
    ``t_i`` in the plane along the contact's tangent, ``s_i`` along the disk's axis) carry the
    reaction in the plane and ``weight`` out of it (+z and -z alike), the moment free within
    the pressure shift's reach ``cz +- shift`` (see :func:`in_plane_friction`).

    Exact for the circular cones (to ~1e-10): at a fixed moment the requirement is the root
    of the dual capacity (:func:`_lift_at`); over the moment it is convex (the feasible
    ``(moment, mu)`` pairs form a convex set), minimised by golden-section search. Where the
    generators span a plane that is not the moment's axis, the in-plane load fixes the
    moment."""
    rank, px, py, pz = _span(gens, m)
    lo, hi = cz - shift, cz + shift
    if rank == 2 and abs(pz) > 1e-9:
        z = min(max(-(px * cx + py * cy) / pz, lo), hi)
        return _lift_at(gens, m, cx, cy, z, weight, tol)
    if shift <= 0.0:
        return _lift_at(gens, m, cx, cy, cz, weight, tol)
    a, b = lo, hi
    z1 = b - _GOLDEN * (b - a)
    z2 = a + _GOLDEN * (b - a)
    f1 = _lift_at(gens, m, cx, cy, z1, weight, tol)
    f2 = _lift_at(gens, m, cx, cy, z2, weight, tol)
    for _ in range(_Z_STEPS):
        if f1 <= f2:
            b, z2, f2 = z2, z1, f1
            z1 = b - _GOLDEN * (b - a)
            f1 = _lift_at(gens, m, cx, cy, z1, weight, tol)
        else:
            a, z1, f1 = z1, z2, f2
            z2 = a + _GOLDEN * (b - a)
            f2 = _lift_at(gens, m, cx, cy, z2, weight, tol)
    # a convex function's minimum may sit on an end of the reach
    return min(f1, f2, _lift_at(gens, m, cx, cy, lo, weight, tol),
               _lift_at(gens, m, cx, cy, hi, weight, tol))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _same_patch(normals, points, patches, i, j, tol):
    """Contacts i and j share a pressure patch: the same label, or both unlabelled on one
    flat face (:func:`_same_face`)."""
    if patches[i] >= 0 or patches[j] >= 0:
        return patches[i] == patches[j]
    return _same_face(normals, points, i, j, tol)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def hertz_half_width(radius_m, thickness_m, youngs_modulus_pa, poisson_ratio):
    """``c`` [m N^-1/2] such that ``c sqrt(F)`` is the half-width of the contact patch of a
    flat face pressed on the disk by a force ``F`` [N]: Hertz line contact in plane strain,
    ``a = sqrt(4 F r / (pi t E*))`` with ``E* = E / (1 - nu^2)`` (the width of
    :func:`envs.model.contact_width.hertz_arc_coefficient`, as a length)."""
    # a flat face: the relative radius is the disk's own
    return hertz_arc_coefficient(radius_m, thickness_m, youngs_modulus_pa, poisson_ratio,
                                 radius_m) * math.pi * radius_m


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _same_face(normals, points, i, j, tol):
    """Contacts i and j share a normal and lie on one line across it."""
    if abs(normals[i, 0] - normals[j, 0]) > 1e-9 or abs(normals[i, 1] - normals[j, 1]) > 1e-9:
        return False
    return abs((points[i, 0] - points[j, 0]) * normals[i, 0]
               + (points[i, 1] - points[j, 1]) * normals[i, 1]) <= tol


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _same_normal(normals, i, j):
    """Contacts i and j share a normal (to rounding)."""
    return (abs(normals[i, 0] - normals[j, 0]) <= 1e-9
            and abs(normals[i, 1] - normals[j, 1]) <= 1e-9)


# the one-slot fields of a holding row by the names grasp results and batch outputs give them
# (beside them: the pin force "pin_force_n", slots H_PIN_X..H_PIN_Y, and the limit's code
# "friction_limit", slot H_LIMIT, an integer)
HOLDING_SCALARS: tuple[tuple[str, int], ...] = (
    ("pin_moment_nm", H_PIN_MOMENT), ("required_friction", H_MU), ("payload_n", H_PAYLOAD),
    ("grip_force_n", H_GRIP), ("friction_limit_angle_rad", H_LIMIT_ANGLE))


def holding_fields(row) -> dict:
    """One holding row (layout ``H_*``) as the named fields of a grasp's result: the pin force
    ``pin_force_n`` as ``(x, y)`` floats [N], the :data:`HOLDING_SCALARS` as floats and the
    limit's code ``friction_limit`` as an int."""
    fields = {"pin_force_n": (float(row[H_PIN_X]), float(row[H_PIN_Y]))}
    fields.update({name: float(row[slot]) for name, slot in HOLDING_SCALARS})
    fields["friction_limit"] = int(row[H_LIMIT])
    return fields
