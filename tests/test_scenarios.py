"""Scenarios: the deterministic set, the design x scenario batch, the robust reward, and designs
that survive their bench (object ranges, placement tolerance)."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from envs.evaluate import DesignBounds, evaluate_designs
from envs.object_file import load_object, parse_object
from envs.scenarios import Scenarios, evaluate_scenarios, robust_reward
from envs.scene import DESIGN_FIELDS, Scene, SoftDisk
from optim.problem import DesignProblem

KF = 0.073  # the paper gripper's spring [N·m/rad]
EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "objects"
D1 = DESIGN_FIELDS.index("distance_m")


@pytest.fixture(scope="module")
def paper_disk() -> SoftDisk:
    return Scene.preset("paper-r070").disk


@pytest.fixture(scope="module")
def designs(paper_disk) -> np.ndarray:
    return DesignBounds().sample(np.random.default_rng(3), 24, paper_disk)


def test_the_set_is_corners_face_centres_and_centre():
    assert len(Scenarios().scenarios()) == 1
    one = Scenarios.of({"radius_m": (0.01, 0.02)})
    assert [s.values["radius_m"] for s in one.scenarios()] == [0.015, 0.01, 0.02]
    two = Scenarios.of(placement_tolerance_m=0.002)
    pts = {(s.dx_m, s.dy_m) for s in two.scenarios()}
    assert pts == {(a, b) for a in (-0.002, 0.0, 0.002) for b in (-0.002, 0.0, 0.002)}
    assert two.scenarios()[0].label == "nominal"
    three = Scenarios.of({"radius_m": (0.01, 0.02), "youngs_modulus_pa": (1e5, 3e5)}, (0.001, 0))
    assert len(three.scenarios()) == 2**3 + 2 * 3 + 1
    assert three.varied == ("radius_m", "youngs_modulus_pa", "dy_m")


def test_bad_scenarios_are_named():
    with pytest.raises(ValueError, match="unknown field 'strain_limit'"):
        Scenarios.of({"strain_limit": (0.1, 0.2)})
    with pytest.raises(ValueError, match="low = 0.02 must not exceed"):
        Scenarios.of({"radius_m": (0.02, 0.01)})
    with pytest.raises(ValueError, match="placement_tolerance_m"):
        Scenarios.of(placement_tolerance_m="1 mm")
    with pytest.raises(ValueError, match=r"placement_tolerance_m\[1\] = -0.001 is outside"):
        Scenarios.of(placement_tolerance_m=(0.001, -0.001))
    with pytest.raises(ValueError, match="placement_across_m"):
        Scenarios(placement_across_m=-0.001)


def test_no_variation_is_the_plain_evaluation(paper_disk, designs):
    table = evaluate_scenarios(designs, paper_disk, Scenarios(), torsion_stiffness_nm_per_rad=KF,
                               friction_coefficient=0.5)
    plain = evaluate_designs(designs, paper_disk, torsion_stiffness_nm_per_rad=KF)
    for key in ("reward", "peak_compression", "jaw_angles_rad", "holds"):
        np.testing.assert_array_equal(table.per_scenario[key][:, 0], plain[key])
        np.testing.assert_array_equal(table.summary[key], plain[key])


@pytest.mark.parametrize("warm_start", [False, True])
def test_each_scenario_is_its_own_grasp(paper_disk, designs, warm_start):
    """Every (design, scenario) answer equals an independent evaluate_designs of that object
    placed there: the centre fixed where placed, a scenario's radius moving its nearest point.
    Solved from rest, bit for bit; from the nominal scenario's answer (the fast path of
    envs.solver.follow), within the solver's tolerance."""
    sc = Scenarios.of({"radius_m": (0.06, 0.08), "friction_coefficient": (0.3, 0.7)},
                      (0.003, 0.002))
    table = evaluate_scenarios(designs, paper_disk, sc, torsion_stiffness_nm_per_rad=KF,
                               friction_coefficient=0.5, warm_start=warm_start)
    same = (np.testing.assert_array_equal if not warm_start
            else lambda a, b: np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-9))
    for j, s in enumerate(table.scenarios):
        radius = s.values.get("radius_m", paper_disk.radius_m)
        rows = designs.copy()
        rows[:, D1] += paper_disk.radius_m + s.dy_m - radius
        disk = SoftDisk(radius, 0.0, paper_disk.youngs_modulus_pa, paper_disk.poisson_ratio,
                        paper_disk.thickness_m, density_kg_m3=paper_disk.density_kg_m3)
        alone = evaluate_designs(rows, disk, torsion_stiffness_nm_per_rad=KF,
                                 friction_coefficients=s.values.get("friction_coefficient",
                                                                    0.5),
                                 offsets_x_m=s.dx_m)
        same(table.per_scenario["reward"][:, j], alone["reward"])
        same(table.per_scenario["jaw_angles_rad"][:, j], alone["jaw_angles_rad"])
        np.testing.assert_array_equal(table.per_scenario["converged"][:, j], alone["converged"])
    r = table.per_scenario["reward"]
    np.testing.assert_array_equal(table.summary["reward"], r.min(axis=1))
    np.testing.assert_array_equal(table.summary["reward_nominal"], r[:, 0])
    worst = table.summary["worst_scenario"]
    pick = np.arange(r.shape[0])
    np.testing.assert_array_equal(r[pick, worst], r.min(axis=1))
    _check_governing_and_envelopes(table)


