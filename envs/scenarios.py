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
The design itself may vary as built (:mod:`envs.tolerances`): its lengths, rest angle, spring
and torque within manufacturing tolerances are scenario dimensions beside the object's.

The scenario set is deterministic and covers the box of the ``k`` quantities that vary: its
centre, the ``2 k`` centres of its faces (the edge midpoints of a rectangle) and its corners.
Up to :data:`FULL_CORNER_DIMS` quantities the corners are all ``2^k`` of them (``2^k + 2 k + 1``
scenarios: 9 for two quantities, the 3 x 3 grid). Beyond, the search uses a covering set of
corners: the rows of a two-level Plackett-Burman design of ``n >= k + 1`` runs and their
mirror images (the fold-over, ``2 n`` corners: every quantity at both ends equally often, and
no quantity's effect aliased with a pair's interaction), ``2 n + 2 k + 1`` scenarios (31 for
seven quantities against 143); ``full=True`` gives every corner, which the finish and
``verify`` check the reported design on. The robust reward of a design is the worst
scenario's reward by default; the mean and the CVaR (the mean of the worst :data:`CVAR_SHARE`
of the scenarios) are offered beside it.

:func:`evaluate_scenarios` solves a population of designs under every scenario as one batch of
``B x K`` grasps of :func:`envs.evaluate.evaluate_designs` and returns the answers as one table
(first axes design and scenario) with a summary row per design: the **governing** scenario's
own row (the lowest reward, so that its terms give its reward) and, under names of their own
(:data:`ENVELOPE_KEYS`), the envelopes over the scenarios: how many hold, the largest payload,
compression and required friction, the smallest contact score and margins.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any, NamedTuple

import numpy as np

from .evaluate import METRIC_KEYS, evaluate_designs
from .model.defaults import PLAUSIBLE_RANGES
from .model.jaw import DESIGN_WIDTHS
from .objects import with_semi_axes
from .scene import DESIGN_FIELDS, SoftDisk
from .tolerances import (
    Tolerances,
    apply_tolerances,
    tolerance_changes,
    tolerance_dimensions,
)
from .validation import check_range

