"""The width of a contact finer than the mesh: Hertz's line contact of the disk on a flat face.

A contour of ``N`` points (or a FEM rim of nodes) resolves a contact only to one point spacing:
a face that touches with a vanishing force still presses one or two points, a whole facet
(``2 pi r / N``) of apparent contact. Below that resolution the physics gives the width: a
cylinder of radius ``r`` pressed on a rigid flat by a force ``P`` per unit thickness touches
over ``2 b`` with ``b = sqrt(4 P r / (pi E*))`` (Hertz, plane strain ``E* = E / (1 - nu^2)``;
the same formula as :func:`envs.fem.hertz.hertz_line_compression`). The share of the contour
in contact with one face is then at most ``2 b / (2 pi r) = k sqrt(F)`` with ``F = P t`` and
``k`` from :func:`hertz_arc_coefficient`. The design evaluator counts each face's contact as
the smaller of its pressed points' (nodes') share and this width (:func:`contact_share`), at
both fidelities, so that a light touch scores its physical width and not the mesh's spacing; as
the mesh refines, the count resolves the width and the cap stops binding.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["hertz_arc_coefficient", "contact_share"]


@njit(cache=True, error_model="numpy", _nrt=False)
def hertz_arc_coefficient(radius_m, thickness_m, youngs_modulus_pa, poisson_ratio):
    """``k`` [N^-1/2] such that ``k sqrt(F)`` is the share of the contour in contact with a flat
    face pressed by a force ``F`` [N] (Hertz line contact, plane strain, see the module).

    Parameters
    ----------
    radius_m, thickness_m, youngs_modulus_pa, poisson_ratio
        The disk's ``r`` [m], ``t`` [m], ``E`` [Pa] (the object's modulus: the FEM's physical
        E, the PSM's disk stiffness scale times E, without a member's discretization scale) and
        ``nu`` [-] (compiled: called per row by the design evaluator's metric loop).

    Returns
    -------
    float
        ``sqrt(4 / (pi^3 r t E*))`` with ``E* = E / (1 - nu^2)``.
    """
    e_star = youngs_modulus_pa / (1.0 - poisson_ratio * poisson_ratio)
    return math.sqrt(4.0 / (math.pi**3 * radius_m * thickness_m * e_star))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def contact_share(node_share, face_force_n, hertz_k):
    """One face's share of the contour in contact: the share its pressed points (nodes) stand
    for, at most the Hertz width ``hertz_k sqrt(F)`` of its face force ``F`` [N]."""
    width = hertz_k * math.sqrt(face_force_n) if face_force_n > 0.0 else 0.0
    return width if width < node_share else node_share
