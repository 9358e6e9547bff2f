"""Point-spring model (PSM) of the disk: discretization, stiffness rules and energy.

The disk is a fan of ``N`` isosceles triangles around its pinned centre: ``N`` contour points,
``N`` radial springs (rest length ``r``) and ``N`` contour springs (rest length
``h = 2 r sin(pi/N)``). Everything the solver needs is packed in a :class:`ScaledProblem`, a
non-dimensional copy of the scene (lengths in units of ``r``, stiffness in units of ``s E t``),
so tolerances are independent of the physical size. The disk's ``contour_stiffness_ratio``
multiplies the contour springs only (on top of ``s``), see :func:`disk_spring_stiffness`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scene import Scene, SoftDisk, check_range, closed_angle_rad, finger_frame

__all__ = [
    "STIFFNESS_RULES",
    "MIN_TRIANGLES",
    "MAX_TRIANGLES",
    "spring_stiffness",
    "disk_spring_stiffness",
    "rest_points",
    "ScaledProblem",
    "corner_radius",
    "scaled_problem",
    "spring_strains",
    "energy_scaled",
    "gradient_scaled",
]

MIN_TRIANGLES = 4
MAX_TRIANGLES = 20000
STIFFNESS_RULES = ("van_gelder", "cst_fit")


def _cst_stiffness(points: np.ndarray, nu: float) -> np.ndarray:
    """Plane-stress linear stiffness matrix (6x6) of a constant-strain triangle, per ``E t``."""
    (x1, y1), (x2, y2), (x3, y3) = points
    area = 0.5 * ((x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1))
    b = np.array([y2 - y3, y3 - y1, y1 - y2])
    c = np.array([x3 - x2, x1 - x3, x2 - x1])
    bm = np.zeros((3, 6))
    bm[0, 0::2] = b
    bm[1, 1::2] = c
    bm[2, 0::2] = c
    bm[2, 1::2] = b
    bm /= 2 * area
    dm = np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]]) / (1 - nu**2)
    return area * bm.T @ dm @ bm


def _spring_matrix(points: np.ndarray, a: int, b: int) -> np.ndarray:
    """Linear stiffness (6x6) of a unit spring between triangle vertices ``a`` and ``b``."""
    d = points[b] - points[a]
    d = d / np.linalg.norm(d)
    k = np.zeros((6, 6))
    dd = np.outer(d, d)
    for i, j, sgn in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
        k[2 * i : 2 * i + 2, 2 * j : 2 * j + 2] = sgn * dd
    return k


def spring_stiffness(
    n_triangles: int, radius_m: float, rule: str = "van_gelder", poisson_ratio: float = 0.45
) -> tuple[float, float]:
    """Radial and contour spring stiffness per unit ``s E t`` [-].

    Parameters
    ----------
    n_triangles
        Number of fan triangles ``N`` (>= 4: with 3 the triangles are obtuse).
    radius_m
        Disk radius ``r`` [m] (the rules are scale free; kept for clarity of units).
    rule
        ``"van_gelder"``: area rule ``k_c = s E t sum_e A_e / |c|^2`` of CONVENTIONS.md.
        ``"cst_fit"``: Poisson-aware rule; the three spring stiffnesses of each triangle are the
        least-squares fit of its plane-stress constant-strain (linear FEM) stiffness matrix, in
        the spirit of Lloyd, Szekely and Harders (2007); shared springs add both triangles'.
    poisson_ratio
        Poisson's ratio, used by ``"cst_fit"`` only.

    Returns
    -------
    k_int, k_ext : float
        Radial (internal) and contour (external) stiffness divided by ``s E t``.

    Raises
    ------
    ValueError
        For an unknown rule, ``N`` out of range, or a rule giving a non-positive stiffness.
    """
    n = _check_n(n_triangles)
    check_range("radius_m", radius_m, 0.0, math.inf, low_open=True)
    if rule not in STIFFNESS_RULES:
        raise ValueError(f"stiffness rule {rule!r} is unknown; allowed: {STIFFNESS_RULES}")
    phi = 2 * math.pi / n
    if rule == "van_gelder":
        area = 0.5 * math.sin(phi)  # per r^2
        h = 2 * math.sin(math.pi / n)
        k_int, k_ext = 2 * area, area / h**2
    else:
        tri = np.array([[0.0, 0.0], [1.0, 0.0], [math.cos(phi), math.sin(phi)]])
        target = _cst_stiffness(tri, poisson_ratio)
        basis = [_spring_matrix(tri, 0, 1), _spring_matrix(tri, 0, 2), _spring_matrix(tri, 1, 2)]
        a = np.array([[np.sum(bi * bj) for bj in basis] for bi in basis])
        rhs = np.array([np.sum(bi * target) for bi in basis])
        k_r1, k_r2, k_c = np.linalg.solve(a, rhs)
        # each radial spring is shared by two triangles, each contour spring belongs to one
        k_int, k_ext = float(k_r1 + k_r2), float(k_c)
    if k_int <= 0 or k_ext <= 0:
        raise ValueError(
            f"stiffness rule {rule!r} gives a non-positive spring stiffness "
            f"(k_int={k_int:.3g}, k_ext={k_ext:.3g}) for n_triangles={n}; use more triangles"
        )
    return float(k_int), float(k_ext)


def disk_spring_stiffness(
    disk: SoftDisk, n_triangles: int, rule: str = "van_gelder"
) -> tuple[float, float]:
    """Physical radial and contour spring stiffness of a disk's fan [N/m].

    ``k_int = s E t k_int'`` and ``k_ext = rho_c s E t k_ext'`` with ``k_int', k_ext'`` from
    :func:`spring_stiffness`, ``s`` the disk's ``stiffness_scale`` and ``rho_c`` its
    ``contour_stiffness_ratio`` (which multiplies the contour springs only).

    Parameters
    ----------
    disk
        The disk (radius, material, thickness and both calibration factors).
    n_triangles
        Number of fan triangles ``N``.
    rule
        Stiffness rule, see :func:`spring_stiffness`.

    Returns
    -------
    k_int_n_per_m, k_ext_n_per_m : float
        Radial (internal) and contour (external) spring stiffness [N/m].
    """
    k_int, k_ext = spring_stiffness(n_triangles, disk.radius_m, rule, disk.poisson_ratio)
    k_unit = disk.stiffness_scale * disk.youngs_modulus_pa * disk.thickness_m  # N/m
    return k_int * k_unit, k_ext * disk.contour_stiffness_ratio * k_unit


def _check_n(n_triangles: int) -> int:
    if isinstance(n_triangles, bool) or int(n_triangles) != n_triangles:
        raise ValueError(f"n_triangles must be an integer, got {n_triangles!r}")
    n = int(n_triangles)
    if not MIN_TRIANGLES <= n <= MAX_TRIANGLES:
        raise ValueError(
            f"n_triangles = {n} is outside the allowed range [{MIN_TRIANGLES}, {MAX_TRIANGLES}] "
            "(N = 3 gives 120-degree triangles, i.e. negative stiffness)"
        )
    return n


def rest_points(n_triangles: int, phase_rad: float = math.pi / 2) -> np.ndarray:
    """Unit contour points of the fan, counter-clockwise, the first at ``phase_rad``."""
    ang = phase_rad + 2 * math.pi * np.arange(n_triangles) / n_triangles
    return np.column_stack([np.cos(ang), np.sin(ang)])


@dataclass(frozen=True)
class ScaledProblem:
    """Non-dimensional grasp problem: lengths / r, forces / (s E t r), torques / (s E t r^2).

    Attributes
    ----------
    n : int
        Number of triangles.
    params : numpy.ndarray
        Packed parameters for the compiled solver (see :mod:`envs.kernels`).
    length_m, force_n, torque_nm : float
        Units used for scaling back to SI.
    """

    n: int
    params: np.ndarray
    length_m: float
    force_n: float
    torque_nm: float

    @property
    def k_int(self) -> float:
        return float(self.params[0])

    @property
    def k_ext(self) -> float:
        return float(self.params[1])

    @property
    def rest_contour(self) -> float:
        return float(self.params[2])


# Layout of ScaledProblem.params (shared with envs.kernels).
P_KR, P_KC, P_H, P_C0X, P_C0Y, P_C1X, P_C1Y, P_HW, P_LMAX = range(9)
P_TAU, P_KAPPA, P_TH0, P_THMIN, P_PHASE, P_RHO = range(9, 15)
N_PARAMS = 15
# Finger end corners are rounded with this radius (fraction of the disk radius, at most a tenth
# of the half width): it makes point-on-corner contact differentiable; its effect on the
# geometry is below 1e-3 r.
CORNER_ROUNDING = 1e-3


def corner_radius(finger_width_m: float, radius_m: float) -> float:
    """Rounding radius of the finger end corners [m] (see :data:`CORNER_ROUNDING`)."""
    return min(CORNER_ROUNDING * radius_m, 0.05 * finger_width_m)


def scaled_problem(
    scene: Scene,
    torque_nm: float,
    n_triangles: int = 20,
    stiffness_rule: str = "van_gelder",
    phase_rad: float = math.pi / 2,
) -> ScaledProblem:
    """Pack a scene and an actuation torque into a :class:`ScaledProblem`.

    Parameters
    ----------
    scene
        Gripper and disk; the disk's ``stiffness_scale`` sets the stiffness unit ``s E t`` and
        its ``contour_stiffness_ratio`` multiplies the scaled contour stiffness ``P_KC``.
    torque_nm
        Actuation torque ``T_a`` on each finger [N·m], >= 0.
    n_triangles
        Number of fan triangles ``N``.
    stiffness_rule
        See :func:`spring_stiffness`.
    phase_rad
        Angle of the first contour point [rad] (pi/2: top, mirror-symmetric for even N).
    """
    check_range("torque_nm", torque_nm, 0.0, math.inf)
    check_range("phase_rad", phase_rad)
    n = _check_n(n_triangles)
    g, d = scene.gripper, scene.disk
    r = d.radius_m
    k_unit = d.stiffness_scale * d.youngs_modulus_pa * d.thickness_m  # N/m
    k_int, k_ext = spring_stiffness(n, r, stiffness_rule, d.poisson_ratio)
    k_ext *= d.contour_stiffness_ratio  # second calibration factor, contour springs only
    p = np.zeros(N_PARAMS)
    p[P_KR], p[P_KC], p[P_H] = k_int, k_ext, 2 * math.sin(math.pi / n)
    centre = d.center_m
    for side, (ix, iy) in enumerate(((P_C0X, P_C0Y), (P_C1X, P_C1Y))):
        joint, _, _ = finger_frame(g, side, g.rest_angle_rad)
        p[ix], p[iy] = (centre - joint) / r
    p[P_HW] = g.finger_width_m / (2 * r)
    p[P_LMAX] = g.finger_length_m / r
    p[P_TAU] = torque_nm / (k_unit * r**2)
    p[P_KAPPA] = g.torsion_stiffness_nm_per_rad / (k_unit * r**2)
    p[P_TH0] = g.rest_angle_rad
    p[P_THMIN] = closed_angle_rad(g)
    p[P_PHASE] = phase_rad
    p[P_RHO] = corner_radius(g.finger_width_m, r) / r
    return ScaledProblem(n, p, r, k_unit * r, k_unit * r**2)


def spring_strains(q: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Engineering strains ``(L - L0) / L0`` of the radial and contour springs.

    Parameters
    ----------
    q
        Contour points relative to the centre, in units of ``r``, shape (N, 2).
    h
        Contour rest length in units of ``r``.
    """
    radial = np.linalg.norm(q, axis=1) - 1.0
    contour = np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1) / h - 1.0
    return radial, contour


