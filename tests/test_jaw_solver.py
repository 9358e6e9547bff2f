"""Shaped jaws in the point-spring solver: a cradle that fits the disk, a V-groove's flank
forces against the fingers' moment balance, random grooved designs checked independently.

The geometry of the expected answers is worked out here from the jaw's definition
(:mod:`envs.model.jaw`), not taken from the solver.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from envs.batch_metrics import grooves_m
from envs.check import check_grasp
from envs.model.contact_width import hertz_arc_coefficient
from envs.model.jaw import JawProfile
from envs.model.layout import C_MOUTH_ROOT, C_MOUTH_TIP, N_GROOVE
from envs.model.problem import SceneColumns
from envs.scene import Scene
from envs.scoring import grooved_face_share
from envs.solver.pipeline import solve_columns
from envs.solver.simulate import simulate

BASE = Scene.preset("paper-r070")
GRIP, DISK = BASE.gripper, BASE.disk
R = DISK.radius_m
HW = GRIP.finger_width_m / 2
# distance from the right joint (d_3, 0) to the fixed disk centre (0, d_1 + r)
JC = math.hypot(GRIP.joint_offset_m, DISK.distance_m + R)
KF = GRIP.torsion_stiffness_nm_per_rad


def _fit_angle(m_centre: float) -> tuple[float, float]:
    """Position ``a`` of a groove and the finger angle at which the disk centre sits at finger
    coordinates ``(a, m_centre)``: the joint-to-centre distance is fixed, so
    ``a = sqrt(JC^2 - m^2)``; the right finger's ``s = v . e``, ``m = v . n`` with
    ``e = (sin, cos)``, ``n = (-cos, sin)`` and ``v = C - J = (-d_3, d_1 + r)``."""
    a = math.sqrt(JC * JC - m_centre * m_centre)
    vx, vy = -GRIP.joint_offset_m, DISK.distance_m + R
    # with v = |v| (cos alpha, sin alpha): s = |v| sin(alpha + theta), m = -|v| cos(alpha +
    # theta)
    theta = math.atan2(a, -m_centre) - math.atan2(vy, vx)
    s = vx * math.sin(theta) + vy * math.cos(theta)
    m = -vx * math.cos(theta) + vy * math.sin(theta)
    assert abs(s - a) < 1e-12 and abs(m - m_centre) < 1e-12
    return a, theta


def test_fitted_cradle_touches_its_whole_arc():
    """A cradle of the disk's radius, placed where the closing finger brings its centre onto
    the disk's, touches along its whole arc at a small torque: the contacts cover the arc's
    share of the contour within a point spacing, and the force spreads over them."""
    depth = 0.006
    a, theta = _fit_angle(HW - depth + R)  # the arc's centre: depth - R below the face
    jaw = JawProfile.cradle(R, depth, a)
    # just past the torque at which the spring alone would hold the finger at the fit
    torque = 1.01 * KF * (GRIP.rest_angle_rad - theta)
    res = simulate(BASE.with_changes(jaw=jaw), torque)
    assert res.converged and res.kkt.passed, res.message
    n = res.points_m.shape[0]
    arc_share = 2 * math.asin(jaw.mouth_half_width_m / R) / (2 * math.pi)
    for j in range(2):
        forces = res.contact_forces_n[j]
        pressed = int(np.count_nonzero(forces > 0.0))
        assert abs(pressed / n - arc_share) <= 1.0 / n, (j, pressed, arc_share * n)
        # spread along the arc, not one or two points carrying it
        assert pressed >= 4
        assert forces.max() < 0.5 * forces.sum()
        assert not res.corner_forces_n[j].any()
    # the finger closed to the fit (the disk barely deformed)
    assert res.jaw_angles_rad[0] == pytest.approx(theta, abs=1e-3)


def _vee_flank_normal(j: int, theta: float, side: float, half: float) -> np.ndarray:
    """World unit normal (on the disk) of a V flank of finger j at angle theta: in the groove's
    (u, v) frame (u along the finger, v depth below the face) the flank on side ``side`` of the
    centre line has outward normal ``(-side cos b, -sin b)``; ``u`` is along the axis e and
    ``-v`` along the inward normal n."""
    s, c = math.sin(theta), math.cos(theta)
    e, n = ((np.array([s, c]), np.array([-c, s])) if j == 0
            else (np.array([-s, c]), np.array([c, s])))
    return -side * math.cos(half) * e + math.sin(half) * n


def test_vee_flank_forces_balance_the_finger():
    """A wide V-groove holds the disk on both flanks of each finger. Each pressed point lies on
    a flank, its force along that flank's normal (from the V's geometry), and the flank forces
    balance the finger: ``T_a - k_f (theta_0 - theta) = sum (p_i - J) x F_i`` about the joint;
    the mirror-symmetric scene leaves the pin no force across the axis."""
    opening = math.radians(160.0)
    half = opening / 2
    depth = 0.006
    # the disk resting on both flanks: its centre on the centre line, r / sin(b) from the apex
    a, _ = _fit_angle(HW - depth + R / math.sin(half))
    jaw = JawProfile.vee(opening, depth, a)
    torque = 0.2
    res = simulate(BASE.with_changes(jaw=jaw), torque)
    assert res.converged and res.kkt.passed, res.message
    for j in range(2):
        theta = res.jaw_angles_rad[j]
        joint = np.array([GRIP.joint_offset_m if j == 0 else -GRIP.joint_offset_m, 0.0])
        e = (np.array([math.sin(theta), math.cos(theta)]) if j == 0
             else np.array([-math.sin(theta), math.cos(theta)]))
        moment = 0.0  # of the disk's forces on the finger about its joint, closing positive
        flank_force = {-1.0: 0.0, 1.0: 0.0}
        for i in np.flatnonzero(res.contact_forces_n[j] > 0.0):
            p = res.points_m[i]
            side = 1.0 if (p - joint) @ e > a else -1.0
            normal = _vee_flank_normal(j, theta, side, half)
            force_on_finger = -res.contact_forces_n[j, i] * normal
            arm = p - joint
            cross = arm[0] * force_on_finger[1] - arm[1] * force_on_finger[0]
            # closing turns the right finger +z, the left one -z
            moment += cross if j == 0 else -cross
            flank_force[side] += res.contact_forces_n[j, i]
        assert flank_force[-1.0] > 0.0 and flank_force[1.0] > 0.0, flank_force
        assert not res.corner_forces_n[j].any()
        drive = torque - KF * (GRIP.rest_angle_rad - theta) - res.stop_torques_nm[j]
        assert moment + drive == pytest.approx(0.0, abs=1e-9 * torque)
    assert res.pin_force_n[0] == pytest.approx(0.0, abs=1e-9 * res.grip_force_n)


def _random_jaws(rng: np.random.Generator, count: int) -> list[JawProfile]:
    """Cradles (radius 0.7 to 2 r) and V-grooves (opening 90 to 170 deg) alternately, 15 to 75 %
    of the finger's width deep, centred near where the closing finger meets the disk."""
    a0 = math.sqrt(JC * JC - (HW + R) ** 2)
    jaws = []
    for k in range(count):
        depth = GRIP.finger_width_m * rng.uniform(0.15, 0.75)
        if k % 2 == 0:
            radius = max(R * rng.uniform(0.7, 2.0), depth)
            jaw = JawProfile.cradle(radius, depth, 0.0)
        else:
            jaw = JawProfile.vee(math.radians(rng.uniform(90.0, 170.0)), depth, 0.0)
        half = jaw.mouth_half_width_m
        # kept on the face with its rounded mouth edges (a millimetre to spare)
        lo, hi = half + 1e-3, GRIP.finger_length_m - half - 1e-3
        a = min(max(a0 + rng.uniform(-0.5, 0.5) * half, lo), hi)
        jaws.append(JawProfile(jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, a))
    return jaws


