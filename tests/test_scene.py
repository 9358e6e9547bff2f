"""Scene validation and presets."""

import math
from dataclasses import replace

import pytest

from envs.scene import PRESETS, Gripper, Scene, SoftDisk, closed_angle_rad


def test_presets_build_and_match_conventions():
    for name in PRESETS:
        scene = Scene.preset(name)
        assert scene.gripper.finger_length_m > 0
    g = Scene.preset("paper-r070").gripper
    assert g.finger_length_m == 0.2 and g.joint_offset_m == 0.025
    assert math.isclose(g.rest_angle_rad, math.radians(45))
    assert g.torsion_stiffness_nm_per_rad == 0.073
    assert Scene.preset("forceps-d").disk.radius_m == 0.0025
    assert Scene.preset("forceps-d").disk.stiffness_scale == 0.033


def test_rest_gap_about_one_millimetre_for_paper_disks():
    # docs/model.md: with Tables 1 and 2 the rest gap between disk and each face is ~1 mm
    for name in ("paper-r050", "paper-r070", "paper-r100"):
        s = Scene.preset(name)
        g, d = s.gripper, s.disk
        n = (-math.cos(g.rest_angle_rad), math.sin(g.rest_angle_rad))
        c = d.center_m
        gap = n[0] * (c[0] - g.joint_offset_m) + n[1] * c[1] - g.finger_width_m / 2 - d.radius_m
        assert 0.0005 < gap < 0.0015, (name, gap)


@pytest.mark.parametrize(
    "field,value",
    [
        ("finger_length_m", 0.0),
        ("finger_length_m", math.nan),
        ("rest_angle_rad", 0.0),
        ("rest_angle_rad", math.pi / 2),
        ("joint_offset_m", -0.01),
        ("finger_width_m", 0.0),
        ("finger_width_m", 0.5),
        ("torsion_stiffness_nm_per_rad", 0.0),
        ("torsion_stiffness_nm_per_rad", math.inf),
    ],
)
def test_gripper_rejects_bad_fields(field, value):
    g = Scene.preset("paper-r070").gripper
    with pytest.raises(ValueError, match=field):
        replace(g, **{field: value})


@pytest.mark.parametrize(
    "field,value",
    [
        ("radius_m", -0.05),
        ("radius_m", math.nan),
        ("youngs_modulus_pa", 0.0),
        ("poisson_ratio", 0.5),
        ("poisson_ratio", -1.0),
        ("thickness_m", 0.0),
        ("stiffness_scale", -1.0),
        ("contour_stiffness_ratio", 0.0),
        ("contour_stiffness_ratio", 1001.0),
        ("contour_stiffness_ratio", math.nan),
        ("distance_m", math.inf),
    ],
)
def test_disk_rejects_bad_fields(field, value):
    d = Scene.preset("paper-r070").disk
    with pytest.raises(ValueError, match=field):
        replace(d, **{field: value})


def test_contour_stiffness_ratio_defaults_to_one_and_names_its_range():
    d = Scene.preset("paper-r070").disk
    assert d.contour_stiffness_ratio == 1.0
    assert replace(d, contour_stiffness_ratio=1e3).contour_stiffness_ratio == 1e3
    with pytest.raises(ValueError, match=r"contour_stiffness_ratio.*\(0, 1000\]"):
        replace(d, contour_stiffness_ratio=-0.5)
    s = Scene.preset("paper-r070").with_changes(contour_stiffness_ratio=2.0)
    assert s.disk.contour_stiffness_ratio == 2.0


def test_scene_rejects_overlap_and_wide_fingers():
    s = Scene.preset("paper-r070")
    with pytest.raises(ValueError, match="overlap the disk"):
        Scene(s.gripper, replace(s.disk, distance_m=0.0))
    with pytest.raises(ValueError, match="finger_width_m"):
        Scene(replace(s.gripper, finger_width_m=0.15), s.disk)
    with pytest.raises(ValueError, match="unknown scene preset"):
        Scene.preset("paper-r999")


def test_short_fingers_are_allowed_but_reported():
    s = Scene.preset("paper-r070")
    short = Scene(s.gripper, replace(s.disk, distance_m=0.3))
    assert not short.reachable and "cannot reach" in short.warnings[0]
    assert s.reachable and s.warnings == ()


def test_closed_angle_puts_face_tip_on_axis():
    g = Gripper(0.2, 0.7, 0.025, 0.01, 0.073)
    t = closed_angle_rad(g)
    tip_x = g.joint_offset_m + g.finger_length_m * math.sin(t) - g.finger_width_m / 2 * math.cos(t)
    assert abs(tip_x) < 1e-15
    assert SoftDisk(0.05, 0.01).center_m[1] == pytest.approx(0.06)
