"""Contact: rim nodes, rigid obstacles (jaw faces, plate) and the tip corners of the jaws.

Node-to-face gaps with their derivatives with respect to the node positions and to the
obstacle's scalar unknown, and the corner-to-rim signed distance with its exact Hessian
(complex step of the analytic gradient). The penalty itself is applied by :mod:`.system`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from envs.model.contact_width import (
    contact_arc_share,
    contact_indicator,
    plane_strain_modulus_pa,
)
from envs.model.geometry import bar_distance, finger_frame
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
    def build(cls, body: _Body, arc_facets: np.ndarray, centre: np.ndarray, thickness_m: float):
        b, mesh = body.basis, body.mesh
        verts = mesh.facets[:, arc_facets]  # (2, nf)
        vdofs = b.nodal_dofs[:, verts]  # (2 comps, 2 ends, nf)
        mdofs = b.facet_dofs[:, arc_facets]  # (2 comps, nf)
        pa = mesh.p[:, verts[0]] - centre[:, None]
        pb = mesh.p[:, verts[1]] - centre[:, None]
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
    extent, ``dg/dp`` (m, 2), ``dg/dq``, ``d2g/dq2`` and ``d2g/dp dq`` (m, 2).
    """

    qi: int

    def evaluate(self, p: np.ndarray, q: float):  # pragma: no cover - interface
        raise NotImplementedError


class _JawFace(_Obstacle):
    """Gripping face of one finger (docs/model.md): ``g = n.(p - J) - w/2``, 0 <= e.(p-J) <= l."""

    def __init__(self, scene: Scene, side: int, qi: int) -> None:
        self.gripper = scene.gripper
        self.side = side
        self.qi = qi

    def evaluate(self, p: np.ndarray, q: float):
        joint, axis, normal = finger_frame(self.gripper, self.side, q)
        rel = p - joint
        s = rel @ axis
        m = rel @ normal
        g = m - 0.5 * self.gripper.finger_width_m
        valid = (s >= 0.0) & (s <= self.gripper.finger_length_m)
        # dn/dtheta = e and de/dtheta = -n for both fingers
        dgdp = np.broadcast_to(normal, p.shape)
        return g, valid, dgdp, s, -m, np.broadcast_to(axis, p.shape)


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
        return g, np.ones(m, dtype=bool), dgdp, -np.ones(m), zeros, np.zeros((m, 2))


class _JawTip:
    """Tip corner ``c = J + l e + (w/2) n`` of one finger's gripping face (driven by ``q``)."""

    def __init__(self, scene: Scene, side: int, qi: int) -> None:
        self.gripper = scene.gripper
        self.side = side
        self.qi = qi

    def evaluate(self, q: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Corner position and its first and second derivatives with respect to ``q``."""
        joint, axis, normal = finger_frame(self.gripper, self.side, q)
        ln, hw = self.gripper.finger_length_m, 0.5 * self.gripper.finger_width_m
        # de/dtheta = -n and dn/dtheta = e for both fingers
        return joint + ln * axis + hw * normal, -ln * normal + hw * axis, -ln * axis - hw * normal


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


def rim_contact_shares(scene: Scene, rim: _Rim, order: np.ndarray, positions_m: np.ndarray,
                       face_forces_n: list[np.ndarray], jaw_angles_rad: np.ndarray
                       ) -> tuple[float, float]:
    """Share of the rim in contact with each jaw's face, interpolated between rim nodes: the
    point-spring model's measure (:mod:`envs.model.contact_width`) on the FEM's rim.

    Parameters
    ----------
    scene
        The grasped scene (the gripper's bars; the disk's ``E``, ``nu``, its centre).
    rim
        The rim nodes (reference positions, their share of the rim times the thickness).
    order
        The rim nodes counter-clockwise (indices into ``rim``).
    positions_m
        Deformed rim node positions [m], (m, 2), in ``rim``'s order.
    face_forces_n
        Each face's penalty force on each rim node [N], two arrays (m,) in ``rim``'s order.
    jaw_angles_rad
        The fingers' angles [rad], (2,).

    Returns
    -------
    tuple of float
        Right and left face's share: each rim segment between neighbours counts with its share
        of the reference rim, in full where both nodes press, in part where one does
        (:func:`~envs.model.contact_width.contact_arc_share`). A pressed node's indicator
        takes its pressure (force over its Simpson weight) and its spacing (the mean of its two
        segments), a free node's its distance to the finger's bar.
    """
    disk, grip = scene.disk, scene.gripper
    e_star = plane_strain_modulus_pa(disk.youngs_modulus_pa, disk.poisson_ratio)
    ref = rim.ref_m[order] - disk.center_m
    angle = np.arctan2(ref[:, 1], ref[:, 0])
    segment = np.mod(np.roll(angle, -1) - angle, 2 * math.pi) / (2 * math.pi)
    spacing_m = 0.5 * (segment + np.roll(segment, 1)) * 2 * math.pi * disk.radius_m
    weight_m2 = rim.weight_m2[order]
    p = positions_m[order]
    shares = []
    for side, forces in enumerate(face_forces_n):
        joint, axis, normal = finger_frame(grip, side, float(jaw_angles_rad[side]))
        rel = p - joint
        gap_m = bar_distance(rel @ axis, rel @ normal, grip.finger_length_m,
                             grip.finger_width_m)
        f = forces[order]
        phi = np.array([contact_indicator(float(f[i]), float(weight_m2[i]), float(spacing_m[i]),
                                          float(gap_m[i]), e_star) for i in range(f.size)])
        shares.append(float(contact_arc_share(phi, segment)))
    return shares[0], shares[1]
