"""A design policy: a gripper for a new object in one forward pass, trained with RL.

GripperDesign-v2 is a contextual bandit: an object, one design, one reward. Trained over an
object distribution that covers real use (:class:`envs.design_env.ObjectDistribution`), a
stable-baselines3 agent (SAC by default, or PPO) learns a policy from the object to a design;
:func:`train_policy` runs the training and returns a :class:`DesignPolicy`, whose
:meth:`~DesignPolicy.design` answers a new object with one forward pass of the actor network,
in numpy (no torch needed to use it). :meth:`~DesignPolicy.refine` starts CMA-ES at that
design for a few evaluations more. A policy trained by ``scripts/train_shipped_policy.py``
ships with the package (:func:`load_policy` with no path).

The observation is what changes a relative design's grasp: the Poisson ratio, the strain
limit, the friction coefficient, the calibration scale, the payload ratio ``f rho g pi r / (s
E)`` and the placement tolerance over the radius. The model is scale invariant (every length in
radii, the torque and the joint spring in ``s E t r^2``, forces in ``s E t r``), so radius,
modulus, thickness and density need not be observed; the policy designs in the
object-relative box and the design is scaled to the object.

Training settings that learn (measured, see ``scripts/bench_policy.py``): ``gamma = 0`` (one
step an episode), 64 environments stepped by one batched evaluation, several gradient steps a
step, a small initial action noise (the box's centre at std 1 clips a third of the coordinates
and misses the object with half the samples), and the reward's tail below the holding grasps
bounded smoothly at the object's strain limit (:func:`bounded_tail`): the optimum is about a
third of the strain limit, and a critic fitting misses at -3 cannot resolve differences of
0.005 near it.
"""

from __future__ import annotations

import functools
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any

import numpy as np

from envs.design_env import (
    OBS_FIELDS,
    ObjectDistribution,
    evaluate_objects,
    jaw_bounds,
    observe_rows,
)
from envs.evaluate import DesignBounds, RewardWeights
from envs.model.defaults import DEFAULT_PAYLOAD_FACTOR
from envs.model.family import resolve_model
from envs.scene import SoftDisk
from envs.validation import check_input_file

from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = [
    "RL_METHODS",
    "DesignPolicy",
    "PolicyMismatchError",
    "TrainingSettings",
    "bounded_tail",
    "load_policy",
    "run_policy",
    "train_policy",
    "write_training_outputs",
    "learning_curve_figure",
    "heldout_objects",
    "heldout_rewards",
    "SHIPPED_POLICY",
]

RL_METHODS = ("sac", "ppo")
RL_HINT = "training a policy needs stable-baselines3 and torch: pip install 'psm-grasp[rl]'"
POLICY_FORMAT = 1
POLICY_FILES = ("policy.json", "policy.npz")
ACTIVATIONS = ("relu", "tanh")  # of the hidden layers (DesignPolicy.actions)
SQUASHES = ("tanh", "clip")  # of the output: SAC's tanh, PPO's clipped mean
MAX_LAYERS = 64  # a policy's linear layers at most (the shipped ones have 3)
# the type of each key of a policy's metadata (DesignPolicy.save, train_policy's meta)
POLICY_META_TYPES: dict[str, type] = {
    "format": int, "obs_fields": list, "bounds": dict, "name": str, "package_version": str,
    "reward_weights": dict, "model": dict, "joint_spring": dict, "distribution": dict,
    "method": str, "training": dict, "activation": str, "squash": str, "n_layers": int}
_KIND_WORDS = {int: "an integer", list: "a list", dict: "an object ({...})", str: "a string"}
SHIPPED_POLICY = Path(__file__).resolve().parent / "policies" / "default"
# the shipped policy that designs shaped jaws too (the "any" jaw space of GripperJawDesign-v0)
SHIPPED_JAW_POLICY = Path(__file__).resolve().parent / "policies" / "jaws"
SHIPPED_JAWS = {"straight": SHIPPED_POLICY, "any": SHIPPED_JAW_POLICY}
REFINE_SIGMA = 0.1  # CMA-ES step size around the policy's design, in the normalized box
# the step size in the jaw columns: a cold CMA-ES's (its sigma0), since the jaw policy's
# grooves are where its designs miss most (scripts/bench_policy.py --jaw any)
REFINE_JAW_SIGMA = 0.4


class PolicyMismatchError(ValueError):
    """A saved policy does not fit this package (observation, actions, model, version)."""


def bounded_tail(reward: np.ndarray, strain_limit: np.ndarray, scale: float = 1.0
                 ) -> np.ndarray:
    """The reward with its negative part bounded smoothly at ``scale`` times the strain limit.

    ``r`` where ``r >= 0``, else ``b r / (b - r)`` with ``b = scale * strain_limit``: strictly
    increasing (every tier of the reward keeps its order: a miss never outscores a grasp),
    slope 1 at 0 (designs near the optimum keep their differences) and bounded below by
    ``-b``, a scale of the optimum itself (about a third of the strain limit).
    """
    r = np.asarray(reward, dtype=np.float64)
    b = scale * np.asarray(strain_limit, dtype=np.float64)
    return np.where(r >= 0.0, r, b * r / (b - np.minimum(r, 0.0)))


