"""Shaped jaws in the finite-element reference: the grooved finger's gap (the shared kernel
``envs.model.jaw.jaw_gap``) chained to rim nodes and finger angles, the groove's mouth corners,
conforming contact measures and the statics of grooved grasps (meshes of r / 12: under a
second a grasp)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

from envs import fem
from envs.fem import contact as fem_contact
from envs.fem import grasp as fem_grasp_module
from envs.fem.loaded import fem_holding
from envs.model.contact_width import (
    FLAT_FACE_CURVATURE_PER_M,
    hertz_arc_coefficient,
    relative_radius_m,
    segment_hertz_cap,
)
from envs.model.geometry import closed_angle_rad, finger_frame
from envs.model.holding import H_MU, NO_PATCH, hertz_half_width
from envs.model.jaw import STRAIGHT, JawProfile
from envs.model.loads import holding_row
from envs.scene import Scene
from tests.test_fem import solve_spied

R070 = Scene.preset("paper-r070")
RINGS = 12
DEPTH_M = 0.0075  # the deepest groove the 10 mm fingers allow (3/4 of the width)
VEE_OPENING_RAD = math.radians(150.0)


def _seated(scene: Scene, make_jaw, centre_height_m: float) -> tuple[Scene, float]:
    """The scene with both fingers grooved by ``make_jaw(position_m)`` placed so that the disk
    centre lies on the groove's centre line ``centre_height_m`` above the face when it first
    touches; returns it and the actuation torque that closes the fingers to that angle."""
    grip, disk = scene.gripper, scene.disk
    hw, centre = grip.finger_width_m / 2, disk.center_m

    def across(theta: float) -> float:
        joint, _, normal = finger_frame(grip, 0, theta)
        return float(normal @ (centre - joint))

    theta = brentq(lambda t: across(t) - (hw + centre_height_m), 0.0, grip.rest_angle_rad)
    joint, axis, _ = finger_frame(grip, 0, theta)
    jaw = make_jaw(float(axis @ (centre - joint)))
    onset = grip.torsion_stiffness_nm_per_rad * (grip.rest_angle_rad - theta)
    return replace(scene, gripper=replace(grip, jaw=jaw)), onset


def _cradle_scene():
    # a cradle of the disk's own radius, seated: its arc's centre on the disk's centre
    r = R070.disk.radius_m
    return _seated(R070, lambda a: JawProfile.cradle(r, DEPTH_M, a), r - DEPTH_M)


def _vee_scene():
    # a 150 deg V in which the disk touches both flanks (inside the mouth) at first contact
    r, half = R070.disk.radius_m, VEE_OPENING_RAD / 2
    return _seated(R070, lambda a: JawProfile.vee(VEE_OPENING_RAD, DEPTH_M, a),
                   r / math.sin(half) - DEPTH_M)


def _small_cradle_scene():
    # a cradle of half the disk's radius: the disk rests on its two rounded mouth edges
    r = R070.disk.radius_m
    mouth = JawProfile.cradle(0.5 * r, DEPTH_M, 0.1).mouth_half_width_m
    return _seated(R070, lambda a: JawProfile.cradle(0.5 * r, DEPTH_M, a),
                   math.sqrt(r * r - mouth * mouth))


def _solve(scene: Scene, torques, rings: int = RINGS):
    """FEM grasp (no cache) on ``rings`` rings and the system and state of its last Newton
    solve."""
    return solve_spied(scene, torques, scene.disk.radius_m / rings)


@pytest.fixture(scope="module")
def cradle():
    scene, onset = _cradle_scene()
    return (scene, onset) + _solve(scene, [1.02 * onset])


@pytest.fixture(scope="module")
def vee():
    scene, onset = _vee_scene()
    return (scene, onset) + _solve(scene, [5.0 * onset])


@pytest.fixture(scope="module")
def small_cradle():
    scene, onset = _small_cradle_scene()
    return (scene, onset) + _solve(scene, [5.0 * onset])


def _finger_contacts(system, x, load, side: int):
    """The contacts of one finger on the disk: normals, points, forces (rim nodes on the jaw,
    then the finger's loaded corners), from the system's contact list split by finger."""
    normals, points, forces, _, _ = system.contact_list(x, load)
    right = points[:, 0] > 0.0
    pick = right if side == 0 else ~right
    return normals[pick], points[pick], forces[pick]


def _hub_reaction(system, x) -> np.ndarray:
    """The rigid hub's force on the disk from the elastic forces at the fixed nodes (the
    gradient of the elastic energy there), independent of the contact list."""
    n = system.n
    _, g_el = system.body.energy_gradient(x[:n])
    fixed = np.setdiff1d(np.arange(n), system.free)
    basis = system.body.basis
    is_x = np.zeros(n, dtype=bool)
    is_y = np.zeros(n, dtype=bool)
    for dofs in (basis.nodal_dofs, basis.facet_dofs, basis.interior_dofs):
        if dofs.size:  # (2 components, entities)
            is_x[dofs[0]] = True
            is_y[dofs[1]] = True
    assert np.all(is_x ^ is_y)
    return np.array([g_el[fixed[is_x[fixed]]].sum(), g_el[fixed[is_y[fixed]]].sum()])


def _check_statics(scene: Scene, result, system, x, load) -> None:
    """Each finger's moment balance about its joint and the disk's force balance with the hub."""
    grip = scene.gripper
    for side in (0, 1):
        normals, points, forces = _finger_contacts(system, x, load, side)
        theta = result.jaw_angles_rad[side]
        joint, axis, normal = finger_frame(grip, side, theta)
        # the finger turns about its joint with d e / d theta = -n: rate omega (z) per radian
        omega = axis[0] * -normal[1] - axis[1] * -normal[0]
        on_finger = -forces[:, None] * normals
        rel = points - joint
        moment = float(np.sum(rel[:, 0] * on_finger[:, 1] - rel[:, 1] * on_finger[:, 0]))
        drive = load - grip.torsion_stiffness_nm_per_rad * (grip.rest_angle_rad - theta)
        assert omega * moment == pytest.approx(drive, rel=1e-6)
    _, _, _, net, _ = system.contact_list(x, load)
    np.testing.assert_allclose(_hub_reaction(system, x), -net, rtol=1e-6,
                               atol=1e-9 * np.abs(net).max())
    np.testing.assert_allclose(result.pin_force_n, -net, rtol=1e-9, atol=1e-12)


# ------------------------------------------------------------------------ the gap and its chain


def _points_near_groove(scene: Scene, side: int, theta: float, count: int, rng) -> np.ndarray:
    grip, jaw = scene.gripper, scene.gripper.jaws[side]
    joint, axis, normal = finger_frame(grip, side, theta)
    half = max(jaw.mouth_half_width_m, 0.01)
    s = jaw.position_m + rng.uniform(-1.5, 1.5, count) * half
    m = grip.finger_width_m / 2 + rng.uniform(-1.2 * jaw.depth_m - 1e-3, 3e-3, count)
    return joint + s[:, None] * axis + m[:, None] * normal


@pytest.mark.parametrize("make", [
    lambda a: JawProfile.cradle(0.07, DEPTH_M, a),
    lambda a: JawProfile.vee(VEE_OPENING_RAD, DEPTH_M, a),
    lambda a: JawProfile(DEPTH_M, 0.02, math.radians(100.0), a),
    lambda a: JawProfile.cradle(0.035, DEPTH_M, a),
], ids=["cradle", "vee", "rounded-vee", "small-cradle"])
@pytest.mark.parametrize("side", [0, 1])
def test_jaw_solid_gap_derivatives_match_finite_differences(make, side):
    """The grooved obstacle's normal (dg/dp) is a unit vector and, with dg/dq and the second
    derivatives, the finite differences of the gap, at points around the groove (outside, on
    the rounded edges, inside the solid)."""
    scene = replace(R070, gripper=replace(R070.gripper, jaw=make(0.08)))
    ob = fem_contact.jaw_obstacle(scene, side, side)
    assert isinstance(ob, fem_contact._JawSolid)
    theta = 0.6
    p = _points_near_groove(scene, side, theta, 400, np.random.default_rng(side))
    g, valid, dgdp, dgdq, d2q, d2pq, d2pp = ob.evaluate(p, theta)
    assert np.all(valid)
    np.testing.assert_allclose(np.linalg.norm(dgdp, axis=1), 1.0, rtol=1e-12)
    h = 1e-7
    # central differences where the gap is smooth over the stencil (away from its medial
    # axis, where the nearest surface point jumps): the one-sided differences agree there
    smooth = np.ones(p.shape[0], dtype=bool)
    fd_p = np.empty_like(dgdp)
    fd_pp = np.empty_like(d2pp)
    for k in range(2):
        dp = np.zeros(2)
        dp[k] = h
        gp, _, np_, *_ = ob.evaluate(p + dp, theta)
        gm, _, nm, *_ = ob.evaluate(p - dp, theta)
        fd_p[:, k] = (gp - gm) / (2 * h)
        fd_pp[:, :, k] = (np_ - nm) / (2 * h)
        smooth &= np.abs((gp - g) - (g - gm)) < 1e-3 * h
        smooth &= np.all(np.abs(np_ - nm) < 1e-2, axis=1)
    gp, _, np_, dqp, *_ = ob.evaluate(p, theta + h)
    gm, _, nm, dqm, *_ = ob.evaluate(p, theta - h)
    smooth &= np.abs((gp - g) - (g - gm)) < 1e-3 * h
    assert np.count_nonzero(smooth) >= 0.8 * p.shape[0]
    s = smooth
    np.testing.assert_allclose(fd_p[s], dgdp[s], atol=1e-6)
    np.testing.assert_allclose(((gp - gm) / (2 * h))[s], dgdq[s], atol=1e-6 * 0.2)
    np.testing.assert_allclose(((dqp - dqm) / (2 * h))[s], d2q[s], atol=1e-5 * 0.2)
    np.testing.assert_allclose(((np_ - nm) / (2 * h))[s], d2pq[s], atol=1e-4)
    scale = 1.0 / min(make(0.08).bottom_radius_m or 1.0, 1.0)
    np.testing.assert_allclose(fd_pp[s], d2pp[s], atol=1e-3 * scale)


def test_depth_zero_solid_is_the_flat_face():
    """A groove of depth 0 is the straight bar: the solid's gap at nodes along the face equals
    the flat face's (outside, touching, penetrating), normal and derivatives included."""
    grip = R070.gripper
    theta = 0.62
    rng = np.random.default_rng(5)
    for side in (0, 1):
        joint, axis, normal = finger_frame(grip, side, theta)
        s = rng.uniform(0.0, grip.finger_length_m, 300)
        m = grip.finger_width_m / 2 + rng.uniform(-2e-3, 5e-3, 300)
        p = joint + s[:, None] * axis + m[:, None] * normal
        flat = fem_contact._JawFace(R070, side, side).evaluate(p, theta)
        solid = fem_contact._JawSolid(R070, side, side, STRAIGHT).evaluate(p, theta)
        for a, b in zip(flat[:6], solid[:6], strict=True):
            np.testing.assert_allclose(np.asarray(b, dtype=float), np.asarray(a, dtype=float),
                                       rtol=0, atol=1e-15)
        np.testing.assert_array_equal(solid[6], 0.0)  # no curvature


