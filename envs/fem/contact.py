"""Contact: rim nodes, rigid obstacles (jaw faces, plate) and the convex corners of the jaws.

Node-to-face gaps with their derivatives with respect to the node positions and to the
obstacle's scalar unknown, and the corner-to-rim signed distance with its exact Hessian
(complex step of the analytic gradient). The penalty itself is applied by :mod:`.system`.

A straight finger's obstacle is its flat gripping face (:class:`_JawFace`); a grooved finger's
is its solid, the bar minus the groove (:class:`_JawSolid`), whose gap, normal and curvature come
from the shared kernel :func:`envs.model.jaw.jaw_gap` of both fidelities. The convex corners
pressed against the rim's segments are each finger's tip corner and a groove's two rounded mouth
edges (:class:`_JawCorner`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from envs.model.contact_width import (
    FLAT_FACE_CURVATURE_PER_M,
    contact_arc_share,
    contact_indicator,
    contact_share,
    curvature_weight_n,
    hertz_arc_coefficient,
    outline_hertz_coefficient,
    outline_run_share,
    plane_strain_modulus_pa,
    relative_radius_m,
    run_curvature_per_m,
    run_share,
    segment_contact,
)
from envs.model.geometry import bar_distance, corner_radius, finger_frame
from envs.model.jaw import (
    G_CENTRE,
    G_COS,
    G_DEPTH,
    G_MOUTH,
    G_POSITION,
    G_RADIUS,
    G_SIN,
    N_GROOVE,
    JawProfile,
    jaw_gap,
    pack_groove,
)
from envs.scene import Scene

from .body import _Body

_PENALTY_FACTOR = 100.0  # default eps = 100 E / h


@dataclass
class _Rim:
    """Contact nodes of the rim: dof indices, reference positions and penalty weights."""

    dofs: np.ndarray  # (m, 2) x and y dof of each node
    ref_m: np.ndarray  # (m, 2) reference positions
    weight_m2: np.ndarray  # (m,) rim length share times thickness [m^2]

    @classmethod
    def build(cls, body: _Body, arc_facets: np.ndarray, centre: np.ndarray, thickness_m: float,
              curved: bool = False):
        """The rim of ``arc_facets``; their lengths as circular arcs about ``centre``, or
        (``curved``: an outline's rim) as the quadratic edges through their midside nodes."""
        b, mesh = body.basis, body.mesh
        verts = mesh.facets[:, arc_facets]  # (2, nf)
        vdofs = b.nodal_dofs[:, verts]  # (2 comps, 2 ends, nf)
        mdofs = b.facet_dofs[:, arc_facets]  # (2 comps, nf)
        pa = mesh.p[:, verts[0]] - centre[:, None]
        pb = mesh.p[:, verts[1]] - centre[:, None]
        if curved:
            from .mesh import _p2_lengths

            length = _p2_lengths(pa, b.doflocs[:, mdofs[0]] - centre[:, None], pb)
        else:
            radius = np.linalg.norm(pa, axis=0)
            cosang = np.sum(pa * pb, axis=0) / (radius * np.linalg.norm(pb, axis=0))
            length = radius * np.arccos(np.clip(cosang, -1.0, 1.0))
        xdofs = np.concatenate((vdofs[0, 0], vdofs[0, 1], mdofs[0]))
        ydofs = np.concatenate((vdofs[1, 0], vdofs[1, 1], mdofs[1]))
        wts = np.concatenate((length / 6, length / 6, 2 * length / 3))
        uniq, inv = np.unique(xdofs, return_inverse=True)
        weight = np.zeros(uniq.size)
        np.add.at(weight, inv, wts)
        ymap = np.zeros(uniq.size, dtype=np.int64)
        ymap[inv] = ydofs
        dofs = np.column_stack((uniq, ymap))
        ref = b.doflocs[:, uniq].T.copy()
        return cls(dofs, ref, weight * thickness_m)


class _Obstacle:
    """A rigid obstacle driven by one scalar unknown ``q`` (index ``qi``).

    ``evaluate(p, q)`` returns, per rim node, the gap ``g``, whether the node is in the face's
    extent, ``dg/dp`` (m, 2), ``dg/dq``, ``d2g/dq2``, ``d2g/dp dq`` (m, 2) and ``d2g/dp2``
    (m, 2, 2), the last ``None`` for a flat obstacle (no curvature).
    """

    qi: int

    def evaluate(self, p: np.ndarray, q: float):  # pragma: no cover - interface
        raise NotImplementedError


def _finger_coords(gripper, side: int, p: np.ndarray, q: float):
    """Finger ``side`` at angle ``q``: its axis ``e`` and inward normal ``n``, the points'
    coordinates ``s = e.(p - J)`` and ``m = n.(p - J)`` [m], and whether ``0 <= s <= l`` (a
    point beside the gripping face)."""
    joint, axis, normal = finger_frame(gripper, side, q)
    rel = p - joint
    s = rel @ axis
    m = rel @ normal
    return axis, normal, s, m, (s >= 0.0) & (s <= gripper.finger_length_m)


class _JawFace(_Obstacle):
    """Gripping face of one finger (docs/model.md): ``g = n.(p - J) - w/2``, 0 <= e.(p-J) <= l."""

    def __init__(self, scene: Scene, side: int, qi: int) -> None:
        self.gripper = scene.gripper
        self.side = side
        self.qi = qi

    def evaluate(self, p: np.ndarray, q: float):
        axis, normal, s, m, valid = _finger_coords(self.gripper, self.side, p, q)
        g = m - 0.5 * self.gripper.finger_width_m
        # dn/dtheta = e and de/dtheta = -n for both fingers
        dgdp = np.broadcast_to(normal, p.shape)
        return g, valid, dgdp, s, -m, np.broadcast_to(axis, p.shape), None


# columns of _jaw_gaps' rows: the gap and its derivatives in finger coordinates (s, m)
JG_GAP, JG_S, JG_M, JG_SS, JG_SM, JG_MM = range(6)
N_JAW_GAP = 6


@njit(cache=True, error_model="numpy", _nrt=False)
def _core_gap(s, m, hw, rho, groove):
    """Gap of a point deeper than ``rho`` inside a grooved finger (where :func:`jaw_gap` is
    ``-rho`` with no gradient): ``-rho`` minus its distance to the nearer of the core's face and
    the grown groove's wall, with derivatives, so that a penalty keeps pushing such a point out
    along the nearest surface's normal. Returns ``(g, g_s, g_m, g_ss, g_sm, g_mm)``."""
    face = hw - rho - m
    if not groove[G_DEPTH] > 0.0:
        return -rho - face, 0.0, 1.0, 0.0, 0.0, 0.0
    u = s - groove[G_POSITION]
    wv = hw - m - groove[G_CENTRE]
    radius, cb, sb = groove[G_RADIUS], groove[G_COS], groove[G_SIN]
    side = 1.0 if u >= 0.0 else -1.0
    if wv * cb >= abs(u) * sb:
        # below the bottom arc's tangent points: the distance to the arc
        dist = math.sqrt(u * u + wv * wv)
        wall = dist - radius
        nu, nv = u / dist, wv / dist
        # (u, wv) -> (s, m): d/ds = d/du, d/dm = -d/dwv; g = -rho - wall
        huu, huv, hvv = (1.0 - nu * nu) / dist, -nu * nv / dist, (1.0 - nv * nv) / dist
        wall_derivs = (-nu, nv, -huu, huv, -hvv)
    else:
        wall = cb * side * u + sb * wv - radius
        wall_derivs = (-cb * side, sb, 0.0, 0.0, 0.0)
    if face <= wall:
        return -rho - face, 0.0, 1.0, 0.0, 0.0, 0.0
    gs, gm, gss, gsm, gmm = wall_derivs
    return -rho - wall, gs, gm, gss, gsm, gmm


@njit(cache=True, error_model="numpy", _nrt=False)
def _jaw_gaps(s, m, lmax, hw, rho, groove, out):
    """:func:`envs.model.jaw.jaw_gap` of each point ``(s[i], m[i])`` into row ``out[i]``
    (columns ``JG_*``), continued below ``-rho`` inside the solid by :func:`_core_gap`."""
    for i in range(s.shape[0]):
        g, gs, gm, gss, gsm, gmm = jaw_gap(s[i], m[i], lmax, hw, rho, groove, 0)
        if gs == 0.0 and gm == 0.0:
            g, gs, gm, gss, gsm, gmm = _core_gap(s[i], m[i], hw, rho, groove)
        out[i, JG_GAP], out[i, JG_S], out[i, JG_M] = g, gs, gm
        out[i, JG_SS], out[i, JG_SM], out[i, JG_MM] = gss, gsm, gmm


def packed_groove(scene: Scene, jaw: JawProfile) -> tuple[np.ndarray, float]:
    """A finger's groove packed in SI (:func:`envs.model.jaw.pack_groove`, unit 1) and the
    corner radius ``rho`` [m] of its rounded edges."""
    grip = scene.gripper
    rho = float(corner_radius(grip.finger_width_m, scene.disk.radius_m))
    groove = np.zeros(N_GROOVE)
    pack_groove(jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m, rho,
                1.0, groove, 0)
    return groove, rho


def jaw_gaps_local(scene: Scene, side: int, jaw: JawProfile, along_m: np.ndarray,
                   across_m: np.ndarray) -> np.ndarray:
    """Gap of points to a finger's solid and its derivatives in finger coordinates, (k, 6) in
    the ``JG_*`` columns; ``along_m``, ``across_m``: the points' ``s`` and ``m`` [m]."""
    grip = scene.gripper
    groove, rho = packed_groove(scene, jaw)
    s = np.ascontiguousarray(along_m, dtype=float)
    m = np.ascontiguousarray(across_m, dtype=float)
    out = np.empty((s.size, N_JAW_GAP))
    _jaw_gaps(s, m, grip.finger_length_m, 0.5 * grip.finger_width_m, rho, groove, out)
    return out


class _JawSolid(_Obstacle):
    """The solid of a grooved finger (bar minus groove, convex edges rounded), gap by
    :func:`envs.model.jaw.jaw_gap`, for nodes with ``0 <= e.(p - J) <= l`` (as the flat face).

    With ``s = e.(p - J)``, ``m = n.(p - J)`` and ``de/dq = -n``, ``dn/dq = e`` (both fingers),
    ``ds/dq = -m`` and ``dm/dq = s``: the gap's derivatives in finger coordinates chain to the
    node position and the finger angle exactly (the kernel's Hessian gives the curvature terms).
    """

    grooved = True  # its runs of loaded nodes are pressure patches (FemSystem.contact_list)

    def __init__(self, scene: Scene, side: int, qi: int, jaw: JawProfile) -> None:
        self.scene = scene
        self.gripper = scene.gripper
        self.side = side
        self.qi = qi
        self.jaw = jaw

    def evaluate(self, p: np.ndarray, q: float):
        axis, normal, s, m, valid = _finger_coords(self.gripper, self.side, p, q)
        d = jaw_gaps_local(self.scene, self.side, self.jaw, s, m)
        gs, gm = d[:, JG_S], d[:, JG_M]
        gss, gsm, gmm = d[:, JG_SS], d[:, JG_SM], d[:, JG_MM]
        dgdp = gs[:, None] * axis + gm[:, None] * normal
        dgdq = -m * gs + s * gm
        d2q = -s * gs - m * gm + m * m * gss - 2.0 * m * s * gsm + s * s * gmm
        d2pq = ((-m * gss + s * gsm + gm)[:, None] * axis
                + (-m * gsm + s * gmm - gs)[:, None] * normal)
        ee, nn = np.outer(axis, axis), np.outer(normal, normal)
        en = np.outer(axis, normal) + np.outer(normal, axis)
        d2pp = gss[:, None, None] * ee + gsm[:, None, None] * en + gmm[:, None, None] * nn
        return d[:, JG_GAP], valid, dgdp, dgdq, d2q, d2pq, d2pp


def jaw_obstacle(scene: Scene, side: int, qi: int) -> _Obstacle:
    """The obstacle of one finger: its flat face when straight, its grooved solid otherwise."""
    jaw = scene.gripper.jaws[side]
    return _JawFace(scene, side, qi) if jaw.depth_m == 0.0 else _JawSolid(scene, side, qi, jaw)


class _Plate(_Obstacle):
    """Flat horizontal plate at ``y = y0 - q`` pressing down on the body."""

    def __init__(self, y0_m: float, qi: int) -> None:
        self.y0_m = y0_m
        self.qi = qi

    def evaluate(self, p: np.ndarray, q: float):
        g = self.y0_m - q - p[:, 1]
        m = p.shape[0]
        dgdp = np.zeros((m, 2))
        dgdp[:, 1] = -1.0
        zeros = np.zeros(m)
        return g, np.ones(m, dtype=bool), dgdp, -np.ones(m), zeros, np.zeros((m, 2)), None


class _JawCorner:
    """A convex corner of one finger, a circle of radius ``radius_m`` (0: a sharp corner)
    centred at ``c = J + s_c e + m_c n`` (finger coordinates ``along_m``, ``across_m``), driven
    by ``q``: its gap to the rim is the centre's signed distance to the rim polygon minus
    ``radius_m``."""

    def __init__(self, scene: Scene, side: int, qi: int, along_m: float, across_m: float,
                 radius_m: float = 0.0) -> None:
        self.gripper = scene.gripper
        self.side = side
        self.qi = qi
        self.along_m = float(along_m)
        self.across_m = float(across_m)
        self.radius_m = float(radius_m)

    def evaluate(self, q: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre position and its first and second derivatives with respect to ``q``."""
        joint, axis, normal = finger_frame(self.gripper, self.side, q)
        sc, mc = self.along_m, self.across_m
        # de/dtheta = -n and dn/dtheta = e for both fingers
        return joint + sc * axis + mc * normal, -sc * normal + mc * axis, -sc * axis - mc * normal


def _JawTip(scene: Scene, side: int, qi: int) -> _JawCorner:
    """Tip corner ``c = J + l e + (w/2) n`` of one finger's gripping face (a sharp corner)."""
    grip = scene.gripper
    return _JawCorner(scene, side, qi, grip.finger_length_m, 0.5 * grip.finger_width_m)


def jaw_corners(scene: Scene) -> list[_JawCorner]:
    """The convex corners of both fingers pressed against the rim: the two tip corners (first,
    finger 0 then 1), then each grooved finger's two rounded mouth edges, centred at
    ``(a -+ u_E, w/2 - rho)`` in finger coordinates (:data:`envs.model.layout.G_MOUTH`)."""
    corners = [_JawTip(scene, 0, 0), _JawTip(scene, 1, 1)]
    hw = 0.5 * scene.gripper.finger_width_m
    for side, jaw in enumerate(scene.gripper.jaws):
        if jaw.depth_m == 0.0:
            continue
        groove, rho = packed_groove(scene, jaw)
        for sign in (-1.0, 1.0):
            corners.append(_JawCorner(scene, side, side,
                                      groove[G_POSITION] + sign * groove[G_MOUTH], hw - rho, rho))
    return corners


def _segment_gap_gradient(z: np.ndarray) -> tuple[complex, np.ndarray]:
    """Signed distance of point ``c`` to the line of segment ``a -> b`` and its gradient.

    ``z = (a_x, a_y, b_x, b_y, c_x, c_y)``; the distance is positive on the right of ``a -> b``
    (outside of a counter-clockwise polygon). Written with analytic operations only, so that it
    accepts complex input (complex-step differentiation of the gradient gives the exact Hessian).
    """
    ax, ay, bx, by, cx, cy = z
    tx, ty = bx - ax, by - ay
    dx, dy = cx - ax, cy - ay
    cross = dx * ty - dy * tx
    length = np.sqrt(tx * tx + ty * ty)
    d_cross = np.array([dy - ty, tx - dx, -dy, dx, ty, -tx])
    d_len = np.array([-tx, -ty, tx, ty, 0.0 * tx, 0.0 * tx]) / length
    return cross / length, d_cross / length - cross * d_len / length**2


def _vertex_distance_gradient(z: np.ndarray) -> tuple[complex, np.ndarray]:
    """Distance ``|c - v|`` and its gradient, ``z = (v_x, v_y, c_x, c_y)`` (complex-safe)."""
    vx, vy, cx, cy = z
    ex, ey = cx - vx, cy - vy
    dist = np.sqrt(ex * ex + ey * ey)
    return dist, np.array([-ex, -ey, ex, ey]) / dist


def _with_hessian(func, z: np.ndarray, sign: float = 1.0):
    """Value, gradient and exact Hessian (complex step of the analytic gradient) of ``func``."""
    g, gvec = func(z)
    n = z.size
    step = 1e-30 * max(1.0, float(np.max(np.abs(z))))
    hess = np.empty((n, n))
    for j in range(n):
        zc = z.astype(complex)
        zc[j] += 1j * step
        hess[:, j] = np.imag(func(zc)[1]) / step
    return sign * float(np.real(g)), sign * np.real(gvec), sign * 0.5 * (hess + hess.T)


def _corner_feature(poly: np.ndarray, c: np.ndarray) -> tuple[float, str, int]:
    """Signed distance of ``c`` to a closed counter-clockwise polygon and its nearest feature.

    Returns ``(gap, kind, index)``: ``gap`` is negative inside; ``kind`` is ``"segment"`` (the
    nearest point is inside segment ``index -> index + 1``) or ``"vertex"`` (it is vertex
    ``index``).
    """
    t = np.roll(poly, -1, axis=0) - poly
    d = c - poly
    len2 = np.sum(t * t, axis=1)
    xi = np.clip(np.sum(t * d, axis=1) / len2, 0.0, 1.0)
    near = poly + xi[:, None] * t
    dist2 = np.sum((c - near) ** 2, axis=1)
    k = int(np.argmin(dist2))
    # crossing-number inside test
    y0, y1 = poly[:, 1], np.roll(poly[:, 1], -1)
    crosses = (y0 > c[1]) != (y1 > c[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = poly[:, 0] + (c[1] - y0) * t[:, 0] / t[:, 1]
    inside = bool(np.count_nonzero(crosses & (c[0] < xint)) % 2)
    gap = (-1.0 if inside else 1.0) * math.sqrt(float(dist2[k]))
    if 0.0 < xi[k] < 1.0:
        return gap, "segment", k
    return gap, "vertex", (k if xi[k] == 0.0 else (k + 1) % poly.shape[0])


def jaw_curvature_per_m(local: np.ndarray) -> np.ndarray:
    """The jaw's curvature [1/m] at points, from their gap's derivatives in finger coordinates
    (rows of :func:`jaw_gaps_local`): minus the gap's second derivative along the surface's
    tangent, positive where the jaw is concave towards the point (``1 / R`` on a cradle's arc),
    0 on a flat face or flank, negative on a rounded convex edge."""
    ts, tm = -local[:, JG_M], local[:, JG_S]
    return -(local[:, JG_SS] * ts * ts + 2.0 * local[:, JG_SM] * ts * tm
             + local[:, JG_MM] * tm * tm)


def _segment_shares(phi: np.ndarray, segment: np.ndarray, forces_n: np.ndarray,
                    curvature_per_m: np.ndarray, scene: Scene,
                    outline: tuple[np.ndarray, float] | None = None) -> float:
    """One grooved face's share of the rim: the sum over its contact segments (runs of
    neighbouring pressed nodes) of :func:`envs.model.contact_width.run_share`, the rule the
    point-spring model applies to its contour points.

    Each run's curvature is its nodes' curvatures weighted by their forces
    (:func:`~envs.model.contact_width.curvature_weight_n`: a node on a rounded convex edge does
    not count); its extent is the rim segments of its pressed nodes and its two interpolated
    edges, its edge spacing the rim segments in which those edges lie. ``outline``: an outline's
    nodes' rest curvatures [1/m] and its perimeter [m] (each run capped on its own curvature
    under it, :func:`~envs.model.contact_width.outline_run_share`).
    """
    disk = scene.disk
    pressed = phi > 0.0
    n = phi.size
    if not np.any(pressed):
        return 0.0
    # label the runs of pressed nodes, walking from a free node (if any) so that none wraps
    first = int(np.argmin(pressed)) if not np.all(pressed) else 0
    run = np.full(n, -1)
    label = -1
    for k in range(n):
        i = (first + k) % n
        if pressed[i]:
            if k == 0 or not pressed[(i - 1) % n]:
                label += 1
            run[i] = label
    extent = np.zeros(label + 1)
    edges = np.zeros(label + 1)
    for i in range(n):
        j = (i + 1) % n
        part = segment[i] * segment_contact(float(phi[i]), float(phi[j]))
        if part > 0.0:
            extent[run[i] if pressed[i] else run[j]] += part
        if pressed[i] != pressed[j]:
            # a run's edge lies in the segment between a pressed node and a free one
            edges[run[i] if pressed[i] else run[j]] += segment[i]
    total = 0.0
    for k in range(label + 1):
        members = np.flatnonzero(run == k)
        weights = np.array([curvature_weight_n(float(forces_n[i]), float(curvature_per_m[i]))
                            for i in members])
        curvature = run_curvature_per_m(float(np.sum(weights * curvature_per_m[members])),
                                        float(np.sum(weights)))
        if outline is not None:
            own = forces_n[members]
            total += outline_run_share(
                float(extent[k]), float(np.sum(own)), curvature, float(edges[k]),
                _weighted_curvature(own, outline[0][members], outline[0]), outline[1],
                disk.thickness_m, disk.youngs_modulus_pa, disk.poisson_ratio)
            continue
        total += run_share(float(extent[k]), float(np.sum(forces_n[members])), curvature,
                           float(edges[k]), disk.radius_m, disk.thickness_m,
                           disk.youngs_modulus_pa, disk.poisson_ratio)
    return total


def _weighted_curvature(forces_n: np.ndarray, curvature_per_m: np.ndarray,
                        every: np.ndarray) -> float:
    """An outline's curvature under a contact: its pressed nodes' rest curvatures weighted by
    their forces; with no force, the largest of ``every`` (the point-spring model's rule,
    :func:`envs.scoring._object_curvature`)."""
    weight = float(np.sum(np.maximum(forces_n, 0.0)))
    if weight > 0.0:
        return float(np.sum(np.maximum(forces_n, 0.0) * curvature_per_m)) / weight
    return float(max(np.max(every), 0.0))


def rim_contact_shares(scene: Scene, rim: _Rim, order: np.ndarray, positions_m: np.ndarray,
                       face_forces_n: list[np.ndarray], jaw_angles_rad: np.ndarray,
                       outline_map=None) -> tuple[tuple[float, float], tuple[float, float]]:
    """Share of the rim in contact with each jaw, interpolated between rim nodes (the
    point-spring model's measure, :mod:`envs.model.contact_width`, on the FEM's rim), and the
    same capped by Hertz's width.

    Parameters
    ----------
    scene
        The grasped scene (the gripper's fingers and jaws; the disk's ``E``, ``nu``, ``t``, its
        centre).
    rim
        The rim nodes (reference positions, their share of the rim times the thickness).
    order
        The rim nodes counter-clockwise (indices into ``rim``).
    positions_m
        Deformed rim node positions [m], (m, 2), in ``rim``'s order.
    face_forces_n
        Each jaw's penalty force on each rim node [N], two arrays (m,) in ``rim``'s order.
    jaw_angles_rad
        The fingers' angles [rad], (2,).

    Returns
    -------
    tuple
        ``(extents, shares)``, each (right, left). ``extents``: each rim segment between
        neighbours counts with its share of the reference rim, in full where both nodes press,
        in part where one does (:func:`~envs.model.contact_width.contact_arc_share`); a pressed
        node's indicator takes its pressure (force over its Simpson weight) and its spacing (the
        mean of its two segments), a free node's its gap to the finger (to the bar of a straight
        finger, to the grooved solid of :func:`envs.model.jaw.jaw_gap` otherwise). ``shares``:
        a straight face's extent at most the Hertz width of its force on a flat face
        (:func:`~envs.model.contact_width.contact_share`); a grooved face's contact segments
        each at most the Hertz width of its own force on the jaw's curvature under it
        (:func:`_segment_shares`: a fitted cradle is not capped, a V's flanks are capped one by
        one, a disk wedged into a narrower groove scores the extent it touches).
        ``outline_map``: an outline's :class:`~envs.fem.mesh.OutlineMap` (``None``: a disk):
        its rim's segments count by arc length, and each contact is capped on the outline's
        own curvature under it (the point-spring model's rule).
    """
    disk, grip = scene.disk, scene.gripper
    e_star = plane_strain_modulus_pa(disk.youngs_modulus_pa, disk.poisson_ratio)
    weight_m2 = rim.weight_m2[order]
    p = positions_m[order]
    outline = None
    if outline_map is None:
        ref = rim.ref_m[order] - disk.center_m
        angle = np.arctan2(ref[:, 1], ref[:, 0])
        segment = np.mod(np.roll(angle, -1) - angle, 2 * math.pi) / (2 * math.pi)
        spacing_m = 0.5 * (segment + np.roll(segment, 1)) * 2 * math.pi * disk.radius_m
        flat_k = hertz_arc_coefficient(disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa,
                                       disk.poisson_ratio,
                                       relative_radius_m(disk.radius_m,
                                                         FLAT_FACE_CURVATURE_PER_M))
    else:
        # an outline: segments by arc length, each node's own rest curvature
        ref = rim.ref_m[order]
        s = outline_map.arc_fraction(ref, disk.center_m)
        segment = np.mod(np.roll(s, -1) - s, 1.0)
        spacing_m = 0.5 * (segment + np.roll(segment, 1)) * outline_map.perimeter_m
        rel = ref - disk.center_m
        kappa = outline_map.curvature_per_m(np.arctan2(rel[:, 1], rel[:, 0]) - outline_map.psi)
        outline = (kappa, outline_map.perimeter_m)
    extents, shares = [], []
    for side, forces in enumerate(face_forces_n):
        jaw = grip.jaws[side]
        joint, axis, normal = finger_frame(grip, side, float(jaw_angles_rad[side]))
        rel = p - joint
        if jaw.depth_m == 0.0:
            gap_m = bar_distance(rel @ axis, rel @ normal, grip.finger_length_m,
                                 grip.finger_width_m)
        else:
            local = jaw_gaps_local(scene, side, jaw, rel @ axis, rel @ normal)
            gap_m = local[:, JG_GAP]
        f = forces[order]
        phi = np.array([contact_indicator(float(f[i]), float(weight_m2[i]), float(spacing_m[i]),
                                          float(gap_m[i]), e_star) for i in range(f.size)])
        extent = float(contact_arc_share(phi, segment))
        extents.append(extent)
        if jaw.depth_m == 0.0 and outline is not None:
            k = outline_hertz_coefficient(_weighted_curvature(f, outline[0], outline[0]),
                                          FLAT_FACE_CURVATURE_PER_M, outline[1],
                                          disk.thickness_m, disk.youngs_modulus_pa,
                                          disk.poisson_ratio)
            shares.append(float(contact_share(extent, float(np.sum(f)), k)))
        elif jaw.depth_m == 0.0:
            shares.append(float(contact_share(extent, float(np.sum(f)), flat_k)))
        else:
            shares.append(_segment_shares(phi, segment, f, jaw_curvature_per_m(local), scene,
                                          outline))
    return (extents[0], extents[1]), (shares[0], shares[1])
