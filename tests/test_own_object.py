"""Designing for your own object: object files on the command line, no silent non-grasp, a
design a builder can use (the own-object issue), and the reported optimum's model."""

from __future__ import annotations

import csv
import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from envs import SoftDisk
from envs.object_file import load_object
from optim import DesignProblem, NoGraspWarning, optimize
from optim.build_sheet import build_sheet

ROOT = Path(__file__).resolve().parents[1]
OBJECTS = ROOT / "examples" / "objects"
# (at the paper's foam density, 50 kg/m^3: the disk's default density was that before it became
# an object file's, 1000)
TISSUE = SoftDisk(0.004, 0.0, youngs_modulus_pa=8e3, poisson_ratio=0.45, thickness_m=0.005,
                  density_kg_m3=50.0)


def test_the_tissue_sample_gets_a_grasp_with_every_default():
    """r = 4 mm, E = 8 kPa: with the paper's absolute joint spring no design of the box touched
    it; with the spring relative to the object CMA-ES finds a grasp that holds (and lifts it:
    the default payload, at a foam's density; reward 0.017, 0.02+ without it)."""
    result = optimize("cmaes", DesignProblem(TISSUE), budget=600, seed=0)
    assert result.best_reward > 0.01
    assert result.extra["grasp_found"] is True and result.best_metrics["holds"]


def test_a_run_whose_best_design_does_not_grasp_warns():
    stiff = DesignProblem(TISSUE, torsion_stiffness_nm_per_rad=0.073)  # 100x its torque unit
    with pytest.warns(NoGraspWarning, match="found no grasp of the object in 60 evaluations"):
        result = optimize("random", stiff, budget=60, seed=0)
    assert result.extra["grasp_found"] is False


def test_the_optimize_command_designs_for_an_object_file(tmp_path, capsys):
    # (the reaction alone: the subject is the object file and the build sheet; with the tomato's
    # payload, 0.21 N, the finer member finds the search's optimum needing infinite friction)
    code = main(["optimize", "--object", str(OBJECTS / "cherry_tomato.toml"), "--budget", "300",
                 "--out", str(tmp_path), "--no-progress", "--payload-factor", "0"])
    assert code == 0
    data = json.loads((tmp_path / "portfolio_seed0_result.json").read_text())
    assert data["object"]["name"] == "cherry tomato" and data["object"]["radius_m"] == 0.012
    assert data["object"]["strain_limit"] == 0.10 and data["object"]["friction_coefficient"] == 0.5
    assert data["extra"]["grasp_found"] is True and data["best_reward"] > 0.02
    # the reported optimum is the finer member's, and the JSON says so
    assert data["extra"]["reward_model"] == {"n_triangles": 96, "n_rings": 6,
                                             "element": "nhquad", "calibrated": True}
    assert data["extra"]["search_reward"] != data["best_reward"]
    # a design a builder can use, and a drawing that names the object
    for name in ("design.json", "design.csv", "drawing.png", "best_grasp.png"):
        assert (tmp_path / f"portfolio_seed0_{name}").stat().st_size > 0
    sheet = json.loads((tmp_path / "portfolio_seed0_design.json").read_text())
    rows = {r["quantity"]: r["value"] for r in sheet["rows"]}
    design = data["best_design"]
    assert rows["finger_length_mm"] == pytest.approx(design["finger_length_m"] * 1e3)
    assert rows["object_diameter_mm"] == pytest.approx(24.0)
    assert rows["torsion_stiffness_nm_per_rad"] == pytest.approx(
        data["object"]["torsion_stiffness_nm_per_rad"])
    with (tmp_path / "portfolio_seed0_design.csv").open() as f:
        table = {row["quantity"]: row for row in csv.DictReader(f)}
    assert table["torque_nm"]["unit"] == "N·m"
    assert float(table["rest_angle_deg"]["value"]) == pytest.approx(
        math.degrees(design["rest_angle_rad"]), rel=1e-5)
    out = capsys.readouterr().out
    assert "holding: needs friction" in out and "finer member" in out


