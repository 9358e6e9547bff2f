"""The benchmark suite (optim.bench): its instances, runs scored as a user sees them, the ask/tell
entry for outside optimizers, the best-known targets and the IOHprofiler logs read back."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from envs.object_file import load_object
from envs.scene import design_row
from optim import BudgetExhaustedError, optimize
from optim.bench import (
    INSTANCES,
    OBJECTS,
    BenchRun,
    finished_curve,
    load_targets,
    make_problem,
    read_ioh,
    targets_meta,
    targets_stale,
)
from optim.finish import RANKING_MEMBER, finish_result
from optim.run import problem_kwargs

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "objects"
FAST = "puck-straight"  # one exact object, six columns


def test_instances_are_every_object_with_both_jaws():
    assert set(INSTANCES) == {f"{o}-{j}" for o in OBJECTS for j in ("any", "straight")}
    scenarios = {"puck": 1, "cherry-tomato": 1, "foam": 1, "strawberry": 9, "tomatoes": 9,
                 "tomatoes-mu05": 9, "blueberries": 25}  # 2^k + 2k + 1 for k varied
    assert {i.object_key: i.n_scenarios() for i in INSTANCES.values()} == scenarios
    assert {i.n_var for i in INSTANCES.values() if i.jaw == "straight"} == {6}
    problem = make_problem("blueberries-any")
    assert problem.n_var == INSTANCES["blueberries-any"].n_var == 10
    assert problem.disk.radius_m == pytest.approx(0.0075)  # the ranges' centre
    assert problem.scenarios.ranges["youngs_modulus_pa"] == (2e5, 6e5)


@pytest.mark.parametrize(("key", "example"), [
    ("puck", "silicone_puck"), ("cherry-tomato", "cherry_tomato"), ("foam", "foam_disk"),
    ("strawberry", "strawberry"), ("tomatoes", "tomatoes_10_15mm")])
def test_the_suites_objects_are_the_examples_when_written(key, example):
    """The suite keeps its own copy (an instance must not move with an example): were an
    example edited on purpose, drop it here."""
    spec = load_object(EXAMPLES / f"{example}.toml")
    disk, settings = problem_kwargs(None, spec, None, None, None, None, jaw="any")
    ours = make_problem(f"{key}-any").object_info()
    from optim import DesignProblem

    theirs = DesignProblem(disk, name=f"{key}-any", **settings).object_info()
    assert ours == theirs


def test_an_instance_is_not_changed_by_its_arguments():
    with pytest.raises(ValueError, match=r"unknown benchmark instance 'strawbery-any'; "
                                         r"allowed: puck-any, "):
        make_problem("strawbery-any")
    with pytest.raises(ValueError, match=r"jaw: fixed by instance 'puck-any'"):
        make_problem("puck-any", jaw="straight")


def test_finished_curve_ends_at_the_finish():
    """The curve's last point is what optim.finish reports for the run (an independent path:
    the result's top designs as SI rows, re-scored)."""
    problem = make_problem(FAST)
    result = optimize("cmaes", problem, budget=60, seed=1)
    curve = finished_curve(problem, result)
    assert curve.evaluations[-1] == 60 and np.all(np.diff(curve.evaluations) > 0)
    finished = finish_result(problem, result)
    assert curve.reward[-1] == finished.best_reward
    assert curve.best_design == finished.best_design
    assert np.all(np.diff(curve.search_reward) >= 0)


def test_the_default_method_is_scored_and_logged_with_its_screen(tmp_path):
    """The portfolio screens on the nominal scenario (charged a ninth of an evaluation a design,
    its designs not archived): its curve ends at the package's finish, and its log counts the
    run's budget, every archived design at its own evaluation count."""
    from optim.bench import IOHLog, run_method

    problem = make_problem("strawberry-straight")
    with IOHLog(tmp_path, "portfolio") as log:
        score = run_method("strawberry-straight", "portfolio", budget=80, seed=0, targets={},
                           log=log, n_checkpoints=1, problem=problem)
    assert score.result.n_evaluations == 80 and score.curve.evaluations[-1] == 80
    arc = problem.archive()
    assert arc["evaluations"][-1] <= 80 and arc["evaluations"].size < 80  # the screen's charge
    assert np.all(np.diff(arc["evaluations"]) > 0)
    assert score.reward == finish_result(problem, score.result).best_reward
    (logged,) = read_ioh(tmp_path)
    assert logged.evals == 80 and logged.evaluations[-1] == 80
    rows = dict(zip(arc["evaluations"].tolist(), arc["reward"].tolist(), strict=True))
    for e, y in zip(logged.evaluations.tolist(), logged.raw_y.tolist(), strict=True):
        assert y == pytest.approx(rows.get(e, -1e300), rel=1e-9, abs=1e-9)  # (10 digits)
    assert logged.best_y == pytest.approx(arc["reward"].max())


