"""The loaded grasp (envs.model.loads, envs.solver.loaded, envs.fem.loaded): the free object's
normal forces under a load, against closed forms of statics, and the PSM against the FEM."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from envs import DesignBounds, Scene, evaluate_designs, simulate
from envs.model.family import resolve_model
from envs.model.holding import H_MU, hertz_half_width
from envs.model.layout import (
    S_OFFSET_X,
    S_POISSON,
    S_RADIUS,
    S_SCALE,
    S_THICKNESS,
    S_YOUNG,
)
from envs.model.loads import (
    LOAD_SETS,
    N_RESPONSE,
    Response,
    friction_under_load,
    load_set_code,
    loaded_holding_row,
    patch_constraints,
    patch_response,
)
from envs.model.problem import pack_params, scene_centre_y_m
from envs.scene import SoftDisk
from envs.solver.pipeline import solve_columns
from envs.solver.reaction import loaded_contacts

R070 = Scene.preset("paper-r070")


def _loaded(scene: Scene, torque_nm: float) -> dict:
    """The default model's grasp of ``scene``: its contact list, each contact's response to a
    load on the freed object, the holding row, the centre, the jaw angles and the Hertz
    patches' coefficient."""
    spec = resolve_model()
    rows = scene.rows(torque_nm)
    rows[:, S_SCALE] *= spec.scale
    n = spec.n_triangles
    sol = solve_columns(rows, n, phase_rad=math.pi / 2, n_rings=spec.n_rings,
                        element=spec.element)
    assert sol.converged[0]
    prm = pack_params(rows, n, "van_gelder", math.pi / 2, spec.n_rings, spec.element)
    s = rows[0]
    unit = s[S_SCALE] * s[S_YOUNG] * s[S_THICKNESS] * s[S_RADIUS]
    out = loaded_contacts(s, prm[0], n, sol.state_scaled[0], sol.face_scaled[0],
                          sol.corner_forces_n[0] / unit,
                          sol.stop_torques_nm[0] / (unit * s[S_RADIUS]))
    # the fixed centre: a disk's, or an outline's centroid (d_1 + its lift at its orientation)
    out["centre"] = np.array([s[S_OFFSET_X], scene_centre_y_m(s)])
    out["radius"] = s[S_RADIUS]
    out["angles"] = sol.jaw_angles_rad[0]
    out["half_width"] = hertz_half_width(s[S_RADIUS], s[S_THICKNESS], s[S_SCALE] * s[S_YOUNG],
                                         s[S_POISSON])
    return out


def _friction(g: dict, load) -> float:
    """The friction the freed object needs under the one in-plane ``load`` [N]."""
    row = g["row"]
    return friction_under_load(g["normals"], g["points"], g["forces"], g["centre"],
                               g["radius"], row[:2], row[2], g["model"], load,
                               g["half_width"], g["patches"])


def _faces(g: dict) -> tuple[np.ndarray, np.ndarray]:
    """The right and left faces' loaded normal forces per unit load (3 columns) and at the
    released reaction alone."""
    f0 = -g["row"][:3]
    loaded0 = g["forces"] + g["response"] @ f0
    right = g["fingers"] == 0
    per_load = np.array([g["response"][right].sum(axis=0), g["response"][~right].sum(axis=0)])
    return per_load, np.array([loaded0[right].sum(), loaded0[~right].sum()])


@pytest.fixture(scope="module")
def symmetric():
    """paper-r070 at 0.2 N·m: a mirror-symmetric grasp on the two flat faces."""
    return _loaded(R070, 0.2)


