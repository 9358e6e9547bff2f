"""The hyperelastic body: P2 basis, energy, residual and tangent assembly (:class:`_Body`).

The element kernels are vectorised on the scikit-fem basis data; the ``skfem.asm`` forms they
are checked against (in the tests) are kept here too.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementTriP2, ElementVector, LinearForm, MeshTri2, asm
from skfem.helpers import ddot, grad

from .material import _lame, _neo_hookean


@BilinearForm
def _tangent_form(u, v, w):
    return np.einsum("ij...,ijkl...,kl...->...", grad(v), w["A"], grad(u))


@LinearForm
def _residual_form(v, w):
    return ddot(w["P"], grad(v))


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