__all__ = [
    "RANGE_FIELDS",
    "ROBUST_MEASURES",
    "CVAR_SHARE",
    "Scenario",
    "Scenarios",
    "ScenarioTable",
    "SUMMARY_KEYS",
    "ENVELOPE_KEYS",
    "FULL_CORNER_DIMS",
    "evaluate_scenarios",
    "robust_reward",
    "place",
    "place_built",
    "covering_corners",
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

# all 2^k corners up to this many varied quantities (32 corners); a covering set beyond
FULL_CORNER_DIMS = 5
# generating rows of Plackett-Burman designs whose size is not a power of two (each run the
# cyclic shifts of the row, then a run of all -1); powers of two are Sylvester-Hadamard's
_PLACKETT_BURMAN = {12: "++-+++---+-", 20: "++--++++-+-+----++-"}
# the envelopes over a design's scenarios a summary row carries beside the governing row:
# key -> (dtype, shape after the design axis)
ENVELOPE_KEYS = {
    "n_scenarios": (np.int64, ()),  # scenarios checked
    "scenarios_holding": (np.int64, ()),  # of them, those that hold within the strain limit
    "holds_all": (np.bool_, ()),  # every scenario holds within the strain limit
    "all_converged": (np.bool_, ()),
    "all_touching": (np.bool_, (2,)),  # each finger touches in every scenario
    "max_payload_n": (np.float64, ()),  # the largest payload any scenario puts on the gripper
    "max_required_friction": (np.float64, ()),
    "max_peak_compression": (np.float64, ()),
    "min_contact_score": (np.float64, ()),
    "min_friction_margin": (np.float64, ()),  # min of (friction coefficient - required) [-]
    "min_strain_margin": (np.float64, ()),  # min of (strain limit - peak compression) [-]
}


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
    design
        The design as built (:func:`envs.tolerances.tolerance_changes`): lengths and the rest
        angle changed by [m, rad], ``torque_rel`` and ``spring_rel`` the torque's and the
        spring's relative changes [-]; empty: as designed.
    """

    values: Mapping[str, float] = field(default_factory=dict)
    dx_m: float = 0.0
    dy_m: float = 0.0
    label: str = "nominal"
    dpsi_rad: float = 0.0
    design: Mapping[str, float] = field(default_factory=dict)

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
        """Plain data (what a result JSON records): the design's changes as built under
        ``design`` when there are any."""
        return {"label": self.label, **{k: float(v) for k, v in self.values.items()},
                "dx_m": self.dx_m, "dy_m": self.dy_m,
                **({ORIENTATION_FIELD: self.dpsi_rad} if self.dpsi_rad != 0.0 else {}),
                **({"design": {k: float(v) for k, v in self.design.items()}}
                   if self.design else {})}


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
    tolerances
        The design's manufacturing tolerances (:class:`envs.tolerances.Tolerances`), each a
        scenario dimension of its own; default none.
    """

    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    placement_along_m: float = 0.0
    placement_across_m: float = 0.0
    orientation_tolerance_rad: float = 0.0
    tolerances: Tolerances = field(default_factory=Tolerances)

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
        high = PLAUSIBLE_RANGES["placement_tolerance_m"][1]
        for name in ("placement_along_m", "placement_across_m"):
            object.__setattr__(self, name, check_range(name, getattr(self, name), 0.0, high))
        object.__setattr__(self, "orientation_tolerance_rad", check_range(
            "orientation_tolerance_rad", self.orientation_tolerance_rad, 0.0, math.pi / 2))
        if self.tolerances is None:
            object.__setattr__(self, "tolerances", Tolerances())
        if not isinstance(self.tolerances, Tolerances):
            raise ValueError(f"tolerances must be an envs.tolerances.Tolerances, got "
                             f"{type(self.tolerances).__name__}")

    def check_placement(self, radius_m: float) -> None:
        """A placement tolerance larger than the object's radius ``radius_m`` [m] is refused;
        ten radii and more, with the unit it was most likely typed in (``0.5`` for 0.5 mm on
        a 12 mm object)."""
        for name, value in (("along", self.placement_along_m),
                            ("across", self.placement_across_m)):
            if value > radius_m:
                # ten radii and more: most likely millimetres typed as metres
                hint = (f": was it typed in millimetres? {value:g} mm is {value * 1e-3:g} m"
                        if value * 1e-3 <= radius_m <= 0.1 * value else "")
                raise ValueError(f"placement_tolerance_m ({name} the axis) = {value:g} m "
                                 f"exceeds the object's radius {radius_m:g} m{hint}")

    @classmethod
    def of(cls, ranges: Mapping[str, Any] | None = None,
           placement_tolerance_m: float | tuple[float, float] | None = None,
           tolerances: Tolerances | None = None,
           orientation_tolerance_deg: float | None = None) -> Scenarios:
        """From ranges, a placement tolerance given as one number (both directions) or as
        ``(along, across)`` [m], manufacturing tolerances and an outline's orientation
        tolerance ``+-`` [deg]."""
        along = across = 0.0
        if placement_tolerance_m is not None:
            tol = placement_tolerance_m
            high = PLAUSIBLE_RANGES["placement_tolerance_m"][1]
            if isinstance(tol, int | float) and not isinstance(tol, bool):
                along = across = check_range("placement_tolerance_m", tol, 0.0, high)
            elif hasattr(tol, "__len__") and len(tol) == 2 and not isinstance(tol, str):
                along, across = (check_range(f"placement_tolerance_m[{i}]", v, 0.0, high)
                                 for i, v in enumerate(tol))
            else:
                raise ValueError("placement_tolerance_m must be a number or a pair (along, "
                                 f"across) [m], got {tol!r}")
        turn = 0.0 if orientation_tolerance_deg is None else math.radians(check_range(
            "orientation_tolerance_deg", orientation_tolerance_deg, 0.0, 90.0))
        return cls(dict(ranges or {}), along, across, orientation_tolerance_rad=turn,
                   tolerances=Tolerances() if tolerances is None else tolerances)

    def with_tolerances(self, tolerances: Tolerances | None) -> Scenarios:
        """These scenarios with other manufacturing tolerances."""
        return replace(self, tolerances=Tolerances() if tolerances is None else tolerances)

    @property
    def varied(self) -> tuple[str, ...]:
        """The quantities that vary (a range of positive width, a positive tolerance), in the
        order of :data:`RANGE_FIELDS`, then ``dx_m``, ``dy_m``, then the design's own
        (:func:`envs.tolerances.tolerance_dimensions`)."""
        names = [k for k in RANGE_FIELDS if k in self.ranges
                 and self.ranges[k][1] > self.ranges[k][0]]
        if self.placement_across_m > 0.0:
            names.append("dx_m")
        if self.placement_along_m > 0.0:
            names.append("dy_m")
        if self.orientation_tolerance_rad > 0.0:
            names.append(ORIENTATION_FIELD)
        return (*names, *tolerance_dimensions(self.tolerances))

    @property
    def uses_covering_set(self) -> bool:
        """Whether :meth:`scenarios` covers the corners with a subset of them (more than
        :data:`FULL_CORNER_DIMS` quantities vary)."""
        return len(self.varied) > FULL_CORNER_DIMS

    @property
    def is_trivial(self) -> bool:
        """Whether nothing varies (the one nominal scenario)."""
        return not self.varied

    def nominal_disk(self, disk: SoftDisk) -> SoftDisk:
        """The disk at the ranges' centre (fields without a range keep the disk's value); a
        placement tolerance beyond its radius is refused (:meth:`check_placement`)."""
        changes = {k: 0.5 * (lo + hi) for k, (lo, hi) in self.ranges.items()
                   if k in DISK_RANGE_FIELDS}
        nominal = replace(disk, **changes) if changes else disk
        axes = [0.5 * sum(self.ranges[k]) if k in self.ranges else None
                for k in OUTLINE_RANGE_FIELDS]
        if any(v is not None for v in axes):
            nominal = with_semi_axes(nominal, *axes)
        self.check_placement(nominal.radius_m)
        return nominal

    def nominal_friction(self, friction_coefficient: float) -> float:
        """The friction coefficient at its range's centre (or the one given)."""
        if "friction_coefficient" in self.ranges:
            lo, hi = self.ranges["friction_coefficient"]
            return 0.5 * (lo + hi)
        return float(friction_coefficient)

    def unit_points(self, full: bool = False) -> np.ndarray:
        """The scenario set in the unit box ``[-1, 1]^k`` of :attr:`varied`: the centre first,
        then the ``2 k`` face centres, then the corners: all ``2^k`` of them up to
        :data:`FULL_CORNER_DIMS` quantities or with ``full``, else the covering set of
        :func:`covering_corners`; shape (K, k)."""
        k = len(self.varied)
        points = [np.zeros(k)]
        for axis in range(k):
            for sign in (-1.0, 1.0):
                p = np.zeros(k)
                p[axis] = sign
                points.append(p)
        if k >= 2:  # (for k = 1 the corners are the face centres)
            if full or k <= FULL_CORNER_DIMS:
                points.extend(np.array(c) for c in itertools.product((-1.0, 1.0), repeat=k))
            else:
                points.extend(covering_corners(k))
        return np.array(points).reshape(len(points), k)

    def scenarios(self, full: bool = False) -> tuple[Scenario, ...]:
        """The deterministic scenario set, the nominal first (:meth:`unit_points`; ``full``:
        every corner)."""
        names = self.varied
        out = []
        for point in self.unit_points(full):
            values: dict[str, float] = {}
            design: dict[str, float] = {}
            dx = dy = dpsi = 0.0
            marks = []
            for name, u in zip(names, point.tolist(), strict=True):
                if name == "dx_m":
                    dx = u * self.placement_across_m
                elif name == "dy_m":
                    dy = u * self.placement_along_m
                elif name == ORIENTATION_FIELD:
                    dpsi = u * self.orientation_tolerance_rad
                elif name not in self.ranges:
                    if u != 0.0:
                        design.update(tolerance_changes(self.tolerances, name, u))
                else:
                    lo, hi = self.ranges[name]
                    # the ends exactly as given
                    values[name] = lo if u == -1.0 else hi if u == 1.0 else (
                        lo + 0.5 * (u + 1.0) * (hi - lo))
                if u != 0.0:
                    marks.append(f"{name}{'+' if u > 0 else '-'}")
            out.append(Scenario(values, dx, dy, " ".join(marks) or "nominal", dpsi_rad=dpsi,
                                design=design))
        return tuple(out)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scenarios:
        """The inverse of :meth:`as_dict` (a result JSON's ``object["scenarios"]``)."""
        try:
            return cls({k: tuple(v) for k, v in data.get("ranges", {}).items()},
                       data.get("placement_along_m", 0.0), data.get("placement_across_m", 0.0),
                       orientation_tolerance_rad=data.get("orientation_tolerance_rad", 0.0),
                       tolerances=Tolerances.from_dict(data.get("tolerances")))
        except (AttributeError, TypeError) as exc:
            raise ValueError(f"scenarios must be a table of ranges and tolerances: {exc}"
                             ) from None

    def as_dict(self) -> dict[str, Any]:
        """Plain data (what a result JSON records); the manufacturing tolerances under
        ``tolerances`` when there are any."""
        return {"ranges": {k: list(v) for k, v in self.ranges.items()},
                "placement_along_m": self.placement_along_m,
                "placement_across_m": self.placement_across_m,
                **({"orientation_tolerance_rad": self.orientation_tolerance_rad}
                   if self.orientation_tolerance_rad > 0.0 else {}),
                **({} if self.tolerances.is_zero
                   else {"tolerances": self.tolerances.as_dict()})}


def _two_level_design(runs: int) -> np.ndarray:
    """A two-level orthogonal design of ``runs`` rows (a Plackett-Burman design: Sylvester's
    Hadamard matrix for a power of two, else the cyclic shifts of a generating row and a row
    of -1), without its constant column: shape (runs, runs - 1), entries +-1, columns
    mutually orthogonal."""
    if runs & (runs - 1) == 0:
        from scipy.linalg import hadamard

        return hadamard(runs).astype(np.float64)[:, 1:]
    row = np.array([1.0 if c == "+" else -1.0 for c in _PLACKETT_BURMAN[runs]])
    shifts = np.array([np.roll(row, i) for i in range(runs - 1)])
    return np.vstack([shifts, -np.ones(runs - 1)])


def covering_corners(k: int) -> np.ndarray:
    """Corners of ``[-1, 1]^k`` that cover the box for ``k > FULL_CORNER_DIMS`` quantities:
    the first ``k`` columns of a Plackett-Burman design of ``n`` runs (the smallest of 8, 12,
    16, 20, 32, ... with ``n >= k + 1``) and its fold-over (every run mirrored): ``2 n``
    distinct corners, each quantity at each end in half of them, and (a resolution IV design)
    no quantity's effect aliased with a two-quantity interaction; shape (2 n, k)."""
    if k < 1:
        raise ValueError(f"k must be at least 1, got {k}")
    n = next(m for m in (4, 8, 12, 16, 20, 32, 64, 128) if m >= k + 1) if k < 128 else None
    if n is None:
        raise ValueError(f"at most 127 varied quantities, got {k}")
    half = _two_level_design(n)[:, :k]
    both = np.vstack([half, -half])
    _, first = np.unique(both, axis=0, return_index=True)
    return both[np.sort(first)]


class ScenarioTable(NamedTuple):
    """The answers of :func:`evaluate_scenarios`.

    Attributes
    ----------
    per_scenario
        Every key of :data:`envs.evaluate.METRIC_KEYS` with first axes (B, K): design, scenario.
    summary
        One row per design (first axis B): every key of :data:`~envs.evaluate.METRIC_KEYS` as
        the governing scenario's own row (the lowest reward: ``worst_scenario``, its index),
        so that its reward terms give its reward; the robust ``reward``, ``reward_worst``,
        ``reward_mean``, ``reward_cvar``, ``reward_nominal``; and the envelopes over the
        scenarios under their own names (``governing_scenario``: its label;
        :data:`ENVELOPE_KEYS`: ``holds_all``,
        ``scenarios_holding``, ``max_payload_n``, ``max_required_friction``,
        ``max_peak_compression``, ``min_contact_score``, ...). Feasible in every scenario
        (``holds_all``) is the governing row's feasibility: every grasp that does not hold
        within the strain limit scores below every one that does.
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
    """Design rows, each in its own scenario: the rows with the scenario's placement (and the
    design as built, :func:`envs.tolerances.apply_tolerances`, but for the spring: see
    :func:`place_built`), and the scenarios' disks, friction coefficients and lateral offsets
    [m] (the per-row inputs of :func:`~envs.evaluate.evaluate_designs`).

    The placed centre is fixed: ``d_1 + r`` of the design against the nominal disk, moved by
    ``dy``; a scenario's own radius puts its nearest point at the rest (an outline's centroid
    likewise: its lowest point at its own size and orientation, :attr:`SoftDisk.lift_m`).
    """
    rows, disks, frictions, offsets, _ = place_built(designs, nominal, friction, 1.0, cases)
    return rows, disks, frictions, offsets


def place_built(designs: np.ndarray, nominal: SoftDisk, friction: float,
                torsion_stiffness_nm_per_rad: float,
                cases: list[Scenario] | tuple[Scenario, ...]):
    """:func:`place`, and each row's joint spring as built [N·m/rad]: the rows, disks,
    friction coefficients, lateral offsets and springs of the scenarios."""
    rows = np.array(designs, dtype=np.float64, copy=True)
    springs = np.full(rows.shape[0], float(torsion_stiffness_nm_per_rad))
    if any(s.design for s in cases):
        rows, springs = apply_tolerances(rows, springs, [s.design for s in cases])
    disks = [s.disk(nominal) for s in cases]
    dy = np.array([s.dy_m for s in cases])
    radius = np.array([d.lift_m for d in disks])
    rows[:, DISTANCE_COLUMN] += nominal.lift_m + dy - radius
    frictions = np.array([s.friction(friction) for s in cases])
    offsets = np.array([s.dx_m for s in cases])
    return rows, disks, frictions, offsets, springs


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


def envelopes(table: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The envelopes of :data:`ENVELOPE_KEYS` over the scenarios (axis 1) of a table."""
    within = table["holds"] & (table["peak_compression"] <= table["strain_limit"])
    k = table["reward"].shape[1]
    with np.errstate(invalid="ignore"):
        friction_margin = table["friction_coefficient"] - table["required_friction"]
    return {
        "n_scenarios": np.full(table["reward"].shape[0], k, dtype=np.int64),
        "scenarios_holding": within.sum(axis=1).astype(np.int64),
        "holds_all": within.all(axis=1),
        "all_converged": table["converged"].all(axis=1),
        "all_touching": table["touching"].all(axis=1),
        "max_payload_n": table["payload_n"].max(axis=1),
        "max_required_friction": table["required_friction"].max(axis=1),
        "max_peak_compression": table["peak_compression"].max(axis=1),
        "min_contact_score": table["contact_score"].min(axis=1),
        "min_friction_margin": friction_margin.min(axis=1),
        "min_strain_margin": (table["strain_limit"] - table["peak_compression"]).min(axis=1),
    }


