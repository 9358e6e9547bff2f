"""Scenarios: what varies between the design and the bench, and the robust reward over them.

A design is one physical gripper (absolute lengths, angle, spring and torque). A *scenario* is
one object and one placement: the object's parameters within their stated ranges (radius,
modulus, thickness, density, friction, ...) and its centre displaced from the nominal ``C = (0,
d_1 + r)`` by ``(dx, dy)`` within the placement tolerance (``dy`` along the gripper's axis,
``dx`` across it). The *nominal* scenario is the ranges' centre with no displacement; the design
space stays relative to the nominal object.

A displaced object is held where it was placed: its centre stays fixed there while the jaws
close. Across the axis this is conservative: a free object on a slippery surface would be pushed
towards the middle. A larger or smaller object keeps the placed centre, so its nearest point moves
by the change of radius.

An object that is not a disk (:mod:`envs.objects`) may also be turned: an orientation
tolerance ``+- dpsi`` (``orientation_tolerance_rad``, beside the placement tolerance) about its
centroid, which stays where it was placed, and an ellipse's semi-axes may range
(``semi_axis_a_m``, ``semi_axis_b_m``).

The scenario set is deterministic and covers the box of the ``k`` quantities that vary: its
``2^k`` corners, the ``2 k`` centres of its faces (the edge midpoints of a rectangle) and its
centre, ``2^k + 2 k + 1`` scenarios (9 for two quantities: the 3 x 3 grid). The robust reward
of a design is the worst scenario's reward by default; the mean and the CVaR (the mean of the
worst :data:`CVAR_SHARE` of the scenarios) are offered beside it.

:func:`evaluate_scenarios` solves a population of designs under every scenario as one batch of
``B x K`` grasps of :func:`envs.evaluate.evaluate_designs` and returns the answers as one table
(first axes design and scenario) with a summary row per design: the worst case of each measure.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any, NamedTuple

import numpy as np

from .evaluate import METRIC_KEYS, evaluate_designs
from .model.jaw import DESIGN_WIDTHS
from .objects import with_semi_axes
from .scene import DESIGN_FIELDS, SoftDisk
from .validation import check_range

__all__ = [
    "RANGE_FIELDS",
    "ROBUST_MEASURES",
    "CVAR_SHARE",
    "Scenario",
    "Scenarios",
    "ScenarioTable",
    "SUMMARY_KEYS",
    "evaluate_scenarios",
    "robust_reward",
    "place",
]

# object quantities that may vary (the disk's own fields, and the friction of the pads on it)
DISK_RANGE_FIELDS = ("radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
                     "density_kg_m3")
# an ellipse's (or superellipse's) semi-axes along and across its first axis [m]
OUTLINE_RANGE_FIELDS = ("semi_axis_a_m", "semi_axis_b_m")
RANGE_FIELDS = (*DISK_RANGE_FIELDS, "friction_coefficient", *OUTLINE_RANGE_FIELDS)
ROBUST_MEASURES = ("worst", "mean", "cvar")
CVAR_SHARE = 0.25  # the CVaR's tail: the mean of the worst quarter of the scenarios
# the placement as the last two coordinates of a scenario's point in the unit box
PLACEMENT_FIELDS = ("dx_m", "dy_m")
ORIENTATION_FIELD = "dpsi_rad"  # the orientation, after the placement
DISTANCE_COLUMN = DESIGN_FIELDS.index("distance_m")

# how the summary row of a design takes each key over its scenarios (others: the worst
# scenario's value, the one with the lowest reward)
_ALL_KEYS = ("valid_at_rest", "converged", "stable", "holds", "touching")
_MIN_KEYS = ("contact_score", "grip_share")
_MAX_KEYS = ("peak_strain", "peak_log_strain", "max_displacement_ratio", "peak_compression",
             "required_friction", "rest_violation", "finger_gap_m")


@dataclass(frozen=True)
class Scenario:
    """One object and one placement.

    Parameters
    ----------
    values
        The varied quantities of the object (:data:`RANGE_FIELDS`) and their values [SI].
    dx_m, dy_m
        The object's centre displaced across (x) and along (y) the gripper's axis [m].
    dpsi_rad
        An outline turned about its centroid from its nominal orientation [rad].
    label
        A short name: ``nominal``, or the varied quantities at their low (``-``), middle
        (``0``) or high (``+``) end, e.g. ``radius_m+ dx_m-``.
    """

    values: Mapping[str, float] = field(default_factory=dict)
    dx_m: float = 0.0
    dy_m: float = 0.0
    label: str = "nominal"
    dpsi_rad: float = 0.0

    def disk(self, nominal: SoftDisk) -> SoftDisk:
        """The scenario's object: the nominal disk with its varied fields (its placement is the
        design's, :meth:`Scenarios.flatten`); an outline with its semi-axes and turned by
        ``dpsi_rad``."""
        changes = {k: v for k, v in self.values.items() if k in DISK_RANGE_FIELDS}
        disk = replace(nominal, **changes) if changes else nominal
        axes = [self.values.get(k) for k in OUTLINE_RANGE_FIELDS]
        if any(v is not None for v in axes):
            disk = with_semi_axes(disk, *axes)
        if self.dpsi_rad != 0.0 and disk.outline is not None:  # (a disk turned is itself)
            disk = replace(disk, orientation_rad=disk.orientation_rad + self.dpsi_rad)
        return disk

    def friction(self, nominal: float) -> float:
        """The scenario's friction coefficient [-]."""
        return float(self.values.get("friction_coefficient", nominal))

    def as_dict(self) -> dict[str, Any]:
        """Plain data (what a result JSON records)."""
        return {"label": self.label, **{k: float(v) for k, v in self.values.items()},
                "dx_m": self.dx_m, "dy_m": self.dy_m,
                **({ORIENTATION_FIELD: self.dpsi_rad} if self.dpsi_rad != 0.0 else {})}