def test_straight_grasp_answers_are_unchanged(monkeypatch):
    """Depth 0 gives the FEM answers of the straight finger: the values pinned from the
    flat-face solver (paper-r070, mesh r / 6, T_a = 0.2 N·m), and the same grasp solved with
    every finger as a grooved solid of depth 0 (the kernel's straight bar)."""
    scene = replace(R070, gripper=replace(R070.gripper, jaw=JawProfile(0.0, 0.01, 0.5, 0.1)))
    (plain,), *_ = _solve(scene, [0.2], rings=6)
    assert plain.jaw_angles_rad[0] == pytest.approx(PINNED_R070_T02["jaw_angle_rad"], rel=1e-12)
    assert plain.contact_forces_n[0] == pytest.approx(PINNED_R070_T02["force_n"], rel=1e-9)
    assert plain.contact_fractions[0] == pytest.approx(PINNED_R070_T02["fraction"], rel=1e-9)
    monkeypatch.setattr(fem_grasp_module, "jaw_obstacle", lambda sc, side, qi:
                        fem_contact._JawSolid(sc, side, qi, STRAIGHT))
    (solid,), *_ = _solve(scene, [0.2], rings=6)
    np.testing.assert_allclose(solid.jaw_angles_rad, plain.jaw_angles_rad, rtol=1e-9)
    np.testing.assert_allclose(solid.contact_forces_n, plain.contact_forces_n, rtol=1e-6)
    np.testing.assert_allclose(solid.contact_fractions, plain.contact_fractions, rtol=1e-6)
    np.testing.assert_allclose(solid.contact_shares, plain.contact_shares, rtol=1e-6)


