"""What a run may claim about its object: a design that holds, that nothing holds, or neither.

A run's answer is the best design it found within its budget (CONVENTIONS, Searches). When that
design holds the object within its strain limit, the run says so. When it does not, the run has
found nothing, which says something about the object only when independent starts agree: a
search from one start may have missed the region where designs hold. So:

- ``holds``: the reported design holds the object within its strain limit in every scenario;
- ``nothing holds``: it does not, and none of the run's independent starts (at least
  :data:`MIN_AGREEING_STARTS`; the portfolio's, :mod:`optim.portfolio`) found a design that holds,
  by the search model or by the finer member that re-scored each start's best: a verdict about
  the object, ``psm-grasp optimize`` exits with :data:`NO_GRASP_EXIT`;
- ``undecided``: it does not, but a start found designs the search model says hold (and the
  finer member does not confirm), or the run had a single start (every method but the
  portfolio): no verdict about the object, and the message says what to try; ``optimize`` exits
  with :data:`UNDECIDED_EXIT`.
"""

from __future__ import annotations

from typing import Any

from .result import OptimResult, no_grasp_reason

__all__ = ["HOLDS", "NOTHING_HOLDS", "UNDECIDED", "VERDICTS", "NO_GRASP_EXIT", "UNDECIDED_EXIT",
           "MIN_AGREEING_STARTS", "search_verdict", "verdict_exit_code"]

HOLDS, NOTHING_HOLDS, UNDECIDED = "holds", "nothing holds", "undecided"
VERDICTS = (HOLDS, NOTHING_HOLDS, UNDECIDED)
NO_GRASP_EXIT = 3  # the starts agree: nothing holds the object
UNDECIDED_EXIT = 5  # no design that holds was found, and the run cannot say that none does
# independent starts that must agree before a run says that nothing holds
MIN_AGREEING_STARTS = 2


def _starts(result: OptimResult) -> list[dict[str, Any]]:
    """The run's independent starts (a portfolio's ``extra["starts"]``), each with whether its
    best holds by the search model; one start for the other methods. (The finish re-scores
    every start's best with the finer member: one that holds there is the reported design.)"""
    starts = [dict(s) for s in result.extra.get("starts", ())]
    if not starts:
        found = result.extra.get("search_grasp_found", result.extra.get("grasp_found"))
        return [{"label": result.method, "holds": bool(found)}]
    return starts


def search_verdict(result: OptimResult, time_s: float | None = None) -> dict[str, Any]:
    """The run's verdict: ``{"verdict": one of VERDICTS, "starts": k, "starts_holding": j,
    "message": ...}`` (what :func:`optim.run.run_optimize` records as ``extra["verdict"]``).

    ``time_s``: the search's wall time to quote (default the result's)."""
    seconds = result.wall_time_s if time_s is None else time_s
    starts = _starts(result)
    holding = [s for s in starts if s.get("holds")]
    base = {"starts": len(starts), "starts_holding": len(holding)}
    if result.extra.get("grasp_found"):
        return {"verdict": HOLDS, **base,
                "message": "the reported design holds the object within its strain limit"}
    reason = no_grasp_reason(result.best_metrics)
    spent = f"{result.n_evaluations} evaluations, {seconds:.0f} s"
    if len(starts) >= MIN_AGREEING_STARTS and not holding:
        return {"verdict": NOTHING_HOLDS, **base,
                "message": f"nothing holds the object: {len(starts)} independent starts agree "
                           f"({spent}); the best design {reason}"}
    if holding:
        why = (f"{len(holding)} of {len(starts)} starts found designs the search model says "
               "hold, which the finer member does not confirm (they sit at the edge of the "
               "strain limit or of the friction needed)")
    else:
        why = (f"one start ({result.method}) cannot say that nothing holds; the default method "
               "(portfolio) races independent starts")
    return {"verdict": UNDECIDED, **base,
            "message": f"no design that holds was found in {spent}, and no verdict about the "
                       f"object: {why}; the best design {reason}. Try a longer search (--time, "
                       "--budget), another --jaw, or the default method"}


def verdict_exit_code(verdict: dict[str, Any]) -> int:
    """``optimize``'s exit code of a verdict: 0 (holds), :data:`NO_GRASP_EXIT` (nothing holds),
    :data:`UNDECIDED_EXIT`."""
    return {HOLDS: 0, NOTHING_HOLDS: NO_GRASP_EXIT}.get(verdict["verdict"], UNDECIDED_EXIT)
