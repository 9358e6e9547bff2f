"""Hertz validation: diametral compression of a disk between two rigid flat plates.

The analytic line-contact result (:func:`hertz_line_compression`) and the same load case solved
by the finite-element model on a quarter disk graded towards the contact
(:func:`fem_plate_compression`).
"""

from __future__ import annotations

import math

import numpy as np

from envs.scene import SoftDisk
from envs.validation import check_range

from .body import _Body
from .contact import _PENALTY_FACTOR, _Plate, _Rim
from .material import _check_plane
from .mesh import _arc_facets, _check_mesh_size, _graded_quarter_mesh, _quadratic_mesh
from .newton import _ramp
from .system import _System


def _effective_modulus(disk: SoftDisk, plane: str) -> float:
    e, nu = disk.youngs_modulus_pa, disk.poisson_ratio
    return e / (1 - nu**2) if plane == "strain" else e


def hertz_line_compression(disk: SoftDisk, load_n_per_m: float, plane: str = "strain") -> float:
    """Hertz (linear-elastic) diametral compression of a disk between two rigid flat plates.

    ``b = sqrt(4 P R / (pi E*))`` and ``delta = 2 P / (pi E*) (2 ln(4 R / b) - 1)``, with ``P`` the
    plate force per unit thickness [N/m] and ``E* = E / (1 - nu^2)`` in plane strain, ``E`` in
    plane stress.

    Returns
    -------
    float
        Change of the diameter between the plates [m].
    """
    _check_plane(plane)
    p = check_range("load_n_per_m", load_n_per_m, 0.0, math.inf, low_open=True)
    es = _effective_modulus(disk, plane)
    r = disk.radius_m
    b = math.sqrt(4 * p * r / (math.pi * es))
    return 2 * p / (math.pi * es) * (2 * math.log(4 * r / b) - 1)


def fem_plate_compression(
    disk: SoftDisk,
    load_n_per_m: float,
    mesh_size_m: float | None = None,
    plane: str = "strain",
) -> float:
    """Diametral compression of the disk squeezed between two rigid, frictionless flat plates.

    A quarter of the disk is modelled (symmetry: ``u_x = 0`` on the vertical diameter and
    ``u_y = 0`` on the horizontal one; the hub is not used). The top plate is force controlled:
    its descent ``s`` is an unknown with potential ``-(P t / 2) s`` so that the plate force per
    unit thickness on the full disk equals ``load_n_per_m``; by symmetry the diameter shortens by
    ``2 s``. The mesh is the structured quarter mesh refined towards the contact point until the
    element size there is ``mesh_size_m``.

    Parameters
    ----------
    disk
        The disk (``stiffness_scale`` is ignored, ``distance_m`` is irrelevant).
    load_n_per_m
        Plate force per unit thickness ``P`` [N/m], > 0.
    mesh_size_m
        Element size at the contact, in (0, r). Default ``min(b / 8, r / 8)`` with ``b`` the
        Hertz half-width of the contact.
    plane
        ``"strain"`` or ``"stress"``.

    Returns
    -------
    float
        Change of the diameter between the plates [m].

    Raises
    ------
    ValueError
        For invalid inputs.
    RuntimeError
        If the nonlinear solve fails.
    """
    if not isinstance(disk, SoftDisk):
        raise ValueError(f"disk must be a SoftDisk, got {type(disk).__name__}")
    _check_plane(plane)
    p_load = check_range("load_n_per_m", load_n_per_m, 0.0, math.inf, low_open=True)
    r, t, e = disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa
    es = _effective_modulus(disk, plane)
    b = math.sqrt(4 * p_load * r / (math.pi * es))
    if mesh_size_m is None:
        h = min(b / 8, r / 8)
    else:
        h = _check_mesh_size(mesh_size_m, r)
    base, _ = _graded_quarter_mesh(r, h)
    arcs = _arc_facets(base, r)
    mesh = _quadratic_mesh(base, r, arcs)
    body = _Body(mesh, e, disk.poisson_ratio, t, plane)
    rim = _Rim.build(body, arcs, np.zeros(2), t)
    tol = 1e-12 * r
    bas = body.basis
    comp_dofs = [np.concatenate((bas.nodal_dofs[c], bas.facet_dofs[c])) for c in (0, 1)]
    fixed = np.concatenate(
        [d[np.abs(bas.doflocs[c, d]) < tol] for c, d in enumerate(comp_dofs)]
    )  # u_x = 0 on x = 0 and u_y = 0 on y = 0
    force = 0.5 * p_load * t  # on the quarter

    def q_potential(q: np.ndarray, load: float):
        return -float(load * force * q[0]), np.array([-load * force]), np.zeros((1, 1))

    system = _System(
        body,
        rim,
        fixed,
        [_Plate(r, 0)],
        1,
        q_potential,
        _PENALTY_FACTOR * e / h,
        q_scale=np.array([1.0]),
        force_tol_n=1e-8 * force,
        length_scale_m=b,
        rim_order=np.argsort(np.arctan2(rim.ref_m[:, 1], rim.ref_m[:, 0])),
    )
    x = np.zeros(body.n + 1)
    x[-1] = 0.5 * hertz_line_compression(disk, p_load, plane)

    def accept(xx: np.ndarray) -> str | None:
        if body.min_jacobian(xx[: body.n]) <= 0:
            return "inverted element"
        return None

    # the load factor goes 0 -> 1; the initial plate position makes the first step well posed
    x, load, rep, _ = _ramp(system, x, 0.0, 1.0, 0, accept)
    if not rep.converged:
        raise RuntimeError(f"plate compression solve failed: {rep.message}")
    return 2.0 * float(x[-1])
