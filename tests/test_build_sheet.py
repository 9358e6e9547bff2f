"""The build sheet a workshop builds from: lengths in millimetres, what the design depends on
(friction, payload, tolerances, scenarios, the fixed centre), stacked fingers when the joints are
closer than half a finger width, and the design space that keeps them apart."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from matplotlib.patches import Polygon

from cli.main import main
from envs import DesignBounds, Scene
from envs.scene import DESIGN_FIELDS
from optim import DesignProblem, optimize
from optim.build_sheet import (
    ASSEMBLY_SIDE_BY_SIDE,
    ASSEMBLY_STACKED,
    assembly_of,
    build_sheet,
    drawing_figure,
    write_build_sheet,
)

DISK = Scene.preset("paper-r070").disk
OBJ = {"name": "test disk", "radius_m": 0.012, "thickness_m": 0.024, "youngs_modulus_pa": 1.5e5,
       "poisson_ratio": 0.45, "strain_limit": 0.1, "friction_coefficient": 0.5,
       "torsion_stiffness_nm_per_rad": 0.004}
# joints 0.5 mm from the axis, fingers 2 mm wide: they overlap by 1 mm at the joints
STACKED = {"finger_length_m": 0.05, "rest_angle_rad": 0.4, "joint_offset_m": 0.0005,
           "finger_width_m": 0.002, "torque_nm": 0.01, "distance_m": 0.02}
APART = {**STACKED, "joint_offset_m": 0.001}  # d3 = w/2 exactly: the joint ends just meet
# the left finger's corners at rest [mm] from the model's frame (J_L = (-d3, 0), axis
# (-sin, cos), inward normal (cos, sin)): joint end back, joint end face, tip face, tip back
OUTLINE_LEFT_MM = 1e3 * np.array([
    [-0.0005 - 0.001 * np.cos(0.4), -0.001 * np.sin(0.4)],
    [-0.0005 + 0.001 * np.cos(0.4), 0.001 * np.sin(0.4)],
    [-0.0005 + 0.001 * np.cos(0.4) - 0.05 * np.sin(0.4), 0.001 * np.sin(0.4) + 0.05 * np.cos(0.4)],
    [-0.0005 - 0.001 * np.cos(0.4) - 0.05 * np.sin(0.4), -0.001 * np.sin(0.4) + 0.05 * np.cos(0.4)],
])


def _offsets_and_widths(designs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return (designs[:, DESIGN_FIELDS.index("joint_offset_m")],
            designs[:, DESIGN_FIELDS.index("finger_width_m")])


def _keys(tree) -> list[str]:
    """Every key of a nested JSON value."""
    if isinstance(tree, dict):
        return [*tree, *(k for v in tree.values() for k in _keys(v))]
    if isinstance(tree, list):
        return [k for v in tree for k in _keys(v)]
    return []


# --- the design space that keeps the joints apart --------------------------------------------


def test_joints_apart_maps_the_whole_box_to_designs_with_d3_at_least_half_w():
    rng = np.random.default_rng(0)
    action = rng.uniform(-1.0, 1.0, size=(4000, 6))
    d3, w = _offsets_and_widths(DesignBounds().scale(action, DISK))
    assert np.mean(d3 < w / 2) > 0.1  # the default box holds many stacked designs
    apart = DesignBounds(joints_apart=True)
    d3a, wa = _offsets_and_widths(apart.scale(action, DISK))
    assert np.all(d3a >= wa / 2)
    assert np.array_equal(wa, w)  # only the joint offset's map changes
    # the ends of its coordinate are w/2 and the box's high end
    edge = action.copy()
    edge[:, 2] = -1.0
    d3_low, w_low = _offsets_and_widths(apart.scale(edge, DISK))
    np.testing.assert_allclose(d3_low, w_low / 2, rtol=1e-12)
    edge[:, 2] = 1.0
    np.testing.assert_allclose(_offsets_and_widths(apart.scale(edge, DISK))[0],
                               0.6 * DISK.radius_m, rtol=1e-12)
    # and unscale inverts it (where the placement was not raised to 0, as for the default)
    designs = apart.scale(action, DISK)
    placed = designs[:, DESIGN_FIELDS.index("distance_m")] > 0
    np.testing.assert_allclose(apart.unscale(designs, DISK)[placed], action[placed], atol=1e-9)


def test_joints_apart_bad_input_is_named():
    with pytest.raises(ValueError, match="joints_apart must be True or False"):
        DesignBounds(joints_apart="yes")
    high = (8.0, 1.0, 0.1, 0.4, 0.3, 1.2)  # joint offsets up to 0.1 r, widths up to 0.4 r
    with pytest.raises(ValueError, match=r"high joint_offset_r = 0.1 must be at least half of "
                                         r"high finger_width_r = 0.4"):
        DesignBounds(high=high, joints_apart=True)
    with pytest.raises(ValueError, match="joints_apart must be True or False"):
        DesignProblem(DISK, joints_apart=1)


def test_an_optimized_design_keeps_its_joints_apart():
    problem = DesignProblem(DISK, joints_apart=True)
    result = optimize("cmaes", problem, budget=120, seed=0)
    d = result.best_design
    assert d["joint_offset_m"] >= d["finger_width_m"] / 2
    assert result.extra["joints_apart"] is True and result.best_reward > 0.0
    d3, w = _offsets_and_widths(problem.to_physical(problem.archive()["x"]))
    assert d3.size == 120 and np.all(d3 >= w / 2)
    # the default space is the box it always was
    assert DesignProblem(DISK).bounds == DesignBounds()
    # its grasp drawn in millimetres, like the sheet
    from optim.charts import best_grasp_figure

    ax = best_grasp_figure(result).axes[0]
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylim()[1] > 2 * DISK.radius_m * 1e3
    assert "fingers side by side" in ax.get_title()


def test_the_policy_cannot_keep_the_joints_apart(tmp_path, capsys):
    from optim.run import run_optimize

    with pytest.raises(ValueError, match="design policy .* cannot keep the joints apart"):
        run_optimize("policy", scene="paper-r070", joints_apart=True, out=tmp_path,
                     progress=False)
    assert main(["optimize", "--method", "policy", "--joints-apart", "--out",
                 str(tmp_path)]) == 2
    assert "--joints-apart" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


# --- assembly: stacked or side by side -------------------------------------------------------


def test_fingers_closer_than_half_a_width_are_stacked():
    sheet = build_sheet(STACKED, OBJ)
    assert sheet["assembly"] == ASSEMBLY_STACKED == "stacked"
    assert "forceps" in sheet["assembly_note"] and "--joints-apart" in sheet["assembly_note"]
    rows = {r["quantity"]: r["value"] for r in sheet["rows"]}
    assert rows["joint_end_overlap_mm"] == pytest.approx(1.0)
    assert build_sheet(APART, OBJ)["assembly"] == ASSEMBLY_SIDE_BY_SIDE == "side by side"
    assert assembly_of(0.1e-3, 1e-3)[0] == ASSEMBLY_STACKED
    assert assembly_of(0.0, 1e-3)[0] == "common pivot"  # both fingers on one pin
    assert assembly_of(0.6e-3, 1e-3)[0] == ASSEMBLY_SIDE_BY_SIDE


def test_the_drawing_shows_stacked_fingers_one_behind_the_other():
    def hatched(fig):
        return [p for ax in fig.axes for p in ax.patches
                if isinstance(p, Polygon) and p.get_hatch()]

    def text(fig):
        return " ".join(t.get_text() for ax in fig.axes for t in ax.texts)

    fig = drawing_figure(build_sheet(STACKED, OBJ))
    behind = hatched(fig)  # in the drawing and in the detail of the joints
    assert len(behind) == 2 and behind[0].get_label() == "left finger (behind)"
    np.testing.assert_allclose(behind[0].get_xy()[:4], OUTLINE_LEFT_MM, atol=1e-4)  # 0.1 um
    assert "STACKED" in text(fig) and "forceps" in text(fig)
    assert "stacked" in fig.axes[0].get_title()
    assert any("overlap w - 2 d3 = 1 mm" in ax.get_title() for ax in fig.axes)
    fig = drawing_figure(build_sheet(APART, OBJ))
    assert not hatched(fig) and "SIDE BY SIDE" in text(fig)
    assert not any("detail" in ax.get_title() for ax in fig.axes)


# --- what the design depends on, in millimetres ----------------------------------------------


def _scenario_rows(payload: bool) -> list[dict]:
    rows = []
    for k, (dx, dy) in enumerate(((0.0, 0.0), (0.0015, 0.0), (-0.0015, 0.001))):
        row = {"scenario": {"label": "nominal" if k == 0 else f"s{k}", "radius_m": 0.012 + dy,
                            "dx_m": dx, "dy_m": dy},
               "reward": 0.02 - 0.01 * k, "holds": k < 2, "peak_compression": 0.02 * (k + 1),
               "required_friction": "inf" if k == 2 else 0.3, "strain_limit": 0.1}
        if payload:
            row.update(payload_n=0.21, grip_force_n=1.5 - 0.2 * k)
        rows.append(row)
    return rows


def test_the_sheet_states_friction_tolerances_scenarios_and_the_fixed_centre(tmp_path):
    obj = {**OBJ, "scenarios": {"ranges": {"radius_m": [0.010, 0.015]},
                                "placement_along_m": 0.001, "placement_across_m": 0.0015}}
    metrics = {"jaw_angles_rad": [0.3, 0.3], "required_friction": 0.3, "holds": True}
    paths = write_build_sheet(STACKED, obj, tmp_path, "t", metrics, _scenario_rows(False))
    sheet = json.loads(paths["design_json"].read_text())
    cond = {r["quantity"]: r["value"] for r in sheet["conditions"]}
    assert cond["friction_coefficient"] == 0.5 and cond["strain_limit"] == 0.1
    assert cond["placement_tolerance_along_mm"] == pytest.approx(1.0)
    assert cond["placement_tolerance_across_mm"] == pytest.approx(1.5)
    assert sheet["tolerances"]["object_ranges"] == {"radius_mm": [pytest.approx(10.0),
                                                                  pytest.approx(15.0)]}
    assert "held where it was placed" in sheet["fixed_centre"]
    table = sheet["scenarios"]
    assert [r["label"] for r in table] == ["nominal", "s1", "s2"]
    assert table[1]["dx_mm"] == pytest.approx(1.5) and table[2]["dy_mm"] == pytest.approx(1.0)
    assert table[2]["required_friction"] == "inf" and table[2]["holds"] is False
    assert table[2]["object"] == {"radius_mm": pytest.approx(13.0)}
    assert sheet["object"]["radius_mm"] == pytest.approx(12.0)
    assert sheet["grasp"]["closed_angles_deg"][0] == pytest.approx(np.degrees(0.3))
    # millimetres throughout: no length in metres anywhere in the sheet
    assert not [k for k in _keys(sheet) if k.endswith("_m")]
    with paths["scenarios_csv"].open() as f:
        rows = list(csv.DictReader(f))
    assert [r["label"] for r in rows] == ["nominal", "s1", "s2"]
    assert float(rows[1]["dx_mm"]) == pytest.approx(1.5) and rows[2]["holds"] == "False"
    with paths["design_csv"].open() as f:
        design = {r["quantity"]: r for r in csv.DictReader(f)}
    assert design["assembly"]["value"] == "stacked"
    assert design["friction_coefficient"]["value"] == "0.5"
    assert design["range_radius_mm"]["value"] == "10 to 15"
    assert design["scenarios"]["value"] == "3" and "t_scenarios.csv" in design["scenarios"][
        "meaning"]
    assert design["payload_n"]["value"] == "not modelled"
    assert paths["drawing"].stat().st_size > 0


def test_the_payload_is_stated_when_the_result_has_one(tmp_path):
    obj = {**OBJ, "density_kg_m3": 1000.0, "payload_factor": 2.0}
    metrics = {"payload_n": 0.21, "grip_force_n": 1.5, "holds": True}
    sheet = build_sheet(STACKED, obj, metrics, _scenario_rows(True))
    cond = {r["quantity"]: r["value"] for r in sheet["conditions"]}
    assert (cond["density_kg_m3"], cond["payload_factor"]) == (1000.0, 2.0)
    assert (cond["payload_n"], cond["grip_force_n"]) == (0.21, 1.5)
    assert sheet["grasp"]["payload_n"] == 0.21
    assert [r["grip_force_n"] for r in sheet["scenarios"]] == pytest.approx([1.5, 1.3, 1.1])
    text = " ".join(t.get_text() for ax in drawing_figure(sheet).axes for t in ax.texts)
    assert "payload W = 0.21 N" in text and "not modelled" not in text
    # without them the sheet says the payload was not modelled, nowhere a number
    bare = build_sheet(STACKED, OBJ, {"holds": True})
    cond = {r["quantity"]: r["value"] for r in bare["conditions"]}
    assert {cond[k] for k in ("density_kg_m3", "payload_factor", "payload_n",
                              "grip_force_n")} == {"not modelled"}
    text = " ".join(t.get_text() for ax in drawing_figure(bare).axes for t in ax.texts)
    assert "payload: not modelled" in text


def test_drawings_in_millimetres_are_the_metre_drawings_scaled():
    from matplotlib.figure import Figure

    from envs.render import draw_design, draw_grasp

    scene = Scene.preset("paper-r070")
    limits = []
    for unit in ("m", "mm"):
        ax = Figure().add_subplot()
        draw_grasp(ax, scene, length_unit=unit)
        limits.append((np.array(ax.get_xlim()), np.array(ax.get_ylim()), ax.get_xlabel()))
    np.testing.assert_allclose(limits[1][0], 1e3 * limits[0][0])
    np.testing.assert_allclose(limits[1][1], 1e3 * limits[0][1])
    assert (limits[0][2], limits[1][2]) == ("x [m]", "x [mm]")
    with pytest.raises(ValueError, match=r"length_unit must be one of \['m', 'mm'\]"):
        draw_design(Figure().add_subplot(), [0.2, 0.7, 0.02, 0.01, 0.1, 0.01], 0.07,
                    length_unit="cm")


def test_the_optimize_command_writes_the_sheet_of_a_run_with_scenarios(tmp_path):
    tomato = "examples/objects/cherry_tomato.toml"
    code = main(["optimize", "--object", tomato, "--budget", "40", "--placement-tolerance",
                 "0.0015", "--joints-apart", "--no-finish", "--no-progress", "--out",
                 str(tmp_path)])
    assert code in (0, 3)  # a short run need not find a grasp; its sheet is written either way
    result = json.loads((tmp_path / "portfolio_seed0_result.json").read_text())
    sheet = json.loads((tmp_path / "portfolio_seed0_design.json").read_text())
    assert result["extra"]["joints_apart"] is True and sheet["assembly"] == "side by side"
    rows = result["extra"]["scenario_rows"]
    assert len(sheet["scenarios"]) == len(rows) == 9
    for entry, row in zip(sheet["scenarios"], rows, strict=True):
        assert entry["label"] == row["scenario"]["label"]
        assert entry["dx_mm"] == pytest.approx(row["scenario"]["dx_m"] * 1e3)
        assert entry["reward"] == pytest.approx(row["reward"])
    assert sorted({round(abs(r["dx_mm"]), 9) for r in sheet["scenarios"]}) == [0.0, 1.5]
    assert sheet["tolerances"]["placement_across_mm"] == pytest.approx(1.5)
    assert (tmp_path / "portfolio_seed0_scenarios.csv").read_text().count("\n") == 10
    from optim.build_sheet import dxf_available

    assert (tmp_path / "portfolio_seed0_fingers.dxf").exists() == dxf_available()


def test_the_dxf_holds_each_finger_outline_in_millimetres(tmp_path):
    ezdxf = pytest.importorskip("ezdxf")
    from optim.build_sheet import DXF_LAYERS, write_dxf

    sheet = build_sheet(STACKED, OBJ)
    doc = ezdxf.readfile(write_dxf(sheet, tmp_path / "f.dxf"))
    assert doc.header["$INSUNITS"] == 4  # millimetres
    space = doc.modelspace()
    for side in ("right", "left"):
        (outline,) = space.query(f'LWPOLYLINE[layer=="{DXF_LAYERS[side]}"]')
        assert outline.closed
        np.testing.assert_allclose([p[:2] for p in outline.get_points()],
                                   sheet["finger_outline_mm"][side])
    np.testing.assert_allclose(sheet["finger_outline_mm"]["left"], OUTLINE_LEFT_MM, atol=1e-4)
    points = [tuple(p.dxf.location)[:2] for p in space.query("POINT")]
    np.testing.assert_allclose(sorted(points), [(-0.5, 0.0), (0.5, 0.0)])
    (circle,) = space.query("CIRCLE")
    assert circle.dxf.radius == pytest.approx(12.0)
    assert tuple(circle.dxf.center)[:2] == pytest.approx((0.0, 32.0))
