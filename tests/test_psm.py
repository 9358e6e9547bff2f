"""Stiffness rules and exact derivatives of the compiled model (against finite differences)."""

import math

import numpy as np
import pytest

from envs.model.geometry import rest_points
from envs.model.layout import P_KC, P_KR
from envs.model.problem import scaled_params
from envs.model.stiffness import disk_spring_stiffness, spring_stiffness
from envs.scene import Scene
from tests.kernels import K


class _Prob:
    """The solver's parameter row of a scene, as the tests below use it."""

    def __init__(self, scene, torque_nm, n, rule="van_gelder"):
        self.n = n
        self.params = scaled_params(scene, torque_nm, n, rule)


scaled_problem = _Prob


def test_van_gelder_matches_conventions():
    for n in (4, 12, 20, 60):
        k_int, k_ext = spring_stiffness(n, 0.07)
        area = 0.5 * math.sin(2 * math.pi / n)
        h = 2 * math.sin(math.pi / n)
        assert k_int == pytest.approx(2 * area)
        assert k_ext == pytest.approx(area / h**2)


def test_cst_fit_is_poisson_aware_and_positive():
    a = spring_stiffness(20, 0.07, "cst_fit", 0.2)
    b = spring_stiffness(20, 0.07, "cst_fit", 0.45)
    assert min(a + b) > 0
    assert abs(a[0] - b[0]) > 1e-3 * a[0]


@pytest.mark.parametrize("n", [3, 2, 20001])
def test_bad_triangle_counts_raise(n):
    with pytest.raises(ValueError, match="n_triangles"):
        spring_stiffness(n, 0.07)


def test_unknown_rule_raises():
    with pytest.raises(ValueError, match="stiffness rule"):
        spring_stiffness(20, 0.07, "magic")


@pytest.mark.parametrize("rule", ["van_gelder", "cst_fit"])
def test_contour_stiffness_ratio_scales_only_the_contour_springs(rule):
    base = Scene.preset("paper-r070").with_changes(stiffness_scale=1.5)
    scene = base.with_changes(contour_stiffness_ratio=2.5)
    p0 = scaled_problem(base, 0.3, 20, rule).params
    p1 = scaled_problem(scene, 0.3, 20, rule).params
    assert p1[P_KC] == pytest.approx(2.5 * p0[P_KC], rel=1e-15)
    mask = np.ones(len(p0), dtype=bool)
    mask[P_KC] = False
    np.testing.assert_array_equal(p1[mask], p0[mask])
    # physical stiffness [N/m]: k_int = s E t k_int', k_ext = rho_c s E t k_ext'
    d = scene.disk
    k_unit = 1.5 * d.youngs_modulus_pa * d.thickness_m
    k_int, k_ext = disk_spring_stiffness(d, 20, rule)
    assert k_int == pytest.approx(p1[P_KR] * k_unit, rel=1e-15)
    assert k_ext == pytest.approx(p1[P_KC] * k_unit, rel=1e-15)
    ki, ke = spring_stiffness(20, d.radius_m, rule, d.poisson_ratio)
    assert k_ext / k_int == pytest.approx(2.5 * ke / ki, rel=1e-15)


def _sc(th):
    """The kernels take a finger angle as its sine and cosine."""
    return np.sin(th), np.cos(th)


def _state(n=12, seed=0):
    rng = np.random.default_rng(seed)
    prob = scaled_problem(Scene.preset("paper-r070"), 0.3, n)
    x = np.empty(2 * n + 2)
    x[: 2 * n] = (rest_points(n) * (1 + 0.05 * rng.standard_normal((n, 1)))).ravel()
    x[: 2 * n] += 0.02 * rng.standard_normal(2 * n)
    x[2 * n :] = 0.6 + 0.05 * rng.standard_normal(2)
    return prob, x