def _check_governing_and_envelopes(table):
    """The summary row is the governing (lowest reward) scenario's own row, so its terms give
    its reward; the envelopes over the scenarios are fields of their own."""
    from envs.evaluate import METRIC_KEYS

    per, summary = table.per_scenario, table.summary
    worst = summary["worst_scenario"]
    pick = np.arange(worst.size)
    for key in METRIC_KEYS:
        if key != "reward":  # (the robust measure's: the worst scenario's here)
            np.testing.assert_array_equal(summary[key], per[key][pick, worst], err_msg=key)
    terms = sum(summary[k] for k in ("reward_contact", "reward_deform", "penalty_slip",
                                     "penalty_miss", "penalty_gap", "penalty_invalid",
                                     "penalty_fail"))
    np.testing.assert_allclose(terms, summary["reward"], rtol=0, atol=1e-12)
    assert [table.scenarios[w].label for w in worst] == list(summary["governing_scenario"])
    within = per["holds"] & (per["peak_compression"] <= per["strain_limit"])
    np.testing.assert_array_equal(summary["holds_all"], within.all(axis=1))
    np.testing.assert_array_equal(summary["scenarios_holding"], within.sum(axis=1))
    np.testing.assert_array_equal(summary["max_payload_n"], per["payload_n"].max(axis=1))
    np.testing.assert_array_equal(summary["max_peak_compression"],
                                  per["peak_compression"].max(axis=1))
    np.testing.assert_array_equal(summary["max_required_friction"],
                                  per["required_friction"].max(axis=1))
    np.testing.assert_array_equal(summary["min_contact_score"], per["contact_score"].min(axis=1))
    # feasible in every scenario is the governing row's feasibility (the reward's tiers)
    governing_ok = summary["holds"] & (summary["peak_compression"] <= summary["strain_limit"])
    np.testing.assert_array_equal(governing_ok, summary["holds_all"])


def test_a_displacement_across_is_mirror_symmetric(paper_disk, designs):
    """dx and -dx give the mirrored grasp of a symmetric gripper: the same reward."""
    sc = Scenarios(placement_across_m=0.004)
    table = evaluate_scenarios(designs, paper_disk, sc, torsion_stiffness_nm_per_rad=KF,
                               friction_coefficient=0.5)
    labels = [s.label for s in table.scenarios]
    minus, plus = labels.index("dx_m-"), labels.index("dx_m+")
    solved = table.per_scenario["converged"][:, minus] & table.per_scenario["converged"][:, plus]
    assert solved.sum() >= 10
    np.testing.assert_allclose(table.per_scenario["reward"][solved, minus],
                               table.per_scenario["reward"][solved, plus], atol=1e-6)
    np.testing.assert_allclose(table.per_scenario["jaw_angles_rad"][solved, minus],
                               table.per_scenario["jaw_angles_rad"][solved, plus][:, ::-1],
                               atol=1e-7)


