"""The loaded grasp: the friction a free object needs over the load set of how it is picked.

The solved grasp holds its object by a fixed centre (:mod:`envs.model.holding`). Lifted, the
object is free: the fixed centre's reaction and the payload ``W`` are loads on it, and the
contacts must carry them. They move the object a little, and the contacts' normal forces change
as the grasp's stiffness decides: a load that pushes the object into a jaw is carried by that
jaw's normal force. Each fidelity gives that stiffness as a *response*: the change of every
contact's normal force per unit load on the free object (a force along x, along y, a moment
about the centre), linearized about the solved grasp with the contacts sticking
(:func:`envs.solver.loaded.grasp_response` for the point-spring model, :mod:`envs.fem.grasp`
for the FEM). Given it, a load ``f`` on the object leaves the normal forces

    N_i'(f) = N_i + R_i . (f - p),         p the fixed centre's reaction (released),

(a contact the load would pull off carries nothing) and friction must carry what they leave:
the tangential forces ``t_i`` along the contacts' tangents with ``sum_i t_i tau_i = -(sum_i
N_i' nu_i + F)`` and the matching moment, ``|t_i| <= mu N_i'``. The required friction of one
load is the smallest such ``mu``: the gauge of :func:`envs.model.holding.in_plane_friction`
on the loaded normal forces, each face's pressure free to shift within its Hertz patch as
before (:mod:`envs.model.holding`): the onset of gross slip of the loaded grasp.

The *load set* is how the gripper picks (:data:`LOAD_SETS`):

* ``"top-down"``: the gripper points down and lifts; the payload pulls along the gripper's
  axis, towards the tips (+y) and back (-y, set down or decelerated).
* ``"side"``: the gripper comes from the side with its fingers' plane level: the payload acts
  along the disk's axis, +z (its weight) and -z.
* ``"any"`` (default): every in-plane direction and out of the plane.

Every set includes the object held at rest (the reaction alone, no payload). The required
friction is the largest over the set; which load sets it is reported (``LIMIT_*`` of
:mod:`envs.model.holding`, with the direction of an in-plane pull).

Out of the plane the 2-D model has no stiffness: the out-of-plane load leaves the in-plane
normal forces as the reaction alone left them, and the exact 3-D cone requirement
(:func:`envs.model.holding.lift_friction`) is taken on those.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .holding import (
    H_GRIP,
    H_LIMIT,
    H_LIMIT_ANGLE,
    H_MU,
    H_PAYLOAD,
    H_PIN_MOMENT,
    H_PIN_X,
    H_PIN_Y,
    LIMIT_IN_PLANE,
    LIMIT_NONE,
    LIMIT_OUT_OF_PLANE,
    LIMIT_REACTION,
    NO_PATCH,
    SPAN_TOL,
    _merge,
    _same_normal,
    _same_patch,
    in_plane_friction,
    lift_friction,
)

__all__ = [
    "LOAD_TOP_DOWN",
    "LOAD_SIDE",
    "LOAD_ANY",
    "LOAD_SETS",
    "DEFAULT_LOAD_SET",
    "N_RESPONSE",
    "load_set_code",
    "Response",
    "loaded_holding",
    "loaded_holding_row",
    "holding_row",
    "friction_under_load",
    "patch_constraints",
    "patch_response",
]

LOAD_TOP_DOWN, LOAD_SIDE, LOAD_ANY = range(3)
#: The load sets by name, in the order of their codes.
LOAD_SETS = ("top-down", "side", "any")
#: The load set checked when none is given: every direction (a pick not stated).
DEFAULT_LOAD_SET = "any"
#: Columns of a response: a force along x, along y [N] and a moment about the centre [N·m].
N_RESPONSE = 3
# the in-plane directions sampled for the "any" set, then refined about the worst
_DIRECTIONS = 24
_REFINE_STEPS = 24  # golden-section steps: the bracket (2 / 24 of a turn) shrinks to ~1e-6 rad
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)
# a finger on its closed stop: its joint's stiffness over the force scale x r
_LOCKED = 1e9


def load_set_code(load_set: str) -> int:
    """The code (``LOAD_*``) of a load set's name; ``ValueError`` naming the allowed ones."""
    if load_set not in LOAD_SETS:
        raise ValueError(f"load_set must be one of {', '.join(map(repr, LOAD_SETS))}, got "
                         f"{load_set!r}")
    return LOAD_SETS.index(load_set)