# the straight finger's answers before grooves existed (flat-face solver, see the test above)
PINNED_R070_T02 = {"jaw_angle_rad": 0.6601656258758632, "force_n": 3.7937334633800717,
                   "fraction": 0.07752781273767856}


def _contact_gradient_tangent(system, x, load):
    """The contact part of the system's gradient and tangent (elastic terms left out)."""
    _, grad, (rows, cols, vals), _, _ = system._contact(x, load, True)
    nt = system.ntot
    if not vals:
        return grad, sp.csr_matrix((nt, nt))
    return grad, sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                       np.concatenate(cols))), shape=(nt, nt))


@pytest.mark.parametrize("case", ["cradle", "vee", "small_cradle"])
def test_grooved_contact_tangent_matches_finite_differences(case, request):
    """The contact tangent of grooved jaws (nodes on the curved solid, the mouth corners, the
    finger angles) is the derivative of the contact forces."""
    _scene, _onset, _results, system, x, load = request.getfixturevalue(case)
    grad, k = _contact_gradient_tangent(system, x, load)
    rng = np.random.default_rng(3)
    d = np.zeros_like(x)
    d[system.free] = 1e-3 * rng.standard_normal(system.free.size)
    d[-2:] = [1.0, 0.7]
    step = 1e-8
    fd = (_contact_gradient_tangent(system, x + step * d, load)[0]
          - _contact_gradient_tangent(system, x - step * d, load)[0]) / (2 * step)
    assert np.abs(fd - k @ d).max() <= 1e-7 * np.abs(k @ d).max()