def test_robust_measures():
    r = np.array([[0.1, -0.2, 0.3, 0.0], [1.0, 1.0, 1.0, 1.0]])
    np.testing.assert_allclose(robust_reward(r, "worst"), [-0.2, 1.0])
    np.testing.assert_allclose(robust_reward(r, "mean"), [0.05, 1.0])
    np.testing.assert_allclose(robust_reward(r, "cvar"), [-0.2, 1.0])  # ceil(0.25 * 4) = 1
    with pytest.raises(ValueError, match="robust must be one of"):
        robust_reward(r, "median")


def test_object_file_ranges_and_tolerance():
    spec = parse_object({"object": {"radius_m": [0.010, 0.015], "youngs_modulus_pa": [1e5, 3e5],
                                    "poisson_ratio": 0.45, "thickness_m": 0.02,
                                    "placement_tolerance_m": [0.002, 0.001]}}, "tomato.toml")
    assert spec.disk.radius_m == pytest.approx(0.0125)
    assert spec.disk.youngs_modulus_pa == pytest.approx(2e5)
    assert spec.scenarios.ranges["radius_m"] == (0.010, 0.015)
    assert (spec.scenarios.placement_along_m, spec.scenarios.placement_across_m) == (0.002, 0.001)
    base = {"radius_m": 0.01, "youngs_modulus_pa": 1e5, "poisson_ratio": 0.45,
            "thickness_m": 0.02}
    with pytest.raises(ValueError, match=r"tomato.toml: \[object\]: strain_limit must be a "
                                         "number"):
        parse_object({"object": {**base, "strain_limit": [0.1, 0.2]}}, "tomato.toml")
    with pytest.raises(ValueError, match="low must not exceed high"):
        parse_object({"object": {**base, "radius_m": [0.02, 0.01]}}, "tomato.toml")
    with pytest.raises(ValueError, match=r"radius_m = \[0.01, -1\]: its high end: radius_m = -1 "):
        parse_object({"object": {**base, "radius_m": [0.01, -1]}}, "tomato.toml")
    with pytest.raises(ValueError, match="placement_tolerance_m"):
        parse_object({"object": {**base, "placement_tolerance_m": -0.001}}, "tomato.toml")


def test_problem_with_scenarios_is_one_gripper_for_all(paper_disk):
    sc = Scenarios.of({"radius_m": (0.06, 0.08)}, 0.002)
    problem = DesignProblem(paper_disk, scenarios=sc, torsion_stiffness_rel=0.0149)
    assert problem.disk.radius_m == pytest.approx(0.07)
    x = np.zeros((3, 6))
    out = problem.evaluate(x)
    table = problem.evaluate_scenarios(problem.to_physical(x))
    np.testing.assert_array_equal(out["reward"], table.per_scenario["reward"].min(axis=1))
    assert problem.object_info()["scenarios"]["ranges"]["radius_m"] == [0.06, 0.08]
    with pytest.raises(ValueError, match="robust must be one of"):
        DesignProblem(paper_disk, scenarios=sc, robust="best")


def _grid_check(design: dict, disk: SoftDisk, kf: float, mu: float, limit: float,
                offsets: list[tuple[float, float]], disks: list[SoftDisk]):
    """Independent check through the API: the design on every (disk, offset) of a grid."""
    rows, ds, dx = [], [], []
    base = np.array([design[k] for k in DESIGN_FIELDS])
    centre_y = base[D1] + disk.radius_m
    for d in disks:
        for ox, oy in offsets:
            row = base.copy()
            row[D1] = centre_y + oy - d.radius_m
            rows.append(row)
            ds.append(d)
            dx.append(ox)
    return evaluate_designs(np.array(rows), ds, offsets_x_m=np.array(dx),
                            torsion_stiffness_nm_per_rad=kf, friction_coefficients=mu,
                            strain_limits=limit)


def _optimize(problem: DesignProblem, budget: int):
    from optim.cmaes import run_cmaes

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_cmaes(problem, budget=budget, seed=0)