@njit(cache=True, error_model="numpy", _nrt=False)
def _groups(normals, points, forces, patches, count, length_scale, gen_group, shift_group):
    """Group the contacts once for every load: ``gen_group[i]`` the contact whose generator
    contact i's tangential force joins (a patch's contacts of one normal act as one, at their
    force-weighted arm), ``shift_group[i]`` the first contact of its pressure patch (a flat
    face's contacts of one normal on one line, or one label's: a run along the object's contour
    on a grooved jaw, whose pressure may shift by the Hertz half-width of its total force)."""
    tol = 1e-3 * length_scale
    for i in range(count):
        gen_group[i] = i
        shift_group[i] = i
        if not forces[i] > 0.0:
            continue
        for k in range(i):
            if forces[k] > 0.0 and _same_patch(normals, points, patches, i, k, tol):
                shift_group[i] = shift_group[k]
                break
        if patches[i] >= 0:
            for k in range(i):
                if (forces[k] > 0.0 and patches[k] == patches[i]
                        and _same_normal(normals, i, k)):
                    gen_group[i] = gen_group[k]
                    break


class Response(NamedTuple):
    """A fidelity's loaded grasp, for the holding of its contact list (:func:`loaded_holding`):
    the constraints of :func:`patch_constraints` (``cons``, ``weights``: each contact's
    normal group and patch, and its share of their force; ``mn`` normal constraints of ``mc``)
    and what :func:`patch_response` makes of them (``response``: each constraint's change of
    force per unit load; ``coupling``: the release of constraints). ``mc = 0``: the normal
    forces as solved (the bound :func:`holding_row` gives)."""

    cons: np.ndarray
    weights: np.ndarray
    mn: int
    mc: int
    response: np.ndarray
    coupling: np.ndarray

    @classmethod
    def none(cls, count: int) -> Response:
        """No response: every load leaves the normal forces as solved."""
        rows = max(count, 1)
        return cls(np.full((rows, 2), -1, dtype=np.int64), np.zeros((rows, 2)), 0, 0,
                   np.zeros((1, N_RESPONSE)), np.zeros((1, 1)))


@njit(cache=True, error_model="numpy")
def _work(count, mc):
    """Scratch of :func:`_one_load`: the groups, the loaded forces, the generators, the
    pressure patches, and the constraints' forces and their release."""
    rows, m = max(count, 1), max(mc, 1)
    return (np.zeros(rows, dtype=np.int64), np.zeros(rows, dtype=np.int64), np.zeros(rows),
            np.zeros((rows, 3)), np.zeros(rows), np.zeros(m), np.zeros(m),
            np.zeros(m, dtype=np.int64), np.zeros(m, dtype=np.int64), np.zeros((m, m)),
            np.zeros(m, dtype=np.int64), np.zeros(m))


