"""Runtime profiles: the share of (run, target) pairs an optimizer has reached after a budget.

The way the COCO benchmarking platform compares optimizers across problems (Hansen et al.,
"COCO: a platform for comparing continuous optimizers in a black-box setting", 2021): each
object gets a ladder of target rewards between a baseline and the best reward any method found
on it; a run reaches a target at the first evaluation whose best-so-far reward is at least the
target; the runtime profile of a method is the empirical distribution of those first hits over
all its runs and all targets of all objects, drawn against the number of evaluations (or the
wall time). A method whose curve lies higher reached more targets sooner; its right end is the
share it reached within the budget. Unlike one object's median curve it aggregates objects
whose rewards live on different scales.
"""

from __future__ import annotations

import numpy as np

from .result import OptimResult

__all__ = ["target_ladder", "first_hits", "runtime_profile"]


def target_ladder(best_reward: float, baseline_reward: float, n_targets: int = 11,
                  smallest_gap: float = 1e-2) -> np.ndarray:
    """Target rewards of one object, from easy to hard.

    The targets close the gap between ``baseline_reward`` (e.g. the median reward of random
    designs) and ``best_reward`` (the best any method found) down to gaps log-spaced from the
    whole gap to ``smallest_gap`` of it, as COCO's targets are log-spaced in the distance to
    the optimum.

    Raises
    ------
    ValueError
        ``n_targets`` < 1, ``smallest_gap`` outside (0, 1), a reward not finite.
    """
    if not (np.isfinite(best_reward) and np.isfinite(baseline_reward)):
        raise ValueError(f"best_reward and baseline_reward must be finite, got {best_reward!r} "
                         f"and {baseline_reward!r}")
    if int(n_targets) < 1:
        raise ValueError(f"n_targets must be >= 1, got {n_targets!r}")
    if not 0.0 < smallest_gap < 1.0:
        raise ValueError(f"smallest_gap must be in (0, 1), got {smallest_gap!r}")
    gap = max(best_reward - baseline_reward, 0.0)
    return best_reward - gap * np.logspace(0.0, np.log10(smallest_gap), int(n_targets))


def first_hits(result: OptimResult, targets: np.ndarray, axis: str = "evaluations"
               ) -> np.ndarray:
    """Evaluations (or wall time [s]) at which a run's best-so-far reward first reaches each
    target; ``inf`` for a target it never reached.

    ``axis`` is ``"evaluations"`` or ``"wall_time"``.
    """
    if axis not in ("evaluations", "wall_time"):
        raise ValueError(f"axis must be 'evaluations' or 'wall_time', got {axis!r}")
    xs = np.asarray(result.history_evaluations if axis == "evaluations"
                    else result.history_wall_time_s, dtype=float)
    best = np.maximum.accumulate(np.asarray(result.history_best_reward, dtype=float))
    out = np.full(len(targets), np.inf)
    for k, target in enumerate(np.asarray(targets, dtype=float)):
        reached = np.flatnonzero(best >= target)
        if reached.size:
            out[k] = xs[reached[0]]
    return out


def runtime_profile(hits: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Share of the (run, target) pairs of ``hits`` (any shape; ``inf``: never reached)
    reached at or before each budget of ``grid``."""
    flat = np.sort(np.asarray(hits, dtype=float).ravel())
    if flat.size == 0:
        return np.zeros(len(grid))
    return np.searchsorted(flat, np.asarray(grid, dtype=float), side="right") / flat.size
