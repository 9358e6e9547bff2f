"""pycma's own restart strategies as methods: ``cma:ipop`` and ``cma:bipop``.

``cma.fmin2`` with restarts: IPOP-CMA-ES (each restart doubles the population) or BIPOP-CMA-ES
(Hansen 2009: restarts alternate between doubled populations and small ones with a random,
smaller step size, under a shared budget), each run started from a uniform random point of the
normalized box [-1, 1]^n (the first from its centre, as :func:`optim.cmaes.run_cmaes`). A
population is evaluated in one call (``parallel_objective``); the search stops once the budget or
the time limit is spent, the candidates past the budget scored as the worst (they are not
evaluated, counted nor recorded). Settings as :func:`~optim.cmaes.run_cmaes`'s (bounds, step
size 0.4, the flat-fitness tolerance), so that the two differ by the restart strategy only.

BIPOP draws its small populations' sizes and step sizes from numpy's global random state:
the run seeds it with its seed and puts the caller's state back afterwards.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from .ask_tell import NON_FINITE_LOSS, loss_of
from .cmaes import _import_cma, default_popsize
from .optimize import Optimizer
from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["PREFIX", "STRATEGIES", "run_cma_restarts", "driver", "check_name"]

PREFIX = "cma"
STRATEGIES = ("ipop", "bipop")
MAX_RESTARTS = 10_000  # the budget ends a run, not a count of restarts
SIGMA0 = 0.4  # as run_cmaes's default


def check_name(name: Any) -> str:
    """Validate a restart strategy of :data:`STRATEGIES`.

    Raises
    ------
    ValueError
        For another name (the message lists the allowed ones).
    """
    if not isinstance(name, str) or name not in STRATEGIES:
        raise ValueError(f"unknown pycma restart strategy {name!r}; allowed: "
                         f"{', '.join(STRATEGIES)}")
    return name


@contextlib.contextmanager
def _global_seed(seed: int) -> Iterator[None]:
    """numpy's global random state seeded with ``seed`` inside, the caller's put back after."""
    state = np.random.get_state()  # noqa: NPY002 (pycma draws from the global state)
    np.random.seed(seed)  # noqa: NPY002
    try:
        yield
    finally:
        np.random.set_state(state)  # noqa: NPY002


def run_cma_restarts(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    strategy: str = "bipop",
) -> OptimResult:
    """Maximize the reward with ``cma.fmin2`` and its IPOP or BIPOP restarts.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1.
    seed
        Seed of the start points, of CMA-ES's samples and of BIPOP's draws.
    strategy
        ``"ipop"`` or ``"bipop"`` (default).

    Returns
    -------
    OptimResult
        Its method ``cma:STRATEGY``; ``extra`` holds the number of runs (the first and its
        restarts).
    """
    budget, seed, strategy = check_budget(budget), check_seed(seed), check_name(strategy)
    cma = _import_cma()
    rng = np.random.default_rng(seed)
    runs = [0]

    def x0() -> np.ndarray:  # called by fmin2 at every start: the centre, then uniform points
        runs[0] += 1
        return np.zeros(problem.n_var) if runs[0] == 1 else rng.uniform(-1.0, 1.0, problem.n_var)

    def objective(xs: list[np.ndarray]) -> list[float]:
        n = min(len(xs), problem.remaining)
        loss = np.full(len(xs), NON_FINITE_LOSS)
        if n:
            loss[:n] = loss_of(problem.evaluate(np.array(xs[:n]))["reward"])
        return loss.tolist()

    options = {
        "bounds": [-1.0, 1.0],
        "popsize": default_popsize(problem.n_var),
        "maxfevals": budget,
        "randn": lambda *shape: rng.standard_normal(shape),
        "seed": np.nan,  # the global state is seeded (and put back) around the run instead
        "verbose": -9, "verb_log": 0, "verb_disp": 0,
        "eval_final_mean": False,  # every evaluation is the search's
        "tolflatfitness": 10,  # as run_cmaes: invalid designs share one penalty
        "termination_callback": lambda es: problem.remaining <= 0,
    }
    problem.start(budget)
    with _global_seed(seed), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pycma's notes on its own settings
        cma.fmin2(None, x0, SIGMA0, options, parallel_objective=objective,
                          restarts=MAX_RESTARTS, bipop=strategy == "bipop")
    return problem.result(f"{PREFIX}:{strategy}", seed, options={"sigma0": SIGMA0},
                          extra={"runs": runs[0]})


def driver(name: str) -> Optimizer:
    """The driver of method ``cma:NAME``: :func:`run_cma_restarts` with that strategy.

    Raises
    ------
    ValueError
        For a strategy not in :data:`STRATEGIES`.
    """
    name = check_name(name)

    def run(problem: DesignProblem, *, budget: int, seed: int = 0) -> OptimResult:
        return run_cma_restarts(problem, budget=budget, seed=seed, strategy=name)

    run.__name__ = run.__qualname__ = f"run_cma_{name}"
    run.__doc__ = f"Method ``cma:{name}``: :func:`run_cma_restarts` with {name.upper()}."
    return run