@njit(cache=True, error_model="numpy", _nrt=False)
def _release(lam, lam0, mn, mc, cons, count, coupling, released, which, small, piv, tmp):
    """Release the normal groups the load pulls off (their force would be negative), and the
    sliding of a patch whose every group is released, moving the others' forces as the grasp's
    stiffness decides: ``lam = lam0 - M_{:S} M_{SS}^-1 lam0_S`` over the released set ``S``
    (``M``, the ``coupling``, the inverse's block of the constraints: the solution with the
    set's constraints taken out of the system and their forces zero), grown until no force is
    negative. A set the rest cannot hold (a singular ``M_SS``) keeps the forces clamped at 0."""
    for c in range(mc):
        lam0[c] = lam[c]
        released[c] = 0
    size = 0
    for _ in range(mn + 1):
        added = False
        for c in range(mn):
            if released[c] == 0 and lam[c] < 0.0:
                released[c] = 1
                which[size] = c
                size += 1
                added = True
        if not added:
            return
        for t in range(mn, mc):
            if released[t] != 0:
                continue
            members = alone = 0
            for i in range(count):
                if cons[i, 1] == t and cons[i, 0] >= 0:
                    members += 1
                    alone += released[cons[i, 0]]
            if members > 0 and alone == members:
                released[t] = 1
                which[size] = t
                size += 1
        for a in range(size):
            tmp[a] = lam0[which[a]]
            for b in range(size):
                small[a, b] = coupling[which[a], which[b]]
        if not _lu(small, piv, size):
            for c in range(mn):
                lam[c] = max(lam[c], 0.0)
            return
        _lu_solve(small, piv, size, tmp)
        for c in range(mc):
            v = lam0[c]
            for a in range(size):
                v -= coupling[c, which[a]] * tmp[a]
            lam[c] = v
        for a in range(size):
            lam[which[a]] = 0.0


@njit(cache=True, error_model="numpy", _nrt=False)
def _one_load(normals, points, forces, count, model, mn, mc, centre_x, centre_y, length_scale,
              fx, fy, fm, half_width, work, tol, weight):
    """The friction the loaded grasp needs under the load ``f = (fx, fy, fm)`` on the free
    object (the released reaction, ``-pin``, and the payload's pull), and ``weight`` out of
    the plane (0: none). Returns ``(mu, total)``, ``total`` the loaded normal forces' sum.

    Friction carries what the loaded normal forces ``N'`` leave: ``-f + sum (N - N') nu``
    (and its moment), which is ``-(sum N' nu + W)`` when the pin balances the forces as solved
    (``pin = -sum N nu``) and the pin's force with the normal forces as solved (``mc = 0``)."""
    cons, weights, response, coupling = model
    (gen_group, shift_group, loaded, gens, shift, lam, lam0, released, which, small, piv,
     tmp) = work
    # the constraints' forces: their base (a normal group's as solved; a patch slides with no
    # force) and the load's change, the groups it pulls off released
    for c in range(mc):
        lam[c] = response[c, 0] * fx + response[c, 1] * fy + response[c, 2] * fm
    for i in range(count):
        if forces[i] > 0.0 and cons[i, 0] >= 0:
            lam[cons[i, 0]] += forces[i]
    if mc > 0:
        _release(lam, lam0, mn, mc, cons, count, coupling, released, which, small, piv, tmp)
    # what the normal forces' change leaves to friction, beside the load
    need_x, need_y, need_m = -fx, -fy, -fm
    grip = 0.0
    for i in range(count):
        f = forces[i]
        if not f > 0.0:
            loaded[i] = 0.0
            continue
        grip += f
        v = f if mc == 0 else max(weights[i, 0] * lam[cons[i, 0]], 0.0)
        loaded[i] = v
        d = f - v
        need_x += d * normals[i, 0]
        need_y += d * normals[i, 1]
        need_m += d * ((points[i, 0] - centre_x) * normals[i, 1]
                       - (points[i, 1] - centre_y) * normals[i, 0])
    # the generators: a group's tangential force at its force-weighted arm
    for i in range(count):
        gens[i, 0] = gens[i, 1] = gens[i, 2] = 0.0
        shift[i] = 0.0
    total = 0.0
    for i in range(count):
        v = loaded[i]
        if not v > 0.0:
            continue
        total += v
        tx, ty = -normals[i, 1], normals[i, 0]
        g = gen_group[i]
        gens[g, 0] += v * tx
        gens[g, 1] += v * ty
        gens[g, 2] += v * ((points[i, 0] - centre_x) * ty
                           - (points[i, 1] - centre_y) * tx) / length_scale
        shift[shift_group[i]] += v
    # the pressure shift's reach (zero rows of the generators are skipped by the merge)
    reach = 0.0
    for i in range(count):
        s = shift[i]
        if s > 0.0:
            reach += s * half_width * math.sqrt(s)
    m = _merge(gens, count)
    if grip > 0.0 and not total > 0.0:
        return math.inf, total  # the load pulls every contact off: nothing holds the object
    scale = max(grip, math.hypot(need_x, need_y))
    if weight > 0.0:
        mu = lift_friction(gens, m, need_x, need_y, need_m / length_scale,
                           reach / length_scale, weight, tol * scale)
    else:
        mu = in_plane_friction(gens, m, need_x, need_y, need_m / length_scale,
                               reach / length_scale, 0.0, tol * scale)[0]
    return mu, total


