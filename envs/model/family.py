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

The nh-quad member (``element="nhquad"``) moves the volumetric term from the triangles to the
quads, which removes the locking; what is left is the stiffness of linear triangles in bending
of a coarse ring layer, which depends on the ring count M and not on nu, nor on N near the N
it was fitted at (measured): one scale per M, :data:`NHQUAD_SCALES`, below 1 and rising towards
1 as the rings refine. Far from the fitted N the triangles' shape changes and so does the
error (``scripts/fig5_error_vs_n.py``, r = 0.10 m, M = 2: 9 % RMS at N = 20, 1.2 % at 40,
2.4 % at 64, 3.5 % at 200): refine N and M together; :func:`calibration_scale` warns outside
the range.

A shipped scale multiplies the disk's own ``stiffness_scale``: that field stays the user's
material calibration (1 for the paper disks, 0.033 for the paper's TPU forceps), the member's
scale corrects the discretization (:func:`calibration_scale`, :func:`calibrated_disk`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from typing import NamedTuple

from ..validation import (
    PsmGraspWarning,
    check_choice,
    check_integer,
    check_n_triangles,
    check_range,
)
from .defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_MODEL_N_TRIANGLES,
    DEFAULT_MODEL_RINGS,
    MAX_SPRING_CELL_ASPECT,
    MAX_TRIANGLES,
    MAX_TRIANGLES_FAMILY,
    MIN_TRIANGLES,
    PAPER_N_TRIANGLES,
)
from .energy import lame_per_e
from .rings import HUB_RADIUS, MAX_RINGS

__all__ = ["CAUCHY_SHEAR_PER_E", "CST_SCALES", "NHQUAD_SCALES", "hybrid_scales", "hybrid_disk",
           "cst_disk", "calibration_scale", "calibrated_disk", "ModelSpec", "resolve_model",
           "ELEMENTS", "spring_cell_aspect", "triangle_range"]

#: Element energies of the model family: springs (and the area energy), the constant-strain
#: neo-Hookean triangle, or nh-quad (those triangles' deviatoric part and a volumetric term
#: per quad, :mod:`envs.model.energy`).
ELEMENTS = ("spring", "cst", "nhquad")


class ModelSpec(NamedTuple):
    """A validated member of the model family: contour points ``N``, rings ``M``, element and
    the factor on the disk's ``stiffness_scale`` (the member's shipped calibration, or 1)."""

    n_triangles: int
    n_rings: int
    element: str
    scale: float

    def kwargs(self) -> dict:
        """Keyword arguments that select this member in :func:`envs.simulate` and
        :func:`envs.evaluate_designs`."""
        return {"n_triangles": self.n_triangles, "n_rings": self.n_rings,
                "element": self.element, "calibrated": self.scale != 1.0}


def spring_cell_aspect(n_triangles: int, n_rings: int) -> float:
    """Depth over width of a cell of the spring ring mesh (``M >= 2``).

    The rings are spaced geometrically from the hub (:mod:`envs.model.rings`), so every layer's
    cells have the same shape: depth ``(1 - h^(1/M)) rho`` over width ``2 pi rho / N``.
    """
    return (1.0 - HUB_RADIUS ** (1.0 / n_rings)) * n_triangles / (2.0 * math.pi)


def triangle_range(n_rings: int, element: str) -> tuple[int, int]:
    """Contour points ``N`` a member with ``n_rings`` rings of ``element`` accepts.

    The springs-only fan to :data:`MAX_TRIANGLES` (it stops converging reliably beyond); a
    spring ring mesh only while its cells' aspect (:func:`spring_cell_aspect`) is within
    :data:`MAX_SPRING_CELL_ASPECT` of square (its springs lose the shear stiffness the hybrid
    scales assume, see ``envs/model/defaults.py``); the other members to
    :data:`MAX_TRIANGLES_FAMILY`.
    """
    if element != "spring":
        return MIN_TRIANGLES, MAX_TRIANGLES_FAMILY
    if n_rings == 1:
        return MIN_TRIANGLES, MAX_TRIANGLES
    per_aspect = 2.0 * math.pi / (1.0 - HUB_RADIUS ** (1.0 / n_rings))
    low = max(MIN_TRIANGLES, math.ceil(per_aspect / MAX_SPRING_CELL_ASPECT - 1e-9))
    high = per_aspect * MAX_SPRING_CELL_ASPECT + 1e-9
    return low, MAX_TRIANGLES_FAMILY if high >= MAX_TRIANGLES_FAMILY else math.floor(high)


def _check_triangles(n_triangles, n_rings: int, element: str) -> int:
    if element == "spring" and n_rings == 1:
        return check_n_triangles(n_triangles)
    n = check_integer("n_triangles", n_triangles, MIN_TRIANGLES, MAX_TRIANGLES_FAMILY)
    low, high = triangle_range(n_rings, element)
    if not low <= n <= high:  # only a spring ring mesh has a narrower range
        raise ValueError(
            f"n_triangles = {n} is outside the allowed range [{low}, {high}] for element "
            f"'spring' with n_rings = {n_rings}: its cells would be "
            f"{spring_cell_aspect(n, n_rings):.2f} times as deep as wide (allowed "
            f"{1 / MAX_SPRING_CELL_ASPECT:.1f}-{MAX_SPRING_CELL_ASPECT:.1f}), where springs "
            "lose the shear stiffness the model assumes; use more rings, or element "
            "'nhquad' or 'cst' for a finer contour")
    return n


def resolve_model(n_triangles=None, n_rings=None, element=DEFAULT_ELEMENT,
                  calibrated=None) -> ModelSpec:
    """Validate a member of the family, with the defaults filled in.

    Parameters
    ----------
    n_triangles
        Contour points ``N`` in :func:`triangle_range`: 4 to ``MAX_TRIANGLES`` = 500 for the
        springs-only fan (it stops converging reliably beyond), cells of aspect 0.4-2.5 for a
        spring ring mesh (M = 2: N 4-22, M = 8: 11-62), 4 to ``MAX_TRIANGLES_FAMILY`` = 2000
        otherwise. ``None``: 40 for ``"nhquad"`` (the default model), the paper's 20 otherwise
        (within every spring ring mesh's range).
    n_rings
        Rings ``M``, 1 to 16 (2 to 16 for ``"nhquad"``). ``None``: 2 for ``"nhquad"``, 1 (the
        paper's fan) otherwise.
    element
        One of :data:`ELEMENTS`; default ``"nhquad"`` (the default model); ``"spring"`` with
        the other defaults is the paper's fan.
    calibrated
        ``None`` (default): the member's shipped scale where it has one
        (:func:`calibration_scale`), else 1; ``True``: the shipped scale, a ValueError if
        there is none; ``False``: 1 (the member as is, e.g. to reproduce the paper).
    """
    element = check_choice("element", element, ELEMENTS)
    quad = element == "nhquad"
    m = (DEFAULT_MODEL_RINGS if quad else 1) if n_rings is None else check_integer(
        "n_rings", n_rings, 2 if quad else 1, MAX_RINGS)
    if n_triangles is None:
        n = DEFAULT_MODEL_N_TRIANGLES if quad else PAPER_N_TRIANGLES
    else:
        n = _check_triangles(n_triangles, m, element)
    if calibrated is None:
        # (no try/except: raising for every fan costs a call ~2 us)
        shipped = m in NHQUAD_SCALES if quad else (element == "cst" and (n, m) in CST_SCALES)
        scale = calibration_scale(n, m, element) if shipped else 1.0
    elif isinstance(calibrated, bool):
        scale = calibration_scale(n, m, element) if calibrated else 1.0
    else:
        raise ValueError(f"calibrated must be None, True or False, got {calibrated!r}")
    return ModelSpec(n, m, element, scale)

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


#: Calibration scale of the nh-quad members by ring count ``M -> (s, fitted over N, RMS on the
#: paper disks, worst held-out disk RMS, largest held-out error)`` (errors in %, at the middle
#: N of the fit). Provenance: ``scripts/calibrate_family.py --element nhquad`` (2026-11-24):
#: least squares of the relative closing-angle error against the FEM (P2, r/12, plane strain)
#: on the three paper disks over 0.05-0.5 N·m and the listed N at once; held out: r = 0.06 and
#: 0.085 m, E = 50 and 300 kPa, nu = 0.30 (r = 0.07 m) and nu = 0.40 (r = 0.05 m), never fitted.
#: The scale rises towards 1 and the error falls as the rings refine (the FEM is the limit).
NHQUAD_SCALES = {
    2: (0.8389, (32, 40, 48), 0.92, 1.49, 2.87),
    3: (0.9046, (40, 48, 56), 0.78, 0.92, 2.36),
    4: (0.9348, (48, 56, 64), 0.38, 0.63, 1.31),
    6: (0.9642, (64, 80, 96), 0.35, 0.54, 1.48),
}


NHQUAD_N_RANGE = (0.8, 1.25)  # the factors on the fitted N range a shipped nh-quad scale holds


def calibration_scale(n_triangles: int, n_rings: int, element: str) -> float:
    """The shipped discretization scale of a member of the family.

    An nh-quad member with N outside ``NHQUAD_N_RANGE`` times its fitted N range (M = 2:
    26-60) gets the scale with a :class:`~envs.validation.PsmGraspWarning`: its error grows
    there (see the module's docstring).

    Raises
    ------
    ValueError
        For a member without one (the springs' members have the physics-derived
        :func:`hybrid_scales` or the disk's own scale instead), naming what is shipped.
    """
    n, m = int(n_triangles), int(n_rings)
    if element == "nhquad":
        if m not in NHQUAD_SCALES:
            raise ValueError(f"n_rings = {m} has no shipped nh-quad calibration; one of "
                             f"{sorted(NHQUAD_SCALES)} (or fit one with "
                             "scripts/calibrate_family.py)")
        fitted = NHQUAD_SCALES[m][1]
        low, high = NHQUAD_N_RANGE[0] * min(fitted), NHQUAD_N_RANGE[1] * max(fitted)
        if not low <= n <= high:
            warnings.warn(
                f"the shipped nh-quad scale for n_rings = {m} was fitted at N = {fitted}; "
                f"at n_triangles = {n} (outside {low:.0f}-{high:.0f}) its closing-angle error "
                "against the FEM grows (e.g. M = 2, r = 0.10 m: 1.2 % RMS at N = 40, 9 % at "
                "N = 20, 3.5 % at N = 200; scripts/fig5_error_vs_n.py): refine N and M together "
                "(N / M about 16-20)", PsmGraspWarning, stacklevel=4)
        return NHQUAD_SCALES[m][0]
    if element == "cst":
        if (n, m) not in CST_SCALES:
            raise ValueError(f"(n_triangles, n_rings) = {(n, m)} has no shipped calibration; "
                             f"one of {sorted(CST_SCALES)} (or fit one with "
                             "scripts/calibrate_family.py)")
        return CST_SCALES[(n, m)][0]
    raise ValueError(f"element {element!r} has no shipped calibration (only 'nhquad' and "
                     "'cst'; the spring members take hybrid_scales)")


def calibrated_disk(disk, n_triangles: int, n_rings: int, element: str):
    """``disk`` as the calibrated member models it: its ``stiffness_scale`` times the member's
    :func:`calibration_scale`."""
    return replace(disk, stiffness_scale=disk.stiffness_scale
                   * calibration_scale(n_triangles, n_rings, element))


def cst_disk(disk, n_triangles: int, n_rings: int):
    """:func:`calibrated_disk` of the constant-strain member ``(N, M)``."""
    return calibrated_disk(disk, n_triangles, n_rings, "cst")
