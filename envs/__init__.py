"""Point-spring model of a soft disk grasped by an angular gripper, and its design environment.

Importing the package registers ``GripperDesign-v2``, ``GripperJawDesign-v0`` (the same task
with shaped jaws in the action: a separate id, not a later version of v2) and
``GripperShapeDesign-v0`` (v2's task with objects that are not disks: ellipses at any
orientation, their shape observed; a separate id too) with Gymnasium::

    import gymnasium as gym
    import envs

    env = gym.make("GripperDesign-v2")
    vec = gym.make_vec("GripperDesign-v2", num_envs=64, vectorization_mode="vector_entry_point")
    jaws = gym.make("GripperJawDesign-v0", jaw="cradle")
"""

from __future__ import annotations

import warnings

import gymnasium

from ._kernel_cache import kernel_cache

# every kernel of the package is created by these imports: cached in a folder of this version
# of the source (numba would check a kernel's own file only, not the files it inlines)
with kernel_cache():
    from .design_env import GripperDesignEnv, GripperDesignVectorEnv, ObjectDistribution
    from .evaluate import DesignBounds, RewardWeights, evaluate_designs
    from .scene import PRESETS, Design, Gripper, Scene, SoftDisk
    from .solver import GraspResult, simulate, simulate_ramp

__all__ = [
    "Gripper",
    "SoftDisk",
    "Scene",
    "PRESETS",
    "simulate",
    "simulate_ramp",
    "GraspResult",
    "evaluate_designs",
    "Design",
    "DesignBounds",
    "RewardWeights",
    "ObjectDistribution",
    "GripperDesignEnv",
    "GripperDesignVectorEnv",
    "ENV_ID",
    "JAW_ENV_ID",
    "SHAPE_ENV_ID",
    "sb3_vec_env",
]

ENV_ID = "GripperDesign-v2"
JAW_ENV_ID = "GripperJawDesign-v0"  # with shaped jaws (envs.design_env.make_vector_env_v3)
SHAPE_ENV_ID = "GripperShapeDesign-v0"  # ellipses at any orientation, their shape observed


def sb3_vec_env(num_envs: int, seed: int | None = None, **env_kwargs):
    """A stable-baselines3 ``VecEnv`` of ``GripperDesign-v2`` stepped by one batched evaluation.

    See :func:`envs.sb3_env.sb3_vec_env` (imported here lazily: stable-baselines3 is the
    optional ``rl`` extra).
    """
    from .sb3_env import sb3_vec_env as make

    return make(num_envs, seed=seed, **env_kwargs)

if ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=ENV_ID,
        # the env inside Gymnasium's passive checker, its reset arguments checked outside it:
        # a refused first reset would break the checker for good (envs/reset_check.py)
        entry_point="envs.reset_check:make_env",
        disable_env_checker=True,  # make_env adds the checker itself
        vector_entry_point="envs.design_env:GripperDesignVectorEnv",
        # no TimeLimit: the env terminates after its one step by itself, and a TimeLimit of 1
        # would also flag that step as truncated (Gymnasium's checker rejects it)
    )

# v3 is v2 with shaped jaws (a wider action), not a newer v2: Gymnasium's "The environment
# GripperDesign-v2 is out of date. You should consider upgrading to version `v3`", which it
# says for any lower version of a registered name, would be wrong advice on every make of v2
warnings.filterwarnings("ignore", message=r".*The environment GripperDesign-v2 is out of date",
                        category=DeprecationWarning)

if JAW_ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=JAW_ENV_ID,
        # as v2 (reset arguments checked outside the checker, no TimeLimit); the jaws of the
        # action chosen at make (jaw=..., jaw_per_finger=...)
        entry_point="envs.reset_check:make_env_v3",
        disable_env_checker=True,
        vector_entry_point="envs.design_env:make_vector_env_v3",
    )

if SHAPE_ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=SHAPE_ENV_ID,
        # as v2; every object an ellipse at some orientation, its shape observed
        entry_point="envs.reset_check:make_env_v4",
        disable_env_checker=True,
        vector_entry_point="envs.design_env:make_vector_env_v4",
    )