@njit(cache=True, error_model="numpy")
def loaded_holding(normals, points, forces, patches, model, mn, mc, count, centre_x,
                   centre_y, length_scale, pin_x, pin_y, pin_moment, payload, load_set,
                   half_width, out):
    """The holding row of a solved grasp freed of its fixed centre, over a load set.

    Parameters
    ----------
    normals, points, forces, patches, count, centre_x, centre_y, length_scale
        Contact ``i < count``: unit normal on the object (2,), the point where it acts [m]
        (2,), its normal force [N] (>= 0; zero forces are skipped) and its pressure-patch
        label (:data:`envs.model.holding.NO_PATCH`: the flat-face rule, one normal on one
        line), the object's centre [m] and the length scale [m] of the moment row (its
        radius).
    model, mn, mc
        The loaded grasp, ``(cons, weights, response, coupling)`` and the constraint counts
        of a :class:`Response` (``mc = 0``: the normal forces as solved, the bound of
        :func:`holding_row`).
    pin_x, pin_y, pin_moment
        The fixed centre's reaction on the object [N, N, N·m], released here.
    payload
        The payload ``W`` [N], >= 0.
    load_set
        ``LOAD_TOP_DOWN``, ``LOAD_SIDE`` or ``LOAD_ANY``.
    half_width
        The contact patches' ``c`` [m N^-1/2] (:func:`envs.model.holding.hertz_half_width`).
    out
        The holding row (layout ``H_*``), written: the reaction and grip as solved, the
        required friction over the load set and what sets it.
    """
    total = 0.0
    for i in range(count):
        if forces[i] > 0.0:
            total += forces[i]
    out[H_PIN_X] = pin_x
    out[H_PIN_Y] = pin_y
    out[H_PIN_MOMENT] = pin_moment
    out[H_PAYLOAD] = payload
    out[H_GRIP] = total
    work = _work(count, mc)
    _groups(normals, points, forces, patches, count, length_scale, work[0], work[1])
    fx, fy, fm = -pin_x, -pin_y, -pin_moment
    mu, held = _one_load(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                         length_scale, fx, fy, fm, half_width, work, SPAN_TOL, 0.0)
    code, angle = LIMIT_REACTION, math.nan
    if payload > 0.0 and mu < math.inf:
        mu0 = mu
        if load_set != LOAD_SIDE:
            worst, phi = _in_plane_worst(normals, points, forces, count, model, mn, mc,
                                         centre_x, centre_y, length_scale, fx, fy, fm,
                                         payload, load_set, half_width, work)
            if worst > mu:
                mu, code, angle = worst, LIMIT_IN_PLANE, phi
        ratio = payload / held if held > 0.0 else math.inf
        # out of the plane: bounded by the proportional shares; the exact need where it may
        # set the answer
        if load_set != LOAD_TOP_DOWN and mu < math.inf and (
                math.sqrt(mu0 * mu0 + ratio * ratio) > mu):
            lift, _ = _one_load(normals, points, forces, count, model, mn, mc, centre_x,
                                centre_y, length_scale, fx, fy, fm, half_width, work,
                                SPAN_TOL, payload)
            if lift > mu:
                mu, code, angle = lift, LIMIT_OUT_OF_PLANE, math.nan
    if mu == 0.0:
        code = LIMIT_NONE
    out[H_MU] = mu
    out[H_LIMIT] = code
    out[H_LIMIT_ANGLE] = angle


