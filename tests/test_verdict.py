"""One scenario per number, and a design that does not hold says so everywhere: the summary
line's terms give its reward, the sheet's payload is the largest scenario's, the banner on the
sheet, its CSV, the drawing and the best-grasp figure, and ``verify`` exits 3."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from cli.main import main
from optim import OptimResult
from optim.design_verdict import verdict_of
from optim.sheet import drawing_figure, write_build_sheet
from optim.verify import NO_GRASP_EXIT, NOT_CONFIRMED_EXIT, verify_exit_code

OBJ = {"name": "berry", "radius_m": 0.008, "thickness_m": 0.016, "youngs_modulus_pa": 4e5,
       "poisson_ratio": 0.45, "strain_limit": 0.08, "friction_coefficient": 0.5,
       "density_kg_m3": 1000.0, "payload_factor": 2.0, "torsion_stiffness_nm_per_rad": 0.002}
DESIGN = {"finger_length_m": 0.04, "rest_angle_rad": 0.5, "joint_offset_m": 0.003,
          "finger_width_m": 0.004, "torque_nm": 0.01, "distance_m": 0.01}
EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "objects"
TERM = re.compile(r"(contact|deform|slip|miss|gap|invalid|fail) ([+-]\d+\.\d+)")


def _row(label, holds, compression, need, payload, reward):
    return {"scenario": {"label": label, "dx_m": 0.0, "dy_m": 0.0}, "valid_at_rest": True,
            "converged": True, "touching": [True, True], "holds": holds,
            "peak_compression": compression, "strain_limit": 0.08, "required_friction": need,
            "friction_coefficient": 0.5, "payload_n": payload, "grip_force_n": 1.0,
            "reward": reward, "jaw_angles_rad": [0.3, 0.3]}


ROWS = [_row("nominal", True, 0.05, 0.3, 0.035, 0.02),
        _row("radius_m+", False, 0.06, 0.7, 0.079, -1.2),
        _row("radius_m-", True, 0.09, 0.2, 0.020, -0.3)]


def test_the_verdict_counts_the_scenarios_and_names_the_limits():
    verdict = verdict_of(ROWS[0], ROWS)
    assert (verdict.total, verdict.failing, verdict.holds) == (3, 2, False)
    assert verdict.banner == ("DOES NOT HOLD in 2 of 3 scenarios: limited by friction (1), the "
                              "strain limit (1)")
    assert verdict_of(ROWS[0]).holds and verdict_of(ROWS[0]).banner is None
    heavy = {**ROWS[0], "holds": False, "payload_n": 2.0, "grip_force_n": 1.0}
    assert verdict_of(heavy).banner == "DOES NOT HOLD its object: limited by the payload"


def test_a_design_that_does_not_hold_carries_the_banner(tmp_path):
    metrics = {**ROWS[1], "governing_scenario": "radius_m+", "max_payload_n": 0.079}
    paths = write_build_sheet(DESIGN, OBJ, tmp_path, "b", metrics, ROWS)
    sheet = json.loads(paths["design_json"].read_text())
    banner = "DOES NOT HOLD in 2 of 3 scenarios: limited by friction (1), the strain limit (1)"
    assert sheet["verdict"]["banner"] == banner and sheet["verdict"]["holds"] is False
    with paths["design_csv"].open() as f:
        first = next(csv.DictReader(f))
    assert (first["quantity"], first["value"]) == ("WARNING", banner)
    fig = drawing_figure(sheet)
    assert fig._suptitle is not None and fig._suptitle.get_text() == banner
    # the sheet's payload is the largest any scenario puts on the gripper, not the nominal's
    cond = {r["quantity"]: r["value"] for r in sheet["conditions"]}
    assert cond["payload_n"] == 0.079
    # and the grasp it states is the governing scenario's own, named
    assert sheet["grasp"]["scenario"] == "radius_m+" and sheet["grasp"]["holds"] is False
    holding = write_build_sheet(DESIGN, OBJ, tmp_path, "h", ROWS[0], ROWS[:1])
    sheet = json.loads(holding["design_json"].read_text())
    assert sheet["verdict"]["banner"] is None and drawing_figure(sheet)._suptitle is None


def test_the_best_grasp_figure_carries_the_banner():
    from optim.charts import best_grasp_figure

    result = OptimResult("cmaes", 0, 10, DESIGN, -1.2, {**ROWS[1]}, (10,), (-1.2,), (1.0,), 10,
                         1.0, object={**OBJ, "stiffness_scale": 1.0},
                         extra={"scenario_rows": ROWS})
    fig = best_grasp_figure(result)
    assert fig._suptitle.get_text().startswith("DOES NOT HOLD in 2 of 3 scenarios")


def test_the_exit_code_of_a_verification():
    ok = {"reported_holds": True, "best_confirmed": True, "all_fem_converged": True}
    assert verify_exit_code({"summary": ok}) == 0
    assert verify_exit_code({"summary": {**ok, "all_fem_converged": False}}) == 1
    assert verify_exit_code({"summary": {**ok, "best_confirmed": False,
                                         "all_fem_converged": False}}) == NOT_CONFIRMED_EXIT
    assert verify_exit_code({"summary": {**ok, "reported_holds": False,
                                         "best_confirmed": False}}) == NO_GRASP_EXIT == 3


def test_verify_exits_3_on_a_design_that_does_not_hold(tmp_path, capsys):
    """A run whose reported design is invalid at rest (the fingers through the object): the
    FEM has nothing to solve, and verify says the design does not hold."""
    pytest.importorskip("skfem")
    from envs.scene import Scene

    disk = Scene.preset("paper-r070").disk
    design = {**DESIGN, "finger_length_m": 0.2, "rest_angle_rad": 0.2, "joint_offset_m": 0.02,
              "finger_width_m": 0.01, "torque_nm": 0.1, "distance_m": 0.0}
    obj = {"name": "disk", "radius_m": disk.radius_m, "youngs_modulus_pa": 1e5,
           "poisson_ratio": 0.45, "thickness_m": 0.01, "stiffness_scale": 1.0,
           "strain_limit": 0.1, "friction_coefficient": 0.5, "payload_factor": 0.0,
           "torsion_stiffness_nm_per_rad": 0.073}
    OptimResult("cmaes", 0, 1, design, -4.0, {"valid_at_rest": False}, (1,), (-4.0,), (0.1,),
                1, 0.1, object=obj, top_designs=({"design": design, "reward": -4.0},)
                ).to_json(tmp_path / "cmaes_seed0_result.json")
    assert main(["verify", str(tmp_path), "--top", "1"]) == NO_GRASP_EXIT
    err = capsys.readouterr().err
    assert "the reported design does not hold its object" in err


def test_the_summary_line_names_its_scenario_and_its_terms_give_its_reward():
    metrics = {**ROWS[0], "reward_contact": 0.075, "reward_deform": -0.2302,
               "penalty_slip": 0.0, "penalty_miss": 0.0, "penalty_gap": 0.0,
               "penalty_invalid": 0.0, "penalty_fail": 0.0, "reward": -0.1552,
               "governing_scenario": "radius_m+ dx_m-", "n_scenarios": 25,
               "contact_score": 0.075}
    for robust, reward in (("worst", -0.1552), ("mean", 0.0123)):
        result = OptimResult("cmaes", 0, 10, DESIGN, reward, metrics, (10,), (reward,), (1.0,),
                             10, 1.0, object={**OBJ, "robust": robust})
        line = result.summary()
        assert "governing scenario 'radius_m+ dx_m-'" in line and "25" in line
        terms = sum(float(v) for _, v in TERM.findall(line))
        stated = float(re.search(r"(?:reward|scores) (-?\d+\.\d+) =", line)[1])
        assert terms == pytest.approx(stated, abs=1e-4)
        assert stated == pytest.approx(metrics["reward"])
        if robust == "mean":
            assert "best reward 0.0123 (mean over 25 scenarios" in line


@pytest.fixture(scope="module")
def tomato_run(tmp_path_factory):
    """A short run for tomatoes of 10-15 mm built within a workshop's tolerances (7 scenario
    dimensions: the covering set in the search, every corner for the reported design)."""
    out = tmp_path_factory.mktemp("tomatoes")
    import contextlib
    import io

    from envs.object_file import load_object
    from envs.tolerances import parse_tolerances
    from optim.run import run_optimize

    obj = load_object(EXAMPLES / "tomatoes_10_15mm.toml")
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        result, paths = run_optimize(
            "cmaes", obj=obj, budget=12, out=out, progress=False, finish=False,
            tolerances=parse_tolerances({"length_mm": 0.1, "angle_deg": 0.5,
                                         "spring_percent": 10, "torque_percent": 5}))
    return result, paths, printed.getvalue()


def test_a_run_prints_one_scenario_per_number(tomato_run):
    result, paths, printed = tomato_run
    line = printed.splitlines()[0]
    rows = result.extra["scenario_rows"]
    assert result.extra["scenario_set"] == "full" and len(rows) == 1 + 2 * 7 + 2**7
    governing = min(rows, key=lambda r: r["reward"])
    assert f"governing scenario {governing['scenario']['label']!r} of {len(rows)}" in line
    stated = float(re.search(r"best reward (-?\d+\.\d+) =", line)[1])
    terms = sum(float(v) for _, v in TERM.findall(line.split(" (governing")[0]))
    assert terms == pytest.approx(stated, abs=1e-4 * 3)
    assert stated == pytest.approx(governing["reward"], abs=5e-5) == result.best_reward
    m = result.best_metrics
    assert m["contact_score"] == governing["contact_score"]  # the governing scenario's own
    assert m["max_payload_n"] == max(r["payload_n"] for r in rows) > rows[0]["payload_n"]
    assert "largest payload" in printed and "largest friction needed" in printed
    sheet = json.loads(paths["design_json"].read_text())
    cond = {r["quantity"]: r["value"] for r in sheet["conditions"]}
    assert cond["payload_n"] == m["max_payload_n"]  # the 15 mm tomato's, not the nominal's
    assert sheet["checked"]["tolerances"] == {"length_mm": pytest.approx(0.1),
                                              "angle_deg": pytest.approx(0.5),
                                              "torque_percent": pytest.approx(5.0),
                                              "spring_percent": pytest.approx(10.0)}
    assert "every corner" in sheet["checked"]["scenario_set"]
    verdict = sheet["verdict"]
    assert verdict["holds"] == result.extra["grasp_found"]
    assert (verdict["banner"] is None) == verdict["holds"]
    assert (verdict["banner"] or "") in printed
