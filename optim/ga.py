"""Genetic algorithms with pymoo: a single-objective GA and NSGA-II (contact vs strain).

Both run pymoo's ask / evaluate / tell loop on a pymoo ``Problem`` whose vectorized
``_evaluate`` hands the whole population to :class:`~optim.problem.DesignProblem` in one call.
The loop (rather than ``pymoo.optimize.minimize``) lets the last generation be truncated so that
exactly ``budget`` evaluations are made, as for every driver.

- GA: one objective, ``F = -reward``.
- NSGA-II: two objectives, ``F = (-contact_score, peak_compression)`` (contact up, compression
  down), and three inequality constraints ``G <= 0``: the grasp converged, both fingers touch
  the disk, the peak compression is within the strain limit. The Pareto front of the result is
  the non-dominated set of every feasible design evaluated in the run. With scenarios the
  objectives and constraints are the envelopes over them (the smallest contact score, the
  largest compression and required friction, converged and touching in every scenario:
  :func:`~optim.problem.front_columns`): a feasible design holds within the strain limit in
  every scenario.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .problem import DesignProblem, check_budget, check_seed, front_columns
from .result import OptimResult

__all__ = ["run_ga", "run_nsga2", "pymoo_problem", "DEFAULT_POP_SIZE"]

DEFAULT_POP_SIZE = 40


def _import_pymoo():
    try:
        import pymoo  # noqa: F401
    except ImportError as exc:
        raise ImportError("GA and NSGA-II need pymoo: pip install 'psm-grasp[optim]'") from exc


def pymoo_problem(problem: DesignProblem, n_obj: int):
    """A pymoo ``Problem`` over [-1, 1]^6 evaluating populations through ``problem``.

    Parameters
    ----------
    problem
        The design problem (counts the evaluations, keeps the history).
    n_obj
        1: ``F = -reward``; 2: ``F = (-contact_score, peak_compression)`` with four constraints
        (converged, both fingers touching, the strain limit, the friction coefficient).
    """
    _import_pymoo()
    from pymoo.core.problem import Problem

    if n_obj not in (1, 2):
        raise ValueError(f"n_obj must be 1 or 2, got {n_obj!r}")

    class _GraspDesign(Problem):
        def __init__(self) -> None:
            super().__init__(n_var=problem.n_var, n_obj=n_obj, n_ieq_constr=0 if n_obj == 1 else 4,
                             xl=-1.0, xu=1.0)

        def _evaluate(self, x, out, *args, **kwargs):
            m = problem.evaluate(x)
            if n_obj == 1:
                out["F"] = -m["reward"][:, None]
                return
            contact, compression = front_columns(m)
            out["F"] = np.column_stack([-contact, compression])
            # (with scenarios: in every scenario)
            missing = np.count_nonzero(~m.get("all_touching", m["touching"]), axis=1)
            converged = m.get("all_converged", m["converged"])
            friction = m.get("max_required_friction", m["required_friction"])
            out["G"] = np.column_stack([
                0.5 - converged.astype(np.float64),  # <= 0 iff converged
                missing - 0.5,  # <= 0 iff both fingers touch
                (compression - problem.strain_limit) / problem.strain_limit,
                # <= 0 iff it holds without the pin (inf, one finger: a large finite value)
                np.minimum(friction / problem.friction_coefficient - 1.0, 1e6),
            ])

    return _GraspDesign()


def _check_pop_size(pop_size: Any) -> int:
    if isinstance(pop_size, bool) or int(pop_size) != pop_size or pop_size < 4:
        raise ValueError(f"pop_size must be an integer >= 4, got {pop_size!r}")
    return int(pop_size)


def _run(algorithm, problem: DesignProblem, n_obj: int, budget: int, seed: int) -> None:
    """pymoo's ask / evaluate / tell loop, stopping at exactly ``budget`` evaluations."""
    from pymoo.core.termination import NoTermination

    pp = pymoo_problem(problem, n_obj)
    problem.start(budget)
    algorithm.setup(pp, termination=NoTermination(), seed=seed, verbose=False)
    while problem.remaining > 0:
        pop = algorithm.ask()
        x = pop.get("X")
        if len(x) > problem.remaining:
            problem.evaluate(x[: problem.remaining])  # recorded, not told
            break
        algorithm.evaluator.eval(pp, pop)
        algorithm.tell(infills=pop)


def run_ga(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    pop_size: int = DEFAULT_POP_SIZE,
) -> OptimResult:
    """Maximize the reward with pymoo's genetic algorithm (SBX crossover, polynomial mutation).

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1.
    seed
        Seed of pymoo's random generator.
    pop_size
        Population size, >= 4.
    """
    budget, seed, pop_size = check_budget(budget), check_seed(seed), _check_pop_size(pop_size)
    _import_pymoo()
    from pymoo.algorithms.soo.nonconvex.ga import GA

    _run(GA(pop_size=pop_size, eliminate_duplicates=True), problem, 1, budget, seed)
    return problem.result("ga", seed, options={"pop_size": pop_size})


def run_nsga2(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    pop_size: int = DEFAULT_POP_SIZE,
) -> OptimResult:
    """Pareto front of contact score (up) against peak strain (down) with NSGA-II.

    Parameters
    ----------
    problem
        The design problem; its strain limit is a constraint here.
    budget
        Evaluations, >= 1.
    seed
        Seed of pymoo's random generator.
    pop_size
        Population size, >= 4.

    Returns
    -------
    OptimResult
        ``pareto_front`` holds the non-dominated feasible designs; ``best_design`` is the best
        reward seen, as for the other methods.
    """
    budget, seed, pop_size = check_budget(budget), check_seed(seed), _check_pop_size(pop_size)
    _import_pymoo()
    from pymoo.algorithms.moo.nsga2 import NSGA2

    _run(NSGA2(pop_size=pop_size, eliminate_duplicates=True), problem, 2, budget, seed)
    return problem.result("nsga2", seed, options={"pop_size": pop_size}, pareto=True)
