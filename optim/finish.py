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

The designs it scores are rounded to the manufacturing resolution first
(:func:`optim.parts.resolution.round_design`): the reported design is the one a workshop builds
and the build sheet states. Where the search judged designs on a covering set of the scenario
box's corners (:attr:`envs.scenarios.Scenarios.uses_covering_set`), the best
:data:`FULL_CHECK_TOP` are scored again on every corner and the best of them by that is
reported, with its rows over every corner.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from envs.model.family import resolve_model
from envs.scene import design_row

from .result import OptimResult, to_jsonable

__all__ = ["RANKING_MEMBER", "FINISH_TOP", "FULL_CHECK_TOP", "finish_result"]

# the finer member whose reward ranks random designs like the FEM's, also at soft strain
# limits where the default's ranking is a little below it (scripts/fidelity.py,
# docs/accuracy.md): the re-ranking to trust when the FEM is not at hand, and the member that
# reports an optimization's optimum
RANKING_MEMBER = {"n_triangles": 96, "n_rings": 6, "element": "nhquad", "calibrated": True}
FINISH_TOP = 10  # distinct designs re-scored (what an OptimResult keeps)
FULL_CHECK_TOP = 3  # of them, the best checked on every corner of a large scenario box


def _finer(member: dict[str, Any], than: dict[str, Any]) -> bool:
    """Whether ``member`` resolves the disk more finely than ``than`` (more rings, or as many
    rings and more points)."""
    a = resolve_model(member.get("n_triangles"), member.get("n_rings"), member.get("element"))
    b = resolve_model(than.get("n_triangles"), than.get("n_rings"), than.get("element"))
    return (a.n_rings, a.n_triangles) > (b.n_rings, b.n_triangles)


def _rounded_picks(picks: list[dict[str, Any]], resolution) -> list[dict[str, Any]]:
    """The picks with their designs rounded (:func:`~optim.parts.resolution.round_design`),
    the later of two that round alike dropped; unchanged without a resolution."""
    if resolution is None:
        return picks
    from .parts.resolution import round_design

    out, seen = [], []
    for pick in picks:
        design = round_design(pick["design"], resolution)
        if design not in seen:
            seen.append(design)
            out.append({**pick, "design": design})
    return out


def _full_check(problem, designs: np.ndarray, order: np.ndarray, scorer: dict[str, Any]
                ) -> tuple[int, dict[str, np.ndarray] | None]:
    """Where the search used a covering set of the scenario box's corners: the best
    :data:`FULL_CHECK_TOP` designs of ``order`` on every corner; the index of the best by
    that and its summary rows (``None``: no full check, the best of ``order`` stands)."""
    if problem.scenarios is None or not problem.scenarios.uses_covering_set:
        return int(order[0]), None
    first = order[:FULL_CHECK_TOP]
    full = problem.evaluate_scenarios(designs[first], scorer, full=True).summary
    best = int(np.argmax(full["reward"]))  # first maximum: the better ranked on ties
    return int(first[best]), {k: v[best:best + 1] for k, v in full.items()}


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
                  top: int = FINISH_TOP, resolution=None) -> OptimResult:
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
        coarser, the designs are re-scored by the run's own (rounded), or without a
        resolution the result is returned unchanged but for ``extra["reward_model"]``.
    top
        Designs re-scored, at most those the result keeps.
    resolution
        The manufacturing resolution (:class:`optim.parts.resolution.Resolution`) the designs
        are rounded to before they are scored; ``None``: as found.

    Returns
    -------
    OptimResult
        ``best_design``, ``best_reward`` and ``best_metrics`` of the best re-scored design by
        the finer member; ``top_designs`` in its order, each with its ``search_reward``;
        ``extra``: ``reward_model`` (the member that produced ``best_reward``),
        ``search_reward`` (the run's own model's reward of the reported design) and
        ``finish`` (evaluations and seconds).
    """
    from .problem import metrics_row
    from .result import grasp_found

    member = dict(RANKING_MEMBER if member is None else member)
    own = problem.model.kwargs()
    finer = _finer(member, own)
    picks = _rounded_picks(_candidates(result, top), resolution)
    if not picks or (not finer and resolution is None):
        return replace(result, extra={**result.extra, "reward_model": to_jsonable(own)})
    scorer = member if finer else own
    t0 = time.perf_counter()
    designs = np.array([design_row(p["design"]) for p in picks])
    out = problem.evaluate_physical(designs, scorer)
    order = np.argsort(-out["reward"], kind="stable")
    best, full = _full_check(problem, designs, order, scorer)
    reward = float(out["reward"][best] if full is None else full["reward"][0])
    holds = problem.feasible(out)
    if full is not None:
        holds[best] = bool(full["holds_all"][0])
    # the reported design first, with its reward as reported (on every corner where checked)
    ranked = tuple({"design": picks[i]["design"],
                    "reward": reward if i == best else float(out["reward"][i]),
                    "search_reward": float(picks[i]["reward"]), "holds": bool(holds[i])}
                   for i in [best, *(j for j in order.tolist() if j != best)])
    extra = {**result.extra,
             "search_grasp_found": bool(result.extra.get("grasp_found")),
             "reward_model": to_jsonable(scorer),
             "search_model": to_jsonable(own),
             "search_reward": float(picks[best]["reward"]),
             "finish": {"evaluations": len(picks),
                        "full_check_designs": 0 if full is None else min(FULL_CHECK_TOP,
                                                                         len(picks)),
                        "seconds": time.perf_counter() - t0}}
    if resolution is not None:
        extra["resolution"] = resolution.as_dict()
    metrics = metrics_row(out, best) if full is None else metrics_row(full, 0)
    extra["grasp_found"] = grasp_found(metrics)
    extra.update(problem.scenario_extra(picks[best]["design"], scorer, full=full is not None))
    return replace(result, best_design=dict(picks[best]["design"]),
                   best_reward=reward, best_metrics=metrics,
                   top_designs=ranked, extra=to_jsonable(extra))