def _summary(table: dict[str, np.ndarray], robust: str) -> dict[str, np.ndarray]:
    """The governing (lowest reward) scenario's own row of every key, the robust rewards and
    the envelopes (:func:`envelopes`)."""
    reward = table["reward"]
    worst = np.argmin(reward, axis=1)  # first minimum: the earlier scenario on ties
    pick = np.arange(reward.shape[0])
    out: dict[str, np.ndarray] = {key: values[pick, worst] for key, values in table.items()}
    out.update(envelopes(table))
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
                       full: bool = False,
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
    full
        Every corner of the box, also beyond :data:`FULL_CORNER_DIMS` quantities (what the
        finish and ``verify`` check the reported design on); default: the covering set.
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
    if not isinstance(full, bool):
        raise ValueError(f"full must be True or False, got {full!r}")
    for name in ("friction_coefficients", "offsets_x_m", "torsion_stiffness_rel", "leaders"):
        if name in kwargs:
            raise ValueError(f"{name} is set by the scenarios; do not pass it")
    designs = np.asarray(designs, dtype=np.float64)
    if designs.ndim != 2 or designs.shape[1] not in DESIGN_WIDTHS:
        raise ValueError(f"designs must have shape (B, n) with n in {DESIGN_WIDTHS} (the "
                         f"columns of envs.scene.ALL_DESIGN_FIELDS), got {designs.shape}")
    scenarios.check_placement(disk.radius_m)
    cases = scenarios.scenarios(full)
    # design-major: row b K + k is design b in scenario k
    rows, disks, frictions, offsets, springs = place_built(
        np.repeat(designs, len(cases), axis=0), disk, friction_coefficient,
        torsion_stiffness_nm_per_rad, cases * designs.shape[0])
    extra = {"offsets_x_m": offsets} if np.any(offsets) else {}
    k = len(cases)
    leaders = nominal_leaders(np.full(designs.shape[0], k)) if warm_start else None
    if leaders is not None:
        extra["leaders"] = leaders
    one_spring = not np.any(springs != springs[0]) if springs.size else True
    flat = evaluate_designs(rows, disks, friction_coefficients=frictions,
                            torsion_stiffness_nm_per_rad=(torsion_stiffness_nm_per_rad
                                                          if one_spring else springs),
                            **extra, **kwargs)
    b = designs.shape[0]
    table = {key: v.reshape(b, k, *v.shape[1:]) for key, v in flat.items()}
    summary = _summary(table, robust)
    summary["governing_scenario"] = np.array([cases[w].label for w in
                                              summary["worst_scenario"].tolist()], dtype=object)
    return ScenarioTable(table, summary, cases)


# keys a summary row carries beyond METRIC_KEYS
SUMMARY_KEYS = (*METRIC_KEYS, "reward_worst", "reward_mean", "reward_cvar", "reward_nominal",
                "worst_scenario", "governing_scenario", *ENVELOPE_KEYS)
