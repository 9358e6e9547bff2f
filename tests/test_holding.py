"""Holding: the pin reaction and the required friction, against closed forms, a linear program,
and the FEM (envs.model.holding, envs.solver.reaction, the FEM's contact list)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from envs import DesignBounds, Scene, evaluate_designs, simulate
from envs.model.family import resolve_model
from envs.model.holding import H_MU, hertz_half_width
from envs.model.layout import S_DISTANCE, S_POISSON, S_RADIUS, S_SCALE, S_THICKNESS, S_YOUNG
from envs.model.loads import holding_row
from envs.model.problem import pack_params
from envs.scene import Design
from envs.solver.pipeline import solve_columns
from envs.solver.reaction import loaded_contacts

R070 = Scene.preset("paper-r070")


def _pressure_shift(normals, points, forces, centre, length, half_width=0.0
                    ) -> tuple[float, float]:
    """How far the normal forces' moment can move when each face's pressure shifts within its
    Hertz patch of half-width ``half_width sqrt(F)`` (faces: one normal, one line), computed
    again here in numpy."""
    offsets = np.einsum("ij,ij->i", points, normals)
    low = high = 0.0
    done = np.zeros(forces.size, dtype=bool)
    for i in range(forces.size):
        if done[i]:
            continue
        face = (np.abs(normals - normals[i]).max(axis=1) <= 1e-9) & (
            np.abs(offsets - offsets[i]) <= 1e-6 * length)
        done |= face
        total = forces[face].sum()
        low -= total * half_width * np.sqrt(total)
        high += total * half_width * np.sqrt(total)
    return low, high


def _lp_friction(normals, points, forces, centre, length, pin, moment, half_width=0.0
                 ) -> float:
    """The required friction as a plain linear program (scipy): min mu over (t, mu, delta) with
    sum t_i tau_i = pin, sum t_i m_i + delta = moment, |t_i| <= mu N_i, delta within the faces'
    pressure shift."""
    k = forces.size
    tau = np.column_stack([-normals[:, 1], normals[:, 0]])
    arm = (points[:, 0] - centre[0]) * tau[:, 1] - (points[:, 1] - centre[1]) * tau[:, 0]
    low, high = _pressure_shift(normals, points, forces, centre, length, half_width)
    a_eq = np.zeros((3, k + 2))
    a_eq[0, :k], a_eq[1, :k], a_eq[2, :k] = tau[:, 0], tau[:, 1], arm / length
    a_eq[2, k + 1] = 1.0 / length
    b_eq = np.array([pin[0], pin[1], moment / length])
    a_ub = np.zeros((2 * k, k + 2))
    a_ub[:k, :k], a_ub[k:, :k] = np.eye(k), -np.eye(k)
    a_ub[:k, k] = a_ub[k:, k] = -forces
    res = linprog(np.r_[np.zeros(k), 1.0, 0.0], A_ub=a_ub, b_ub=np.zeros(2 * k), A_eq=a_eq,
                  b_eq=b_eq, bounds=[(None, None)] * k + [(0, None), (low, high)],
                  method="highs")
    return float(res.x[k]) if res.status == 0 else math.inf


@pytest.mark.parametrize("model", [{}, {"element": "spring"}])
def test_the_symmetric_grasp_on_the_faces_needs_tan_theta(model):
    """paper-r070 at 0.2 N·m: mu = tan(theta) and |pin force| = (N_R + N_L) sin(theta), the
    pin pulling the object back into the jaws (-y), no moment."""
    res = simulate(R070, 0.2, payload_factor=0, **model)
    assert res.converged and res.n_contacts[0] > 0 and not res.corner_forces_n.any()
    theta = res.jaw_angles_rad[0]
    assert res.jaw_angles_rad[1] == pytest.approx(theta, abs=1e-9)
    assert res.required_friction == pytest.approx(math.tan(theta), rel=1e-6)
    push = sum(res.total_force_n) * math.sin(theta)
    assert np.linalg.norm(res.pin_force_n) == pytest.approx(push, rel=1e-6)
    assert res.pin_force_n[1] < 0 and abs(res.pin_force_n[0]) < 1e-9 * push
    assert abs(res.pin_moment_nm) < 1e-9 * push * R070.disk.radius_m
    assert res.holds(0.8) and not res.holds(0.7)


def test_a_grasp_turned_off_its_mirror_symmetry_needs_about_the_same_friction():
    """The required friction is continuous: an equilibrium a hair off the symmetric one (a hub
    moment, unequal patches) needs about tan(theta), not infinity, as the pressure on each face
    shifts a little between its contact points. Torques around a design whose grasp breaks the
    mirror symmetry, and its mirror-symmetric neighbours."""
    designs = DesignBounds().sample(np.random.default_rng(0), 2000, R070.disk)
    out = evaluate_designs(designs, R070.disk, payload_factors=0)
    grasp = out["converged"] & out["touching"].all(axis=1) & (out["n_contacts"] > 1).all(axis=1)
    turned = np.abs(out["jaw_angles_rad"][:, 0] - out["jaw_angles_rad"][:, 1])
    rows = np.flatnonzero(grasp & (turned > 1e-6) & (turned < math.radians(0.5)))
    assert rows.size >= 5
    need = out["required_friction"][rows]
    theta = out["jaw_angles_rad"][rows].mean(axis=1)
    assert np.all(np.isfinite(need))
    # (an asymmetric grasp is not the closed form's symmetric one: close to it, not on it)
    assert np.median(np.abs(need / np.tan(theta) - 1.0)) < 0.05
    sweep = np.repeat(designs[rows[:1]], 11, axis=0)
    sweep[:, 4] *= np.linspace(0.9, 1.1, 11)
    swept = evaluate_designs(sweep, R070.disk, payload_factors=0)
    assert np.all(np.isfinite(swept["required_friction"]))
    assert np.max(np.abs(np.diff(swept["required_friction"]))) < 0.05


def test_closed_forms_of_the_linear_program():
    centre = np.array([0.0, 0.1])
    faces = np.array([[-1.0, 0.0], [1.0, 0.0]])  # parallel faces: nothing to carry
    points = centre + np.array([[0.05, 0.0], [-0.05, 0.0]])
    out = holding_row(faces, points, [2.0, 2.0], centre, 0.07, [0.0, 0.0], 0.0)
    assert out[H_MU] == 0.0
    # one finger touching: its tangent cannot carry its own normal force
    out = holding_row(faces[:1], points[:1], [2.0], centre, 0.07, [2.0, 0.0], 0.0)
    assert out[H_MU] == math.inf
    # nothing touching, nothing carried
    assert holding_row(np.zeros((0, 2)), np.zeros((0, 2)), [], centre, 0.07, [0, 0], 0)[H_MU] == 0
    # inclined faces at theta, unequal forces on several points each: still tan(theta) when the
    # pin carries the net force and no moment
    theta = 0.3
    n_r = np.array([-math.cos(theta), math.sin(theta)])
    n_l = np.array([math.cos(theta), math.sin(theta)])
    axis_r = np.array([math.sin(theta), math.cos(theta)])
    axis_l = np.array([-math.sin(theta), math.cos(theta)])
    foot_r, foot_l = centre + 0.05 * -n_r, centre + 0.05 * -n_l
    normals = np.array([n_r, n_r, n_l, n_l])
    pts = np.array([foot_r, foot_r + 0.01 * axis_r, foot_l, foot_l - 0.01 * axis_l])
    forces = np.array([1.0, 2.0, 1.5, 1.5])
    pin = -(forces[:, None] * normals).sum(axis=0)
    out = holding_row(normals, pts, forces, centre, 0.07, pin, 0.0)
    assert out[H_MU] == pytest.approx(math.tan(theta), rel=1e-12)


def _solved(designs, disk):
    """The default member's batch solution of design rows (as evaluate_designs solves them)
    and its scene rows."""
    spec = resolve_model()
    rows = np.concatenate([Design.from_array(d).to_scene(disk).rows(d[4]) for d in designs])
    rows[:, S_SCALE] *= spec.scale  # the member's shipped calibration
    sol = solve_columns(rows, spec.n_triangles, phase_rad=math.pi / 2, n_rings=spec.n_rings,
                        element=spec.element)
    return spec, rows, sol


def test_corner_and_face_contacts_match_a_linear_program():
    """On random designs (some pressing with a finger's corner), the closed-form gauge is the
    linear program's optimum on the freed object's loaded normal forces (the released
    reaction moves them, :mod:`envs.model.loads`), and the pin force is minus the sum of the
    contact forces."""
    disk = R070.disk
    designs = DesignBounds().sample(np.random.default_rng(11), 120, disk)
    out = evaluate_designs(designs, disk, payload_factors=0)
    keep = np.flatnonzero(out["converged"] & out["touching"].all(axis=1))
    spec, rows, sol = _solved(designs[keep], disk)
    n = spec.n_triangles
    np.testing.assert_array_equal(sol.holding[:, H_MU], out["required_friction"][keep])
    prm = pack_params(rows, n, "van_gelder", math.pi / 2, spec.n_rings, spec.element)
    corners = checked = asymmetric = 0
    for b in range(rows.shape[0]):
        force_unit = rows[b, S_SCALE] * rows[b, S_YOUNG] * rows[b, S_THICKNESS] * rows[b, S_RADIUS]
        got = loaded_contacts(rows[b], prm[b], n, sol.state_scaled[b], sol.face_scaled[b],
                              sol.corner_forces_n[b] / force_unit,
                              sol.stop_torques_nm[b] / (force_unit * rows[b, S_RADIUS]))
        row = got["row"]
        # (the batch's compilation of the kernel and this call's may round a last bit apart)
        np.testing.assert_allclose(row, sol.holding[b], rtol=1e-12, atol=1e-15)
        normals, points, forces = got["normals"], got["points"], got["forces"]
        # the pin carries what the contact forces leave: minus their sum
        total = (forces[:, None] * normals).sum(axis=0)
        np.testing.assert_allclose(row[:2], -total, rtol=1e-12, atol=1e-12)
        corners += bool(sol.corner_totals_n[b].any())
        centre = np.array([0.0, rows[b, S_DISTANCE] + disk.radius_m])
        half = hertz_half_width(disk.radius_m, rows[b, S_THICKNESS],
                                rows[b, S_SCALE] * rows[b, S_YOUNG], rows[b, S_POISSON])
        # the freed object: its normal forces moved by the released reaction (a grasp whose
        # reaction pulls a contact off releases it, moving the others': not this closed form)
        loaded = forces + got["response"] @ -row[:3]
        if loaded.min() < 0.0:
            continue
        need = -(loaded[:, None] * normals).sum(axis=0)
        arm = points - centre
        need_moment = -np.sum(loaded * (arm[:, 0] * normals[:, 1] - arm[:, 1] * normals[:, 0]))
        press = loaded > 0.0
        mu_lp = _lp_friction(normals[press], points[press], loaded[press], centre,
                             disk.radius_m, need, need_moment, half)
        if mu_lp < 1e6:
            assert row[H_MU] == pytest.approx(mu_lp, rel=1e-6, abs=1e-9), b
            checked += 1
        else:  # single points that cannot balance the moment too (no pressure to shift)
            assert row[H_MU] > 1e6, b
        asymmetric += abs(sol.jaw_angles_rad[b, 0] - sol.jaw_angles_rad[b, 1]) > 1e-6
    assert checked >= 60 and corners >= 3 and asymmetric >= 3


def test_a_miss_carries_nothing_and_a_hold_is_a_converged_grasp_within_the_coefficient():
    disk = R070.disk
    designs = DesignBounds().sample(np.random.default_rng(2), 300, disk)
    designs[:20, 4] = 0.0  # no torque: the fingers stay open
    out = evaluate_designs(designs, disk, friction_coefficients=0.3, payload_factors=0)
    none = out["converged"] & ~out["touching"].any(axis=1)
    assert none[:20].all()
    assert np.all(out["required_friction"][none] == 0.0)
    assert np.all(out["pin_force_n"][none] == 0.0) and not out["holds"][none].any()
    grasp = out["converged"] & out["touching"].all(axis=1)
    np.testing.assert_array_equal(out["holds"], grasp & (out["required_friction"] <= 0.3))
    assert 0 < out["holds"].sum() < grasp.sum()


def test_the_point_spring_model_carries_what_the_fem_carries():
    """16 random designs on paper-r070: |pin force| and the required friction of the default
    model within 5 % (median) of the FEM's (measured: 0.3 % and 0.2 %)."""
    disk = R070.disk
    designs = DesignBounds().sample(np.random.default_rng(3), 16, disk)
    psm = evaluate_designs(designs, disk, payload_factors=0)
    fem = evaluate_designs(designs, disk, fidelity="fem", fem_rings=6, payload_factors=0)
    both = (psm["converged"] & fem["converged"] & psm["touching"].all(axis=1)
            & fem["touching"].all(axis=1) & np.isfinite(psm["required_friction"])
            & np.isfinite(fem["required_friction"]))
    assert both.sum() >= 10
    pin_p = np.linalg.norm(psm["pin_force_n"][both], axis=1)
    pin_f = np.linalg.norm(fem["pin_force_n"][both], axis=1)
    assert np.median(np.abs(pin_p - pin_f) / pin_f) <= 0.05
    mu_p, mu_f = psm["required_friction"][both], fem["required_friction"][both]
    assert np.median(np.abs(mu_p - mu_f) / mu_f) <= 0.05
    np.testing.assert_array_equal(psm["holds"][both], fem["holds"][both])


def test_an_optimizer_given_a_friction_returns_a_design_that_holds_with_it():
    from optim import DesignProblem, optimize

    for mu in (0.3, 0.15):
        # (the reaction alone: the subject is the friction an optimizer is given)
        result = optimize("cmaes", DesignProblem(R070.disk, friction_coefficient=mu,
                                                 payload_factor=0), budget=400, seed=0)
        m = result.best_metrics
        assert result.extra["grasp_found"] and m["holds"]
        assert m["required_friction"] <= mu and m["friction_coefficient"] == mu


@pytest.mark.parametrize("argv", [[], ["--object", "examples/objects/foam_disk.toml"]],
                         ids=["paper-r070", "foam-disk"])
def test_the_reported_optimum_is_the_fem_s_within_ten_percent(argv, tmp_path, capsys):
    """psm-grasp optimize --budget 1000 --verify-top 1 --payload-factor 0: the reward the run
    reports for its best design (the finer member's, after the finish) within 10 % (+ 1e-4)
    of the FEM's (the reaction alone)."""
    pytest.importorskip("skfem")
    from cli.main import main

    root = Path(__file__).resolve().parents[1]
    argv = [a if not a.endswith(".toml") else str(root / a) for a in argv]
    assert main(["optimize", "--budget", "1000", "--verify-top", "1", "--no-progress",
                 "--payload-factor", "0", "--out", str(tmp_path), *argv]) == 0
    report = json.loads((tmp_path / "verify.json").read_text())
    s = report["summary"]
    assert s["best_confirmed"]
    assert abs(s["reported_reward"] - s["fem_reward_of_reported"]) <= (
        0.10 * abs(s["fem_reward_of_reported"]) + 1e-4)
    assert s["reward_model"]["n_rings"] == 6


def _arc_grasp(nodes_per_finger, jitter_m=0.0, seed=0):
    """Two fingers each pressing the disk (r = 0.07 m, centre C) along an arc of 20 deg about
    -/+ 75 deg from the top with a parabolic pressure, resolved by ``nodes_per_finger``
    contacts of radial normals; the pin carries the net force. Returns the contact list, the
    pin force and each contact's run label (one run per finger)."""
    rng = np.random.default_rng(seed)
    centre, r = np.array([0.0, 0.1]), 0.07
    normals, points, forces, labels = [], [], [], []
    for side, mid in enumerate((math.radians(-15.0), math.radians(195.0))):
        phi = mid + math.radians(10.0) * np.linspace(-1, 1, nodes_per_finger + 2)[1:-1]
        weight = 1.0 - ((phi - mid) / math.radians(10.0)) ** 2
        f = 3.0 * weight / weight.sum()
        out = np.c_[np.cos(phi), np.sin(phi)]
        points.append(centre + (r + jitter_m * rng.standard_normal(phi.size))[:, None] * out)
        normals.append(-out)
        forces.append(f)
        labels.append(np.full(phi.size, side))
    normals, points, forces = np.concatenate(normals), np.concatenate(points), np.concatenate(
        forces)
    pin = -(forces[:, None] * normals).sum(axis=0)
    return centre, r, normals, points, forces, pin, np.concatenate(labels)


def test_a_run_on_a_curved_jaw_is_one_pressure_patch_at_any_mesh():
    # the same pressure on an arc, resolved by 3 to 48 contacts, a sideways payload to carry:
    # as one patch a run's pressure shift is its total force's, so the required friction
    # converges with the mesh; with each contact a face of its own (the flat-face rule) the
    # shift shrinks like 1/sqrt(nodes) and the friction keeps growing with the mesh
    half_width = hertz_half_width(0.07, 0.01, 1e5, 0.45)
    patch, single = {}, {}
    for nodes in (3, 12, 48):
        centre, r, normals, points, forces, pin, labels = _arc_grasp(nodes)
        patch[nodes] = holding_row(normals, points, forces, centre, r, pin, 0.0, 0.3,
                                   half_width, labels)[H_MU]
        single[nodes] = holding_row(normals, points, forces, centre, r, pin, 0.0, 0.3,
                                    half_width)[H_MU]
        # the reaction alone: the closed form of faces at 75 deg, the patches aside
        alone = holding_row(normals, points, forces, centre, r, pin, 0.0, 0.0, half_width,
                            labels)[H_MU]
        assert alone == pytest.approx(math.tan(math.radians(15.0)), rel=1e-9)
    assert abs(patch[48] - patch[12]) < 0.005 * patch[48]
    assert abs(patch[48] - patch[3]) < 0.02 * patch[48]
    assert single[48] - single[12] > 0.05
    assert all(single[k] > patch[k] for k in patch)


def test_a_flat_flank_jittered_by_the_gap_tolerance_keeps_the_exact_flank_s_answer():
    # a flat flank seen by the FEM: its nodes off the flank's line by the penalty's
    # penetration (~1e-7 m); as one patch of one normal they are one generator and the answer
    # is the exact line's. Two flat flanks cannot take the moment of a heavy sideways payload
    # (infinite friction); each node its own generator, the jitter opens a sliver facet whose
    # tiny support reads as a huge finite friction instead
    centre, r = np.array([0.0, 0.1]), 0.07
    theta = 0.2
    normals, points, forces, labels = [], [], [], []
    for side, sign in enumerate((1.0, -1.0)):
        n = np.array([-sign * math.cos(theta), math.sin(theta)])
        axis = np.array([sign * math.sin(theta), math.cos(theta)])
        foot = centre - r * n
        for k in range(6):
            normals.append(n)
            points.append(foot + (k - 2.5) * 0.002 * axis)
            forces.append(1.0 + 0.1 * k)
            labels.append(side)
    normals, points, forces = np.array(normals), np.array(points), np.array(forces)
    labels = np.array(labels)
    pin = -(forces[:, None] * normals).sum(axis=0)
    jittered = points + 1e-7 * np.random.default_rng(1).standard_normal(points.shape)
    half_width = hertz_half_width(r, 0.01, 1e6, 0.45)
    for payload in (0.1, 1.0):
        exact = holding_row(normals, points, forces, centre, r, pin, 0.0, payload, half_width,
                            labels)[H_MU]
        noisy = holding_row(normals, jittered, forces, centre, r, pin, 0.0, payload,
                            half_width, labels)[H_MU]
        assert noisy == exact
    assert exact == math.inf
    assert np.isfinite(holding_row(normals, jittered, forces, centre, r, pin, 0.0, 1.0,
                                   half_width)[H_MU])
    with pytest.raises(ValueError, match="patches"):
        holding_row(normals, points, forces, centre, r, pin, 0.0, 1.0, half_width, labels[:3])


def test_the_point_spring_runs_name_consecutive_pressed_points():
    # the labels of envs.solver.reaction: a run of consecutive pressed points (wrapping round
    # the contour's ends) shares its first point's label, per finger; a mouth edge joins the run
    # of a pressed end of its edge, else is a patch of its own; the bar's corners keep the
    # flat-face rule
    from envs.model.holding import NO_PATCH
    from envs.model.layout import C_FACE_TIP, C_MOUTH_ROOT, C_MOUTH_TIP
    from envs.solver.reaction import _corner_label, _run_label

    n = 10
    lam = np.zeros((2, n))
    lam[0, [0, 1, 2, 5, 6, 9]] = 1.0
    labels = [_run_label(lam, 0, i, n) for i in (9, 0, 1, 2, 5, 6)]
    assert labels == [9, 9, 9, 9, 5, 5]
    lam[1, :] = 1.0  # pressed all round: one run
    assert {_run_label(lam, 1, i, n) for i in range(n)} == {n}
    assert _corner_label(lam, 0, C_MOUTH_TIP, 2, 3, n) == 9  # the edge 2-3 ends the run 9..2
    assert _corner_label(lam, 0, C_MOUTH_ROOT, 4, 5, n) == 5
    free = _corner_label(lam, 0, C_MOUTH_TIP, 3, 4, n)
    assert free >= 2 * n and free != _corner_label(lam, 0, C_MOUTH_ROOT, 3, 4, n)
    assert _corner_label(lam, 0, C_FACE_TIP, 2, 3, n) == NO_PATCH
