"""Runs on the suite's instances: a package method (:func:`run_method`) or your own optimizer
(:class:`BenchRun`, evaluating whole batches), each scored as a user sees it
(:class:`BenchScore`: the finish's reward, its gap to the best known) and logged in
IOHprofiler's format when asked.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..optimize import get_optimizer
from ..problem import DesignProblem, check_budget, check_seed, check_time_limit
from ..result import NoGraspWarning, OptimResult
from .ioh_log import IOHLog
from .problems import check_instance, make_problem
from .scoring import CHECKPOINTS, FinishedCurve, finished_curve
from .targets import REACHED_GAP, Target, load_targets

__all__ = ["BenchScore", "BenchRun", "score_run", "run_method"]


@dataclass(frozen=True)
class BenchScore:
    """One run, scored as its user sees it.

    Parameters
    ----------
    instance, method, seed
        What ran.
    evaluations, seconds
        What it spent (the search: the finish's re-scoring left out).
    search_reward
        The search model's best reward.
    reward
        The finish's reward (the finer member's, of the best of the ten best distinct
        designs).
    target
        The instance's best-known reward (``None``: no target known).
    curve
        The finish's reward at some of the run's evaluation counts
        (:func:`~optim.bench.scoring.finished_curve`).
    result
        The run's result (the search model's answer, as ``optimize`` returns it).
    """

    instance: str
    method: str
    seed: int
    evaluations: int
    seconds: float
    search_reward: float
    reward: float
    target: float | None
    curve: FinishedCurve
    result: OptimResult

    @property
    def gap(self) -> float:
        """How far the finished reward is below the best known (NaN without a target;
        negative: a new best)."""
        return math.nan if self.target is None else self.target - self.reward

    @property
    def reached(self) -> bool:
        """Whether the run ended within :data:`~optim.bench.targets.REACHED_GAP` of the best
        known."""
        return self.gap <= REACHED_GAP

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON); the result as :meth:`OptimResult.to_dict`."""
        return {"instance": self.instance, "method": self.method, "seed": self.seed,
                "evaluations": self.evaluations, "seconds": self.seconds,
                "search_reward": self.search_reward, "reward": self.reward,
                "target": self.target, "gap": self.gap, "reached": self.reached,
                "curve": self.curve.to_dict(), "result": self.result.to_dict()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> BenchScore:
        """The score of :meth:`to_dict`'s data."""
        return cls(instance=data["instance"], method=data["method"], seed=int(data["seed"]),
                   evaluations=int(data["evaluations"]), seconds=float(data["seconds"]),
                   search_reward=float(data["search_reward"]), reward=float(data["reward"]),
                   target=None if data["target"] is None else float(data["target"]),
                   curve=FinishedCurve.from_dict(data["curve"]),
                   result=OptimResult.from_dict(data["result"]))


def score_run(instance: str, problem: DesignProblem, result: OptimResult, *,
              targets: dict[str, Target] | None = None, log: IOHLog | None = None,
              n_checkpoints: int = CHECKPOINTS) -> BenchScore:
    """Score a finished run on an instance (before the next run on its problem) and log it.

    Parameters
    ----------
    instance
        The instance's name.
    problem
        Its problem, the run's archive still in it.
    result
        The run's result.
    targets
        The best-known rewards (default :func:`~optim.bench.targets.load_targets`).
    log
        An IOHprofiler logger to log the run to, or ``None``.
    n_checkpoints
        Evaluation counts the finish scores (1: the run's end alone).
    """
    curve = finished_curve(problem, result, n_checkpoints=n_checkpoints)
    targets = load_targets() if targets is None else targets
    target = targets.get(instance)
    score = BenchScore(instance=instance, method=result.method, seed=result.seed,
                       evaluations=result.n_evaluations, seconds=result.wall_time_s,
                       search_reward=result.best_reward,
                       reward=float(curve.reward[-1]) if curve.reward.size else -math.inf,
                       target=None if target is None else target.reward, curve=curve,
                       result=result)
    if log is not None:
        arc = problem.archive()
        log.add(instance, arc["x"], arc["reward"], result.history_evaluations,
                result.history_wall_time_s, seed=result.seed, finished_reward=score.reward,
                archive_evaluations=arc["evaluations"])
    return score


def run_method(instance: str, method: str, *, budget: int, seed: int = 0,
               time_limit_s: float | None = None, problem: DesignProblem | None = None,
               targets: dict[str, Target] | None = None, log: IOHLog | None = None,
               n_checkpoints: int = CHECKPOINTS, **options: Any) -> BenchScore:
    """Run a package method (:data:`optim.METHODS`, ``ng:NAME``) on an instance and score it.

    Parameters
    ----------
    instance
        The instance's name (:data:`~optim.bench.problems.INSTANCES`).
    method
        The method.
    budget, seed
        Evaluations and seed.
    time_limit_s
        A wall-time limit beside the budget [s], or ``None``.
    problem
        The instance's problem to reuse (e.g. with an executor; default: a new one).
    targets, log, n_checkpoints
        As :func:`score_run`.
    **options
        The method's options.
    """
    check_instance(instance)
    driver = get_optimizer(method)
    problem = make_problem(instance) if problem is None else problem
    problem.time_limit_s = None if time_limit_s is None else check_time_limit(time_limit_s)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NoGraspWarning)  # the score says it
            result = driver(problem, budget=check_budget(budget), seed=check_seed(seed),
                            **options)
    finally:
        problem.time_limit_s = None
    return score_run(instance, problem, result, targets=targets, log=log,
                     n_checkpoints=n_checkpoints)