def test_cradle_tangent_carries_the_jaws_curvature(cradle):
    """Sliding the pressed nodes along the cradle's arc turns their forces with its normal: the
    tangent's curvature term ``-f d2g/dp2``, alone when the nodes move along the surface."""
    _scene, _onset, _results, system, x, load = cradle
    forces = system.contact_forces(x, load)[0][0]
    pressed = np.flatnonzero(forces > 0)
    _, _, dgdp, *_ = system.obstacles[0].evaluate(system.rim_positions(x), x[system.n])
    d = np.zeros_like(x)
    tangent = np.column_stack((-dgdp[pressed, 1], dgdp[pressed, 0]))
    d[system.rim.dofs[pressed]] = tangent
    grad, k = _contact_gradient_tangent(system, x, load)
    # a step of 10 nm: the gap's round-off (1e-17 m on a 0.07 m arc) stays far below the
    # curvature's change of the normal
    step = 1e-8
    fd = (_contact_gradient_tangent(system, x + step * d, load)[0]
          - _contact_gradient_tangent(system, x - step * d, load)[0]) / (2 * step)
    kd = k @ d
    assert np.abs(kd).max() > 0.0
    np.testing.assert_allclose(fd, kd, rtol=0, atol=1e-2 * np.abs(kd).max())


