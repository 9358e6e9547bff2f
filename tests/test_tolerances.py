"""Manufacturing tolerances as scenario dimensions (envs.tolerances), the covering set beyond
five dimensions, the object file's [gripper.tolerances] and --tolerances, and a placement
tolerance larger than the object refused with a unit hint."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from envs.evaluate import DesignBounds, evaluate_designs
from envs.object_file import parse_object
from envs.scenarios import FULL_CORNER_DIMS, Scenarios, covering_corners, evaluate_scenarios
from envs.scene import DESIGN_FIELDS, Scene
from envs.tolerances import Tolerances, parse_tolerances

KF = 0.073
COLUMN = {name: DESIGN_FIELDS.index(name) for name in DESIGN_FIELDS}
TOLERANCES = Tolerances(length_m=2e-4, angle_rad=math.radians(1.0), torque_rel=0.1,
                        spring_rel=0.2)
OBJECT = {"radius_m": 0.012, "youngs_modulus_pa": 1.5e5, "poisson_ratio": 0.45,
          "thickness_m": 0.024}


@pytest.mark.parametrize("k", range(FULL_CORNER_DIMS + 1, 20))
def test_the_covering_set_is_a_balanced_orthogonal_fold_over(k):
    corners = covering_corners(k)
    assert corners.shape[1] == k and set(np.unique(corners)) == {-1.0, 1.0}
    assert len(corners) < 2**k and len(np.unique(corners, axis=0)) == len(corners)
    np.testing.assert_array_equal(corners.sum(axis=0), 0)  # each end in half of them
    gram = corners.T @ corners
    np.testing.assert_array_equal(gram, len(corners) * np.eye(k))  # orthogonal columns
    # resolution IV: no main effect aliased with a two-quantity interaction
    for a, b, c in itertools.combinations(range(k), 3):
        assert abs(corners[:, a] @ (corners[:, b] * corners[:, c])) < len(corners)


def test_the_tolerances_are_dimensions_of_the_set():
    sc = Scenarios.of({}, 0.002, TOLERANCES)
    assert sc.varied == ("dx_m", "dy_m", "finger_length_m", "finger_width_m",
                         "joint_offset_m", "rest_angle_rad", "closing_moment")
    assert sc.uses_covering_set
    assert len(sc.scenarios()) == 1 + 2 * 7 + 16  # centre, face centres, the fold-over of 8
    assert len(sc.scenarios(full=True)) == 1 + 2 * 7 + 2**7
    small = Scenarios.of({}, None, Tolerances(angle_rad=0.01, torque_rel=0.05))
    assert not small.uses_covering_set and len(small.scenarios()) == 9
    closing = next(s for s in small.scenarios() if s.label == "closing_moment+")
    assert closing.design == {"torque_rel": 0.05, "spring_rel": -0.0}
    assert Scenarios.from_dict(sc.as_dict()) == sc
    assert "tolerances" not in Scenarios.of({}, 0.002).as_dict()


def test_each_built_scenario_is_its_own_grasp():
    """A scenario of the design as built equals an independent evaluate_designs of the changed
    design row with the changed spring."""
    disk = Scene.preset("paper-r070").disk
    designs = DesignBounds().sample(np.random.default_rng(5), 6, disk)
    designs[:, COLUMN["joint_offset_m"]][0] = 0.0  # a common pivot stays one
    sc = Scenarios.of({}, None, TOLERANCES)
    table = evaluate_scenarios(designs, disk, sc, torsion_stiffness_nm_per_rad=KF,
                               friction_coefficient=0.5, warm_start=False)
    for j, s in enumerate(table.scenarios):
        rows = designs.copy()
        d = s.design
        for name in ("finger_length_m", "finger_width_m", "rest_angle_rad"):
            rows[:, COLUMN[name]] += d.get(name, 0.0)
        offset = rows[:, COLUMN["joint_offset_m"]]
        rows[:, COLUMN["joint_offset_m"]] = np.where(
            offset > 0, np.maximum(offset + d.get("joint_offset_m", 0.0), 0.0), 0.0)
        rows[:, COLUMN["torque_nm"]] *= 1.0 + d.get("torque_rel", 0.0)
        alone = evaluate_designs(rows, disk, torsion_stiffness_nm_per_rad=KF * (
            1.0 + d.get("spring_rel", 0.0)))
        np.testing.assert_array_equal(table.per_scenario["reward"][:, j], alone["reward"])
        np.testing.assert_array_equal(table.per_scenario["jaw_angles_rad"][:, j],
                                      alone["jaw_angles_rad"])
    # the weakest closing (torque low, spring high) closes least
    labels = [s.label for s in table.scenarios]
    weak, strong = labels.index("closing_moment-"), labels.index("closing_moment+")
    ok = table.per_scenario["converged"][:, [weak, strong]].all(axis=1)
    angles = table.per_scenario["jaw_angles_rad"][ok][:, [weak, strong], 0]
    assert ok.sum() >= 2 and np.all(angles[:, 0] >= angles[:, 1])


def test_the_object_file_and_the_option_give_tolerances():
    spec = parse_object({"object": OBJECT, "gripper": {"tolerances": {
        "length_mm": 0.1, "angle_deg": 0.5, "spring_percent": 10, "torque_percent": 5}}}, "f")
    assert spec.gripper is None  # a [gripper] table of tolerances alone
    assert spec.tolerances == Tolerances(1e-4, math.radians(0.5), 0.05, 0.1)
    assert spec.scenarios.tolerances == spec.tolerances
    assert spec.info()["scenarios"]["tolerances"]["spring_rel"] == pytest.approx(0.1)
    from cli.optimize import tolerances_option

    assert tolerances_option("length=0.1,angle=0.5,spring=10,torque=5") == spec.tolerances
    for bad, match in (({"length_mm": -0.1}, r"length_mm = -0.1 is outside \[0, 10\]"),
                       ({"spring_percent": 80}, r"spring_percent = 80 is outside \[0, 50\]"),
                       ({"lenght_mm": 0.1}, "unknown key 'lenght_mm'"),
                       ({"angle_deg": "1"}, "angle_deg must be a number")):
        with pytest.raises(ValueError, match=match):
            parse_object({"object": OBJECT, "gripper": {"tolerances": bad}}, "f")
    with pytest.raises(ValueError, match="KEY=VALUE"):
        tolerances_option("0.1")
    with pytest.raises(ValueError, match="tolerances: unknown key 'colour'"):
        parse_tolerances({"colour": 1})


def test_a_placement_tolerance_larger_than_the_object_is_refused_with_a_unit_hint():
    with pytest.raises(ValueError, match=r"placement_tolerance_m \(along the axis\) = 0.5 m "
                       r"exceeds the object's radius 0.012 m: was it typed in millimetres\? "
                       r"0.5 mm is 0.0005 m"):
        parse_object({"object": {**OBJECT, "placement_tolerance_m": 0.5}}, "f")
    # beyond the radius but not ten times it: refused, without a guess at the unit
    with pytest.raises(ValueError, match=r"= 0.02 m exceeds the object's radius 0.012 m$"):
        parse_object({"object": {**OBJECT, "placement_tolerance_m": 0.02}}, "f")
    disk = Scene.preset("paper-r070").disk
    with pytest.raises(ValueError, match="exceeds the object's radius"):
        Scenarios.of({}, 0.5).nominal_disk(disk)
    from optim.problem import DesignProblem

    with pytest.raises(ValueError, match="typed in millimetres"):
        DesignProblem(disk, scenarios=Scenarios.of({}, (0.002, 0.9)))


@pytest.mark.slow
def test_a_design_optimized_with_tolerances_holds_in_every_corner_as_built(tmp_path):
    """The strawberry (placed within +-1.5 mm) built within +-0.1 mm, +-0.5 deg, spring +-10 %
    and torque +-5 %: the optimized design, rebuilt from its build sheet's numbers at every
    corner of the box (placement and build, 2^7) and evaluated independently through
    evaluate_designs with the model that reported it, holds within the strain limit in each."""
    import json

    from cli.main import main

    code = main(["optimize", "--object", "examples/objects/strawberry.toml", "--budget", "300",
                 "--method", "cmaes",
                 "--tolerances", "length=0.1,angle=0.5,spring=10,torque=5", "--no-progress",
                 "--out", str(tmp_path)])
    assert code == 0
    sheet = json.loads((tmp_path / "cmaes_seed0_design.json").read_text())
    result = json.loads((tmp_path / "cmaes_seed0_result.json").read_text())
    rows = {r["quantity"]: r["value"] for r in sheet["rows"]}
    cond = {r["quantity"]: r["value"] for r in sheet["conditions"]}
    tol = sheet["checked"]["tolerances"]
    spec = parse_object({"object": {"radius_m": rows["object_diameter_mm"] / 2e3,
                                    "youngs_modulus_pa": sheet["object"]["youngs_modulus_pa"],
                                    "poisson_ratio": sheet["object"]["poisson_ratio"],
                                    "thickness_m": sheet["object"]["thickness_mm"] / 1e3,
                                    "density_kg_m3": sheet["object"]["density_kg_m3"]}}, "f")
    nominal = np.array([rows["finger_length_mm"] / 1e3, math.radians(rows["rest_angle_deg"]),
                        rows["joint_offset_mm"] / 1e3, rows["finger_width_mm"] / 1e3,
                        rows["torque_nm"], rows["object_distance_mm"] / 1e3])
    designs, springs, offsets = [], [], []
    for dx, dy, dl, dw, dd, da, closing in itertools.product((-1.0, 1.0), repeat=7):
        row = nominal.copy()
        row[COLUMN["finger_length_m"]] += dl * tol["length_mm"] / 1e3
        row[COLUMN["finger_width_m"]] += dw * tol["length_mm"] / 1e3
        if row[COLUMN["joint_offset_m"]] > 0.0:
            row[COLUMN["joint_offset_m"]] = max(0.0, row[COLUMN["joint_offset_m"]]
                                                + dd * tol["length_mm"] / 1e3)
        row[COLUMN["rest_angle_rad"]] += da * math.radians(tol["angle_deg"])
        row[COLUMN["torque_nm"]] *= 1.0 + closing * tol["torque_percent"] / 100
        row[COLUMN["distance_m"]] += dy * cond["placement_tolerance_along_mm"] / 1e3
        designs.append(row)
        springs.append(rows["torsion_stiffness_nm_per_rad"]
                       * (1.0 - closing * tol["spring_percent"] / 100))
        offsets.append(dx * cond["placement_tolerance_across_mm"] / 1e3)
    out = evaluate_designs(np.array(designs), spec.disk,
                           torsion_stiffness_nm_per_rad=np.array(springs),
                           offsets_x_m=np.array(offsets),
                           strain_limits=cond["strain_limit"],
                           friction_coefficients=cond["friction_coefficient"],
                           payload_factors=2.0, **result["extra"]["reward_model"])
    within = out["holds"] & (out["peak_compression"] <= cond["strain_limit"])
    assert within.all(), f"{int((~within).sum())} of 128 corners do not hold"
    assert sheet["verdict"]["holds"] and sheet["verdict"]["banner"] is None