@njit(cache=True, error_model="numpy", _nrt=False)
def _in_plane_worst(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                    length_scale, fx, fy, fm, payload, load_set, half_width, work):
    """The largest friction over the set's in-plane pulls of size ``payload`` and the
    direction of the pull that needs it [rad from +x]: top-down the gripper's axis both ways;
    any every direction (sampled, then refined by golden section about the worst sample)."""
    best, best_phi = -1.0, 0.0
    samples = 2 if load_set == LOAD_TOP_DOWN else _DIRECTIONS
    for k in range(samples):
        phi = (0.5 * math.pi + math.pi * k if load_set == LOAD_TOP_DOWN
               else 2.0 * math.pi * k / samples)
        v = _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                  length_scale, fx, fy, fm, payload, phi, half_width, work)
        if v > best:
            best, best_phi = v, phi
    if load_set == LOAD_TOP_DOWN or not best < math.inf:
        return best, best_phi
    step = 2.0 * math.pi / samples
    a, b = best_phi - step, best_phi + step
    p1, p2 = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    v1 = _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
               length_scale, fx, fy, fm, payload, p1, half_width, work)
    v2 = _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
               length_scale, fx, fy, fm, payload, p2, half_width, work)
    for _ in range(_REFINE_STEPS):
        if v1 >= v2:
            b, p2, v2 = p2, p1, v1
            p1 = b - _GOLDEN * (b - a)
            v1 = _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                       length_scale, fx, fy, fm, payload, p1, half_width, work)
        else:
            a, p1, v1 = p1, p2, v2
            p2 = a + _GOLDEN * (b - a)
            v2 = _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                       length_scale, fx, fy, fm, payload, p2, half_width, work)
    for v, phi in ((v1, p1), (v2, p2)):
        if v > best:
            best, best_phi = v, phi
    return best, math.atan2(math.sin(best_phi), math.cos(best_phi))


@njit(cache=True, error_model="numpy", _nrt=False)
def _pull(normals, points, forces, count, model, mn, mc, centre_x, centre_y, length_scale, fx,
          fy, fm, payload, phi, half_width, work):
    """The friction of the pull ``payload`` along ``phi`` on top of the released reaction."""
    return _one_load(normals, points, forces, count, model, mn, mc, centre_x, centre_y,
                     length_scale, fx + payload * math.cos(phi), fy + payload * math.sin(phi),
                     fm, half_width, work, SPAN_TOL, 0.0)[0]


def _contact_arrays(normals, points, forces, patches):
    """A contact list as the kernels' arrays (labels default: the flat-face rule)."""
    normals = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 2)
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    forces = np.ascontiguousarray(forces, dtype=np.float64).reshape(-1)
    count = forces.size
    labels = (np.full(count, NO_PATCH, dtype=np.int64) if patches is None
              else np.ascontiguousarray(patches, dtype=np.int64).reshape(-1))
    if labels.size != count:
        raise ValueError(f"patches needs one label per contact ({count}), got {labels.size}")
    return normals, points, forces, labels, count


def loaded_holding_row(normals, points, forces, centre_m, length_scale_m, pin_force_n,
                       pin_moment_nm, response: Response | None = None, payload_n: float = 0.0,
                       load_set: str = DEFAULT_LOAD_SET, half_width: float = 0.0,
                       patches=None) -> np.ndarray:
    """:func:`loaded_holding` of plain arrays (the FEM's contact list, tests), a row
    (N_HOLD,); ``response`` ``None``: the normal forces as solved."""
    from .holding import N_HOLD

    normals, points, forces, labels, count = _contact_arrays(normals, points, forces, patches)
    resp = Response.none(count) if response is None else response
    out = np.empty(N_HOLD)
    loaded_holding(normals, points, forces, labels,
                   (resp.cons, resp.weights, resp.response, resp.coupling), int(resp.mn),
                   int(resp.mc), count, float(centre_m[0]), float(centre_m[1]),
                   float(length_scale_m), float(pin_force_n[0]), float(pin_force_n[1]),
                   float(pin_moment_nm), float(payload_n), load_set_code(load_set),
                   float(half_width), out)
    return out


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _root(parent, i):
    """The root of contact i's set (union-find), compressing the path."""
    r = i
    while parent[r] != r:
        r = parent[r]
    while parent[i] != r:
        parent[i], i = r, parent[i]
    return r


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _join(parent, i, k):
    """Put contacts i and k in one set (the smaller root leads)."""
    a, b = _root(parent, i), _root(parent, k)
    if a != b:
        parent[max(a, b)] = min(a, b)


