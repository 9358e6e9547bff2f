"""The one interface shared by every optimizer driver, and the registry of methods.

A driver is a function ``run_x(problem, *, budget, seed, **options) -> OptimResult``: it calls
``problem.start(budget)``, asks the problem to evaluate whole populations until the budget is
spent (truncating its last population so that exactly ``budget`` evaluations are made) and
returns ``problem.result(...)``. Drivers are imported lazily, so that ``cma``, ``pymoo`` and
``torch`` load only when used.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any, Protocol

from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["METHODS", "Optimizer", "get_optimizer", "option_names", "check_options",
           "optimize"]

# method -> (module, function, pip extra holding its dependency)
_DRIVERS: dict[str, tuple[str, str, str]] = {
    "portfolio": ("optim.portfolio", "run_portfolio", "optim"),
    "cmaes": ("optim.cmaes", "run_cmaes", "optim"),
    "ga": ("optim.ga", "run_ga", "optim"),
    "nsga2": ("optim.ga", "run_nsga2", "optim"),
    "random": ("optim.random_search", "run_random_search", "optim"),
    "policy": ("optim.rl", "run_policy", "optim"),
}
METHODS: tuple[str, ...] = tuple(_DRIVERS)
# every driver's own arguments, not options
_COMMON = ("problem", "budget", "seed")


class Optimizer(Protocol):
    """What every driver is: a function of a problem, a budget and a seed."""

    def __call__(self, problem: DesignProblem, *, budget: int, seed: int,
                 **options: Any) -> OptimResult:
        """Spend ``budget`` evaluations of ``problem``; return the run's result."""
        ...


def get_optimizer(method: str) -> Optimizer:
    """The driver of a method name from :data:`METHODS`.

    Raises
    ------
    ValueError
        For an unknown method (the message lists the allowed ones).
    ImportError
        When the method's optional dependency is missing (with the install hint).
    """
    if method not in _DRIVERS:
        raise ValueError(f"unknown method {method!r}; allowed: {', '.join(METHODS)}")
    module_name, func_name, extra = _DRIVERS[method]
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ImportError(
            f"method {method!r} needs {exc.name!r}: pip install 'psm-grasp[{extra}]'"
        ) from exc
    return getattr(module, func_name)


def option_names(method: str) -> tuple[str, ...]:
    """The options a method takes: its driver's keyword arguments besides the budget and the
    seed, read from the driver's signature.

    A driver that passes ``**options`` on (PPO and SAC, to stable-baselines3) names what it
    accepts with a module function ``option_names(method)``.

    Raises
    ------
    ValueError
        For an unknown method.
    ImportError
        When the method's optional dependency is missing.
    """
    driver = get_optimizer(method)
    params = inspect.signature(driver).parameters.values()
    names = [p.name for p in params
             if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name not in _COMMON]
    if any(p.kind is p.VAR_KEYWORD for p in params):
        module = importlib.import_module(_DRIVERS[method][0])
        names += [n for n in module.option_names(method) if n not in names]
    return tuple(names)


def check_options(method: str, options: dict[str, Any]) -> None:
    """Refuse options a method does not take, before any work (a driver would raise a
    ``TypeError``, or stable-baselines3 deep inside a run).

    Raises
    ------
    ValueError
        Naming the unknown options and listing the method's.
    """
    allowed = option_names(method)
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(f"unknown option{'s' if len(unknown) > 1 else ''} "
                         f"{', '.join(map(repr, unknown))} for method {method!r}; allowed: "
                         f"{', '.join(allowed) or 'none'}")


def optimize(method: str, problem: DesignProblem, *, budget: int, seed: int = 0,
             **options: Any) -> OptimResult:
    """Run one optimizer on a problem.

    Parameters
    ----------
    method
        One of :data:`METHODS`.
    problem
        The design problem (object, strain limit, executor).
    budget
        Evaluations to spend, >= 1.
    seed
        Seed of the run, in [0, 2**32).
    **options
        Method options (see each driver; :func:`option_names` lists them).

    Raises
    ------
    ValueError
        For an unknown method, a bad budget or seed, an option the method does not take
        (:func:`check_options`) or a bad option value.
    """
    driver = get_optimizer(method)
    if not isinstance(problem, DesignProblem):
        raise ValueError(f"problem must be a DesignProblem, got {type(problem).__name__}")
    check_options(method, options)
    return driver(problem, budget=check_budget(budget), seed=check_seed(seed), **options)