# --------------------------------------------------------------------------------- the grasps


def test_fitted_cradle_touches_along_its_arc_at_a_small_torque(cradle):
    """A cradle of the disk's radius closing on the undeformed disk touches along its whole
    arc as soon as it presses (conforming contact: no Hertz cap), its force spread along it."""
    scene, onset, (res,), system, x, load = cradle
    disk, jaw = scene.disk, scene.gripper.jaw
    assert res.converged
    arc = 2 * math.asin(jaw.mouth_half_width_m / disk.radius_m) / (2 * math.pi)
    spacing = 1.0 / system.rim.dofs.shape[0]
    for side in (0, 1):
        assert res.contact_shares[side] == res.contact_fractions[side]  # not capped
        assert abs(res.contact_shares[side] - arc) <= 1.5 * spacing
        flat_cap = hertz_arc_coefficient(
            disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa, disk.poisson_ratio,
            relative_radius_m(disk.radius_m, FLAT_FACE_CURVATURE_PER_M)) * math.sqrt(
                res.contact_forces_n[side])
        assert flat_cap < 0.5 * arc  # a flat face's width at this force: far less
    forces = system.contact_forces(x, load)[0][0]
    pressed = np.flatnonzero(forces > 0)
    pos = system.rim_positions(x)[pressed] - disk.center_m
    ang = np.arctan2(pos[:, 1], pos[:, 0])
    assert np.ptp(ang) / (2 * math.pi) >= arc - 2 * spacing
    pressure = forces[pressed] / system.rim.weight_m2[pressed]
    # the finger turns about its joint, so the pressure grows along the arc, but every node
    # inside the contact's edges carries a fair part of it
    inner = np.argsort(ang)[2:-2]
    assert pressure[inner].min() > 0.2 * pressure[inner].max()


def test_a_cradle_s_arc_of_rim_nodes_is_one_pressure_patch(cradle):
    """The FEM's contact list labels each finger's run of loaded rim nodes on the cradle as
    one pressure patch (the rule the point-spring model applies to its contour points), the
    two fingers' runs apart, and the holding row is the one of those labels (the freed disk's
    loaded grasp, :func:`envs.fem.loaded.fem_holding`); the normal forces as solved (the
    bound) need more."""
    scene, onset, (res,), system, x, load = cradle
    normals, points, forces, net, moment, patches = system.contact_list(
        x, load, with_patches=True)
    right = points[:, 0] > scene.disk.center_m[0]
    for side in (right, ~right):
        labels = np.unique(patches[side])
        assert labels.size == 1 and labels[0] != NO_PATCH
        assert np.sum(side) >= 5  # a conforming arc: many nodes, one patch
    assert patches[right][0] != patches[~right][0]
    disk = scene.disk
    centre = np.asarray(disk.center_m, dtype=float)
    moment_c = moment - (centre[0] * net[1] - centre[1] * net[0])
    half = hertz_half_width(disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa,
                            disk.poisson_ratio)
    grip = scene.gripper
    locked = tuple(bool(q < closed_angle_rad(grip)) for q in x[system.n:])
    row = fem_holding(system, system.body, system.rim, x, load, centre, disk.radius_m,
                      grip.joint_offset_m, grip.torsion_stiffness_nm_per_rad, locked, 0.0, "any",
                      half, disk.youngs_modulus_pa * disk.thickness_m * disk.radius_m)
    assert res.required_friction == pytest.approx(row[H_MU], rel=1e-9, abs=1e-12)
    bound = holding_row(normals, points, forces, centre, disk.radius_m, -net, -moment_c, 0.0,
                        half, patches)
    assert row[H_MU] < bound[H_MU]