def test_bench_run_for_an_outside_optimizer_scores_and_logs_it(tmp_path):
    run = BenchRun(FAST, budget=45, seed=7, algorithm="my-random", log_dir=tmp_path)
    assert run.n_var == 6 and run.bounds[0].tolist() == [-1.0] * 6
    rng = np.random.default_rng(0)
    while run.remaining > 0:
        x = rng.uniform(-1.0, 1.0, (min(20, run.remaining), run.n_var))
        assert run.evaluate(x).shape == (x.shape[0],)
    with pytest.raises(BudgetExhaustedError):
        run.evaluate(np.zeros((1, 6)))
    score = run.close()
    assert run.close() is score and run.remaining == 0
    with pytest.raises(ValueError, match="the run is closed"):
        run.evaluate(np.zeros((1, 6)))
    assert (score.evaluations, score.method, score.seed) == (45, "my-random", 7)
    assert score.curve.evaluations[-1] == 45
    # the reported design, re-scored here by the finer member, gives the score's reward
    again = run.problem.evaluate_physical(design_row(score.curve.best_design)[None, :],
                                          RANKING_MEMBER)["reward"][0]
    assert again == pytest.approx(score.reward, abs=1e-12)

    (logged,) = read_ioh(tmp_path)
    assert logged.function_name == f"psm_{FAST}" and logged.algorithm == "my-random"
    assert logged.maximization and logged.dimension == 6
    assert logged.evals == 45 and logged.evaluations[-1] == 45
    assert logged.attributes == {"seed": 7, "finished_reward": pytest.approx(score.reward)}
    # every logged row is the archive's reward at that evaluation, and every improvement of
    # the best so far is logged
    reward = run.problem.archive()["reward"]
    np.testing.assert_allclose(logged.raw_y, reward[logged.evaluations - 1], rtol=1e-9)
    improved = np.flatnonzero(np.diff(np.maximum.accumulate(reward)) > 0) + 2
    assert set(improved) <= set(logged.evaluations.tolist())
    assert logged.best_y == pytest.approx(reward.max())
    assert np.all(np.diff(logged.columns["wall_time_s"]) >= 0)


def test_the_reader_takes_the_loggers_non_finite_numbers(tmp_path):
    data = tmp_path / "data_f9_psm_x"
    data.mkdir()
    (data / "IOHprofiler_f9_DIM2.dat").write_text("evaluations raw_y\n1 -inf\n3 0.5\n")
    (tmp_path / "IOHprofiler_f9_psm_x.json").write_text(
        '{"function_id": 9, "function_name": "psm_x", "maximization": true, '
        '"algorithm": {"name": "a", "info": "a"}, "run_attributes": ["seed"], '
        '"scenarios": [{"dimension": 2, "path": "data_f9_psm_x/IOHprofiler_f9_DIM2.dat", '
        '"runs": [{"instance": 1, "evals": 3, "best": {"evals": 3, "y": nan, "x": [0, 0]}, '
        '"seed": 1}]}]}')
    (run,) = read_ioh(tmp_path)
    assert math.isnan(run.best_y) and run.raw_y[0] == -math.inf
    assert run.best_so_far().tolist() == [-math.inf, 0.5] and run.attributes == {"seed": 1}


def test_targets_say_how_they_were_obtained():
    targets, meta = load_targets(), targets_meta()
    if not targets:
        pytest.skip("no targets.json (python scripts/bench_targets.py)")
    assert set(targets) <= set(INSTANCES)
    assert meta["commands"] and meta["finer_member"] == RANKING_MEMBER
    assert meta["runs"] >= len(targets)
    # every instance has a target or is listed without one
    assert sorted([*targets, *meta["instances_without_target"]]) == sorted(INSTANCES)
    raw = json.loads((Path(__file__).resolve().parent.parent / "optim" / "bench"
                      / "targets.json").read_text())["targets"]
    for name, t in targets.items():
        runs = raw[name]["finished_by_method"]
        assert t.reward == pytest.approx(max(max(v) for v in runs.values()), abs=1e-6)
        assert any(key.split(" (")[0] == t.method for key in runs)
    if targets_stale() or FAST not in targets:
        pytest.skip("the model changed since the targets were computed")
    # the target's design, scored again by the finer member, gives the target
    t = targets[FAST]
    problem = make_problem(FAST)
    again = problem.evaluate_physical(design_row(t.design)[None, :], RANKING_MEMBER)["reward"]
    assert again[0] == pytest.approx(t.reward, abs=1e-6)


def test_the_comparison_script_writes_its_figure_table_and_logs(tmp_path):
    import importlib.util

    path = Path(__file__).resolve().parent.parent / "scripts" / "compare_optimizers.py"
    spec = importlib.util.spec_from_file_location("compare_optimizers", path)
    compare = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(compare)
    assert compare.main(["--budget", "20", "--seeds", "2", "--instances", FAST, "--methods",
                         "random", "ng:TwoPointsDE", "--out", str(tmp_path)]) == 0
    out = json.loads((tmp_path / "compare.json").read_text())
    assert (tmp_path / "compare.png").stat().st_size > 0
    rows = {r["method"]: r for r in out["tables"][FAST]}
    runs = out["runs"][FAST]
    assert rows["random"]["median"] == np.median([r["reward"] for r in runs["random"]])
    shares = out["profiles"]["evaluations"]
    assert all(0.0 <= v <= 1.0 for v in shares["random"]) and shares["random"][-1] > 0
    # read again from its JSON (as after new targets): the same tables
    assert compare.main(["--replot", str(tmp_path / "compare.json"), "--out",
                         str(tmp_path / "again")]) == 0
    again = json.loads((tmp_path / "again" / "compare.json").read_text())
    assert again["tables"] == out["tables"] and again["runs"] == out["runs"]
    logged = read_ioh(tmp_path / "compare_ioh")
    assert sorted((r.algorithm, r.attributes["seed"]) for r in logged) == [
        ("ng:TwoPointsDE", 0), ("ng:TwoPointsDE", 1), ("random", 0), ("random", 1)]
