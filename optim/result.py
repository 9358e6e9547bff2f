"""The one result type of every optimizer driver, with a JSON round trip."""

from __future__ import annotations

import json
import math
from dataclasses import MISSING, asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from envs.validation import PsmGraspWarning, check_integer, check_real, read_text_file

__all__ = ["NoGraspWarning", "OptimResult", "grasp_found", "no_grasp_reason", "to_jsonable",
           "check_result_data", "front_point"]

RESULT_VERSION = 1


def to_jsonable(value: Any) -> Any:
    """Convert numpy scalars/arrays, tuples and nested containers to plain JSON types."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()  # then as a Python number (an infinite one is written as text)
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def front_point(point: dict[str, Any]) -> tuple[float, float]:
    """A Pareto front entry's contact score and peak compression: with scenarios their
    envelopes (``min_contact_score``, ``max_peak_compression``)."""
    return (float(point.get("min_contact_score", point.get("contact_score", math.nan))),
            float(point.get("max_peak_compression", point.get("peak_compression", math.nan))))


class NoGraspWarning(PsmGraspWarning):
    """An optimization's best design does not grasp its object (invalid, not converged, or a
    finger that does not touch): the run's answer is not a gripper to build."""


def grasp_found(metrics: dict[str, Any]) -> bool:
    """Whether a design's metrics (:attr:`OptimResult.best_metrics`) are a grasp that lifts
    its object: valid at rest, converged, both fingers touching and, where the metrics say
    it, the required friction (its payload included) within the object's coefficient
    (``holds``) and the peak compression within the strain limit."""
    touching = metrics.get("touching") or [False, False]
    within = metrics.get("peak_compression", 0.0) <= metrics.get("strain_limit", math.inf)
    return bool(metrics.get("valid_at_rest") and metrics.get("converged") and all(touching)
                and metrics.get("holds", True) and within
                # with scenarios: in every one (the governing row says so too)
                and metrics.get("holds_all", True))


def no_grasp_reason(metrics: dict[str, Any]) -> str:
    """Why a design's metrics are not a grasp, in words."""
    if not metrics:
        return "was never evaluated"
    if not metrics.get("valid_at_rest"):
        return "is invalid at rest (the fingers overlap the disk, ...)"
    if not metrics.get("converged"):
        return "did not converge"
    touching = metrics.get("touching") or [False, False]
    if not all(touching):
        return "does not touch the disk with both fingers"
    need, mu = metrics.get("required_friction"), metrics.get("friction_coefficient")
    if metrics.get("holds", True):
        return (f"squeezes the object beyond its strain limit (limited by the strain limit: "
                f"peak compression {metrics.get('peak_compression', math.nan):.3g} > "
                f"{metrics.get('strain_limit', math.nan):.3g})")
    payload, grip = metrics.get("payload_n", 0.0), metrics.get("grip_force_n", math.nan)
    if payload and mu is not None and not mu * grip >= payload:
        return (f"cannot lift the object (limited by the payload: its grip of {grip:.3g} N "
                f"carries at most {mu * grip:.3g} N by friction {mu:g}, less than the payload "
                f"of {payload:.3g} N)")
    what = {2: f"to carry its payload of {payload:.3g} N out of the plane",
            3: f"to carry its payload of {payload:.3g} N in the plane"}.get(
                metrics.get("friction_limit", 0), "to hold it without the fixed centre")
    return (f"would let the object slip out (limited by friction: it needs a coefficient of "
            f"{_number(need)} {what}, more than the object's {mu})")


