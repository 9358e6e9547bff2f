"""Finite-element reference for the soft-disk grasp (scikit-fem, quadratic triangles).

This module solves the same quasi-static grasp as the point-spring model (see
``shared/CONVENTIONS.md``) with a continuum model, so that the point-spring results can be
checked against a mesh-converged reference:

* the disk is meshed with quadratic triangles: isoparametric P2 geometry (``MeshTri2``, the
  midside nodes of the rim are on the circle) and P2 displacements
  (``ElementVector(ElementTriP2())``);
* the material is a compressible neo-Hookean solid,
  ``W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2`` per unit reference volume, with the Lame
  parameters of the *physical* ``E`` and ``nu`` of the disk. The point-spring calibration factor
  ``stiffness_scale`` is deliberately ignored: the FEM is the physical reference;
* plane strain (default, out-of-plane stretch 1) or plane stress (out-of-plane stretch
  ``lambda_3`` solved at every quadrature point from ``S_33 = 0``, i.e. the exact plane-stress
  reduction of the same 3-D energy; it linearises to the usual plane-stress elasticity);
* the energy per unit reference area is multiplied by the (reference) thickness ``t``;
* the centre of the disk is held by a small rigid hub: every P2 node within ``hub_radius_m``
  (default ``0.1 r``) of the centre is fixed; the mesh has a ring of nodes (with curved P2
  edges) exactly on the hub's edge, so the hub is the same circle on every mesh. The peak strain
  is measured outside the hub (and outside a layer of one hub radius around it, where the hub
  causes a local concentration, reported separately);
* each finger is a rigid bar on a torsion spring, torque controlled: the unknowns are the
  displacement field and the two finger angles, the finger potential is
  ``T_a theta + k_f (theta - theta_a0)^2 / 2``;
* frictionless contact between every rim node of the P2 mesh (vertices and midside nodes) and the
  gripping face of each finger, by a node-to-face penalty ``eps/2 min(g, 0)^2`` weighted by the
  node's share of the rim (Simpson weights ``L/6, 2L/3, L/6`` of each quadratic rim edge) and by
  ``t``, i.e. a pressure penalty (default ``eps = 100 E / h``); optional augmented-Lagrangian
  updates reduce the penetration;
* the tip corner of each gripping face (``J + l e + (w/2) n``) is a second contact feature: a
  corner-to-rim penalty on its signed distance to the deformed rim polygon (rim nodes in order),
  with stiffness ``eps t`` times the mean rim segment length. It matters when the disk sits
  beyond the finger tips (e.g. the forceps scenes); the force it carries is reported separately.
  The end face of the bar is not modelled (a node beyond the tip is free);
* the closed-jaw stop of ``closed_angle_rad`` is a stiff one-sided torsion penalty
  (``1e4 k_f``), reached only when the disk is out of reach.

The coupled displacement/angle system is solved by Newton's method with exact tangents: the
elastic tangent is assembled from the scikit-fem basis (vectorised element kernels on the
``Basis`` gradients, quadrature weights and dof maps, checked against ``skfem.asm`` in the
tests), contact derivatives with respect to the displacements and the angles are added exactly
(the corner Hessian by complex-step differentiation of the analytic gradient, exact to
round-off), the linear systems are solved with SuperLU (minimum-degree ordering on ``A^T + A``,
symmetric mode, ordering reused between Newton steps), steps are globalised by a bracketing
strong-Wolfe line search on the total potential with an anti-tunnelling penetration cap, and a
failed load step is bisected. Each load step starts from the secant extrapolation of the two
previous converged states when that is admissible.

Public API
----------
:func:`fem_grasp`, :class:`FemResult`, :func:`fem_plate_compression`,
:func:`hertz_line_compression`.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP2,
    ElementVector,
    LinearForm,
    MeshTri,
    MeshTri2,
    asm,
)
from skfem.helpers import ddot, grad

from envs.model.geometry import closed_angle_rad, finger_frame
from envs.scene import Scene, SoftDisk
from envs.validation import check_range

__all__ = [
    "FemResult",
    "fem_grasp",
    "fem_plate_compression",
    "hertz_line_compression",
    "default_mesh_size_m",
    "FEM_VERSION",
]

#: Version tag of the discretisation and solver; part of the cache key.
FEM_VERSION = "fem-2"

_PLANES = ("strain", "stress")
_DEFAULT_RINGS = 12  # rings of the default disk mesh: 6 * 12**2 = 864 elements
_PENALTY_FACTOR = 100.0  # default eps = 100 E / h
_MAX_NEWTON = 40
_MAX_BISECTIONS = 12
_STOP_STIFFNESS_FACTOR = 1e4  # joint-stop penalty stiffness, in units of k_f


# --------------------------------------------------------------------------------------------
# Validation helpers
# --------------------------------------------------------------------------------------------


def _check_plane(plane: str) -> str:
    if plane not in _PLANES:
        raise ValueError(f"plane must be one of {list(_PLANES)}, got {plane!r}")
    return plane


def _check_mesh_size(mesh_size_m: float, radius_m: float) -> float:
    return check_range("mesh_size_m", mesh_size_m, 0.0, radius_m, low_open=True, high_open=True)


def default_mesh_size_m(radius_m: float) -> float:
    """Default element size of the grasp mesh, ``r / 12`` (864 quadratic triangles) [m]."""
    return radius_m / _DEFAULT_RINGS


# --------------------------------------------------------------------------------------------
# Meshes
# --------------------------------------------------------------------------------------------


def _fan_mesh(
    radius_m: float,
    rings: int,
    sectors: int,
    start_angle_rad: float,
    span_rad: float,
    ring_radii_m: np.ndarray | None = None,
) -> MeshTri:
    """Structured disk (or disk sector) mesh of straight triangles.

    The domain is cut into ``sectors`` equal circular sectors; each one carries the regular
    triangulation of a triangle with ``rings`` lattice rows, mapped so that row ``k`` lies on the
    circle of radius ``k r / rings`` (or ``ring_radii_m[k - 1]``) with uniformly spaced nodes.
    With six sectors starting at ``pi/2`` the full disk is mirror symmetric about the y axis (and
    nearly equilateral). Centred at the origin.
    """
    periodic = math.isclose(span_rad, 2 * math.pi)
    points = [np.zeros((2, 1))]
    first = [0]
    count = 1
    for k in range(1, rings + 1):
        n = sectors * k if periodic else sectors * k + 1
        ang = start_angle_rad + np.arange(n) * span_rad / (sectors * k)
        rad = radius_m * k / rings if ring_radii_m is None else float(ring_radii_m[k - 1])
        points.append(np.vstack((rad * np.cos(ang), rad * np.sin(ang))))
        first.append(count)
        count += n

    def index(k: int, s: int, i: np.ndarray) -> np.ndarray:
        if k == 0:
            return np.zeros_like(i)
        g = s * k + i
        if periodic:
            g = g % (sectors * k)
        return first[k] + g

    tris = []
    for s in range(sectors):
        for k in range(1, rings + 1):
            i = np.arange(k)
            tris.append(np.vstack((index(k - 1, s, i), index(k, s, i), index(k, s, i + 1))))
            j = np.arange(k - 1)
            tris.append(np.vstack((index(k - 1, s, j), index(k, s, j + 1), index(k - 1, s, j + 1))))
    p = np.hstack(points)
    p[np.abs(p) < 1e-15 * radius_m] = 0.0
    return MeshTri(p, np.hstack(tris).astype(np.int64))


def _quadratic_mesh(
    mesh: MeshTri,
    radius_m: float,
    arc_facets: np.ndarray,
    centre: np.ndarray | None = None,
    extra_circles: Sequence[tuple[float, np.ndarray]] = (),
) -> MeshTri2:
    """Quadratic (isoparametric) copy of ``mesh`` with the rim midside nodes on the circle.

    ``centre`` is the centre of the circle (default: origin); ``extra_circles`` lists further
    ``(radius, facets)`` whose midside nodes are moved onto concentric circles (the hub edge).
    """
    c = np.zeros((2, 1)) if centre is None else np.asarray(centre, dtype=float).reshape(2, 1)
    m2 = MeshTri2.from_mesh(mesh)
    loc = m2.doflocs.copy()
    for rad, facets in [(radius_m, arc_facets), *extra_circles]:
        dofs = m2.dofs.get_facet_dofs(facets).flatten()
        rel = loc[:, dofs] - c
        loc[:, dofs] = c + rel * (rad / np.linalg.norm(rel, axis=0))
    return replace(m2, doflocs=loc)


def _arc_facets(mesh: MeshTri, radius_m: float, boundary: bool = True) -> np.ndarray:
    """Facets lying on the circle of radius ``radius_m`` about the origin (both end nodes on it).

    Only boundary facets are searched unless ``boundary`` is false.
    """
    cand = mesh.boundary_facets() if boundary else np.arange(mesh.facets.shape[1])
    ends = mesh.p[:, mesh.facets[:, cand]]  # (2, 2, nf)
    rad = np.linalg.norm(ends, axis=0)
    on = np.all(np.abs(rad - radius_m) < 1e-9 * radius_m, axis=0)
    return cand[on]


def _grasp_mesh(radius_m: float, rings: int, hub_radius_m: float) -> tuple[MeshTri, int]:
    """Ring radii of the grasp mesh: one ring lies exactly on the hub's edge.

    ``k_h = max(1, round(rings * hub / r))`` rings evenly fill the hub and the remaining
    ``rings - k_h`` evenly fill the annulus ``hub < rho < r``, so that the rigid hub is the same
    circle on every mesh (a hub made of "the nodes that happen to lie inside" would change its
    size with the mesh, and the hub's compliance with it). Returns the straight-sided mesh
    (centred at the origin) and ``k_h``.
    """
    k_h = int(min(rings - 1, max(1, round(rings * hub_radius_m / radius_m))))
    inner = hub_radius_m * np.arange(1, k_h + 1) / k_h
    outer = hub_radius_m + (radius_m - hub_radius_m) * np.arange(1, rings - k_h + 1) / (rings - k_h)
    radii = np.concatenate((inner, outer))
    return _fan_mesh(radius_m, rings, 6, math.pi / 2, 2 * math.pi, radii), k_h


def _project_rim(mesh: MeshTri, radius_m: float, quarter: bool) -> MeshTri:
    """Move the boundary nodes of the rim (not of the symmetry lines) onto the circle."""
    p = mesh.p.copy()
    nodes = mesh.boundary_nodes()
    if quarter:
        tol = 1e-12 * radius_m
        nodes = nodes[(p[0, nodes] > tol) & (p[1, nodes] > tol)]
    p[:, nodes] *= radius_m / np.linalg.norm(p[:, nodes], axis=0)
    return replace(mesh, doflocs=p)


def _graded_quarter_mesh(radius_m: float, contact_size_m: float) -> tuple[MeshTri, int]:
    """Quarter disk (x, y >= 0, centred at the origin) refined towards the top point (0, r).

    Starts from the structured quarter mesh with ``max(8, r / contact_size)`` rings (capped) and
    bisects, level by level, the elements close to ``(0, r)`` until the element size there is at
    most ``contact_size_m``; rim nodes are projected back on the circle after every level.
    Returns the mesh and the number of refinement levels.
    """
    rings = int(min(16, max(8, math.ceil(radius_m / contact_size_m))))
    mesh = _fan_mesh(radius_m, rings, 2, 0.0, math.pi / 2)
    top = np.array([[0.0], [radius_m]])
    size = radius_m / rings
    levels = 0
    while size > contact_size_m * (1 + 1e-9) and levels < 30:
        centroids = mesh.p[:, mesh.t].mean(axis=1)
        dist = np.linalg.norm(centroids - top, axis=0)
        marked = np.nonzero(dist < 4.0 * size)[0]
        mesh = _project_rim(mesh.refined(marked), radius_m, quarter=True)
        size /= 2
        levels += 1
    return mesh, levels


# --------------------------------------------------------------------------------------------
# Material: compressible neo-Hookean, plane strain or plane stress
# --------------------------------------------------------------------------------------------


def _lame(youngs_modulus_pa: float, poisson_ratio: float) -> tuple[float, float]:
    mu = youngs_modulus_pa / (2 * (1 + poisson_ratio))
    lam = youngs_modulus_pa * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    return mu, lam


def _out_of_plane_log_stretch(ln_j2: np.ndarray, mu: float, lam: float) -> np.ndarray:
    """Solve ``mu (l3^2 - 1) + lam ln(J2 l3) = 0`` for ``a = ln l3`` (plane stress)."""
    a = -lam / (lam + 2 * mu) * ln_j2  # small-strain guess
    for _ in range(50):
        em = np.expm1(2 * a)
        f = mu * em + lam * (ln_j2 + a)
        da = -f / (2 * mu * (1 + em) + lam)
        a = a + da
        if np.max(np.abs(da), initial=0.0) < 1e-14:
            break
    return a


def _neo_hookean(
    hmat: np.ndarray,
    mu: float,
    lam: float,
    plane: str,
    stress: bool,
    tangent: bool | None = None,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, bool]:
    """Energy density, first Piola-Kirchhoff stress and tangent at quadrature points.

    ``W = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2`` with ``I1 = tr(F^T F) + lambda_3^2`` and
    ``J = det(F) lambda_3`` (``lambda_3 = 1`` in plane strain, from ``S_33 = 0`` in plane stress).
    The energy is evaluated from the displacement gradient ``H = F - I`` in a form free of
    first-order cancellations (``W = mu/2 H:H - mu det H + mu (z - log1p z) + ...`` with
    ``z = tr H + det H``) so that it stays accurate to round-off at tiny strains, which the line
    search relies on.

    Parameters
    ----------
    hmat
        In-plane displacement gradients ``H = F - I``, shape ``(2, 2, ...)``.
    mu, lam
        Lame parameters [Pa].
    plane
        ``"strain"`` or ``"stress"``.
    stress
        Whether to compute the stress ``P`` (shape ``(2, 2, ...)``).
    tangent
        Whether to compute the tangent ``dP/dF`` (shape ``(2, 2, 2, 2, ...)``); defaults to
        ``stress``.

    Returns
    -------
    w, p, a, ok
        Energy density [J/m^3], stress, tangent (``None`` when not requested) and ``ok`` = all
        ``det F > 0``.
    """
    h11, h12, h21, h22 = hmat[0, 0], hmat[0, 1], hmat[1, 0], hmat[1, 1]
    det_h = h11 * h22 - h12 * h21
    z = h11 + h22 + det_h  # det F - 1
    if not np.all(z > -1.0):
        return np.full(z.shape, np.inf), None, None, False
    ln_j2 = np.log1p(z)
    hh = h11**2 + h12**2 + h21**2 + h22**2
    # mu/2 (2 tr H + H:H) - mu ln J2 = mu/2 H:H - mu det H + mu (z - log1p z)
    w = 0.5 * mu * hh - mu * det_h + mu * (z - ln_j2)
    if plane == "stress":
        a3 = _out_of_plane_log_stretch(ln_j2, mu, lam)
        em = np.expm1(2 * a3)  # lambda_3^2 - 1
        ln_j = ln_j2 + a3
        w = w + mu * (0.5 * em - a3)
        lam_eff = lam - lam**2 / (2 * mu * (1 + em) + lam)
    else:
        ln_j = ln_j2
        lam_eff = lam
    w = w + 0.5 * lam * ln_j**2
    if not stress:
        return w, None, None, True
    j2 = 1.0 + z
    f11, f12, f21, f22 = 1.0 + h11, h12, h21, 1.0 + h22
    finv = np.array([[f22, -f12], [-f21, f11]]) / j2  # F^-1
    finv_t = np.swapaxes(finv, 0, 1)  # F^-T
    coef = lam * ln_j - mu
    p = mu * np.array([[f11, f12], [f21, f22]]) + coef * finv_t
    if tangent is False:
        return w, p, None, True
    eye = np.eye(2)
    a = (
        mu * np.einsum("ik,jl->ijkl", eye, eye).reshape((2, 2, 2, 2) + (1,) * (hmat.ndim - 2))
        + lam_eff * np.einsum("ij...,kl...->ijkl...", finv_t, finv_t)
        - coef * np.einsum("li...,jk...->ijkl...", finv, finv)
    )
    return w, p, a, True


@BilinearForm
def _tangent_form(u, v, w):
    return np.einsum("ij...,ijkl...,kl...->...", grad(v), w["A"], grad(u))


@LinearForm
def _residual_form(v, w):
    return ddot(w["P"], grad(v))


def _log_strain_magnitude(fmat: np.ndarray) -> np.ndarray:
    """Largest in-plane principal logarithmic (Hencky) strain magnitude ``max |ln lambda_i|``."""
    c11 = fmat[0, 0] ** 2 + fmat[1, 0] ** 2
    c22 = fmat[0, 1] ** 2 + fmat[1, 1] ** 2
    c12 = fmat[0, 0] * fmat[0, 1] + fmat[1, 0] * fmat[1, 1]
    mean = 0.5 * (c11 + c22)
    rad = np.sqrt(0.25 * (c11 - c22) ** 2 + c12**2)
    lo = np.maximum(mean - rad, 1e-300)
    hi = mean + rad
    return np.maximum(np.abs(0.5 * np.log(hi)), np.abs(0.5 * np.log(lo)))


# --------------------------------------------------------------------------------------------
# Discrete model: elastic body + rim contact nodes + rigid obstacles with scalar unknowns
# --------------------------------------------------------------------------------------------


class _Body:
    """Hyperelastic body discretised with P2 triangles (scikit-fem basis and assembly)."""

    def __init__(
        self,
        mesh: MeshTri2,
        youngs_modulus_pa: float,
        poisson_ratio: float,
        thickness_m: float,
        plane: str,
    ) -> None:
        self.mesh = mesh
        self.basis = Basis(mesh, ElementVector(ElementTriP2()), intorder=4)
        ref = np.array([[0.0, 1.0, 0.0, 0.5, 0.5, 0.0], [0.0, 0.0, 1.0, 0.0, 0.5, 0.5]])
        self.node_basis = Basis(
            mesh, ElementVector(ElementTriP2()), quadrature=(ref, np.full(6, 1 / 12))
        )
        self.mu, self.lam = _lame(youngs_modulus_pa, poisson_ratio)
        self.thickness_m = thickness_m
        self.plane = plane
        self.n = self.basis.N
        self.dx = self.basis.dx
        self.qp_xy = np.asarray(self.basis.global_coordinates())
        # Vectorised element kernels built from the scikit-fem basis data: local dof j of the
        # vector P2 element is (scalar function fn[j]) * (unit vector comp[j]).
        nloc = self.basis.Nbfun
        grads = np.array([np.asarray(self.basis.basis[j][0].grad) for j in range(nloc)])
        rows = np.abs(grads).reshape(nloc, 2, -1).max(axis=2)  # (nloc, 2 components)
        self._comp = np.argmax(rows, axis=1)
        if not np.all(rows[np.arange(nloc), 1 - self._comp] == 0.0):
            raise RuntimeError("unexpected vector-element layout in scikit-fem")
        scalar = {}
        fn = np.zeros(nloc, dtype=np.int64)
        for j in range(nloc):
            # the two components of one scalar P2 function share its gradient
            key = j // 2 if nloc == 12 else j
            fn[j] = key
            scalar.setdefault(key, grads[j, self._comp[j]])
        self._fn = fn
        self._dphi = np.array([scalar[i] for i in range(len(scalar))])  # (6, 2, nel, nq)
        dofs = self.basis.element_dofs  # (nloc, nel)
        self._rows = np.broadcast_to(dofs[:, None, :], (nloc, nloc, dofs.shape[1])).ravel()
        self._cols = np.broadcast_to(dofs[None, :, :], (nloc, nloc, dofs.shape[1])).ravel()
        self._dofs = dofs

    def displacement_gradient(self, u: np.ndarray, basis: Basis | None = None) -> np.ndarray:
        """``H = grad u`` at the quadrature points, shape ``(2, 2, nel, nq)``."""
        b = self.basis if basis is None else basis
        return np.asarray(b.interpolate(u).grad)

    def deformation_gradient(self, u: np.ndarray, basis: Basis | None = None) -> np.ndarray:
        """``F = I + grad u`` at the quadrature points, shape ``(2, 2, nel, nq)``."""
        return self.displacement_gradient(u, basis) + np.eye(2)[:, :, None, None]

    def energy(self, u: np.ndarray) -> float:
        w, _, _, ok = _neo_hookean(
            self.displacement_gradient(u), self.mu, self.lam, self.plane, False
        )
        if not ok:
            return math.inf
        return float(self.thickness_m * np.sum(w * self.dx))

    def energy_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray | None]:
        """Energy and gradient (``(inf, None)`` if an element is inverted)."""
        w, p, _, ok = _neo_hookean(
            self.displacement_gradient(u), self.mu, self.lam, self.plane, True, False
        )
        if not ok:
            return math.inf, None
        tdx = self.thickness_m * self.dx
        r_loc = np.einsum("abeq,nbeq->nae", p * tdx, self._dphi, optimize=True)
        r_loc = r_loc[self._fn, self._comp]
        g = np.bincount(self._dofs.ravel(), weights=r_loc.ravel(), minlength=self.n)
        return float(np.sum(w * tdx)), g

    def evaluate(self, u: np.ndarray) -> tuple[float, np.ndarray, sp.csr_matrix] | None:
        """Energy, gradient and tangent, or ``None`` if an element is inverted."""
        w, p, a, ok = _neo_hookean(
            self.displacement_gradient(u), self.mu, self.lam, self.plane, True
        )
        if not ok:
            return None
        t = self.thickness_m
        energy = float(t * np.sum(w * self.dx))
        tdx = t * self.dx
        # residual: R[n, a, e] = sum_q P[a, b] dphi[n, b] t dx
        r_loc = np.einsum("abeq,nbeq->nae", p * tdx, self._dphi, optimize=True)
        r_loc = r_loc[self._fn, self._comp]  # (nloc, nel)
        g = np.bincount(self._dofs.ravel(), weights=r_loc.ravel(), minlength=self.n)
        # tangent: K[n, a, m, c, e] = sum_q dphi[n, b] A[a, b, c, d] dphi[m, d] t dx
        tmp = np.einsum("nbeq,abcdeq->nacdeq", self._dphi, a * tdx, optimize=True)
        k_loc = np.einsum("nacdeq,mdeq->namce", tmp, self._dphi, optimize=True)
        fn, comp = self._fn, self._comp
        k_loc = k_loc[fn[:, None], comp[:, None], fn[None, :], comp[None, :]]  # (nloc, nloc, nel)
        k = sp.csr_matrix((k_loc.ravel(), (self._rows, self._cols)), shape=(self.n, self.n))
        return energy, g, k

    def evaluate_skfem(self, u: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        """Gradient and tangent assembled with ``skfem.asm`` (reference for the fast kernels)."""
        _, p, a, ok = _neo_hookean(
            self.displacement_gradient(u), self.mu, self.lam, self.plane, True
        )
        if not ok:
            raise ValueError("inverted element")
        t = self.thickness_m
        g = t * asm(_residual_form, self.basis, P=p)
        k = t * asm(_tangent_form, self.basis, A=a)
        return g, k.tocsr()

    def min_jacobian(self, u: np.ndarray) -> float:
        """Smallest ``det F`` at the quadrature points and at the six P2 nodes of every element."""
        out = math.inf
        for b in (self.basis, self.node_basis):
            f = self.deformation_gradient(u, b)
            out = min(out, float(np.min(f[0, 0] * f[1, 1] - f[0, 1] * f[1, 0])))
        return out


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
    """Gripping face of one finger (CONVENTIONS.md): ``g = n.(p - J) - w/2``, 0 <= e.(p-J) <= l."""

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


class _System:
    """Total potential of body + contact + scalar unknowns, with free-dof bookkeeping."""

    def __init__(
        self,
        body: _Body,
        rim: _Rim,
        fixed_dofs: np.ndarray,
        obstacles: Sequence[_Obstacle],
        nq: int,
        q_potential: Callable[[np.ndarray, float], tuple[float, np.ndarray, np.ndarray]],
        penalty_pa_per_m: float,
        q_scale: np.ndarray,
        force_tol_n: float,
        length_scale_m: float,
        corners: Sequence[_JawTip] = (),
        rim_order: np.ndarray | None = None,
    ) -> None:
        self.body = body
        self.rim = rim
        self.obstacles = list(obstacles)
        self.nq = nq
        self.q_potential = q_potential
        self.n = body.n
        self.ntot = body.n + nq
        free = np.ones(self.ntot, dtype=bool)
        free[fixed_dofs] = False
        self.free = np.nonzero(free)[0]
        self.k_node = penalty_pa_per_m * rim.weight_m2  # (m,) [N/m]
        self.multipliers = [np.zeros(rim.dofs.shape[0]) for _ in self.obstacles]
        self.q_scale = q_scale
        self.force_tol_n = force_tol_n
        self.length_scale_m = length_scale_m
        self._order: np.ndarray | None = None
        # tip corners against the deformed rim polygon (rim nodes in counter-clockwise order)
        self.corners = list(corners)
        self.rim_order = rim_order
        if self.corners:
            poly = rim.ref_m[rim_order]
            seg = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
            thickness = float(rim.weight_m2.sum() / seg.sum())
            self.k_corner = penalty_pa_per_m * thickness * float(np.mean(seg))
        self.corner_multipliers = np.zeros(len(self.corners))
        # penetration cap of trial points: a quarter of the shortest rim segment
        ref = rim.ref_m[rim_order] if rim_order is not None else rim.ref_m
        seg_len = np.linalg.norm(np.diff(ref, axis=0), axis=1)
        self.pen_cap_m = 0.25 * float(np.min(seg_len))

    # positions of the rim nodes
    def rim_positions(self, x: np.ndarray) -> np.ndarray:
        return self.rim.ref_m + x[self.rim.dofs]

    def _contact(self, x: np.ndarray, load: float, want_tangent: bool):
        p = self.rim_positions(x)
        energy = 0.0
        grad = np.zeros(self.ntot)
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        forces = []
        for ob, lam in zip(self.obstacles, self.multipliers, strict=True):
            q = x[self.n + ob.qi]
            g, valid, dgdp, dgdq, d2q, d2pq = ob.evaluate(p, q)
            k = self.k_node
            trial = lam - k * g
            act = valid & (trial > 0)
            f = np.where(act, trial, 0.0)  # contact force on each node [N]
            forces.append(f)
            energy += float(np.sum(np.where(act, trial**2, 0.0) / (2 * k) - lam**2 / (2 * k)))
            if not np.any(act):
                continue
            ia = np.nonzero(act)[0]
            fa, ka = f[ia], k[ia]
            dp = dgdp[ia]
            dofs = self.rim.dofs[ia]
            qd = self.n + ob.qi
            np.add.at(grad, dofs[:, 0], -fa * dp[:, 0])
            np.add.at(grad, dofs[:, 1], -fa * dp[:, 1])
            grad[qd] += float(np.sum(-fa * dgdq[ia]))
            if want_tangent:
                # Hessian of psi(g(x)): k dg dg^T - f d2g
                for a in range(2):
                    for b in range(2):
                        rows.append(dofs[:, a])
                        cols.append(dofs[:, b])
                        vals.append(ka * dp[:, a] * dp[:, b])
                    kpq = ka * dp[:, a] * dgdq[ia] - fa * d2pq[ia, a]
                    rows += [dofs[:, a], np.full(ia.size, qd)]
                    cols += [np.full(ia.size, qd), dofs[:, a]]
                    vals += [kpq, kpq]
                rows.append(np.array([qd]))
                cols.append(np.array([qd]))
                vals.append(np.array([np.sum(ka * dgdq[ia] ** 2 - fa * d2q[ia])]))
        corner_forces = np.zeros(len(self.corners))
        if self.corners:
            poly_idx = self.rim_order
            poly = p[poly_idx]
            k = self.k_corner
            for ci, corner in enumerate(self.corners):
                qd = self.n + corner.qi
                c, dc, d2c = corner.evaluate(float(x[qd]))
                lam_c = self.corner_multipliers[ci]
                gap, kind, idx = _corner_feature(poly, c)
                trial = lam_c - k * gap
                if trial <= 0:
                    energy -= lam_c**2 / (2 * k)
                    continue
                corner_forces[ci] = trial
                energy += (trial**2 - lam_c**2) / (2 * k)
                if kind == "segment":
                    nodes = [poly_idx[idx], poly_idx[(idx + 1) % poly_idx.size]]
                    z = np.concatenate((poly[idx], poly[(idx + 1) % poly_idx.size], c))
                    _, gz, hz = _with_hessian(_segment_gap_gradient, z)
                else:
                    nodes = [poly_idx[idx]]
                    z = np.concatenate((poly[idx], c))
                    _, gz, hz = _with_hessian(_vertex_distance_gradient, z, math.copysign(1, gap))
                # chain rule from (rim nodes, corner position) to (rim dofs, q)
                nv = 2 * len(nodes)
                dg = np.concatenate((gz[:nv], [gz[nv:] @ dc]))
                dofs = np.concatenate([self.rim.dofs[i] for i in nodes] + [np.array([qd])])
                np.add.at(grad, dofs, -trial * dg)
                if want_tangent:
                    d2g = np.empty((nv + 1, nv + 1))
                    d2g[:nv, :nv] = hz[:nv, :nv]
                    d2g[:nv, nv] = d2g[nv, :nv] = hz[:nv, nv:] @ dc
                    d2g[nv, nv] = dc @ hz[nv:, nv:] @ dc + gz[nv:] @ d2c
                    local = k * np.outer(dg, dg) - trial * d2g
                    rows.append(np.repeat(dofs, nv + 1))
                    cols.append(np.tile(dofs, nv + 1))
                    vals.append(local.ravel())
        return energy, grad, (rows, cols, vals), forces, corner_forces

    def energy(self, x: np.ndarray, load: float) -> float:
        e_el = self.body.energy(x[: self.n])
        if not math.isfinite(e_el):
            return math.inf
        e_c = self._contact(x, load, False)[0]
        e_q, _, _ = self.q_potential(x[self.n :], load)
        return e_el + e_c + e_q

    def energy_gradient(self, x: np.ndarray, load: float) -> tuple[float, np.ndarray | None]:
        e_el, g_el = self.body.energy_gradient(x[: self.n])
        if g_el is None:
            return math.inf, None
        e_c, g, _, _, _ = self._contact(x, load, False)
        e_q, g_q, _ = self.q_potential(x[self.n :], load)
        g[: self.n] += g_el
        g[self.n :] += g_q
        return e_el + e_c + e_q, g

    def evaluate(self, x: np.ndarray, load: float):
        out = self.body.evaluate(x[: self.n])
        if out is None:
            return None
        e_el, g_el, k_el = out
        e_c, g_c, (rows, cols, vals), _, _ = self._contact(x, load, True)
        e_q, g_q, h_q = self.q_potential(x[self.n :], load)
        g = g_c
        g[: self.n] += g_el
        g[self.n :] += g_q
        nt = self.ntot
        qidx = np.arange(self.n, nt)
        rr = np.concatenate(rows + [np.repeat(qidx, self.nq)]) if rows else np.repeat(qidx, self.nq)
        cc = np.concatenate(cols + [np.tile(qidx, self.nq)]) if cols else np.tile(qidx, self.nq)
        vv = np.concatenate(vals + [h_q.ravel()]) if vals else h_q.ravel()
        kc = sp.csr_matrix((vv, (rr, cc)), shape=(nt, nt))
        indptr = np.concatenate((k_el.indptr, np.full(self.nq, k_el.indptr[-1])))
        k_full = sp.csr_matrix((k_el.data, k_el.indices, indptr), shape=(nt, nt)) + kc
        return e_el + e_c + e_q, g, k_full

    def contact_forces(self, x: np.ndarray, load: float) -> tuple[list[np.ndarray], np.ndarray]:
        """Per-obstacle node forces and per-corner forces [N]."""
        out = self._contact(x, load, False)
        return out[3], out[4]

    def gaps(self, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        p = self.rim_positions(x)
        out = []
        for ob in self.obstacles:
            g, valid, *_ = ob.evaluate(p, x[self.n + ob.qi])
            out.append((g, valid))
        return out

    def update_multipliers(self, x: np.ndarray, load: float) -> None:
        nodes, corners = self.contact_forces(x, load)
        self.multipliers = [f.copy() for f in nodes]
        self.corner_multipliers = corners.copy()

    def solve(self, kff: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
        """Sparse LU solve (SuperLU, symmetric mode).

        The fill-reducing ordering (minimum degree on ``A^T + A``) is computed at the first
        factorisation and reused afterwards (the sparsity pattern only changes by the few
        contact couplings), which saves the ordering time of every Newton step.
        """
        opts = {"SymmetricMode": True}
        if self._order is None or self._order.size != kff.shape[0]:
            lu = spla.splu(kff.tocsc(), permc_spec="MMD_AT_PLUS_A", options=opts)
            self._order = np.argsort(lu.perm_c)
            return lu.solve(rhs)
        o = self._order
        lu = spla.splu(kff[o][:, o].tocsc(), permc_spec="NATURAL", options=opts)
        out = np.empty_like(rhs)
        out[o] = lu.solve(rhs[o])
        return out

    def penetration(self, x: np.ndarray) -> float:
        """Largest penetration [m] of a rim node into a face or of a tip corner into the rim."""
        p = self.rim_positions(x)
        worst = 0.0
        for ob in self.obstacles:
            g, valid, *_ = ob.evaluate(p, x[self.n + ob.qi])
            if np.any(valid):
                worst = max(worst, float(np.max(-g[valid])))
        if self.corners:
            poly = p[self.rim_order]
            for corner in self.corners:
                c = corner.evaluate(float(x[self.n + corner.qi]))[0]
                worst = max(worst, -_corner_feature(poly, c)[0])
        return worst

    def penetration_cap(self, x: np.ndarray) -> float:
        """Largest penetration a line-search trial point may have (anti-tunnelling guard)."""
        return max(self.pen_cap_m, 2.0 * self.penetration(x))

    def residual_ratio(self, g: np.ndarray) -> float:
        """Largest free residual (forces; generalised forces / ``q_scale``) over the tolerance."""
        gf = g[self.free]
        nu = self.free.size - self.nq
        r_u = float(np.max(np.abs(gf[:nu]), initial=0.0))
        r_q = float(np.max(np.abs(gf[nu:]) / self.q_scale, initial=0.0))
        return max(r_u, r_q) / self.force_tol_n

    def converged(self, g: np.ndarray) -> bool:
        return self.residual_ratio(g) <= 1.0


@dataclass
class _NewtonReport:
    converged: bool
    iterations: int
    message: str


def _line_search(
    system: _System, x: np.ndarray, dx: np.ndarray, e0: float, slope: float, load: float
) -> tuple[np.ndarray, bool]:
    """Bracketing line search on ``phi(a) = Pi(x + a dx)`` (strong Wolfe conditions).

    The full Newton step is taken when it satisfies Armijo's condition and does not overshoot
    the minimum along the line (``phi'(1) <= eta |phi'(0)|``). Otherwise the minimum is bracketed
    and located by safeguarded regula falsi on ``phi'`` until ``|phi'(a)| <= eta |phi'(0)|``:
    an accurate line minimum matters when the Newton model does not yet see a contact that is
    about to close (otherwise the steps would only creep towards the contact). Trial points with
    an inverted element or with a penetration beyond the system's cap (which would let a node or
    a tip corner tunnel through) count as overshoots. ``phi'`` is evaluated from the gradient, so
    the search stays meaningful when energy differences are at round-off level.
    """
    free = system.free
    eta = 0.25
    pen_cap = system.penetration_cap(x)
    lo, d_lo = 0.0, slope
    hi, d_hi = math.inf, math.inf
    alpha = 1.0
    best: np.ndarray | None = None
    for _ in range(60):
        xt = x.copy()
        xt[free] += alpha * dx
        et, gt = (math.inf, None)
        if system.penetration(xt) <= pen_cap:
            et, gt = system.energy_gradient(xt, load)
        if gt is None or not math.isfinite(et):
            hi, d_hi = alpha, math.inf
        else:
            dphi = float(gt[free] @ dx)
            floor = 1e-12 * (abs(e0) + abs(et))
            armijo = et <= e0 + 1e-4 * alpha * slope + floor
            if armijo and abs(dphi) <= eta * abs(slope):
                return xt, True
            if armijo and dphi < 0:
                if alpha == 1.0:
                    return xt, True  # the Newton step is still descending: take it
                lo, d_lo = alpha, dphi
                best = xt
            else:
                hi, d_hi = alpha, dphi if dphi > 0 else math.inf
        width = hi - lo
        if math.isfinite(d_hi) and d_hi > 0 > d_lo:
            a_new = lo + width * (-d_lo) / (d_hi - d_lo)
        else:
            a_new = lo + 0.25 * width
        if not lo + 0.05 * width <= a_new <= hi - 0.05 * width:
            a_new = lo + 0.5 * width
        alpha = a_new
        if width < 1e-14:
            break
    if best is not None:
        return best, True
    return x, False


def _newton(system: _System, x: np.ndarray, load: float) -> tuple[np.ndarray, _NewtonReport]:
    """Damped Newton on the total potential (energy line search, inversion guard)."""
    free = system.free
    nq = system.nq
    nu = free.size - nq
    x = x.copy()
    for it in range(_MAX_NEWTON):
        out = system.evaluate(x, load)
        if out is None:
            return x, _NewtonReport(False, it, "inverted element (det F <= 0) at the start point")
        e0, g, k = out
        if not math.isfinite(e0) or not np.all(np.isfinite(g)):
            return x, _NewtonReport(False, it, "non-finite energy or residual")
        if system.converged(g):
            return x, _NewtonReport(True, it, "converged")
        gf = g[free]
        kff = k[free][:, free].tocsr()
        try:
            dx = system.solve(kff, -gf)
        except RuntimeError:
            dx = None
        slope = float(gf @ dx) if dx is not None and np.all(np.isfinite(dx)) else math.nan
        if not slope < 0:
            # not a descent direction (indefinite tangent): shift towards the diagonal
            diag = np.abs(kff.diagonal()) + 1e-30
            shift = 1e-3
            while shift < 1e6:
                try:
                    dx = system.solve(kff + sp.diags(shift * diag), -gf)
                    slope = float(gf @ dx)
                except RuntimeError:
                    slope = math.nan
                if slope < 0:
                    break
                shift *= 10
            else:
                return x, _NewtonReport(False, it, "no descent direction found")
        # round-off floor: a negligible Newton correction with a nearly converged residual
        step_u = float(np.max(np.abs(dx[:nu]), initial=0.0))
        step_q = float(np.max(np.abs(dx[nu:]) * system.q_scale, initial=0.0))
        if max(step_u, step_q) < 1e-10 * system.length_scale_m and system.residual_ratio(g) < 1e3:
            return x, _NewtonReport(True, it, "converged (round-off floor)")
        xt, ok = _line_search(system, x, dx, e0, slope, load)
        if not ok:
            return x, _NewtonReport(False, it, "line search failed")
        x = xt
    out = system.evaluate(x, load)
    if out is not None and system.converged(out[1]):
        return x, _NewtonReport(True, _MAX_NEWTON, "converged")
    return x, _NewtonReport(False, _MAX_NEWTON, f"no convergence in {_MAX_NEWTON} Newton steps")


def _solve_load(
    system: _System,
    x: np.ndarray,
    load: float,
    al_iterations: int,
    accept: Callable[[np.ndarray], str | None],
) -> tuple[np.ndarray, _NewtonReport]:
    """Newton solve at one load, with optional augmented-Lagrangian passes and a final check."""
    saved = [m.copy() for m in system.multipliers]
    saved_c = system.corner_multipliers.copy()
    total = 0
    xs, rep = _newton(system, x, load)
    total += rep.iterations
    for _ in range(al_iterations):
        if not rep.converged:
            break
        system.update_multipliers(xs, load)
        xs, rep = _newton(system, xs, load)
        total += rep.iterations
    if rep.converged:
        problem = accept(xs)
        if problem:
            rep = _NewtonReport(False, rep.iterations, problem)
    if not rep.converged:
        system.multipliers = saved
        system.corner_multipliers = saved_c
    return xs, _NewtonReport(rep.converged, total, rep.message)


def _ramp(
    system: _System,
    x: np.ndarray,
    load_from: float,
    load_to: float,
    al_iterations: int,
    accept: Callable[[np.ndarray], str | None],
    previous: tuple[np.ndarray, float] | None = None,
) -> tuple[np.ndarray, float, _NewtonReport, tuple[np.ndarray, float] | None]:
    """Go from ``load_from`` to ``load_to`` with step bisection on failure.

    ``previous`` is the converged state before ``x`` (state, load); when given, each step starts
    from the secant extrapolation of the two last converged states (falling back to ``x`` if
    that fails). Returns the last converged state, its load, a report and the state before it.
    """
    cur = load_from
    step = load_to - load_from
    iters = 0
    depth = 0
    while True:
        target = load_to if abs(load_to - cur) <= abs(step) * (1 + 1e-12) else cur + step
        starts = [x]
        if previous is not None and previous[1] != cur:
            ratio = (target - cur) / (cur - previous[1])
            if 0 < ratio <= 2:
                xp = x + ratio * (x - previous[0])
                if system.penetration(xp) <= system.penetration_cap(x) and math.isfinite(
                    system.energy(xp, target)
                ):
                    starts.insert(0, xp)
        for x0 in starts:
            xs, rep = _solve_load(system, x0, target, al_iterations, accept)
            iters += rep.iterations
            if rep.converged:
                break
        if rep.converged:
            previous = (x, cur)
            x, cur = xs, target
            if target == load_to:
                return x, cur, _NewtonReport(True, iters, "converged"), previous
            if depth > 0:
                step *= 2  # try to grow the step again
                depth -= 1
        else:
            depth += 1
            if depth > _MAX_BISECTIONS:
                msg = f"step bisection exhausted ({_MAX_BISECTIONS} halvings): {rep.message}"
                return x, cur, _NewtonReport(False, iters, msg), previous
            step *= 0.5


# --------------------------------------------------------------------------------------------
# Results and cache
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FemResult:
    """Finite-element grasp state at one actuation torque.

    Attributes
    ----------
    torque_nm
        Actuation torque ``T_a`` of each finger [N·m].
    jaw_angles_rad
        ``(theta_R, theta_L)`` [rad] (NaN when not converged).
    converged
        Whether Newton converged and all post-checks passed.
    message
        ``"converged"`` (``"converged (jaws on the closed stop)"`` when the disk is out of reach
        and the jaws rest on the ``closed_angle_rad`` stop) or the reason of the failure.
    contour_m
        Deformed positions of all rim nodes of the P2 mesh (vertices and midside nodes), ordered
        counter-clockwise by their reference polar angle about the disk centre starting at the
        top (angle pi/2), shape ``(M, 2)`` [m].
    contact_forces_n
        Total normal contact force on the right and left jaw [N] (whole thickness).
    peak_strain
        Largest magnitude of the in-plane principal logarithmic (Hencky) strain
        ``max |ln lambda_i|`` over the quadrature points outside the hub [-], excluding the layer
        ``hub_radius_m < rho <= 2 hub_radius_m`` around it: the clamped rigid hub carries the
        net jaw force and causes a local strain concentration at its edge (an artefact of the
        hub model, reported separately as ``hub_edge_peak_strain``).
    n_elements
        Number of quadratic triangles.
    n_dofs
        Number of unknowns: free displacement dofs (hub dofs excluded) plus the two angles.
    mesh_size_m
        Element size ``r / rings`` of the structured disk mesh [m].
    solve_time_s
        Wall time of the solve [s] (of the original solve when read from the cache; ignored by
        ``==``, which compares the physical results).
    newton_iterations
        Newton iterations spent on this torque (including bisected sub-steps).
    max_penetration_m
        Largest penetration of a rim node into a jaw face or of a tip corner into the rim [m]
        (penalty artefact; reduce it with ``al_iterations``).
    max_displacement_m
        Largest rim-node displacement [m].
    contact_node_counts
        Number of rim nodes in contact with the right and left jaw's face.
    tip_forces_n
        Part of ``contact_forces_n`` carried by each finger's tip corner [N] (0 when the corner
        does not touch the disk).
    plane
        ``"strain"`` or ``"stress"``.
    hub_radius_m
        Radius of the rigid hub [m].
    hub_edge_peak_strain
        Same strain measure over the layer ``hub_radius_m < rho <= 2 hub_radius_m`` [-].
    from_cache
        Whether the result was read from the disk cache (ignored by ``==``).
    """

    torque_nm: float
    jaw_angles_rad: tuple[float, float]
    converged: bool
    message: str
    contour_m: np.ndarray
    contact_forces_n: tuple[float, float]
    peak_strain: float
    n_elements: int
    n_dofs: int
    mesh_size_m: float
    solve_time_s: float = field(compare=False)
    newton_iterations: int
    max_penetration_m: float = math.nan
    max_displacement_m: float = math.nan
    contact_node_counts: tuple[int, int] = (0, 0)
    tip_forces_n: tuple[float, float] = (0.0, 0.0)
    plane: str = "strain"
    hub_radius_m: float = math.nan
    hub_edge_peak_strain: float = math.nan
    from_cache: bool = field(default=False, compare=False)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, FemResult):
            return NotImplemented
        for f in fields(self):
            if not f.compare:
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, str) or isinstance(b, str):
                if a != b:
                    return False
            elif not np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True):
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict:
        """JSON-serialisable dict (floats round-trip exactly)."""
        out = {}
        for f in fields(self):
            if f.name == "from_cache":
                continue
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple):
                v = list(v)
            out[f.name] = v
        return out

    @classmethod
    def from_json(cls, data: dict, from_cache: bool = True) -> FemResult:
        """Inverse of :meth:`to_json`."""
        kw = dict(data)
        kw["contour_m"] = np.asarray(kw["contour_m"], dtype=float).reshape(-1, 2)
        kw["jaw_angles_rad"] = tuple(float(v) for v in kw["jaw_angles_rad"])
        kw["contact_forces_n"] = tuple(float(v) for v in kw["contact_forces_n"])
        kw["contact_node_counts"] = tuple(int(v) for v in kw["contact_node_counts"])
        kw["tip_forces_n"] = tuple(float(v) for v in kw["tip_forces_n"])
        return cls(**kw, from_cache=from_cache)


def _cache_dir() -> Path:
    return Path(os.environ.get("PSM_GRASP_CACHE", os.path.join("out", "cache"))) / "fem"


def _cache_key(inputs: dict) -> str:
    text = json.dumps(inputs, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _load_cache(path: Path, inputs: dict) -> list[FemResult] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if data.get("inputs") != inputs:
        return None
    try:
        return [FemResult.from_json(r) for r in data["results"]]
    except (KeyError, TypeError, ValueError):
        return None


def _store_cache(path: Path, inputs: dict, results: list[FemResult]) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(json.dumps({"inputs": inputs, "results": [r.to_json() for r in results]}))
        os.replace(tmp, path)
    except OSError:
        pass  # the cache is an optimisation only


# --------------------------------------------------------------------------------------------
# Grasp
# --------------------------------------------------------------------------------------------


def fem_grasp(
    scene: Scene,
    torques_nm: Sequence[float],
    mesh_size_m: float | None = None,
    plane: str = "strain",
    hub_radius_m: float | None = None,
    cache: bool = True,
    *,
    penalty_pa_per_m: float | None = None,
    al_iterations: int = 0,
) -> list[FemResult]:
    """Finite-element grasp of the scene's disk at a sequence of actuation torques.

    The torques are the load ramp: they are solved in the given order, each one warm-started from
    the previous converged state (starting from the open gripper at zero torque). A step that
    fails (Newton or line-search failure, inverted element) is bisected; a torque that cannot be
    reached gives ``converged=False`` with the reason and NaN fields, and the ramp continues from
    the last converged state.

    Parameters
    ----------
    scene
        Gripper and disk. ``disk.stiffness_scale`` is ignored (the FEM uses the physical ``E``).
    torques_nm
        Actuation torques ``T_a >= 0`` [N·m], finite.
    mesh_size_m
        Element size ``h`` in (0, r); the disk is meshed with ``n = ceil(r / h)`` rings, i.e.
        ``6 n^2`` quadratic triangles (mirror symmetric about the y axis): ``k_h`` rings fill the
        hub and ``n - k_h`` evenly spaced rings the annulus outside it. Default ``r / 12``
        (864 elements).
    plane
        ``"strain"`` (default) or ``"stress"``.
    hub_radius_m
        Radius of the rigid hub holding the centre, in ``(0, 0.5 r]``, default ``0.1 r``. The
        mesh has a ring of nodes exactly on the hub's edge (curved P2 edges on the circle), and
        all nodes on or inside it are fixed, so the hub is the same circle on every mesh. The
        peak strain is measured outside the hub (see :class:`FemResult`).
    cache
        Read/write results under ``$PSM_GRASP_CACHE/fem`` (default ``out/cache/fem`` relative to
        the working directory), keyed by a hash of all inputs.
    penalty_pa_per_m
        Contact penalty ``eps`` [Pa/m]; default ``100 E / h``.
    al_iterations
        Augmented-Lagrangian multiplier updates per torque (0 = pure penalty).

    Returns
    -------
    list of FemResult
        One result per torque, in order.

    Raises
    ------
    ValueError
        For an invalid parameter (the message names it and gives the allowed range).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a Scene, got {type(scene).__name__}")
    disk, grip = scene.disk, scene.gripper
    r = disk.radius_m
    try:
        torques = [float(v) for v in np.asarray(torques_nm, dtype=float).ravel()]
    except (TypeError, ValueError):
        raise ValueError("torques_nm must be a sequence of finite numbers >= 0") from None
    if not torques:
        raise ValueError("torques_nm must contain at least one torque")
    for i, tq in enumerate(torques):
        check_range(f"torques_nm[{i}]", tq, 0.0, math.inf)
    _check_plane(plane)
    h = default_mesh_size_m(r) if mesh_size_m is None else _check_mesh_size(mesh_size_m, r)
    if hub_radius_m is not None:
        check_range("hub_radius_m", hub_radius_m, 0.0, 0.5 * r, low_open=True)
    if penalty_pa_per_m is not None:
        check_range("penalty_pa_per_m", penalty_pa_per_m, 0.0, math.inf, low_open=True)
    if not isinstance(al_iterations, int | np.integer) or not 0 <= al_iterations <= 50:
        raise ValueError(f"al_iterations must be an integer in [0, 50], got {al_iterations!r}")
    rings = max(2, math.ceil(r / h - 1e-9))
    h_eff = r / rings
    hub = 0.1 * r if hub_radius_m is None else float(hub_radius_m)
    eps = (
        _PENALTY_FACTOR * disk.youngs_modulus_pa / h_eff
        if penalty_pa_per_m is None
        else float(penalty_pa_per_m)
    )

    inputs = {
        "version": FEM_VERSION,
        "gripper": {f.name: getattr(grip, f.name) for f in fields(grip)},
        "disk": {
            f.name: getattr(disk, f.name) for f in fields(disk)
            if f.name not in ("stiffness_scale", "contour_stiffness_ratio")
        },
        "torques_nm": torques,
        "rings": rings,
        "plane": plane,
        "hub_radius_m": hub,
        "penalty_pa_per_m": eps,
        "al_iterations": int(al_iterations),
    }
    path = _cache_dir() / f"{_cache_key(inputs)}.json"
    if cache:
        hit = _load_cache(path, inputs)
        if hit is not None:
            return hit

    results = _solve_grasp(scene, torques, rings, plane, hub, eps, int(al_iterations))
    if cache:
        _store_cache(path, inputs, results)
    return results


