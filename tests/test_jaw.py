"""Jaw profiles: the gap to a grooved finger (envs.model.jaw) against geometry worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from envs.model.jaw import (
    N_GROOVE,
    STRAIGHT,
    JawProfile,
    jaw_gap,
    jaws_of_row,
    pack_groove,
)
from envs.model.problem import REST_JAW, rest_codes
from envs.scene import Gripper, Scene

RHO = 1e-3
LENGTH, HALF_WIDTH = 4.0, 0.2


def _gap(jaw: JawProfile):
    groove = np.zeros(N_GROOVE)
    pack_groove(jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m, RHO,
                1.0, groove, 0)
    return lambda s, m: jaw_gap(s, m, LENGTH, HALF_WIDTH, RHO, groove, 0)


CRADLE = JawProfile.cradle(1.0, 0.15, 2.0)
VEE = JawProfile.vee(math.radians(90.0), 0.15, 2.0)
ROUNDED = JawProfile(0.2, 0.3, math.radians(60.0), 2.0)


def test_kinds_and_mouths():
    assert STRAIGHT.kind == "straight" and CRADLE.kind == "cradle" and VEE.kind == "vee"
    assert ROUNDED.kind == "rounded vee"
    # a circular segment of depth h in a circle of radius R: half-chord sqrt(2 R h - h^2)
    assert CRADLE.mouth_half_width_m == pytest.approx(math.sqrt(2 * 0.15 - 0.15 ** 2))
    # a right-angled V of depth h: half-width h
    assert VEE.mouth_half_width_m == pytest.approx(0.15)


@pytest.mark.parametrize("angle_deg", [0.0, 15.0, 30.0])
def test_cradle_gap_is_distance_to_its_arc(angle_deg):
    """A point inside the cradle's circle, 0.1 from its arc, has gap 0.1; its gap gradient
    points from the arc's centre's side toward the point (the arc's inward normal)."""
    gap = _gap(CRADLE)
    centre_m = HALF_WIDTH - (CRADLE.depth_m - CRADLE.bottom_radius_m)
    a = math.radians(angle_deg)
    s, m = 2.0 + 0.9 * math.sin(a), centre_m - 0.9 * math.cos(a)
    g, g_s, g_m, *_ = gap(s, m)
    assert g == pytest.approx(0.1, abs=1e-12)
    assert (g_s, g_m) == pytest.approx((-math.sin(a), math.cos(a)), abs=1e-12)


@pytest.mark.parametrize("height", [0.0, 0.05, 0.1])
def test_vee_gap_on_its_axis(height):
    """A point on a right-angled V's axis, ``t`` above the face, is ``(t + h) sin 45`` from
    both flanks."""
    g = _gap(VEE)(2.0, HALF_WIDTH + height)[0]
    assert g == pytest.approx((height + VEE.depth_m) * math.sin(math.pi / 4), abs=1e-12)


def test_depth_zero_is_the_bar():
    """Beside the face, at the tip and at a rounded corner the straight profile's gap is the
    distance to the bar's core ``[0, l] x [-(w/2 - rho), w/2 - rho]`` grown by ``rho``."""
    gap = _gap(STRAIGHT)
    assert gap(2.0, HALF_WIDTH + 0.3)[0] == pytest.approx(0.3)
    assert gap(LENGTH + 0.2, 0.0)[0] == pytest.approx(0.2 - RHO)
    corner = (LENGTH, HALF_WIDTH - RHO)
    assert gap(corner[0] + 0.3, corner[1] + 0.4)[0] == pytest.approx(0.5 - RHO)


@pytest.mark.parametrize("jaw", [CRADLE, VEE, ROUNDED], ids=["cradle", "vee", "rounded"])
def test_gap_is_continuous_and_derivatives_match_differences(jaw):
    """Along a line across the mouth the gap moves no more than the step (a 1-Lipschitz
    distance); its gradient is a unit vector and matches central differences, as does the
    Hessian away from the few kinks (the V's axis, where the nearest flank changes)."""
    gap = _gap(jaw)
    for level in (HALF_WIDTH + 0.01, HALF_WIDTH - 0.05):
        s = np.linspace(0.5, 3.5, 6001)
        values = np.array([gap(x, level)[0] for x in s])
        assert np.max(np.abs(np.diff(values))) <= (s[1] - s[0]) * (1 + 1e-9)
    rng = np.random.default_rng(4)
    eps, bad = 1e-6, 0
    for _ in range(1500):
        s, m = rng.uniform(1.0, 3.0), rng.uniform(0.0, 0.6)
        g, g_s, g_m, g_ss, g_sm, g_mm = gap(s, m)
        if g < 0.0 or abs(s - 2.0) < 1e-4:
            continue
        assert math.hypot(g_s, g_m) == pytest.approx(1.0, abs=1e-9)
        fd_s = (gap(s + eps, m)[0] - gap(s - eps, m)[0]) / (2 * eps)
        fd_m = (gap(s, m + eps)[0] - gap(s, m - eps)[0]) / (2 * eps)
        assert (fd_s, fd_m) == pytest.approx((g_s, g_m), abs=1e-5)
        fd_ss = (gap(s + eps, m)[1] - gap(s - eps, m)[1]) / (2 * eps)
        fd_mm = (gap(s, m + eps)[2] - gap(s, m - eps)[2]) / (2 * eps)
        bad += abs(fd_ss - g_ss) + abs(fd_mm - g_mm) > 1e-3 * (1 + abs(g_ss) + abs(g_mm))
    assert bad <= 3  # a sample within eps of a kink between two surface pieces


def test_profiles_refused_with_named_ranges():
    with pytest.raises(ValueError, match="depth_m"):
        JawProfile(-1.0)
    with pytest.raises(ValueError, match="undercut"):
        JawProfile.cradle(0.01, 0.02, 0.1)
    with pytest.raises(ValueError, match="opening_angle_rad"):
        JawProfile.vee(math.radians(175.0), 0.01, 0.1)
    with pytest.raises(ValueError, match="finger_width_m"):
        Gripper(0.2, 0.7, 0.025, 0.01, 0.07, jaw=JawProfile.cradle(0.07, 0.009, 0.1))
    with pytest.raises(ValueError, match="position_m"):
        Gripper(0.2, 0.7, 0.025, 0.01, 0.07, jaw=JawProfile.cradle(0.07, 0.005, 0.01))


def test_scene_rows_carry_both_jaws_and_rest_codes_check_them():
    base = Scene.preset("paper-r070")
    left = JawProfile.vee(math.radians(90.0), 0.004, 0.12)
    grip = Gripper(0.2, base.gripper.rest_angle_rad, 0.025, 0.01, 0.073,
                   jaw=JawProfile.cradle(0.07, 0.004, 0.1), left_jaw=left)
    scene = Scene(grip, base.disk)
    cols = scene.columns(0.1)
    assert cols.jaw_depth_m.tolist() == [[0.004, 0.004]]
    assert cols.jaw_opening_angle_rad[0, 1] == pytest.approx(math.radians(90.0))
    assert rest_codes(cols.rows())[0] == 0
    bad = cols.rows()
    bad[0, -1] = 0.199  # the left groove's mouth beyond the tip
    assert rest_codes(bad)[0] == REST_JAW


def test_design_rows_of_every_width():
    assert jaws_of_row(np.zeros(6)) == (STRAIGHT, None)
    right, left = jaws_of_row([0.2, 0.7, 0.02, 0.01, 0.1, 0.01, 0.004, 0.07, 0.0, 0.1])
    assert right == JawProfile.cradle(0.07, 0.004, 0.1) and left is None
    with pytest.raises(ValueError, match="design row"):
        jaws_of_row(np.zeros(7))