def _package_version() -> str:
    try:
        return importlib_metadata.version("psm-grasp")
    except importlib_metadata.PackageNotFoundError:  # pragma: no cover - source checkout
        return "0+unknown"


@dataclass(frozen=True)
class TrainingSettings:
    """How a policy is trained (recorded in its metadata).

    Parameters
    ----------
    method
        ``"sac"`` or ``"ppo"`` (stable-baselines3).
    steps
        Environment steps (designs evaluated) of the training, >= ``n_envs``.
    seed
        Seed of the agent and of the environments.
    n_envs
        Environments stepped together by one batched evaluation.
    net_arch
        Hidden layers of the actor and the critic(s).
    tail_scale
        :func:`bounded_tail` scale of the training reward (0: the env's reward as it is).
    initial_log_std
        Initial log standard deviation of the action noise.
    learning_rate, batch_size, gradient_steps
        SAC's learning rate, batch and gradient steps per environment step (PPO: learning rate
        and minibatch; ``n_steps`` per rollout is ``2048 // n_envs``).
    """

    method: str = "sac"
    steps: int = 200_000
    seed: int = 0
    n_envs: int = 64
    net_arch: tuple[int, ...] = (64, 64)
    tail_scale: float = 1.0
    initial_log_std: float = -1.0
    learning_rate: float = 1e-3
    batch_size: int = 256
    gradient_steps: int = 8

    def __post_init__(self) -> None:
        if self.method not in RL_METHODS:
            raise ValueError(f"method must be one of {RL_METHODS}, got {self.method!r}")
        check_seed(self.seed)
        for name, low in (("n_envs", 1), ("batch_size", 1), ("gradient_steps", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
        steps = check_budget(self.steps)
        if steps < self.n_envs:
            raise ValueError(f"steps = {steps} must be at least n_envs = {self.n_envs}")
        arch = tuple(int(v) for v in self.net_arch)
        if not arch or min(arch) < 1:
            raise ValueError(f"net_arch must be positive layer sizes, got {self.net_arch!r}")
        object.__setattr__(self, "net_arch", arch)
        for name, low, high in (("tail_scale", 0.0, 100.0), ("initial_log_std", -5.0, 1.0),
                                ("learning_rate", 1e-6, 1.0)):
            v = float(getattr(self, name))
            if not low <= v <= high:
                raise ValueError(f"{name} = {v!r} is outside the allowed range [{low}, {high}]")


@dataclass
class DesignPolicy:
    """An object -> design policy: the actor network's layers and what it was trained for.

    Attributes
    ----------
    layers
        ``(weights (out, in), bias (out,))`` of each linear layer, input to output.
    activation
        Activation of the hidden layers (``"relu"`` or ``"tanh"``).
    squash
        ``"tanh"`` (SAC's deterministic action) or ``"clip"`` (PPO's mean, clipped).
    meta
        The metadata: format, package version, observation fields, action bounds, reward
        weights, model member, joint spring, object distribution, training settings and
        results.
    """

    layers: list[tuple[np.ndarray, np.ndarray]]
    activation: str
    squash: str
    meta: dict[str, Any] = field(default_factory=dict)

    # --- the forward pass -------------------------------------------------------------------

    def actions(self, observations: np.ndarray) -> np.ndarray:
        """Normalized designs in [-1, 1] (B, :attr:`bounds` ``n_var``: 6, plus the jaw
        columns of a policy that designs shaped jaws) of observations (B, 6): one forward
        pass."""
        x = np.asarray(observations, dtype=np.float64)
        for k, (w, b) in enumerate(self.layers):
            x = x @ w.T + b
            if k < len(self.layers) - 1:
                x = np.maximum(x, 0.0) if self.activation == "relu" else np.tanh(x)
        return np.tanh(x) if self.squash == "tanh" else np.clip(x, -1.0, 1.0)

    @property
    def bounds(self) -> DesignBounds:
        """The action box the policy designs in."""
        return bounds_of_meta(self.meta["bounds"])

    @property
    def jaw(self) -> str:
        """The jaws the policy designs: ``"straight"``, or a kind of shaped jaws (``"any"``)."""
        return self.bounds.jaw

    def problem(self, disk: SoftDisk, strain_limit: float, friction_coefficient: float,
                **kwargs: Any) -> DesignProblem:
        """The design problem of an object with the policy's settings (box, weights, model
        member, joint spring)."""
        spring = self.meta["joint_spring"]
        return DesignProblem(disk, strain_limit, friction_coefficient, bounds=self.bounds,
                             weights=RewardWeights(**self.meta["reward_weights"]),
                             **spring, **self.meta["model"], **kwargs)

    def design(self, disk: SoftDisk, strain_limit: float, friction_coefficient: float,
               payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
               placement_tolerance_rel: float = 0.0) -> dict[str, float]:
        """The policy's design for one object, in SI units (keys of
        :data:`envs.scene.DESIGN_FIELDS`).

        Parameters
        ----------
        disk, strain_limit, friction_coefficient
            The object and what its grasp must respect.
        payload_factor
            ``f`` of the payload ``W = f rho pi r^2 t g`` [-] (default 2).
        placement_tolerance_rel
            Placement tolerance over the radius [-], in [0, 0.5] (default 0).

        Raises
        ------
        ValueError
            For an object outside the observable range (the message names the field).
        """
        return self.problem(disk, strain_limit, friction_coefficient,
                            payload_factor=payload_factor).design_dict(
            self.normalized(disk, strain_limit, friction_coefficient, payload_factor,
                            placement_tolerance_rel))

    def normalized(self, disk: SoftDisk, strain_limit: float, friction_coefficient: float,
                   payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
                   placement_tolerance_rel: float = 0.0) -> np.ndarray:
        """The policy's design for one object, normalized (its bounds' ``n_var``,) (arguments
        as :meth:`design`)."""
        if not isinstance(disk, SoftDisk):
            raise ValueError(f"disk must be a SoftDisk, got {type(disk).__name__}")
        obs = observe_rows([disk], np.array([[strain_limit, friction_coefficient,
                                              payload_factor, placement_tolerance_rel]],
                                            dtype=float))
        return self.actions(obs)[0]

    def starts(self, problem: DesignProblem) -> np.ndarray:
        """The policy's candidate designs for a problem's object, normalized rows (k,
        :attr:`~optim.problem.DesignProblem.n_var`): its own design and, for a policy of shaped
        jaws, the same gripper with its groove centred where the object meets the finger
        (:meth:`~envs.design_space.DesignBounds.aligned`) and the shipped straight policy's
        design as a straight bar. A policy of shaped jaws places grooves where its training
        left them, often away from the contact."""
        x0 = self.normalized(problem.disk, problem.strain_limit, problem.friction_coefficient,
                             problem.payload_factor, problem_tolerance_rel(problem))
        if self.jaw == "straight":
            return x0[None, :]
        fields = self.bounds.fields
        at_foot = x0.copy()
        at_foot[fields.index("jaw_position")] = 0.0
        bar = np.zeros_like(x0)
        bar[:6] = _shipped_policy("straight").normalized(
            problem.disk, problem.strain_limit, problem.friction_coefficient,
            problem.payload_factor, problem_tolerance_rel(problem))
        bar[fields.index("jaw_depth_w")] = -1.0  # depth 0: a straight bar
        return np.stack([x0, self.bounds.aligned(at_foot[None, :])[0], bar])

    def run(self, problem: DesignProblem, *, budget: int = 1, seed: int = 0) -> OptimResult:
        """The best of the policy's candidate designs for a problem's object (:meth:`starts`),
        then CMA-ES started at it for the rest of the budget (step size :data:`REFINE_SIGMA`,
        :data:`REFINE_JAW_SIGMA` in the jaw columns, :func:`refine_stds`): an
        :class:`OptimResult` with method ``"policy"``."""
        from .cmaes import run_cmaes

        budget, seed = check_budget(budget), check_seed(seed)
        if problem.bounds != self.bounds:
            raise ValueError(f"the problem's design box {problem.bounds} is not the one the "
                             f"policy designs in, {self.bounds}")
        starts = self.starts(problem)
        problem.start(budget)
        first_out = problem.evaluate(starts[:budget])
        x0 = starts[int(np.argmax(first_out["reward"]))]
        first = (problem.best_reward, problem.n_evaluations)
        stds = refine_stds(self.bounds)
        if budget > first[1]:
            run_cmaes(_Continue(problem), budget=budget - first[1], seed=seed,
                      x0=np.clip(x0, -1.0, 1.0), sigma0=REFINE_SIGMA, stds=stds)
        return problem.result("policy", seed, options={"refine": budget - 1,
                                                       "sigma0": REFINE_SIGMA,
                                                       "stds": stds.tolist()},
                              extra={"policy_reward": first[0],
                                     "policy": self.meta.get("name", "policy")})

    # --- saving and loading -----------------------------------------------------------------

    def save(self, folder: str | Path) -> Path:
        """Write ``policy.json`` (metadata) and ``policy.npz`` (layers) to ``folder``."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        arrays = {}
        for k, (w, b) in enumerate(self.layers):
            arrays[f"w{k}"], arrays[f"b{k}"] = w.astype(np.float32), b.astype(np.float32)
        np.savez_compressed(folder / "policy.npz", **arrays)
        meta = {**self.meta, "activation": self.activation, "squash": self.squash,
                "n_layers": len(self.layers)}
        (folder / "policy.json").write_text(json.dumps(meta, indent=1) + "\n")
        return folder


def refine_stds(bounds: DesignBounds) -> np.ndarray:
    """Per-column factors of :data:`REFINE_SIGMA` for the refinement of a policy's design:
    1 in the six gripper columns, :data:`REFINE_JAW_SIGMA` / :data:`REFINE_SIGMA` in the jaw
    columns."""
    stds = np.ones(bounds.n_var)
    stds[len(bounds.fields) - len(bounds.jaw_fields):] = REFINE_JAW_SIGMA / REFINE_SIGMA
    return stds


def problem_tolerance_rel(problem: DesignProblem) -> float:
    """The placement tolerance over the radius the policy observes for a problem: the larger
    of its scenarios' tolerances along and across the axis over the nominal radius (0 without
    scenarios). The policy observes the nominal object of a problem with ranges."""
    s = problem.scenarios
    if s is None:
        return 0.0
    return max(s.placement_along_m, s.placement_across_m) / problem.disk.radius_m


class _Continue:
    """A view of a started problem whose ``start`` keeps the run going: CMA-ES refining the
    policy's design counts into the same budget, history and best."""

    def __init__(self, problem: DesignProblem) -> None:
        self._problem = problem

    def start(self, budget: int | None, time_limit_s: float | None = None) -> None:
        pass

    def result(self, *args: Any, **kwargs: Any) -> None:
        return None  # the run's result is the problem's own, made by the caller

    def __getattr__(self, name: str) -> Any:
        return getattr(self._problem, name)


def bounds_meta(bounds: DesignBounds) -> dict[str, Any]:
    """A policy's design box as its metadata records it: the six columns' bounds and, for a
    policy that designs shaped jaws, the jaw kind, per finger or not, and the jaw columns'
    bounds."""
    meta: dict[str, Any] = {"low": list(bounds.low), "high": list(bounds.high)}
    if bounds.jaw != "straight":
        meta.update({"jaw": bounds.jaw, "jaw_per_finger": bounds.jaw_per_finger,
                     "jaw_low": list(bounds.jaw_low), "jaw_high": list(bounds.jaw_high)})
    return meta


def bounds_of_meta(meta: dict[str, Any]) -> DesignBounds:
    """The design box of a policy's metadata (:func:`bounds_meta`)."""
    jaw = meta.get("jaw", "straight")
    extra: dict[str, Any] = {}
    if jaw != "straight":
        extra = {"jaw": jaw, "jaw_per_finger": bool(meta.get("jaw_per_finger", False)),
                 "jaw_low": tuple(meta["jaw_low"]), "jaw_high": tuple(meta["jaw_high"])}
    return DesignBounds(tuple(meta["low"]), tuple(meta["high"]), **extra)


def _expected_meta(bounds: DesignBounds | None = None) -> dict[str, Any]:
    """What this package needs of a policy's metadata to use it (the default box, with the
    jaws of ``bounds`` if given)."""
    b = DesignBounds() if bounds is None else bounds
    return {"format": POLICY_FORMAT, "obs_fields": [list(f) for f in OBS_FIELDS],
            "bounds": bounds_meta(b)}


def _check_meta(meta: dict[str, Any], where: str) -> None:
    expected = _expected_meta()
    if meta.get("format") != expected["format"]:
        raise PolicyMismatchError(f"{where}: policy format {meta.get('format')!r}, this "
                                  f"package reads format {POLICY_FORMAT}")
    if meta.get("obs_fields") != expected["obs_fields"]:
        raise PolicyMismatchError(
            f"{where}: the policy observes {meta.get('obs_fields')}, this package's env "
            f"observes {expected['obs_fields']}: retrain it (psm-grasp train-policy)")
    try:
        bounds_of_meta(meta.get("bounds", {}))
    except (KeyError, TypeError, ValueError) as exc:
        raise PolicyMismatchError(f"{where}: the policy's design box {meta.get('bounds')} does "
                                  f"not fit this package ({exc})") from None
    for key in ("low", "high"):
        got = np.asarray(meta.get("bounds", {}).get(key, []), dtype=float)
        want = np.asarray(expected["bounds"][key])
        if got.shape != want.shape or not np.allclose(got, want, rtol=1e-12, atol=0):
            raise PolicyMismatchError(
                f"{where}: the policy designs in the box {meta.get('bounds')}, this package's "
                f"default box is {expected['bounds']}: retrain it (psm-grasp train-policy)")
    try:
        resolve_model(**meta["model"])
        RewardWeights(**meta["reward_weights"])
        ObjectDistribution(**{k: tuple(v) if isinstance(v, list) else v
                              for k, v in meta["distribution"].items()})
    except (KeyError, TypeError, ValueError) as exc:
        raise PolicyMismatchError(f"{where}: the policy's settings do not fit this package "
                                  f"({exc})") from None
    mine, theirs = _package_version(), str(meta.get("package_version", ""))
    # (a source tree that is not installed has no version to compare)
    if "unknown" not in mine and theirs.split(".")[:2] != mine.split(".")[:2]:
        raise PolicyMismatchError(f"{where}: the policy was trained with psm-grasp {theirs}, "
                                  f"this is {mine}: retrain it (psm-grasp train-policy)")


def load_policy(path: str | Path | None = None, jaw: str = "straight") -> DesignPolicy:
    """Load a saved policy: ``path`` a folder written by :meth:`DesignPolicy.save` (or
    ``psm-grasp train-policy --out``); ``None``: the policy shipped with the package for the
    jaws ``jaw`` (``"straight"``, default; ``"any"``: the one that designs shaped jaws too).

    Raises
    ------
    ValueError
        One line naming the folder or the file: a folder without the policy's files, or a file
        that cannot be read (not JSON, not a numpy archive, a missing layer);
        :class:`PolicyMismatchError` (a ``ValueError``) for a policy that does not fit this
        package (observation, action box, model member, reward weights, version).
    """
    if path is None and jaw not in SHIPPED_JAWS:
        raise ValueError(f"jaw: a policy is shipped for jaws {sorted(SHIPPED_JAWS)}, not "
                         f"{jaw!r}")
    folder = SHIPPED_JAWS[jaw] if path is None else Path(path)
    where = (("the shipped policy" + ("" if jaw == "straight" else f" for {jaw} jaws"))
             if path is None else f"policy folder {str(folder)!r}")
    missing = [name for name in POLICY_FILES if not (folder / name).is_file()]
    if missing:
        raise ValueError(f"{where}: no {missing[0]} in it (a folder written by psm-grasp "
                         "train-policy --out)")
    meta = _read_meta(folder / "policy.json")
    _check_meta(meta, where)
    layers = _read_layers(folder / "policy.npz", meta["n_layers"])
    _check_layers(layers, bounds_of_meta(meta["bounds"]).n_var, folder / "policy.npz")
    return DesignPolicy(layers, meta.pop("activation"), meta.pop("squash"), meta)


def _check_layers(layers: list[tuple[np.ndarray, np.ndarray]], n_out: int, path: Path) -> None:
    """The layers of a policy chain from the observation to the action: ``w{k}`` (out, in)
    with ``in`` the previous layer's ``out`` (the first: the observation's fields), ``b{k}``
    (out,), the last ``out`` the action's width, every number finite; ``ValueError`` naming
    the file and the array otherwise."""
    width = len(OBS_FIELDS)
    for k, (w, b) in enumerate(layers):
        out = n_out if k == len(layers) - 1 else (w.shape[0] if w.ndim == 2 else -1)
        if w.shape != (out, width) or b.shape != (out,):
            raise ValueError(f"{str(path)!r}: not a policy this package can run (w{k} has "
                             f"shape {w.shape} and b{k} {b.shape}, layer {k} needs "
                             f"({out}, {width}) and ({out},))")
        for name, a in ((f"w{k}", w), (f"b{k}", b)):
            if not np.isfinite(a).all():
                raise ValueError(f"{str(path)!r}: {name} holds a value that is not a finite "
                                 "number (NaN or inf): not a trained policy")
        width = out


def _read_meta(path: Path) -> dict[str, Any]:
    """A policy's ``policy.json``; ``ValueError`` naming the file otherwise."""
    check_input_file("the policy's metadata", path)
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"{str(path)!r}: cannot read it ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{str(path)!r}: not the JSON a policy is saved as ({exc})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{str(path)!r}: not a policy's metadata (a JSON "
                         f"{type(meta).__name__}, not an object)")
    for key, kind in POLICY_META_TYPES.items():
        value = meta.get(key)
        if key in meta and (not isinstance(value, kind) or isinstance(value, bool)):
            raise ValueError(f"{str(path)!r}: not a policy's metadata ({key} = {value!r} is "
                             f"not {_KIND_WORDS[kind]})")
    missing = [k for k in ("n_layers", "activation", "squash") if k not in meta]
    n = meta.get("n_layers")
    if missing or isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_LAYERS:
        raise ValueError(f"{str(path)!r}: not a policy's metadata (" + (
            f"no {missing[0]!r}" if missing else f"n_layers = {n!r}, not an integer in "
            f"[1, {MAX_LAYERS}]") + ")")
    for key, allowed in (("activation", ACTIVATIONS), ("squash", SQUASHES)):
        if meta[key] not in allowed:
            raise ValueError(f"{str(path)!r}: not a policy's metadata ({key} = {meta[key]!r} "
                             f"is not one of {allowed})")
    return meta


