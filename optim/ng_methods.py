"""Nevergrad's optimizers as methods: ``ng:NAME`` runs Nevergrad's optimizer ``NAME``.

Any optimizer of Nevergrad's registry (``nevergrad.optimizers.registry``: ``NGOpt``, its
algorithm selector; ``TwoPointsDE``, a differential evolution; ``PSO``, ``CMA``,
``OnePlusOne``, ...) searches the normalized box [-1, 1]^n through its ask/tell interface
(:func:`optim.ask_tell.run_batches`): it is told the budget and the batch
(``num_workers``), so that it plans for whole batches, and every candidate it asks is evaluated
and told. The parametrization's random state is seeded with the run's seed, so a run repeats.
"""

from __future__ import annotations

import builtins
import contextlib
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from .ask_tell import DEFAULT_BATCH_SIZE, check_batch_size, run_batches
from .optimize import Optimizer
from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["PREFIX", "LISTED", "run_nevergrad", "driver", "check_name", "registry_names"]

PREFIX = "ng"
# the optimizers listed among the package's methods (any other registry name runs too)
LISTED = ("NGOpt", "TwoPointsDE")


def _import_nevergrad():
    try:
        import nevergrad
    except ImportError as exc:
        raise ImportError("the ng: methods need Nevergrad: pip install 'psm-grasp[ng]'") from exc
    return nevergrad


def registry_names() -> tuple[str, ...]:
    """Every optimizer of Nevergrad's registry, sorted."""
    return tuple(sorted(_import_nevergrad().optimizers.registry))


def check_name(name: Any) -> str:
    """Validate a Nevergrad optimizer name (case as Nevergrad spells it).

    Raises
    ------
    ValueError
        For a name not in Nevergrad's registry (the message names close ones and the listed
        ones).
    """
    import difflib

    names = registry_names()
    if not isinstance(name, str) or name not in names:
        close = difflib.get_close_matches(str(name), names, n=5, cutoff=0.6)
        raise ValueError(
            f"unknown Nevergrad optimizer {name!r}"
            + (f" (close: {', '.join(close)})" if close else "")
            + f"; allowed: any of nevergrad.optimizers.registry ({len(names)} names), e.g. "
            + ", ".join(LISTED))
    return name


def _one_element_float(value: Any) -> float:
    """``float`` that also takes a one-element array (numpy before 2.4 did, with a warning)."""
    if isinstance(value, np.ndarray) and value.size == 1:
        return builtins.float(value.reshape(()))
    return builtins.float(value)


@contextlib.contextmanager
def _metamodel_float() -> Iterator[None]:
    """Nevergrad 1.0.12's metamodel (which ``NGOpt`` picks for some budgets) converts a
    one-element prediction with ``float(array)``, which numpy >= 2.4 refuses (a ``TypeError``
    raised while a helper thread of Nevergrad waits: the process then hangs at exit;
    facebookresearch/nevergrad#1612). Inside, that module's ``float`` takes one-element arrays;
    the module is put back after."""
    try:
        from nevergrad.optimization import metamodel
    except ImportError:  # another layout: nothing to mend
        yield
        return
    had = "float" in vars(metamodel)
    old = vars(metamodel).get("float")
    metamodel.float = _one_element_float
    try:
        yield
    finally:
        if had:
            metamodel.float = old
        else:
            del metamodel.float


def _make_optimizer(name: str, n_var: int, budget: int, batch_size: int, seed: int):
    ng = _import_nevergrad()
    space = ng.p.Array(shape=(n_var,), lower=-1.0, upper=1.0)
    space.random_state = np.random.RandomState(seed)
    factory = ng.optimizers.registry[name]
    if batch_size > 1 and getattr(factory, "no_parallelization", False):
        raise ValueError(f"Nevergrad's {name} evaluates one candidate at a time: run it with "
                         "batch_size=1")
    return factory(parametrization=space, budget=budget, num_workers=batch_size)


def run_nevergrad(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    optimizer: str = "NGOpt",
    batch_size: int = DEFAULT_BATCH_SIZE,
) -> OptimResult:
    """Maximize the reward with one of Nevergrad's optimizers.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1 (told to the optimizer; the last batch is asked short).
    seed
        Seed of the parametrization's random state (the optimizer's only randomness).
    optimizer
        A name of ``nevergrad.optimizers.registry`` (default ``NGOpt``).
    batch_size
        Candidates asked per batch, evaluated in one call (Nevergrad's ``num_workers``), in
        [1, 10000].

    Returns
    -------
    OptimResult
        Its method ``ng:NAME``; ``extra`` holds the batches and, for ``NGOpt``, the optimizer
        it chose.
    """
    budget, seed = check_budget(budget), check_seed(seed)
    name, batch_size = check_name(optimizer), check_batch_size(batch_size)
    opt = _make_optimizer(name, problem.n_var, budget, batch_size, seed)

    def ask(n: int):
        cands = [opt.ask() for _ in range(n)]
        return cands, np.array([c.value for c in cands])

    def tell(cands, loss: np.ndarray) -> None:
        for c, y in zip(cands, loss.tolist(), strict=True):
            opt.tell(c, y)

    with warnings.catch_warnings(), _metamodel_float():
        # its advice on settings (a budget small for the dimension, ...) is not the user's, nor
        # pycma's notes on how Nevergrad drives it inside (solutions injected into its CMA-ES)
        warnings.simplefilter("ignore", _import_nevergrad().errors.NevergradWarning)
        warnings.filterwarnings("ignore", module=r"cma\.")
        batches = run_batches(problem, budget, batch_size, ask, tell)
    extra: dict[str, Any] = {"batches": batches}
    chosen = getattr(opt, "optim", None)  # NGOpt's selected optimizer
    if chosen is not None:
        extra["selected"] = getattr(chosen, "name", type(chosen).__name__)
    return problem.result(f"{PREFIX}:{name}", seed, options={"batch_size": batch_size},
                          extra=extra)


def driver(name: str) -> Optimizer:
    """The driver of method ``ng:NAME``: :func:`run_nevergrad` with that optimizer.

    Raises
    ------
    ValueError
        For a name not in Nevergrad's registry.
    """
    name = check_name(name)

    def run(problem: DesignProblem, *, budget: int, seed: int = 0,
            batch_size: int = DEFAULT_BATCH_SIZE) -> OptimResult:
        return run_nevergrad(problem, budget=budget, seed=seed, optimizer=name,
                             batch_size=batch_size)

    run.__name__ = run.__qualname__ = f"run_ng_{name}"
    run.__doc__ = f"Method ``ng:{name}``: :func:`run_nevergrad` with Nevergrad's {name}."
    return run
