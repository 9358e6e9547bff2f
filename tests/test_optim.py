"""Optimizer drivers, the shared problem and result, executors and the CLI.

Budgets are small so the default suite stays fast; the longer checks (SAC, a real killed worker
on a process pool and on a Dask cluster, the demo) are marked ``slow``.
"""

from __future__ import annotations

import concurrent.futures
import math
import os

import numpy as np
import pytest

import envs
from envs.evaluate import evaluate_designs
from envs.scene import PRESETS, SoftDisk
from optim import DesignProblem, OptimResult, optimize
from optim.executors import (
    ChunkFailedError,
    DaskExecutor,
    ProcessExecutor,
    RetryingExecutor,
    SerialExecutor,
    make_executor,
)
from optim.problem import BudgetExhaustedError, paper_design, pareto_mask

SCENE = "paper-r070"
STRAIN_LIMIT = 0.15


def make_problem(**kwargs) -> DesignProblem:
    return DesignProblem.from_scene(SCENE, STRAIN_LIMIT, **kwargs)


@pytest.fixture(scope="module")
def paper_reward() -> float:
    """The paper's gripper on the r = 0.07 m disk, best of a few reasonable torques."""
    disk = PRESETS[SCENE][1]
    designs = np.array([paper_design(SCENE, t) for t in (0.05, 0.1, 0.2, 0.3)])
    out = evaluate_designs(designs, disk, strain_limits=STRAIN_LIMIT)
    assert np.all(out["converged"])
    return float(out["reward"].max())


def same_run(a: OptimResult, b: OptimResult) -> bool:
    return (a.best_reward == b.best_reward and a.best_design == b.best_design
            and a.history_evaluations == b.history_evaluations
            and a.history_best_reward == b.history_best_reward)


# --- the methods ------------------------------------------------------------------------------


@pytest.mark.parametrize(("method", "budget"), [("cmaes", 300), ("ga", 400)])
def test_optimizer_beats_the_paper_gripper(method, budget, paper_reward):
    result = optimize(method, make_problem(), budget=budget, seed=0)
    assert result.n_evaluations == budget
    assert result.best_reward > paper_reward
    assert result.best_metrics["converged"] and all(result.best_metrics["touching"])
    assert result.best_metrics["peak_compression"] <= STRAIN_LIMIT


@pytest.mark.parametrize(("method", "budget"), [("cmaes", 50), ("ga", 50), ("random", 130),
                                                ("nsga2", 45)])
def test_exact_budget_and_monotone_history(method, budget):
    result = optimize(method, make_problem(), budget=budget, seed=1)
    assert result.n_evaluations == budget == result.history_evaluations[-1]
    assert np.all(np.diff(result.history_evaluations) > 0)
    assert np.all(np.diff(result.history_best_reward) >= 0)
    assert np.all(np.diff(result.history_wall_time_s) >= 0)
    assert result.best_reward == result.history_best_reward[-1]
    assert set(result.best_design) == {"finger_length_m", "rest_angle_rad", "joint_offset_m",
                                       "finger_width_m", "torque_nm", "distance_m"}


def test_random_search_batches():
    result = optimize("random", make_problem(), budget=130, seed=0, batch_size=50)
    assert result.history_evaluations == (50, 100, 130)


def test_nsga2_front_is_non_dominated():
    problem = make_problem()
    result = optimize("nsga2", problem, budget=400, seed=0)
    front = result.pareto_front
    assert len(front) >= 2
    arc = problem.archive()
    feasible = arc["feasible"]
    contact, strain = arc["contact_score"][feasible], arc["peak_compression"][feasible]
    for p in front:
        assert p["peak_compression"] <= STRAIN_LIMIT
        # no feasible evaluated design is at least as good in both and better in one
        dominated = ((contact >= p["contact_score"]) & (strain <= p["peak_compression"])
                     & ((contact > p["contact_score"]) | (strain < p["peak_compression"])))
        assert not np.any(dominated)
    for i, p in enumerate(front):
        for j, q in enumerate(front):
            if i != j:
                assert not (q["contact_score"] >= p["contact_score"]
                            and q["peak_compression"] <= p["peak_compression"])
    assert [p["contact_score"] for p in front] == sorted(p["contact_score"] for p in front)


def test_pareto_mask_small_case():
    f = np.array([[0, 3], [1, 1], [2, 0], [2, 2], [1, 1], [3, 3]], dtype=float)
    assert pareto_mask(f).tolist() == [True, True, True, False, False, False]


# --- reproducibility and options -------------------------------------------------------------


