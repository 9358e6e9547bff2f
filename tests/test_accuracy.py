"""Tests of ``envs.accuracy``: stiffness calibration and the choice of the number of triangles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from envs.accuracy import (
    CALIBRATION_FITS,
    ReferenceCurve,
    calibrate,
    choose_n_triangles,
    clear_n_cache,
    closing_errors,
    fem_reference,
    paper_heldout_cases,
    pareto_front,
    psm_curve,
)
from envs.scene import Scene

R050 = Scene.preset("paper-r050")
R070 = Scene.preset("paper-r070")
TORQUES = (0.1, 0.2, 0.3, 0.4)


@pytest.fixture(scope="module")
def synthetic_reference() -> ReferenceCurve:
    """PSM curve of the r = 0.07 disk with a known stiffness scale 2.5 (N = 20)."""
    curve = psm_curve(R070.with_changes(stiffness_scale=2.5), TORQUES, 20)
    assert all(curve.converged)
    return ReferenceCurve(curve.torques_nm, curve.jaw_angles_rad, source="psm s=2.5")


def test_calibration_recovers_a_known_scale(synthetic_reference):
    cal = calibrate(R070, synthetic_reference, 20)
    assert cal.scale == pytest.approx(2.5, rel=1e-3)
    assert cal.initial_scale == 1.0
    assert cal.rms_rel_error < 1e-4
    assert cal.max_rel_error < 1e-4
    assert cal.fit.n_failed == 0
    # the calibrated scene reproduces the reference on torques not used in the fit
    held = psm_curve(R070.with_changes(stiffness_scale=2.5), (0.15, 0.35), 20)
    rep = cal.errors_on(R070, (held.torques_nm, held.jaw_angles_rad))
    assert rep.max_rel_error < 1e-3
    assert rep.stiffness_scale == pytest.approx(cal.scale)


def test_calibration_accepts_a_pair_and_starts_anywhere(synthetic_reference):
    pair = (list(synthetic_reference.torques_nm), list(synthetic_reference.jaw_angles_rad))
    cal = calibrate(R070.with_changes(stiffness_scale=20.0), pair, 20)
    assert cal.scale == pytest.approx(2.5, rel=1e-3)


def test_calibration_against_a_coarse_fem_curve(tmp_path, monkeypatch):
    """Measured (N = 20, FEM r / 6, r = 0.05 disk, 0.1..0.5 N·m): s = 1.836, RMS 1.37 %,
    max 2.1 % relative closing-angle error; the bounds leave a small margin."""
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    ref = fem_reference(R050, (0.1, 0.2, 0.3, 0.4, 0.5), mesh_size_m=R050.disk.radius_m / 6)
    assert len(ref.torques_nm) == 5 and not ref.dropped_torques_nm
    cal = calibrate(R050, ref, 20)
    assert 1.7 < cal.scale < 2.0
    assert cal.rms_rel_error < 0.02
    assert cal.max_rel_error < 0.03
    # the reported errors are those of the calibrated model
    rep = closing_errors(cal.calibrated(R050), ref, 20)
    assert rep.rms_rel_error == pytest.approx(cal.rms_rel_error, rel=1e-6)
    # a physical check of the definition: closing angles are positive and grow with torque
    assert np.all(np.diff(rep.reference_closing_rad) > 0)


SCALE_2, RATIO_2 = 2.5, 0.4  # known parameters of the two-parameter synthetic reference


@pytest.fixture(scope="module")
def synthetic_two_parameter() -> tuple[ReferenceCurve, ReferenceCurve]:
    """PSM curves (fit torques, held-out torques) of the r = 0.07 disk with s = 2.5 and a
    contour stiffness ratio 0.4 (N = 20)."""
    sc = R070.with_changes(stiffness_scale=SCALE_2, contour_stiffness_ratio=RATIO_2)
    fit = psm_curve(sc, TORQUES, 20)
    held = psm_curve(sc, (0.15, 0.35), 20)
    assert all(fit.converged) and all(held.converged)
    return (ReferenceCurve(fit.torques_nm, fit.jaw_angles_rad, source="psm s=2.5 rho=0.4"),
            ReferenceCurve(held.torques_nm, held.jaw_angles_rad, source="psm held-out"))


def test_two_parameter_calibration_recovers_scale_and_ratio(synthetic_two_parameter):
    ref, held = synthetic_two_parameter
    # separate=True is the backward-compatible spelling of fit="scale_and_ratio"
    cal = calibrate(R070, ref, 20, separate=True, heldout={"held": (R070, held)})
    assert cal.fit_mode == "scale_and_ratio"
    assert cal.scale == pytest.approx(SCALE_2, rel=1e-3)
    assert cal.contour_stiffness_ratio == pytest.approx(RATIO_2, rel=1e-3)
    assert cal.initial_scale == 1.0 and cal.initial_contour_stiffness_ratio == 1.0
    assert cal.rms_rel_error < 1e-4 and cal.max_rel_error < 1e-4
    # the profile starts at the scene's ratio and the factors, each with its best scale; the
    # refinement can only improve on its best row
    assert [row[0] for row in cal.profile] == pytest.approx([0.1, 0.3, 1.0, 3.0, 10.0])
    assert cal.rms_rel_error <= min(row[2] for row in cal.profile)
    # held-out torques, both factors reused
    assert set(cal.heldout) == {"held"}
    assert cal.heldout["held"].max_rel_error < 1e-3
    assert cal.heldout["held"].contour_stiffness_ratio == pytest.approx(cal.contour_stiffness_ratio)
    assert cal.heldout_max_rel_error == cal.heldout["held"].max_rel_error
    calibrated = cal.calibrated(R050).disk
    assert (calibrated.stiffness_scale, calibrated.contour_stiffness_ratio) == (
        cal.scale, cal.contour_stiffness_ratio)
    d = cal.to_dict()
    assert d["contour_stiffness_ratio"] == cal.contour_stiffness_ratio
    assert d["heldout"]["held"]["max_rel_error"] == cal.heldout["held"].max_rel_error


def test_scale_only_fit_keeps_the_scene_ratio(synthetic_two_parameter):
    ref, _ = synthetic_two_parameter
    cal = calibrate(R070.with_changes(contour_stiffness_ratio=RATIO_2), ref, 20)
    assert cal.fit_mode == "scale" and cal.profile == ()
    assert cal.contour_stiffness_ratio == RATIO_2
    assert cal.scale == pytest.approx(SCALE_2, rel=1e-3)
    assert math.isnan(cal.heldout_rms_rel_error)  # no held-out case given


def test_calibration_options_are_validated(synthetic_reference):
    assert CALIBRATION_FITS == ("scale", "scale_and_ratio")
    with pytest.raises(ValueError, match="fit must be one of"):
        calibrate(R070, synthetic_reference, 20, fit="ratio")
    with pytest.raises(ValueError, match="ratio_bounds"):
        calibrate(R070, synthetic_reference, 20, fit="scale_and_ratio", ratio_bounds=(0, 10))
    with pytest.raises(ValueError, match="ratio_factors"):
        calibrate(R070, synthetic_reference, 20, fit="scale_and_ratio", ratio_factors=(-1.0,))
    with pytest.raises(ValueError, match="fitted_preset"):
        paper_heldout_cases("forceps-a")


def test_fem_reference_ignores_the_psm_calibration_factors(monkeypatch):
    """The FEM is physical: both PSM factors are reset so all calibrations share its cache."""
    import envs.fem

    seen = []

    def fake_fem_grasp(scene, torques, **kwargs):
        seen.append(scene.disk)
        return []

    monkeypatch.setattr(envs.fem, "fem_grasp", fake_fem_grasp)
    with pytest.raises(ValueError, match="at least one"):
        fem_reference(R070.with_changes(stiffness_scale=3.0, contour_stiffness_ratio=0.2))
    assert seen[0] == R070.disk


@pytest.mark.slow
def test_two_parameter_fit_is_no_worse_on_a_coarse_fem_curve(tmp_path, monkeypatch):
    """Measured (N = 20, FEM r / 6, r = 0.05 disk, 0.1..0.5 N·m): see the README."""
    monkeypatch.setenv("PSM_GRASP_CACHE", str(tmp_path))
    ref = fem_reference(R050, (0.1, 0.2, 0.3, 0.4, 0.5), mesh_size_m=R050.disk.radius_m / 6)
    one = calibrate(R050, ref, 20)
    two = calibrate(R050, ref, 20, fit="scale_and_ratio")
    # the profile contains the scene's ratio (1) with its best scale, so the two-parameter fit
    # is at least as good as the scale-only fit up to the latter's finer tolerance
    assert two.rms_rel_error <= one.rms_rel_error * (1 + 1e-3)
    assert 0.01 <= two.contour_stiffness_ratio <= 100


def test_reference_curve_validation():
    with pytest.raises(ValueError, match="same length"):
        ReferenceCurve((0.1, 0.2), (0.7,))
    with pytest.raises(ValueError, match="finite"):
        ReferenceCurve((0.1,), (math.nan,))
    with pytest.raises(ValueError, match="positive closing"):
        calibrate(R070, ((0.1,), (R070.gripper.rest_angle_rad + 0.01,)), 20)


def test_choose_n_triangles_is_within_tolerance_and_minimal():
    clear_n_cache()
    cands = (8, 12, 16, 20, 24, 32, 40)
    tol = 0.1
    choice = choose_n_triangles(R070, (0.1, 0.3), tol, candidates=cands, reference_n=60,
                                n_torques=2)
    assert choice.within_tolerance
    n = choice.n_triangles
    assert n in cands
    # independent check of the chosen N against the reference
    th0 = R070.gripper.rest_angle_rad
    ref = psm_curve(R070, choice.torques_nm, 60)
    got = psm_curve(R070, choice.torques_nm, n)
    assert all(ref.converged) and all(got.converged)
    c_ref = th0 - np.asarray(ref.jaw_angles_rad)
    c_got = th0 - np.asarray(got.jaw_angles_rad)
    assert np.max(np.abs(c_got / c_ref - 1)) <= tol
    assert np.max(np.abs(np.asarray(got.peak_strains) / np.asarray(ref.peak_strains) - 1)) <= tol
    # minimal: the candidate one step smaller violates the tolerance
    k = cands.index(n)
    if k > 0:
        smaller = choice.row(cands[k - 1])
        assert not smaller.within_tolerance
        assert (smaller.n_failed > 0 or smaller.closing_rel_error > tol
                or smaller.strain_rel_error > tol)
    assert choice.time_per_solve_s > 0 and choice.reference_time_per_solve_s > 0
    # cached per scene and arguments
    again = choose_n_triangles(R070, (0.1, 0.3), tol, candidates=cands, reference_n=60,
                               n_torques=2)
    assert again is choice


def test_choose_n_triangles_validation():
    with pytest.raises(ValueError, match="torque_range"):
        choose_n_triangles(R070, (0.3, 0.1))
    with pytest.raises(ValueError, match="reference_n"):
        choose_n_triangles(R070, (0.1, 0.3), candidates=(8, 200), reference_n=160)
    with pytest.raises(ValueError, match="tolerance"):
        choose_n_triangles(R070, (0.1, 0.3), 0.0)


def test_pareto_front():
    costs = [1.0, 2.0, 3.0, 0.5, 2.5, math.nan]
    errors = [0.5, 0.2, 0.3, 0.9, 0.2, 0.0]
    assert pareto_front(costs, errors) == [3, 0, 1]