def test_fitted_cradle_is_not_capped_when_pressed_hard():
    """Pressed hard, the fitted cradle's disk also presses the cradle's rounded mouth edges and
    the face beyond: still one conforming contact, its share its extent (the edges' nodes do
    not make the cradle's curvature look flatter), at least the arc."""
    scene, onset = _cradle_scene()
    disk, jaw = scene.disk, scene.gripper.jaw
    arc = 2 * math.asin(jaw.mouth_half_width_m / disk.radius_m) / (2 * math.pi)
    results, system, *_ = _solve(scene, [20.0 * onset, 60.0 * onset])
    spacing = 1.0 / system.rim.dofs.shape[0]
    for res in results:
        assert res.converged
        assert res.contact_shares == res.contact_fractions
        assert res.contact_shares[0] > arc - 2 * spacing


def test_vee_flanks_both_carry_forces_in_statics(vee):
    """A V-groove holds the disk on both flanks, each node's force along its flank's normal;
    each finger's moment balance about its joint and the disk's force balance with the hub
    hold; each flank's contact is capped by its own force."""
    scene, onset, (res,), system, x, load = vee
    disk, grip = scene.disk, scene.gripper
    half = VEE_OPENING_RAD / 2
    assert res.converged and res.tip_forces_n == (0.0, 0.0)
    _check_statics(scene, res, system, x, load)
    k = hertz_arc_coefficient(disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa,
                              disk.poisson_ratio, disk.radius_m)
    for side in (0, 1):
        normals, points, forces = _finger_contacts(system, x, load, side)
        _, axis, normal = finger_frame(grip, side, res.jaw_angles_rad[side])
        along = normals @ axis
        for flank in (-1.0, 1.0):
            on = np.sign(along) == flank
            # the flank's normal: (-+cos(phi/2), sin(phi/2)) in (s, m) on either side
            np.testing.assert_allclose(along[on], flank * math.cos(half), atol=1e-9)
            np.testing.assert_allclose(normals[on] @ normal, math.sin(half), atol=1e-9)
            assert np.count_nonzero(on) >= 2 and forces[on].sum() > 0.1 * forces.sum()
        f_lo = forces[along < 0].sum()
        f_hi = forces[along > 0].sum()
        # two flat contacts: capped by k sqrt(F1) + k sqrt(F2), more than one face's cap
        assert res.contact_shares[side] <= k * (math.sqrt(f_lo) + math.sqrt(f_hi)) + 1e-12
        assert res.contact_shares[side] <= res.contact_fractions[side]


def test_small_cradle_rests_on_its_mouth_corners(small_cradle):
    """A cradle narrower than the disk holds it on its two rounded mouth edges: the mouth
    corners carry force, symmetric fingers, statics hold."""
    scene, onset, (res,), system, x, load = small_cradle
    assert res.converged
    _check_statics(scene, res, system, x, load)
    _, corner_forces = system.contact_forces(x, load)
    mouths = [(c, f) for c, f in zip(system.corners, corner_forces, strict=True)
              if c.radius_m > 0.0]
    assert len(mouths) == 4
    assert all(f > 0.0 for _, f in mouths)
    np.testing.assert_allclose(res.jaw_angles_rad[0], res.jaw_angles_rad[1], rtol=1e-9)
    np.testing.assert_allclose(res.contact_forces_n[0], res.contact_forces_n[1], rtol=1e-6)
    # the disk does not reach the cradle's arc: every contact is near a mouth edge
    grip = scene.gripper
    for side in (0, 1):
        _, points, _ = _finger_contacts(system, x, load, side)
        joint, axis, _ = finger_frame(grip, side, res.jaw_angles_rad[side])
        u = (points - joint) @ axis - grip.jaws[side].position_m
        mouth = grip.jaws[side].mouth_half_width_m
        assert np.all(np.abs(np.abs(u) - mouth) < 0.2 * mouth)


