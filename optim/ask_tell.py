"""The batch loop every ask/tell driver shares (Nevergrad's and Optuna's methods).

An outside library proposes candidates one by one (``ask``) and learns their values one by one
(``tell``); the problem evaluates a whole batch per call. :func:`run_batches` asks a batch, has
the problem evaluate it in one call, and tells the library every value, until the budget (or the
time limit) is spent; the last batch is asked short so that exactly ``budget`` evaluations are
made and every one of them is told.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .problem import DesignProblem

__all__ = ["DEFAULT_BATCH_SIZE", "check_batch_size", "run_batches", "loss_of"]

# candidates per batch: what the comparison ran (Optuna and Nevergrad driven in batches
# of 20); Nevergrad is told the batch (``num_workers``) so that it plans for it
DEFAULT_BATCH_SIZE = 20
MAX_BATCH_SIZE = 10_000
# what the libraries minimize for a reward that is not finite (none is, by the reward's
# construction; a library must never be handed an infinity or a NaN)
NON_FINITE_LOSS = 1e6

Ask = Callable[[int], tuple[Sequence[Any], np.ndarray]]
Tell = Callable[[Sequence[Any], np.ndarray], None]


def check_batch_size(batch_size: Any) -> int:
    """Validate a batch size: an integer in [1, 10000].

    Raises
    ------
    ValueError
        Naming the value and the allowed range.
    """
    if (isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer))
            or not 1 <= batch_size <= MAX_BATCH_SIZE):
        raise ValueError(f"batch_size must be an integer in [1, {MAX_BATCH_SIZE}], got "
                         f"{batch_size!r}")
    return int(batch_size)


def loss_of(reward: np.ndarray) -> np.ndarray:
    """What the libraries minimize: the negated reward, a non-finite one replaced by
    :data:`NON_FINITE_LOSS`."""
    loss = -np.asarray(reward, dtype=np.float64)
    return np.where(np.isfinite(loss), loss, NON_FINITE_LOSS)


def run_batches(problem: DesignProblem, budget: int, batch_size: int, ask: Ask,
                tell: Tell) -> int:
    """Ask, evaluate and tell whole batches until the problem's budget or time is spent.

    Parameters
    ----------
    problem
        The design problem; :meth:`~optim.problem.DesignProblem.start` is called here.
    budget
        Evaluations.
    batch_size
        Candidates per batch (the last batch is asked short).
    ask
        ``ask(n) -> (handles, x)``: ``n`` candidates, the library's handles and their rows
        ``x`` (n, ``problem.n_var``) in [-1, 1].
    tell
        ``tell(handles, loss)``: the losses (:func:`loss_of`) of those candidates.

    Returns
    -------
    int
        The number of batches evaluated.
    """
    problem.start(budget)
    batches = 0
    while problem.remaining > 0:
        handles, x = ask(min(batch_size, problem.remaining))
        out = problem.evaluate(x)
        tell(handles, loss_of(out["reward"]))
        batches += 1
    return batches
