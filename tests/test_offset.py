"""An object placed off the gripper's axis: its centre displaced across the axis by ``x_c`` and
held there (``SoftDisk.offset_x_m``, ``evaluate_designs(offsets_x_m=...)``), at both fidelities.

Physics checked: the rest clearance moves by ``x_c cos(theta_a0)`` (the face normal's share of
the displacement), the mirrored placement gives the mirrored grasp, a displaced grasp passes the
independent check and no other, the fixed centre's reaction is taken about the true centre, and
the point-spring model agrees with the FEM off the axis as on it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from matplotlib.patches import Circle

from envs import DesignBounds, Scene, evaluate_designs, simulate, simulate_ramp
from envs.check import check_grasp
from envs.evaluate import finger_gaps_m
from envs.model.family import resolve_model
from envs.model.geometry import distance_to_finger_bar
from envs.model.holding import hertz_half_width
from envs.model.layout import S_OFFSET_X, S_RADIUS, S_SCALE, S_THICKNESS, S_YOUNG
from envs.model.problem import REST_OFFSET, REST_OK, REST_OVERLAP, pack_params, rest_codes
from envs.scene import DESIGN_FIELDS, Design, SoftDisk
from envs.solver.pipeline import solve_columns
from envs.solver.reaction import loaded_contacts
from tests.kkt_reference import kkt_check
from tests.test_holding import _lp_friction

R070 = Scene.preset("paper-r070")
DISK = R070.disk
FAN = {"element": "spring"}


def _face_clearance_m(scene: Scene) -> float:
    """Rest clearance of the centred disk to the right gripping face along its normal [m],
    from the conventions: ``n . (C - J) - w / 2 - r`` with ``n = (-cos theta_a0, sin
    theta_a0)``."""
    g, d = scene.gripper, scene.disk
    th = g.rest_angle_rad
    return (-math.cos(th) * (0.0 - g.joint_offset_m) + math.sin(th) * (d.distance_m + d.radius_m)
            - g.finger_width_m / 2 - d.radius_m)


def _inputs(scene, res):
    """The arguments of a check for a solver result."""
    return [scene, res.torque_nm, res.n_triangles, res.stiffness_rule, res.points_m.copy(),
            tuple(res.jaw_angles_rad), res.contact_forces_n.copy(),
            res.corner_edge_forces_n.copy(), res.stop_torques_nm.copy()]


def _random_placements(seed: int, size: int, fraction: float = 0.15):
    """Random designs of the default box on paper-r070 and random offsets within
    ``+-fraction r``."""
    rng = np.random.default_rng(seed)
    designs = DesignBounds().sample(rng, size, DISK)
    return designs, rng.uniform(-fraction, fraction, size) * DISK.radius_m


# ---------------------------------------------------------------------------------------------
# at rest


def test_a_displacement_uses_up_the_rest_clearance_at_cos_theta():
    """Displaced towards a finger by x_c, the disk comes x_c cos(theta_a0) closer to its face:
    valid just below g / cos(theta_a0), invalid just above it, on either side, with the
    displacement named as the reason."""
    limit = _face_clearance_m(R070) / math.cos(R070.gripper.rest_angle_rad)
    assert 0.5e-3 < limit < 3e-3  # paper-r070: about 1 mm of clearance
    for sign in (1.0, -1.0):
        inside = R070.with_changes(offset_x_m=sign * 0.999 * limit)
        assert rest_codes(inside.rows())[0] == REST_OK
        outside = replace(DISK, offset_x_m=sign * 1.001 * limit)
        with pytest.raises(ValueError, match="offset_x_m") as err:
            Scene(R070.gripper, outside)
        assert "overlaps a finger" in str(err.value)
        rows = R070.rows()
        rows[0, S_OFFSET_X] = sign * 1.001 * limit
        assert rest_codes(rows)[0] == REST_OFFSET
    # past a finger altogether: behind its gripping face
    with pytest.raises(ValueError, match="behind a gripping face"):
        R070.with_changes(offset_x_m=3 * DISK.radius_m)
    # a scene that overlaps centred keeps its own reason, displaced or not
    tight = R070.rows()
    tight[0, DESIGN_FIELDS.index("rest_angle_rad")] = 0.3
    for x in (0.0, 0.3 * limit, -0.3 * limit):
        tight[0, S_OFFSET_X] = x
        assert rest_codes(tight)[0] == REST_OVERLAP


def test_a_row_displaced_onto_a_finger_is_invalid_and_the_others_are_answered():
    designs = np.repeat(Design.from_scene(R070, 0.2).to_array()[None], 3, axis=0)
    offsets = np.array([0.0, 0.02, -0.0005])  # the middle row lies on the right finger
    out = evaluate_designs(designs, DISK, offsets_x_m=offsets)
    np.testing.assert_array_equal(out["valid_at_rest"], [True, False, True])
    np.testing.assert_array_equal(out["converged"], [True, False, True])
    assert 0.0 < out["rest_violation"][1] < 1.0 and out["reward"][1] <= -3.5
    # the overlap depth in radii: the displacement beyond the clearance, along the normal
    depth = (0.02 * math.cos(R070.gripper.rest_angle_rad) - _face_clearance_m(R070)) / (
        DISK.radius_m)
    assert out["rest_violation"][1] == pytest.approx(depth / (1 + depth), rel=1e-9)


@pytest.mark.parametrize("bad", [math.nan, math.inf, "1 mm", np.zeros(2)])
def test_bad_offsets_are_refused_with_their_name(bad):
    designs = Design.from_scene(R070, 0.2).to_array()[None].repeat(3, axis=0)
    with pytest.raises(ValueError, match="offsets_x_m"):
        evaluate_designs(designs, DISK, offsets_x_m=bad)
    if np.ndim(bad) == 0:
        with pytest.raises(ValueError, match="offset_x_m"):
            SoftDisk(0.07, 0.013, offset_x_m=bad)


# ---------------------------------------------------------------------------------------------
# the grasp


def test_zero_offset_is_the_centred_grasp_bit_for_bit():
    designs, _ = _random_placements(1, 40)
    plain = evaluate_designs(designs, DISK)
    for out in (evaluate_designs(designs, DISK, offsets_x_m=0.0),
                evaluate_designs(designs, replace(DISK, offset_x_m=0.0))):
        for key, value in plain.items():
            np.testing.assert_array_equal(out[key], value, err_msg=key)


def test_the_keyword_and_the_disk_field_place_the_object_alike():
    designs, offsets = _random_placements(2, 12, 0.02)
    by_keyword = evaluate_designs(designs, DISK, offsets_x_m=offsets)
    by_disk = evaluate_designs(designs, [replace(DISK, offset_x_m=x) for x in offsets])
    assert by_keyword["converged"].sum() >= 8
    for key, value in by_keyword.items():
        np.testing.assert_array_equal(by_disk[key], value, err_msg=key)


def test_the_mirrored_placement_gives_the_mirrored_grasp():
    """Default model, random designs displaced within +-0.15 r: x_c -> -x_c swaps the jaw
    angles and mirrors the pin's reaction; compression, friction and reward are unchanged
    (measured: equal to 3e-13 rad on 189 of 189 converged pairs)."""
    designs, offsets = _random_placements(0, 60)
    right = evaluate_designs(designs, DISK, offsets_x_m=offsets)
    left = evaluate_designs(designs, DISK, offsets_x_m=-offsets)
    np.testing.assert_array_equal(right["valid_at_rest"], left["valid_at_rest"])
    ok = right["converged"]
    assert ok.sum() >= 45 and np.array_equal(ok, left["converged"])
    np.testing.assert_allclose(right["jaw_angles_rad"][ok], left["jaw_angles_rad"][ok, ::-1],
                               rtol=0, atol=1e-9)
    np.testing.assert_array_equal(right["n_contacts"][ok], left["n_contacts"][ok, ::-1])
    for key in ("peak_compression", "reward", "required_friction"):
        np.testing.assert_allclose(right[key][ok], left[key][ok], rtol=1e-9, atol=1e-12,
                                   err_msg=key)
    force = np.abs(right["pin_force_n"][ok]).max()
    np.testing.assert_allclose(right["pin_force_n"][ok, 0], -left["pin_force_n"][ok, 0],
                               rtol=0, atol=1e-9 * force)
    np.testing.assert_allclose(right["pin_force_n"][ok, 1], left["pin_force_n"][ok, 1],
                               rtol=0, atol=1e-9 * force)
    np.testing.assert_allclose(right["pin_moment_nm"][ok], -left["pin_moment_nm"][ok], rtol=0,
                               atol=1e-9 * force * DISK.radius_m)
    # not a symmetric grasp in disguise: the displaced grasps are turned off the axis
    both = ok & right["touching"].all(axis=1)
    turned = np.abs(np.diff(right["jaw_angles_rad"][both], axis=1))
    assert np.median(turned) > 1e-3


@pytest.mark.parametrize("model", [{}, FAN])
def test_the_finger_the_disk_was_moved_towards_closes_less(model):
    """paper-r070 at 0.2 N·m displaced 1 mm to the right: the right finger meets the disk
    earlier and stays more open than on the axis, the left one closes further, by about as
    much (the disk is pressed about as deep)."""
    centred = simulate(R070, 0.2, **model)
    shifted = simulate(R070.with_changes(offset_x_m=1e-3), 0.2, **model)
    assert centred.converged and shifted.converged
    th_r, th_l = shifted.jaw_angles_rad
    assert th_r > centred.jaw_angles_rad[0] > th_l
    assert abs((th_r + th_l) / 2 - centred.jaw_angles_rad[0]) < 0.1 * (th_r - th_l)


def test_warm_starts_and_finer_meshes_start_from_the_displaced_centre():
    """A torque ramp (each step from the previous equilibrium) ends where a solve from rest
    does, and a fine mesh started from a coarse solution (N = 200, M = 10) where the default
    model is: the starts are taken about the displaced centre."""
    scene = R070.with_changes(offset_x_m=1e-3)
    direct = simulate(scene, 0.2)
    ramp = simulate_ramp(scene, [0.05, 0.1, 0.2])
    assert direct.converged and all(r.converged for r in ramp)
    np.testing.assert_allclose(ramp[-1].jaw_angles_rad, direct.jaw_angles_rad, rtol=0,
                               atol=1e-9)
    fine = simulate(scene, 0.2, n_triangles=200, n_rings=10)
    assert fine.converged
    np.testing.assert_allclose(fine.jaw_angles_rad, direct.jaw_angles_rad, rtol=0.01)
    assert fine.jaw_angles_rad[0] - fine.jaw_angles_rad[1] == pytest.approx(
        direct.jaw_angles_rad[0] - direct.jaw_angles_rad[1], rel=0.1)


def test_a_displaced_grasp_passes_the_independent_check_and_fails_it_centred():
    """The fan displaced by 1 mm: the compiled check and the numpy reference both confirm the
    equilibrium about the displaced centre; the same answer judged as if the centre were on
    the axis has unbalanced spring forces."""
    scene = R070.with_changes(offset_x_m=1e-3)
    res = simulate(scene, 0.2, **FAN)
    assert res.converged and res.kkt.passed
    assert kkt_check(*_inputs(scene, res)).passed
    assert check_grasp(*_inputs(scene, res)).passed
    centred = check_grasp(*_inputs(R070, res))
    assert not centred.passed and centred.force_residual_rel > 1e3 * res.kkt.force_residual_rel
    # the contour lies about the displaced centre
    centroid = res.points_m.mean(axis=0)
    assert centroid[0] == pytest.approx(1e-3, abs=0.05 * 1e-3 + 1e-4 * DISK.radius_m)


def test_the_fixed_centre_carries_what_the_contacts_leave_about_the_true_centre():
    """The fan's pin carries no moment: the contact forces' moment about the displaced centre
    vanishes (about the axis point below it, it would be x_c times their y sum). The pin force
    is minus the faces' forces along their normals."""
    scene = R070.with_changes(offset_x_m=1e-3)
    res = simulate(scene, 0.2, payload_factor=0, **FAN)  # the reaction alone
    assert res.converged and not res.corner_forces_n.any()
    normals = [np.array([-math.cos(t), math.sin(t)]) if side == 0
               else np.array([math.cos(t), math.sin(t)])
               for side, t in enumerate(res.jaw_angles_rad)]
    forces = sum(np.outer(res.contact_forces_n[side], normals[side]) for side in (0, 1))
    np.testing.assert_allclose(res.pin_force_n, -forces.sum(axis=0), rtol=1e-9,
                               atol=1e-12)
    arms = res.points_m - scene.disk.center_m
    moment = float(np.sum(arms[:, 0] * forces[:, 1] - arms[:, 1] * forces[:, 0]))
    scale = np.abs(forces).sum() * DISK.radius_m
    assert abs(moment) < 1e-9 * scale and abs(res.pin_moment_nm) < 1e-9 * scale
    about_axis = moment + 1e-3 * float(forces[:, 1].sum())
    assert abs(about_axis) > 1e-4 * scale
    # the required friction is the linear program's about the true centre (scipy), on the
    # freed disk's normal forces (the released reaction moves them)
    spec = resolve_model(**FAN)
    rows = scene.rows(0.2)
    rows[:, S_SCALE] *= spec.scale
    n = spec.n_triangles
    sol = solve_columns(rows, n, phase_rad=math.pi / 2, element=spec.element)
    prm = pack_params(rows, n, "van_gelder", math.pi / 2, spec.n_rings, spec.element)
    unit = rows[0, S_SCALE] * rows[0, S_YOUNG] * rows[0, S_THICKNESS] * rows[0, S_RADIUS]
    got = loaded_contacts(rows[0], prm[0], n, sol.state_scaled[0], sol.face_scaled[0],
                          sol.corner_forces_n[0] / unit,
                          sol.stop_torques_nm[0] / (unit * rows[0, S_RADIUS]))
    np.testing.assert_allclose(np.sort(got["forces"]),
                               np.sort(np.linalg.norm(forces[forces.any(axis=1)], axis=1)),
                               rtol=1e-9)
    loaded = got["forces"] + got["response"] @ -got["row"][:3]
    assert loaded.min() > 0.0
    arm = got["points"] - scene.disk.center_m
    nu = got["normals"]
    lp = _lp_friction(nu, got["points"], loaded, scene.disk.center_m, DISK.radius_m,
                      -(loaded[:, None] * nu).sum(axis=0),
                      -float(np.sum(loaded * (arm[:, 0] * nu[:, 1] - arm[:, 1] * nu[:, 0]))),
                      hertz_half_width(DISK.radius_m, DISK.thickness_m,
                                       spec.scale * DISK.stiffness_scale
                                       * DISK.youngs_modulus_pa, DISK.poisson_ratio))
    assert res.required_friction == pytest.approx(lp, rel=1e-6)
    # a grasp turned off the axis needs about tan(theta) of its mean angle
    theta = float(np.mean(res.jaw_angles_rad))
    assert res.required_friction == pytest.approx(math.tan(theta), rel=0.1)