@njit(cache=True, error_model="numpy", _nrt=False)
def _number_sets(parent, forces, count, column, first, cons):
    """Number the sets of ``parent`` from ``first`` into ``cons[:, column]`` (-1 for a contact
    without force); returns the next free number."""
    c = first
    for i in range(count):
        cons[i, column] = -1
    for i in range(count):
        if not forces[i] > 0.0:
            continue
        r = _root(parent, i)
        if r == i:
            cons[i, column] = c
            c += 1
    for i in range(count):
        if forces[i] > 0.0 and cons[i, column] < 0:
            cons[i, column] = cons[_root(parent, i), column]
    return c


@njit(cache=True, error_model="numpy", _nrt=False)
def patch_constraints(normals, points, forces, patches, nodes, fingers, count, length_scale,
                      groups, cons, weights):
    """The sticking constraints of the loaded grasp's patch-level model, one per *normal
    group* (a pressure patch's contacts of one normal: a flat face, a flank, each node of a
    curved run, a corner) and one per pressure patch (its sliding along the surface); rolling
    is free. Contacts of one finger whose forces act on a common mesh node join one normal
    group and one patch (a rounded corner pressing two edges at their common node, a tip
    corner beside a face's last node: one touch, whose two rows of the mesh would otherwise
    be nearly the same constraint). Contact i joins normal constraint ``cons[i, 0]`` with
    weight ``weights[i, 0]`` (its share of the group's force) and tangential constraint
    ``cons[i, 1]`` with weight ``weights[i, 1]`` (its share of the patch's); -1 for a contact
    without force. Returns ``(normal, total)``: the number of normal constraints and of all
    (normal first).

    ``nodes`` (>= count, 2): the mesh nodes each contact's force acts on (-1: none);
    ``fingers``: each contact's finger. ``groups`` (>= count, 2) gets the generator and
    pressure-patch groups of :func:`_groups` and is then the two union-find forests."""
    gen_group, shift_group = groups[:, 0], groups[:, 1]
    _groups(normals, points, forces, patches, count, length_scale, gen_group, shift_group)
    # the forests: a normal group's leader, a patch's leader (each leader leads itself)
    for i in range(count):
        gen_group[i] = gen_group[i] if patches[i] >= 0 else shift_group[i]
    for i in range(count):
        if not forces[i] > 0.0:
            continue
        for k in range(i):
            if not (forces[k] > 0.0 and fingers[k] == fingers[i]):
                continue
            shared = False
            for a in range(2):
                for b in range(2):
                    shared = shared or (nodes[i, a] >= 0 and nodes[i, a] == nodes[k, b])
            if shared:
                _join(gen_group, i, k)
                _join(shift_group, i, k)
    mn = _number_sets(gen_group, forces, count, 0, 0, cons)
    mc = _number_sets(shift_group, forces, count, 1, mn, cons)
    # each contact's share of its group's and its patch's force
    for i in range(count):
        weights[i, 0] = weights[i, 1] = 0.0
    for c in range(mc):
        sums = 0.0
        for i in range(count):
            if cons[i, 0] == c or cons[i, 1] == c:
                sums += forces[i]
        for i in range(count):
            if cons[i, 0] == c:
                weights[i, 0] = forces[i] / sums
            elif cons[i, 1] == c:
                weights[i, 1] = forces[i] / sums
    return mn, mc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _direction(normals, i, tangential):
    """Contact i's unit normal (on the object) or its tangent, the normal turned a quarter
    counter-clockwise."""
    if tangential:
        return -normals[i, 1], normals[i, 0]
    return normals[i, 0], normals[i, 1]


