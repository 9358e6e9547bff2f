"""The default search (the portfolio), time as a budget, and what a run may claim (verdicts)."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pytest

from envs.design_space import JAW_RELATIVE_FIELDS
from optim import DesignProblem, OptimResult, optimize
from optim.problem import check_time_limit
from optim.verdict import (
    HOLDS,
    NO_GRASP_EXIT,
    NOTHING_HOLDS,
    UNDECIDED,
    UNDECIDED_EXIT,
    search_verdict,
    verdict_exit_code,
)

SCENE = "paper-r070"


def make_problem(**kwargs) -> DesignProblem:
    return DesignProblem.from_scene(SCENE, 0.15, payload_factor=0.0, **kwargs)


# --- time as a budget -------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [0, -1.0, math.nan, math.inf, "10", True, 1e9])
def test_time_limit_refused_by_name(bad):
    with pytest.raises(ValueError, match="time_limit_s"):
        check_time_limit(bad)


def test_time_limit_ends_a_run_after_its_batch():
    problem = make_problem()
    problem.evaluate(np.zeros((1, 6)))  # loads (or compiles) the kernels outside the clock
    problem.time_limit_s = 0.3
    t0 = time.perf_counter()
    result = optimize("random", problem, budget=10**6, seed=0, batch_size=20)
    elapsed = time.perf_counter() - t0
    assert result.extra["out_of_time"] and result.extra["time_limit_s"] == 0.3
    assert 0 < result.n_evaluations < 10**6
    # the run stops after the batch under way when the limit has passed, not before it
    assert result.history_wall_time_s[-1] >= 0.3
    assert all(t < 0.3 for t in result.history_wall_time_s[:-1])
    assert elapsed < 0.3 + 5.0
    assert problem.remaining == 0


def test_no_time_limit_spends_the_budget():
    problem = make_problem()
    result = optimize("random", problem, budget=40, seed=0)
    assert result.n_evaluations == 40 and not result.extra["out_of_time"]
    assert result.extra["time_limit_s"] is None


# --- the portfolio ----------------------------------------------------------------------------


def test_portfolio_spends_its_budget_exactly_and_repeats_by_seed():
    a = optimize("portfolio", make_problem(), budget=150, seed=3)
    b = optimize("portfolio", make_problem(), budget=150, seed=3)
    assert a.n_evaluations == 150 == a.history_evaluations[-1]
    assert a.best_reward == b.best_reward and a.best_design == b.best_design
    starts = a.extra["starts"]
    assert len(starts) >= 2
    assert sum(s["evaluations"] for s in starts) + a.extra["screened"] == 150
    # the run's best is one start's best or a screened design, never better than the record
    assert max(s["best_reward"] for s in starts) <= a.best_reward
    assert np.all(np.diff(a.history_best_reward) >= 0)


def test_portfolio_with_shaped_jaws_races_a_straight_bar_start():
    problem = make_problem(jaw="any")
    result = optimize("portfolio", problem, budget=200, seed=0)
    labels = [s["label"] for s in result.extra["starts"]]
    assert "straight bars" in labels
    straight = result.extra["start_designs"][labels.index("straight bars")]["design"]
    # a straight bar: the groove's depth is held at its low end, 0
    assert straight["jaw_depth_m"] == 0.0
    # every other start searches the grooves too
    depth = problem.bounds.fields.index(JAW_RELATIVE_FIELDS[0])
    assert depth >= 6


def test_portfolio_polishes_its_leader_alone_over_the_last_share():
    """Over the last POLISH_SHARE of the budget left after the screen the leading start runs
    alone (the others, the straight bars' included, stop), not before every start had
    MIN_STAGE_ROUNDS rounds since the last halving, and its best before the polish is kept for
    the finish."""
    from optim.portfolio import MIN_STAGE_ROUNDS, POLISH_SHARE

    budget = 1500
    problem = make_problem(jaw="any")
    result = optimize("portfolio", problem, budget=budget, seed=1)
    polish, starts = result.extra["polish"], result.extra["starts"]
    screened = result.extra["screened"]
    assert polish is not None
    assert polish["evaluations"] >= screened + (budget - screened) * (1.0 - POLISH_SHARE)
    leader = next(s for s in starts if s["label"] == polish["label"])
    assert leader["evaluations"] >= budget - polish["evaluations"]
    # every evaluation after the polish began is the leader's
    others = sum(s["evaluations"] for s in starts if s is not leader)
    assert others + leader["evaluations"] + screened == budget
    assert others <= polish["evaluations"] - screened
    # a halved start ran its rounds before it stopped
    assert min(s["evaluations"] for s in starts) >= MIN_STAGE_ROUNDS * 4
    # the leader led when it was chosen, and its best then is a candidate of the finish
    before = result.extra["start_designs"][-1]
    assert before["reward"] == polish["reward_before"]
    assert polish["reward_before"] >= max(s["best_reward"] for s in starts if s is not leader)
    assert leader["best_reward"] >= polish["reward_before"]


def test_portfolio_with_shaped_jaws_races_the_best_conforming_cradle():
    """With cradles in the box one start is the best screened conforming cradle (where the
    optima of shaped jaws lie); V-grooves have none."""
    from optim import portfolio

    problem = make_problem(jaw="any")
    result = optimize("portfolio", problem, budget=300, seed=0, polish=0.0)
    labels = [s["label"] for s in result.extra["starts"]]
    assert labels[:2] == [portfolio.STRAIGHT_LABEL, portfolio.CRADLE_LABEL]
    design = result.extra["start_designs"][1]["design"]
    r = problem.disk.radius_m
    # its best stays near a conforming cradle: a groove of bottom radius about the object's
    assert design["jaw_depth_m"] > 0.0
    assert 0.6 < design["jaw_bottom_radius_m"] / r < 2.0
    vee = optimize("portfolio", make_problem(jaw="vee"), budget=150, seed=0, polish=0.0)
    assert portfolio.CRADLE_LABEL not in [s["label"] for s in vee.extra["starts"]]


def test_portfolio_with_scenarios_races_its_starts_on_the_nominal_scenario_first():
    """With scenarios the starts first spend NOMINAL_RACE_SHARE of the budget on the nominal
    scenario (a scenario count's share of an evaluation a design), then race from their best
    there; the run's budget is spent exactly. Without scenarios there is no such race."""
    from envs.scenarios import Scenarios
    from optim.portfolio import NOMINAL_RACE_SHARE

    problem = DesignProblem.from_scene(SCENE, 0.15, payload_factor=0.0, jaw="any",
                                       scenarios=Scenarios.of({}, 0.002))
    budget = 300
    result = optimize("portfolio", problem, budget=budget, seed=0)
    nominal = result.extra["nominal_race"]
    k = problem.scenario_count
    assert k == 9 and result.n_evaluations == budget
    # its charge: up to its share, a batch short at most, each design a ninth
    batch = sum(1 for _ in result.extra["starts"]) * 16
    assert NOMINAL_RACE_SHARE * budget - batch / k <= nominal["evaluations"] \
        <= NOMINAL_RACE_SHARE * budget
    assert nominal["designs"] > 0.8 * k * nominal["evaluations"]  # (batches charged up)
    assert optimize("portfolio", make_problem(jaw="any"), budget=150,
                    seed=0).extra["nominal_race"] is None
    off = optimize("portfolio", DesignProblem.from_scene(
        SCENE, 0.15, payload_factor=0.0, jaw="any", scenarios=Scenarios.of({}, 0.002)),
        budget=budget, seed=0, nominal_race=0.0)
    assert off.extra["nominal_race"] is None


def test_portfolio_without_a_polish_races_to_the_end():
    result = optimize("portfolio", make_problem(jaw="any"), budget=300, seed=1, polish=0.0)
    assert result.extra["polish"] is None and result.n_evaluations == 300
    assert len(result.extra["start_designs"]) == len(result.extra["starts"])


@pytest.mark.parametrize("bad", [{"starts": 0}, {"starts": 2.5}, {"sigma0": 0.0},
                                 {"popsize": 1}, {"polish": -0.1}, {"polish": 0.95},
                                 {"polish": "0.4"}, {"polish": True}, {"nominal_race": -0.1},
                                 {"nominal_race": 0.6}, {"nominal_race": None}])
def test_portfolio_options_refused(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        optimize("portfolio", make_problem(), budget=20, seed=0, **bad)


# --- verdicts ---------------------------------------------------------------------------------


def _result(found: bool, starts=None, method="portfolio", search_found=None) -> OptimResult:
    extra = {"grasp_found": found}
    if starts is not None:
        extra["starts"] = starts
    if search_found is not None:
        extra["search_grasp_found"] = search_found
    metrics = {"valid_at_rest": True, "converged": True, "touching": [True, True],
               "holds": False, "required_friction": 0.9, "friction_coefficient": 0.5,
               "payload_n": 0.0, "grip_force_n": 1.0, "peak_compression": 0.01,
               "strain_limit": 0.1}
    return OptimResult(method=method, seed=0, budget=10, best_design={}, best_reward=-1.2,
                       best_metrics=metrics, history_evaluations=(10,),
                       history_best_reward=(-1.2,), history_wall_time_s=(1.0,),
                       n_evaluations=10, wall_time_s=1.0, object={"strain_limit": 0.1},
                       extra=extra)


def test_verdict_holds():
    v = search_verdict(_result(True, [{"label": "start 1", "holds": True}]))
    assert v["verdict"] == HOLDS and verdict_exit_code(v) == 0


def test_verdict_nothing_holds_needs_agreeing_starts():
    starts = [{"label": f"start {k}", "holds": False} for k in range(4)]
    v = search_verdict(_result(False, starts))
    assert v["verdict"] == NOTHING_HOLDS and verdict_exit_code(v) == NO_GRASP_EXIT
    assert "4 independent starts agree" in v["message"]
    assert "limited by friction" in v["message"]


def test_verdict_undecided_when_starts_disagree():
    starts = [{"label": "start 1", "holds": True}, {"label": "start 2", "holds": False}]
    v = search_verdict(_result(False, starts))
    assert v["verdict"] == UNDECIDED and verdict_exit_code(v) == UNDECIDED_EXIT
    assert "1 of 2 starts" in v["message"] and "--time" in v["message"]


def test_verdict_undecided_for_one_start():
    v = search_verdict(_result(False, None, method="cmaes", search_found=False))
    assert v["verdict"] == UNDECIDED and "one start (cmaes)" in v["message"]
    one = replace(_result(False, [{"label": "start 1", "holds": False}]))
    assert search_verdict(one)["verdict"] == UNDECIDED


# --- the search's groove coordinates ----------------------------------------------------------


def test_touch_foot_matches_a_closing_finger():
    """The closed form against a finger closed in small steps from rest: the first angle at
    which the straight face comes within one radius of the centre, and the foot there."""
    from envs.design_space import DesignBounds, touch_foot_r
    from envs.scene import design_from_relative

    rng = np.random.default_rng(4)
    bounds = DesignBounds()
    rel = bounds.relative(rng.uniform(-1, 1, (40, 6)))
    feet = touch_foot_r(rel)
    si = design_from_relative(rel, 1.0, 1.0)
    for row, foot in zip(si, feet, strict=True):
        length, rest, offset, width, _, distance = row
        centre, joint = np.array([0.0, distance + 1.0]), np.array([offset, 0.0])
        for theta in np.arange(rest, 0.0, -1e-5):
            e = np.array([np.sin(theta), np.cos(theta)])
            n = np.array([-np.cos(theta), np.sin(theta)])
            if n @ (centre - joint) - width / 2 <= 1.0:  # the face line meets the disk
                assert foot == pytest.approx(e @ (centre - joint), abs=2e-4)
                break
        else:
            pytest.fail("the face never met the disk")


def test_aligned_coordinates_put_the_groove_at_the_foot():
    from envs.design_space import DesignBounds, touch_foot_r

    bounds = DesignBounds(jaw="any")
    rng = np.random.default_rng(5)
    y = rng.uniform(-1, 1, (200, bounds.n_var))
    k = bounds.fields.index("jaw_position")
    y[:, k] = 0.0  # no offset: the groove's centre at the foot, where the span allows
    x = bounds.aligned(y, reach_r=1.0)
    assert np.all(np.abs(x) <= 1.0)
    np.testing.assert_array_equal(np.delete(x, k, axis=1), np.delete(y, k, axis=1))
    si = bounds.scale(x, envs_disk())
    r = envs_disk().radius_m
    foot = touch_foot_r(bounds.relative(x)) * r
    centre = si[:, 9]
    inside = (x[:, k] > -1.0) & (x[:, k] < 1.0)
    assert inside.mean() > 0.5
    np.testing.assert_allclose(centre[inside], foot[inside], rtol=1e-9, atol=1e-12)
    # straight jaws pass whole
    straight = DesignBounds()
    z = rng.uniform(-1, 1, (5, 6))
    np.testing.assert_array_equal(straight.aligned(z), z)


def envs_disk():
    from envs.scene import Scene

    return Scene.preset(SCENE).disk


def test_unaligned_inverts_aligned_within_reach():
    from envs.design_space import DesignBounds

    bounds = DesignBounds(jaw="any")
    rng = np.random.default_rng(6)
    y = rng.uniform(-1, 1, (300, bounds.n_var))
    x = bounds.aligned(y, reach_r=0.7)
    k = bounds.fields.index("jaw_position")
    inside = (x[:, k] > -1.0) & (x[:, k] < 1.0)
    back = bounds.unaligned(x, reach_r=0.7)
    np.testing.assert_allclose(back[inside], y[inside], atol=1e-9)


def test_policy_starts_for_shaped_jaws():
    from optim.rl import policy_starts

    problem = DesignProblem.from_scene(SCENE, 0.15, jaw="any")
    rows = policy_starts(problem)
    assert rows.shape == (3, problem.n_var) and np.all(np.abs(rows) <= 1.0)
    depth = problem.bounds.fields.index("jaw_depth_w")
    assert rows[2, depth] == -1.0  # the straight policy's gripper as a straight bar
    # no shipped policy designs per-finger grooves
    per_finger = DesignProblem.from_scene(SCENE, 0.15, jaw="any", jaw_per_finger=True)
    assert policy_starts(per_finger).shape == (0, per_finger.n_var)


def test_nominal_screen_is_the_nominal_scenario_at_its_share_of_the_cost():
    from envs.scenarios import Scenarios

    problem = DesignProblem.from_scene(SCENE, 0.15, scenarios=Scenarios.of({}, 0.002))
    assert problem.scenario_count == 9
    rng = np.random.default_rng(7)
    x = rng.uniform(-1, 1, (20, 6))
    problem.start(100)
    out = problem.screen(x)
    assert problem.n_evaluations == 3  # ceil(20 / 9)
    assert problem.top_designs() == [] and problem.best_reward == -math.inf
    robust = problem.evaluate(x)
    # the same payload on both: the nominal scenario of the robust table
    table = problem.evaluate_scenarios(problem.to_physical(x))
    np.testing.assert_allclose(out["reward"], table.per_scenario["reward"][:, 0], atol=1e-12)
    assert np.all(robust["reward"] <= out["reward"] + 1e-12)


def test_portfolio_with_a_nominal_screen_spends_its_budget():
    from envs.scenarios import Scenarios

    problem = DesignProblem.from_scene(SCENE, 0.15, payload_factor=0.0,
                                       scenarios=Scenarios.of({}, 0.002))
    result = optimize("portfolio", problem, budget=120, seed=0, screen="nominal")
    assert result.n_evaluations == 120
    assert result.extra["screen"] == "nominal"
    assert result.extra["screened"] <= 3 * 7


def test_the_screen_holds_straight_bars_and_cradles_that_conform_to_the_object():
    """With shaped jaws a quarter of the screen are straight bars and a quarter cradles of
    bottom radius 0.95-1.4 object radii centred within 0.3 radii of where the object meets the
    finger, in every prefix of it; V-grooves get no cradles."""
    from envs.design_space import touch_foot_r
    from optim import portfolio

    problem = DesignProblem.from_scene(SCENE, 0.15, jaw="any")
    y = portfolio._screen(problem, 64, seed=3)
    box = problem.bounds.aligned(y, portfolio.ALIGN_REACH_R)
    si = problem.to_physical(box)
    r = problem.disk.radius_m
    fields = problem.bounds.fields
    depth, radius = si[:, 6] / r, si[:, 7] / r  # (JAW_FIELDS: depth, bottom radius, ...)
    straight = np.arange(64) % 4 == 0
    cradle = np.arange(64) % 4 == 2
    assert np.all(depth[straight] == 0.0) and np.all(depth[~straight] > 0.0)
    assert np.all((radius[cradle] >= 0.95 - 1e-9) & (radius[cradle] <= 1.4 + 1e-9))
    offset = np.abs(si[:, 9] / r - touch_foot_r(problem.bounds.relative(box)))
    k = fields.index("jaw_position")
    free = cradle & (np.abs(box[:, k]) < 1.0)  # (a span too short clips the centre)
    assert free.sum() >= 8 and np.all(offset[free] <= portfolio.CRADLE_OFFSET + 1e-9)
    # the other draws of the box are left alone: most of them are no conforming cradle
    other = ~straight & ~cradle
    assert np.mean((radius[other] >= 0.95) & (radius[other] <= 1.4)) < 0.5
    vee = DesignProblem.from_scene(SCENE, 0.15, jaw="vee")
    assert portfolio._cradle_columns(vee) == {}


def test_the_portfolio_given_a_time_alone_sizes_its_phases_by_it():
    """A run given a time and the largest budget (what --time alone gives) sizes its screen and
    halvings by the rate of a pilot batch, and ends near its time, not after a screen sized by
    millions of evaluations."""
    from envs.scenarios import Scenarios
    from optim.problem import MAX_BUDGET

    problem = DesignProblem.from_scene(SCENE, 0.15, jaw="any",
                                       scenarios=Scenarios.of({}, 0.002))
    problem.time_limit_s = 4.0
    start = time.perf_counter()
    result = optimize("portfolio", problem, budget=MAX_BUDGET, seed=0)
    assert time.perf_counter() - start < 60.0  # (the batch under way may overrun a little)
    assert result.extra["out_of_time"] and 0 < result.n_evaluations < 100_000
    assert len(result.extra["starts"]) >= 2  # the race began: the screen did not eat the time


def test_the_default_run_is_its_budget_capped_by_the_default_time(monkeypatch, tmp_path):
    """A run given neither a budget nor a time spends its default budget as a run given that
    budget does (seed for seed: the cap does not size its phases), and stops its search at
    DEFAULT_TIME_LIMIT_S if the budget lasts longer."""
    import optim.run as run
    from optim.problem import DEFAULT_TIME_LIMIT_S

    monkeypatch.setattr(run, "default_budget", lambda scenario_count: 90)
    common = {"scene": SCENE, "seed": 2, "jaw": "any", "finish": False, "progress": False}
    default, _ = run.run_optimize("portfolio", out=tmp_path / "a", **common)
    given, _ = run.run_optimize("portfolio", budget=90, out=tmp_path / "b", **common)
    assert default.extra["time_limit_s"] == DEFAULT_TIME_LIMIT_S
    assert given.extra["time_limit_s"] is None
    assert default.n_evaluations == given.n_evaluations == 90
    assert default.best_reward == given.best_reward
    assert default.best_design == given.best_design
