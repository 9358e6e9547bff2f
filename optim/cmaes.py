"""CMA-ES with pycma: ask a population, evaluate it in one batched call, tell the rewards.

The search runs in the normalized box [-1, 1]^6 (pycma's ``BoundTransform`` keeps every
candidate inside). When pycma's own stopping criteria fire before the budget is spent, the search
restarts from a random point with a doubled population (IPOP-CMA-ES), so the whole budget is used.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["run_cmaes", "default_popsize"]


def default_popsize(dim: int) -> int:
    """pycma's default population size ``4 + floor(3 ln dim)``."""
    return 4 + int(3 * math.log(dim))


def _import_cma():
    try:
        import cma
    except ImportError as exc:
        raise ImportError("CMA-ES needs pycma: pip install 'psm-grasp[optim]'") from exc
    return cma


def _check_options(popsize: int | None, sigma0: float, x0: Any, dim: int):
    if popsize is not None and (isinstance(popsize, bool) or int(popsize) != popsize
                                or popsize < 2):
        raise ValueError(f"popsize must be None or an integer >= 2, got {popsize!r}")
    if not (isinstance(sigma0, (int, float)) and 0.0 < sigma0 <= 2.0):
        raise ValueError(f"sigma0 = {sigma0!r} is outside the allowed range (0, 2]")
    if x0 is not None:
        x0 = np.asarray(x0, dtype=np.float64)
        if x0.shape != (dim,) or np.any(np.abs(x0) > 1.0):
            raise ValueError(f"x0 must be {dim} values in [-1, 1], got {x0.tolist()}")
    return x0


def _check_stds(stds: Any, dim: int) -> np.ndarray | None:
    if stds is None:
        return None
    stds = np.asarray(stds, dtype=np.float64)
    if stds.shape != (dim,) or not np.all((stds > 0.0) & (stds <= 20.0)):
        raise ValueError(f"stds must be {dim} values in (0, 20], got {stds.tolist()}")
    return stds


def run_cmaes(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    popsize: int | None = None,
    sigma0: float = 0.4,
    x0: Any = None,
    restarts: bool = True,
    stds: Any = None,
) -> OptimResult:
    """Maximize the reward with CMA-ES until ``budget`` evaluations are spent.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1; the last population is truncated to hit it exactly (the truncated
        population is evaluated and recorded but not told to CMA-ES).
    seed
        Seed of the run: CMA-ES samples from a ``numpy.random.Generator`` seeded with it (the
        global numpy state is neither used nor changed).
    popsize
        Population size ``lambda`` (default pycma's ``4 + floor(3 ln 6)`` = 9).
    sigma0
        Initial step size in the normalized box, in (0, 2].
    x0
        Initial mean in [-1, 1]^6 (default the centre of the box); restarts draw a uniform one.
    restarts
        Restart with a doubled population when CMA-ES stops before the budget is spent.
    stds
        Per-coordinate factors of ``sigma0`` (``n_var`` values in (0, 20]; default all 1):
        a start trusted in some coordinates more than in others.

    Returns
    -------
    OptimResult
        ``extra`` holds the number of restarts and the final step size.
    """
    budget, seed = check_budget(budget), check_seed(seed)
    x0 = _check_options(popsize, sigma0, x0, problem.n_var)
    stds = _check_stds(stds, problem.n_var)
    cma = _import_cma()
    rng = np.random.default_rng(seed)
    lam = default_popsize(problem.n_var) if popsize is None else int(popsize)
    mean = np.zeros(problem.n_var) if x0 is None else x0
    problem.start(budget)
    n_restarts, sigma = 0, sigma0
    while problem.remaining > 0:
        es = cma.CMAEvolutionStrategy(mean, sigma0, {
            "bounds": [-1.0, 1.0],
            "popsize": lam,
            "randn": lambda *shape: rng.standard_normal(shape),
            "seed": np.nan,  # do not touch numpy's global state
            "verbose": -9,
            "verb_log": 0,
            "verb_disp": 0,
            "tolflatfitness": 10,  # invalid designs share one penalty: give sigma time to grow
            **({} if stds is None or n_restarts else {"CMA_stds": stds}),
        })
        while problem.remaining > 0 and not es.stop():
            xs = es.ask()
            n = min(len(xs), problem.remaining)
            out = problem.evaluate(np.array(xs[:n]))
            if n < len(xs):
                break
            es.tell(xs, (-out["reward"]).tolist())
        sigma = float(es.sigma)
        if not restarts or problem.remaining <= 0:
            break
        n_restarts += 1
        lam *= 2
        mean = rng.uniform(-1.0, 1.0, problem.n_var)
    options = {"popsize": default_popsize(problem.n_var) if popsize is None else int(popsize),
               "sigma0": sigma0, "restarts": restarts}
    if stds is not None:
        options["stds"] = stds.tolist()
    return problem.result("cmaes", seed, options=options,
                          extra={"n_restarts": n_restarts, "final_sigma": sigma,
                                 "final_popsize": lam})
