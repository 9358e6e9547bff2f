"""Reference equilibrium check in plain numpy (the former envs/kkt.py), kept for the tests.

The compiled check of :mod:`envs.check` must reach its verdicts; this file is slow (~2 ms a
grasp) and shares nothing with the solver.

Recomputes, from the returned positions, angles and contact forces only, and with plain numpy
code that shares nothing with the compiled solver: the spring forces, the force balance at every
contour point, the moment balance at each joint, the gaps to the real (finite) finger faces and
corners, the sign of every contact force and complementarity.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from envs.model.geometry import closed_angle_rad, corner_radius, finger_frame
from envs.model.stiffness import spring_stiffness
from envs.scene import Scene

__all__ = ["KKTReport", "kkt_check", "FORCE_TOL", "GAP_TOL"]

FORCE_TOL = 1e-8  # relative force and moment residual
GAP_TOL = 1e-9  # contact gap tolerance, in units of the radius


class KKTReport(NamedTuple):
    """Outcome of :func:`kkt_check` (relative residuals are dimensionless)."""

    passed: bool
    force_residual_rel: float
    moment_residual_rel: float
    max_penetration_m: float
    max_contact_gap_m: float
    min_contact_force_n: float
    reason: str


def _point_in_polygon(pt: np.ndarray, poly: np.ndarray) -> bool:
    x, y = pt
    inside = False
    n = len(poly)
    for i in range(n):
        x1, y1 = poly[i]
        x2, y2 = poly[(i + 1) % n]
        if (y1 > y) != (y2 > y):
            xc = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            if xc > x:
                inside = not inside
    return inside


def _dist_to_polygon(pt: np.ndarray, poly: np.ndarray) -> float:
    a = poly
    b = np.roll(poly, -1, axis=0)
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", pt - a, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
    proj = a + t[:, None] * d
    return float(np.min(np.linalg.norm(pt - proj, axis=1)))


def _edges_crossing(a: np.ndarray, b: np.ndarray, poly: np.ndarray) -> int:
    """Number of polygon edges that properly cross the segment a-b."""
    p, q = poly, np.roll(poly, -1, axis=0)

    def orient(u, v, w):
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (
            v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])

    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    return int(np.count_nonzero((d1 * d2 < 0) & (d3 * d4 < 0)))


def kkt_check(
    scene: Scene,
    torque_nm: float,
    n_triangles: int,
    stiffness_rule: str,
    points_m: np.ndarray,
    jaw_angles_rad: tuple[float, float],
    face_forces_n: np.ndarray,
    corner_forces_n: np.ndarray,
    stop_torques_nm: np.ndarray,
) -> KKTReport:
    """Check equilibrium and contact conditions of a grasp.

    Parameters
    ----------
    scene, torque_nm, n_triangles, stiffness_rule
        The problem that was solved.
    points_m
        Contour points [m], shape (N, 2).
    jaw_angles_rad
        Right and left finger angles [rad].
    face_forces_n
        Normal force of each finger face on each point [N], shape (2, N).
    corner_forces_n
        Force of each finger's rounded corners (tip and root of the gripping face, tip and root
        of the back of the bar) on each contour edge ``(k, k+1)`` [N], shape (2, 4, N), or the
        solver's (2, 6, N) with the mouth corners of a jaw groove unloaded. The force acts
        along the shortest segment between the corner's centre and the edge.
    stop_torques_nm
        Torques of the closed-jaw stops [N·m], (2,).

    Returns
    -------
    KKTReport
        ``passed`` when the relative force and moment residuals are below :data:`FORCE_TOL`,
        the gaps satisfy :data:`GAP_TOL` and all contact forces are non-negative.
    """
    g, d = scene.gripper, scene.disk
    r = d.radius_m
    n = len(points_m)
    k_unit = d.stiffness_scale * d.youngs_modulus_pa * d.thickness_m
    k_int, k_ext = (k * k_unit for k in spring_stiffness(n, r, stiffness_rule, d.poisson_ratio))
    k_ext *= getattr(d, "contour_stiffness_ratio", 1.0)
    h = 2 * r * math.sin(math.pi / n)
    centre = d.center_m
    p = np.asarray(points_m, dtype=float)
    corner_forces = np.asarray(corner_forces_n, dtype=float)
    if corner_forces.shape == (2, 6, n):
        # the solver's layout adds a jaw groove's two mouth edges; this reference knows the
        # straight bar only, whose mouth corners carry nothing
        if corner_forces[:, 4:].any() or any(jaw.depth_m > 0.0 for jaw in g.jaws):
            raise ValueError("the reference check knows straight jaws only")
        corner_forces = corner_forces[:, :4]
    if corner_forces.shape != (2, 4, n):
        raise ValueError(f"corner_forces_n must have shape (2, 4, {n}), got {corner_forces.shape}")
    force = np.zeros_like(p)  # net force on each contour point
    spring_mag = []
    for i in range(n):
        v = p[i] - centre
        length = math.hypot(*v)
        f = k_int * (length - r)
        force[i] -= f * v / length
        spring_mag.append(abs(f))
        w = p[(i + 1) % n] - p[i]
        length = math.hypot(*w)
        f = k_ext * (length - h)
        force[i] += f * w / length
        force[(i + 1) % n] -= f * w / length
        spring_mag.append(abs(f))
    moments = np.zeros(2)
    theta_min = closed_angle_rad(g)
    max_pen = 0.0
    max_gap = 0.0
    min_force = math.inf
    contact_scale = [0.0]
    hw = g.finger_width_m / 2
    rho = corner_radius(g.finger_width_m, r)  # rounded end corners, centres at hw - rho
    for j in range(2):
        theta = jaw_angles_rad[j]
        joint, axis, normal = finger_frame(g, j, theta)
        sign = 1.0 if j == 0 else -1.0  # closing is +z for the right finger, -z for the left
        closing = torque_nm - g.torsion_stiffness_nm_per_rad * (g.rest_angle_rad - theta)
        moments[j] += sign * closing
        moments[j] -= sign * stop_torques_nm[j]
        contact_scale.append(abs(closing))
        rel = p - joint
        s = rel @ axis
        m = rel @ normal
        # the finger body: the bar 0 <= s <= l, |m| <= w/2 with corners rounded to rho, i.e.
        # the rectangle [0, l] x [-(w/2 - rho), w/2 - rho] grown by rho
        ds = s - np.clip(s, 0.0, g.finger_length_m)
        dm = m - np.clip(m, -(hw - rho), hw - rho)
        for i in range(n):
            dist = math.hypot(ds[i], dm[i])
            gap = dist - rho
            direction = (ds[i] * axis + dm[i] * normal) / dist if dist > 0 else normal
            at = p[i] - gap * direction  # the touching point of the finger surface
            max_pen = max(max_pen, -gap)
            lam = face_forces_n[j, i]
            if lam != 0.0:
                min_force = min(min_force, lam)
                max_gap = max(max_gap, abs(gap))
                force[i] += lam * direction
                arm = at - joint
                moments[j] += arm[0] * (-lam * direction[1]) - arm[1] * (-lam * direction[0])
                contact_scale.append(abs(lam) * math.hypot(*arm))
        if _edges_crossing(joint, joint + g.finger_length_m * axis, p):
            # the bar runs right through the disk: points and corners are all outside
            max_pen = max(max_pen, hw)
        for c in range(4):  # tip and root of the gripping face, then of the back
            sc = g.finger_length_m if c % 2 == 0 else 0.0
            side = 1.0 if c < 2 else -1.0
            corner = joint + sc * axis + side * (hw - rho) * normal
            depth = _dist_to_polygon(corner, p)
            depth = rho + depth if _point_in_polygon(corner, p) else rho - depth
            max_pen = max(max_pen, depth)
            for k in np.flatnonzero(corner_forces[j, c]):
                lam = corner_forces[j, c, k]
                a, b = p[k], p[(k + 1) % n]
                dvec = b - a
                t = min(1.0, max(0.0, float((corner - a) @ dvec) / float(dvec @ dvec)))
                vec = corner - (a + t * dvec)  # from the nearest point of the edge
                dist = math.hypot(*vec)
                gap = dist - rho
                nu = vec / dist if dist > 0 else np.zeros(2)
                min_force = min(min_force, lam)
                max_gap = max(max_gap, abs(gap))
                force[k] -= (1 - t) * lam * nu
                force[(k + 1) % n] -= t * lam * nu
                arm = corner - joint
                moments[j] += arm[0] * (lam * nu[1]) - arm[1] * (lam * nu[0])
                contact_scale.append(abs(lam) * math.hypot(*arm))
        if stop_torques_nm[j] != 0.0:
            min_force = min(min_force, stop_torques_nm[j])
            if abs(theta - theta_min) > GAP_TOL:
                max_gap = max(max_gap, abs(theta - theta_min) * r)
    # floor: the spring force of a 1e-4 strain, so that an unloaded disk is judged absolutely
    f_floor = 1e-4 * k_ext * r
    f_ref = max(max(spring_mag), float(np.max(np.abs(face_forces_n))), f_floor)
    f_ref = max(f_ref, float(np.max(np.abs(corner_forces), initial=0.0)))
    m_ref = max(max(contact_scale), torque_nm, f_floor * g.finger_length_m)
    f_res = float(np.max(np.abs(force))) / f_ref
    m_res = float(np.max(np.abs(moments))) / m_ref
    min_force = 0.0 if min_force == math.inf else min_force
    reasons = []
    if not f_res <= FORCE_TOL:
        reasons.append(f"force residual {f_res:.2e} > {FORCE_TOL:g}")
    if not m_res <= FORCE_TOL:
        reasons.append(f"moment residual {m_res:.2e} > {FORCE_TOL:g}")
    if not max_pen <= GAP_TOL * r:
        reasons.append(f"penetration {max_pen:.2e} m > {GAP_TOL:g} r")
    if not max_gap <= GAP_TOL * r:
        reasons.append(f"loaded contact with gap {max_gap:.2e} m > {GAP_TOL:g} r")
    if min_force < 0:
        reasons.append(f"negative contact force {min_force:.2e} N")
    return KKTReport(
        passed=not reasons,
        force_residual_rel=f_res,
        moment_residual_rel=m_res,
        max_penetration_m=max_pen,
        max_contact_gap_m=max_gap,
        min_contact_force_n=min_force,
        reason="; ".join(reasons) if reasons else "ok",
    )