def _disk_fields() -> set[str]:
    return {f.name for f in fields(SoftDisk)}


def _check_range_pair(name: str, pair: Any) -> tuple[float, float]:
    if isinstance(pair, str) or not hasattr(pair, "__len__") or len(pair) != 2:
        raise ValueError(f"range of {name} must be a pair [low, high], got {pair!r}")
    ratio = name == "poisson_ratio"
    low, high = (check_range(f"ranges[{name!r}][{i}]", pair[i], -1.0 if ratio else 0.0,
                             0.5 if ratio else math.inf, low_open=True, high_open=ratio)
                 for i in (0, 1))
    if not low <= high:
        raise ValueError(f"range of {name}: low = {low!r} must not exceed high = {high!r}")
    return low, high


@dataclass(frozen=True)
class Scenarios:
    """The ranges of an object and its placement tolerance: what a design must survive.

    Parameters
    ----------
    ranges
        ``{field: (low, high)}`` for fields of :data:`RANGE_FIELDS` [SI units]: the object's
        radius, Young's modulus, Poisson ratio, thickness, density (where the disk has one) and
        the pads' friction coefficient. A range of zero width is a fixed value.
    placement_along_m
        Placement tolerance along the gripper's axis (y), ``+-`` [m], >= 0.
    placement_across_m
        Placement tolerance across the gripper's axis (x), ``+-`` [m], >= 0.
    orientation_tolerance_rad
        An outline's orientation tolerance ``+- dpsi`` about its centroid [rad], in [0, pi/2]
        (a disk's answers do not depend on it).
    """

    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    placement_along_m: float = 0.0
    placement_across_m: float = 0.0
    orientation_tolerance_rad: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.ranges, Mapping):
            raise ValueError(f"ranges must be a mapping of field -> (low, high), got "
                             f"{type(self.ranges).__name__}")
        allowed = [f for f in RANGE_FIELDS if f in _disk_fields() or f == "friction_coefficient"
                   or f in OUTLINE_RANGE_FIELDS]
        checked: dict[str, tuple[float, float]] = {}
        for name, pair in self.ranges.items():
            if name not in allowed:
                raise ValueError(f"ranges: unknown field {name!r}; allowed: {allowed}")
            checked[name] = _check_range_pair(name, pair)
        object.__setattr__(self, "ranges", checked)
        for name in ("placement_along_m", "placement_across_m"):
            object.__setattr__(self, name, check_range(name, getattr(self, name), 0.0,
                                                       math.inf))
        object.__setattr__(self, "orientation_tolerance_rad", check_range(
            "orientation_tolerance_rad", self.orientation_tolerance_rad, 0.0, math.pi / 2))

    @classmethod
    def of(cls, ranges: Mapping[str, Any] | None = None,
           placement_tolerance_m: float | tuple[float, float] | None = None,
           orientation_tolerance_deg: float | None = None) -> Scenarios:
        """From ranges, a placement tolerance given as one number (both directions) or as
        ``(along, across)`` [m], and an outline's orientation tolerance ``+-`` [deg]."""
        along = across = 0.0
        if placement_tolerance_m is not None:
            tol = placement_tolerance_m
            if isinstance(tol, int | float) and not isinstance(tol, bool):
                along = across = float(tol)
            elif hasattr(tol, "__len__") and len(tol) == 2 and not isinstance(tol, str):
                along, across = tol
            else:
                raise ValueError("placement_tolerance_m must be a number or a pair (along, "
                                 f"across) [m], got {tol!r}")
        turn = 0.0 if orientation_tolerance_deg is None else math.radians(check_range(
            "orientation_tolerance_deg", orientation_tolerance_deg, 0.0, 90.0))
        return cls(dict(ranges or {}), along, across, turn)

    @property
    def varied(self) -> tuple[str, ...]:
        """The quantities that vary (a range of positive width, a positive tolerance), in the
        order of :data:`RANGE_FIELDS` and then ``dx_m``, ``dy_m``."""
        names = [k for k in RANGE_FIELDS if k in self.ranges
                 and self.ranges[k][1] > self.ranges[k][0]]
        if self.placement_across_m > 0.0:
            names.append("dx_m")
        if self.placement_along_m > 0.0:
            names.append("dy_m")
        if self.orientation_tolerance_rad > 0.0:
            names.append(ORIENTATION_FIELD)
        return tuple(names)

    @property
    def is_trivial(self) -> bool:
        """Whether nothing varies (the one nominal scenario)."""
        return not self.varied

    def nominal_disk(self, disk: SoftDisk) -> SoftDisk:
        """The disk at the ranges' centre (fields without a range keep the disk's value)."""
        changes = {k: 0.5 * (lo + hi) for k, (lo, hi) in self.ranges.items()
                   if k in DISK_RANGE_FIELDS}
        disk = replace(disk, **changes) if changes else disk
        axes = [0.5 * sum(self.ranges[k]) if k in self.ranges else None
                for k in OUTLINE_RANGE_FIELDS]
        return with_semi_axes(disk, *axes) if any(v is not None for v in axes) else disk

    def nominal_friction(self, friction_coefficient: float) -> float:
        """The friction coefficient at its range's centre (or the one given)."""
        if "friction_coefficient" in self.ranges:
            lo, hi = self.ranges["friction_coefficient"]
            return 0.5 * (lo + hi)
        return float(friction_coefficient)

    def unit_points(self) -> np.ndarray:
        """The scenario set in the unit box ``[-1, 1]^k`` of :attr:`varied`: the centre first,
        then the ``2 k`` face centres, then the ``2^k`` corners; shape (K, k)."""
        k = len(self.varied)
        points = [np.zeros(k)]
        for axis in range(k):
            for sign in (-1.0, 1.0):
                p = np.zeros(k)
                p[axis] = sign
                points.append(p)
        if k >= 2:  # (for k = 1 the corners are the face centres)
            points.extend(np.array(c) for c in itertools.product((-1.0, 1.0), repeat=k))
        return np.array(points).reshape(len(points), k)

    def scenarios(self) -> tuple[Scenario, ...]:
        """The deterministic scenario set, the nominal first (:meth:`unit_points`)."""
        names = self.varied
        out = []
        for point in self.unit_points():
            values: dict[str, float] = {}
            dx = dy = dpsi = 0.0
            marks = []
            for name, u in zip(names, point.tolist(), strict=True):
                if name == "dx_m":
                    dx = u * self.placement_across_m
                elif name == "dy_m":
                    dy = u * self.placement_along_m
                elif name == ORIENTATION_FIELD:
                    dpsi = u * self.orientation_tolerance_rad
                else:
                    lo, hi = self.ranges[name]
                    # the ends exactly as given
                    values[name] = lo if u == -1.0 else hi if u == 1.0 else (
                        lo + 0.5 * (u + 1.0) * (hi - lo))
                if u != 0.0:
                    marks.append(f"{name}{'+' if u > 0 else '-'}")
            out.append(Scenario(values, dx, dy, " ".join(marks) or "nominal", dpsi))
        return tuple(out)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scenarios:
        """The inverse of :meth:`as_dict` (a result JSON's ``object["scenarios"]``)."""
        try:
            return cls({k: tuple(v) for k, v in data.get("ranges", {}).items()},
                       data.get("placement_along_m", 0.0), data.get("placement_across_m", 0.0),
                       data.get("orientation_tolerance_rad", 0.0))
        except (AttributeError, TypeError) as exc:
            raise ValueError(f"scenarios must be a table of ranges and tolerances: {exc}"
                             ) from None

    def as_dict(self) -> dict[str, Any]:
        """Plain data (what a result JSON records)."""
        return {"ranges": {k: list(v) for k, v in self.ranges.items()},
                "placement_along_m": self.placement_along_m,
                "placement_across_m": self.placement_across_m,
                **({"orientation_tolerance_rad": self.orientation_tolerance_rad}
                   if self.orientation_tolerance_rad > 0.0 else {})}


