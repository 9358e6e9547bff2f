"""GripperDesign-v2 as a stable-baselines3 ``VecEnv`` stepped with ONE batched evaluation.

stable-baselines3's own vector envs (``DummyVecEnv``, ``SubprocVecEnv``) step their sub-envs one
by one, so every design is solved by its own :func:`~envs.evaluate.evaluate_designs` call. Here
all sub-envs live in one :class:`~envs.design_env.GripperDesignVectorEnv` in ``SAME_STEP``
autoreset mode (every step evaluates every design, and every episode is one step), and this
module only translates between the Gymnasium vector API and stable-baselines3's::

    from stable_baselines3 import PPO
    from envs.sb3_env import sb3_vec_env

    env = sb3_vec_env(64, seed=0)
    PPO("MlpPolicy", env, gamma=0.0).learn(10_000)

stable-baselines3 is an optional dependency (``pip install 'psm-grasp[rl]'``): it is imported on
the first call of :func:`sb3_vec_env`, not when this module is imported, so ``import envs``
stays light.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

# from its own module, not from the package: envs/__init__ imports this module, and a module
# importing its package back closes an import circle
from .design_env import GripperDesignVectorEnv

__all__ = ["SB3_INSTALL_HINT", "sb3_vec_env"]

SB3_INSTALL_HINT = ("sb3_vec_env needs stable-baselines3: pip install 'psm-grasp[rl]'")
SEED_LIMIT = 2**32  # the project's seed range (optim.problem.check_seed), as numpy's legacy RNG
# GripperDesignVectorEnv arguments this adapter fixes: SB3 needs same-step autoreset and
# terminated (not truncated) one-step episodes.
_FIXED_KWARGS = ("autoreset_mode", "max_episode_steps", "num_envs")
# keys of a SAME_STEP step's info about the evaluated (ended) objects; the rest is reset info
_FINAL_KEYS = frozenset({"final_obs", "_final_obs", "final_info", "_final_info"})


def _check_num_envs(num_envs: Any) -> int:
    if (isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer)
            or num_envs < 1):
        raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
    return int(num_envs)


def _check_seed(seed: Any) -> int | None:
    if seed is None:
        return None
    if (isinstance(seed, bool) or not isinstance(seed, int | np.integer)
            or not 0 <= seed < SEED_LIMIT):
        raise ValueError(f"seed must be None or an integer in [0, 2**32), got {seed!r}")
    return int(seed)


def _scatter_info(info: dict[str, Any], infos: list[dict[str, Any]]) -> None:
    """Copy a Gymnasium vector ``info`` (arrays with ``_key`` masks) into per-env dicts.

    Scalars become Python scalars (as in :class:`~envs.design_env.GripperDesignEnv`'s info) via
    one ``tolist()`` per key, which is what keeps this cheap for hundreds of envs; rows of
    trailing-shape keys become small arrays (views of a private copy, so they do not alias the
    vector env's buffers).
    """
    # keys present for every env are written row by row with one dict.update each (a
    # key-by-key loop costs a Python assignment per key and env: ~10k per step of 256 envs)
    full_keys: list[str] = []
    full_columns: list[list[Any]] = []
    for key, value in info.items():
        if key.startswith("_"):
            continue
        mask = info.get(f"_{key}")
        arr = np.asarray(value)
        values = arr.tolist() if arr.ndim == 1 and arr.dtype != object else list(arr.copy())
        if mask is None or np.all(mask):
            full_keys.append(key)
            full_columns.append(values)
            continue
        for i in np.flatnonzero(mask).tolist():
            infos[i][key] = values[i]
    if full_keys:
        for env_info, row in zip(infos, zip(*full_columns, strict=True), strict=True):
            env_info.update(zip(full_keys, row, strict=True))


def _option_groups(options: list[dict[str, Any]]) -> list[tuple[dict[str, Any], list[int]]]:
    """Group sub-envs whose pending reset options are equal (one vector reset per group)."""
    groups: list[tuple[dict[str, Any], list[int]]] = []
    for i, opts in enumerate(options):
        for group_opts, rows in groups:
            if group_opts == opts:
                rows.append(i)
                break
        else:
            groups.append((opts, [i]))
    return groups


class _BatchedVecEnvMethods:
    """The stable-baselines3 ``VecEnv`` methods of :class:`GripperDesignSB3VecEnv`.

    Kept free of stable-baselines3 so that it can be defined at import; :func:`_sb3_class`
    combines it with SB3's ``VecEnv`` on first use (``super()`` then reaches ``VecEnv``).
    """

    def __init__(self, num_envs: int = 1, **env_kwargs: Any) -> None:
        fixed = sorted(set(env_kwargs) & set(_FIXED_KWARGS))
        if fixed:
            raise ValueError(f"{', '.join(fixed)} cannot be set: the stable-baselines3 adapter "
                             "uses same-step autoreset and terminated one-step episodes")
        #: The batched Gymnasium vector env holding every sub-env (shared by all of them).
        self.vector_env = GripperDesignVectorEnv(
            _check_num_envs(num_envs), autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
        self._actions: np.ndarray | None = None
        super().__init__(self.vector_env.num_envs,  # type: ignore[call-arg]
                         self.vector_env.single_observation_space,
                         self.vector_env.single_action_space)
        # SB3's base sets only render_modes; video recorders also read render_fps
        self.metadata = {**self.metadata,
                         "render_fps": self.vector_env.metadata["render_fps"]}

    # --- reset and step ------------------------------------------------------------------------

    def reset(self) -> np.ndarray:
        """Reset every sub-env; return the observations, float32 (num_envs, 4).

        Uses the seeds of :meth:`seed` (sub-env ``i`` gets ``seed + i``) and the options of
        :meth:`set_options` (``disk``, ``strain_limit``, ``friction_coefficient``), then forgets
        both, as SB3's vector envs do. The objects' info goes to ``reset_infos``.
        """
        n = self.num_envs
        self.reset_infos = [{} for _ in range(n)]
        # the vector env takes one options dict per call: reset each group of equal options
        # separately (seeds of rows outside the mask are ignored by the vector env)
        for opts, rows in _option_groups(self._options):
            mask = np.zeros(n, dtype=np.bool_)
            mask[rows] = True
            obs, info = self.vector_env.reset(seed=list(self._seeds),
                                              options={**opts, "reset_mask": mask})
            _scatter_info(info, self.reset_infos)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Store the actions (float (num_envs, n) in [-1, 1], n the action space's width: 6,
        more with shaped jaws) for :meth:`step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """Evaluate all stored actions in one batch; every sub-env then resets itself.

        Returns
        -------
        obs, rewards, dones, infos
            The NEXT objects' observations (float32), the rewards (float32), ``dones`` (all
            True: every episode is one step) and one dict per sub-env with every metric of the
            evaluated design (Python scalars or small arrays, as in
            :class:`~envs.design_env.GripperDesignEnv`), ``terminal_observation`` (the evaluated
            object's observation) and ``TimeLimit.truncated`` (False: episodes terminate).
        """
        if self._actions is None:
            raise RuntimeError("call step_async() before step_wait()")
        actions, self._actions = self._actions, None
        obs, rewards, terminated, truncated, info = self.vector_env.step(actions)
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        _scatter_info(info.get("final_info", {}), infos)
        final_obs = info.get("final_obs")
        reset_info = {k: v for k, v in info.items() if k not in _FINAL_KEYS}
        for i in range(self.num_envs):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            if dones[i]:
                infos[i]["terminal_observation"] = final_obs[i]
                self.reset_infos[i] = {}
        _scatter_info(reset_info, self.reset_infos)
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        """Close the batched env."""
        self.vector_env.close()

    # --- rendering -----------------------------------------------------------------------------

    def get_images(self) -> list[np.ndarray | None]:
        """One uint8 RGB frame per sub-env (``render_mode="rgb_array"``), else ``None``s."""
        if self.render_mode != "rgb_array":
            warnings.warn(f"The render mode is {self.render_mode}, but get_images() needs "
                          "'rgb_array' (set render_mode='rgb_array' at construction)",
                          stacklevel=2)
            return [None] * self.num_envs
        return list(self.vector_env.render())

    def render(self, mode: str | None = None) -> np.ndarray | None:
        """Tile the sub-envs' frames into one image (see SB3's ``VecEnv.render``)."""
        return super().render(mode=mode)  # type: ignore[misc]

    # --- attributes and methods ----------------------------------------------------------------
    # The sub-envs are rows of ONE batched env, so their attributes (bounds, distribution,
    # weights, n_triangles, joint_spring, render_mode, ...) are shared: reading
    # returns the shared value for each index, writing or calling affects every sub-env and is
    # therefore refused for a strict subset of them rather than silently applied to all.

    def _indices(self, indices: None | int | Iterable[int]) -> list[int]:
        rows = list(self._get_indices(indices))  # type: ignore[attr-defined]
        bad = [i for i in rows if not 0 <= int(i) < self.num_envs]
        if bad:
            raise IndexError(f"indices {bad} are outside [0, {self.num_envs})")
        return [int(i) for i in rows]

    def _require_all(self, indices: None | int | Iterable[int], what: str) -> list[int]:
        rows = self._indices(indices)
        if sorted(set(rows)) != list(range(self.num_envs)):
            raise ValueError(f"{what} applies to all {self.num_envs} sub-envs at once (they "
                             f"share one batched env); pass indices=None, got {rows}")
        return rows

    def get_attr(self, attr_name: str, indices: None | int | Iterable[int] = None) -> list[Any]:
        """The batched env's attribute, once per index (AttributeError if it has none)."""
        rows = self._indices(indices)
        value = getattr(self.vector_env, attr_name)
        return [value for _ in rows]

    def set_attr(self, attr_name: str, value: Any,
                 indices: None | int | Iterable[int] = None) -> None:
        """Set an attribute of the batched env, i.e. of every sub-env (``indices=None``)."""
        self._require_all(indices, "set_attr")
        setattr(self.vector_env, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any,
                   indices: None | int | Iterable[int] = None, **method_kwargs: Any) -> list[Any]:
        """Call a method of the batched env.

        ``"render"`` returns each requested sub-env's frame; any other method is called once
        (only with ``indices=None``) and its result is repeated for each sub-env.
        """
        if method_name == "render":
            rows = self._indices(indices)
            frames = self.vector_env.render(*method_args, **method_kwargs)
            return [None if frames is None else frames[i] for i in rows]
        rows = self._require_all(indices, f"env_method({method_name!r})")
        result = getattr(self.vector_env, method_name)(*method_args, **method_kwargs)
        return [result for _ in rows]

    def env_is_wrapped(self, wrapper_class: type,
                       indices: None | int | Iterable[int] = None) -> list[bool]:
        """Always False: the sub-envs are rows of a batched env, not wrapped ``gym.Env``\\ s."""
        return [False for _ in self._indices(indices)]


_CLASS_DOC = """A stable-baselines3 ``VecEnv`` of GripperDesign-v2 stepped with one batched call.

    Build it with :func:`sb3_vec_env`. Every ``step`` evaluates all sub-envs' designs in a single
    :func:`~envs.evaluate.evaluate_designs` call (through a
    :class:`~envs.design_env.GripperDesignVectorEnv` in ``SAME_STEP`` autoreset mode, the
    attribute ``vector_env``), ends every episode (``dones`` all True) and returns the next
    objects' observations, as SB3's ``DummyVecEnv`` over single envs does, only without the
    per-env Python loop around the solver.

    Parameters
    ----------
    num_envs
        Number of sub-environments, >= 1.
    **env_kwargs
        ``render_mode``, ``bounds``, ``distribution``, ``weights``, ``n_triangles``,
        ``torsion_stiffness_rel`` (the joint spring relative to each object, the default) or
        ``torsion_stiffness_nm_per_rad`` (absolute), ...: as for
        :class:`~envs.design_env.GripperDesignVectorEnv`.

    Notes
    -----
    The sub-envs share one batched env, so ``get_attr`` returns the shared attribute for each
    index, while ``set_attr`` and ``env_method`` (except ``"render"``) act on all sub-envs and
    refuse a strict subset of indices. ``env_is_wrapped`` is always False.
    """


@functools.cache
def _sb3_class() -> type:
    """Build :class:`GripperDesignSB3VecEnv` (imports stable-baselines3, once)."""
    try:
        from stable_baselines3.common.vec_env.base_vec_env import VecEnv
    except ImportError as exc:
        raise ImportError(SB3_INSTALL_HINT) from exc
    cls = type("GripperDesignSB3VecEnv", (_BatchedVecEnvMethods, VecEnv), {
        "__module__": __name__,
        "__qualname__": "GripperDesignSB3VecEnv",
        "__doc__": _CLASS_DOC,
    })
    return cls


def __getattr__(name: str) -> Any:
    # GripperDesignSB3VecEnv needs stable-baselines3: build it on first access (this also lets
    # pickle find the class by name)
    if name == "GripperDesignSB3VecEnv":
        return _sb3_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def sb3_vec_env(num_envs: int, seed: int | None = None, **env_kwargs: Any):
    """GripperDesign-v2 as a stable-baselines3 ``VecEnv`` stepped with one batched evaluation.

    Parameters
    ----------
    num_envs
        Number of sub-environments (designs evaluated per step), an integer >= 1.
    seed
        ``None`` (fresh entropy) or an integer in ``[0, 2**32)``: the first ``reset()`` draws
        sub-env ``i``'s objects as a :class:`~envs.design_env.GripperDesignEnv` reset with
        ``seed + i`` (as ``make_vec_env(..., seed=seed)`` does); the action space is seeded
        with ``seed``. An SB3 model built with its own ``seed`` re-seeds the env the same way.
    **env_kwargs
        ``render_mode`` (``None`` or ``"rgb_array"``), ``bounds``, ``distribution``,
        ``weights``, ``n_triangles``, ``torsion_stiffness_rel`` (the joint spring relative to
        each object, the default) or ``torsion_stiffness_nm_per_rad`` (absolute), ...: as for
        :class:`~envs.design_env.GripperDesignVectorEnv`. Shaped jaws (GripperJawDesign-v0's
        actions): ``bounds=envs.design_env.jaw_bounds("cradle")``; the action space is as wide
        as the bounds' columns.

    Returns
    -------
    GripperDesignSB3VecEnv
        A ``stable_baselines3.common.vec_env.VecEnv``; wrap it in ``VecMonitor`` for episode
        statistics and ``VecNormalize`` as usual.

    Raises
    ------
    ValueError
        If ``num_envs`` or ``seed`` is out of range, or an env argument is invalid.
    ImportError
        If stable-baselines3 is not installed (with the install hint).
    """
    num_envs = _check_num_envs(num_envs)
    seed = _check_seed(seed)
    env = _sb3_class()(num_envs, **env_kwargs)
    if seed is not None:
        env.seed(seed)
        env.action_space.seed(seed)
    return env
