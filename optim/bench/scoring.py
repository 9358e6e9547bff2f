"""What a user sees of a run: the finish's reward (:func:`optim.finish.finish_result`) had the
run stopped after ``n`` evaluations, at a few ``n``.

The finish re-scores a run's ten best distinct designs with the finer member
(:data:`optim.finish.RANKING_MEMBER`), and at the run's end each independent start's best (a
portfolio's), and reports the best of them. :func:`finished_curve`
applies it to the prefixes of a finished run's archive (its first ``n`` evaluations): the
reward the user would have been told, had the run been given ``n`` evaluations (for a method
that plans by its budget, such as Nevergrad's or pycma's, the prefix of a longer run stands for
a shorter run). Each design is re-scored once, whatever the number of prefixes it is among the
best of.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from envs.scene import design_row

from ..finish import FINISH_TOP, RANKING_MEMBER
from ..problem import DesignProblem, top_distinct
from ..result import OptimResult

__all__ = ["FinishedCurve", "finished_curve", "checkpoints"]

CHECKPOINTS = 8  # prefixes scored per run, log-spaced over its evaluations
QUARTERS = (0.25, 0.5, 0.75)  # and at these shares of its evaluations


@dataclass(frozen=True)
class FinishedCurve:
    """A run's finish at some of its evaluation counts.

    Parameters
    ----------
    evaluations
        The evaluation counts (the end of a batch each), increasing.
    seconds
        The search's wall time [s] when each count was reached (the finish's own time left
        out: about the same for every method on an instance).
    search_reward
        The search model's best reward within each count.
    reward
        The finish's reward within each count (the finer member's, the best of the ten best
        distinct designs by the search model).
    best_design
        The finish's design at the last count (``{field: value}``, SI).
    rescored
        Designs the finer member scored for this curve.
    """

    evaluations: np.ndarray
    seconds: np.ndarray
    search_reward: np.ndarray
    reward: np.ndarray
    best_design: dict[str, float]
    rescored: int

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON)."""
        return {"evaluations": self.evaluations.tolist(), "seconds": self.seconds.tolist(),
                "search_reward": self.search_reward.tolist(), "reward": self.reward.tolist(),
                "best_design": dict(self.best_design), "rescored": self.rescored}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FinishedCurve:
        """The curve of :meth:`to_dict`'s data."""
        return cls(evaluations=np.asarray(data["evaluations"], dtype=np.int64),
                   seconds=np.asarray(data["seconds"], dtype=np.float64),
                   search_reward=np.asarray(data["search_reward"], dtype=np.float64),
                   reward=np.asarray(data["reward"], dtype=np.float64),
                   best_design=dict(data["best_design"]), rescored=int(data["rescored"]))


def checkpoints(batch_ends: Any, n: int = CHECKPOINTS) -> np.ndarray:
    """Indices into a run's batches (``history_evaluations``) at about ``n`` log-spaced
    evaluation counts, the last batch always among them: at each count, the last batch that
    ended within it."""
    ends = np.asarray(batch_ends, dtype=np.float64)
    if ends.size == 0:
        return np.zeros(0, dtype=np.int64)
    if n <= 1:
        return np.array([ends.size - 1])
    # log-spaced from the first batch, and the quarters of the run (a log grid leaves the
    # second half of a run with one point)
    grid = np.concatenate([np.geomspace(ends[0], ends[-1], int(n)),
                           ends[-1] * np.array(QUARTERS)])
    idx = np.searchsorted(ends, grid * (1 + 1e-12), side="right") - 1
    return np.unique(np.append(idx[idx >= 0], ends.size - 1))


def finished_curve(problem: DesignProblem, result: OptimResult, *,
                   member: dict[str, Any] | None = None, top: int = FINISH_TOP,
                   n_checkpoints: int = CHECKPOINTS) -> FinishedCurve:
    """The finish's reward of a run's prefixes, at about ``n_checkpoints`` of its batches.

    Parameters
    ----------
    problem
        The problem the run solved, its archive still the run's (call this before the next
        run on it).
    result
        The run's result (its history gives the batches).
    member
        The finer member (default :data:`~optim.finish.RANKING_MEMBER`).
    top
        The designs the finish re-scores.
    n_checkpoints
        Evaluation counts scored, log-spaced, besides the quarters of the run (1: the run's
        last alone).

    Raises
    ------
    ValueError
        When the problem's archive is not the result's run.
    """
    arc = problem.archive()
    if problem.n_evaluations != result.n_evaluations or (
            arc["evaluations"].size and arc["evaluations"][-1] > result.n_evaluations):
        raise ValueError(f"the problem has counted {problem.n_evaluations} evaluations, the "
                         f"run {result.n_evaluations}: score a run before the next one")
    member = dict(RANKING_MEMBER if member is None else member)
    ends = np.asarray(result.history_evaluations, dtype=np.int64)
    picked = checkpoints(ends, n_checkpoints)
    finer: dict[int, float] = {}  # archive row -> the finer member's reward
    rewards, search, best_rows = [], [], []
    for k in picked.tolist():
        # the designs within the first ends[k] evaluations (a screen's charge counted, its
        # designs not in the archive)
        n = int(np.searchsorted(arc["evaluations"], ends[k], side="right"))
        rows = top_distinct(arc["x"][:n], arc["reward"][:n], top)
        new = [i for i in rows if i not in finer]
        if new:
            out = problem.evaluate_physical(problem.to_physical(arc["x"][new]), member)
            finer.update(zip(new, out["reward"].tolist(), strict=True))
        best = max(rows, key=lambda i: finer[i]) if rows else None
        best_rows.append(best)
        rewards.append(-np.inf if best is None else finer[best])
        search.append(float(np.max(arc["reward"][:n])) if n else -np.inf)
    last = best_rows[-1] if best_rows else None
    best_design = {} if last is None else problem.design_dict(arc["x"][last])
    # at the run's end the finish also scores each independent start's best (a portfolio's)
    scored = [problem.design_dict(arc["x"][i]) for i in rows] if rewards else []
    starts = [p for p in result.extra.get("start_designs", ()) if p["design"] not in scored]
    if starts and rewards:
        out = problem.evaluate_physical(np.array([design_row(p["design"]) for p in starts]),
                                        member)
        i = int(np.argmax(out["reward"]))
        if out["reward"][i] > rewards[-1]:
            rewards[-1], best_design = float(out["reward"][i]), dict(starts[i]["design"])
    return FinishedCurve(
        evaluations=ends[picked].astype(np.int64),
        seconds=np.asarray(result.history_wall_time_s, dtype=np.float64)[picked],
        search_reward=np.array(search), reward=np.array(rewards),
        best_design=best_design, rescored=len(finer) + len(starts))
