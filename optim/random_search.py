"""Random search, the floor every optimizer must beat: uniform designs in [-1, 1]^6."""

from __future__ import annotations

import numpy as np

from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["run_random_search", "DEFAULT_BATCH_SIZE"]

DEFAULT_BATCH_SIZE = 50


def run_random_search(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    batch_size: int = DEFAULT_BATCH_SIZE,
) -> OptimResult:
    """Evaluate ``budget`` uniform random designs, ``batch_size`` per batched call.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1.
    seed
        Seed of the ``numpy.random.Generator`` drawing the designs.
    batch_size
        Designs per call (one history point per batch), >= 1.
    """
    budget, seed = check_budget(budget), check_seed(seed)
    if isinstance(batch_size, bool) or int(batch_size) != batch_size or batch_size < 1:
        raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    rng = np.random.default_rng(seed)
    problem.start(budget)
    while problem.remaining > 0:
        n = min(int(batch_size), problem.remaining)
        problem.evaluate(rng.uniform(-1.0, 1.0, size=(n, problem.n_var)))
    return problem.result("random", seed, options={"batch_size": int(batch_size)})