def test_random_grooved_designs_converge_and_pass_the_check():
    """50 random cradles and V-grooves on paper-r070 at random torques (the fan, N = 20): the
    solver converges on a share comparable to the straight jaws' on the same scenes, and every
    converged grasp passes the independent check (the pipeline runs it; a sample again through
    :func:`envs.check.check_grasp` with the scene's own jaw)."""
    rng = np.random.default_rng(35)
    jaws = _random_jaws(rng, 50)
    torques = rng.uniform(0.03, 0.5, size=len(jaws))
    scenes = [BASE.with_changes(jaw=jaw) for jaw in jaws]
    rows = np.vstack([s.rows(t) for s, t in zip(scenes, torques, strict=True)])
    straight = np.vstack([BASE.rows(t) for t in torques])
    n = 20
    sol = solve_columns(SceneColumns.from_rows(rows), n, phase_rad=math.pi / 2)
    ref = solve_columns(SceneColumns.from_rows(straight), n, phase_rad=math.pi / 2)
    share, share_straight = sol.converged.mean(), ref.converged.mean()
    assert share >= min(0.9, share_straight - 0.05), (share, share_straight)
    # the grooves are used: most grasps press inside a groove (gap to the straight face > 0)
    touched = sol.converged & (sol.face_forces_n.sum(axis=(1, 2)) > 0.0)
    assert touched.sum() >= 25
    for i in np.flatnonzero(sol.converged)[:10]:
        rep = check_grasp(scenes[i], torques[i], n, "van_gelder", sol.points_m[i],
                          sol.jaw_angles_rad[i], sol.face_forces_n[i], sol.corner_forces_n[i],
                          sol.stop_torques_nm[i])
        assert rep.passed, (i, rep.reason)
    # a mouth corner bears only on a grooved finger; a straight one never has them
    assert not ref.corner_forces_n[:, :, [C_MOUTH_TIP, C_MOUTH_ROOT]].any()


