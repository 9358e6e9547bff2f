"""A multi-fidelity finish: the reported optimum scored by a member that ranks like the FEM.

An optimizer searching with the default model (nh-quad 40 x 2) finds where that model is
optimistic: its optima are light touches, whose peak compression the coarse mesh underestimates,
and the reward (a difference of two similar terms) amplifies it, so the search model's own
reward of its optimum is well above the FEM's. :func:`finish_result` re-scores the run's best
distinct designs (:attr:`~optim.result.OptimResult.top_designs`) with :data:`RANKING_MEMBER`
(nh-quad 96 x 6, which ranks designs like the FEM) and reports the best of them by that member:
its reward, its metrics and the model that produced them (``extra["reward_model"]``). It costs
ten evaluations of the finer member (their time is in ``extra["finish"]``).

It chooses among designs the coarse search found: a local search on the finer member instead
finds that member's own optimistic spots.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from envs.model.family import resolve_model
from envs.scene import design_row

from .result import OptimResult, to_jsonable

__all__ = ["RANKING_MEMBER", "FINISH_TOP", "finish_result"]

# the finer member whose reward ranks random designs like the FEM's, also at soft strain
# limits where the default's ranking is a little below it (scripts/fidelity.py,
# docs/accuracy.md): the re-ranking to trust when the FEM is not at hand, and the member that
# reports an optimization's optimum
RANKING_MEMBER = {"n_triangles": 96, "n_rings": 6, "element": "nhquad", "calibrated": True}
FINISH_TOP = 10  # distinct designs re-scored (what an OptimResult keeps)


def _finer(member: dict[str, Any], than: dict[str, Any]) -> bool:
    """Whether ``member`` resolves the disk more finely than ``than`` (more rings, or as many
    rings and more points)."""
    a = resolve_model(member.get("n_triangles"), member.get("n_rings"), member.get("element"))
    b = resolve_model(than.get("n_triangles"), than.get("n_rings"), than.get("element"))
    return (a.n_rings, a.n_triangles) > (b.n_rings, b.n_triangles)


def _candidates(result: OptimResult, top: int) -> list[dict[str, Any]]:
    """The designs the finish re-scores: the run's ``top`` best distinct designs, then the
    best design of each of its independent starts (``extra["start_designs"]``, a portfolio's)
    that is not among them: a start's basin may be the one the finer member prefers."""
    picks = list(result.top_designs)[:top]
    seen = {tuple(design_row(p["design"]).tolist()) for p in picks}
    for pick in result.extra.get("start_designs", ()):
        key = tuple(design_row(pick["design"]).tolist())
        if key not in seen:
            seen.add(key)
            picks.append({"design": dict(pick["design"]), "reward": float(pick["reward"])})
    return picks


def finish_result(problem, result: OptimResult, member: dict[str, Any] | None = None,
                  top: int = FINISH_TOP) -> OptimResult:
    """The run's best distinct designs re-scored by a finer member; the best of them reported.

    Parameters
    ----------
    problem
        The :class:`~optim.problem.DesignProblem` the run solved (object, limits, spring,
        weights).
    result
        Its result.
    member
        The finer member (default :data:`RANKING_MEMBER`). When the run's own member is not
        coarser, the result is returned unchanged but for ``extra["reward_model"]``.
    top
        Designs re-scored, at most those the result keeps.

    Returns
    -------
    OptimResult
        ``best_design``, ``best_reward`` and ``best_metrics`` of the best re-scored design by
        the finer member; ``top_designs`` in its order, each with its ``search_reward``;
        ``extra``: ``reward_model`` (the member that produced ``best_reward``),
        ``search_reward`` (the run's own model's reward of the reported design) and
        ``finish`` (evaluations and seconds).
    """
    from .problem import BEST_METRIC_KEYS

    member = dict(RANKING_MEMBER if member is None else member)
    own = problem.model.kwargs()
    picks = _candidates(result, top)
    if not picks or not _finer(member, own):
        return replace(result, extra={**result.extra, "reward_model": to_jsonable(own)})
    t0 = time.perf_counter()
    designs = np.array([design_row(p["design"]) for p in picks])
    out = problem.evaluate_physical(designs, member)
    order = np.argsort(-out["reward"], kind="stable")
    best = int(order[0])
    holds = problem.feasible(out)
    ranked = tuple({"design": picks[i]["design"], "reward": float(out["reward"][i]),
                    "search_reward": float(picks[i]["reward"]), "holds": bool(holds[i])}
                   for i in order.tolist())
    extra = {**result.extra,
             "search_grasp_found": bool(result.extra.get("grasp_found")),
             "reward_model": to_jsonable(member),
             "search_model": to_jsonable(own),
             "search_reward": float(picks[best]["reward"]),
             "finish": {"evaluations": len(picks),
                        "seconds": time.perf_counter() - t0}}
    metrics = {k: to_jsonable(out[k][best]) for k in BEST_METRIC_KEYS}
    from .result import grasp_found

    extra["grasp_found"] = grasp_found(metrics)
    extra.update(problem.scenario_extra(picks[best]["design"], member))
    return replace(result, best_design=dict(picks[best]["design"]),
                   best_reward=float(out["reward"][best]), best_metrics=metrics,
                   top_designs=ranked, extra=to_jsonable(extra))
