"""Parts a workshop can make: the rounded design, the pivot, the stops, one DXF and one STL per
finger read back (optim.parts, optim.sheet)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from envs.model.jaw import STRAIGHT, JawProfile
from envs.object_file import load_object
from envs.scene import DESIGN_FIELDS, design_mapping
from optim.parts.joint import boss_radius, default_pin_diameter, pivot_of
from optim.parts.options import PartOptions
from optim.parts.resolution import (
    DEFAULT_RESOLUTION,
    Resolution,
    parse_resolution,
    round_design,
    round_significant,
)
from optim.problem import paper_design_for
from optim.sheet import write_build_sheet

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples" / "objects").glob("*.toml"))
MM = 1e3


def test_a_design_rounds_to_the_resolution():
    design = {"finger_length_m": 0.087349, "rest_angle_rad": math.radians(49.6321),
              "joint_offset_m": 0.00004, "finger_width_m": 0.0026049, "torque_nm": 0.157349,
              "distance_m": 0.026551, "jaw_depth_m": 0.00002, "jaw_bottom_radius_m": 0.0012,
              "jaw_opening_angle_rad": 0.0, "jaw_position_m": 0.03}
    r = round_design(design)
    assert r["finger_length_m"] == 0.0873 and r["finger_width_m"] == 0.0026
    assert r["distance_m"] == 0.0266 and r["torque_nm"] == 0.157
    assert r["joint_offset_m"] == 0.0  # 40 um: a common pivot
    assert r["jaw_depth_m"] == 0.0  # a 20 um groove is a straight face
    assert math.degrees(r["rest_angle_rad"]) == pytest.approx(49.6, abs=1e-9)
    assert round_design(r) == r  # on the grid, it stays
    assert round_significant(0.0201049, 3) == 0.0201 and round_significant(0.0, 3) == 0.0
    coarse = round_design(design, Resolution(length_m=1e-3, angle_rad=math.radians(1.0),
                                             significant=2))
    assert coarse["finger_length_m"] == 0.087 and coarse["torque_nm"] == 0.16
    assert math.degrees(coarse["rest_angle_rad"]) == pytest.approx(50.0)
    assert parse_resolution("0.05,0.2,4") == Resolution(5e-5, math.radians(0.2), 4)
    for bad, match in (("0", "resolution.length_m"), ("0.1,0.1,2.5", "DIGITS"),
                       ("x", "numbers")):
        with pytest.raises(ValueError, match=match):
            parse_resolution(bad)


def test_the_pin_rule_and_the_three_assemblies():
    assert default_pin_diameter(0.0026, 1e-4) == pytest.approx(0.0013)
    assert default_pin_diameter(0.0027, 1e-4) == pytest.approx(0.0013)  # rounded down
    assert default_pin_diameter(0.0003, 1e-4) == pytest.approx(0.0001)  # forceps: one step
    # the default pin: the boss is the finger's own half-disk end, a wall of w/4
    assert boss_radius(0.0026, 0.0013, 1e-4) == pytest.approx(0.0013)
    assert boss_radius(0.0026, 0.002, 1e-4) == pytest.approx(0.001 + 0.0005)  # a larger pin
    base = {"finger_length_m": 0.05, "rest_angle_rad": 0.5, "finger_width_m": 0.004,
            "torque_nm": 0.01, "distance_m": 0.01}
    kinds = {}
    for d3 in (0.0, 0.001, 0.002):
        pivot, parts = pivot_of({**base, "joint_offset_m": d3}, (STRAIGHT, STRAIGHT), 0.01012,
                                DEFAULT_RESOLUTION, None, 0.3)
        kinds[d3] = pivot
        assert pivot.plate_thickness_m == pytest.approx(0.0102)  # the slice, rounded up
        assert all(p.pin_diameter_m == pytest.approx(0.002) for p in parts)
    assert kinds[0.0].assembly == "common pivot" and kinds[0.0].pin_x_m == (0.0,)
    assert kinds[0.001].assembly == "stacked" and kinds[0.001].pin_x_m == (0.001, -0.001)
    assert kinds[0.002].assembly == "side by side" and kinds[0.002].lap_length_m == 0.0
    # the half-lap covers where the other finger reaches between the closing stop and rest:
    # two bars of width w from one pivot at +-theta overlap to about (w/2) / tan(theta)
    lap = kinds[0.0].lap_length_m
    stop = kinds[0.0]  # (the closing stop lies halfway to the smallest grasp angle, 0.3)
    assert 0.002 / math.tan(0.3) < lap < 0.002 / math.tan(0.1) and stop.lap_length_m == lap
    assert kinds[0.001].lap_length_m < lap  # joints apart overlap less


def _example_design(path: Path) -> tuple[dict, dict]:
    """The paper's gripper scaled to an example object, rounded, and the object as a result
    records it."""
    spec = load_object(path)
    row = paper_design_for(spec.disk, 0.2)[0]
    design = round_design(design_mapping(row))
    obj = {**spec.info(), "torsion_stiffness_nm_per_rad": 0.0123}
    return design, obj


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_each_example_builds_a_dxf_and_a_watertight_stl_per_finger(path, tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("manifold3d")
    design, obj = _example_design(path)
    paths = write_build_sheet(design, obj, tmp_path, "x", {"holds": True, "converged": True,
                                                           "valid_at_rest": True,
                                                           "touching": [True, True],
                                                           "peak_compression": 0.01,
                                                           "strain_limit": 0.1})
    sheet = json.loads(paths["design_json"].read_text())
    values = sheet["parts"]["values"]
    rows = {r["quantity"]: r["value"] for r in sheet["rows"]}
    # the sheet states the rounded design: every length on the 0.1 mm grid
    for key in ("finger_length_mm", "finger_width_mm", "joint_offset_mm", "object_distance_mm"):
        assert rows[key] == pytest.approx(round(rows[key], 1), abs=1e-9), key
    for side in ("right", "left"):
        doc = ezdxf.readfile(paths[f"dxf_{side}"])
        space = doc.modelspace()
        assert doc.header["$INSUNITS"] == 4  # millimetres
        (hole,) = space.query('CIRCLE[layer=="PIVOT_HOLE"]')
        assert tuple(hole.dxf.center)[:2] == pytest.approx((0.0, 0.0))
        assert 2 * hole.dxf.radius == pytest.approx(values["pin_diameter_mm"])
        (outline,) = space.query('LWPOLYLINE[layer=="OUTLINE"]')
        assert outline.closed
        xs = [p[0] for p in outline.get_points("xy")]
        assert max(xs) == pytest.approx(rows["finger_length_mm"])  # the tip, from the pivot
        assert min(xs) == pytest.approx(-values["boss_radius_mm"], abs=1e-9) or (
            min(xs) == pytest.approx(0.0))  # (a half-disk end: its arc is a bulge)
        measured = sorted(round(d.get_measurement(), 6) for d in space.query("DIMENSION"))
        assert round(rows["finger_length_mm"], 6) in measured
        assert any("FINGER" in t.dxf.text for t in space.query("TEXT"))
        mesh = trimesh.load(paths[f"stl_{side}"])
        assert mesh.is_watertight and mesh.is_volume
        volume = sheet["parts"]["fingers"][side]["volume_mm3"]
        assert mesh.volume == pytest.approx(volume, rel=1e-6)
        extent = mesh.bounds[1] - mesh.bounds[0]
        assert extent[2] == pytest.approx(values["plate_thickness_mm"])
        assert mesh.bounds[1][0] == pytest.approx(rows["finger_length_mm"])


def test_stacked_fingers_get_a_half_lap_in_their_parts(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("manifold3d")
    design = {"finger_length_m": 0.016, "rest_angle_rad": math.radians(15.0),
              "joint_offset_m": 0.0001, "finger_width_m": 0.0006, "torque_nm": 0.001,
              "distance_m": 0.011}
    obj = {"name": "bead", "radius_m": 0.002, "thickness_m": 0.002,
           "torsion_stiffness_nm_per_rad": 1e-3}
    metrics = {"converged": True, "jaw_angles_rad": [0.1, 0.1], "holds": True}
    paths = write_build_sheet(design, obj, tmp_path, "f", metrics, parts=PartOptions())
    sheet = json.loads(paths["design_json"].read_text())
    values = sheet["parts"]["values"]
    assert sheet["assembly"] == values["pivot"] == "stacked"
    lap = values["half_lap_mm"]
    assert 0.0 < lap < 16.0
    # the closing stop lies below every grasp angle, above the faces meeting
    assert values["faces_meet_deg"] <= values["closing_stop_deg"] < math.degrees(0.1)
    assert values["spring_free_angle_deg"] == pytest.approx(15.0)
    assert values["spring_preload_nmm"] == 0.0
    assert values["spring_moment_at_grasp_nmm"] == pytest.approx(1e-3 * (math.radians(15) - 0.1)
                                                                 * MM)
    mesh = trimesh.load(paths["stl_right"])
    assert mesh.is_watertight
    t = values["plate_thickness_mm"]
    # the full plate less half of it over the lap: the mesh's volume is smaller than the plan's
    plan = sheet["parts"]["fingers"]["right"]["volume_mm3"]
    assert mesh.volume == pytest.approx(plan, rel=1e-6) and mesh.volume < 16.3 * 0.6 * t
    # the half-lap's cut: at the pivot the part is half the plate, beyond the lap all of it
    sections = {x: mesh.section(plane_origin=[x, 0.0, 0.0], plane_normal=[1.0, 0.0, 0.0])
                for x in (0.5 * lap, lap + 0.5)}
    assert np.ptp(sections[0.5 * lap].vertices[:, 2]) == pytest.approx(t / 2)
    assert np.ptp(sections[lap + 0.5].vertices[:, 2]) == pytest.approx(t)
    assert sheet["parts"]["fingers"]["left"]["same_as"] == "right"


def test_a_larger_pin_gets_a_boss_and_a_grooved_finger_keeps_its_arc(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    design = {"finger_length_m": 0.05, "rest_angle_rad": 0.5, "joint_offset_m": 0.004,
              "finger_width_m": 0.004, "torque_nm": 0.01, "distance_m": 0.02}
    jaw = JawProfile.cradle(0.012, 0.001, 0.03)
    design.update(zip(("jaw_depth_m", "jaw_bottom_radius_m", "jaw_opening_angle_rad",
                       "jaw_position_m"),
                      (jaw.depth_m, jaw.bottom_radius_m, jaw.opening_angle_rad,
                       jaw.position_m), strict=True))
    obj = {"name": "disk", "radius_m": 0.01, "thickness_m": 0.01,
           "torsion_stiffness_nm_per_rad": 0.01}
    paths = write_build_sheet(design, obj, tmp_path, "g",
                              parts=PartOptions(pin_diameter_m=0.003))
    values = json.loads(paths["design_json"].read_text())["parts"]["values"]
    assert values["pin_diameter_mm"] == pytest.approx(3.0)
    assert values["boss_radius_mm"] == pytest.approx(1.5 + 0.75)  # d/2 + d/4
    space = ezdxf.readfile(paths["dxf_right"]).modelspace()
    (outline,) = space.query('LWPOLYLINE[layer=="OUTLINE"]')
    assert min(p[0] for p in outline.get_points("xy")) == pytest.approx(-2.25, abs=0.01)
    with pytest.raises(ValueError, match="pin_diameter_m"):
        PartOptions(pin_diameter_m=0.0)
    assert len(DESIGN_FIELDS) == 6