def test_check_rejects_a_grasp_inside_the_groove_as_straight():
    """The independent check knows the groove: a fitted cradle's grasp passes with its jaw and
    fails (penetration) when checked as if the jaw were straight."""
    depth = 0.006
    a, theta = _fit_angle(HW - depth + R)
    scene = BASE.with_changes(jaw=JawProfile.cradle(R, depth, a))
    torque = 1.01 * KF * (GRIP.rest_angle_rad - theta)
    res = simulate(scene, torque, 20, element="spring")
    assert res.converged, res.message
    args = (torque, 20, "van_gelder", res.points_m, res.jaw_angles_rad, res.contact_forces_n,
            res.corner_edge_forces_n, res.stop_torques_nm)
    assert check_grasp(scene, *args).passed
    rep = check_grasp(BASE, *args)
    assert not rep.passed and "penetration" in rep.reason


def _face_share(scene: Scene, res, j: int) -> float:
    """The scoring's share of the contour touching finger j (:func:`grooved_face_share`)."""
    disk, grip = scene.disk, scene.gripper
    cols = SceneColumns.from_rows(scene.rows(res.torque_nm))
    packed, rounding = grooves_m(cols)
    return grooved_face_share(res.points_m, res.contact_forces_n[j],
                              res.corner_edge_forces_n[j], j, res.jaw_angles_rad[j],
                              grip.joint_offset_m, grip.finger_length_m, grip.finger_width_m,
                              rounding[0], packed[0], N_GROOVE * j, disk.radius_m,
                              disk.thickness_m, disk.stiffness_scale * disk.youngs_modulus_pa,
                              disk.poisson_ratio)


def _flat_hertz_k(disk) -> float:
    return hertz_arc_coefficient(disk.radius_m, disk.thickness_m,
                                 disk.stiffness_scale * disk.youngs_modulus_pa,
                                 disk.poisson_ratio, disk.radius_m)


