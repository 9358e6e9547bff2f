"""Ring meshes of the model family (docs/model.md): geometry, energy, Newton matrix, solves.

The paper's fan is the one-ring member (its answers are pinned by the regression corpus); these
tests cover what rings add: the mesh's rest geometry, exact derivatives of the energy on it,
the banded Newton matrix in its wider band, and checked equilibria of ring meshes.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from envs.model.defaults import DEFAULT_PHASE_RAD
from envs.model.energy import cst_energy, energy_scaled, gradient_scaled
from envs.model.problem import rest_state, scaled_params
from envs.model.rings import (
    HUB_RADIUS,
    kernel_params,
    mesh_band_index,
    mesh_half_bandwidth,
    n_state,
    n_tri_types,
    point_xy,
    tri_corners,
    tri_rest_area,
)
from envs.scene import Scene
from envs.solver.assembly import _spring_terms
from envs.solver.banded import _factor_solve, band_shape
from envs.solver.simulate import simulate, simulate_ramp

SCENE = Scene.preset("paper-r070").with_changes(area_stiffness_scale=0.3)


def _rest(n, m, scene=SCENE, torque=0.2, element="spring"):
    prm = scaled_params(scene, torque, n, n_rings=m, element=element)
    return prm, rest_state(prm, n)[0]


@pytest.mark.parametrize(("n", "m"), [(8, 2), (20, 3), (21, 4), (12, 6)])
def test_ring_mesh_tiles_the_annulus(n, m):
    """The triangles are counter-clockwise and tile the polygon annulus between the hub and
    the contour: their rest areas sum to the two polygons' difference."""
    prm, x = _rest(n, m)
    kp = kernel_params(prm, n)
    total = 0.0
    for t in range(n_tri_types(m)):
        for i in range(n):
            ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
            a = np.array(point_xy(x, n, m, kp, ka, ia))
            b = np.array(point_xy(x, n, m, kp, kb, ib))
            c = np.array(point_xy(x, n, m, kp, kc, ic))
            u, v = b - a, c - a
            area = 0.5 * (u[0] * v[1] - u[1] * v[0])
            assert area == pytest.approx(tri_rest_area(kp, t, i, m), rel=1e-12)
            assert area > 0
            total += area
    polygon = 0.5 * n * math.sin(2 * math.pi / n)
    assert total == pytest.approx(polygon * (1 - HUB_RADIUS**2), rel=1e-12)


