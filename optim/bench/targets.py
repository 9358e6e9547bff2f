"""Best-known rewards of the suite's instances, with how each was obtained.

``targets.json`` (beside this module) is written by ``python scripts/bench_targets.py``: for
each instance, the best reward the finer member (:data:`optim.finish.RANKING_MEMBER`) gave any
design of long runs of several methods and seeds (each run's ten best distinct designs
re-scored, as the finish does), with that design, the run that found it, and the whole
campaign's settings (methods, seeds, budgets, the package's commit, the time it took). The
file also records a digest of the model's source (``envs/``): rewards move when the physics
does, and :func:`targets_stale` says when the file was written by another version of it (then
rerun the script).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["TARGETS_FILE", "REACHED_GAP", "Target", "load_targets", "targets_meta",
           "targets_stale", "model_digest"]

TARGETS_FILE = Path(__file__).with_name("targets.json")
# a run has found the optimum when its finished reward is within this of the best known (the
# bar a default search is held to: within 0.01 reward, by the finer member, of the best known)
REACHED_GAP = 0.01


@dataclass(frozen=True)
class Target:
    """The best-known reward of one instance.

    Parameters
    ----------
    instance
        The instance's name.
    reward
        The finer member's reward of the best design known.
    search_reward
        The search model's reward of that design (NaN where the file does not say).
    design
        The design (``{field: value}``, SI).
    method, seed, budget
        The run that found it.
    """

    instance: str
    reward: float
    search_reward: float
    design: dict[str, float]
    method: str
    seed: int
    budget: int

    def gap(self, reward: float) -> float:
        """How far a reward is below this one (negative: above it)."""
        return self.reward - float(reward)


def model_digest() -> str:
    """The digest of the model's source (``envs/``) that rewards depend on."""
    from envs._kernel_cache import source_digest

    return source_digest()


def _read(path: Path | None) -> dict[str, Any]:
    path = TARGETS_FILE if path is None else Path(path)
    if not path.exists():
        return {"meta": {}, "targets": {}}
    return json.loads(path.read_text())


def _number(value: Any) -> float:
    """A number of the file; ``null`` (not known: JSON has no NaN) as NaN."""
    return math.nan if value is None else float(value)


def load_targets(path: str | Path | None = None) -> dict[str, Target]:
    """The best-known rewards, by instance (empty when the file is missing)."""
    data = _read(None if path is None else Path(path))
    return {name: Target(instance=name, reward=float(t["reward"]),
                         search_reward=_number(t["search_reward"]), design=dict(t["design"]),
                         method=str(t["method"]), seed=int(t["seed"]), budget=int(t["budget"]))
            for name, t in data.get("targets", {}).items()}


def targets_meta(path: str | Path | None = None) -> dict[str, Any]:
    """How the targets were obtained: the campaign's settings, commit, date and time."""
    return dict(_read(None if path is None else Path(path)).get("meta", {}))


def targets_stale(path: str | Path | None = None) -> bool:
    """Whether the targets were computed with another version of the model's source (then
    ``python scripts/bench_targets.py`` computes them again)."""
    return targets_meta(path).get("model_digest") != model_digest()