def test_a_strawberry_design_survives_its_placement_tolerance():
    """+-1.5 mm both ways: the robust optimum holds within the strain limit at every
    displacement of a 3 x 3 grid inside the box (checked independently, at half and full
    tolerance), and its worst case beats the nominal optimum's worst case."""
    spec = load_object(EXAMPLES / "strawberry.toml")
    disk, mu, limit = spec.disk, spec.friction_coefficient, spec.strain_limit
    tol = spec.scenarios.placement_along_m
    sc = spec.scenarios
    robust = DesignProblem(disk, limit, mu, scenarios=sc)
    nominal = DesignProblem(disk, limit, mu)
    best_robust = _optimize(robust, 600).best_design
    best_nominal = _optimize(nominal, 600).best_design
    kf = robust.torsion_stiffness_nm_per_rad
    for frac in (0.5, 1.0):
        grid = [(a * frac * tol, b * frac * tol) for a in (-1, 0, 1) for b in (-1, 0, 1)]
        out = _grid_check(best_robust, disk, kf, mu, limit, grid, [disk])
        assert out["holds"].all(), out["required_friction"]
        assert (out["peak_compression"] <= limit).all()
    worst = {name: robust.evaluate_physical(
        np.array([[d[k] for k in DESIGN_FIELDS]]))["reward"][0]
        for name, d in (("robust", best_robust), ("nominal", best_nominal))}
    assert worst["robust"] > worst["nominal"]


def test_one_design_serves_tomatoes_of_a_range():
    """Tomatoes of 10-15 mm and 100-300 kPa (examples/objects/tomatoes_10_15mm.toml): one
    design holds within the strain limit on a 3 x 3 grid of the ranges."""
    spec = load_object(EXAMPLES / "tomatoes_10_15mm.toml")
    limit, mu = spec.strain_limit, spec.friction_coefficient
    problem = DesignProblem(spec.disk, limit, mu, scenarios=spec.scenarios)
    best = _optimize(problem, 1500).best_design
    disks = [replace(spec.disk, radius_m=r, youngs_modulus_pa=e) for r in (0.010, 0.0125, 0.015)
             for e in (1e5, 2e5, 3e5)]
    out = _grid_check(best, problem.disk, problem.torsion_stiffness_nm_per_rad, mu, limit,
                      [(0.0, 0.0)], disks)
    assert out["holds"].all()
    assert (out["peak_compression"] <= limit).all()
    assert math.isfinite(problem.best_reward)


def test_verify_solves_each_design_with_the_fem_in_its_worst_scenario():
    """A run with a placement tolerance: verify puts each kept design, with the FEM, in the
    scenario where the ranking member scores it worst, and confirms the reward model's reward
    there (a coarse FEM mesh, ~seconds)."""
    pytest.importorskip("skfem")
    from envs.scenarios import place
    from optim.finish import RANKING_MEMBER, finish_result
    from optim.verify import verify_result

    disk = Scene.preset("paper-r070").disk
    sc = Scenarios.of(placement_tolerance_m=0.002)
    problem = DesignProblem(disk, scenarios=sc, torsion_stiffness_nm_per_rad=KF)
    result = finish_result(problem, _optimize(problem, 120))
    report = verify_result(result, top=2, fem_rings=4)
    designs = np.array([[p["design"][k] for k in DESIGN_FIELDS] for p in result.top_designs[:2]])
    fine = problem.evaluate_scenarios(designs, RANKING_MEMBER)
    worst = fine.summary["worst_scenario"]
    for i, row in enumerate(report["designs"]):
        case = fine.scenarios[int(worst[i])]
        assert row["fem_scenario"] == case.label
        assert row["reward_model_at_fem_scenario"] == pytest.approx(
            fine.per_scenario["reward"][i, worst[i]], abs=1e-12)
        # the FEM's answer is that scenario's grasp, placed and displaced like the model's
        rows, disks, frictions, offsets = place(designs[i : i + 1], problem.disk, 0.5, [case])
        alone = evaluate_designs(rows, disks, friction_coefficients=frictions,
                                 offsets_x_m=offsets, torsion_stiffness_nm_per_rad=KF,
                                 fidelity="fem", fem_rings=4)
        assert row["fem"]["reward"] == pytest.approx(float(alone["reward"][0]), abs=1e-12)
    s = report["summary"]
    best = s["reported_row"]
    assert s["best_confirmed"] == (
        abs(report["designs"][best]["reward_model_at_fem_scenario"] - s["fem_reward_of_reported"])
        <= s["confirm_margin"])
