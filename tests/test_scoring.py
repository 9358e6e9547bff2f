"""The compiled metric and reward loops (envs.scoring) against the documented formulas.

The formulas of :class:`envs.evaluate.RewardWeights` and :func:`envs.evaluate_designs` are
written here again in numpy over the returned columns, as an independent reading of the
docstrings, on a batch that mixes converged, failed and invalid designs and two N groups.
"""

from __future__ import annotations

import numpy as np
import pytest

from envs import DesignBounds, RewardWeights, Scene, SoftDisk, evaluate_designs, simulate
from envs.evaluate import grip_share
from envs.model.contact_width import hertz_arc_coefficient
from envs.model.problem import (
    REST_BEHIND_FACE,
    REST_GRIPPER,
    REST_NOT_FINITE,
    REST_OK,
    REST_OVERLAP,
    REST_WIDTH,
    SceneColumns,
    rest_codes,
)
from envs.scene import Design

from .contact_reference import face_extent_shares


@pytest.fixture(scope="module")
def batch():
    disk = SoftDisk(0.07, 0.0, density_kg_m3=50.0)  # (the paper's foam)
    rng = np.random.default_rng(5)
    designs = DesignBounds().sample(rng, 160, disk)
    designs[::7, 5] = -0.05  # some overlap the disk at rest
    designs[3, 0] = np.nan
    n = np.where(np.arange(designs.shape[0]) % 2 == 0, 12, 20)
    weights = RewardWeights(contact=1.3, deform=0.2, miss=0.4, gap=0.7, invalid=3.5,
                            violation=0.8, fail=2.9, contact_cap=0.4, deform_cap=3.0, slip=0.6)
    # friction per row: some grasps hold, some would slip
    mu = np.where(np.arange(designs.shape[0]) % 3 == 0, 0.2, 0.6)
    out = evaluate_designs(designs, disk, n_triangles=n, element="spring", weights=weights,
                           friction_coefficients=mu)
    return designs, disk, n, weights, out


def test_batch_mixes_outcomes(batch):
    *_, out = batch
    assert (~out["valid_at_rest"]).sum() >= 20
    assert out["converged"].sum() >= 100