@pytest.mark.parametrize("method", ["cmaes", "ga", "nsga2", "random"])
def test_same_seed_same_result(method):
    problem = make_problem()
    a = optimize(method, problem, budget=90, seed=7)
    np.random.seed(123)  # noqa: NPY002 (the drivers must not depend on the global state)
    b = optimize(method, problem, budget=90, seed=7)
    assert same_run(a, b)
    assert a.pareto_front == b.pareto_front
    c = optimize(method, problem, budget=90, seed=8)
    assert c.history_best_reward != a.history_best_reward or c.best_design != a.best_design


def test_bad_options_raise_value_error():
    problem = make_problem()
    with pytest.raises(ValueError, match="unknown method 'simplex'"):
        optimize("simplex", problem, budget=10)
    for budget in (0, -3, 2.5, True, None):
        with pytest.raises(ValueError, match="budget"):
            optimize("cmaes", problem, budget=budget)
    with pytest.raises(ValueError, match="seed"):
        optimize("cmaes", problem, budget=10, seed=-1)
    for limit in (0.0, -0.1, 1.5, math.nan, "a lot"):
        with pytest.raises(ValueError, match="strain_limit"):
            make_problem_with_limit(limit)
    with pytest.raises(ValueError, match="unknown scene"):
        DesignProblem.from_scene("paper-r999")
    with pytest.raises(ValueError, match="popsize"):
        optimize("cmaes", problem, budget=10, popsize=1)
    with pytest.raises(ValueError, match="pop_size"):
        optimize("ga", problem, budget=10, pop_size=2)
    with pytest.raises(ValueError, match="workers"):
        with make_executor(None, 0):
            pass


def make_problem_with_limit(limit):
    return DesignProblem.from_scene(SCENE, limit)


def test_cli_rejects_bad_options(capsys, tmp_path):
    from cli.main import main

    assert main(["optimize", "--budget", "0", "--out", str(tmp_path)]) == 2
    assert "budget" in capsys.readouterr().err
    assert main(["optimize", "--strain-limit", "2", "--out", str(tmp_path)]) == 2
    assert "strain_limit" in capsys.readouterr().err
    # (the methods are not argparse choices since ng:NAME and optuna:NAME: refused by name)
    assert main(["optimize", "--method", "simplex", "--out", str(tmp_path)]) == 2
    assert "--method: unknown method 'simplex'" in capsys.readouterr().err


def test_budget_is_enforced():
    problem = make_problem()
    problem.start(5)
    problem.evaluate(np.zeros((3, 6)))
    with pytest.raises(BudgetExhaustedError):
        problem.evaluate(np.zeros((3, 6)))
    assert problem.n_evaluations == 3


# --- result type and CLI ---------------------------------------------------------------------


def test_result_json_round_trip(tmp_path):
    result = optimize("nsga2", make_problem(), budget=60, seed=2)
    path = result.to_json(tmp_path / "r.json")
    again = OptimResult.from_json(path)
    assert again == result
    assert again.object["radius_m"] == PRESETS[SCENE][1].radius_m
    assert again.object["strain_limit"] == STRAIN_LIMIT


def test_cli_optimize_writes_result_and_charts(tmp_path):
    from cli.main import main

    assert main(["optimize", "--method", "nsga2", "--budget", "80", "--seed", "1", "--out",
                 str(tmp_path), "--no-progress"]) == 0
    for suffix in ("result.json", "convergence.png", "best_grasp.png", "pareto.png"):
        assert (tmp_path / f"nsga2_seed1_{suffix}").stat().st_size > 0
    result = OptimResult.from_json(tmp_path / "nsga2_seed1_result.json")
    assert result.n_evaluations == 80 and result.method == "nsga2"


# --- the design policy (tests/test_policy.py) -------------------------------------------------


# --- executors: same results, and no evaluation lost ------------------------------------------


class FlakyBackend:
    """Fails the first execution of every chunk, as if its worker had been killed."""

    n_workers = 2

    def __init__(self) -> None:
        self.inner = SerialExecutor()
        self.seen: set[bytes] = set()
        self.executions = 0

    def submit(self, fn, chunk):
        key = chunk[0].tobytes()
        if key not in self.seen:
            self.seen.add(key)
            fut = concurrent.futures.Future()
            fut.set_exception(ConnectionResetError("worker killed (simulated)"))
            return fut
        self.executions += 1
        return self.inner.submit(fn, chunk)