def test_segment_hertz_cap_follows_the_jaws_curvature():
    """Flat face: Hertz's width of the disk's radius; a cradle of radius 2 r: relative radius
    2 r (sqrt 2 wider); a cradle that fits or wraps the disk: no cap; no force: nothing."""
    r, t, e, nu = 0.05, 0.01, 1e5, 0.45
    force = 0.3
    flat = segment_hertz_cap(force, 0.0, r, t, e, nu)
    assert flat == pytest.approx(hertz_arc_coefficient(r, t, e, nu, r) * math.sqrt(force))
    es = e / (1 - nu * nu)
    assert flat == pytest.approx(math.sqrt(4 * force * r / (math.pi * es * t)) / (math.pi * r))
    assert segment_hertz_cap(force, 1 / (2 * r), r, t, e, nu) == pytest.approx(
        math.sqrt(2) * flat)
    assert math.isinf(segment_hertz_cap(force, 1 / r, r, t, e, nu))
    assert math.isinf(segment_hertz_cap(force, 2 / r, r, t, e, nu))
    assert segment_hertz_cap(0.0, 0.0, r, t, e, nu) == 0.0


def test_fem_fidelity_scenes_carry_the_rows_jaws():
    """The FEM fidelity of the design evaluator grasps with each row's jaw profiles (a design
    row's jaw columns, right and left), straight where there are none."""
    from envs.scene import Design

    scene, _ = _vee_scene()
    left = JawProfile.cradle(0.05, DEPTH_M, 0.09)
    scene = replace(scene, gripper=replace(scene.gripper, left_jaw=left))
    grooved = Design.from_scene(scene, 0.1).to_array(14)
    straight = Design.from_scene(R070, 0.1).to_array()
    assert Design.from_array(grooved).to_scene(R070.disk).gripper.jaws == (
        scene.gripper.jaw, left)
    assert Design.from_array(straight).to_scene(R070.disk).gripper.jaws == (STRAIGHT, STRAIGHT)


def test_rounded_corner_presses_both_segments_of_a_notch_smoothly():
    """A rounded corner in a notch of the rim (the rim wrapped around a groove's edge) presses
    both segments at once; its penalty energy is smooth as it slides across the node, where
    the nearest segment alone would switch (a kink in the energy's slope)."""
    from envs.fem.system import _corner_terms

    # counter-clockwise, a notch (reflex vertex) at (1, 1.8) in the top edge
    poly = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 1.8], [0.0, 2.0]])
    radius = 0.1

    def energy(cx, all_terms=True):
        c = np.array([cx, 1.85])
        terms = _corner_terms(poly, c, radius) if all_terms else [
            min(_corner_terms(poly, c, radius), key=lambda t: t[0] + radius)]
        return sum(0.5 * min(gap, 0.0) ** 2 for gap, *_ in terms)

    terms = _corner_terms(poly, np.array([1.0, 1.85]), radius)
    assert sorted(kind for _, kind, *_ in terms) == ["segment", "segment"]
    h, d = 1e-7, 1e-4
    slope = [(energy(x + h) - energy(x - h)) / (2 * h) for x in (1.0 - d, 1.0 + d)]
    near = [(energy(x + h, False) - energy(x - h, False)) / (2 * h) for x in (1.0 - d, 1.0 + d)]
    assert abs(slope[1] - slope[0]) < 1e-3 * abs(near[1] - near[0])
    # a sharp corner keeps its one signed term (the tips)
    assert len(_corner_terms(poly, np.array([1.0, 1.85]), 0.0)) == 1


def test_grooved_results_round_trip_the_cache(tmp_path, monkeypatch):
    """A grooved grasp is cached under its own key (the jaws are inputs) with its capped
    shares; a result cached before the shares were stored reads them as NaN."""
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    scene, onset = _cradle_scene()
    h = scene.disk.radius_m / 6
    (first,) = fem.fem_grasp(scene, [2.0 * onset], mesh_size_m=h)
    (again,) = fem.fem_grasp(scene, [2.0 * onset], mesh_size_m=h)
    assert again.from_cache and not first.from_cache and again == first
    assert np.all(np.isfinite(again.contact_shares))
    (straight,) = fem.fem_grasp(R070, [2.0 * onset], mesh_size_m=h)
    assert not straight.from_cache  # another key
    old = first.to_json()
    del old["contact_shares"]
    assert np.all(np.isnan(fem.FemResult.from_json(old).contact_shares))