def check_across_load(g: dict) -> None:
    """A load across the jaws (x) on the symmetric grasp: the faces' normal forces change by
    ``+-a W`` with ``a = 1 / (2 (cos theta + sin theta beta / alpha))`` (statics of the two
    rolling faces: ``alpha``, ``beta`` the force centre's place along the face's normal and
    tangent from the centre; ``1 / (2 cos theta)`` for a centre on the normal's line, where the
    tangential forces stay what the reaction asks of each face), and the friction is that of
    statics on the loaded forces, ``|t| / (N_0 - a W)`` for the relieved face, infinite once it
    is released, at ``W = N_0 / a`` (any object whose grasp is mirror-symmetric on the
    two faces)."""
    theta = g["angles"][0]
    assert g["angles"][1] == pytest.approx(theta, abs=1e-9)
    right = g["fingers"] == 0
    nu = g["normals"][right][0]
    tau = np.array([-nu[1], nu[0]])
    centre = (g["forces"][right, None] * g["points"][right]).sum(axis=0) / g["forces"][
        right].sum() - g["centre"]
    alpha, beta = centre @ nu, centre @ tau
    a = 1.0 / (2.0 * (math.cos(theta) + math.sin(theta) * beta / alpha))
    per_load, loaded0 = _faces(g)
    assert per_load[0, 0] == pytest.approx(a, rel=1e-9)
    assert per_load[1, 0] == pytest.approx(-a, rel=1e-9)
    assert loaded0[0] == pytest.approx(loaded0[1], rel=1e-9)
    end = loaded0[1] / a
    mu0 = _friction(g, (0.0, 0.0))
    assert mu0 == pytest.approx(math.tan(theta), rel=1e-9)
    nu_l = g["normals"][~right][0]
    tangents = np.array([[-nu[1], -nu_l[1]], [nu[0], nu_l[0]]])
    for share in (0.25, 0.5, 0.9):
        w = share * end
        forces = loaded0 + w * per_load[:, 0]
        # statics: the two faces' tangential forces carry what their normals and W leave
        need = -(forces[0] * nu + forces[1] * nu_l + np.array([w, 0.0]))
        t = np.linalg.solve(tangents, need)
        assert _friction(g, (w, 0.0)) == pytest.approx(np.max(np.abs(t) / forces), rel=1e-6)
        if abs(beta / alpha) < 0.05:  # a centre near the normal's line: a = 1 / (2 cos theta)
            t0 = np.linalg.solve(tangents, -(loaded0[0] * nu + loaded0[1] * nu_l))
            np.testing.assert_allclose(np.abs(t), np.abs(t0), rtol=0.02)
        assert _friction(g, (-w, 0.0)) == pytest.approx(_friction(g, (w, 0.0)), rel=1e-9)
    assert math.isfinite(_friction(g, (0.99 * end, 0.0)))
    assert _friction(g, (1.01 * end, 0.0)) == math.inf


def check_axial_load(g: dict) -> None:
    """A load along the gripper's axis on the symmetric grasp: the faces' tangential forces
    carry it, ``mu = |tan(theta) +- W / (2 N' cos(theta))|``, plus pulling out of the jaws
    (+y), minus pushing in (-y: past ``W = 2 N' sin theta`` the tangential forces turn), N'
    each face's loaded normal force; the faces keep nearly the force their torques give
    them."""
    theta = g["angles"][0]
    per_load, loaded0 = _faces(g)
    for w in (0.1, 0.5, 2.0):
        for sign in (1.0, -1.0):
            face = loaded0[0] + sign * w * per_load[0, 1]
            want = abs(math.tan(theta) + sign * w / (2.0 * face * math.cos(theta)))
            assert _friction(g, (0.0, sign * w)) == pytest.approx(want, rel=1e-9)
    assert abs(per_load[0, 1]) < 0.15


def test_an_across_load_is_carried_by_the_normal_forces(symmetric):
    check_across_load(symmetric)


def test_an_axial_load_needs_tan_theta_plus_its_share(symmetric):
    check_axial_load(symmetric)


def test_a_finger_on_its_torque_alone_keeps_its_moment():
    """With (almost) no joint spring a finger is held by its constant torque alone: a load
    along the axis changes the moment of its contact forces about the joint by nothing, so a
    face's normal force moves only by the moment of its added tangential force along the
    face, ``w / 2`` from the finger's axis (``dN = -(w / 2) dt / s``, ``s`` the contact's
    distance along the finger). (A load across the jaws swings both fingers one way: their
    springs take the moments' change.)"""
    scene = Scene(replace(R070.gripper, torsion_stiffness_nm_per_rad=1e-7), R070.disk)
    g = _loaded(scene, 0.2)
    theta = g["angles"][0]
    per_load, loaded0 = _faces(g)
    right = g["fingers"] == 0
    nu = g["normals"][right][0]
    nu_l = g["normals"][~right][0]
    tangents = np.array([[-nu[1], -nu_l[1]], [nu[0], nu_l[0]]])
    joint = np.array([R070.gripper.joint_offset_m, 0.0])
    centre = (g["forces"][right, None] * g["points"][right]).sum(axis=0) / g["forces"][
        right].sum()
    lever = np.linalg.norm(centre - joint)
    w = 1.0
    base = np.linalg.solve(tangents, -(loaded0[0] * nu + loaded0[1] * nu_l))
    for k, load in ((1, (0.0, w)), (1, (0.0, -w))):
        forces = loaded0 + load[1] * per_load[:, k]
        dt = np.linalg.solve(tangents, -(forces[0] * nu + forces[1] * nu_l + np.array(load)))
        dt -= base
        # the right face's added force, normal and along the face, about the joint
        added = load[1] * per_load[0, k] * nu + dt[0] * np.array([-nu[1], nu[0]])
        arm = centre - joint
        moment = float(arm[0] * added[1] - arm[1] * added[0])
        assert abs(moment) <= 1e-6 * lever * w
        assert abs(dt[0]) > 0.1 * w  # (not trivially: the face carries a share)
    assert theta > 0.0


