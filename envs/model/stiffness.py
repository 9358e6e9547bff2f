"""Spring stiffness rules of the fan (per unit ``s E t``, and in N/m for a disk).

``"van_gelder"`` is the area rule of docs/model.md, ``k_c = s E t sum_e A_e / |c|^2`` over the
triangles e that share spring c; ``"cst_fit"`` is a Poisson-aware rule. The disk's
``contour_stiffness_ratio`` multiplies the contour springs only, on top of ``s``.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from envs.model.defaults import MIN_TRIANGLES, MODEL_MAX_TRIANGLES
from envs.validation import check_integer, check_range

from .defaults import STIFFNESS_RULES

__all__ = ["DiskMaterial", "spring_stiffness", "disk_spring_stiffness"]


class DiskMaterial(Protocol):
    """What the stiffness rules read of a disk: an :class:`envs.scene.SoftDisk` or anything
    with these fields (the model sits below the scene and does not import it)."""

    radius_m: float  # r [m]
    youngs_modulus_pa: float  # E [Pa]
    poisson_ratio: float  # nu [-]
    thickness_m: float  # t [m]
    stiffness_scale: float  # s [-]
    contour_stiffness_ratio: float  # rho_c [-]


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
        ``"van_gelder"``: area rule ``k_c = s E t sum_e A_e / |c|^2`` of docs/model.md.
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
    # the rule is defined on every fan the model allows; which N a solve should use is the
    # public entry points' business (MAX_TRIANGLES)
    n = check_integer("n_triangles", n_triangles, MIN_TRIANGLES, MODEL_MAX_TRIANGLES)
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
    disk: DiskMaterial, n_triangles: int, rule: str = "van_gelder"
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
