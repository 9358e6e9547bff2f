"""A contact that slides over a groove's rounded mouth edge (point-spring model).

Cradles on paper-r070 (5 mm deep, centred 100 mm along the 10 mm wide fingers, 0.3 N·m) press
the disk on the face beside the groove, the contact ending at the groove's mouth. As the
cradle's radius grows past R = 111.257 mm the last pressed contour point slides off the face
over the mouth edge and its force (1.13 N) passes to the edge's corner pressing the contour
edge beside it: the same equilibrium, continuous in R. Two constraints describe that touch
there; the solves used to fail at it, and the contact score stepped by 0.015 (the point's force
left the measure).
"""

from __future__ import annotations

import numpy as np
import pytest

from envs import Scene, evaluate_designs, simulate
from envs.batch_metrics import grooves_m
from envs.model.jaw import JAW_FIELDS
from envs.model.layout import C_MOUTH_ROOT
from envs.model.problem import SceneColumns
from envs.scene import DESIGN_FIELDS, Design
from envs.scoring import pressed_force_n

PAPER = Scene.preset("paper-r070")
SWITCH_M = 111.257e-3  # cradle radius where the touch passes to the mouth edge [m]
RADIUS_COLUMN = (DESIGN_FIELDS + JAW_FIELDS).index("jaw_bottom_radius_m")


def _designs(radii_m: np.ndarray) -> np.ndarray:
    """Cradle designs of the paper gripper, one row per cradle radius [m]."""
    g, disk = PAPER.gripper, PAPER.disk
    row = np.array([g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m,
                    0.3, disk.distance_m, 0.005, 0.11, 0.0, 0.1])
    designs = np.repeat(row[None], radii_m.size, axis=0)
    designs[:, RADIUS_COLUMN] = radii_m
    return designs


def _simulate(radius_m: float):
    return simulate(Design.from_array(_designs(np.array([radius_m]))[0]).to_scene(PAPER.disk),
                    0.3)


def test_the_solves_converge_where_the_touch_passes_to_the_mouth_edge():
    """Radii within 15 um of the switch: every solve converges (the independent check confirms
    the equilibrium), the jaw angle is the same on both sides to 1e-8 rad (one branch, no snap),
    and the switch lies between them: the mouth edge's corner carries the touch above it, a
    contour point's own contact below."""
    radii = SWITCH_M + np.linspace(-15e-6, 15e-6, 24)
    out = evaluate_designs(_designs(radii), PAPER.disk)
    assert out["converged"].all(), out["status"]
    angles = out["jaw_angles_rad"][:, 0]
    assert np.ptp(angles) < 1e-8
    below, above = _simulate(float(radii[0])), _simulate(float(radii[-1]))
    for res in (below, above):
        assert res.converged and res.kkt.passed
        assert res.kkt.force_residual_rel < 1e-8 and res.kkt.moment_residual_rel < 1e-8
    assert below.corner_forces_n[0, C_MOUTH_ROOT] == 0.0
    assert above.corner_forces_n[0, C_MOUTH_ROOT] == pytest.approx(1.13, abs=0.01)
    # the same total force on the finger either way
    assert below.contact_forces_n[0].sum() == pytest.approx(
        above.contact_forces_n[0].sum() + above.corner_forces_n[0].sum(), rel=1e-5)


def test_the_contact_score_is_continuous_where_the_touch_passes_to_the_mouth_edge():
    """60 cradle radii from 110.0 to 112.5 mm across the switch: the contact score's largest
    step between neighbours is within twice its mean step and a hundredth of one point's share
    ``1 / N`` (a whole point's force leaving the measure there was a step of 0.015, 0.6 / N).
    The score is continuous, not smooth: its slope in R grows about fivefold past the switch,
    where the point beside the mouth edge rises off the face as the corner's foot moves along
    the contour edge."""
    radii = np.linspace(110.0e-3, 112.5e-3, 60)
    out = evaluate_designs(_designs(radii), PAPER.disk)
    assert out["converged"].all(), out["status"]
    steps = np.abs(np.diff(out["contact_score"]))
    assert np.max(steps) < 2.0 * np.mean(steps)
    assert np.max(steps) < 0.01 / out["n_triangles"][0]


def test_a_corner_s_force_is_shared_by_its_edge_s_end_points():
    """The measure's point forces above the switch: the mouth edge's 1.13 N on a contour edge
    goes to that edge's two end points (nearly all to the one the corner's foot lies next to),
    and the points' forces sum to the finger's face and corner forces together."""
    res = _simulate(SWITCH_M + 50e-6)
    g = PAPER.gripper
    cols = SceneColumns.from_rows(Design.from_array(_designs(np.array([SWITCH_M + 50e-6]))[0])
                                  .to_scene(PAPER.disk).rows(0.3))
    packed, rounding = grooves_m(cols)
    n = res.points_m.shape[0]
    pressed = np.array([pressed_force_n(res.points_m, res.contact_forces_n[0],
                                        res.corner_edge_forces_n[0], i, 0, res.jaw_angles_rad[0],
                                        g.joint_offset_m, g.finger_length_m, g.finger_width_m,
                                        float(rounding[0]), packed[0], 0) for i in range(n)])
    edge = int(np.argmax(res.corner_edge_forces_n[0, C_MOUTH_ROOT]))
    assert 0 <= edge < n - 1  # (its end points edge and edge + 1, not wrapping round)
    force = res.corner_edge_forces_n[0, C_MOUTH_ROOT, edge]
    assert pressed.sum() == pytest.approx(res.contact_forces_n[0].sum()
                                          + res.corner_edge_forces_n[0].sum(), rel=1e-12)
    gained = pressed - res.contact_forces_n[0]
    assert np.flatnonzero(gained > 0.0).tolist() in ([edge], [edge, edge + 1], [edge + 1])
    assert gained[edge] + gained[edge + 1] == pytest.approx(force, rel=1e-12)
    assert max(gained[edge], gained[edge + 1]) > 0.99 * force