class ScenarioTable(NamedTuple):
    """The answers of :func:`evaluate_scenarios`.

    Attributes
    ----------
    per_scenario
        Every key of :data:`envs.evaluate.METRIC_KEYS` with first axes (B, K): design, scenario.
    summary
        One row per design (first axis B): the robust ``reward``, ``reward_worst``,
        ``reward_mean``, ``reward_cvar``, ``reward_nominal``, ``worst_scenario`` (its index) and
        every key of :data:`~envs.evaluate.METRIC_KEYS` as its worst case over the scenarios:
        ``holds``, ``converged``, ``valid_at_rest``, ``stable``, ``touching`` all of them; the
        smallest ``contact_score`` and ``grip_share``; the largest strains, peak compression,
        required friction, gaps and violation; the other keys the worst scenario's.
    scenarios
        The scenarios, in the order of the second axis.
    """

    per_scenario: dict[str, np.ndarray]
    summary: dict[str, np.ndarray]
    scenarios: tuple[Scenario, ...]


def robust_reward(rewards: np.ndarray, measure: str = "worst") -> np.ndarray:
    """The robust reward of rows of scenario rewards (B, K): the worst, the mean, or the CVaR
    (the mean of the worst ``ceil(CVAR_SHARE K)`` scenarios); shape (B,)."""
    if measure not in ROBUST_MEASURES:
        raise ValueError(f"robust must be one of {ROBUST_MEASURES}, got {measure!r}")
    r = np.asarray(rewards, dtype=np.float64)
    if measure == "worst":
        return r.min(axis=1)
    if measure == "mean":
        return r.mean(axis=1)
    tail = max(1, math.ceil(CVAR_SHARE * r.shape[1]))
    return np.sort(r, axis=1)[:, :tail].mean(axis=1)