def _number(value: Any) -> str:
    """A friction coefficient in words (infinite: none can)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    return f"{v:.3g}" if math.isfinite(v) else "inf (no friction can)"


@dataclass(frozen=True)
class OptimResult:
    """Outcome of one optimizer run on one object.

    The history has one point per evaluated batch (a CMA-ES generation, a GA generation, a random
    batch, an RL policy probe): the best reward seen so far after that many evaluations and that
    much wall time.

    Parameters
    ----------
    method
        Name of the optimizer (``"cmaes"``, ``"ga"``, ``"nsga2"``, ``"random"``,
        ``"policy"``).
    seed
        Seed of the run (>= 0).
    budget
        Evaluation budget of the run (>= 1).
    best_design
        Best design found, in physical units: ``{"finger_length_m": ..., "rest_angle_rad": ...,
        "joint_offset_m": ..., "finger_width_m": ..., "torque_nm": ..., "distance_m": ...}``.
    best_reward
        Reward of ``best_design`` [-].
    best_metrics
        Metrics of ``best_design`` from :func:`envs.evaluate.evaluate_designs` (``contact_score``,
        ``peak_strain``, ``n_contacts``, ``total_force_n``, ``converged``, reward terms, ...).
    history_evaluations
        Evaluations done after each batch (increasing).
    history_best_reward
        Best reward so far after each batch (non-decreasing).
    history_wall_time_s
        Wall time since the start of the run after each batch [s].
    n_evaluations
        Evaluations done in total (<= ``budget``).
    wall_time_s
        Wall time of the whole run [s].
    object
        The fixed object: disk fields in SI units, ``strain_limit`` and the scene name if any.
    pareto_front
        NSGA-II only: the non-dominated feasible designs (contact score up, peak compression down),
        each ``{"design": {...}, "contact_score": ..., "peak_compression": ..., "reward": ...}``,
        sorted by contact score.
    options
        The method's options as used (population size, sigma0, ...).
    top_designs
        The best distinct designs evaluated (up to 10, best first), each ``{"design": {...},
        "reward": ...}``: what ``psm-grasp verify`` re-scores with the FEM.
    executor
        How the populations were evaluated (``"in-process"``, ``"processes(2)"``,
        ``"dask(tcp://...)"``).
    extra
        Method-specific extras (e.g. the number of CMA-ES restarts), and from every driver
        ``grasp_found``: whether the best design is a grasp (:func:`grasp_found`; when it is
        not, the run also warns with :class:`NoGraspWarning`).
    """

    method: str
    seed: int
    budget: int
    best_design: dict[str, float]
    best_reward: float
    best_metrics: dict[str, Any]
    history_evaluations: tuple[int, ...]
    history_best_reward: tuple[float, ...]
    history_wall_time_s: tuple[float, ...]
    n_evaluations: int
    wall_time_s: float
    object: dict[str, Any] = field(default_factory=dict)
    pareto_front: tuple[dict[str, Any], ...] = ()
    options: dict[str, Any] = field(default_factory=dict)
    top_designs: tuple[dict[str, Any], ...] = ()
    executor: str = "in-process"
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, kind in (("seed", int), ("budget", int), ("n_evaluations", int),
                           ("best_reward", float), ("wall_time_s", float)):
            object.__setattr__(self, name, kind(getattr(self, name)))
        object.__setattr__(self, "history_evaluations",
                           tuple(int(v) for v in self.history_evaluations))
        object.__setattr__(self, "history_best_reward",
                           tuple(float(v) for v in self.history_best_reward))
        object.__setattr__(self, "history_wall_time_s",
                           tuple(float(v) for v in self.history_wall_time_s))
        object.__setattr__(self, "pareto_front", tuple(self.pareto_front))
        object.__setattr__(self, "top_designs", tuple(self.top_designs))
        n = len(self.history_evaluations)
        if len(self.history_best_reward) != n or len(self.history_wall_time_s) != n:
            raise ValueError(
                "history_evaluations, history_best_reward and history_wall_time_s must have the "
                f"same length, got {n}, {len(self.history_best_reward)}, "
                f"{len(self.history_wall_time_s)}"
            )
        if self.n_evaluations > self.budget:
            raise ValueError(
                f"n_evaluations = {self.n_evaluations} exceeds the budget {self.budget}"
            )

    # --- serialization -----------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Plain-JSON dictionary of every field (plus a format version)."""
        data = to_jsonable(asdict(self))
        data["version"] = RESULT_VERSION
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> OptimResult:
        """Inverse of :meth:`to_dict`: every field checked before use (:func:`check_result_data`;
        an unknown key, a missing field or a bad value raises one ``ValueError`` naming it)."""
        data = dict(data)
        data.pop("version", None)
        names = {f.name for f in fields(cls)}
        unknown = set(data) - names
        if unknown:
            raise ValueError(f"unknown OptimResult fields {sorted(unknown)}")
        check_result_data(data)
        data["pareto_front"] = tuple(data.get("pareto_front", ()))
        data["top_designs"] = tuple(data.get("top_designs", ()))
        return cls(**data)

    def to_json(self, path: str | Path) -> Path:
        """Write the result as JSON (parent folders are created); return the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path

    @classmethod
    def from_json(cls, path: str | Path) -> OptimResult:
        """Read a result written by :meth:`to_json`.

        Raises
        ------
        ValueError
            One line naming the file and what is wrong with it: unreadable, not JSON (with the
            line and column), or not a result (a missing or unknown field, a bad value).
        """
        path = Path(path)
        text = read_text_file(path, "result", "JSON")
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{str(path)!r}: not valid JSON: {exc}") from None
        if not isinstance(data, dict):
            raise ValueError(f"{str(path)!r}: not a result written by psm-grasp optimize (a "
                             f"JSON {type(data).__name__}, not an object)")
        try:
            return cls.from_dict(data)
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{str(path)!r}: not a result written by psm-grasp optimize "
                             f"({exc})") from None

    # --- convenience -------------------------------------------------------------------------

    @property
    def evaluations_per_s(self) -> float:
        """Evaluation throughput of the run [1/s]."""
        return self.n_evaluations / self.wall_time_s if self.wall_time_s > 0 else math.inf

    def summary(self) -> str:
        """One line: method, seed, best reward and the reward's terms that give it, the
        contact score and peak compression of the grasp they come from (with scenarios the
        governing scenario's, named), evaluations, time."""
        from .design_verdict import reward_terms

        m = self.best_metrics
        terms = " ".join(f"{name} {value:+.4f}" for name, value in reward_terms(m))
        governing = m.get("governing_scenario")
        robust = self.object.get("robust", "worst")
        head = f"{self.method:>7s} seed {self.seed}: best reward {self.best_reward:.4f}"
        grasp = (f"contact {m.get('contact_score', float('nan')):.4f}, peak compression "
                 f"{m.get('peak_compression', float('nan')):.4f}")
        if governing is None:
            body = f" = {terms} ({grasp})"
        elif robust == "worst":
            body = (f" = {terms} (governing scenario {governing!r} of "
                    f"{m.get('n_scenarios')}: {grasp})")
        else:
            body = (f" ({robust} over {m.get('n_scenarios')} scenarios; the governing scenario "
                    f"{governing!r} scores {m.get('reward', float('nan')):.4f} = {terms}: "
                    f"{grasp})")
        return f"{head}{body} after {self.n_evaluations} evaluations in {self.wall_time_s:.1f} s"


# --- a result read back: every field checked before use ---------------------------------------


def _json_real(name: str, value: Any, low: float = -math.inf, high: float = math.inf) -> float:
    """A real field of a result JSON: a number, or the text ``"inf"`` / ``"-inf"`` that
    :func:`to_jsonable` writes for an infinite one, in ``[low, high]``."""
    if isinstance(value, str) and value in ("inf", "-inf"):
        value = float(value)
    v = check_real(name, value)
    if not low <= v <= high:  # (NaN is outside too)
        raise ValueError(f"{name} = {value!r} is outside the allowed range [{low:g}, {high:g}]")
    return v


def _json_list(name: str, value: Any) -> list:
    if not isinstance(value, list | tuple):
        raise ValueError(f"{name} must be a list, got {value!r}")
    return list(value)


def _json_dict(name: str, value: Any) -> dict:
    if not isinstance(value, dict):
        raise ValueError(f"{name} must be an object ({{...}}), got {value!r}")
    return value


def _check_object(obj: dict[str, Any]) -> None:
    """A result's ``object``: each number by the object file's rule for its key (range and
    plausible range), the model member, the text fields."""
    from envs.object_file import GRIPPER_KEYS, OBJECT_KEYS, check_value

    rules = {**OBJECT_KEYS, "torsion_stiffness_nm_per_rad":
             GRIPPER_KEYS["torsion_stiffness_nm_per_rad"]}
    for key, value in obj.items():
        if key in rules and value is not None:
            check_value(f"object.{key}", value, rules[key])
    for key in ("name", "scene", "file", "element", "robust"):
        if obj.get(key) is not None and not isinstance(obj[key], str):
            raise ValueError(f"object.{key} must be a string, got {obj[key]!r}")
    if any(k in obj for k in ("n_triangles", "n_rings", "element")):
        from envs.model.family import resolve_model

        try:
            resolve_model(obj.get("n_triangles"), obj.get("n_rings"), obj.get("element"),
                          obj.get("calibrated"))
        except ValueError as exc:
            raise ValueError(f"object: {exc}") from None


def _check_design(name: str, design: Any, obj: dict[str, Any]) -> None:
    """A recorded design: its fields (:func:`envs.scene.design_row`), each a finite number,
    the gripper's by the rules of a ``[gripper]`` table (range and plausible range) and the
    torque plausible on the object (:func:`envs.scene.check_torque`)."""
    from envs.model.defaults import PAPER_TORSION_STIFFNESS_REL
    from envs.object_file import GRIPPER_KEYS, check_value
    from envs.scene import DESIGN_FIELDS, check_torque, design_fields, design_row

    absent = [k for k in DESIGN_FIELDS if isinstance(design, dict) and k not in design]
    if absent:
        raise ValueError(f"{name} has no {absent[0]!r}")
    try:
        row = design_row(design)
        for key, v in zip(design_fields(row.size), row.tolist(), strict=True):
            if key in GRIPPER_KEYS:  # a gripper's field: as in a [gripper] table
                check_value(key, design[key], GRIPPER_KEYS[key])
            elif not math.isfinite(v):
                raise ValueError(f"{key} = {design[key]!r} is not a finite number")
        unit = _torque_unit_nm(obj)
        if unit is not None:
            rel = obj.get("torsion_stiffness_rel") or PAPER_TORSION_STIFFNESS_REL
            kf = obj.get("torsion_stiffness_nm_per_rad") or rel * unit
            check_torque("torque_nm", design["torque_nm"], unit, kf)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from None


def _torque_unit_nm(obj: dict[str, Any]) -> float | None:
    """The torque unit ``s E t r^2`` [N·m] of a result's (checked) object, ``None`` when it
    lacks a field of it."""
    keys = ("stiffness_scale", "youngs_modulus_pa", "thickness_m", "radius_m")
    if not all(isinstance(obj.get(k), int | float) for k in keys):
        return None
    s, e, t, r = (float(obj[k]) for k in keys)
    return s * e * t * r * r


def _check_extra(extra: dict[str, Any]) -> None:
    from envs.design_space import JAW_KINDS
    from envs.validation import check_choice

    if "jaw" in extra:
        check_choice("extra.jaw", extra["jaw"], JAW_KINDS)
    for key in ("jaw_per_finger", "grasp_found", "joints_apart", "out_of_time"):
        if key in extra and not isinstance(extra[key], bool):
            raise ValueError(f"extra.{key} must be true or false, got {extra[key]!r}")
    if extra.get("time_limit_s") is not None:
        _json_real("extra.time_limit_s", extra["time_limit_s"], 0.0)


def check_result_data(data: dict[str, Any]) -> None:
    """Validate the fields of a result read back (a JSON written by :meth:`OptimResult.to_json`,
    perhaps edited by hand or cut short) before any of them is used: each is of its type and
    in its range, the object's numbers by the object file's rules (a radius of 12 m is
    refused as in an object file), each kept design's fields finite and plausible.

    Raises
    ------
    ValueError
        One line naming the field (``best_reward``, ``object.radius_m``, ``top_designs[2]``)
        and what is wrong with it.
    """
    missing = [f.name for f in fields(OptimResult) if f.default is MISSING
               and f.default_factory is MISSING and f.name not in data]
    if missing:
        raise ValueError(f"no field {missing[0]!r}")
    if not isinstance(data["method"], str) or not data["method"].strip():
        raise ValueError(f"method must be a non-empty string, got {data['method']!r}")
    check_integer("seed", data["seed"], 0, 2**32 - 1)
    # (any budget a run may have had: optim.problem.MAX_BUDGET may change between versions)
    budget = check_integer("budget", data["budget"], 1, 2**62)
    _json_real("best_reward", data["best_reward"])
    _json_dict("best_metrics", data["best_metrics"])
    for name, low in (("history_best_reward", -math.inf), ("history_wall_time_s", 0.0)):
        for i, v in enumerate(_json_list(name, data[name])):
            _json_real(f"{name}[{i}]", v, low)
    for i, v in enumerate(_json_list("history_evaluations", data["history_evaluations"])):
        check_integer(f"history_evaluations[{i}]", v, 0, budget)
    check_integer("n_evaluations", data["n_evaluations"], 0, budget)
    _json_real("wall_time_s", data["wall_time_s"], 0.0)
    obj = _json_dict("object", data.get("object", {}))
    _check_object(obj)
    if _json_dict("best_design", data["best_design"]):
        _check_design("best_design", data["best_design"], obj)
    for name in ("top_designs", "pareto_front"):
        for i, pick in enumerate(_json_list(name, data.get(name, []))):
            pick = _json_dict(f"{name}[{i}]", pick)
            _check_design(f"{name}[{i}].design", pick.get("design"), obj)
            if "reward" in pick:
                _json_real(f"{name}[{i}].reward", pick["reward"])
    _json_dict("options", data.get("options", {}))
    if not isinstance(data.get("executor", ""), str):
        raise ValueError(f"executor must be a string, got {data['executor']!r}")
    _check_extra(_json_dict("extra", data.get("extra", {})))