@pytest.mark.parametrize("m", [1, 2, 3, 5])
def test_band_order_covers_every_point_within_the_band(m):
    n = 14
    idx = mesh_band_index(n, m)
    assert sorted(idx // 2) == list(range(n * m))
    bw = mesh_half_bandwidth(m)
    # every spring couples two points within the half bandwidth (neighbouring angles)
    pos = idx.reshape(-1)
    for k in range(1, m + 1):
        for i in range(n):
            p = i if k == m else n + (k - 1) * n + i
            for dk in (-1, 0, 1):
                k2 = k + dk
                if not 1 <= k2 <= m:
                    continue
                for di in (-1, 0, 1):
                    i2 = (i + di) % n
                    q = i2 if k2 == m else n + (k2 - 1) * n + i2
                    assert abs(pos[p] - pos[q]) + 1 <= bw


@pytest.mark.parametrize(("n", "m", "element"), [(10, 2, "spring"), (16, 4, "spring"),
                                                 (10, 2, "cst"), (12, 1, "cst"),
                                                 (16, 3, "cst"), (10, 2, "nhquad"),
                                                 (15, 4, "nhquad")])
def test_energy_gradient_and_band_hessian_are_exact(n, m, element):
    """Gradient by central differences; the banded Newton matrix times a vector against
    differences of the gradient (springs and area energy, or constant-strain triangles)."""
    prm, x0 = _rest(n, m, element=element)
    kp = kernel_params(prm, n)
    rng = np.random.default_rng(3)
    x = x0 + 2e-3 * rng.standard_normal(x0.size)
    g = gradient_scaled(x, prm, n)
    e = np.eye(x.size)
    fd = np.array([(energy_scaled(x + 1e-6 * e[d], prm, n) - energy_scaled(x - 1e-6 * e[d], prm,
                                                                              n)) / 2e-6
                   for d in range(x.size)])
    np.testing.assert_allclose(fd, g, atol=2e-8 * np.abs(g).max())
    nbb, bw = band_shape(n, kp)
    bidx = mesh_band_index(n, m)
    ab, bb, dd = np.zeros((nbb, bw + 1)), np.zeros((nbb, 2)), np.zeros((2, 2))
    grad = np.zeros(x.size)
    _spring_terms(x, n, kp, bidx, grad, ab, bb, dd, False)
    # dense Hessian in state order from the band
    full = np.zeros((nbb + 2, nbb + 2))
    for p in range(nbb):
        for d in range(bw + 1):
            if p - d >= 0:
                full[p, p - d] = full[p - d, p] = ab[p, d]
    full[:nbb, nbb:] = bb
    full[nbb:, :nbb] = bb.T
    full[nbb:, nbb:] = dd
    perm = np.empty(x.size, dtype=int)  # state index -> band row
    for d in range(x.size):
        if d < 2 * n:
            perm[d] = bidx[d // 2] + d % 2
        elif d < 2 * n + 2:
            perm[d] = nbb + d - 2 * n
        else:
            p = (d - 2) // 2
            perm[d] = bidx[p] + (d - 2) % 2
    hess = full[np.ix_(perm, perm)]
    v = rng.standard_normal(x.size)
    hv = (gradient_scaled(x + 1e-6 * v, prm, n) - gradient_scaled(x - 1e-6 * v, prm, n)) / 2e-6
    np.testing.assert_allclose(hess @ v, hv, atol=1e-6 * np.abs(hv).max())
    # and the banded factor-and-solve of the bordered matrix matches a dense solve
    shift = 1.0
    rhs = rng.standard_normal(nbb + 2)
    lb, ybuf, ob, ot = np.zeros_like(ab), np.zeros((nbb, 2)), np.zeros(nbb), np.zeros(2)
    assert _factor_solve(ab, bb, dd, lb, ybuf, nbb, shift, rhs[:nbb].copy(), rhs[nbb:].copy(),
                         ob, ot)
    want = np.linalg.solve(full + shift * np.eye(nbb + 2), rhs)
    np.testing.assert_allclose(np.concatenate((ob, ot)), want, rtol=1e-9, atol=1e-12)


def test_cst_energy_keeps_its_relative_accuracy_at_tiny_strains():
    """The neo-Hookean triangle's energy is exact to round-off relative to itself at any
    strain: at 1e-8 it matches linear elasticity (which it equals to first order in the
    strain), where the textbook form ``mu/2 (I1 - 2) - mu ln J`` kept only an absolute accuracy
    of about ``eps mu A0`` (noise the line search could not see through)."""
    rng = np.random.default_rng(5)
    a0, mu, lam = 0.01, 0.34, 1.5
    for strain in (1e-8, 1e-4):
        for _ in range(20):
            h = strain * rng.standard_normal((2, 2))
            f = np.eye(2) + h
            # identity rest edges: Ds = F, Dm^-1 = I
            e = cst_energy(f[0, 0], f[0, 1], f[1, 0], f[1, 1], 1.0, 0.0, 0.0, 1.0, a0, mu, lam)
            linear = a0 * (0.5 * mu * ((h[0, 0] - h[1, 1]) ** 2 + (h[0, 1] + h[1, 0]) ** 2)
                           + 0.5 * (mu + lam) * np.trace(h) ** 2)
            assert e == pytest.approx(linear, rel=20 * strain, abs=0.0)
    # at a finite strain it is the textbook energy
    f = np.array([[1.2, 0.1], [-0.05, 0.9]])
    j = np.linalg.det(f)
    textbook = a0 * (0.5 * mu * ((f * f).sum() - 2) - mu * math.log(j)
                     + 0.5 * lam * math.log(j) ** 2)
    e = cst_energy(f[0, 0], f[0, 1], f[1, 0], f[1, 1], 1.0, 0.0, 0.0, 1.0, a0, mu, lam)
    assert e == pytest.approx(textbook, rel=1e-13, abs=0.0)


# the members an optimizer's best designs are re-scored with, and their neighbours
CONTACT_FREE_MEMBERS = [
    {"element": "nhquad", "n_triangles": n, "n_rings": m}
    for n, m in ((40, 2), (48, 3), (56, 4), (64, 4), (80, 5), (96, 6), (96, 4), (120, 6))
] + [{"element": "spring", "n_triangles": 20}, {"element": "cst"},
     {"element": "cst", "n_triangles": 48, "n_rings": 3},
     {"element": "cst", "n_triangles": 96, "n_rings": 6}]


@pytest.mark.filterwarnings("ignore:the shipped nh-quad scale")
@pytest.mark.parametrize("member", CONTACT_FREE_MEMBERS,
                         ids=lambda k: f"{k['element']}-{k.get('n_triangles')}x{k.get('n_rings')}")
def test_a_contact_free_design_answers_the_free_state_in_few_iterations(member):
    """Torque 0 (an optimizer clipping the torque to the box's lower bound) and torques too
    small to reach the disk: the answer is the rest mesh with the fingers at their free angle
    ``theta_a0 - T / k_f`` (the rest angle at T = 0), no contact and nothing on the pin, a
    converged solve in a few iterations. The ring members ran into the iteration limit here
    (status 1 after 700 iterations): the line search could not see the last decrease through
    the round-off of the neo-Hookean energy (:func:`envs.model.energy.cst_energy`)."""
    from envs import DesignBounds, evaluate_designs

    disk = Scene.preset("paper-r070").disk
    torques = np.array([0.0, 1e-12, 1e-9, 1e-6, 1e-3])
    designs = DesignBounds().scale(np.tile([0.0, 0, 0, 0, -1, 0], (torques.size, 1)), disk)
    assert np.all(designs[:, 4] == 0.0)
    designs[:, 4] = torques
    kf = 0.073
    out = evaluate_designs(designs, disk, torsion_stiffness_nm_per_rad=kf, **member)
    np.testing.assert_array_equal(out["status"], 0)
    assert out["converged"].all() and out["stable"].all()
    assert out["iterations"].max() <= 20, out["iterations"]
    free = designs[:, 1] - torques / kf
    np.testing.assert_allclose(out["jaw_angles_rad"], np.column_stack((free, free)), rtol=0,
                               atol=1e-10)
    assert out["jaw_angles_rad"][0, 0] == designs[0, 1]  # the rest angle itself at T = 0
    np.testing.assert_array_equal(out["n_contacts"], 0)
    assert not out["touching"].any()
    np.testing.assert_array_equal(out["pin_force_n"], 0.0)
    np.testing.assert_array_equal(out["total_force_n"], 0.0)
    # the mesh stays at rest: unstrained, and unmoved where a hub holds its turn about the
    # centre or the torque is at most 1e-6 N·m (a fan's rigid turn is neutral without contact,
    # an equally valid answer: at 1e-3 N·m the fast attempt's saddle test turns the spring fan
    # by a quarter of its point spacing)
    assert out["peak_strain"].max() < 1e-12
    held = torques <= 1e-6 if member.get("n_rings", 1) == 1 else torques >= 0.0
    assert out["max_displacement_ratio"][held].max() < 1e-12


def test_rest_state_is_an_equilibrium_of_the_mesh():
    for m in (2, 4):
        prm, x = _rest(16, m)
        g = gradient_scaled(x, prm, 16)
        pts = np.delete(g, [32, 33])
        assert np.abs(pts).max() < 1e-13
        assert x.size == n_state(16, m)


@pytest.mark.parametrize(("m", "element"), [(2, "spring"), (4, "spring"), (3, "cst"),
                                              (1, "cst"), (2, "nhquad"), (4, "nhquad")])
def test_ring_grasp_is_a_checked_equilibrium(m, element):
    """A ring mesh grasp converges and the independent check (its own mesh, forces from the
    triangles' shares of each spring, or its own constant-strain stresses) passes; the
    interior points come back in metres."""
    res = simulate(SCENE, 0.2, 20, n_rings=m, element=element)
    assert res.converged, res.message
    assert res.kkt.passed and res.kkt.force_residual_rel < 1e-8
    assert res.n_rings == m
    assert res.interior_points_m.shape == ((m - 1) * 20, 2)
    r = SCENE.disk.radius_m
    dist = np.linalg.norm(res.interior_points_m - SCENE.disk.center_m, axis=1)
    assert np.all((dist > HUB_RADIUS * r) & (dist < r))
    assert res.inverted_triangles == 0
    # more points carry the load: the jaw still closes, and less than on the rigid disk
    assert res.jaw_angles_rad[0] < SCENE.gripper.rest_angle_rad


def test_ring_ramp_warm_starts_and_is_monotone():
    torques = [0.05, 0.1, 0.2, 0.3]
    out = simulate_ramp(SCENE, torques, 16, n_rings=3, element="spring")
    assert all(r.converged for r in out), [r.message for r in out]
    closing = [SCENE.gripper.rest_angle_rad - np.mean(r.jaw_angles_rad) for r in out]
    assert np.all(np.diff(closing) > 0)


def test_ramp_snaps_off_a_symmetric_branch_that_loses_its_stability():
    # a 4-point disk squeezed on two opposite corners: past ~1 N·m the symmetric equilibrium
    # is a saddle (the square turns to lay a side on each finger). A direct solve there stays
    # on the saddle and says so; the ramp leaves it for the stable grasp, which closes further
    scene = Scene.preset("paper-r050")
    torque = 1.231
    direct = simulate(scene, torque, 4, n_rings=2, element="nhquad")
    assert direct.converged and not direct.stable
    torques = 0.02 * 1.25 ** np.arange(22)
    out = simulate_ramp(scene, torques, 4, n_rings=2, element="nhquad")
    assert all(r.converged and r.stable for r in out), [(r.torque_nm, r.message) for r in out]
    snapped = simulate_ramp(scene, [0.5, 0.9, torque], 4, n_rings=2, element="nhquad")[-1]
    assert snapped.converged and snapped.stable
    assert np.mean(snapped.jaw_angles_rad) < np.mean(direct.jaw_angles_rad) - 0.05


def test_a_failed_solve_is_retried_from_a_turned_rest_shape():
    # the same disk past its bifurcation: from the rest shape the solve stays on the symmetric
    # saddle and fails; from the rest shape turned a quarter spacing it reaches the stable
    # grasp, and simulate reports it with every attempt's iterations
    from envs.solver.simulate import TURNED_STARTS, _Problem, _rest, _turned

    scene = Scene.preset("paper-r050")
    res = simulate(scene, 1.734, 4, n_rings=2, element="nhquad")
    assert res.converged and res.stable, res.message
    assert res.kkt.passed
    prob = _Problem(scene, 1.734, 4, "van_gelder", DEFAULT_PHASE_RAD, 2, "nhquad",
                    res.model_scale)
    plain, _ = prob.solve()
    assert not plain.converged
    turned, _ = prob.solve(_turned(prob, _rest(prob), TURNED_STARTS[0]), np.zeros((2, 4)))
    assert turned.converged
    np.testing.assert_allclose(res.jaw_angles_rad, turned.jaw_angles_rad, rtol=0, atol=1e-9)
    assert res.iterations == plain.iterations + turned.iterations


def test_ring_arguments_are_validated():
    with pytest.raises(ValueError, match="n_rings"):
        simulate(SCENE, 0.2, 20, n_rings=0, element="spring")
    with pytest.raises(ValueError, match="n_rings"):
        simulate(SCENE, 0.2, 20, n_rings=2.5, element="spring")
    with pytest.raises(ValueError, match="newton"):
        simulate(SCENE, 0.2, 20, method="slsqp", n_rings=2, element="spring")
    with pytest.raises(ValueError, match="element"):
        simulate(SCENE, 0.2, 20, n_rings=2, element="fem")


def test_cst_fallback_matrix_is_the_linear_elastic_one():
    """The convexified Hessian of a constant-strain triangle is the tangent at rest: positive
    semi-definite (the rotation its only null mode), whatever the current state."""
    from envs.model.energy import cst_hessian_column, cst_rest

    m00, m01, m10, m11, a0 = cst_rest(0.0, 0.0, 1.0, 0.2, 0.3, 0.9)
    for ds in ((1.0, 0.3, 0.2, 0.9), (0.5, -0.2, 0.4, 0.3)):  # the second compressed, sheared
        cols = np.array([cst_hessian_column(*ds, m00, m01, m10, m11, a0, 0.3, 2.0, r, e, True)
                         for r in (0, 1) for e in (0, 1)])
        assert np.allclose(cols, cols.T)
        # over the edge matrix the only null mode is the infinitesimal rotation
        eig = np.linalg.eigvalsh(cols)
        assert eig[0] == pytest.approx(0.0, abs=1e-12) and eig[1] > 1e-3
        exact = np.array([cst_hessian_column(*ds, m00, m01, m10, m11, a0, 0.3, 2.0, r, e, False)
                          for r in (0, 1) for e in (0, 1)])
        assert np.allclose(exact, exact.T)


@pytest.mark.parametrize("nu", [0.3, 0.4, 0.45, 0.49])
def test_hybrid_scales_give_the_lame_moduli_on_the_equilateral_lattice(nu):
    """Homogenisation: under a uniform small strain the equilateral lattice deforms affinely
    (one node per cell); its energy per area, from the model's own spring and area terms with
    the hybrid scales, is the plane-strain ``lambda/2 (tr e)^2 + mu e:e`` of E and nu."""
    from envs.model.energy import area_energy, spring_energy
    from envs.model.family import hybrid_scales

    youngs, t = 1.0, 1.0
    s, c_a = hybrid_scales(nu)
    lam = youngs * nu / ((1 + nu) * (1 - 2 * nu))
    mu = youngs / (2 * (1 + nu))
    kappa = c_a * (lam + mu)
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, math.sqrt(3) / 2]])
    a0 = math.sqrt(3) / 4
    for strain in ([[1, 0], [0, 0]], [[0, 1], [1, 0]], [[1, 0], [0, 1]], [[0.3, -0.7],
                                                                          [-0.7, 0.2]]):
        eps = 1e-5 * np.asarray(strain, dtype=float)
        moved = corners @ (np.eye(2) + eps).T
        energy = 0.0
        for c in range(3):
            d = (c + 1) % 3
            rest = np.linalg.norm(corners[d] - corners[c])
            # the triangle's share of each edge's area-rule spring, s E t A0 / L0^2
            dx, dy = moved[d] - moved[c]
            energy += spring_energy(dx, dy, s * youngs * t * a0 / rest**2, rest)
        u, v = moved[1] - moved[0], moved[2] - moved[0]
        energy += area_energy(0.5 * (u[0] * v[1] - u[1] * v[0]), kappa * t, a0)
        want = 0.5 * lam * np.trace(eps) ** 2 + mu * np.sum(eps * eps)
        assert energy / (a0 * t) == pytest.approx(want, rel=2e-4)


