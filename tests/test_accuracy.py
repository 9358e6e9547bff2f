"""Tests of ``envs.accuracy``: stiffness calibration and the choice of the number of triangles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from envs.accuracy import (
    ReferenceCurve,
    calibrate,
    choose_n_triangles,
    clear_n_cache,
    closing_errors,
    fem_reference,
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


def test_separate_scales_are_not_supported(synthetic_reference):
    with pytest.raises(NotImplementedError, match="single stiffness_scale"):
        calibrate(R070, synthetic_reference, 20, separate=True)


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