def _fd_check(fun, x, grad, hess, eps=1e-6):
    for a in range(len(x)):
        xp, xm = x.copy(), x.copy()
        xp[a] += eps
        xm[a] -= eps
        gp, gradp = fun(xp)
        gm, gradm = fun(xm)
        assert (gp - gm) / (2 * eps) == pytest.approx(grad[a], abs=1e-6, rel=1e-6)
        np.testing.assert_allclose((gradp - gradm) / (2 * eps), hess[:, a], atol=1e-5, rtol=1e-5)


@pytest.mark.parametrize("sc_kind", ["face", "beyond_tip", "behind_root", "back", "back_tip"])
def test_face_constraint_derivatives(sc_kind):
    # gap of a point to the finger's rounded bar: face, tip and root corners, back of the bar
    prob, x = _state()
    n = prob.n
    q = x[: 2 * n].reshape(n, 2).copy()
    prm = prob.params.copy()
    i, j = 8, 0
    # place point i in finger coordinates (s along the bar, m along the inward normal)
    lmax, hw, rho = prm[K.P_LMAX], prm[K.P_HW], prm[K.P_RHO]
    s_m = {
        "face": (0.5 * lmax, hw + 0.1),
        "beyond_tip": (lmax + 0.05, hw - rho + 0.03),  # round the rounded tip corner
        "behind_root": (-0.05, hw + 0.02),
        "back": (0.5 * lmax, -hw - 0.1),  # behind the bar
        "back_tip": (lmax + 0.04, -hw - 0.02),
    }[sc_kind]
    th = x[2 * n + j]
    e = np.array([np.sin(th), np.cos(th)])
    nrm = np.array([-np.cos(th), np.sin(th)])
    q[i] = -prm[K.P_C0X : K.P_C0X + 2] + s_m[0] * e + s_m[1] * nrm

    def fun(z):
        qq = q.copy()
        qq[i] = z[:2]
        g5, h5 = np.zeros(5), np.zeros((5, 5))
        val = K._face_eval(qq, i, j, *_sc(z[2]), prm, g5, h5, True)
        return val, g5[:3].copy()

    z = np.array([q[i, 0], q[i, 1], x[2 * n + j]])
    g5, h5 = np.zeros(5), np.zeros((5, 5))
    val = K._face_eval(q, i, j, *_sc(z[2]), prm, g5, h5, True)
    assert val > 0
    assert K._face_gap(q, i, j, *_sc(z[2]), prm) == pytest.approx(val, abs=1e-15)
    g_only = np.zeros(5)
    K._face_eval(q, i, j, *_sc(z[2]), prm, g_only, np.zeros((5, 5)), False)
    np.testing.assert_allclose(g_only, g5, atol=1e-15)
    _fd_check(fun, z, g5[:3], h5[:3, :3])


@pytest.mark.parametrize("c,k", [(1, 9), (0, 9), (1, 3), (0, 0), (2, 6), (3, 9), (2, 0)])
def test_corner_constraint_derivatives(c, k):
    # corner c of the bar (0/1 tip/root of the face, 2/3 of the back) against edge k: the
    # edge-interior and the end-point branches of the segment distance
    prob, x = _state()
    n = prob.n
    q = x[: 2 * n].reshape(n, 2).copy()
    j = 1

    def fun(z):
        qq = q.copy()
        qq[k] = z[:2]
        qq[(k + 1) % n] = z[2:4]
        g5, h5 = np.zeros(5), np.zeros((5, 5))
        val = K._corner_eval(qq, k, j, *_sc(z[4]), c, prob.params, g5, h5, True)
        return val, g5.copy()

    z = np.array([*q[k], *q[(k + 1) % n], x[2 * n + j]])
    g5, h5 = np.zeros(5), np.zeros((5, 5))
    val = K._corner_eval(q, k, j, *_sc(z[4]), c, prob.params, g5, h5, True)
    assert K._corner_gap(q, k, j, *_sc(z[4]), c, prob.params) == pytest.approx(val, abs=1e-13)
    g_only = np.zeros(5)
    K._corner_eval(q, k, j, *_sc(z[4]), c, prob.params, g_only, np.zeros((5, 5)), False)
    np.testing.assert_allclose(g_only, g5, atol=1e-15)
    _fd_check(fun, z, g5, h5)


