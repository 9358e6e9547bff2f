"""The fast attempt of the solver: its saddle test on the gauge, its turn off a symmetric
saddle, and its start closed to the first contact (envs.solver.gauge, envs.solver.start)."""

import math

import numpy as np
import pytest

from envs.model.geometry import rest_points
from envs.model.problem import scaled_params
from envs.scene import Scene
from envs.solver import simulate
from tests.kernels import K


def _gauge_params(n, k_gauge):
    """Solver parameters of the paper-r070 scene with a gauge of stiffness ``k_gauge`` held at
    rest (anchor 0)."""
    prm = np.zeros(K.N_KERNEL_PARAMS)
    prm[: K.N_PARAMS] = scaled_params(Scene.preset("paper-r070"), 0.3, n)
    prm[K.P_GAUGE] = k_gauge
    prm[K.P_GMAX] = k_gauge
    prm[K.P_GPROX] = K.GAUGE_AT_REST
    return prm


def _dense(ab, bb, dd, bidx, n):
    """The Newton matrix in natural order from its band storage."""
    nb = 2 * n
    dense_b = np.zeros((nb + 2, nb + 2))
    for p in range(nb):
        for kk in range(K.BW + 1):
            if p - kk >= 0:
                dense_b[p, p - kk] = dense_b[p - kk, p] = ab[p, kk]
    dense_b[:nb, nb:] = bb
    dense_b[nb:, :nb] = bb.T
    dense_b[nb:, nb:] = dd
    perm = np.array([bidx[i] + c for i in range(n) for c in range(2)] + [nb, nb + 1])
    return dense_b[np.ix_(perm, perm)], perm


@pytest.mark.parametrize("scale", [0.97, 1.03])
@pytest.mark.parametrize("k_gauge", [0.3, 3.0, 30.0])
def test_rank_one_saddle_test_matches_the_dense_eigenvalues(scale, k_gauge):
    # a contour shrunk about the pin has its springs compressed: turning it about the pin
    # (straight along the tangents) lowers the energy, a mode only the gauge holds up; a
    # stretched contour resists the turn by itself
    n = 12
    prm = _gauge_params(n, k_gauge)
    x = np.zeros(2 * n + 2)
    x[: 2 * n] = scale * rest_points(n).ravel()
    x[2 * n :] = 0.7
    bidx = K._band_index(n)
    nb = 2 * n
    ab, bb, dd = np.zeros((nb, K.BW + 1)), np.zeros((nb, 2)), np.zeros((2, 2))
    K._spring_terms(x, n, prm, bidx, np.zeros(nb + 2), ab, bb, dd, False)
    w, perm = _dense(ab, bb, dd, bidx, n)
    t = np.zeros(nb + 2)
    t[0], t[1] = -math.sin(prm[K.P_PHASE]), math.cos(prm[K.P_PHASE])
    wb, wt = np.zeros(nb), np.zeros(2)
    # the interior point tests the matrix it has just factored (and only one it could factor)
    lb, ybuf = np.zeros((nb, K.BW + 1)), np.zeros((nb, 2))
    factored = K._factor_solve(ab, bb, dd, lb, ybuf, nb, 0.0, np.zeros(nb), np.zeros(2),
                               np.zeros(nb), np.zeros(2))
    assert factored == (np.linalg.eigvalsh(w)[0] > 0.0)
    if not factored:
        return
    ratio = K._gauge_holds_saddle(x, n, prm, bidx, bb, dd, lb, ybuf, 0.0, np.zeros(nb),
                                  np.zeros(2), wb, wt)
    sol = np.linalg.solve(w, t)
    assert ratio == pytest.approx(k_gauge * t @ sol, rel=1e-9)
    # W^-1 t, the unstable mode's shape, in band order (perm: natural dof -> band index)
    np.testing.assert_allclose(np.concatenate([wb, wt])[perm], sol, rtol=1e-9,
                               atol=1e-12 * np.abs(sol).max())
    without_gauge = np.linalg.eigvalsh(w - k_gauge * np.outer(t, t))[0]
    assert (ratio > 1.0 + K.SADDLE_MARGIN) == (without_gauge < 0.0)
    assert (ratio > 1.0 + K.SADDLE_MARGIN) == (scale < 1.0)


@pytest.mark.parametrize("name", ["paper-r050", "paper-r070", "paper-r100"])
def test_closed_start_stops_the_margin_short_of_the_first_contact(name):
    # the fingers close freely until a contour point meets a face: the start is closed to
    # CLOSE_MARGIN before that, with every gap still open
    n = 20
    prm = _gauge_params(n, 0.0)
    prm[: K.N_PARAMS] = scaled_params(Scene.preset(name), 0.3, n)
    x = np.zeros(2 * n + 2)
    x[: 2 * n] = rest_points(n).ravel()
    x[2 * n :] = prm[K.P_TH0]
    K._close_to_contact(x, n, prm)
    q = x[: 2 * n].reshape(n, 2)
    for j in range(2):
        th = x[2 * n + j]
        assert th < prm[K.P_TH0]  # closed from rest
        gaps = [K._face_gap(q, i, j, math.sin(th), math.cos(th), prm) for i in range(n)]
        assert min(gaps) > 0.0
        touch = th - K.CLOSE_MARGIN
        gaps = [K._face_gap(q, i, j, math.sin(touch), math.cos(touch), prm) for i in range(n)]
        assert min(gaps) == pytest.approx(0.0, abs=1e-12)
    assert x[2 * n] == pytest.approx(x[2 * n + 1], abs=1e-14)  # a mirror-symmetric scene


@pytest.mark.parametrize("name,torque_nm", [("paper-r070", 0.6), ("paper-r100", 0.2)])
def test_symmetric_scene_leaves_its_symmetric_saddle_in_the_first_round(name, torque_nm):
    # mirror-symmetric scene and start (N even, first point at the top): the stable grasp is
    # asymmetric, so the symmetric equilibrium the gauge steers to is a saddle. The fast
    # attempt turns off it within the first round; the gauge held at rest until its release
    # found the saddle only after a whole round and needed a second from an escape start
    res = simulate(Scene.preset(name), torque_nm, 20, element="spring")
    assert res.converged and res.stable
    assert abs(res.jaw_angles_rad[0] - res.jaw_angles_rad[1]) > 1e-3
    assert res.rounds == 1