@njit(cache=True, error_model="numpy")
def patch_response(compliance, mn, mc, normals, points, fingers, count, cons, weights,
                   centre_x, centre_y, joint_offset, kf, locked, length_scale, force_scale,
                   response, coupling):
    """The loaded grasp's response: each constraint's change of force per unit load on the
    free object, and how releasing constraints moves the others', from the patch-level model.

    The object moves rigidly (``q``: a translation and a turn about the centre) and deforms
    elastically (``compliance``); each finger turns about its joint against its spring
    (``kf``); every constraint of :func:`patch_constraints` sticks (the object's and the
    finger's material points move together along the constraint's direction). The
    constraints' forces ``lam``, the motion and the fingers' turns solve the symmetric
    saddle-point system ::

        [[G,      A_q, A_d ],    [lam]   [ 0]
         [A_q^T,  0,   0   ],  x [q  ] = [-f]
         [A_d^T,  0,   -K_f]]    [d  ]   [ 0]

    with ``G`` the object's compliance between the constraints (from its hub) and ``A_q``,
    ``A_d`` what the rigid motion and the fingers' turns move them by. Its inverse's block of
    the constraints, ``coupling``, releases constraints (:func:`_release`).

    Parameters
    ----------
    compliance
        (>= mc, >= mc) ``G`` [m/N]: the displacement along constraint c per unit force along
        constraint c' (each a contact-weighted sum, :func:`patch_constraints`), the hub held.
    mn, mc, cons, weights
        From :func:`patch_constraints`.
    normals, points, fingers, count
        The contact list and each contact's finger (0 right, 1 left).
    centre_x, centre_y
        The object's centre [m] (its hub, where the load acts).
    joint_offset
        ``d_3`` [m]: the joints at ``(+-d_3, 0)``.
    kf, locked
        The joints' stiffness [N·m/rad] and whether each finger is on its closed stop (2,).
    length_scale, force_scale
        ``r`` [m] and a force [N] that scale the system.
    response
        (>= mc, N_RESPONSE), written: each constraint's change of force per unit force along
        x, along y [N/N] and per unit moment [N/(N·m)] on the object. Zero where the system is
        singular (an object the contacts do not hold in place: one finger touching).
    coupling
        (>= mc, >= mc), written: the inverse's block of the constraints (scaled).

    Returns
    -------
    bool
        False where the system is singular.
    """
    size = mc + 5
    a = np.zeros((size, size))
    r, fs = length_scale, force_scale
    big = 0.0
    for c in range(mc):
        big = max(big, compliance[c, c])
        for c2 in range(mc):
            a[c, c2] = compliance[c, c2] * fs / r
    for c in range(mc):
        # a floor of round-off size for constraints the mesh can hardly tell apart
        a[c, c] += 1e-9 * big * fs / r
    for i in range(count):
        for kind in range(2):
            c = cons[i, kind]
            if c < 0:
                continue
            w = weights[i, kind]
            dx, dy = _direction(normals, i, kind == 1)
            px, py = (points[i, 0] - centre_x) / r, (points[i, 1] - centre_y) / r
            a[c, mc] += w * dx
            a[c, mc + 1] += w * dy
            a[c, mc + 2] += w * (-dx * py + dy * px)
            j = fingers[i]
            # a point of finger j turns about its joint: opening (theta up) turns the right
            # finger clockwise (sign -1), the left counter-clockwise (+1)
            sign = -1.0 if j == 0 else 1.0
            jx = (joint_offset if j == 0 else -joint_offset) / r
            vx, vy = points[i, 0] / r - jx, points[i, 1] / r
            a[c, mc + 3 + j] -= w * sign * (-dx * vy + dy * vx)
    for c in range(mc):
        for k in range(5):
            a[mc + k, c] = a[c, mc + k]
    for j in range(2):
        stiff = _LOCKED if locked[j] else max(kf, 1e-9 * fs * r) / (fs * r)
        a[mc + 3 + j, mc + 3 + j] = -stiff
    lu = a.copy()
    piv = np.zeros(size, dtype=np.int64)
    ok = _lu(lu, piv, size)
    for c in range(mc):
        for k in range(N_RESPONSE):
            response[c, k] = 0.0
        for c2 in range(mc):
            coupling[c, c2] = 0.0
    if not ok:
        return False
    rhs = np.zeros(size)
    for k in range(N_RESPONSE):
        rhs[:] = 0.0
        rhs[mc + k] = -1.0
        _lu_solve(lu, piv, size, rhs)
        unit = 1.0 if k < 2 else 1.0 / r  # per N, per N·m
        for c in range(mc):
            response[c, k] = rhs[c] * unit
    for c in range(mc):
        rhs[:] = 0.0
        rhs[c] = 1.0
        _lu_solve(lu, piv, size, rhs)
        for c2 in range(mc):
            coupling[c2, c] = rhs[c2]
    return True