def energy_scaled(x: np.ndarray, prob: ScaledProblem) -> float:
    """Total potential energy (springs + actuation + torsion springs), scaled [-].

    ``x`` holds the N contour points (relative to the centre, in units of ``r``) followed by the
    right and left finger angles.
    """
    p, n = prob.params, prob.n
    q = x[: 2 * n].reshape(n, 2)
    th = x[2 * n : 2 * n + 2]
    lr = np.linalg.norm(q, axis=1)
    lc = np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1)
    e = 0.5 * p[P_KR] * np.sum((lr - 1.0) ** 2) + 0.5 * p[P_KC] * np.sum((lc - p[P_H]) ** 2)
    return float(e + np.sum(p[P_TAU] * th + 0.5 * p[P_KAPPA] * (th - p[P_TH0]) ** 2))


def gradient_scaled(x: np.ndarray, prob: ScaledProblem) -> np.ndarray:
    """Gradient of :func:`energy_scaled`."""
    p, n = prob.params, prob.n
    q = x[: 2 * n].reshape(n, 2)
    th = x[2 * n : 2 * n + 2]
    lr = np.linalg.norm(q, axis=1)
    d = np.roll(q, -1, axis=0) - q
    lc = np.linalg.norm(d, axis=1)
    g = (p[P_KR] * (lr - 1.0) / lr)[:, None] * q
    fc = (p[P_KC] * (lc - p[P_H]) / lc)[:, None] * d
    g -= fc
    g += np.roll(fc, 1, axis=0)
    out = np.empty_like(x)
    out[: 2 * n] = g.ravel()
    out[2 * n :] = p[P_TAU] + p[P_KAPPA] * (th - p[P_TH0])
    return out