def place(designs: np.ndarray, nominal: SoftDisk, friction: float,
          cases: list[Scenario] | tuple[Scenario, ...]):
    """Design rows, each in its own scenario: the rows with the scenario's placement, and the
    scenarios' disks, friction coefficients and lateral offsets [m] (the per-row inputs of
    :func:`~envs.evaluate.evaluate_designs`).

    The placed centre is fixed: ``d_1 + r`` of the design against the nominal disk, moved by
    ``dy``; a scenario's own radius puts its nearest point at the rest (an outline's centroid
    likewise: its lowest point at its own size and orientation, :attr:`SoftDisk.lift_m`).
    """
    rows = np.array(designs, dtype=np.float64, copy=True)
    disks = [s.disk(nominal) for s in cases]
    dy = np.array([s.dy_m for s in cases])
    radius = np.array([d.lift_m for d in disks])
    rows[:, DISTANCE_COLUMN] += nominal.lift_m + dy - radius
    frictions = np.array([s.friction(friction) for s in cases])
    offsets = np.array([s.dx_m for s in cases])
    return rows, disks, frictions, offsets


def nominal_leaders(sizes) -> np.ndarray | None:
    """Leaders (:func:`~envs.evaluate.evaluate_designs`) of a design-major batch whose design
    ``i`` has ``sizes[i]`` consecutive rows, its nominal scenario first: each design's first
    row leads its others; ``None`` where no design has more than one row."""
    sizes = np.asarray(sizes, dtype=np.int64)
    if sizes.max(initial=0) <= 1:
        return None
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    leaders = np.repeat(starts, sizes)
    leaders[starts] = -1
    return leaders