@njit(cache=True, error_model="numpy", _nrt=False)
def _lu(a, piv, n):
    """LU with partial pivoting in place; False where a pivot is below 1e-13 of the largest
    entry (singular)."""
    big = 0.0
    for i in range(n):
        for j in range(n):
            big = max(big, abs(a[i, j]))
    if not big > 0.0:
        return False
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(a[i, k]) > abs(a[p, k]):
                p = i
        piv[k] = p
        if not abs(a[p, k]) > 1e-13 * big:
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            a[i, k] = f
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
    return True


@njit(cache=True, error_model="numpy", _nrt=False)
def _lu_solve(lu, piv, n, b):
    """Solve with :func:`_lu`'s factors in place."""
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        for j in range(i):
            b[i] -= lu[i, j] * b[j]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            b[i] -= lu[i, j] * b[j]
        b[i] /= lu[i, i]


def friction_under_load(normals, points, forces, centre_m, length_scale_m, pin_force_n,
                        pin_moment_nm, response: Response | None, load_n,
                        half_width: float = 0.0, patches=None) -> float:
    """The friction the freed object's grasp needs under one in-plane load ``load_n`` (a
    force ``(x, y)`` [N] on the object at its centre; ``(0, 0)``: the released reaction
    alone), the contact list and its :class:`Response` as for :func:`loaded_holding_row`
    (tests, scripts: one load rather than a load set)."""
    normals, points, forces, labels, count = _contact_arrays(normals, points, forces, patches)
    resp = Response.none(count) if response is None else response
    work = _work(count, int(resp.mc))
    _groups(normals, points, forces, labels, count, float(length_scale_m), work[0], work[1])
    wx, wy = float(load_n[0]), float(load_n[1])
    return _one_load(normals, points, forces, count,
                     (resp.cons, resp.weights, resp.response, resp.coupling), int(resp.mn),
                     int(resp.mc), float(centre_m[0]), float(centre_m[1]),
                     float(length_scale_m), -float(pin_force_n[0]) + wx,
                     -float(pin_force_n[1]) + wy, -float(pin_moment_nm), float(half_width),
                     work, SPAN_TOL, 0.0)[0]


def holding_row(normals, points, forces, centre_m, length_scale_m, pin_force_n,
                pin_moment_nm, payload_n: float = 0.0, half_width: float = 0.0,
                patches=None) -> np.ndarray:
    """The holding row (N_HOLD,) of a contact list with its normal forces *as solved*: the
    former rule, a bound on the freed object's need (:func:`loaded_holding_row` with no
    response), over the load set ``"any"``. ``half_width``: the patches' ``c`` [m N^-1/2]
    (:func:`envs.model.holding.hertz_half_width`; 0: no shift); ``patches``: each contact's
    patch label (default: :data:`envs.model.holding.NO_PATCH` for all, the flat-face rule)."""
    return loaded_holding_row(normals, points, forces, centre_m, length_scale_m, pin_force_n,
                              pin_moment_nm, None, payload_n, "any", half_width, patches)
