"""``gym.make("GripperDesign-v2")``: the env inside Gymnasium's passive checker, its reset
arguments checked outside it.

Gymnasium's :class:`~gymnasium.wrappers.PassiveEnvChecker` (which ``gym.make`` puts around every
env unless told not to) marks its first ``reset`` as checked *before* calling the env, and keeps
that reset's data for its first ``step`` check only when the call returns. A first reset the env
refuses (an unknown option, a strain limit outside (0, 0.5], ...) leaves it marked but without
data, and every later first ``step`` then fails in its check with a ``TypeError``: one typo
would break the env for good. So the registered entry point, :func:`make_env`, builds the
checker itself, with :class:`ResetCheck` around it, and the registration disables the checker
``gym.make`` would add outside (``disable_env_checker=True``): a refused reset is refused
before the checker sees it. An extra wrapper registered as ``additional_wrappers`` would do the
same, but ``gym.make_vec`` refuses those with the vector entry point.
"""

from __future__ import annotations

from copy import deepcopy
from typing import Any

import gymnasium as gym
from gymnasium.utils import RecordConstructorArgs
from gymnasium.wrappers import PassiveEnvChecker

from .design_env import GripperDesignEnv, check_reset_arguments, jaw_bounds

__all__ = ["ResetCheck", "make_env", "make_env_v3"]


class ResetCheck(gym.Wrapper, RecordConstructorArgs):
    """Validates ``reset``'s seed and options (:func:`envs.design_env.check_reset_arguments`)
    before the wrapped env, and the wrappers inside it, are called; otherwise transparent."""

    def __init__(self, env: gym.Env) -> None:
        RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Refuse bad arguments with a ``ValueError``, then reset the wrapped env."""
        check_reset_arguments(seed, options)
        return self.env.reset(seed=seed, options=options)

    @property
    def spec(self):
        """The spec of the registered env: :func:`make_env` builds these wrappers and the
        checker again, so ``gym.make(env.spec)`` must not add them (nor an outer checker)."""
        if self._cached_spec is None and self.env.spec is not None:
            spec = deepcopy(self.env.spec)
            spec.disable_env_checker = True
            self._cached_spec = spec
        return self._cached_spec


def make_env(**kwargs: Any) -> gym.Env:
    """The entry point of ``GripperDesign-v2``: :class:`ResetCheck` around Gymnasium's
    :class:`~gymnasium.wrappers.PassiveEnvChecker` around a
    :class:`~envs.design_env.GripperDesignEnv` of ``kwargs``."""
    return ResetCheck(PassiveEnvChecker(GripperDesignEnv(**kwargs)))


def make_env_v3(*, jaw: str = "any", jaw_per_finger: bool = False, bounds=None,
                **kwargs: Any) -> gym.Env:
    """The entry point of ``GripperJawDesign-v0``: :func:`make_env` with the jaw columns in the
    action (:func:`envs.design_env.jaw_bounds`: ``jaw`` one of ``"straight"``, ``"cradle"``,
    ``"vee"``, ``"any"`` (default), ``jaw_per_finger``)."""
    return make_env(bounds=jaw_bounds(jaw, jaw_per_finger, bounds), **kwargs)


# gym.make reads the render modes from its entry point
def make_env_v4(**kwargs: Any) -> gym.Env:
    """The entry point of ``GripperShapeDesign-v0``: :func:`make_env` of an env that draws
    ellipses at any orientation and observes their shape (``observe_shapes=True``)."""
    return make_env(observe_shapes=True, **kwargs)


make_env.metadata = GripperDesignEnv.metadata  # type: ignore[attr-defined]
make_env_v4.metadata = GripperDesignEnv.metadata  # type: ignore[attr-defined]
make_env_v3.metadata = GripperDesignEnv.metadata  # type: ignore[attr-defined]