class BenchRun:
    """One run of your own optimizer on an instance: evaluate batches, then :meth:`close`.

    ::

        from optim.bench import BenchRun

        run = BenchRun("strawberry-any", budget=1000, seed=0, algorithm="my-es",
                       log_dir="out/ioh")
        while run.remaining > 0:
            x = ask(min(20, run.remaining))   # your optimizer: rows in [-1, 1]^run.n_var
            tell(x, run.evaluate(x))          # rewards, to maximize
        score = run.close()                   # the finish, the gap to the best known, the log
        print(score.reward, score.gap)

    Parameters
    ----------
    instance
        The instance's name (:data:`~optim.bench.problems.INSTANCES`).
    budget
        Evaluations, >= 1.
    seed
        Your run's seed (recorded).
    algorithm
        Your optimizer's name (recorded; the logs' algorithm).
    log_dir
        Write the run's IOHprofiler log under this folder (``None``: no log).
    time_limit_s
        A wall-time limit [s] beside the budget (:attr:`remaining` is 0 once it has passed),
        or ``None``.
    **problem_kwargs
        Further :class:`~optim.problem.DesignProblem` arguments (an ``executor``).
    """

    def __init__(self, instance: str, budget: int, *, seed: int = 0,
                 algorithm: str = "external", log_dir: str | Path | None = None,
                 time_limit_s: float | None = None, **problem_kwargs: Any) -> None:
        self.instance = check_instance(instance).name
        self.seed = check_seed(seed)
        if not isinstance(algorithm, str) or not algorithm.strip():
            raise ValueError(f"algorithm must be a non-empty name, got {algorithm!r}")
        self.algorithm = algorithm
        self.log_dir = log_dir
        self.problem = make_problem(instance, **problem_kwargs)
        self.problem.start(check_budget(budget),
                           None if time_limit_s is None else check_time_limit(time_limit_s))
        self._score: BenchScore | None = None

    @property
    def n_var(self) -> int:
        """Columns of a design row."""
        return self.problem.n_var

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The box of the rows: every column in [-1, 1]."""
        return -np.ones(self.n_var), np.ones(self.n_var)

    @property
    def remaining(self) -> int:
        """Evaluations left (0 once the time limit, if any, has passed)."""
        return 0 if self._score is not None else self.problem.remaining

    def evaluate(self, x: Any) -> np.ndarray:
        """Rewards (B,) of a batch of rows (B, :attr:`n_var`) in [-1, 1] (clipped), to
        maximize; one call per batch.

        Raises
        ------
        ValueError
            For rows of another width, or a run already closed.
        optim.BudgetExhaustedError
            For more rows than :attr:`remaining`.
        """
        if self._score is not None:
            raise ValueError("the run is closed: start a new BenchRun")
        return self.problem.evaluate(np.atleast_2d(np.asarray(x, dtype=np.float64)))["reward"]

    def close(self) -> BenchScore:
        """End the run: its result, the finish's reward, the gap to the best known, and its
        IOHprofiler log (with ``log_dir``). Closing again returns the same score."""
        if self._score is not None:
            return self._score
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NoGraspWarning)
            result = self.problem.result(self.algorithm, self.seed)
        if self.log_dir is None:
            self._score = score_run(self.instance, self.problem, result)
        else:
            with IOHLog(self.log_dir, self.algorithm) as log:
                self._score = score_run(self.instance, self.problem, result, log=log)
        return self._score