def test_fitted_cradle_scores_its_whole_arc_at_any_force():
    """The contact measure of a cradle that fits the disk is its arc's share at a small force,
    where a flat face's Hertz cap would allow less than half of it: conforming contact has no
    Hertz cap. The measure runs from the first pressed point to the last, and the arc's ends
    fall between points: within a point spacing at each end."""
    depth = 0.006
    a, theta = _fit_angle(HW - depth + R)
    scene = BASE.with_changes(jaw=JawProfile.cradle(R, depth, a))
    res = simulate(scene, 1.01 * KF * (GRIP.rest_angle_rad - theta))
    assert res.converged, res.message
    n = res.points_m.shape[0]
    arc_share = 2 * math.asin(scene.gripper.jaw.mouth_half_width_m / R) / (2 * math.pi)
    k_flat = _flat_hertz_k(scene.disk)
    for j in range(2):
        share = _face_share(scene, res, j)
        assert abs(share - arc_share) <= 2.0 / n, (share, arc_share)
        assert k_flat * math.sqrt(res.contact_forces_n[j].sum()) < 0.5 * arc_share


def test_vee_flanks_are_two_contacts_each_capped_by_its_force():
    """A V-groove's two flank contacts are two flat-face contacts: at a squeeze that resolves
    both over several points, each is capped by the flat Hertz width of its own force, so the
    finger's share is ``k (sqrt(F_1) + sqrt(F_2))``, more than one cap of their sum."""
    opening = math.radians(160.0)
    depth = 0.006
    a, _ = _fit_angle(HW - depth + R / math.sin(opening / 2))
    scene = BASE.with_changes(jaw=JawProfile.vee(opening, depth, a))
    res = simulate(scene, 0.2)
    assert res.converged, res.message
    k_flat = _flat_hertz_k(scene.disk)
    for j in range(2):
        forces = res.contact_forces_n[j]
        e = np.array([math.sin(res.jaw_angles_rad[j]) * (1 if j == 0 else -1),
                      math.cos(res.jaw_angles_rad[j])])
        joint = np.array([GRIP.joint_offset_m * (1 if j == 0 else -1), 0.0])
        along = (res.points_m - joint) @ e
        pressed = forces > 0.0
        flanks = [forces[pressed & (along < a)].sum(), forces[pressed & (along > a)].sum()]
        assert min(flanks) > 0.0
        share = _face_share(scene, res, j)
        capped = k_flat * (math.sqrt(flanks[0]) + math.sqrt(flanks[1]))
        assert share == pytest.approx(capped, rel=1e-12)
        assert share > k_flat * math.sqrt(sum(flanks)) * 1.2


def test_solver_gap_smooths_only_the_ridge_of_a_vee():
    """The solver's gap to a V-grooved finger is the kernel's, except in a cone about the V's
    centre line above its bottom, where it is a smooth lower bound: its gradient matches
    central differences in and around the groove (a sharp V, a rounded one, a narrow one), and
    it is the kernel's gap and normal at every point on the surface."""
    from envs.model.jaw import jaw_gap, pack_groove
    from envs.model.layout import N_PARAMS, P_GROOVE0, P_HW, P_LMAX, P_RHO
    from envs.solver.contact import _solver_jaw_gap

    rng = np.random.default_rng(3)
    for opening, bottom in ((math.radians(160.0), 0.0), (math.radians(90.0), 0.01),
                            (math.radians(30.0), 0.0)):
        prm = np.zeros(N_PARAMS)
        prm[P_HW], prm[P_LMAX], prm[P_RHO] = 0.5, 10.0, 0.02
        depth = 0.7
        pack_groove(depth, bottom, opening, 5.0, 0.02, 1.0, prm, P_GROOVE0)
        lowered = 0
        for _ in range(4000):
            s = 5.0 + rng.uniform(-2.0, 2.0)
            m = 0.5 - rng.uniform(-0.5, depth + 0.05)
            g = _solver_jaw_gap(s, m, 0, prm)
            ref = jaw_gap(s, m, 10.0, 0.5, 0.02, prm, P_GROOVE0)
            assert g[0] <= ref[0] + 1e-15
            lowered += g[0] < ref[0]
            h = 1e-7
            fd_s = (_solver_jaw_gap(s + h, m, 0, prm)[0] - _solver_jaw_gap(s - h, m, 0, prm)[0])
            fd_m = (_solver_jaw_gap(s, m + h, 0, prm)[0] - _solver_jaw_gap(s, m - h, 0, prm)[0])
            assert abs(fd_s / (2 * h) - g[1]) < 1e-6 and abs(fd_m / (2 * h) - g[2]) < 1e-6
            if abs(ref[0]) < 1e-3:
                assert g == ref  # at a surface: the kernel's own gap and normal
        assert lowered > 0