@pytest.mark.parametrize("aspect", [0.4, 1.0, 2.5, 10.0])
def test_a_diagonal_cut_cell_carries_shear_only_through_its_diagonal(aspect):
    """Homogenisation of the ring mesh's cell (width w, depth a w, one diagonal; one node per
    cell, so a uniform strain is its equilibrium): with the area-rule springs its energy under
    pure shear is ``2 mu e_xy^2`` with ``mu = s E a^2 / (1 + a^2)^2``, 2/3 of the equilateral
    lattice's 3/8 s E at a = 1 and falling like 1 / a^2: why a spring ring mesh is accepted
    only for cells near square (``MAX_SPRING_CELL_ASPECT``); the area energy adds nothing."""
    from envs.model.energy import area_energy, spring_energy
    from envs.model.family import CAUCHY_SHEAR_PER_E

    youngs, t, w = 1.0, 1.0, 1.0
    d = aspect * w
    cell = w * d
    edges = ((w, 0.0), (0.0, d), (w, d))  # tangential, radial, diagonal: one each per cell
    e_xy = 1e-5
    eps = np.array([[0.0, e_xy], [e_xy, 0.0]])
    energy = 0.0
    for ex, ey in edges:
        rest = math.hypot(ex, ey)
        # every edge is shared by two triangles of area cell / 2: k = E t cell / L^2
        dx, dy = (np.eye(2) + eps) @ np.array([ex, ey])
        energy += spring_energy(dx, dy, youngs * t * cell / rest**2, rest)
    # shear keeps both triangles' areas: the area energy is zero to second order
    u, v = (np.eye(2) + eps) @ np.array([w, 0.0]), (np.eye(2) + eps) @ np.array([w, d])
    sheared_area = 0.5 * (u[0] * v[1] - u[1] * v[0])
    assert area_energy(sheared_area, youngs * t, 0.5 * cell) < 1e-6 * energy
    mu = energy / (cell * t) / (2 * e_xy**2)
    assert mu == pytest.approx(youngs * aspect**2 / (1 + aspect**2) ** 2, rel=1e-4)
    if aspect == 1.0:
        assert mu / CAUCHY_SHEAR_PER_E == pytest.approx(2 / 3, rel=1e-4)