def _solve_grasp(
    scene: Scene,
    torques: list[float],
    rings: int,
    plane: str,
    hub: float,
    eps: float,
    al_iterations: int,
) -> list[FemResult]:
    disk, grip = scene.disk, scene.gripper
    r, t = disk.radius_m, disk.thickness_m
    centre = disk.center_m
    base, _ = _grasp_mesh(r, rings, hub)
    arcs = _arc_facets(base, r)
    hub_edge = _arc_facets(base, hub, boundary=False)
    base = replace(base, doflocs=base.p + centre[:, None])
    mesh = _quadratic_mesh(base, r, arcs, centre, extra_circles=[(hub, hub_edge)])
    body = _Body(mesh, disk.youngs_modulus_pa, disk.poisson_ratio, t, plane)
    rim = _Rim.build(body, arcs, centre, t)

    # the rigid hub: every node on or inside the (curved) hub ring
    dist = np.linalg.norm(body.basis.doflocs - centre[:, None], axis=0)
    fixed = np.nonzero(dist <= hub * (1 + 1e-9))[0]
    kf, th0 = grip.torsion_stiffness_nm_per_rad, grip.rest_angle_rad
    th_stop = closed_angle_rad(grip)
    k_stop = _STOP_STIFFNESS_FACTOR * kf

    def q_potential(q: np.ndarray, torque: float):
        e = float(np.sum(torque * q + 0.5 * kf * (q - th0) ** 2))
        g = torque + kf * (q - th0)
        hdiag = np.full(2, kf)
        below = q < th_stop
        e += float(np.sum(np.where(below, 0.5 * k_stop * (q - th_stop) ** 2, 0.0)))
        g = g + np.where(below, k_stop * (q - th_stop), 0.0)
        hdiag = hdiag + np.where(below, k_stop, 0.0)
        return e, g, np.diag(hdiag)

    force_tol = 1e-10 * disk.youngs_modulus_pa * t * r
    # rim nodes counter-clockwise from the top (contour output and tip-corner polygon)
    angle = np.arctan2(rim.ref_m[:, 1] - centre[1], rim.ref_m[:, 0] - centre[0])
    order = np.argsort(np.mod(angle - math.pi / 2, 2 * math.pi), kind="stable")
    system = _System(
        body,
        rim,
        fixed,
        [_JawFace(scene, 0, 0), _JawFace(scene, 1, 1)],
        2,
        q_potential,
        eps,
        q_scale=np.array([r, r]),
        force_tol_n=force_tol,
        length_scale_m=r,
        corners=[_JawTip(scene, 0, 0), _JawTip(scene, 1, 1)],
        rim_order=order,
    )
    n = body.n
    # strain regions (see FemResult.peak_strain)
    rho = np.linalg.norm(body.qp_xy - centre[:, None, None], axis=0)
    outside_hub = rho > 2 * hub
    hub_layer = (rho > hub) & ~outside_hub

    def accept(x: np.ndarray) -> str | None:
        if body.min_jacobian(x[:n]) <= 0:
            return "inverted element (det F <= 0 at a node or quadrature point)"
        return None

    x = np.zeros(n + 2)
    x[n:] = grip.rest_angle_rad
    load = 0.0
    previous: tuple[np.ndarray, float] | None = None
    n_free = system.free.size
    results = []
    for torque in torques:
        t0 = time.perf_counter()
        x_new, load_new, rep, previous = _ramp(
            system, x, load, torque, al_iterations, accept, previous
        )
        elapsed = time.perf_counter() - t0
        x, load = x_new, load_new
        common = dict(
            torque_nm=torque,
            n_elements=int(mesh.t.shape[1]),
            n_dofs=int(n_free),
            mesh_size_m=r / rings,
            solve_time_s=elapsed,
            newton_iterations=int(rep.iterations),
            plane=plane,
            hub_radius_m=hub,
        )
        if not rep.converged:
            results.append(
                FemResult(
                    jaw_angles_rad=(math.nan, math.nan),
                    converged=False,
                    message=f"failed at T_a = {torque:g} N·m (last converged "
                    f"{load:g} N·m): {rep.message}",
                    contour_m=np.full((rim.ref_m.shape[0], 2), math.nan),
                    contact_forces_n=(math.nan, math.nan),
                    tip_forces_n=(math.nan, math.nan),
                    peak_strain=math.nan,
                    **common,
                )
            )
            continue
        forces, tip = system.contact_forces(x, load)
        gaps = system.gaps(x)
        pen = 0.0
        for (g, valid), f in zip(gaps, forces, strict=True):
            act = valid & (f > 0)
            if np.any(act):
                pen = max(pen, float(np.max(-g[act])))
        tip_pen = (tip - system.corner_multipliers) / system.k_corner
        pen = max(pen, float(np.max(np.where(tip > 0, tip_pen, 0.0))))
        fmat = body.deformation_gradient(x[:n])
        strain = _log_strain_magnitude(fmat)
        disp = np.linalg.norm(x[rim.dofs], axis=1)
        at_stop = bool(np.any(x[n:] < th_stop))
        results.append(
            FemResult(
                jaw_angles_rad=(float(x[n]), float(x[n + 1])),
                converged=True,
                message="converged (jaws on the closed stop)" if at_stop else "converged",
                contour_m=system.rim_positions(x)[order],
                contact_forces_n=(
                    float(np.sum(forces[0]) + tip[0]),
                    float(np.sum(forces[1]) + tip[1]),
                ),
                tip_forces_n=(float(tip[0]), float(tip[1])),
                peak_strain=float(np.max(strain[outside_hub])),
                hub_edge_peak_strain=float(np.max(strain[hub_layer], initial=0.0)),
                max_penetration_m=max(pen, 0.0),
                max_displacement_m=float(np.max(disp)),
                contact_node_counts=(
                    int(np.count_nonzero(forces[0] > 0)),
                    int(np.count_nonzero(forces[1] > 0)),
                ),
                **common,
            )
        )
    return results


# --------------------------------------------------------------------------------------------
# Diametral compression between two plates (Hertz validation)
# --------------------------------------------------------------------------------------------


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
