"""Shaped jaws on the drawings and the build sheet: each finger's groove drawn with its own
profile, measured back from the polygon against hand-worked geometry; the sheet, its CSV, its
drawing and its DXF state the profile in millimetres; a design without jaw fields keeps today's
sheet."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from envs.model.geometry import finger_frame
from envs.model.jaw import JAW_FIELDS, LEFT_JAW_FIELDS, STRAIGHT, JawProfile
from envs.render import draw_design, draw_grasp, finger_polygon
from envs.scene import Gripper, Scene
from optim.build_sheet import build_sheet, drawing_figure, jaw_rows, write_build_sheet

L, W, ANGLE, OFFSET = 0.05, 0.006, 0.4, 0.003  # finger length, width, rest angle, joint [SI]
H, R_CRADLE, A = 0.003, 0.012, 0.03  # cradle depth, radius, position [m]
CRADLE = JawProfile.cradle(R_CRADLE, H, A)
VEE = JawProfile.vee(math.radians(90.0), H, 0.025)
ROUNDED = JawProfile(0.004, 0.002, math.radians(70.0), A)  # flanks carry the bottom arc
OBJ = {"name": "test disk", "radius_m": 0.012, "thickness_m": 0.024, "youngs_modulus_pa": 1.5e5,
       "poisson_ratio": 0.45, "strain_limit": 0.1, "friction_coefficient": 0.5,
       "torsion_stiffness_nm_per_rad": 0.004}
DESIGN = {"finger_length_m": L, "rest_angle_rad": ANGLE, "joint_offset_m": OFFSET,
          "finger_width_m": W, "torque_nm": 0.01, "distance_m": 0.02}


def _fields(jaw: JawProfile, names=JAW_FIELDS) -> dict[str, float]:
    values = (jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad, jaw.position_m)
    return dict(zip(names, values, strict=True))


def _finger_coordinates(points: np.ndarray, side: int, angle: float = ANGLE) -> np.ndarray:
    """Drawing points as (s, m) in a finger's frame, by the model's own frame (not the
    drawing's)."""
    gripper = Gripper(L, ANGLE, OFFSET, W, 1.0)
    joint, axis, normal = finger_frame(gripper, side, angle)
    rel = np.asarray(points) - joint
    return np.column_stack([rel @ axis, rel @ normal])


def _groove(points_sm: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Depth, mouth width and the cutout's points of a finger polygon in finger coordinates:
    the points off the bar's four sides."""
    s, m = points_sm.T
    eps = 1e-9
    on_face = np.isclose(m, W / 2, atol=eps) & (s > eps) & (s < L - eps)
    inner = (m < W / 2 - eps) & (m > -W / 2 + eps) & (s > eps) & (s < L - eps)
    mouth = s[on_face].max() - s[on_face].min()
    return W / 2 - m[inner].min(), mouth, points_sm[inner]


def _shoelace(poly: np.ndarray) -> float:
    x, y = poly.T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


# --- the fingers' polygons -------------------------------------------------------------------


@pytest.mark.parametrize("side", [0, 1])
def test_a_cradle_is_cut_to_its_depth_mouth_and_arc(side):
    poly = finger_polygon(L, ANGLE, OFFSET, W, side, CRADLE)
    depth, mouth, cut = _groove(_finger_coordinates(poly, side))
    assert depth == pytest.approx(H, rel=1e-9)
    # a chord of the circle at depth h below its lowest point: 2 sqrt(h (2R - h))
    assert mouth == pytest.approx(2 * math.sqrt(H * (2 * R_CRADLE - H)), rel=1e-9)
    centre = np.array([A, W / 2 + R_CRADLE - H])
    np.testing.assert_allclose(np.hypot(*(cut - centre).T), R_CRADLE, rtol=1e-9)
    # the bar less the circular segment; the arc is sampled by chords of at most 5 deg, which
    # leave out R^2 d^3 / 12 each (d the chord's angle): 0.34 % of this segment
    segment = R_CRADLE**2 * math.acos((R_CRADLE - H) / R_CRADLE) \
        - (R_CRADLE - H) * math.sqrt(2 * R_CRADLE * H - H * H)
    assert _shoelace(poly) == pytest.approx(L * W - segment, abs=5e-3 * segment)


@pytest.mark.parametrize("side", [0, 1])
def test_a_vee_and_a_rounded_vee_have_their_flanks(side):
    depth, mouth, cut = _groove(_finger_coordinates(finger_polygon(L, ANGLE, OFFSET, W, side,
                                                                   VEE), side))
    assert depth == pytest.approx(H, rel=1e-9)
    assert mouth == pytest.approx(2 * H * math.tan(math.radians(45.0)), rel=1e-9)  # 2 h tan 45
    np.testing.assert_allclose(cut, [[0.025, W / 2 - H]], atol=1e-12)  # one sharp bottom
    # a rounded V: the flanks tangent to the bottom arc at half the opening off the depth
    h, rb, beta = ROUNDED.depth_m, ROUNDED.bottom_radius_m, math.radians(35.0)
    depth, mouth, cut = _groove(_finger_coordinates(finger_polygon(L, ANGLE, OFFSET, W, side,
                                                                   ROUNDED), side))
    assert depth == pytest.approx(h, rel=1e-9)
    # the flank's line cos(b) |u| + sin(b) (v - (h - R)) = R met at the face v = 0
    assert mouth == pytest.approx(2 * (rb + (h - rb) * math.sin(beta)) / math.cos(beta),
                                  rel=1e-9)
    arc = cut[cut[:, 1] < W / 2 - (h - rb) - rb * math.sin(beta) + 1e-12]
    assert len(arc) >= 3
    np.testing.assert_allclose(np.hypot(*(arc - [A, W / 2 - (h - rb)]).T), rb, rtol=1e-9)


def test_a_straight_jaw_draws_todays_bar():
    for side in (0, 1):
        joint, axis, normal = finger_frame(Gripper(L, ANGLE, OFFSET, W, 1.0), side, ANGLE)
        corners = [joint + s * axis + m * normal
                   for s, m in ((0.0, -W / 2), (L, -W / 2), (L, W / 2), (0.0, W / 2))]
        np.testing.assert_allclose(finger_polygon(L, ANGLE, OFFSET, W, side), corners,
                                   atol=1e-15)
        # depth 0 ignores the rest of the profile
        np.testing.assert_array_equal(finger_polygon(L, ANGLE, OFFSET, W, side),
                                      finger_polygon(L, ANGLE, OFFSET, W, side,
                                                     JawProfile(0.0, 0.01, 1.0, 0.02)))


def _finger_patches(ax) -> list[np.ndarray]:
    # (a closed patch repeats its first point)
    return [p.get_xy()[:-1] for p in ax.patches if isinstance(p, Polygon) and p.get_fill()
            and p.get_zorder() == 3]


def test_a_grasp_drawing_draws_each_fingers_own_groove():
    base = Scene.preset("paper-r070")
    g = base.gripper
    cradle = JawProfile.cradle(0.07, 0.005, 0.1)
    vee = JawProfile.vee(math.radians(100.0), 0.004, 0.08)
    scene = Scene(Gripper(g.finger_length_m, g.rest_angle_rad, g.joint_offset_m,
                          g.finger_width_m, g.torsion_stiffness_nm_per_rad, jaw=cradle,
                          left_jaw=vee), base.disk)
    ax = Figure().add_subplot()
    draw_grasp(ax, scene, length_unit="mm")
    right, left = _finger_patches(ax)
    args = (g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m)
    np.testing.assert_allclose(right, 1e3 * finger_polygon(*args, 0, cradle))
    np.testing.assert_allclose(left, 1e3 * finger_polygon(*args, 1, vee))
    # the right finger's cradle (an arc: many points), the left one's V (three)
    assert len(right) > 4 + 6 and len(left) == 4 + 3


def test_a_design_row_with_jaw_columns_is_drawn_with_its_grooves():
    row = [*DESIGN.values(), *_fields(CRADLE).values()]
    ax = Figure().add_subplot()
    draw_design(ax, row, 0.012)
    right, left = (p.get_xy()[:-1] for p in ax.patches if isinstance(p, Polygon))
    np.testing.assert_allclose(right, finger_polygon(L, ANGLE, OFFSET, W, 0, CRADLE))
    np.testing.assert_allclose(left, finger_polygon(L, ANGLE, OFFSET, W, 1, CRADLE))
    # an impossible groove (a cradle deeper than its radius): the bars drawn straight
    bad = [*DESIGN.values(), 0.003, 0.001, 0.0, 0.03]
    ax = Figure().add_subplot()
    draw_design(ax, bad, 0.012)
    assert [len(p.get_xy()) - 1 for p in ax.patches if isinstance(p, Polygon)] == [4, 4]


# --- the build sheet -------------------------------------------------------------------------


def _texts(fig) -> str:
    return " ".join([t.get_text() for ax in fig.axes for t in ax.texts]
                    + [ax.get_title() for ax in fig.axes])


def test_the_sheet_dimensions_a_cradle_in_millimetres(tmp_path):
    design = {**DESIGN, **_fields(CRADLE)}
    paths = write_build_sheet(design, OBJ, tmp_path, "c")
    sheet = json.loads(paths["design_json"].read_text())
    jaws = sheet["jaws"]
    entry = jaws["right"]
    # alike but for where the groove sits: the left one mirrored about the axis
    assert jaws["same"] is True
    assert jaws["left"] == {**entry, "centre_on_face_mm": [-entry["centre_on_face_mm"][0],
                                                          entry["centre_on_face_mm"][1]]}
    assert entry["kind"] == "cradle"
    assert (entry["depth_mm"], entry["bottom_radius_mm"], entry["opening_angle_deg"],
            entry["position_mm"]) == pytest.approx((3.0, 12.0, 0.0, 30.0))
    mouth_mm = 2e3 * math.sqrt(H * (2 * R_CRADLE - H))  # 15.87 mm
    assert entry["mouth_width_mm"] == pytest.approx(mouth_mm)
    # the model's rounding of the mouth edges: 1e-3 r here (below a twentieth of w)
    assert entry["mouth_edge_radius_mm"] == pytest.approx(0.012)
    joint, axis, normal = finger_frame(Gripper(L, ANGLE, OFFSET, W, 1.0), 0, ANGLE)
    np.testing.assert_allclose(entry["centre_on_face_mm"], 1e3 * (joint + A * axis
                                                                  + W / 2 * normal), atol=1e-4)
    with paths["design_csv"].open() as f:
        rows = {r["quantity"]: r for r in csv.DictReader(f)}
    assert rows["jaw_kind"]["value"] == "cradle"
    assert float(rows["jaw_depth_mm"]["value"]) == pytest.approx(3.0)
    assert float(rows["jaw_bottom_radius_mm"]["value"]) == pytest.approx(12.0)
    assert float(rows["jaw_position_mm"]["value"]) == pytest.approx(30.0)
    assert float(rows["jaw_mouth_width_mm"]["value"]) == pytest.approx(mouth_mm, rel=1e-5)
    assert rows["jaw_depth_mm"]["unit"] == "mm" and "both fingers" in rows["jaw_kind"]["meaning"]
    # the outline's arc: one segment of each finger with a bulge, in the CSV too
    assert sum(float(r["value"]) != 0.0 for k, r in rows.items() if k.endswith("_bulge")) == 2
    text = _texts(drawing_figure(sheet))
    for label in ("mouth 15.87", "h = 3.00", "R 12.00", "a = 30.00", "both fingers' jaw: cradle",
                  "cradle groove, depth h = 3.000 mm, bottom radius R = 12.000 mm"):
        assert label in text, label


def test_fingers_with_different_profiles_are_stated_each(tmp_path):
    design = {**DESIGN, **_fields(CRADLE), **_fields(VEE, LEFT_JAW_FIELDS)}
    sheet = build_sheet(design, OBJ)
    assert sheet["jaws"]["same"] is False
    assert (sheet["jaws"]["right"]["kind"], sheet["jaws"]["left"]["kind"]) == ("cradle", "vee")
    rows = {r["quantity"]: r["value"] for r in jaw_rows(sheet)}
    assert rows["right_jaw_bottom_radius_mm"] == pytest.approx(12.0)
    assert rows["left_jaw_opening_angle_deg"] == pytest.approx(90.0)
    assert rows["left_jaw_position_mm"] == pytest.approx(25.0)
    assert rows["left_jaw_mouth_width_mm"] == pytest.approx(6.0)  # 2 h tan 45 deg
    assert not any(k.startswith("jaw_") for k in rows)
    text = _texts(drawing_figure(sheet))
    for label in ("right finger's jaw: cradle", "left finger's jaw: vee", "90.0°",
                  "mouth 6.00", "a = 25.00", "a = 30.00"):
        assert label in text, label
    # a straight finger beside a grooved one is stated as straight
    one = build_sheet({**design, **_fields(STRAIGHT, LEFT_JAW_FIELDS)}, OBJ)
    rows = {r["quantity"]: r["value"] for r in jaw_rows(one)}
    assert rows["left_jaw"] == "straight" and rows["right_jaw_kind"] == "cradle"
    assert len(one["finger_outline_mm"]["left"]) == 4


def test_the_dxf_cuts_the_cradle_as_an_arc(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    from ezdxf.math import bulge_to_arc

    from optim.build_sheet import DXF_LAYERS, write_dxf

    sheet = build_sheet({**DESIGN, **_fields(CRADLE)}, OBJ)
    space = ezdxf.readfile(write_dxf(sheet, tmp_path / "f.dxf")).modelspace()
    gripper = Gripper(L, ANGLE, OFFSET, W, 1.0)
    for side, name in enumerate(("right", "left")):
        (outline,) = space.query(f'LWPOLYLINE[layer=="{DXF_LAYERS[name]}"]')
        points = list(outline.get_points("xyb"))
        arcs = [(p, points[(k + 1) % len(points)]) for k, p in enumerate(points) if p[2] != 0.0]
        assert len(points) == 6 and len(arcs) == 1
        start, end = arcs[0]
        centre, _, _, radius = bulge_to_arc(start[:2], end[:2], start[2])
        assert radius == pytest.approx(12.0, rel=1e-4)  # mm, from vertices kept to 0.1 um
        joint, axis, normal = finger_frame(gripper, side, ANGLE)
        expected = 1e3 * (joint + A * axis + (W / 2 + R_CRADLE - H) * normal)
        np.testing.assert_allclose(tuple(centre), expected, atol=2e-3)
        # the arc runs through the groove's bottom, not round the other way
        bottom = 1e3 * (joint + A * axis + (W / 2 - H) * normal)
        assert np.hypot(*(bottom - expected)) == pytest.approx(12.0, rel=1e-9)
        np.testing.assert_allclose(points[2][:2], sheet["finger_outline_mm"][name][2])


def test_a_design_without_jaw_fields_keeps_todays_sheet(tmp_path):
    plain = build_sheet(DESIGN, OBJ)
    zero = build_sheet({**DESIGN, **_fields(STRAIGHT)}, OBJ)
    assert plain == zero
    assert plain["jaws"] == {"right": {"kind": "straight"}, "left": {"kind": "straight"},
                             "same": True}
    assert "finger_outline_bulge" not in plain
    assert [len(plain["finger_outline_mm"][side]) for side in ("right", "left")] == [4, 4]
    assert jaw_rows(plain) == [{"quantity": "jaw", "value": "straight", "unit": "-",
                                "meaning": "both fingers: a flat gripping face, no groove"}]
    paths = write_build_sheet(DESIGN, OBJ, tmp_path, "s")
    with paths["design_csv"].open() as f:
        rows = {r["quantity"]: r for r in csv.DictReader(f)}
    assert rows["jaw"]["value"] == "straight"
    assert not [k for k in rows if k.endswith("_bulge") or k.startswith("jaw_")]
    fig = drawing_figure(plain)
    assert "jaws, both fingers: straight" in _texts(fig)
    assert not any("jaw:" in ax.get_title() for ax in fig.axes)
    # a sheet written before jaw profiles (no "jaws") is drawn as today's, its jaws straight
    legacy = {k: v for k, v in plain.items() if k != "jaws"}
    assert jaw_rows(legacy) == jaw_rows(plain)
    assert "jaws, both fingers: straight" in _texts(drawing_figure(legacy))


def test_bad_jaw_fields_are_named():
    with pytest.raises(ValueError, match="needs all of .*missing .jaw_bottom_radius_m."):
        build_sheet({**DESIGN, "jaw_depth_m": 0.003}, OBJ)
    # a cradle wider than the finger is long
    with pytest.raises(ValueError, match="the right finger's jaw: jaw position_m"):
        build_sheet({**DESIGN, **_fields(JawProfile.cradle(0.05, 0.004, 0.01))}, OBJ)
    with pytest.raises(ValueError, match="the left finger's jaw: jaw depth_m"):
        build_sheet({**DESIGN, **_fields(CRADLE),
                     **_fields(JawProfile.vee(1.0, 0.0055, 0.02), LEFT_JAW_FIELDS)}, OBJ)


def test_bad_drawing_input_is_named():
    from envs.render import outline_polygon

    with pytest.raises(ValueError, match="side must be 0"):
        finger_polygon(L, ANGLE, OFFSET, W, 2, CRADLE)
    with pytest.raises(ValueError, match="arc_step_rad"):
        outline_polygon(np.zeros((3, 3)), arc_step_rad=0.0)
    with pytest.raises(ValueError, match=r"shape \(K, 3\)"):
        outline_polygon(np.zeros((3, 2)))


# --- the jaw page's examples run and print what they say --------------------------------------


def test_the_examples_of_the_jaw_page_run(tmp_path, monkeypatch, capsys):
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "jaws.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", page, flags=re.DOTALL)
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        # each print's comment says what it prints
        said = [line.split("# ", 1)[1].split(",")[0] for line in block.splitlines()
                if line.startswith("print(")]
        exec(compile(block, "docs/jaws.md", "exec"), {})
        printed = capsys.readouterr().out.splitlines()
        assert [line.strip() for line in printed] == said
    sheet = json.loads((tmp_path / "out" / "cradle_design.json").read_text())
    assert sheet["jaws"]["right"]["kind"] == "cradle"
    assert (tmp_path / "out" / "cradle_drawing.png").stat().st_size > 0