# a disk wedged into a groove narrower than itself: the water-like disk's shaped optimum
# (examples/objects/water_disk.toml, found by scripts/jaw_comparison.py), a rounded V whose
# bottom arc (66.5 mm) is 5 % smaller than the disk (70 mm), 21 mm deep, opening 112 deg
WEDGED_DESIGN = (0.3140254232308895, 0.9377450016710519, 0.03893766180380683,
                 0.027972911086744167, 1.1156386356639794, 0.051195053341855826,
                 0.020979544355708094, 0.0664959234145449, 1.9540592856308905,
                 0.11209813395736047)


def test_a_disk_wedged_into_a_narrower_groove_scores_it_mouth_to_mouth_at_both_fidelities():
    """Squeezed into a rounded V whose bottom arc is smaller than the disk, the disk presses
    both flanks and the arc as one conforming patch that ends at the groove's mouth edges: at
    both fidelities (the FEM's r / 12 rim, the 96 x 6 point-spring member) each face's share
    is the arc the mouth spans, seen from the disk's centre at the solved jaw angle, within
    three of the fidelity's spacings (the rim pressed in under the rounded mouth edges, and
    half a spacing off at each edge, :func:`envs.model.contact_width.run_share`), and the two
    fidelities' shares agree within 3 %. A flat face's Hertz width at the face's force is far
    narrower (and the width on the run's mean curvature, the flanks carrying two fifths of the
    force, a quarter narrower): the run is no Hertz contact, and its extent stands."""
    from envs.model.defaults import PAPER_TORSION_STIFFNESS_NM_PER_RAD
    from envs.object_file import load_object
    from envs.scene import Design
    from envs.solver.simulate import simulate
    from tests.test_jaw_solver import _face_share

    disk = load_object(Path(__file__).resolve().parents[1] / "examples" / "objects"
                       / "water_disk.toml").disk
    design = Design.from_array(np.array(WEDGED_DESIGN))
    scene = design.to_scene(disk, PAPER_TORSION_STIFFNESS_NM_PER_RAD)
    grip, r = scene.gripper, disk.radius_m
    centre = np.asarray(scene.disk.center_m, dtype=float)  # (placed by the design)

    def mouth_arc(side: int, angle_rad: float) -> float:
        joint, axis, normal = finger_frame(grip, side, angle_rad)
        jaw = grip.jaws[side]
        ends = [joint + (jaw.position_m + s * jaw.mouth_half_width_m) * axis
                + 0.5 * grip.finger_width_m * normal - centre for s in (-1.0, 1.0)]
        turn = math.atan2(ends[0][0] * ends[1][1] - ends[0][1] * ends[1][0],
                          float(ends[0] @ ends[1]))
        return abs(turn) / (2 * math.pi)

    (res,), system, _, _ = _solve(scene, [design.torque_nm])
    assert res.converged
    fem_spacing = 1.0 / system.rim.dofs.shape[0]
    psm = simulate(scene, design.torque_nm, n_triangles=96, n_rings=6)
    assert psm.converged, psm.message
    for side in (0, 1):
        arc = mouth_arc(side, res.jaw_angles_rad[side])
        assert 0.25 < arc < 0.28
        fem_share = res.contact_shares[side]
        assert abs(fem_share - arc) <= 3 * fem_spacing, (fem_share, arc)
        assert fem_share >= res.contact_fractions[side] - fem_spacing
        psm_share = _face_share(scene, psm, side)
        assert abs(psm_share - mouth_arc(side, psm.jaw_angles_rad[side])) <= 3.0 / 96
        assert psm_share == pytest.approx(fem_share, rel=0.03)
        flat = segment_hertz_cap(res.contact_forces_n[side], FLAT_FACE_CURVATURE_PER_M, r,
                                 disk.thickness_m, disk.youngs_modulus_pa, disk.poisson_ratio)
        assert flat < 0.6 * arc