def test_spring_ring_meshes_are_refused_beyond_their_cell_aspect():
    """A spring ring member is accepted while its cells are 0.4-2.5 times as deep as wide; the
    message names the parameter, the range and the way out; the other members are not
    affected."""
    from envs.model.defaults import MAX_SPRING_CELL_ASPECT
    from envs.model.family import resolve_model, spring_cell_aspect, triangle_range

    for m in (2, 3, 4, 8, 16):
        low, high = triangle_range(m, "spring")
        assert spring_cell_aspect(high, m) <= MAX_SPRING_CELL_ASPECT
        assert spring_cell_aspect(high + 1, m) > MAX_SPRING_CELL_ASPECT
        assert low == 4 or spring_cell_aspect(low - 1, m) < 1 / MAX_SPRING_CELL_ASPECT
        assert resolve_model(high, m, "spring").n_triangles == high
        with pytest.raises(ValueError, match=r"n_triangles = \d+ .*\[\d+, \d+\].*nhquad"):
            resolve_model(high + 1, m, "spring")
    assert triangle_range(2, "spring") == (4, 22)
    assert triangle_range(1, "spring") == (4, 500)
    assert triangle_range(2, "cst") == triangle_range(2, "nhquad") == (4, 2000)
    # the default N (the paper's 20) is a valid spring ring mesh for every ring count
    assert all(resolve_model(None, m, "spring").n_triangles == 20 for m in range(1, 17))
    with pytest.raises(ValueError, match="n_triangles"):
        simulate(SCENE, 0.2, 100, n_rings=2, element="spring")
    from envs.evaluate import evaluate_designs
    g, disk = SCENE.gripper, SCENE.disk
    design = [[g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m, 0.2,
               disk.distance_m]]
    assert evaluate_designs(design, disk, n_triangles=20, n_rings=2,
                            element="spring")["converged"][0]
    with pytest.raises(ValueError, match="n_triangles"):
        evaluate_designs(design, disk, n_triangles=[20, 100], n_rings=2, element="spring")


