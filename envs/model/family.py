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
"""

from __future__ import annotations

from dataclasses import replace

from ..validation import check_range

__all__ = ["CAUCHY_SHEAR_PER_E", "hybrid_scales", "hybrid_disk"]

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
    lam = nu / ((1.0 + nu) * (1.0 - 2.0 * nu))  # per E
    mu = 1.0 / (2.0 * (1.0 + nu))
    return mu / CAUCHY_SHEAR_PER_E, (lam - mu) / (lam + mu)


def hybrid_disk(disk):
    """``disk`` (an :class:`envs.scene.SoftDisk`) with the :func:`hybrid_scales` of its own
    Poisson ratio as ``stiffness_scale`` and ``area_stiffness_scale``."""
    s, c_a = hybrid_scales(disk.poisson_ratio)
    return replace(disk, stiffness_scale=s, area_stiffness_scale=c_a)