def test_failed_chunks_are_resubmitted_and_nothing_is_lost():
    reference = optimize("cmaes", make_problem(), budget=60, seed=4)
    backend = FlakyBackend()
    executor = RetryingExecutor(backend, max_retries=1)
    problem = make_problem(executor=executor, chunk_size=4)
    result = optimize("cmaes", problem, budget=60, seed=4)
    assert same_run(result, reference)
    assert result.n_evaluations == 60
    # popsize 9 in chunks of 4: 3 chunks per generation; 6 full generations + one of 6 rows
    assert executor.n_resubmitted == backend.executions == 6 * 3 + 2
    assert len(problem.archive()["reward"]) == 60


def test_a_chunk_failing_every_time_raises():
    class Broken:
        def submit(self, fn, chunk):
            fut = concurrent.futures.Future()
            fut.set_exception(RuntimeError("always"))
            return fut

    problem = make_problem(executor=RetryingExecutor(Broken(), max_retries=2))
    with pytest.raises(ChunkFailedError, match="failed 3 times"):
        optimize("random", problem, budget=5)


def test_dask_local_cluster_gives_the_in_process_result():
    pytest.importorskip("distributed")
    reference = optimize("cmaes", make_problem(), budget=45, seed=5)
    executor = DaskExecutor.local(2, processes=False)
    try:
        assert executor.n_workers == 2
        result = optimize("cmaes", make_problem(executor=executor), budget=45, seed=5)
    finally:
        executor.close()
    assert same_run(result, reference)
    assert result.executor.startswith("dask(")


def _exit_once(marker: str, fn, chunk):
    """Kill the worker process the first time any chunk runs."""
    if not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(1)
    return fn(chunk)


class _KillFirst:
    def __init__(self, marker, fn):
        self.marker, self.fn = marker, fn

    def __call__(self, chunk):
        return _exit_once(self.marker, self.fn, chunk)


class _KillingProcessExecutor(ProcessExecutor):
    def __init__(self, marker, **kwargs):
        self.marker = marker
        super().__init__(**kwargs)

    def submit(self, fn, item):
        return super().submit(_KillFirst(self.marker, fn), item)


@pytest.mark.slow
def test_process_pool_survives_a_killed_worker(tmp_path):
    reference = optimize("ga", make_problem(), budget=80, seed=6)
    executor = _KillingProcessExecutor(str(tmp_path / "killed"), n_workers=2)
    try:
        result = optimize("ga", make_problem(executor=executor), budget=80, seed=6)
    finally:
        executor.close()
    assert (tmp_path / "killed").exists() and executor.n_resubmitted >= 1
    assert same_run(result, reference)


@pytest.mark.slow
def test_dask_worker_killed_mid_run_loses_nothing(tmp_path):
    pytest.importorskip("distributed")
    reference = optimize("ga", make_problem(), budget=120, seed=6)
    executor = DaskExecutor.local(2, processes=True)
    marker = str(tmp_path / "killed")
    original_submit = executor.submit
    executor.submit = lambda fn, item: original_submit(_KillFirst(marker, fn), item)
    try:
        result = optimize("ga", make_problem(executor=executor), budget=120, seed=6)
    finally:
        executor.close()
    assert os.path.exists(marker)
    assert same_run(result, reference)


@pytest.mark.slow
def test_demo_writes_its_files(tmp_path):
    from optim.run import run_demo

    assert run_demo(tmp_path) == 0
    for name in ("demo_result.json", "demo_convergence.png", "demo_best_grasp.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_charted_grasp_is_the_scored_grasp_with_calibration_fields():
    # a disk with non-default calibration: the chart must re-solve the scene that was scored
    from optim.charts import scene_of

    disk = SoftDisk(0.07, 0.013, stiffness_scale=1.7, contour_stiffness_ratio=2.5)
    problem = DesignProblem(disk, n_triangles=20, element="spring")
    design = np.array([0.2, 0.8, 0.025, 0.01, 0.3, 0.013])
    out = problem.evaluate_physical(design[None, :])
    assert out["converged"][0]
    action = problem.bounds.unscale(design, disk)
    scene = scene_of(problem.design_dict(action), problem.object_info())
    assert scene.disk.contour_stiffness_ratio == 2.5
    res = envs.simulate(scene, design[4], 20, element="spring")
    np.testing.assert_allclose(res.jaw_angles_rad, out["jaw_angles_rad"][0], rtol=0, atol=1e-12)
    # and the plain disk would have given another grasp (the test can fail)
    plain = envs.simulate(scene.with_changes(contour_stiffness_ratio=1.0), design[4], 20,
        element="spring")
    assert abs(plain.jaw_angles_rad[0] - res.jaw_angles_rad[0]) > 1e-4