@pytest.mark.parametrize("k_area", [0.0, 0.5])
def test_energy_gradient_and_banded_hessian(k_area):
    prob, x = _state(n=10)
    n = prob.n
    prm = np.append(prob.params, 0.3)  # with a gauge spring
    prm[K.P_KA] = k_area  # and the area energy of the model family

    def grad_of(z):
        gr = np.zeros(2 * n + 2)
        K.mesh_gradient(z, n, prm, gr)
        K._gauge_gradient(z, prm, gr)
        return K._energy(z, n, prm), gr

    e, gr = grad_of(x)
    bidx = K._band_index(n)
    ab, bb, dd = np.zeros((2 * n, K.BW + 1)), np.zeros((2 * n, 2)), np.zeros((2, 2))
    K._spring_terms(x, n, prm, bidx, np.zeros(2 * n + 2), ab, bb, dd, False)
    # rebuild the dense Hessian in natural order from the band storage
    dense_b = np.zeros((2 * n + 2, 2 * n + 2))
    for p in range(2 * n):
        for kk in range(K.BW + 1):
            if p - kk >= 0:
                dense_b[p, p - kk] = dense_b[p - kk, p] = ab[p, kk]
    dense_b[2 * n :, 2 * n :] = dd
    perm = np.array([bidx[i] + c for i in range(n) for c in range(2)] + [2 * n, 2 * n + 1])
    dense = dense_b[np.ix_(perm, perm)]
    _fd_check(grad_of, x, gr, dense)