def _arc(sign: float, angles_deg: np.ndarray, radius: float):
    """A cradle's contacts on the object of centre (0, 0): points on its rim at the angles
    (right side, mirrored for ``sign`` -1), normals pointing into the object."""
    phi = np.radians(angles_deg)
    points = np.column_stack([sign * radius * np.cos(phi), radius * np.sin(phi)])
    return points, -points / radius


def test_a_cradle_pushed_into_its_bottom_needs_no_friction():
    """Two mirrored cradles each pressing a run of contacts around the object, pushed into
    the right one's bottom: the push is carried by the cradles' normal forces alone (each
    run's tangential force vanishes by symmetry), so no friction at all, where the normal
    forces as solved would need friction to carry it."""
    radius = 0.01
    angles = np.arange(-30.0, 31.0, 10.0)
    pr, nr = _arc(1.0, angles, radius)
    pl, nl = _arc(-1.0, angles, radius)
    points, normals = np.vstack([pr, pl]), np.vstack([nr, nl])
    k = points.shape[0]
    forces = np.ones(k)
    fingers = np.repeat([0, 1], k // 2)
    patches = np.repeat([0, 1], k // 2)
    nodes = np.column_stack([np.arange(k), np.full(k, -1)])
    groups = np.zeros((k, 2), dtype=np.int64)
    cons = np.zeros((k, 2), dtype=np.int64)
    weights = np.zeros((k, 2))
    mn, mc = patch_constraints(normals, points, forces, patches, nodes, fingers, k, radius,
                               groups, cons, weights)
    assert mn == k and mc == k + 2  # each node of a curved run its own normal, a run one slide
    # independent contact springs: any compliance with the mirror symmetry would do
    compliance = 1e-4 * np.eye(mc)
    response, coupling = np.zeros((mc, N_RESPONSE)), np.zeros((mc, mc))
    assert patch_response(compliance, mn, mc, normals, points, fingers, k, cons, weights, 0.0,
                          0.0, 0.02, 0.05, (False, False), radius, 10.0, response, coupling)
    model = Response(cons, weights, mn, mc, response, coupling)
    centre, pin = np.zeros(2), np.zeros(2)  # the cradles balance each other
    for w in (0.5, 2.0, 5.0):
        assert friction_under_load(normals, points, forces, centre, radius, pin, 0.0, model,
                                   (w, 0.0), 0.0, patches) == pytest.approx(0.0, abs=1e-9)
        loaded = forces + w * weights[:, 0] * response[cons[:, 0], 0]
        assert loaded.min() > 0.0
        np.testing.assert_allclose((loaded[:, None] * normals).sum(axis=0), [-w, 0.0],
                                   atol=1e-9 * w)
        assert friction_under_load(normals, points, forces, centre, radius, pin, 0.0, None,
                                   (w, 0.0), 0.0, patches) > 0.05


def test_the_load_sets_check_their_directions(symmetric):
    """Each load set includes the reaction alone; top-down pulls along the axis both ways,
    side out of the plane (the 3-D cones: ``sqrt(tan^2 theta + (W / sum N)^2)`` for the
    symmetric grasp), any every direction: at least both others."""
    g = symmetric
    theta = g["angles"][0]
    w = 0.5
    rows = {name: loaded_holding_row(g["normals"], g["points"], g["forces"], g["centre"],
                                     g["radius"], g["row"][:2], g["row"][2], g["model"], w,
                                     name, g["half_width"], g["patches"])
            for name in LOAD_SETS}
    per_load, loaded0 = _faces(g)
    out = max(_friction(g, (0.0, w)), _friction(g, (0.0, -w)))
    assert rows["top-down"][H_MU] == pytest.approx(out, rel=1e-12)
    assert rows["side"][H_MU] == pytest.approx(
        math.hypot(math.tan(theta), w / loaded0.sum()), rel=1e-6)
    assert rows["any"][H_MU] >= max(rows["top-down"][H_MU], rows["side"][H_MU])
    # the worst in-plane direction is found: no sampled pull needs more
    worst = max(_friction(g, (w * math.cos(p), w * math.sin(p)))
                for p in np.linspace(0.0, 2 * math.pi, 361))
    assert rows["any"][H_MU] >= worst * (1 - 1e-9)
    with pytest.raises(ValueError, match="load_set must be one of"):
        load_set_code("sideways")


def test_the_grasp_reports_the_load_set_it_checked():
    res = simulate(R070, 0.2, load_set="top-down")
    assert res.load_set == "top-down" and res.to_dict()["load_set"] == "top-down"
    with pytest.raises(ValueError, match="load_set"):
        simulate(R070, 0.2, load_set="up")
    with pytest.raises(ValueError, match="load_set"):
        evaluate_designs(DesignBounds().sample(np.random.default_rng(0), 2, R070.disk),
                         R070.disk, load_set="down")


def test_the_point_spring_model_carries_the_load_as_the_fem_does():
    """8 random designs on a water-dense r = 0.07 m disk (a payload of 3 N, 10-30 % of their
    grip) at friction 1: the default model's required friction under the payload, load set
    any, within 5 % (median) of the FEM's on a 6-ring mesh (measured: ~1 %; the accuracy page's
    figure, scripts/loaded_accuracy.py, has more)."""
    disk = SoftDisk(R070.disk.radius_m, 0.0, density_kg_m3=1000.0)
    mu_p, mu_f = required_friction_both(disk, 8)
    assert mu_p.size >= 5
    assert np.median(np.abs(mu_p - mu_f) / mu_f) <= 0.05


def required_friction_both(disk: SoftDisk, designs: int) -> tuple[np.ndarray, np.ndarray]:
    """The required friction under the payload (load set any, friction 1) of ``designs``
    random designs (seed 5) by the default model and by the FEM on 6 rings, over the designs
    that converged, touch with both fingers and need a finite friction at both."""
    rows = DesignBounds().sample(np.random.default_rng(5), designs, disk)
    psm = evaluate_designs(rows, disk, friction_coefficients=1.0)
    fem = evaluate_designs(rows, disk, friction_coefficients=1.0, fidelity="fem", fem_rings=6)
    both = (psm["converged"] & fem["converged"] & psm["touching"].all(axis=1)
            & fem["touching"].all(axis=1) & np.isfinite(psm["required_friction"])
            & np.isfinite(fem["required_friction"]))
    return psm["required_friction"][both], fem["required_friction"][both]


def test_the_grape_needs_no_more_friction_for_what_its_normals_carry():
    """A grape (r = 9.5 mm, 275 kPa, t = 20 mm, 1050 kg/m^3, friction 0.7) in the grooved optimum
    of ``psm-grasp optimize --jaw any --budget 800`` (a rounded V, 0.83 mm deep, jaw angle 16°):
    pushed towards the joints (within 35° of -y, where the jaws' normals carry it) at payload
    factor 4 it needs no more friction than held at rest, and every pull of the load set needs a
    finite friction within the grape's 0.7. The normal forces as solved (the bound) need more
    at every factor."""
    grape = SoftDisk(0.0095, 0.0, 275e3, 0.45, 0.02, density_kg_m3=1050.0)
    design = np.array([0.03854, 0.538653, 0.00059293, 0.001285, 0.076647, 0.021314,
                       0.00082559, 0.008217, 0.895509, 0.029198])
    from envs.scene import Design

    scene = Design.from_array(design).to_scene(grape, 0.007395)
    g = _loaded(scene, design[4])
    assert min(g["angles"]) > 0.2 and len(set(g["patches"].tolist())) >= 4  # V flanks
    rest = _friction(g, (0.0, 0.0))
    w = grape.payload_n(4.0)
    for deg in range(-125, -54, 10):
        phi = math.radians(deg)
        assert _friction(g, (w * math.cos(phi), w * math.sin(phi))) <= rest * (1 + 1e-9)
    row = g["row"]
    for name in LOAD_SETS:
        for factor in (0.5, 2.0, 4.0):
            args = (g["normals"], g["points"], g["forces"], g["centre"], g["radius"], row[:2],
                    row[2])
            loaded = loaded_holding_row(*args, g["model"], grape.payload_n(factor), name,
                                        g["half_width"], g["patches"])[H_MU]
            fixed = loaded_holding_row(*args, None, grape.payload_n(factor), name,
                                       g["half_width"], g["patches"])[H_MU]
            assert rest <= loaded < 0.7 and loaded < fixed