def test_reward_terms_follow_their_formulas(batch):
    designs, disk, n, w, out = batch
    ok = out["converged"]
    valid = out["valid_at_rest"]
    missing = (~out["touching"]).sum(axis=1)
    need, mu = out["required_friction"], out["friction_coefficient"]
    hold = ok & (missing == 0) & (need <= mu)
    slip = ok & (missing == 0) & ~hold
    miss_row = ok & (missing > 0)
    floor = w.deform * w.deform_cap
    assert hold.sum() >= 20 and slip.sum() >= 20 and miss_row.sum() >= 5
    np.testing.assert_array_equal(out["holds"], hold)
    q = out["peak_compression"] / out["strain_limit"]
    within = hold & (q <= 1.0)
    contact = np.where(within, w.contact * np.minimum(out["contact_score"], w.contact_cap), 0.0)
    crush = -w.deform - (floor - w.deform) * (q - 1.0) / q  # x / (1 + x) with x = q - 1
    deform = np.where(within, -w.deform * q, np.where(hold, crush, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        excess = need / mu - 1.0
        bounded = np.where(np.isfinite(excess), excess / (1.0 + excess), 1.0)
    slipping = np.where(slip, -floor - w.slip * bounded, 0.0)
    miss = np.where(miss_row, -(floor + w.slip) - w.miss * missing, 0.0)
    g = out["finger_gap_m"].max(axis=1) / disk.radius_m
    gap = np.where(miss_row, -w.gap * g / (1 + g), 0.0)
    invalid = np.where(valid, 0.0, -w.invalid - w.violation * out["rest_violation"])
    fail = np.where(valid & ~ok, -w.fail, 0.0)
    for key, ref in (("reward_contact", contact), ("reward_deform", deform),
                     ("penalty_slip", slipping), ("penalty_miss", miss), ("penalty_gap", gap),
                     ("penalty_invalid", invalid), ("penalty_fail", fail)):
        np.testing.assert_allclose(out[key], ref, rtol=0, atol=1e-15, err_msg=key)
    np.testing.assert_allclose(out["reward"],
                               contact + deform + slipping + miss + gap + invalid + fail,
                               rtol=0, atol=1e-15)
    # the tiers: every hold above every slip above every miss above every failure and every
    # invalid design
    tiers = [out["reward"][m] for m in (hold, slip, miss_row, valid & ~ok, ~valid)]
    for upper, lower in zip(tiers, tiers[1:], strict=False):
        if upper.size and lower.size:
            assert upper.min() > lower.max() or (upper.min() == lower.max() == -w.fail)


def test_contact_score_is_grip_share_times_contact_fraction(batch):
    """Each face's share of the contour is the contact's extent interpolated between its
    points, at most the Hertz width of its face force (both read from simulate's answer for the
    same design, row by row, and the definition written again in numpy)."""
    designs, disk, n, w, out = batch
    ok = out["converged"]
    k = hertz_arc_coefficient(disk.radius_m, disk.thickness_m, disk.youngs_modulus_pa,
                              disk.poisson_ratio, disk.radius_m)
    capped = uncapped = 0
    for i in np.flatnonzero(ok):
        scene = Design.from_array(designs[i]).to_scene(disk)
        res = simulate(scene, float(designs[i, 4]), int(n[i]), element="spring")
        face = res.contact_forces_n.sum(axis=1)
        extents = face_extent_shares(res.points_m, res.contact_forces_n, scene.gripper,
                                     res.jaw_angles_rad, disk)
        # the extent lies between the pressed points' span less one spacing and plus one
        nodes = out["n_contacts"][i] / n[i]
        assert np.all((extents >= nodes - 1 / n[i] - 1e-12) & (extents <= nodes + 1 / n[i]))
        shares = np.minimum(extents, k * np.sqrt(face))
        capped += int(np.sum(shares < extents))
        uncapped += int(np.sum((shares == extents) & (extents > 0)))
        assert out["contact_score"][i] == pytest.approx(out["grip_share"][i] * shares.sum(),
                                                        rel=1e-9, abs=1e-15)
    # the extent is an outer estimate: the cap binds on most faces, the extent on light touches
    assert capped > 100 and uncapped >= 3
    assert np.all(out["n_contacts"][~ok] == 0) and np.all(out["contact_score"][~ok] == 0.0)
    # the share from its definition: (T - k_f (theta_0 - theta) - M_stop) / T, clipped, min
    cols = SceneColumns(*(np.full(3, v) for v in (0.1, 0.6, 0.01, 0.01, 0.07, 0.07, 0.0,
                                                  1e5, 0.45, 0.01, 1.0, 1.0, 1.0)),
                        torque_nm=np.array([0.2, 0.2, 0.0]), offset_x_m=np.zeros(3))
    jaw = np.array([[0.5, 0.4], [0.6, 0.6], [0.5, 0.5]])
    stop = np.array([[0.0, 0.01], [0.0, 0.0], [0.0, 0.0]])
    ref = np.clip((0.2 - 0.07 * (0.6 - jaw[:2]) - stop[:2]) / 0.2, 0, 1).min(axis=1)
    np.testing.assert_allclose(grip_share(cols, jaw, stop), [*ref, 0.0], rtol=0, atol=1e-15)
    # the compiled loop has no bounds checks: a short array is refused before it runs
    with pytest.raises(ValueError, match=r"jaw_angles_rad must have shape \(3, 2\)"):
        grip_share(cols, jaw[:2], stop)
    with pytest.raises(ValueError, match="stop_torques_nm"):
        grip_share(cols, jaw, stop.ravel())


def test_rest_codes_name_the_first_failed_test():
    base = Scene.preset("paper-r070").rows(0.2)[0]
    cases = (  # (column, value, code)
        (None, None, REST_OK),
        (6, np.inf, REST_NOT_FINITE),
        (13, -1.0, REST_GRIPPER),  # negative torque
        (3, 0.2, REST_GRIPPER),  # finger as wide as it is long
        (3, 0.15, REST_WIDTH),  # wider than the disk
        (6, -0.2, REST_BEHIND_FACE),  # the disk centre behind the gripping faces
        (1, 0.05, REST_OVERLAP),  # fingers nearly closed at rest
    )
    rows = np.tile(base, (len(cases), 1))
    for k, (col, value, _) in enumerate(cases):
        if col is not None:
            rows[k, col] = value
    assert list(rest_codes(rows)) == [code for *_, code in cases]
    # the columns of the same scenes give the same codes
    assert list(rest_codes(SceneColumns.from_rows(rows))) == [code for *_, code in cases]