def test_hybrid_scales_validate_and_are_physical():
    from envs.model.family import hybrid_scales

    s, c_a = hybrid_scales(0.45)
    assert s == pytest.approx(4 / (3 * 1.45)) and 0.9 < s < 1.0
    assert c_a == pytest.approx(0.80, abs=0.01)
    assert hybrid_scales(0.25)[1] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError, match="poisson_ratio"):
        hybrid_scales(0.2)


def test_choose_model_picks_the_cheapest_member_within_tolerance():
    """Against the FEM of paper-r070 the paper's fan (s = 1) is ~30 % off; hybrid ring members
    are within a few percent, and the choice is the cheapest of those within tolerance."""
    pytest.importorskip("skfem")
    from envs.accuracy.members import Member, choose_model

    torques = (0.1, 0.2, 0.3)
    members = (Member(20, 1), Member(20, 2, "hybrid"), Member(20, 3, "calibrated", "cst"))
    got = choose_model(Scene.preset("paper-r070"), 0.06, torques, members=members)
    rows = {r.member: r for r in got.rows}
    assert rows[Member(20, 1)].max_rel_error > 0.2
    assert not rows[Member(20, 1)].within_tolerance
    assert got.within_tolerance and got.member.n_rings > 1
    ok = [r for r in got.rows if r.within_tolerance]
    assert rows[got.member].compiled_s_per_torque == min(r.compiled_s_per_torque for r in ok)
    # nothing within an impossible tolerance: the most accurate member, flagged
    tight = choose_model(Scene.preset("paper-r070"), 1e-6, torques, members=members)
    assert not tight.within_tolerance
    assert tight.member != Member(20, 1)
    with pytest.raises(ValueError, match="tolerance"):
        choose_model(Scene.preset("paper-r070"), 0.0, torques, members=members)


