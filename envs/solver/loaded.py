"""The point-spring model's compliance at its contacts, for the loaded grasp.

A lifted object is free of its fixed centre: the centre's reaction and the payload are loads on
it, carried by the contacts, whose normal forces change as the grasp's stiffness decides
(:mod:`envs.model.loads`: the patch-level model, one stated definition for both fidelities).
What that model needs from a fidelity is the object's own compliance between its sticking
constraints: the displacement along one constraint per unit force along another, the object held
by its hub. :func:`contact_compliance` gives it for the point-spring model, from the solved
grasp's Hessian of the element energies (the solver's own assembly and banded factor): a unit
force along a constraint is shared by its contacts in proportion to their forces (a corner's by
the two ends of the contour edge it presses), and ``G = Z^T Z`` with ``Z = L^-1 A`` the
forward sweeps of those force vectors through the factor ``L``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..model.layout import P_GAUGE, P_KC, P_KR, P_RINGS
from .assembly import _newton_matrix
from .banded import BW, _chol_band, _chol_general, _forward_from, band_shape

__all__ = ["response_work", "contact_compliance"]

_CH = 16  # columns of the solver's constraint-curvature cache (assembly.CH_BLOCK + 1)


@njit(cache=True, error_model="numpy")
def response_work(n, prm):
    """Scratch arrays of :func:`contact_compliance` for N contour points and the mesh of
    ``prm``, one tuple (allocated once per block of rows)."""
    nbb, bw = band_shape(n, prm)
    nstate = 2 * n * int(prm[P_RINGS]) + 2
    return (np.zeros((nbb, bw + 1)), np.zeros((nbb, bw + 1)), np.zeros((nbb, 2)),
            np.zeros((2, 2)), np.zeros(nstate), np.zeros(nstate), np.zeros(nstate),
            np.zeros(1), np.zeros(1), np.zeros((1, 5)), np.zeros((1, 5), dtype=np.int64),
            np.zeros((1, _CH)), np.zeros(5), np.zeros((5, 5)), np.zeros(5, dtype=np.int64),
            np.zeros(1, dtype=np.int64), np.zeros(nbb))


@njit(cache=True, error_model="numpy", _nrt=False)
def _energy_factor(kprm, n, x, bidx, work, psd):
    """Assemble the element energies' Hessian at ``x`` (band order; the fan's turn about its
    pin held by the solver's gauge spring, which the rigid turn of the loaded grasp takes
    over) and factor it; False where it is not positive definite."""
    (ab, lb, bb, dd, grad, gb, res, lam, sig, cg, cd, ch, grad5, hess5, dofs, none, _) = work
    gauge = kprm[P_GAUGE]
    if kprm[P_RINGS] == 1:
        kprm[P_GAUGE] = max(kprm[P_KC], kprm[P_KR])
    # no constraints: the body alone, its hub (the fan's pin) held
    # (np.int64: a literal 0 would compile the Newton matrix once more)
    _newton_matrix(x, n, kprm, bidx, none, none, none, np.int64(0), lam, sig, grad, ab, bb, dd, sig,
                   grad5, hess5, dofs, 0.0, psd, gb, res, cg, cd, ch)
    kprm[P_GAUGE] = gauge
    nbb = ab.shape[0]
    if ab.shape[1] == BW + 1:
        return _chol_band(ab, lb, nbb, 0.0)
    return _chol_general(ab, lb, nbb, 0.0)


@njit(cache=True, error_model="numpy")
def contact_compliance(kprm, n, x, bidx, work, nodes, node_share, normals, count, cons,
                       weights, mc, length_scale, force_unit):
    """The object's compliance between the loaded grasp's constraints [m/N], (mc, mc), or a
    (0, 0) array where the body's Hessian is not positive definite.

    Parameters
    ----------
    kprm, n, x, bidx
        The kernels' parameter copy, N, the scaled solved state and the band index.
    work
        :func:`response_work`'s scratch.
    nodes, node_share
        Contact i's contour points (i, 0) and (i, 1) (-1: none) and the share of its force on
        the first (the second takes the rest).
    normals, count, cons, weights, mc
        The contact list's normals and the constraints of
        :func:`envs.model.loads.patch_constraints`.
    length_scale, force_unit
        ``r`` [m] and the force unit ``s E t r`` [N] of the scaled state.
    """
    lb, rhs = work[1], work[16]
    # the exact Hessian; its convexified fallback (no negative geometric stiffness) where the
    # squeeze leaves the exact one indefinite
    if not _energy_factor(kprm, n, x, bidx, work, n < 0):
        if not _energy_factor(kprm, n, x, bidx, work, n > 0):
            return np.zeros((0, 0))
    nbb = lb.shape[0]
    z = np.zeros((mc, nbb))
    first = np.full(mc, nbb, dtype=np.int64)
    for c in range(mc):
        rhs[:] = 0.0
        for i in range(count):
            for kind in range(2):
                if cons[i, kind] != c:
                    continue
                w = weights[i, kind]
                dx, dy = ((-normals[i, 1], normals[i, 0]) if kind == 1
                          else (normals[i, 0], normals[i, 1]))
                for e in range(2):
                    p = nodes[i, e]
                    if p < 0:
                        continue
                    share = node_share[i] if e == 0 else 1.0 - node_share[i]
                    row = bidx[p]
                    rhs[row] += w * share * dx
                    rhs[row + 1] += w * share * dy
                    first[c] = min(first[c], row)
        if first[c] < nbb:
            _forward_from(lb, nbb, rhs, z[c], first[c])
    g = np.zeros((mc, mc))
    scale = length_scale / force_unit
    for c in range(mc):
        for c2 in range(c + 1):
            v = 0.0
            for p in range(max(first[c], first[c2]), nbb):
                v += z[c, p] * z[c2, p]
            g[c, c2] = g[c2, c] = v * scale
    return g
