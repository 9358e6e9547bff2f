"""Whether a reported design holds, in words every output shares: the verdict and its banner.

A design *holds* in a scenario when its grasp converged, both fingers touch, the friction it
needs (its payload included) is within the object's coefficient and its peak compression within
the strain limit. :func:`verdict_of` counts the scenarios where it does not and names what
limits each (:func:`limit_of`); :attr:`Verdict.banner` is the one line the build sheet, its
CSV, the drawing, the best-grasp figure and the command line print for a design that does not
hold: ``DOES NOT HOLD in k of n scenarios: limited by ...``.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

__all__ = ["Verdict", "verdict_of", "limit_of", "LIMITS", "reward_terms"]

# what limits a grasp that does not hold, in the order the reward's tiers rank them (worst first)
LIMITS = ("invalid at rest", "no converged grasp", "a finger that does not touch",
          "friction", "the payload", "the strain limit")
# the reward's terms as OptimResult.best_metrics holds them, with their short names
REWARD_TERMS = (("reward_contact", "contact"), ("reward_deform", "deform"),
                ("penalty_slip", "slip"), ("penalty_miss", "miss"), ("penalty_gap", "gap"),
                ("penalty_invalid", "invalid"), ("penalty_fail", "fail"))


def limit_of(metrics: dict[str, Any]) -> str | None:
    """What keeps one grasp (a row of metrics) from holding, one of :data:`LIMITS`, or
    ``None`` when it holds within the strain limit."""
    if not metrics.get("valid_at_rest", True):
        return LIMITS[0]
    if not metrics.get("converged", True):
        return LIMITS[1]
    if not all(metrics.get("touching") or [True, True]):
        return LIMITS[2]
    if not metrics.get("holds", True):
        payload, grip = metrics.get("payload_n") or 0.0, metrics.get("grip_force_n")
        mu = metrics.get("friction_coefficient")
        if payload and mu is not None and grip is not None and not mu * grip >= payload:
            return LIMITS[4]
        return LIMITS[3]
    if not _number(metrics.get("peak_compression", 0.0)) <= _number(
            metrics.get("strain_limit", math.inf)):
        return LIMITS[5]
    return None


def _number(value: Any) -> float:
    """A metric as a float (a JSON result writes infinity as text)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


@dataclass(frozen=True)
class Verdict:
    """Whether a design holds in the scenarios it was checked in.

    Attributes
    ----------
    total
        Scenarios checked (1 without scenarios).
    failing
        Of them, those where it does not hold within the strain limit.
    limits
        ``(what limits, in how many scenarios)``, the most frequent first.
    """

    total: int
    failing: int
    limits: tuple[tuple[str, int], ...] = ()

    @property
    def holds(self) -> bool:
        """Whether it holds in every scenario checked."""
        return self.failing == 0

    @property
    def limited_by(self) -> str:
        """The limits in words: ``friction (3), the strain limit (1)``."""
        return ", ".join(f"{name} ({count})" if self.total > 1 else name
                         for name, count in self.limits)

    @property
    def banner(self) -> str | None:
        """The warning line for a design that does not hold; ``None`` when it holds."""
        if self.holds:
            return None
        where = (f"in {self.failing} of {self.total} scenarios" if self.total > 1
                 else "its object")
        return f"DOES NOT HOLD {where}: limited by {self.limited_by}"

    def as_dict(self) -> dict[str, Any]:
        """Plain data (what a build sheet records)."""
        return {"holds": self.holds, "scenarios": self.total, "failing": self.failing,
                "limited_by": [list(item) for item in self.limits], "banner": self.banner}


def verdict_of(metrics: dict[str, Any] | None,
               scenario_rows: list[dict[str, Any]] | None = None) -> Verdict:
    """The verdict of a design: over its scenario rows (a result's ``extra["scenario_rows"]``)
    when there are any, else of its one grasp's ``metrics``."""
    rows = scenario_rows or [metrics or {"valid_at_rest": False}]
    limits = Counter(limit for limit in map(limit_of, rows) if limit is not None)
    ordered = tuple(sorted(limits.items(), key=lambda item: (-item[1],
                                                             LIMITS.index(item[0]))))
    return Verdict(len(rows), sum(limits.values()), ordered)


def reward_terms(metrics: dict[str, Any]) -> list[tuple[str, float]]:
    """The reward's terms of a row of metrics that are not zero, ``(name, value)``; their sum
    is the row's reward (:class:`envs.evaluate.RewardWeights`)."""
    terms = [(name, _number(metrics[key])) for key, name in REWARD_TERMS if key in metrics]
    shown = [(name, value) for name, value in terms if value != 0.0]
    return shown or terms[:1]