def test_the_default_model_is_the_choice_on_disks_no_scale_was_fitted_to():
    """The default of simulate and the env follows from choose_model: over the held-out disks
    (other radii, moduli, Poisson ratios; the paper torque ramp; ~15 s with the FEM) at 4 % max
    and 2 % RMS, every candidate of DEFAULT_MEMBERS is solved and the cheapest within is the
    default nh-quad 40 x 2. The coarser 32 x 2 misses (4.6 % at contact onset), the finer 48 x 3
    is within at twice the cost; the paper's fan and the hybrid spring rings miss far. Each row
    is its worst disk."""
    pytest.importorskip("skfem")
    from envs.accuracy import DEFAULT_MEMBERS, DEFAULT_MODEL, Member, choose_model, heldout_scenes
    from envs.model.defaults import DEFAULT_ELEMENT, DEFAULT_MODEL_N_TRIANGLES, DEFAULT_MODEL_RINGS

    assert (DEFAULT_MODEL.n_triangles, DEFAULT_MODEL.n_rings, DEFAULT_MODEL.element) == (
        DEFAULT_MODEL_N_TRIANGLES, DEFAULT_MODEL_RINGS, DEFAULT_ELEMENT)
    got = choose_model(list(heldout_scenes().values()), 0.04, rms_tolerance=0.02,
                       members=DEFAULT_MEMBERS)
    rows = {r.member: r for r in got.rows}
    assert got.member == DEFAULT_MODEL and got.within_tolerance
    coarse, fine = Member(32, 2, "calibrated", "nhquad"), Member(48, 3, "calibrated", "nhquad")
    assert rows[coarse].max_rel_error > 0.04 and rows[coarse].rms_rel_error < 0.02
    assert rows[DEFAULT_MODEL].max_rel_error < 0.04 and rows[DEFAULT_MODEL].rms_rel_error < 0.02
    assert rows[fine].within_tolerance
    assert rows[fine].max_rel_error < rows[DEFAULT_MODEL].max_rel_error
    for row in got.rows:
        if row.member.n_rings == 1:
            assert row.max_rel_error > 0.3  # the paper's fan at s = 1
        elif row.member.scales == "hybrid":
            assert row.max_rel_error > 0.1  # nu = 0.30 is far from the springs' own
    with pytest.raises(ValueError, match="rms_tolerance"):
        choose_model(Scene.preset("paper-r070"), 0.04, rms_tolerance=1.5, members=(coarse,))
    with pytest.raises(ValueError, match="scene"):
        choose_model([], 0.04, members=(coarse,))


def test_calibrated_cst_member_is_within_its_shipped_errors():
    """The shipped scale of a constant-strain member (fitted on the paper disks) reproduces its
    recorded fit on paper-r070, and the scale is physical (locking makes linear triangles a
    few percent too stiff: s slightly below 1)."""
    pytest.importorskip("skfem")
    from envs.accuracy import PAPER_TORQUES_NM, fem_reference
    from envs.model.family import CST_SCALES, cst_disk

    for scale, *_ in CST_SCALES.values():
        assert 0.85 < scale < 1.0
    scene = Scene.preset("paper-r070")
    ref = fem_reference(scene, PAPER_TORQUES_NM)
    # the shipped scale is applied by default; by hand (cst_disk) it must not be applied twice
    out = simulate_ramp(scene, list(ref.torques_nm), 32, n_rings=6, element="cst")
    model = Scene(scene.gripper, cst_disk(scene.disk, 32, 6))
    again = simulate_ramp(model, list(ref.torques_nm), 32, n_rings=6, element="cst",
                          calibrated=False)
    assert all(r.converged for r in out)
    assert out[0].model_scale == CST_SCALES[(32, 6)][0]
    assert [r.jaw_angles_rad for r in again] == [r.jaw_angles_rad for r in out]
    err = (scene.gripper.rest_angle_rad - np.array([np.mean(r.jaw_angles_rad) for r in out])) \
        / ref.closing_rad(scene) - 1
    # the fit's RMS over the three paper disks is 1.13 %; one disk may be a little off it
    assert np.sqrt(np.mean(err**2)) < 0.02
    with pytest.raises(ValueError, match="calibration"):
        cst_disk(scene.disk, 21, 3)