def test_finger_gaps_are_the_bars_distance_to_the_displaced_disk():
    designs, offsets = _random_placements(4, 8, 0.1)
    angles = np.random.default_rng(5).uniform(0.0, 0.6, (8, 2))
    gaps = finger_gaps_m(designs, DISK.radius_m, angles, offsets)
    for i, des in enumerate(designs):
        scene = Design.from_array(des).to_scene(replace(DISK, offset_x_m=offsets[i]))
        for side in (0, 1):
            ref = distance_to_finger_bar(scene.gripper, side, float(angles[i, side]),
                                         scene.disk.center_m) - DISK.radius_m
            assert gaps[i, side] == pytest.approx(max(0.0, ref), rel=1e-12, abs=1e-15)


def test_the_drawing_shows_the_disk_where_it_was_placed():
    from envs.render import grasp_figure

    scene = R070.with_changes(offset_x_m=1e-3)
    fig = grasp_figure(scene, simulate(scene, 0.2))
    circles = [p for p in fig.axes[0].patches if isinstance(p, Circle)]
    assert circles and all(c.center[0] == pytest.approx(1e-3) for c in circles)


# ---------------------------------------------------------------------------------------------
# the FEM


def test_the_displaced_fem_agrees_with_the_point_spring_model(tmp_path, monkeypatch):
    """Three random designs displaced by 0.1 r towards one finger or the other (coarse FEM,
    8 rings): the closing angles of the default model within 2 % of the FEM's (measured:
    0.14 %, as on the axis: 0.08 %); the FEM's own mirror images are mirrored; one cache entry
    per placement."""
    pytest.importorskip("skfem")
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    designs = DesignBounds().sample(np.random.default_rng(3), 3, DISK)
    offsets = np.array([0.1, -0.1, 0.1]) * DISK.radius_m
    psm = evaluate_designs(designs, DISK, offsets_x_m=offsets)
    fem = evaluate_designs(designs, DISK, offsets_x_m=offsets, fidelity="fem", fem_rings=8)
    assert psm["valid_at_rest"].all() and psm["converged"].all() and fem["converged"].all()
    closing_psm = designs[:, 1, None] - psm["jaw_angles_rad"]
    closing_fem = designs[:, 1, None] - fem["jaw_angles_rad"]
    assert (np.abs(np.diff(closing_fem, axis=1)) > 0.01 * closing_fem.max()).any()
    np.testing.assert_allclose(closing_psm, closing_fem, rtol=0.02)
    np.testing.assert_allclose(psm["peak_compression"], fem["peak_compression"], rtol=0.06,
                               atol=1e-4)
    mirrored = evaluate_designs(designs, DISK, offsets_x_m=-offsets, fidelity="fem",
                                fem_rings=8)
    np.testing.assert_allclose(mirrored["jaw_angles_rad"], fem["jaw_angles_rad"][:, ::-1],
                               rtol=0, atol=1e-7)
    np.testing.assert_allclose(mirrored["peak_compression"], fem["peak_compression"],
                               rtol=1e-6, atol=1e-9)
    assert len(list((tmp_path / "fem").glob("*.json"))) == 6  # the offset is in the key
