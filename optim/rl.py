"""PPO and SAC (stable-baselines3) on GripperDesign-v1: a policy from objects to designs.

Unlike the other drivers, RL does not search one object's design space: it trains a policy on
objects drawn at random (GripperDesign-v1 is a contextual bandit, one step per object) and is
then *asked* for a design for the fixed object. To compare it with the per-object optimizers on
equal terms, every training step counts as one evaluation of the budget, and every
``probe_every`` evaluations the deterministic policy's design for the fixed object is evaluated
(one more evaluation): the history is the best probe so far. :func:`evaluate_policy_regret`
measures what the amortization costs: the policy's reward on several objects against per-object
CMA-ES optima.

Defaults are small (CPU torch, two 64-unit layers, a few thousand steps).
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from envs.design_env import ObjectDistribution, observe
from envs.scene import SoftDisk

from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = [
    "RL_METHODS",
    "PolicyRegret",
    "train_policy",
    "run_ppo",
    "run_sac",
    "policy_design",
    "evaluate_policy_regret",
    "training_distribution",
]

RL_METHODS = ("ppo", "sac")
RL_HINT = "PPO and SAC need stable-baselines3 and torch: pip install 'psm-grasp[rl]'"
DEFAULT_N_ENVS = 4
DEFAULT_PROBES = 20
DEFAULT_NET = (64, 64)
# arguments of the stable-baselines3 constructors that train_policy sets (not options)
_SET_BY_TRAIN_POLICY = ("policy", "env", "seed", "policy_kwargs", "device", "verbose",
                        "_init_setup_model")


class PolicyRegret(NamedTuple):
    """The policy against a per-object CMA-ES optimum on one object."""

    object: dict[str, float]
    policy_design: dict[str, float]
    policy_reward: float
    cmaes_reward: float
    regret: float  # cmaes_reward - policy_reward (negative: the policy did better)


def _import_sb3():
    try:
        import stable_baselines3
        import torch  # noqa: F401
    except ImportError as exc:
        raise ImportError(RL_HINT) from exc
    return stable_baselines3


def option_names(method: str) -> tuple[str, ...]:
    """The options of :func:`run_ppo` and :func:`run_sac`: :func:`train_policy`'s own and the
    stable-baselines3 constructor's, but those :func:`train_policy` sets itself (read by
    :func:`optim.optimize.option_names`; imports stable-baselines3)."""
    if method not in RL_METHODS:
        raise ValueError(f"unknown RL method {method!r}; allowed: {', '.join(RL_METHODS)}")
    own = [p.name for p in inspect.signature(train_policy).parameters.values()
           if p.kind is p.KEYWORD_ONLY and p.name not in ("budget", "seed")]
    algo = inspect.signature(getattr(_import_sb3(), method.upper())).parameters.values()
    return tuple(own + [p.name for p in algo if p.kind is not p.VAR_KEYWORD
                        and p.name not in _SET_BY_TRAIN_POLICY])


def training_distribution(problem: DesignProblem) -> ObjectDistribution:
    """The env's default object distribution, widened to contain the problem's object (its
    radius, modulus, Poisson ratio, thickness, strain limit and friction; its calibration
    scale for every draw)."""
    base = ObjectDistribution()
    d = problem.disk

    def widen(pair, value):
        return (min(pair[0], value), max(pair[1], value))

    return ObjectDistribution(
        radius_range_m=widen(base.radius_range_m, d.radius_m),
        youngs_modulus_range_pa=widen(base.youngs_modulus_range_pa, d.youngs_modulus_pa),
        poisson_ratio_range=widen(base.poisson_ratio_range, d.poisson_ratio),
        thickness_range_m=widen(base.thickness_range_m, d.thickness_m),
        strain_limit_range=widen(base.strain_limit_range, problem.strain_limit),
        friction_range=widen(base.friction_range, problem.friction_coefficient),
        stiffness_scale=d.stiffness_scale,
    )


def policy_design(model: Any, disk: SoftDisk, strain_limit: float, problem: DesignProblem
                  ) -> np.ndarray:
    """The deterministic policy's normalized design (6,) for an object."""
    action, _ = model.predict(observe(disk, strain_limit, problem.friction_coefficient),
                              deterministic=True)
    return np.clip(np.asarray(action, dtype=np.float64).reshape(problem.n_var), -1.0, 1.0)


