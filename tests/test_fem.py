"""Tests of the finite-element grasp reference ``envs.fem`` (coarse meshes, a few seconds each)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from envs import fem
from envs.scene import Scene, SoftDisk, closed_angle_rad

R070 = Scene.preset("paper-r070")
COARSE = R070.disk.radius_m / 6  # 216 elements


def _load_for_relative_compression(disk: SoftDisk, target: float, plane: str = "strain"):
    """Plate load per unit thickness giving a Hertz compression ``delta / r = target``."""
    r, e = disk.radius_m, disk.youngs_modulus_pa
    return brentq(
        lambda p: fem.hertz_line_compression(disk, p, plane) / r - target,
        1e-9 * e * r,
        1e-2 * e * r,
    )


def _hertz_half_width(disk: SoftDisk, load: float, plane: str = "strain") -> float:
    es = (
        disk.youngs_modulus_pa / (1 - disk.poisson_ratio**2)
        if plane == "strain"
        else (disk.youngs_modulus_pa)
    )
    return math.sqrt(4 * load * disk.radius_m / (math.pi * es))


def _onset_torque(scene: Scene) -> float:
    """Torque at which the undeformed disk first touches the faces (pure geometry)."""
    g, d = scene.gripper, scene.disk
    c = d.center_m

    def gap(theta: float) -> float:
        joint = np.array([g.joint_offset_m, 0.0])
        normal = np.array([-math.cos(theta), math.sin(theta)])
        return float(normal @ (c - joint)) - g.finger_width_m / 2 - d.radius_m

    theta_c = brentq(gap, 0.0, g.rest_angle_rad)
    return g.torsion_stiffness_nm_per_rad * (g.rest_angle_rad - theta_c)


# ----------------------------------------------------------------------------- material / kernels


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_material_stress_and_tangent_match_finite_differences(plane):
    rng = np.random.default_rng(0)
    h = 0.3 * rng.standard_normal((2, 2, 7))
    mu, lam = 1.3, 4.1
    w, p, a, ok = fem._neo_hookean(h, mu, lam, plane, True)
    assert ok
    step = 1e-6
    for i in range(2):
        for j in range(2):
            hp, hm = h.copy(), h.copy()
            hp[i, j] += step
            hm[i, j] -= step
            wp, pp, _, _ = fem._neo_hookean(hp, mu, lam, plane, True)
            wm, pm, _, _ = fem._neo_hookean(hm, mu, lam, plane, True)
            np.testing.assert_allclose((wp - wm) / (2 * step), p[i, j], atol=1e-8)
            np.testing.assert_allclose((pp - pm) / (2 * step), a[:, :, i, j], atol=1e-7)


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_material_linearises_to_small_strain_elasticity(plane):
    e_mod, nu = 2.0, 0.3
    mu, lam = fem._lame(e_mod, nu)
    eps = 1e-7

    def lateral_stress(e2):
        hmat = np.array([[eps, 0.0], [0.0, e2]])[:, :, None]
        return fem._neo_hookean(hmat, mu, lam, plane, True)[1][1, 1, 0]

    e2 = brentq(lateral_stress, -1e-6, 1e-6, xtol=1e-22)
    hmat = np.array([[eps, 0.0], [0.0, e2]])[:, :, None]
    axial = fem._neo_hookean(hmat, mu, lam, plane, True)[1][0, 0, 0]
    modulus = e_mod / (1 - nu**2) if plane == "strain" else e_mod
    assert axial / eps == pytest.approx(modulus, rel=1e-5)


def test_vectorised_assembly_matches_skfem_asm():
    disk = R070.disk
    base = fem._fan_mesh(disk.radius_m, 4, 6, math.pi / 2, 2 * math.pi)
    mesh = fem._quadratic_mesh(base, disk.radius_m, fem._arc_facets(base, disk.radius_m))
    for plane in ("strain", "stress"):
        body = fem._Body(mesh, disk.youngs_modulus_pa, disk.poisson_ratio, 0.01, plane)
        u = 1e-3 * np.random.default_rng(1).standard_normal(body.n)
        _, g, k = body.evaluate(u)
        g_ref, k_ref = body.evaluate_skfem(u)
        np.testing.assert_allclose(g, g_ref, rtol=0, atol=1e-12 * np.abs(g_ref).max())
        assert abs(k - k_ref).max() <= 1e-12 * abs(k_ref).max()


def solve_spied(scene: Scene, torques, mesh_size_m: float):
    """FEM grasps (no cache) and the system, state and load of the last Newton solve."""
    captured = {}
    original = fem.newton._newton

    def spy(system, x, load):
        out = original(system, x, load)
        captured.update(system=system, x=out[0], load=load)
        return out

    fem.newton._newton = spy
    try:
        results = fem.fem_grasp(scene, torques, mesh_size_m=mesh_size_m, cache=False)
    finally:
        fem.newton._newton = original
    return results, captured["system"], captured["x"], captured["load"]


def test_contact_tangent_matches_finite_differences_of_gradient():
    """Exact derivatives of the coupled (u, theta) system, faces and tip corners included."""
    _, system, x, load = solve_spied(Scene.preset("forceps-b"), [0.0004], 2e-3 / 6)
    _, tip = system.contact_forces(x, load)
    assert np.all(tip > 0)  # tip-corner contact is active at this state
    rng = np.random.default_rng(2)
    d = np.zeros_like(x)
    d[system.free] = 1e-3 * rng.standard_normal(system.free.size)
    d[-2:] = [1.0, 0.7]
    _, g, k = system.evaluate(x, load)
    step = 1e-9  # small: the corner penetration is only ~1e-9 m, the active set must not change
    gp = system.evaluate(x + step * d, load)[1]
    gm = system.evaluate(x - step * d, load)[1]
    fd = (gp - gm) / (2 * step)
    assert np.abs(fd - k @ d).max() <= 1e-6 * np.abs(k @ d).max()


# ------------------------------------------------------------------------------------ Hertz check


def test_plate_compression_matches_hertz_within_3_percent():
    disk = R070.disk
    load = _load_for_relative_compression(disk, 1e-3)
    delta = fem.fem_plate_compression(disk, load)
    hertz = fem.hertz_line_compression(disk, load)
    assert delta / disk.radius_m == pytest.approx(1e-3, rel=0.05)
    assert abs(delta / hertz - 1) < 0.03


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_plate_compression_coarse_mesh_within_8_percent(plane):
    disk = SoftDisk(0.05, 0.004, youngs_modulus_pa=2e6, poisson_ratio=0.3)
    load = _load_for_relative_compression(disk, 1e-3, plane)
    b = _hertz_half_width(disk, load, plane)
    delta = fem.fem_plate_compression(disk, load, mesh_size_m=4 * b, plane=plane)
    assert abs(delta / fem.hertz_line_compression(disk, load, plane) - 1) < 0.08


# ------------------------------------------------------------------------------------------ grasp


def test_free_closing_before_contact():
    g = R070.gripper
    onset = _onset_torque(R070)
    torques = [0.0, 0.25 * onset, 0.5 * onset, 0.95 * onset]
    results = fem.fem_grasp(R070, torques, mesh_size_m=COARSE, cache=False)
    for tq, res in zip(torques, results, strict=True):
        assert res.converged, res.message
        expected = g.rest_angle_rad - tq / g.torsion_stiffness_nm_per_rad
        assert res.jaw_angles_rad == pytest.approx((expected, expected), abs=1e-12)
        assert res.contact_forces_n == (0.0, 0.0)
        assert res.peak_strain == pytest.approx(0.0, abs=1e-12)


def test_contact_starts_at_the_geometric_onset_torque():
    onset = _onset_torque(R070)
    assert 0.002 < onset < 0.003  # rest gap ~1.4 mm over a lever of ~0.04 m/rad
    below, above = fem.fem_grasp(R070, [0.97 * onset, 1.2 * onset], mesh_size_m=COARSE, cache=False)
    assert below.contact_forces_n == (0.0, 0.0)
    assert min(above.contact_forces_n) > 0


def test_jaw_angles_and_contour_are_mirror_symmetric():
    results = fem.fem_grasp(R070, [0.05, 0.3], mesh_size_m=COARSE, cache=False)
    r = R070.disk.radius_m
    for res in results:
        assert res.converged, res.message
        right, left = res.jaw_angles_rad
        assert right == pytest.approx(left, abs=1e-10)
        assert res.contact_forces_n[0] == pytest.approx(res.contact_forces_n[1], rel=1e-8)
        contour = res.contour_m
        mirrored = contour[(-np.arange(contour.shape[0])) % contour.shape[0]]
        np.testing.assert_allclose(mirrored[:, 0], -contour[:, 0], atol=1e-9 * r)
        np.testing.assert_allclose(mirrored[:, 1], contour[:, 1], atol=1e-9 * r)


def test_jaw_angle_decreases_monotonically_with_torque():
    torques = np.linspace(0.05, 0.5, 6)
    results = fem.fem_grasp(R070, torques, mesh_size_m=COARSE, cache=False)
    assert all(res.converged for res in results)
    angles = np.array([res.jaw_angles_rad[0] for res in results])
    forces = np.array([res.contact_forces_n[0] for res in results])
    assert np.all(np.diff(angles) < 0)
    assert np.all(np.diff(forces) > 0)
    # the jaws stay far above the free-closing angle: the disk carries the torque
    g = R070.gripper
    assert np.all(angles > g.rest_angle_rad - torques / g.torsion_stiffness_nm_per_rad)


def test_result_fields():
    (res,) = fem.fem_grasp(R070, [0.2], mesh_size_m=COARSE, cache=False)
    assert res.converged and res.message == "converged"
    assert res.n_elements == 6 * 6**2
    assert res.mesh_size_m == pytest.approx(COARSE)
    assert res.contour_m.shape == (2 * 6 * 6, 2)  # rim vertices + midside nodes
    assert res.contour_m[0, 0] == pytest.approx(0.0, abs=1e-12)  # starts at the top
    assert res.contour_m[0, 1] > R070.disk.center_m[1]
    assert 0 < res.peak_strain < 0.5
    assert 0 < res.max_penetration_m < 1e-3 * R070.disk.radius_m
    assert res.newton_iterations > 0 and res.solve_time_s > 0
    assert res.hub_radius_m == pytest.approx(0.1 * R070.disk.radius_m)
    # moment balance on each finger: the contact forces carry the net closing torque
    g = R070.gripper
    net = 0.2 - g.torsion_stiffness_nm_per_rad * (g.rest_angle_rad - res.jaw_angles_rad[0])
    lever_min, lever_max = 0.03, g.finger_length_m
    assert lever_min * res.contact_forces_n[0] < net < lever_max * res.contact_forces_n[0]


def test_mesh_refinement_changes_jaw_angle_by_less_than_0p2_percent():
    coarse, fine = (
        fem.fem_grasp(R070, [0.05, 0.2], mesh_size_m=R070.disk.radius_m / rings, cache=False)
        for rings in (6, 12)
    )
    for a, b in zip(coarse, fine, strict=True):
        assert abs(b.jaw_angles_rad[0] / a.jaw_angles_rad[0] - 1) < 0.002
        assert abs(b.contact_forces_n[0] / a.contact_forces_n[0] - 1) < 0.01


@pytest.mark.slow
def test_mesh_convergence_default_mesh_within_0p2_percent():
    default, fine = (
        fem.fem_grasp(R070, [0.05, 0.2, 0.5], mesh_size_m=R070.disk.radius_m / rings, cache=False)
        for rings in (12, 24)
    )
    for a, b in zip(default, fine, strict=True):
        assert abs(b.jaw_angles_rad[0] / a.jaw_angles_rad[0] - 1) < 0.002
        assert abs(b.peak_strain / a.peak_strain - 1) < 0.05


def test_plane_stress_is_softer_than_plane_strain():
    strain, stress = (
        fem.fem_grasp(R070, [0.2], mesh_size_m=COARSE, plane=plane, cache=False)[0]
        for plane in ("strain", "stress")
    )
    assert stress.converged and stress.plane == "stress"
    assert stress.jaw_angles_rad[0] < strain.jaw_angles_rad[0]


def test_augmented_lagrangian_reduces_penetration():
    plain, al = (
        fem.fem_grasp(R070, [0.2], mesh_size_m=COARSE, al_iterations=n, cache=False)[0]
        for n in (0, 2)
    )
    assert al.converged
    assert al.max_penetration_m < 1e-2 * plain.max_penetration_m
    assert al.jaw_angles_rad[0] == pytest.approx(plain.jaw_angles_rad[0], abs=1e-3)


def test_tip_corner_contact_when_disk_is_beyond_the_tips():
    scene = Scene.preset("forceps-b")  # disk centre above the finger tips
    results = fem.fem_grasp(scene, [0.0004, 0.001], mesh_size_m=2e-3 / 6, cache=False)
    for res in results:
        assert res.converged, res.message
        assert res.tip_forces_n[0] > 0
        assert res.tip_forces_n[0] == pytest.approx(res.contact_forces_n[0], rel=1e-9)
    assert results[1].jaw_angles_rad[0] < results[0].jaw_angles_rad[0]


def test_unreachable_disk_closes_on_the_joint_stop():
    scene = Scene.preset("paper-r050").with_changes(distance_m=0.3)
    (res,) = fem.fem_grasp(scene, [0.2], mesh_size_m=0.05 / 4, cache=False)
    assert res.converged and "stop" in res.message
    assert res.jaw_angles_rad[0] == pytest.approx(closed_angle_rad(scene.gripper), abs=1e-3)
    assert res.contact_forces_n == (0.0, 0.0)


def test_failed_solve_is_reported_not_hidden(monkeypatch):
    monkeypatch.setattr(fem.newton, "_MAX_NEWTON", 0)
    monkeypatch.setattr(fem.newton, "_MAX_BISECTIONS", 2)
    results = fem.fem_grasp(R070, [0.1, 0.2], mesh_size_m=COARSE, cache=False)
    for res in results:
        assert not res.converged
        assert "failed" in res.message and "bisection" in res.message
        assert all(math.isnan(a) for a in res.jaw_angles_rad)
        assert np.all(np.isnan(res.contour_m))


# ----------------------------------------------------------------------------------------- inputs


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"mesh_size_m": 0.0}, "mesh_size_m"),
        ({"mesh_size_m": -1e-3}, "mesh_size_m"),
        ({"mesh_size_m": 0.07}, "mesh_size_m"),
        ({"mesh_size_m": math.nan}, "mesh_size_m"),
        ({"plane": "axisymmetric"}, "plane"),
        ({"torques_nm": [0.1, -0.1]}, "torques_nm"),
        ({"torques_nm": [math.inf]}, "torques_nm"),
        ({"torques_nm": [math.nan]}, "torques_nm"),
        ({"torques_nm": []}, "torques_nm"),
        ({"torques_nm": ["a"]}, "torques_nm"),
        ({"hub_radius_m": 0.0}, "hub_radius_m"),
        ({"hub_radius_m": 0.05}, "hub_radius_m"),
        ({"penalty_pa_per_m": -1.0}, "penalty_pa_per_m"),
        ({"al_iterations": -1}, "al_iterations"),
    ],
)
def test_fem_grasp_rejects_bad_inputs(kwargs, name):
    args = {"torques_nm": [0.1], "cache": False, **kwargs}
    with pytest.raises(ValueError, match=name):
        fem.fem_grasp(R070, **args)


def test_fem_grasp_rejects_non_scene():
    with pytest.raises(ValueError, match="scene"):
        fem.fem_grasp(R070.disk, [0.1], cache=False)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"load_n_per_m": 0.0}, "load_n_per_m"),
        ({"load_n_per_m": -1.0}, "load_n_per_m"),
        ({"load_n_per_m": math.nan}, "load_n_per_m"),
        ({"load_n_per_m": 1.0, "mesh_size_m": 0.0}, "mesh_size_m"),
        ({"load_n_per_m": 1.0, "mesh_size_m": 1.0}, "mesh_size_m"),
        ({"load_n_per_m": 1.0, "plane": "strian"}, "plane"),
    ],
)
def test_plate_compression_rejects_bad_inputs(kwargs, name):
    with pytest.raises(ValueError, match=name):
        fem.fem_plate_compression(R070.disk, **kwargs)


# ------------------------------------------------------------------------------------------ cache


def test_cache_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    torques = [0.05, 0.1]
    first = fem.fem_grasp(R070, torques, mesh_size_m=COARSE)
    files = list((tmp_path / "fem").glob("*.json"))
    assert len(files) == 1
    assert json.loads(files[0].read_text())["inputs"]["torques_nm"] == torques
    assert not any(res.from_cache for res in first)

    second = fem.fem_grasp(R070, torques, mesh_size_m=COARSE)
    assert all(res.from_cache for res in second)
    assert second == first
    for a, b in zip(first, second, strict=True):
        assert np.array_equal(a.contour_m, b.contour_m)
        assert a.jaw_angles_rad == b.jaw_angles_rad
        assert a.solve_time_s == b.solve_time_s

    # the calibration scale does not enter the FEM: same cache entry
    scaled = R070.with_changes(stiffness_scale=0.033)
    assert all(res.from_cache for res in fem.fem_grasp(scaled, torques, mesh_size_m=COARSE))
    # any physical change is a new entry
    fem.fem_grasp(R070, torques, mesh_size_m=COARSE, plane="stress")
    assert len(list((tmp_path / "fem").glob("*.json"))) == 2
    # cache=False neither reads nor writes
    fresh = fem.fem_grasp(R070, torques, mesh_size_m=COARSE, cache=False)
    assert not any(res.from_cache for res in fresh)


def test_corrupt_cache_file_is_recomputed(tmp_path, monkeypatch):
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    first = fem.fem_grasp(R070, [0.05], mesh_size_m=COARSE)
    (path,) = (tmp_path / "fem").glob("*.json")
    path.write_text("{not json")
    again = fem.fem_grasp(R070, [0.05], mesh_size_m=COARSE)
    assert not again[0].from_cache and again == first
