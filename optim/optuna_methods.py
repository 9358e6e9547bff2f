"""Optuna's samplers as methods: ``optuna:tpe``, ``optuna:random``, ``optuna:qmc``.

An Optuna study (in memory, maximizing the reward) over the normalized box [-1, 1]^n, one
float parameter per column, driven through its ask/tell interface
(:func:`optim.ask_tell.run_batches`): a batch of trials is asked, evaluated in one call, and
every trial told. The sampler is seeded with the run's seed. Optuna's own log lines (one per
trial) are kept quiet during the run and its verbosity put back afterwards.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .ask_tell import DEFAULT_BATCH_SIZE, check_batch_size, run_batches
from .optimize import Optimizer
from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["PREFIX", "SAMPLERS", "LISTED", "run_optuna", "driver", "check_name"]

PREFIX = "optuna"
# sampler name -> (optuna.samplers class, its keyword arguments besides the seed); Optuna's
# defaults otherwise, as a user of Optuna would run them (TPE's constant liar on: batches ask
# trials before the last ones are told)
SAMPLERS: dict[str, tuple[str, dict[str, Any]]] = {
    "tpe": ("TPESampler", {"constant_liar": True}),
    "random": ("RandomSampler", {}),
    "qmc": ("QMCSampler", {"scramble": True}),  # scrambled Sobol points
}
LISTED = tuple(SAMPLERS)


def _import_optuna():
    try:
        import optuna
    except ImportError as exc:
        raise ImportError("the optuna: methods need Optuna: pip install 'psm-grasp[optuna]'"
                          ) from exc
    return optuna


def check_name(name: Any) -> str:
    """Validate a sampler name of :data:`SAMPLERS`.

    Raises
    ------
    ValueError
        For another name (the message lists the allowed ones).
    """
    if not isinstance(name, str) or name not in SAMPLERS:
        raise ValueError(f"unknown Optuna sampler {name!r}; allowed: {', '.join(SAMPLERS)}")
    return name


def _study(sampler: str, seed: int):
    optuna = _import_optuna()
    cls, kwargs = SAMPLERS[sampler]
    return optuna.create_study(direction="minimize",
                               sampler=getattr(optuna.samplers, cls)(seed=seed, **kwargs))


def run_optuna(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    sampler: str = "tpe",
    batch_size: int = DEFAULT_BATCH_SIZE,
) -> OptimResult:
    """Maximize the reward with an Optuna sampler.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations (trials), >= 1; the last batch is asked short.
    seed
        Seed of the sampler.
    sampler
        ``"tpe"`` (default, the tree-structured Parzen estimator), ``"random"`` or ``"qmc"``.
    batch_size
        Trials asked per batch, evaluated in one call, in [1, 10000].
    """
    budget, seed = check_budget(budget), check_seed(seed)
    sampler, batch_size = check_name(sampler), check_batch_size(batch_size)
    optuna = _import_optuna()
    from optuna.distributions import FloatDistribution

    space = {f"x{i}": FloatDistribution(-1.0, 1.0) for i in range(problem.n_var)}
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        with warnings.catch_warnings():
            # its experimental options (the constant liar) and its advice to samplers are not
            # the user's to act on
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            warnings.simplefilter("ignore", UserWarning)
            study = _study(sampler, seed)

            def ask(n: int):
                trials = [study.ask(space) for _ in range(n)]
                return trials, np.array([[t.params[k] for k in space] for t in trials])

            def tell(trials, loss: np.ndarray) -> None:
                for t, y in zip(trials, loss.tolist(), strict=True):
                    study.tell(t, y)

            batches = run_batches(problem, budget, batch_size, ask, tell)
    finally:
        optuna.logging.set_verbosity(verbosity)
    return problem.result(f"{PREFIX}:{sampler}", seed, options={"batch_size": batch_size},
                          extra={"batches": batches})


def driver(name: str) -> Optimizer:
    """The driver of method ``optuna:NAME``: :func:`run_optuna` with that sampler.

    Raises
    ------
    ValueError
        For a sampler not in :data:`SAMPLERS`.
    """
    name = check_name(name)

    def run(problem: DesignProblem, *, budget: int, seed: int = 0,
            batch_size: int = DEFAULT_BATCH_SIZE) -> OptimResult:
        return run_optuna(problem, budget=budget, seed=seed, sampler=name,
                          batch_size=batch_size)

    run.__name__ = run.__qualname__ = f"run_optuna_{name}"
    run.__doc__ = f"Method ``optuna:{name}``: :func:`run_optuna` with the {name} sampler."
    return run
