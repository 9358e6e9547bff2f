"""pycma's own restart strategies as methods: ``cma:ipop`` and ``cma:bipop``.

``cma.fmin2`` with restarts: IPOP-CMA-ES (each restart doubles the population) or BIPOP-CMA-ES
(Hansen 2009: restarts alternate between doubled populations and small ones with a random,
smaller step size, under a shared budget), each run started from a uniform random point of the
normalized box [-1, 1]^n (the first from its centre, as :func:`optim.cmaes.run_cmaes`). A
population is evaluated in one call (``parallel_objective``); the search stops once the budget or
the time limit is spent, the candidates past the budget scored as the worst (they are not
evaluated, counted nor recorded). Settings as :func:`~optim.cmaes.run_cmaes`'s (bounds, step
size 0.4, the flat-fitness tolerance), but for when a run ends (:data:`TOLFUN`,
:data:`TOLX`): with pycma's defaults no run ends within thousands of evaluations here, and no
restart strategy would restart.

BIPOP draws its small populations' sizes and step sizes from numpy's global random state:
the run seeds it with its seed and puts the caller's state back afterwards.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from envs.validation import check_range

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
# When a run ends, so that restarts happen within budgets of thousands: pycma's defaults
# (1e-11) never end a run on this problem (CMA-ES on paper-r070 ran 4000 evaluations without
# one), so neither IPOP nor BIPOP would restart. A run ends when its recent rewards agree within
# TOLFUN (a tenth of the 1e-3 that tells designs apart) or its steps are below TOLX of the
# normalized box (0.05 % of its width).
TOLFUN = 1e-4
TOLX = 1e-3


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
    tolfun: float = TOLFUN,
    tolx: float = TOLX,
    tolstagnation: int | None = None,
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
    tolfun
        A run ends when its recent rewards agree within this, in (0, 1].
    tolx
        A run ends when its steps are below this in the normalized box, in (0, 1].
    tolstagnation
        A run ends when the median of its recent rewards has not improved in this many
        iterations (pycma's ``tolstagnation``), an integer >= 1; ``None``: pycma's own
        ``100 + 100 n^1.5 / popsize`` (about 4000 evaluations with shaped jaws).

    Returns
    -------
    OptimResult
        Its method ``cma:STRATEGY``; ``extra`` holds the number of runs (the first and its
        restarts).
    """
    budget, seed, strategy = check_budget(budget), check_seed(seed), check_name(strategy)
    tolfun = check_range("tolfun", tolfun, 0.0, 1.0, low_open=True)
    tolx = check_range("tolx", tolx, 0.0, 1.0, low_open=True)
    if tolstagnation is not None and (isinstance(tolstagnation, bool)
                                      or not isinstance(tolstagnation, int | np.integer)
                                      or tolstagnation < 1):
        raise ValueError(f"tolstagnation must be None or an integer >= 1 (iterations), got "
                         f"{tolstagnation!r}")
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
        "tolfun": tolfun, "tolfunhist": tolfun, "tolx": tolx,
        **({} if tolstagnation is None else {"tolstagnation": int(tolstagnation)}),
        "termination_callback": lambda es: problem.remaining <= 0,
    }
    problem.start(budget)
    with _global_seed(seed), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pycma's notes on its own settings
        cma.fmin2(None, x0, SIGMA0, options, parallel_objective=objective,
                          restarts=MAX_RESTARTS, bipop=strategy == "bipop")
    return problem.result(f"{PREFIX}:{strategy}", seed,
                          options={"sigma0": SIGMA0, "tolfun": tolfun, "tolx": tolx,
                                   "tolstagnation": tolstagnation},
                          extra={"runs": runs[0]})


def driver(name: str) -> Optimizer:
    """The driver of method ``cma:NAME``: :func:`run_cma_restarts` with that strategy.

    Raises
    ------
    ValueError
        For a strategy not in :data:`STRATEGIES`.
    """
    name = check_name(name)

    def run(problem: DesignProblem, *, budget: int, seed: int = 0, tolfun: float = TOLFUN,
            tolx: float = TOLX, tolstagnation: int | None = None) -> OptimResult:
        return run_cma_restarts(problem, budget=budget, seed=seed, strategy=name,
                                tolfun=tolfun, tolx=tolx, tolstagnation=tolstagnation)

    run.__name__ = run.__qualname__ = f"run_cma_{name}"
    run.__doc__ = f"Method ``cma:{name}``: :func:`run_cma_restarts` with {name.upper()}."
    return run