def _summary(table: dict[str, np.ndarray], robust: str) -> dict[str, np.ndarray]:
    reward = table["reward"]
    worst = np.argmin(reward, axis=1)  # first minimum: the earlier scenario on ties
    pick = np.arange(reward.shape[0])
    out: dict[str, np.ndarray] = {}
    for key, values in table.items():
        if key in _ALL_KEYS:
            out[key] = values.all(axis=1)
        elif key in _MIN_KEYS:
            out[key] = values.min(axis=1)
        elif key in _MAX_KEYS:
            out[key] = values.max(axis=1)
        else:
            out[key] = values[pick, worst]
    out["reward"] = robust_reward(reward, robust)
    for measure in ROBUST_MEASURES:
        out[f"reward_{measure}"] = robust_reward(reward, measure)
    out["reward_nominal"] = reward[:, 0].copy()
    out["worst_scenario"] = worst.astype(np.int64)
    return out


def evaluate_scenarios(designs, disk: SoftDisk, scenarios: Scenarios, *,
                       torsion_stiffness_nm_per_rad: float,
                       friction_coefficient: float,
                       robust: str = "worst",
                       warm_start: bool = True,
                       **kwargs: Any) -> ScenarioTable:
    """Solve every design under every scenario, as one batch, and summarize it per design.

    Parameters
    ----------
    designs
        Array (B, 6) of SI designs (columns :data:`~envs.scene.DESIGN_FIELDS`) placed against
        the nominal object: its ``distance_m`` is the nominal disk's ``d_1``; or (B, 10) or
        (B, 14) with the jaw columns (:data:`~envs.scene.ALL_DESIGN_FIELDS`), absolute like
        every other column: one physical gripper in every scenario.
    disk
        The nominal object (:meth:`Scenarios.nominal_disk`).
    scenarios
        The ranges and the placement tolerance.
    torsion_stiffness_nm_per_rad
        The gripper's joint spring [N·m/rad]: one physical gripper for every scenario.
    friction_coefficient
        The nominal friction coefficient [-] (a scenario's range replaces it).
    robust
        The summary's ``reward``: one of :data:`ROBUST_MEASURES`.
    warm_start
        Solve each design's other scenarios from its nominal scenario's answer on that
        answer's contact set, falling back to a solve from rest wherever the independent check
        does not confirm a stable equilibrium (the ``leaders`` of
        :func:`~envs.evaluate.evaluate_designs`); ``False``: every scenario from rest.
    **kwargs
        Passed to :func:`~envs.evaluate.evaluate_designs` (strain limits, the member, weights,
        executor, ...); not the per-row ``disks``, friction or offsets, which the scenarios set.

    Returns
    -------
    ScenarioTable
    """
    if not isinstance(scenarios, Scenarios):
        raise ValueError(f"scenarios must be a Scenarios, got {type(scenarios).__name__}")
    if robust not in ROBUST_MEASURES:
        raise ValueError(f"robust must be one of {ROBUST_MEASURES}, got {robust!r}")
    if not isinstance(warm_start, bool):
        raise ValueError(f"warm_start must be True or False, got {warm_start!r}")
    for name in ("friction_coefficients", "offsets_x_m", "torsion_stiffness_rel", "leaders"):
        if name in kwargs:
            raise ValueError(f"{name} is set by the scenarios; do not pass it")
    designs = np.asarray(designs, dtype=np.float64)
    if designs.ndim != 2 or designs.shape[1] not in DESIGN_WIDTHS:
        raise ValueError(f"designs must have shape (B, n) with n in {DESIGN_WIDTHS} (the "
                         f"columns of envs.scene.ALL_DESIGN_FIELDS), got {designs.shape}")
    cases = scenarios.scenarios()
    # design-major: row b K + k is design b in scenario k
    rows, disks, frictions, offsets = place(np.repeat(designs, len(cases), axis=0), disk,
                                            friction_coefficient, cases * designs.shape[0])
    extra = {"offsets_x_m": offsets} if np.any(offsets) else {}
    k = len(cases)
    leaders = nominal_leaders(np.full(designs.shape[0], k)) if warm_start else None
    if leaders is not None:
        extra["leaders"] = leaders
    flat = evaluate_designs(rows, disks, friction_coefficients=frictions,
                            torsion_stiffness_nm_per_rad=torsion_stiffness_nm_per_rad,
                            **extra, **kwargs)
    b = designs.shape[0]
    table = {key: v.reshape(b, k, *v.shape[1:]) for key, v in flat.items()}
    return ScenarioTable(table, _summary(table, robust), cases)


# keys a summary row carries beyond METRIC_KEYS
SUMMARY_KEYS = (*METRIC_KEYS, "reward_worst", "reward_mean", "reward_cvar", "reward_nominal",
                "worst_scenario")