def _budget_callback(problem: DesignProblem, model_ref: list, probe_every: int):
    from stable_baselines3.common.callbacks import BaseCallback

    class _Budget(BaseCallback):
        """Counts training steps as evaluations, probes the policy, stops at the budget."""

        def __init__(self) -> None:
            super().__init__()
            self.since_probe = 0
            self.n_probes = 0

        def probe(self) -> None:
            x = policy_design(model_ref[0], problem.disk, problem.strain_limit, problem)
            problem.evaluate(x[None, :])
            self.n_probes += 1
            self.since_probe = 0

        def _on_step(self) -> bool:
            n = self.training_env.num_envs
            problem.add_external_evaluations(n)
            self.since_probe += n
            if self.since_probe >= probe_every and problem.remaining >= n + 2:
                self.probe()
            return problem.remaining >= n + 1  # room for one more step and the final probe

    return _Budget()


def _make_model(method: str, env: Any, seed: int, net: tuple[int, ...], budget: int,
                options: dict[str, Any]):
    sb3 = _import_sb3()
    policy_kwargs = {"net_arch": list(net)}
    if method == "ppo":
        kwargs = {"n_steps": 64, "batch_size": 64, "n_epochs": 5, "learning_rate": 3e-4,
                  "gamma": 0.0, "gae_lambda": 0.0, "ent_coef": 0.0}
        kwargs.update(options)
        return sb3.PPO("MlpPolicy", env, seed=seed, policy_kwargs=policy_kwargs, device="cpu",
                       verbose=0, **kwargs)
    kwargs = {"learning_starts": min(100, budget // 4), "batch_size": 64,
              "buffer_size": max(budget, 1000), "gamma": 0.0, "learning_rate": 1e-3,
              "train_freq": 1, "gradient_steps": 1}
    kwargs.update(options)
    return sb3.SAC("MlpPolicy", env, seed=seed, policy_kwargs=policy_kwargs, device="cpu",
                   verbose=0, **kwargs)


def train_policy(
    method: str,
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    n_envs: int = DEFAULT_N_ENVS,
    probe_every: int | None = None,
    net_arch: Sequence[int] = DEFAULT_NET,
    torch_threads: int | None = 1,
    **algo_options: Any,
) -> tuple[Any, OptimResult]:
    """Train PPO or SAC on GripperDesign-v1 with random objects, probing the fixed object.

    Parameters
    ----------
    method
        ``"ppo"`` or ``"sac"``.
    problem
        The fixed object (probed), and the env's physics settings (N, k_f, bounds, weights).
    budget
        Evaluations: training steps (one design on a random object each) plus probes;
        >= ``n_envs + 2``.
    seed
        Seed of the model and of the environments.
    n_envs
        Environments stepped together, their designs evaluated in one batch
        (:func:`envs.sb3_env.sb3_vec_env`), >= 1.
    probe_every
        Training steps between probes of the fixed object (default ``budget / 20``).
    net_arch
        Hidden layer sizes of the actor and the critic.
    torch_threads
        torch intra-op threads during training (None: leave torch's setting); the small
        networks run fastest on one thread, leaving the cores to the solver.
    **algo_options
        Passed to the stable-baselines3 constructor (``n_steps``, ``learning_rate``, ...).

    Returns
    -------
    model, OptimResult
        The trained model and the result (best probe design; ``extra`` holds the training
        steps, the number of probes and the final policy's reward).
    """
    if method not in RL_METHODS:
        raise ValueError(f"unknown RL method {method!r}; allowed: {', '.join(RL_METHODS)}")
    budget, seed = check_budget(budget), check_seed(seed)
    if isinstance(n_envs, bool) or int(n_envs) != n_envs or n_envs < 1:
        raise ValueError(f"n_envs must be an integer >= 1, got {n_envs!r}")
    n_envs = int(n_envs)
    if budget < n_envs + 2:
        raise ValueError(f"budget = {budget} is too small for {method}: it needs at least "
                         f"n_envs + 2 = {n_envs + 2} evaluations")
    if probe_every is None:
        probe_every = max(n_envs, budget // DEFAULT_PROBES)
    if isinstance(probe_every, bool) or int(probe_every) != probe_every or probe_every < 1:
        raise ValueError(f"probe_every must be an integer >= 1, got {probe_every!r}")
    net = tuple(int(v) for v in net_arch)
    _import_sb3()
    import torch
    from stable_baselines3.common.vec_env import VecMonitor

    from envs.sb3_env import sb3_vec_env

    # one batched evaluation per training step of n_envs designs (n_envs evaluations of the
    # budget); VecMonitor keeps the episode statistics that make_vec_env's Monitor gave
    env = VecMonitor(sb3_vec_env(
        n_envs, seed=seed,
        bounds=problem.bounds,
        distribution=training_distribution(problem),
        weights=problem.weights,
        **problem.joint_spring_kwargs(),
        **problem.model.kwargs(),
    ))
    threads = torch.get_num_threads()
    if torch_threads is not None:
        torch.set_num_threads(int(torch_threads))
    try:
        problem.start(budget)
        model = _make_model(method, env, seed, net, budget, dict(algo_options))
        model_ref = [model]
        callback = _budget_callback(problem, model_ref, int(probe_every))
        model.learn(total_timesteps=budget, callback=callback, progress_bar=False)
        callback.probe()  # the final policy, always recorded
        final = problem.evaluate_physical(problem.to_physical(
            policy_design(model, problem.disk, problem.strain_limit, problem))[None, :])
        final_reward = float(final["reward"][0])
    finally:
        torch.set_num_threads(threads)
        env.close()
    options = {"n_envs": n_envs, "probe_every": int(probe_every), "net_arch": list(net),
               **algo_options}
    extra = {"training_steps": int(model.num_timesteps), "n_probes": callback.n_probes,
             "final_policy_reward": final_reward}
    return model, problem.result(method, seed, options=options, extra=extra)


def run_ppo(problem: DesignProblem, *, budget: int, seed: int = 0, **options: Any
            ) -> OptimResult:
    """PPO on GripperDesign-v1 (see :func:`train_policy` for the options)."""
    return train_policy("ppo", problem, budget=budget, seed=seed, **options)[1]


def run_sac(problem: DesignProblem, *, budget: int, seed: int = 0, **options: Any
            ) -> OptimResult:
    """SAC on GripperDesign-v1 (see :func:`train_policy` for the options)."""
    return train_policy("sac", problem, budget=budget, seed=seed, **options)[1]


def _as_problem(obj: Any, template: DesignProblem | None) -> DesignProblem:
    if isinstance(obj, DesignProblem):
        return obj
    if isinstance(obj, SoftDisk):
        disk, limit = obj, None
    else:
        try:
            disk, limit = obj
        except (TypeError, ValueError):
            raise ValueError(
                f"objects must be DesignProblems, SoftDisks or (SoftDisk, strain_limit) pairs, "
                f"got {obj!r}") from None
    kwargs: dict[str, Any] = {}
    if template is not None:
        kwargs = {**template.joint_spring_kwargs(), "bounds": template.bounds,
                  "weights": template.weights, "executor": template.executor,
                  **template.model.kwargs()}
        if limit is None:
            limit = template.strain_limit
    if limit is None:
        return DesignProblem(disk, **kwargs)
    return DesignProblem(disk, limit, **kwargs)


def evaluate_policy_regret(
    model: Any,
    objects: Sequence[Any],
    cmaes_budget: int,
    *,
    seed: int = 0,
    template: DesignProblem | None = None,
) -> list[PolicyRegret]:
    """The policy's design on each object against a per-object CMA-ES optimum (the regret).

    Parameters
    ----------
    model
        A trained stable-baselines3 model (``predict(obs, deterministic=True)``).
    objects
        :class:`~optim.problem.DesignProblem`\\ s, :class:`~envs.scene.SoftDisk`\\ s or
        ``(SoftDisk, strain_limit)`` pairs.
    cmaes_budget
        Evaluations of each CMA-ES run, >= 1.
    seed
        Seed of the CMA-ES runs.
    template
        Physics settings (N, k_f, bounds, weights, executor, default strain limit) for objects
        that are not already problems; default those of :class:`DesignProblem`.

    Returns
    -------
    list[PolicyRegret]
        One row per object; ``regret = cmaes_reward - policy_reward``.
    """
    from .cmaes import run_cmaes

    cmaes_budget, seed = check_budget(cmaes_budget), check_seed(seed)
    rows = []
    for obj in objects:
        problem = _as_problem(obj, template)
        x = policy_design(model, problem.disk, problem.strain_limit, problem)
        policy_out = problem.evaluate_physical(problem.to_physical(x)[None, :])
        best = run_cmaes(problem, budget=cmaes_budget, seed=seed)
        policy_reward = float(policy_out["reward"][0])
        cmaes_reward = best.best_reward
        rows.append(PolicyRegret(
            object=problem.object_info(),
            policy_design=problem.design_dict(x),
            policy_reward=policy_reward,
            cmaes_reward=cmaes_reward,
            regret=cmaes_reward - policy_reward,
        ))
    return rows
