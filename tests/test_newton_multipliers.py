"""Newton's multipliers of the active-set polish (envs.solver.polish._contact_schur and
_newton_multipliers), against dense linear algebra (numpy): the corrected step solves the
equality-constrained Newton system ``W dx - J^T delta = -grad``, ``J dx = -g`` on the active
constraints, for both layouts of the banded factor (the fan's 2 x 2 blocks, a ring mesh's scalar
band); the forward sweep from a row (envs.solver.banded._forward_from) gives ``|L^-1 r|^2 =
r^T A^-1 r``."""

from __future__ import annotations

import numpy as np
import pytest

from envs.model.rings import mesh_band_index, mesh_half_bandwidth
from envs.solver.assembly import _rhs_to_band, _step_from_band
from envs.solver.banded import BW, _factor_solve, _forward_from
from envs.solver.polish import _contact_schur, _newton_multipliers

N_POINTS = 12  # contour points of the test mesh


def _band_positions(n: int, rings: int) -> np.ndarray:
    """Position of every natural-order unknown in the factor's order (points in band order,
    then the two finger angles), as _rhs_to_band places them."""
    bidx = mesh_band_index(n, rings)
    nb, nx = 2 * n, 2 * n * rings + 2
    nbb = nx - 2
    pos = np.empty(nx, dtype=np.int64)
    for d in range(nx):
        if d < nb:
            pos[d] = bidx[d // 2] + d % 2
        elif d < nb + 2:
            pos[d] = nbb + d - nb
        else:
            pos[d] = bidx[(d - 2) // 2] + (d - 2) % 2
    return pos


def _random_system(rings: int, rng: np.random.Generator):
    """A random symmetric positive definite bordered banded matrix with the solver's band
    pattern, in band storage and in natural order."""
    n = N_POINTS
    nbb = 2 * n * rings
    bw = BW if rings == 1 else mesh_half_bandwidth(rings)
    a = np.zeros((nbb, nbb))
    for j in range(nbb):
        for d in range(1, bw + 1):
            if j - d >= 0 and not (rings == 1 and d == BW and j % 2 == 0):
                # (the fan's factor works by 2 x 2 point blocks: an even row reaches 4 back)
                a[j, j - d] = a[j - d, j] = rng.uniform(-1.0, 1.0)
    a += np.diag(2.0 * bw + 2.0 + rng.uniform(0.0, 1.0, nbb))
    border = rng.uniform(-0.5, 0.5, (nbb, 2))
    corner = np.array([[30.0, 1.0], [1.0, 25.0]])
    full = np.block([[a, border], [border.T, corner]])  # factor order
    ab = np.zeros((nbb, bw + 1))
    for j in range(nbb):
        for d in range(min(j, bw) + 1):
            ab[j, d] = a[j, j - d]
    pos = _band_positions(n, rings)
    natural = full[np.ix_(pos, pos)]
    return n, ab, border.copy(), corner.copy(), natural, pos


@pytest.mark.parametrize("rings", [1, 2])
def test_forward_sweep_from_a_row(rings):
    rng = np.random.default_rng(3 + rings)
    _, ab, bb, dd, _, _ = _random_system(rings, rng)
    nbb = ab.shape[0]
    lb = np.zeros_like(ab)
    ybuf = np.zeros((nbb, 2))
    rb, ob = np.zeros(nbb), np.zeros(nbb)
    rt, ot = np.zeros(2), np.zeros(2)
    assert _factor_solve(ab, bb, dd, lb, ybuf, nbb, 0.0, rb, rt, ob, ot)
    a_band = np.zeros((nbb, nbb))
    bw = ab.shape[1] - 1
    for j in range(nbb):
        for d in range(min(j, bw) + 1):
            a_band[j, j - d] = a_band[j - d, j] = ab[j, d]
    for start in (0, 5, nbb - 3):
        r1 = np.zeros(nbb)
        r2 = np.zeros(nbb)
        r1[start:] = rng.normal(size=nbb - start)
        r2[start + 1:] = rng.normal(size=nbb - start - 1)
        z1, z2 = np.zeros(nbb), np.zeros(nbb)
        _forward_from(lb, nbb, r1, z1, start)
        _forward_from(lb, nbb, r2, z2, start + 1)
        want = r1 @ np.linalg.solve(a_band, r2)
        assert z1 @ z2 == pytest.approx(want, rel=1e-12, abs=1e-14)
        assert np.all(z1[:start] == 0.0)


@pytest.mark.parametrize("rings", [1, 2])
def test_newton_multipliers_solve_the_constrained_newton_system(rings):
    rng = np.random.default_rng(11 + rings)
    n, ab, bb, dd, natural, _ = _random_system(rings, rng)
    nbb, nx, nb = ab.shape[0], natural.shape[0], 2 * n
    bidx = mesh_band_index(n, rings)
    # constraints like the solver's: a face contact (a point and its finger's angle), a corner
    # contact (an edge's two points and the angle), a joint stop (the angle), one inactive
    cd = np.array([[6, 7, nb, 0, 0], [10, 11, 12, 13, nb + 1], [nb + 1, 0, 0, 0, 0],
                   [2, 3, nb, 0, 0]], dtype=np.int64)
    cg = rng.uniform(-1.0, 1.0, (4, 5))
    cg[0, 3:] = 0.0
    cg[2, 1:] = 0.0
    cg[3, 3:] = 0.0
    active = np.array([True, True, True, False])
    mcount = active.size
    g = rng.uniform(-1e-3, 1e-3, mcount)
    grad = rng.normal(size=nx)
    # the plain step W^-1 (-grad), as the polish has it before the multipliers
    lb = np.zeros_like(ab)
    ybuf = np.zeros((nbb, 2))
    rb, ob = np.zeros(nbb), np.zeros(nbb)
    rt, ot = np.zeros(2), np.zeros(2)
    _rhs_to_band(grad, bidx, nb, rb, rt)
    assert _factor_solve(ab, bb, dd, lb, ybuf, nbb, 0.0, rb, rt, ob, ot)
    step = np.zeros(nx)
    _step_from_band(ob, ot, bidx, nb, grad, step)
    np.testing.assert_allclose(natural @ step, -grad, atol=1e-12)
    act = np.zeros(mcount, dtype=np.int64)
    first = np.zeros(mcount, dtype=np.int64)
    zc = np.empty((mcount, nbb))
    zt = np.zeros((mcount, 2))
    sch = np.zeros((mcount, mcount))
    delta = np.zeros(mcount)
    k = _contact_schur(lb, bb, dd, ybuf, nbb, 0.0, bidx, nb, cg, cd, active, mcount, act,
                       first, zc, zt, sch, rb)
    assert k == 3 and list(act[:k]) == [0, 1, 2]
    assert _newton_multipliers(k, act, sch, cg, cd, g, step, delta, lb, bb, dd, ybuf, nbb, 0.0,
                               bidx, nb, np.zeros(nx), rb, rt, ob, ot, np.zeros(nx))
    jac = np.zeros((k, nx))
    for i in range(k):
        for a in range(5):
            jac[i, cd[i, a]] += cg[i, a]
    # the KKT system of the active set, solved densely
    kkt = np.block([[natural, -jac.T], [jac, np.zeros((k, k))]])
    want = np.linalg.solve(kkt, np.concatenate([-grad, -g[:k]]))
    np.testing.assert_allclose(step, want[:nx], rtol=0.0, atol=1e-11)
    np.testing.assert_allclose(delta[:k], want[nx:], rtol=0.0, atol=1e-10)
    # the active constraints met to first order (S carries a floor of 1e-12 of its diagonal)
    np.testing.assert_allclose(jac @ step, -g[:k], rtol=0.0, atol=1e-9 * np.abs(g).max())