def test_band_ordering_keeps_neighbours_within_bandwidth():
    for n in (4, 5, 20, 21, 1000):
        idx = K._band_index(n)
        assert sorted(idx // 2) == list(range(n))
        for i in range(n):
            assert abs(idx[i] - idx[(i + 1) % n]) + 1 <= K.BW


def _bordered_band_system(n, rng, diag_boost):
    """A random symmetric matrix [[A, B], [B^T, D]] with A banded in 2x2 blocks (a point's
    block couples with the two blocks before it) in the kernels' storage, and the same matrix
    dense."""
    nb = 2 * n
    dense = np.zeros((nb + 2, nb + 2))
    for p in range(nb):
        for k in range(1, K.BW + 1):
            if p - k >= 0 and p // 2 - (p - k) // 2 <= 2:
                dense[p, p - k] = dense[p - k, p] = rng.normal()
    dense[:nb, nb:] = rng.normal(size=(nb, 2))
    dense[nb:, :nb] = dense[:nb, nb:].T
    dense[nb, nb + 1] = dense[nb + 1, nb] = rng.normal()
    dense[np.diag_indices(nb + 2)] = diag_boost * (np.abs(dense).sum(axis=1) + 1.0)
    ab = np.zeros((nb, K.BW + 1))
    for p in range(nb):
        for k in range(K.BW + 1):
            if p - k >= 0:
                ab[p, k] = dense[p, p - k]
    return dense, ab, dense[:nb, nb:].copy(), dense[nb:, nb:].copy()


@pytest.mark.parametrize("n", [4, 7, 20])
def test_bordered_band_solve_matches_dense_solve(n):
    # the Newton system: banded Cholesky of the contour block, 2x2 Schur complement of the angles
    rng = np.random.default_rng(n)
    nb = 2 * n
    dense, ab, bb, dd = _bordered_band_system(n, rng, 1.0)
    rhs = rng.normal(size=nb + 2)
    shift = 0.3
    out_b, out_t = np.zeros(nb), np.zeros(2)
    ok = K._factor_solve(ab, bb, dd, np.zeros_like(ab), np.zeros((nb, 2)), nb, shift,
                         rhs[:nb].copy(), rhs[nb:].copy(), out_b, out_t)
    assert ok
    want = np.linalg.solve(dense + shift * np.eye(nb + 2), rhs)
    np.testing.assert_allclose(np.concatenate([out_b, out_t]), want, rtol=1e-12, atol=1e-12)
    # an indefinite matrix is refused (the caller then convexifies or shifts)
    _, ab_bad, bb, dd = _bordered_band_system(n, rng, 1.0)
    ab_bad[nb // 2, 0] = -5.0
    assert not K._factor_solve(ab_bad, bb, dd, np.zeros_like(ab), np.zeros((nb, 2)), nb, 0.0,
                               rhs[:nb].copy(), rhs[nb:].copy(), out_b, out_t)


def test_barrier_merit_parts_match_energy_and_log_gaps():
    # the merit sums the logarithms of products of gaps: same value as the plain sum, tiny
    # gaps included (no underflow)
    n = 40
    prob = scaled_problem(Scene.preset("paper-r070"), 0.3, n)
    prm = prob.params
    x = np.concatenate([rest_points(n).ravel(), [prm[K.P_TH0]] * 2])
    kinds = np.zeros(2 * n, dtype=np.int64)
    fj = np.repeat(np.arange(2), n).astype(np.int64)
    fidx = np.tile(np.arange(n), 2).astype(np.int64)
    gaps = np.zeros(2 * n)
    e, logs = K._merit(x, n, prm, kinds, fj, fidx, 2 * n, gaps)
    assert e == pytest.approx(K._energy(x, n, prm), rel=1e-15)
    assert np.all(gaps > 0)
    assert logs == pytest.approx(np.log(gaps).sum(), rel=1e-13)
    # points facing the right finger's gripping face moved to within about 1e-13 r of it
    q = x[: 2 * n].reshape(n, 2)
    s_th, c_th = _sc(x[2 * n])
    moved = []
    for i in range(n):
        _, _, nx, ny, s_bar, m_bar = K._finger_coords(q, i, 0, s_th, c_th, prm)
        if 0.0 < s_bar < prm[K.P_LMAX] and m_bar > prm[K.P_HW]:
            x[2 * i : 2 * i + 2] -= (gaps[i] - 1e-13 * (len(moved) + 1)) * np.array([nx, ny])
            moved.append(i)
    assert len(moved) >= 10
    e, logs = K._merit(x, n, prm, kinds, fj, fidx, 2 * n, gaps)
    assert gaps[moved].max() < 1e-11 and np.all(gaps > 0)
    assert logs == pytest.approx(np.log(gaps).sum(), rel=1e-13)
    x[2 * moved[0] : 2 * moved[0] + 2] -= 1e-3 * np.array([nx, ny])  # into the finger
    assert K._merit(x, n, prm, kinds, fj, fidx, 2 * n, gaps)[0] == math.inf


def test_crossed_through_shortcut_agrees_with_the_full_tests():
    # corners and bars outside the circle holding the contour are skipped: same verdict as
    # testing every corner and bar, on fingers swept through and past a deformed disk
    prob, x = _state(n=20)
    n, prm = prob.n, prob.params
    q = x[: 2 * n].reshape(n, 2)
    verdicts = set()
    for th_r in np.linspace(-0.4, 1.2, 41):
        for th_l in (-0.3, 0.2, 0.9):
            x[2 * n :] = th_r, th_l
            full = False
            for j in range(2):
                s, c = _sc(x[2 * n + j])
                full |= K._bar_crossed(q, n, j, s, c, prm)
                for corner in range(4):
                    kx, ky = K._corner_centre(j, s, c, corner, prm)
                    full |= K._inside(q, n, kx, ky)
            assert K._crossed_through(x, n, prm) == full
            verdicts.add(full)
    assert verdicts == {True, False}


@pytest.mark.parametrize("k_area", [0.0, 0.5])
def test_convexified_fallback_from_the_exact_matrix_matches_a_fresh_assembly(k_area):
    # the interior point's fallback (negative spring stiffness, the area energy's indefinite
    # part and constraint curvature dropped) is made from the exact matrix in place: the same
    # as assembling it afresh
    prob, x = _state(n=12, seed=3)
    n, nb = prob.n, 2 * prob.n
    prm = np.append(prob.params, 0.0)
    prm[K.P_KA] = k_area
    face = np.ones((2, n), dtype=np.bool_)
    corner = np.zeros((2, 4, n), dtype=np.bool_)
    corner[:, :, ::3] = True
    mmax = 10 * n + 2
    kinds, fj, fidx = (np.zeros(mmax, dtype=np.int64) for _ in range(3))
    m = K._build_constraints(face, corner, n, kinds, fj, fidx)
    rng = np.random.default_rng(0)
    lam = rng.uniform(0.1, 1.0, m)
    sig = rng.uniform(0.1, 1.0, m)
    bidx = K._band_index(n)

    def assemble(psd):
        g = np.zeros(m)
        K._all_gaps(x, n, prm, kinds[:m], fj, fidx, g)
        mats = np.zeros((nb, K.BW + 1)), np.zeros((nb, 2)), np.zeros((2, 2))
        ch = np.zeros((m, K.CH_BLOCK + 1))
        cd = np.zeros((m, 5), dtype=np.int64)
        K._newton_matrix(x, n, prm, bidx, kinds, fj, fidx, m, lam, sig, np.zeros(nb + 2),
                         *mats, g, np.zeros(5), np.zeros((5, 5)), np.zeros(5, dtype=np.int64),
                         1e-3, psd, np.zeros(nb + 2), np.zeros(nb + 2), np.zeros((m, 5)), cd,
                         ch)
        return mats, cd, ch

    (ab, bb, dd), cd, ch = assemble(False)
    exact = [a.copy() for a in (ab, bb, dd)]
    K._drop_curvature(x, n, prm, bidx, kinds, fj, m, cd, ch, np.zeros((5, 5)),
                      np.zeros(5, dtype=np.int64), ab, bb, dd)
    fresh, _, _ = assemble(True)
    for got, want in zip((ab, bb, dd), fresh, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    # the state has compressed springs and curved constraints: the two matrices differ
    assert max(np.abs(w - e).max() for w, e in zip(fresh, exact, strict=True)) > 1e-3


def test_area_energy_is_zero_at_rest_and_infinite_when_folded():
    prob, x = _state(n=12)
    prm = prob.params.copy()
    prm[K.P_KA] = 1.0
    n = prob.n
    rest = np.concatenate([rest_points(n).ravel(), x[2 * n :]])
    no_area = prm.copy()
    no_area[K.P_KA] = 0.0
    assert K.fan_energy(rest, n, prm) == pytest.approx(K.fan_energy(rest, n, no_area), abs=1e-15)
    folded = rest.copy()
    folded[2:4] = -0.1 * folded[2:4]  # point 1 through the centre: two triangles turn over
    assert K.fan_energy(folded, n, prm) == math.inf
    assert math.isfinite(K.fan_energy(folded, n, no_area))


def test_triangle_log_strain_is_the_fem_measure():
    # against the FEM reference's Hencky strain of the same deformation gradient, and the
    # analytic limits: a rotation is strain-free, a uniform stretch lambda gives |ln lambda|
    from envs.fem import material

    rng = np.random.default_rng(5)
    a, b = np.array([1.0, 0.0]), np.array([math.cos(0.4), math.sin(0.4)])
    for _ in range(50):
        f = np.eye(2) + 0.3 * rng.standard_normal((2, 2))
        if np.linalg.det(f) <= 0:
            continue
        p, q = f @ a, f @ b
        got = K.triangle_log_strain(*a, *b, *p, *q)
        assert got == pytest.approx(float(material._log_strain_magnitude(f)), rel=1e-12)
    rot = np.array([[math.cos(1.1), -math.sin(1.1)], [math.sin(1.1), math.cos(1.1)]])
    assert K.triangle_log_strain(*a, *b, *(rot @ a), *(rot @ b)) == pytest.approx(0, abs=1e-14)
    assert K.triangle_log_strain(*a, *b, *(0.8 * a), *(0.8 * b)) == pytest.approx(-math.log(0.8))
    assert K.triangle_log_strain(*a, *b, *b, *a) == math.inf  # folded