def _read_layers(path: Path, n_layers: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The ``n_layers`` (weights, biases) of a policy's ``policy.npz``; ``ValueError`` naming
    the file otherwise (not a numpy archive, a truncated one, a missing layer)."""
    import zipfile
    import zlib

    check_input_file("the policy's archive", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            names = [name for k in range(n_layers) for name in (f"w{k}", f"b{k}")]
            absent = [name for name in names if name not in data.files]
            if absent:
                raise ValueError(f"no array {absent[0]!r} of its {n_layers} layers")
            arrays = [data[name].astype(np.float64) for name in names]
    except (OSError, EOFError, ValueError, zipfile.BadZipFile, zlib.error) as exc:
        # np.load of a file that is no archive reads it as a pickle, which it refuses
        what = "not a numpy archive" if "pickle" in str(exc) else exc
        raise ValueError(f"{str(path)!r}: not a policy archive written by psm-grasp "
                         f"train-policy ({what})") from None
    return list(zip(arrays[::2], arrays[1::2], strict=True))


def run_policy(problem: DesignProblem, *, budget: int, seed: int = 0,
               policy: str | Path | DesignPolicy | None = None) -> OptimResult:
    """The ``"policy"`` method of :func:`optim.optimize`: the (shipped) policy's design for
    the problem's object and ``budget - 1`` refining CMA-ES evaluations."""
    if policy is None:
        policy = _shipped_policy(problem.bounds.jaw)
    elif not isinstance(policy, DesignPolicy):
        policy = load_policy(policy)
    return policy.run(problem, budget=budget, seed=seed)


def policy_starts(problem: DesignProblem) -> np.ndarray:
    """The shipped policy's candidate designs for a problem (:meth:`DesignPolicy.starts`),
    normalized rows; none (shape (0, n_var)) where no shipped policy designs in the problem's
    box or observes its object: a search's optional starts (:mod:`optim.portfolio`)."""
    none = np.zeros((0, problem.n_var))
    jaw = problem.bounds.jaw
    if jaw not in SHIPPED_JAWS or problem.bounds.jaw_per_finger:
        return none
    try:
        policy = _shipped_policy(jaw)
        if problem.bounds != policy.bounds:
            return none
        return policy.starts(problem)
    except (ValueError, OSError):  # an object it cannot observe, a policy that does not fit
        return none


@functools.cache
def _shipped_policy(jaw: str = "straight") -> DesignPolicy:
    """The shipped policy for the jaws ``jaw``, read once per process (an optimizer
    comparison asks it often)."""
    return load_policy(jaw=jaw)


# --- training ---------------------------------------------------------------------------------


def _import_sb3():
    try:
        import stable_baselines3
        import torch  # noqa: F401
    except ImportError as exc:
        raise ImportError(RL_HINT) from exc
    return stable_baselines3


def _extract_actor(model: Any, method: str) -> tuple[list, str, str]:
    """The deterministic actor of an SB3 model as numpy layers."""
    import torch.nn as nn

    if method == "sac":
        modules = [*model.actor.latent_pi, model.actor.mu]
        squash = "tanh"
    else:
        modules = [*model.policy.mlp_extractor.policy_net, model.policy.action_net]
        squash = "clip"
    layers, activation = [], "relu"
    for m in modules:
        if isinstance(m, nn.Linear):
            layers.append((m.weight.detach().cpu().numpy().astype(np.float64),
                           m.bias.detach().cpu().numpy().astype(np.float64)))
        elif isinstance(m, nn.Tanh):
            activation = "tanh"
    return layers, activation, squash


def _make_agent(settings: TrainingSettings, env: Any):
    sb3 = _import_sb3()
    net = list(settings.net_arch)
    if settings.method == "sac":
        model = sb3.SAC(
            "MlpPolicy", env, seed=settings.seed, device="cpu", verbose=0, gamma=0.0,
            learning_rate=settings.learning_rate, batch_size=settings.batch_size,
            # random designs first: 32 steps of every env (a quarter of a short run)
            buffer_size=max(settings.steps, 10_000), learning_starts=min(
                32 * settings.n_envs, settings.steps // 4),
            train_freq=1, gradient_steps=settings.gradient_steps,
            policy_kwargs={"net_arch": net})
        # the squashed Gaussian's log std is a linear output: start its bias low, so the
        # first designs scatter around the box's centre instead of piling on its faces
        import torch

        with torch.no_grad():
            model.actor.log_std.bias.fill_(settings.initial_log_std)
        return model
    n_steps = max(2, 2048 // settings.n_envs)
    return sb3.PPO(
        "MlpPolicy", env, seed=settings.seed, device="cpu", verbose=0, gamma=0.0,
        gae_lambda=0.0, n_steps=n_steps, batch_size=min(settings.batch_size,
                                                        n_steps * settings.n_envs),
        n_epochs=10, learning_rate=settings.learning_rate, ent_coef=0.0,
        policy_kwargs={"net_arch": net, "log_std_init": settings.initial_log_std})


def _training_env(settings: TrainingSettings, distribution: ObjectDistribution,
                  weights: RewardWeights, model: dict[str, Any], bounds: DesignBounds):
    from stable_baselines3.common.vec_env import VecEnvWrapper, VecMonitor

    from envs.sb3_env import sb3_vec_env

    class _BoundedTail(VecEnvWrapper):
        """The training reward: the env's with its tail bounded (:func:`bounded_tail`); the
        env's own reward stays in each info."""

        def reset(self):
            return self.venv.reset()

        def step_wait(self):
            obs, rewards, dones, infos = self.venv.step_wait()
            limits = np.array([info["strain_limit"] for info in infos])
            shaped = bounded_tail(rewards, limits, settings.tail_scale)
            return obs, shaped.astype(np.float32), dones, infos

    env = VecMonitor(sb3_vec_env(settings.n_envs, seed=settings.seed, distribution=distribution,
                                 weights=weights, bounds=bounds, **model))
    return _BoundedTail(env) if settings.tail_scale > 0 else env


def _callback(total: int, progress: bool, curve: list, evaluate: Callable[[], float] | None,
              every: int):
    from stable_baselines3.common.callbacks import BaseCallback
    from tqdm.auto import tqdm

    class _Progress(BaseCallback):
        """A progress bar and the learning curve: the mean env reward of recent steps and,
        every ``every`` steps, the deterministic policy's reward on held-out objects."""

        def _on_training_start(self) -> None:
            self.bar = tqdm(total=total, desc="train-policy", unit="step",
                            disable=not progress, leave=False)
            self.since = 0
            self.recent: list[float] = []

        def _on_step(self) -> bool:
            n = self.training_env.num_envs
            self.bar.update(n)
            self.since += n
            infos = self.locals.get("infos") or []
            self.recent.extend(float(i["reward"]) for i in infos if "reward" in i)
            if self.since >= every or self.num_timesteps >= total:
                point = {"steps": int(self.num_timesteps),
                         "mean_reward": float(np.mean(self.recent)) if self.recent else None,
                         "time_s": time.perf_counter() - self.t0}
                if evaluate is not None:
                    point["heldout_reward"] = evaluate()
                curve.append(point)
                self.bar.set_postfix(reward=f"{point['mean_reward']:.3f}", refresh=False)
                self.since, self.recent = 0, []
            return True

        def _on_training_end(self) -> None:
            self.bar.close()

    cb = _Progress()
    cb.t0 = time.perf_counter()
    return cb


def train_policy(method: str = "sac", *, steps: int = 200_000, seed: int = 0,
                 distribution: ObjectDistribution | None = None,
                 weights: RewardWeights | None = None, n_triangles: int | None = None,
                 n_rings: int | None = None, element: str | None = None,
                 progress: bool = True, heldout: list[tuple] | None = None,
                 curve_points: int = 20, torch_threads: int | None = 1, name: str = "policy",
                 jaw: str = "straight", jaw_per_finger: bool = False,
                 **settings: Any) -> DesignPolicy:
    """Train a design policy over an object distribution (stable-baselines3).

    Parameters
    ----------
    method
        ``"sac"`` (default) or ``"ppo"``.
    steps
        Designs evaluated during training (environment steps), >= the number of envs.
    seed
        Seed of the agent and the environments.
    distribution
        The objects trained on (default :class:`~envs.design_env.ObjectDistribution`: radius
        1 mm - 0.2 m, modulus 10 kPa - 10 MPa, Poisson 0.25-0.49, strain limit 0.03-0.17,
        friction 0.2-1.0).
    weights
        Reward weights (default :class:`~envs.evaluate.RewardWeights`).
    n_triangles, n_rings, element
        The model member that scores the designs (default: the default model).
    progress
        Show a progress bar.
    heldout
        Objects (:func:`heldout_objects` tuples: disk, strain limit, friction, payload factor,
        tolerance over the radius) on which the deterministic policy is scored at every point
        of the learning curve (its mean env reward, the worst placement's), or ``None``.
    curve_points
        Points of the learning curve.
    torch_threads
        torch's intra-op threads during training (the small networks run fastest on one,
        leaving the other core to the solver); None leaves torch's setting.
    name
        The policy's name in its metadata.
    jaw, jaw_per_finger
        The jaws it designs: ``"straight"`` (default: GripperDesign-v2's six actions) or a kind
        of shaped jaws (GripperJawDesign-v0's action with the jaw columns of
        :func:`envs.design_env.jaw_bounds`; ``"any"``: cradles, V-grooves and the rounded
        grooves between them).
    **settings
        Fields of :class:`TrainingSettings` (``n_envs``, ``net_arch``, ``tail_scale``, ...).

    Returns
    -------
    DesignPolicy
        Its ``meta["training"]`` holds the settings, the wall time and the learning curve.
    """
    _import_sb3()
    import torch

    cfg = TrainingSettings(method=method, steps=steps, seed=seed, **settings)
    distribution = ObjectDistribution() if distribution is None else distribution
    weights = RewardWeights() if weights is None else weights
    if not isinstance(distribution, ObjectDistribution):
        raise ValueError(f"distribution must be an ObjectDistribution, got "
                         f"{type(distribution).__name__}")
    if not isinstance(weights, RewardWeights):
        raise ValueError(f"weights must be a RewardWeights, got {type(weights).__name__}")
    member = resolve_model(n_triangles, n_rings, element or "nhquad").kwargs()
    bounds = jaw_bounds(jaw, jaw_per_finger) if jaw != "straight" else DesignBounds()
    env = _training_env(cfg, distribution, weights, member, bounds)
    curve: list[dict[str, Any]] = []
    threads = torch.get_num_threads()
    if torch_threads is not None:
        torch.set_num_threads(int(torch_threads))
    t0 = time.perf_counter()
    try:
        agent = _make_agent(cfg, env)
        shell = _policy_shell(cfg, distribution, weights, member, name, bounds)

        def evaluate() -> float:
            layers, activation, squash = _extract_actor(agent, cfg.method)
            return _heldout_reward(DesignPolicy(layers, activation, squash, shell), heldout)

        every = max(cfg.n_envs, cfg.steps // max(1, int(curve_points)))
        agent.learn(total_timesteps=cfg.steps, callback=_callback(
            cfg.steps, progress, curve, evaluate if heldout else None, every))
    finally:
        torch.set_num_threads(threads)
        env.close()
    layers, activation, squash = _extract_actor(agent, cfg.method)
    meta = {**shell, "training": {**asdict(cfg), "wall_time_s": time.perf_counter() - t0,
                                  "curve": curve}}
    policy = DesignPolicy(layers, activation, squash, meta)
    policy.agent = agent  # the SB3 model, for saving or more training (not part of save())
    return policy


def _policy_shell(cfg: TrainingSettings, distribution: ObjectDistribution,
                  weights: RewardWeights, member: dict[str, Any], name: str,
                  bounds: DesignBounds | None = None) -> dict[str, Any]:
    """The metadata of a policy trained with these settings."""
    return {
        **_expected_meta(bounds), "name": name, "package_version": _package_version(),
        "reward_weights": {f.name: getattr(weights, f.name) for f in fields(weights)},
        "model": member, "joint_spring": {"torsion_stiffness_rel": None},
        "distribution": {f.name: getattr(distribution, f.name) for f in fields(distribution)},
        "method": cfg.method,
    }


def _heldout_reward(policy: DesignPolicy, objects: list[tuple]) -> float:
    """Mean reward of the policy's designs on objects (:func:`heldout_objects` tuples), the
    env's robust reward over each object's placements (one batched evaluation)."""
    return float(np.mean(heldout_rewards(policy, objects)))


def heldout_rewards(policy: DesignPolicy, objects: list[tuple]) -> np.ndarray:
    """The env's reward of the policy's designs on objects (:func:`heldout_objects` tuples:
    disk, strain limit, friction, payload factor, tolerance over the radius), (B,)."""
    disks = [o[0] for o in objects]
    needs = np.array([o[1:] for o in objects], dtype=float)
    designs = policy.bounds.scale(policy.actions(observe_rows(disks, needs)), disks)
    out = evaluate_objects(designs, disks, needs,
                           weights=RewardWeights(**policy.meta["reward_weights"]),
                           **policy.meta["joint_spring"], **policy.meta["model"])
    return out["reward"]


def write_training_outputs(policy: DesignPolicy, out: str | Path) -> dict[str, Path]:
    """Write a trained policy to ``out``: ``policy.json`` and ``policy.npz`` (what
    :func:`load_policy` reads), ``sb3_model.zip`` (the whole agent, for more training),
    ``learning_curve.json`` and ``learning_curve.png``."""
    folder = policy.save(out)
    paths = {"policy": folder / "policy.json", "weights": folder / "policy.npz"}
    agent = getattr(policy, "agent", None)
    if agent is not None:
        paths["sb3_model"] = folder / "sb3_model.zip"
        agent.save(paths["sb3_model"])
    curve = policy.meta["training"]["curve"]
    paths["curve_json"] = folder / "learning_curve.json"
    paths["curve_json"].write_text(json.dumps(curve, indent=1) + "\n")
    paths["curve_png"] = folder / "learning_curve.png"
    learning_curve_figure({policy.meta.get("name", "policy"): curve}, paths["curve_png"])
    return paths


def learning_curve_figure(curves: dict[str, list[dict[str, Any]]], path: str | Path,
                          title: str = "training") -> Path:
    """Mean training reward (and held-out reward, where recorded) against steps, one line per
    curve."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.0), dpi=110)
    ax = fig.add_subplot()
    for k, (label, curve) in enumerate(curves.items()):
        steps = [p["steps"] for p in curve]
        ax.plot(steps, [p["mean_reward"] for p in curve], color=f"C{k}", lw=0.8, alpha=0.6,
                label=f"{label}: training designs (env reward)")
        if curve and "heldout_reward" in curve[0]:
            ax.plot(steps, [p["heldout_reward"] for p in curve], color=f"C{k}", lw=1.8,
                    label=f"{label}: policy on held-out objects")
    ax.set_xlabel("designs evaluated in training")
    ax.set_ylabel("mean reward")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return Path(path)


def heldout_objects(n: int, seed: int, distribution: ObjectDistribution | None = None
                    ) -> list[tuple[SoftDisk, float, float, float, float]]:
    """``n`` objects drawn from the distribution with their own seed (never a training
    seed's stream: training envs draw from ``seed + i`` of the training seed): tuples of
    :meth:`~envs.design_env.ObjectDistribution.sample` (disk, strain limit, friction, payload
    factor, placement tolerance over the radius)."""
    rng = np.random.default_rng([int(seed), 9173])
    dist = ObjectDistribution() if distribution is None else distribution
    return [dist.sample(rng) for _ in range(int(n))]
