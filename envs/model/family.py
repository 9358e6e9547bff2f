"""The model family's material scales derived from the physics (before any fit).

A triangle mesh of springs with the area rule obeys the Cauchy relations: on the equilateral
lattice its plane moduli are ``lambda_s = mu_s = 3 E s / 8`` whatever the Poisson ratio (van
Gelder's ``k = s E t sum A / L^2`` gives ``k = sqrt(3) s E t / 2`` per edge; a lattice of such
springs has ``lambda = mu = sqrt(3) k / (4 t)``). A disk of nu = 0.45 has ``lambda / mu = 9``
(plane strain), so springs alone cannot represent it (the fan's closing angles are 27-43 % off
the FEM at s = 1). The hybrid split of Golec et al. (2019) fixes both moduli with two scales:

* the springs carry the shear modulus: ``s = mu / (3 E / 8) = 4 / (3 (1 + nu))``;
* the area energy carries the rest of the bulk modulus ``K = lambda + mu``: the springs bring
  ``lambda_s + mu_s = 2 mu``, so ``kappa = K - 2 mu = lambda - mu``, i.e.
  ``c_A = (lambda - mu) / (lambda + mu)`` (:attr:`envs.scene.SoftDisk.area_stiffness_scale`
  is ``kappa / K``). This needs ``lambda >= mu`` (``nu >= 1/4`` in plane strain).

Both follow from E and nu alone; :func:`hybrid_scales` gives them and
:func:`hybrid_disk` puts them on a disk. The derivation is checked in the tests by
homogenising a periodic lattice of the model's own energy terms.

The constant-strain neo-Hookean member (``element="cst"``) has the material's own moduli and
needs one scale only: linear triangles of a nearly incompressible material lock (are too
stiff) on coarse meshes. :data:`CST_SCALES` ships that scale per member, fitted once against
the FEM (:func:`cst_disk` applies it).
"""

from __future__ import annotations

from dataclasses import replace

from ..validation import check_range
from .energy import lame_per_e

__all__ = ["CAUCHY_SHEAR_PER_E", "CST_SCALES", "hybrid_scales", "hybrid_disk", "cst_disk"]

#: Plane shear (and Lame) modulus of the equilateral area-rule spring lattice, per ``s E``.
CAUCHY_SHEAR_PER_E = 3.0 / 8.0


def hybrid_scales(poisson_ratio: float) -> tuple[float, float]:
    """Spring scale ``s`` and area scale ``c_A`` that give a ring mesh the plane-strain Lame
    moduli of a material of this Poisson ratio (see the module docstring).

    Parameters
    ----------
    poisson_ratio
        ``nu`` in [0.25, 0.5): below 1/4 the springs alone are already too stiff in bulk.

    Returns
    -------
    (float, float)
        ``(s, c_A)``; E cancels out.
    """
    nu = check_range("poisson_ratio", poisson_ratio, 0.25, 0.5, high_open=True)
    lam, mu = lame_per_e(nu)
    return mu / CAUCHY_SHEAR_PER_E, (lam - mu) / (lam + mu)


def hybrid_disk(disk):
    """``disk`` (an :class:`envs.scene.SoftDisk`) with the :func:`hybrid_scales` of its own
    Poisson ratio as ``stiffness_scale`` and ``area_stiffness_scale``."""
    s, c_a = hybrid_scales(disk.poisson_ratio)
    return replace(disk, stiffness_scale=s, area_stiffness_scale=c_a)


#: Calibration scale ``s`` of the constant-strain members ``(N, M) -> s``, with the fit's
#: closing-angle errors against the FEM (12 rings, plane strain). Provenance:
#: ``scripts/calibrate_family.py`` (2026-11-23): least squares of the relative closing-angle
#: error on the three paper disks over 0.05-0.5 N·m; held out: r = 0.06 and 0.085 m, E = 50
#: and 300 kPa, nu = 0.30 (r = 0.07 m) and nu = 0.40 (r = 0.05 m). Columns after the scale:
#: RMS on the paper disks, RMS over the held-out disks (worst single disk), largest held-out
#: error [%]. The errors fall with refinement; the largest is always at the lightest torque
#: (contact onset: the contour polygon lies r (1 - cos(pi/N)) inside the circle).
CST_SCALES = {
    (20, 3): (0.9338, 4.54, 2.84, 3.34, 8.92),
    (20, 4): (0.9714, 4.62, 2.91, 3.42, 9.11),
    (24, 4): (0.9111, 2.62, 2.48, 3.50, 8.21),
    (24, 6): (0.9541, 2.76, 2.64, 3.68, 8.94),
    (32, 6): (0.9166, 1.13, 1.23, 1.62, 4.03),
    (48, 8): (0.9289, 0.83, 0.96, 1.38, 2.09),
}


def cst_disk(disk, n_triangles: int, n_rings: int):
    """``disk`` with the shipped calibration scale of the constant-strain member ``(N, M)``
    (:data:`CST_SCALES`) as its ``stiffness_scale`` (its area scale is not used by that
    member). Raises ValueError for a member without a shipped scale."""
    key = (int(n_triangles), int(n_rings))
    if key not in CST_SCALES:
        raise ValueError(f"(n_triangles, n_rings) = {key} has no shipped calibration; one of "
                         f"{sorted(CST_SCALES)} (or fit one with scripts/calibrate_family.py)")
    return replace(disk, stiffness_scale=CST_SCALES[key][0])