def test_baselines_refuse_a_grooved_jaw():
    """The baselines model straight jaws only: a grooved one is refused by name."""
    scene = BASE.with_changes(jaw=JawProfile.vee(math.radians(120.0), 0.004, 0.05))
    with pytest.raises(ValueError, match="method = 'newton'"):
        simulate(scene, 0.1, method="slsqp")


def test_check_distance_agrees_with_the_kernel():
    """The independent check's grooved-finger distance (the groove as the points near a cone,
    the nearest of the core's boundary pieces) and the shared kernel's agree to round-off on
    points in and around a cradle, a sharp V and a rounded V: two formulas, one solid."""
    from envs import check
    from envs.model.jaw import jaw_gap, pack_groove

    rng = np.random.default_rng(11)
    length, hw, rho = 0.2, 0.005, 7e-5
    for jaw in (JawProfile.cradle(0.05, 0.004, 0.08), JawProfile.vee(math.radians(100.0),
                                                                    0.0035, 0.08),
                JawProfile(0.003, 0.004, math.radians(120.0), 0.08)):
        ck = np.zeros(check.N_CK)
        ck[check.CK_LENGTH], ck[check.CK_HALF_WIDTH], ck[check.CK_RHO] = length, hw, rho
        base = check.CK_JAW0
        ck[base + check.JW_DEPTH] = jaw.depth_m
        ck[base + check.JW_BOTTOM_RADIUS] = jaw.bottom_radius_m
        ck[base + check.JW_OPENING] = jaw.opening_angle_rad
        ck[base + check.JW_POSITION] = jaw.position_m
        packed = np.zeros(N_GROOVE)
        pack_groove(jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m,
                    rho, 1.0, packed, 0)
        half = jaw.mouth_half_width_m
        worst = 0.0
        for _ in range(3000):
            s = jaw.position_m + rng.uniform(-1.5, 1.5) * half
            m = hw - rng.uniform(-0.01, jaw.depth_m * 1.2)
            ks, km, inside = check._groove_nearest(ck, 0, s, m)
            mine = -rho if inside else math.hypot(s - ks, m - km) - rho
            worst = max(worst, abs(mine - jaw_gap(s, m, length, hw, rho, packed, 0)[0]))
        assert worst < 1e-12, (jaw, worst)


def test_reach_distance_sees_the_groove():
    """A point in front of a cradle's centre, ``D`` from the face line, is ``D`` from the
    straight bar and ``D + h`` from the grooved finger (the arc's bottom, ``h`` deep); beside
    the groove the two agree."""
    from envs.model.geometry import distance_to_finger_bar, finger_frame

    depth, a, gap = 0.004, 0.08, 0.01
    jaw = JawProfile.cradle(0.05, depth, a)
    angle = 0.5
    joint, axis, normal = finger_frame(GRIP, 0, angle)
    front = joint + a * axis + (HW + gap) * normal
    beside = joint + 0.15 * axis + (HW + gap) * normal
    straight = distance_to_finger_bar(GRIP, 0, angle, front)
    grooved = distance_to_finger_bar(GRIP, 0, angle, front, jaw, 7e-5)
    assert straight == pytest.approx(gap, abs=1e-15)
    assert grooved == pytest.approx(gap + depth, abs=1e-12)
    both = distance_to_finger_bar(GRIP, 0, np.array([angle, angle]), beside, jaw, 7e-5)
    assert both == pytest.approx([gap, gap], abs=1e-12)