def test_family_members_accept_fine_contours_the_spring_fan_does_not():
    """N = 1000 is refused for the springs-only fan (it mostly fails there) and solved by the
    constant-strain mesh with 2 rings."""
    with pytest.raises(ValueError, match="500"):
        simulate(Scene.preset("paper-r070"), 0.2, 1000, element="spring")
    res = simulate(Scene.preset("paper-r070"), 0.2, 1000, n_rings=2, element="cst")
    assert res.converged, res.message
    with pytest.raises(ValueError, match="n_triangles"):
        simulate(Scene.preset("paper-r070"), 0.2, 2001, n_rings=2, element="cst")


def test_cli_solves_a_calibrated_ring_member(capsys):
    """``psm-grasp simulate --rings M --element cst --calibrated``: the member with its shipped
    scale, checked; a member without a shipped scale is refused before any solve."""
    from cli.main import main

    assert main(["simulate", "--triangles", "20", "--rings", "3", "--element", "cst",
                 "--calibrated", "--json"]) == 0
    out = capsys.readouterr().out
    assert '"n_rings": 3' in out and '"converged": true' in out
    assert main(["simulate", "--triangles", "21", "--rings", "3", "--element", "cst",
                 "--calibrated"]) != 0
    assert "no shipped calibration" in capsys.readouterr().err


def test_drawing_a_ring_grasp_shows_its_mesh():
    """The drawing of a ring member has every edge of its mesh, unstrained at rest and with the
    strains of the solved state otherwise (the largest equals the result's peak spring strain)."""
    from envs.render import mesh_segments

    scene = Scene.preset("paper-r070")
    res = simulate(scene, 0.2, 20, n_rings=3, element="cst")
    prm, x = _rest(20, 3, scene=scene)
    r, c = scene.disk.radius_m, scene.disk.center_m
    rest_pts = x[:40].reshape(-1, 2) * r + c
    rest_inner = x[42:].reshape(-1, 2) * r + c
    segs, strains = mesh_segments(rest_pts, rest_inner, c, r, 3)
    assert segs.shape == (3 * 3 * 20, 2, 2)
    assert np.abs(strains).max() < 1e-12
    _, strains = mesh_segments(res.points_m, res.interior_points_m, c, r, 3)
    assert np.abs(strains).max() == pytest.approx(res.peak_strain, rel=1e-9)


def test_an_nhquad_scale_far_from_its_fitted_n_warns():
    import warnings

    from envs.model.family import calibration_scale

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert calibration_scale(40, 2, "nhquad") == calibration_scale(56, 2, "nhquad")
    with pytest.warns(UserWarning, match="fitted at N = .*refine N and M together"):
        calibration_scale(200, 2, "nhquad")


def test_a_fine_ring_mesh_starts_from_its_coarse_solution_and_reaches_the_same_grasp(
        monkeypatch):
    """Nested iteration on a ring mesh: N = 200 (> NESTED_ABOVE) starts from the N = 80
    solution with every ring prolonged onto the coarse ring's chords. The start must already
    be close to the fine answer (a ring interpolated into the wrong place would not be), and
    the answer must be the one a solve from rest finds."""
    sim = importlib.import_module("envs.solver.simulate")
    scene, n, m = Scene.preset("paper-r070"), 200, 2
    starts = []
    solve = sim._Problem.solve

    def recording(self, x0=None, lam0=None):
        if self.n == n and x0 is not None:
            starts.append(np.array(x0))
        return solve(self, x0, lam0)

    monkeypatch.setattr(sim._Problem, "solve", recording)
    nested = simulate(scene, 0.2, n, n_rings=m, element="nhquad")
    assert nested.converged and len(starts) == 1
    monkeypatch.setattr(sim, "NESTED_ABOVE", 10 ** 6)
    direct = simulate(scene, 0.2, n, n_rings=m, element="nhquad")
    assert direct.converged and len(starts) == 1
    r, centre = scene.disk.radius_m, scene.disk.center_m
    answer = np.concatenate([((nested.points_m - centre) / r).ravel(),
                             ((nested.interior_points_m - centre) / r).ravel()])
    start = np.concatenate([starts[0][: 2 * n], starts[0][2 * n + 2:]])
    # the chords of an 80-gon sit r (1 - cos(pi / 80)) ~ 8e-4 r inside the circle
    assert np.max(np.abs(start - answer)) < 2e-3
    assert np.allclose(nested.points_m, direct.points_m, atol=1e-9 * r)
    assert np.allclose(nested.interior_points_m, direct.interior_points_m, atol=1e-9 * r)
    assert nested.jaw_angles_rad == pytest.approx(direct.jaw_angles_rad, abs=1e-10)


