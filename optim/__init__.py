"""Optimizers for the gripper design, compared side by side on one machine or a Dask cluster.

Every method shares one interface and one result type::

    from optim import DesignProblem, optimize

    problem = DesignProblem.from_scene("paper-r070", strain_limit=0.15)
    result = optimize("cmaes", problem, budget=2000, seed=0)
    result.to_json("out/cmaes.json")

Methods (:data:`METHODS`): ``cmaes`` (pycma), ``ga`` and ``nsga2`` (pymoo), ``random`` and
``policy`` (the shipped design policy's design, then CMA-ES refining it; the policy is trained
with stable-baselines3 by :func:`optim.rl.train_policy`), and other libraries' methods on the
same problem: ``ng:NAME`` (Nevergrad), ``optuna:tpe`` / ``random`` / ``qmc`` (Optuna),
``cma:ipop`` / ``bipop`` (pycma's restarts). Their heavy dependencies are imported only when
used. :mod:`optim.bench` is a benchmark suite of named instances built on them. With a scene
preset or an object file, :func:`optim.run.run_optimize`
also writes the files of ``psm-grasp optimize``.
Populations are evaluated in-process by default, or through an executor of
:mod:`optim.executors` (local processes, Dask).
"""

from __future__ import annotations

from .optimize import METHODS, Optimizer, get_optimizer, optimize
from .problem import DEFAULT_STRAIN_LIMIT, BudgetExhaustedError, DesignProblem, paper_design
from .result import NoGraspWarning, OptimResult

__all__ = [
    "METHODS",
    "DEFAULT_STRAIN_LIMIT",
    "BudgetExhaustedError",
    "DesignProblem",
    "NoGraspWarning",
    "OptimResult",
    "Optimizer",
    "get_optimizer",
    "optimize",
    "paper_design",
]
