"""Runtime profiles (optim.profiles) on runs whose first hits are known by construction."""

from __future__ import annotations

import numpy as np
import pytest

from optim.profiles import first_hits, runtime_profile, target_ladder
from optim.result import OptimResult


def _run(evaluations, best):
    return OptimResult(method="x", seed=0, budget=int(evaluations[-1]), best_design={},
                       best_reward=float(best[-1]), best_metrics={},
                       history_evaluations=tuple(evaluations), history_best_reward=tuple(best),
                       history_wall_time_s=tuple(0.01 * np.asarray(evaluations)),
                       n_evaluations=int(evaluations[-1]), wall_time_s=0.01 * evaluations[-1])


def test_ladder_spans_the_gap_log_spaced():
    t = target_ladder(1.0, 0.0, n_targets=3, smallest_gap=0.01)
    assert t == pytest.approx([0.0, 0.9, 0.99])
    with pytest.raises(ValueError, match="smallest_gap"):
        target_ladder(1.0, 0.0, smallest_gap=1.0)


def test_first_hits_and_profile():
    run = _run([10, 20, 40, 80], [0.1, 0.5, 0.5, 0.95])
    hits = first_hits(run, np.array([0.0, 0.5, 0.9, 0.99]))
    assert hits.tolist() == [10.0, 20.0, 80.0, np.inf]
    assert first_hits(run, np.array([0.5]), axis="wall_time") == pytest.approx([0.2])
    other = _run([10, 20], [0.0, 1.0])
    all_hits = np.stack([hits, first_hits(other, np.array([0.0, 0.5, 0.9, 0.99]))])
    # 8 pairs: 2 reached by 10 evaluations (0.0 by both runs), 6 by 20, 7 by 80
    assert runtime_profile(all_hits, np.array([5, 10, 20, 80])).tolist() == [
        0.0, 2 / 8, 6 / 8, 7 / 8]