def test_the_coarsest_four_ring_disk_ramps_to_forty_percent_strain():
    # the stress grid's ramp (x1.25 steps from 0.02 N·m): at 5.675 N·m its warm-started step
    # failed, and so did the rest shape turned a quarter spacing; an eighth reaches the grasp
    torques = 0.02 * 1.25 ** np.arange(29)
    results = simulate_ramp(Scene.preset("paper-r100"), torques, 4, n_rings=4,
                            element="nhquad", until_peak_strain=0.40)
    assert all(r.converged and r.kkt.passed for r in results)
    assert all(r.inverted_triangles == 0 for r in results)
    assert results[-1].peak_strain >= 0.40


def test_a_fine_one_ring_fan_whose_turn_is_neutral_is_a_stable_grasp():
    # the stress grid's constant-strain one-ring fan at N = 2000 on paper-r070, 2.71 N·m: its
    # turn about the pin is neutral to round-off, and every polished answer was flagged unstable
    # until a mode softer than NEUTRAL of the stiffness counted as neutral (1227 iterations and
    # a failure before; 53 now)
    scene = Scene.preset("paper-r070")
    fine = simulate(scene, 2.7105, 2000, n_rings=1, element="cst")
    assert fine.converged and fine.stable and fine.kkt.passed
    assert fine.iterations < 300
    # a mirror-symmetric squeeze: the jaws close alike, and N = 1000 gives the same grasp
    assert abs(fine.jaw_angles_rad[0] - fine.jaw_angles_rad[1]) < 1e-9
    half = simulate(scene, 2.7105, 1000, n_rings=1, element="cst")
    assert half.converged and half.stable
    assert abs(half.jaw_angles_rad[0] - fine.jaw_angles_rad[0]) < 1e-5
    assert abs(half.peak_strain - fine.peak_strain) < 1e-3 * fine.peak_strain


@pytest.mark.parametrize("poisson_ratio", [0.45, 0.30])
def test_nhquad_members_converge_to_the_fem_under_refinement(poisson_ratio):
    """Convergence rate in the style of scikit-fem's tests: the uncalibrated nh-quad member
    (the disk's own E and nu, no fitted scale) refined in N and M together, against the FEM
    (P2, r / 12) at three torques. Measured: nu = 0.45 4.7 / 2.3 / 0.63 / 0.14 % RMS, nu = 0.30
    5.0 / 2.7 / 0.80 / 0.26 % (rates 1.7 and 1.4)."""
    from envs.accuracy.reference import fem_reference

    scene = Scene.preset("paper-r070").with_changes(poisson_ratio=poisson_ratio)
    ref = fem_reference(scene, [0.1, 0.25, 0.5])
    assert len(ref.torques_nm) == 3  # every FEM point converged
    th0 = scene.gripper.rest_angle_rad
    ns = np.array([16, 32, 64, 128])
    rms = []
    for n in ns:
        rel = []
        for torque, th_fem in zip(ref.torques_nm, ref.jaw_angles_rad, strict=True):
            r = simulate(scene, float(torque), int(n), n_rings=int(n) // 8, element="nhquad",
                         calibrated=False)
            assert r.converged, r.message
            rel.append((np.mean(r.jaw_angles_rad) - th_fem) / (th0 - th_fem))
        rms.append(math.sqrt(np.mean(np.square(rel))))
    rms = np.array(rms)
    rate = -np.polyfit(np.log(ns), np.log(rms), 1)[0]
    assert rate > 1.2, (rms, rate)
    assert rms[-1] < 0.005, rms  # within 0.5 % of the FEM closing angle, with no fit
    assert rms[-1] < rms[0] / 10, rms


@pytest.mark.parametrize("bw", [1, 2, 5, 11, 17])
def test_scalar_banded_cholesky_matches_the_dense_factor(bw):
    """The ring meshes' banded Cholesky (two partial sums per dot product) against numpy's
    dense factor, every parity of the dot products' lengths included; an indefinite matrix
    is refused."""
    from envs.solver.banded import _chol_general

    rng = np.random.default_rng(bw)
    nb = 4 * bw + 7
    full = np.zeros((nb, nb))
    for d in range(1, bw + 1):
        off = rng.standard_normal(nb - d)
        full += np.diag(off, -d) + np.diag(off, d)
    full += np.eye(nb) * (2.0 * bw + 1.0)
    ab = np.zeros((nb, bw + 1))
    for j in range(nb):
        for d in range(min(j, bw) + 1):
            ab[j, d] = full[j, j - d]
    shift = 0.25
    lb = np.zeros_like(ab)
    assert _chol_general(ab, lb, nb, shift)
    want = np.linalg.cholesky(full + shift * np.eye(nb))
    got = np.zeros((nb, nb))
    for j in range(nb):
        got[j, j] = 1.0 / lb[j, bw]  # the diagonal is kept as its reciprocal
        for k in range(max(0, j - bw), j):
            got[j, k] = lb[j, bw - j + k]
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    ab[nb // 2, 0] = -10.0 * nb  # one diagonal entry made hugely negative
    assert not _chol_general(ab, np.zeros_like(ab), nb, shift)