@pytest.mark.parametrize("text,match", [
    ("[object]\nradius_m = 0.01\n", r"missing key 'youngs_modulus_pa'"),
    ("[object]\nradius_m = 0.01\nyoungs_modulus_pa = 1e5\npoisson_ratio = 0.4\n"
     "thickness_m = 0.01\ncolor = 1\n", r"unknown key 'color'"),
    ("[object]\nradius_m = -1\nyoungs_modulus_pa = 1e5\npoisson_ratio = 0.4\n"
     "thickness_m = 0.01\n", r"radius_m = -1 is outside"),
])
def test_a_bad_object_file_stops_the_command_before_any_work(text, match, tmp_path, capsys,
                                                             monkeypatch):
    import optim.run

    monkeypatch.setattr(optim.run, "run_optimize", lambda *a, **k: pytest.fail("ran"))
    path = tmp_path / "obj.toml"
    path.write_text(text)
    for argv in (["optimize", "--object", str(path), "--out", str(tmp_path)],
                 ["simulate", "--object", str(path)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(path) in err and re.search(match, err)
    assert main(["optimize", "--object", str(path), "--scene", "paper-r070"]) == 2
    assert "exclude each other" in capsys.readouterr().err


def test_simulate_an_object_file_with_its_gripper_or_the_papers(capsys):
    assert main(["simulate", "--object", str(OBJECTS / "foam_disk.toml"), "--json",
                 "--payload-factor", "0"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["scene"] == "foam disk" and data["torque_nm"] == 0.05
    assert data["required_friction"] == pytest.approx(math.tan(data["jaw_angles_rad"][0]),
                                                      rel=1e-6)
    assert data["holds"] is False and data["friction_coefficient"] == 0.6  # needs 0.69
    # without a [gripper] table: the paper's gripper scaled to the object, the same grasp in
    # radii as on paper-r070 at 0.2 N·m
    assert main(["simulate", "--object", str(OBJECTS / "tissue_sample.toml"), "--json"]) == 0
    tissue = json.loads(capsys.readouterr().out)
    assert main(["simulate", "--json"]) == 0
    paper = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(tissue["jaw_angles_rad"], paper["jaw_angles_rad"], atol=1e-9)


def test_verify_refuses_a_run_for_another_object(tmp_path, capsys):
    from optim.run import run_optimize

    run_optimize("random", obj=load_object(OBJECTS / "tissue_sample.toml"), budget=20,
                 out=tmp_path, progress=False, verbose=False, finish=False)
    assert main(["verify", str(tmp_path), "--object", str(OBJECTS / "foam_disk.toml")]) == 2
    assert "was for another object (radius_m" in capsys.readouterr().err


def test_the_build_sheet_places_the_fingers_like_the_model():
    from envs.render import finger_polygon
    from envs.scene import Design

    design = {"finger_length_m": 0.05, "rest_angle_rad": 0.3, "joint_offset_m": 0.002,
              "finger_width_m": 0.004, "torque_nm": 0.01, "distance_m": 0.02}
    obj = {"name": "x", "radius_m": 0.01, "torsion_stiffness_nm_per_rad": 0.003}
    sheet = build_sheet(design, obj)
    row = Design(**design).to_array()
    for side, key in ((0, "right"), (1, "left")):
        corners = np.array(sheet["finger_outline_mm"][key]) / 1e3
        expected = finger_polygon(row[0], row[1], row[2], row[3], side)
        # the same four corners (in its own order), to the sheet's 0.1 um rounding
        assert np.abs(np.sort(corners, axis=0) - np.sort(expected, axis=0)).max() < 1e-7
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert sheet["object_centre_mm"] == [0.0, pytest.approx(30.0)]


def test_results_stay_valid_json_and_a_preset_keeps_its_spring(tmp_path):
    from optim.result import to_jsonable

    assert to_jsonable({"mu": np.float64(np.inf), "nan": np.float64(np.nan)}) == {
        "mu": "inf", "nan": None}
    problem = DesignProblem.from_scene("forceps-a", torsion_stiffness_nm_per_rad=None)
    assert problem.torsion_stiffness_nm_per_rad == 1e-3  # the preset's own gripper spring
    path = tmp_path / "o.toml"
    path.write_text("[object]\nradius_m = 0.01\nyoungs_modulus_pa = 1e5\npoisson_ratio = 0.4\n"
                    "thickness_m = 0.01\nfriction_coefficient = 0.0\n")
    with pytest.raises(ValueError, match=r"friction_coefficient = 0.0 is outside the allowed "
                                         r"range \(0, 10\]"):
        load_object(path)
