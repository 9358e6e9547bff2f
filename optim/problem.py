"""The design problem every optimizer solves: one fixed object, designs in [-1, 1]^n (n = 6,
plus the jaw columns of a design space with shaped jaws).

:class:`DesignProblem` wraps :func:`envs.evaluate.evaluate_designs` for a fixed object (a soft
disk and its strain limit). Like pymoo's ``Problem`` it evaluates a whole population per call;
unlike it, it also keeps the bookkeeping shared by every driver: the evaluation budget, the
count, the best design so far, the history (best so far vs evaluations and vs wall time) and an
archive of every evaluated point (for Pareto fronts). Parallelism is injected with ``executor``
(see :mod:`optim.executors`), never hard-coded.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from envs.evaluate import (
    MAX_CHUNK_SIZE,
    METRIC_KEYS,
    DesignBounds,
    RewardWeights,
    evaluate_designs,
)
from envs.model.defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_FRICTION_COEFFICIENT,
    DEFAULT_PAYLOAD_FACTOR,
    DEFAULT_STRAIN_LIMIT,
    MAX_FRICTION_COEFFICIENT,
    MAX_PAYLOAD_FACTOR,
)
from envs.model.family import resolve_model
from envs.model.loads import DEFAULT_LOAD_SET, load_set_code
from envs.objects import outline_info
from envs.scenarios import (
    ENVELOPE_KEYS,
    ROBUST_MEASURES,
    Scenarios,
    ScenarioTable,
    evaluate_scenarios,
)
from envs.scene import (
    PRESETS,
    Scene,
    SoftDisk,
    design_from_relative,
    design_mapping,
    design_row,
    joint_spring,
    joint_spring_kwargs,
    placement_support,
    relative_from_design,
)
from envs.validation import check_integer, check_range, real_array

from .result import NoGraspWarning, OptimResult, grasp_found, no_grasp_reason, to_jsonable

__all__ = [
    "DEFAULT_TIME_LIMIT_S",
    "DEFAULT_STRAIN_LIMIT",
    "BudgetExhaustedError",
    "DesignProblem",
    "check_budget",
    "check_seed",
    "check_time_limit",
    "default_budget",
    "pareto_mask",
    "paper_design",
    "paper_design_for",
    "top_distinct",
]

DEFAULT_CHUNK_SIZE = 256
# Rows per task at least. Measured on 2 cores (paper-r070, N = 20, ~0.25 ms a design in
# process): a round trip to a spawned worker costs about 6 ms, so 9 designs in 2 tasks ran at
# 600 designs/s against 2600 in process, and 64-row tasks reach 80-90 % of the in-process rate.
MIN_CHUNK_SIZE = 64
# the most evaluations a run may be given: about an hour of the default model in process on 2
# cores (~2,600 designs/s, MIN_CHUNK_SIZE's note); a larger budget is a typo (an extra 000)
MAX_BUDGET = 10_000_000
# the default budget of a run (default_budget): as many designs as this many grasps allow (each
# design solves one grasp per scenario), so that the default run takes about the same time
# whatever the scenario count, within these. A grooved design judged in 9 scenarios costs about
# 22 ms of CPU (the tomatoes at friction 0.5, --jaw any: 135 CPU-s for 6,000), so 3,600 of them,
# the finish and the files fit in 60 s on 2 cores; a design judged once costs more a grasp (no
# scenario neighbours to start from: the silicone puck, --jaw any, 12,000 designs took 62 s of
# search on a quiet 2-core machine), hence the ceiling
DEFAULT_GRASP_BUDGET = 32_400
DEFAULT_BUDGET_RANGE = (1_000, 8_000)
# a run given neither a budget nor a time also stops its search after this many seconds when
# its budget is not spent by then: a design near a shaped-jaw optimum (a cradle that conforms
# to the object) costs 20-45 times a random one (the silicone puck: 6-14 ms against 0.3 ms a
# straight bar, serial), and a default run that refined there took 75 s of wall on 2 cores. A
# run that spends its budget first is repeatable seed for seed; one cut short (the shaped-jaw
# runs of the tomatoes and the puck on a 2-core machine) says so (extra["out_of_time"])
DEFAULT_TIME_LIMIT_S = 45.0
MAX_TIME_LIMIT_S = 7 * 24 * 3600.0  # a week: a longer run is a typo (hours for seconds)
TOP_DESIGNS_KEPT = 10  # distinct best designs an OptimResult keeps (for FEM verification)
DISTINCT_DESIGN = 0.02  # normalized coordinates in [-1, 1]: 1 % of the design box's width
# metric keys copied into OptimResult.best_metrics
BEST_METRIC_KEYS = (
    "valid_at_rest", "converged", "stable", "n_contacts", "touching", "total_force_n",
    "jaw_angles_rad", "contact_score", "peak_strain", "peak_log_strain", "max_displacement_ratio",
    "peak_compression",
    "strain_limit", "pin_force_n", "pin_moment_nm", "required_friction", "friction_coefficient",
    "payload_n", "grip_force_n", "friction_limit", "friction_limit_angle_rad",
    "holds", "penalty_slip",
    "reward_contact", "reward_deform", "penalty_miss", "penalty_gap", "penalty_invalid",
    "penalty_fail", "reward",
)

# with scenarios, what a summary row adds to BEST_METRIC_KEYS: the governing scenario (whose
# own row the metrics are) and the envelopes over the scenarios, under their own names
SCENARIO_METRIC_KEYS = ("worst_scenario", "governing_scenario", "reward_worst", "reward_mean",
                        "reward_cvar", "reward_nominal", *ENVELOPE_KEYS)

ProgressHook = Callable[[int, float], None]


def metrics_row(out: dict[str, np.ndarray], i: int) -> dict[str, Any]:
    """Row ``i`` of an evaluation as plain data: :data:`BEST_METRIC_KEYS` and, with
    scenarios, :data:`SCENARIO_METRIC_KEYS` (what :attr:`OptimResult.best_metrics` holds)."""
    keys = (*BEST_METRIC_KEYS, *(k for k in SCENARIO_METRIC_KEYS if k in out))
    return {k: to_jsonable(out[k][i]) for k in keys}


def front_columns(out: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The contact score and peak compression NSGA-II trades and the archive records: with
    scenarios their envelopes (the smallest contact score, the largest compression over the
    scenarios), else the grasp's own."""
    return (out.get("min_contact_score", out["contact_score"]),
            out.get("max_peak_compression", out["peak_compression"]))


class BudgetExhaustedError(RuntimeError):
    """A driver asked for more evaluations than the budget has left."""


def check_budget(budget: Any) -> int:
    """Validate an evaluation budget: an integer in [1, :data:`MAX_BUDGET`].

    Raises
    ------
    ValueError
        Naming the value and the allowed range.
    """
    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 1:
        raise ValueError(f"budget must be an integer in [1, {MAX_BUDGET:,}] (evaluations), got "
                         f"{budget!r}")
    if budget > MAX_BUDGET:
        raise ValueError(f"budget = {int(budget):,} is outside the allowed range [1, "
                         f"{MAX_BUDGET:,}] (evaluations: {MAX_BUDGET:.0e} take about an hour at "
                         "the in-process rate of ~2,600 designs/s on 2 cores; for a longer "
                         "search give --time SECONDS)")
    return int(budget)


def default_budget(scenario_count: int) -> int:
    """The evaluations of a run given neither a budget nor a time: :data:`DEFAULT_GRASP_BUDGET`
    grasps over the scenario count, within :data:`DEFAULT_BUDGET_RANGE` (3,600 designs with 9
    scenarios, 1,296 with 25, 8,000 without scenarios)."""
    low, high = DEFAULT_BUDGET_RANGE
    return int(min(high, max(low, DEFAULT_GRASP_BUDGET // max(1, int(scenario_count)))))


def check_time_limit(time_limit_s: Any, name: str = "time_limit_s") -> float:
    """Validate a run's time limit: seconds in (0, :data:`MAX_TIME_LIMIT_S`] (``name``: the
    parameter's, for the message).

    Raises
    ------
    ValueError
        Naming the value and the allowed range.
    """
    return check_range(name, time_limit_s, 0.0, MAX_TIME_LIMIT_S, low_open=True)


def check_seed(seed: Any) -> int:
    """Validate a seed: an integer in [0, 2**32)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not (
        0 <= seed < 2**32
    ):
        raise ValueError(f"seed must be an integer in [0, 2**32), got {seed!r}")
    return int(seed)


def check_strain_limit(strain_limit: Any) -> float:
    """Validate the object's admissible strain, in (0, 1]."""
    return check_range("strain_limit", strain_limit, 0.0, 1.0, low_open=True)


def check_payload_factor(payload_factor: Any) -> float:
    """Validate a payload factor, in [0, 100] (0: no payload)."""
    return check_range("payload_factor", payload_factor, 0.0, MAX_PAYLOAD_FACTOR)


def check_friction(friction_coefficient: Any) -> float:
    """Validate a Coulomb friction coefficient, in (0, 10]."""
    return check_range("friction_coefficient", friction_coefficient, 0.0,
                       MAX_FRICTION_COEFFICIENT, low_open=True)


def paper_design(scene: str | Scene = "paper-r070", torque_nm: float = 0.1) -> np.ndarray:
    """The scene's own gripper and placement as a design row (6,) in SI units.

    The row has no joint spring: evaluated by :func:`envs.evaluate_designs` with its default,
    the spring is relative to the disk (the paper gripper's own 0.073 N·m/rad only on the
    r = 0.07 m disk); pass ``torsion_stiffness_nm_per_rad`` for the scene's own.

    Parameters
    ----------
    scene
        A preset name (see :data:`envs.scene.PRESETS`) or a :class:`~envs.scene.Scene`.
    torque_nm
        Actuation torque ``T_a`` [N·m] (the paper does not fix one; 0.1 N·m grasps the r = 0.07
        m disk with a peak compression of 0.033, within the default limit 0.10).
    """
    sc = Scene.preset(scene) if isinstance(scene, str) else scene
    g, d = sc.gripper, sc.disk
    return np.array([g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m,
                     float(torque_nm), d.distance_m])


def paper_design_for(disk: SoftDisk, torques_nm: Any = 0.2) -> np.ndarray:
    """The paper's gripper on its r = 0.07 m disk at these torques there [N·m], scaled to
    another object like every relative design (lengths in radii, the torque in ``s E t r^2``):
    SI design rows, shape (k, 6)."""
    paper = Scene.preset("paper-r070").disk
    rows = np.array([paper_design("paper-r070", t) for t in np.atleast_1d(torques_nm)])
    rel = relative_from_design(rows, paper.radius_m, paper.torque_unit_nm)
    return design_from_relative(rel, disk.radius_m, disk.torque_unit_nm,
                                placement_support(disk))


def pareto_mask(objectives: np.ndarray) -> np.ndarray:
    """Non-dominated rows of a (n, 2) array of objectives to minimize.

    A row is dominated when another row is <= in both objectives and < in one. Exact duplicates
    keep their first occurrence only. O(n log n): sort by the first objective, sweep the second.
    """
    f = np.asarray(objectives, dtype=np.float64)
    if f.ndim != 2 or f.shape[1] != 2:
        raise ValueError(f"objectives must have shape (n, 2), got {f.shape}")
    order = np.lexsort((f[:, 1], f[:, 0]))  # by f0, then f1
    mask = np.zeros(f.shape[0], dtype=bool)
    best_f1 = math.inf
    for i in order.tolist():
        if f[i, 1] < best_f1:
            mask[i] = True
            best_f1 = f[i, 1]
    return mask


def top_distinct(x: np.ndarray, reward: np.ndarray, k: int = TOP_DESIGNS_KEPT) -> list[int]:
    """Rows of the ``k`` best distinct designs of ``x`` (n, n_var) by ``reward`` (n,), best
    first (the earlier of equal rewards); rows closer than :data:`DISTINCT_DESIGN` in every
    coordinate to a better one are the same design, and rows of non-finite reward are left
    out."""
    order = np.argsort(-reward, kind="stable")
    picked: list[int] = []
    for i in order.tolist():
        if len(picked) == k or not np.isfinite(reward[i]):
            break
        if all(np.max(np.abs(x[i] - x[j])) > DISTINCT_DESIGN for j in picked):
            picked.append(i)
    return picked


def _describe_executor(executor: Any) -> str:
    if executor is None:
        return "in-process"
    return str(getattr(executor, "description", type(executor).__name__))


class DesignProblem:
    """Gripper design for one fixed object, in the normalized space [-1, 1]^n.

    Row ``x`` (:attr:`n_var` wide: 6, plus the jaw columns of the bounds' ``jaw``) maps to the
    physical design ``bounds.scale(x, disk)`` (columns of
    :data:`envs.evaluate.DESIGN_FIELDS`, then the jaw fields of
    :data:`envs.model.jaw.JAW_FIELDS` with shaped jaws; the box is relative to the object, see
    :class:`~envs.evaluate.DesignBounds`); values outside [-1, 1] are clipped. The objective of
    the single-objective methods is the reward of :func:`envs.evaluate.evaluate_designs`
    (maximized). A design is *feasible* (for NSGA-II) when its grasp converged, both fingers
    touch the disk, the peak compression does not exceed the strain limit and the grasp holds
    the object with its friction coefficient (``required_friction`` at most it).

    Parameters
    ----------
    disk
        The object (its ``distance_m`` is replaced by each design's ``distance_m``).
    strain_limit
        Admissible compressive strain of the object [-], in (0, 1]: a limit on the peak
        compression (:func:`envs.evaluate_designs`).
    friction_coefficient
        Coulomb friction coefficient between the fingers and the object [-], in (0, 10]
        (default 0.5, a rubber or silicone pad): a grasp needing more does not hold the
        object once its centre is free, and scores below every grasp that does.
    payload_factor
        ``f`` of the payload ``W = f rho pi r^2 t g`` (the disk's ``density_kg_m3``) that
        friction must carry besides the centre's reaction, in [0, 100] (default 2: the weight
        plus a lift at 1 g; 0: no payload). A grasp that cannot lift its object does not hold.
    load_set
        How the gripper picks, the payload's directions (:mod:`envs.model.loads`):
        ``"top-down"`` (along the gripper's axis, both ways), ``"side"`` (out of the plane,
        both ways) or ``"any"`` (every direction; default).
    torsion_stiffness_rel
        Joint torsion spring ``k_f`` in the object's torque unit ``s E t r^2`` per radian
        [1/rad], > 0 (:func:`envs.scene.joint_spring`). Default (with
        ``torsion_stiffness_nm_per_rad`` also ``None``): the paper gripper's ratio on its
        r = 0.07 m disk, 0.0149 per radian, so that the spring scales with the object like
        every other column of the relative design space.
    torsion_stiffness_nm_per_rad
        An absolute joint spring [N·m/rad] instead, > 0 (not with ``torsion_stiffness_rel``).
    n_triangles, n_rings, element, calibrated
        The member of the model family that solves each grasp, as in :func:`envs.simulate`
        (default: the default model; ``element="spring"``: the paper's fan). ``self.model``
        holds the resolved member.
    bounds
        Box mapping [-1, 1]^n to physical designs (default :class:`~envs.evaluate.DesignBounds`).
    weights
        Reward weights (default :class:`~envs.evaluate.RewardWeights`).
    executor
        ``None`` (in-process batched: the compiled solver runs the rows in threads) or an object
        with ``.map(fn, iterable)`` from :mod:`optim.executors`.
    chunk_size
        Rows per task with an executor; default: the population split evenly over the
        executor's ``n_workers``, at least :data:`MIN_CHUNK_SIZE` rows per task.
    progress
        Called as ``progress(n_new_evaluations, best_reward)`` after every batch.
    name
        Name of the object (e.g. the scene preset), stored in the result.
    scenarios
        What the design must survive (:class:`envs.scenarios.Scenarios`: the object's ranges
        and a placement tolerance), or ``None``: the one exact object. With scenarios, ``disk``
        and ``friction_coefficient`` become the ranges' centre (the nominal object, which the
        relative design space is scaled to), the joint spring is that of the nominal object for
        every scenario (one physical gripper), and every design is solved under every scenario
        in one batch (:func:`envs.scenarios.evaluate_scenarios`): its reward is the
        ``robust`` measure, its metrics the governing (lowest reward) scenario's own row with
        the envelopes over the scenarios under their own names (a design is feasible when it
        holds within the strain limit in every scenario, ``holds_all``).
    robust
        The robust reward with scenarios: ``"worst"`` (default), ``"mean"`` or ``"cvar"``.
    joints_apart
        Keep every design's joints at least half a finger width from the axis (``d_3 >= w /
        2``), for a gripper whose fingers cannot be stacked at the joints
        (:class:`~envs.evaluate.DesignBounds` ``joints_apart``: ``bounds`` with it set).
        Default ``False``: the bounds as given.
    jaw, jaw_per_finger
        Shaped jaws (:class:`~envs.evaluate.DesignBounds` ``jaw``, ``jaw_per_finger``):
        ``"straight"``, ``"cradle"``, ``"vee"`` or ``"any"``, and whether each finger has its
        own groove; ``None`` (default): the bounds' own (straight bars by default).
    """

    def __init__(
        self,
        disk: SoftDisk,
        strain_limit: float = DEFAULT_STRAIN_LIMIT,
        friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
        *,
        payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
        load_set: str = DEFAULT_LOAD_SET,
        torsion_stiffness_rel: float | None = None,
        torsion_stiffness_nm_per_rad: float | None = None,
        n_triangles: int | None = None,
        bounds: DesignBounds | None = None,
        weights: RewardWeights | None = None,
        executor: Any = None,
        chunk_size: int | None = None,
        progress: ProgressHook | None = None,
        name: str | None = None,
        n_rings: int | None = None,
        element: str | None = None,
        calibrated: bool | None = None,
        scenarios: Scenarios | None = None,
        robust: str = "worst",
        joints_apart: bool = False,
        jaw: str | None = None,
        jaw_per_finger: bool | None = None,
    ) -> None:
        if not isinstance(disk, SoftDisk):
            raise ValueError(f"disk must be a SoftDisk, got {type(disk).__name__}")
        if scenarios is not None and not isinstance(scenarios, Scenarios):
            raise ValueError(f"scenarios must be None or a Scenarios, got "
                             f"{type(scenarios).__name__}")
        if robust not in ROBUST_MEASURES:
            raise ValueError(f"robust must be one of {ROBUST_MEASURES}, got {robust!r}")
        self.scenarios = None if scenarios is None or scenarios.is_trivial else scenarios
        self.robust = robust
        self.disk = disk if self.scenarios is None else self.scenarios.nominal_disk(disk)
        self.strain_limit = check_strain_limit(strain_limit)
        self.friction_coefficient = check_friction(
            friction_coefficient if self.scenarios is None
            else self.scenarios.nominal_friction(friction_coefficient))
        self.payload_factor = check_payload_factor(payload_factor)
        self.payload_n = self.disk.payload_n(self.payload_factor)
        load_set_code(load_set)
        self.load_set = load_set
        self.torsion_stiffness_rel, self._torsion_absolute = joint_spring(
            torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
        self.model = resolve_model(n_triangles, n_rings,
                                   DEFAULT_ELEMENT if element is None else element, calibrated)
        self.n_triangles = self.model.n_triangles
        if not isinstance(joints_apart, bool):
            raise ValueError(f"joints_apart must be True or False, got {joints_apart!r}")
        if bounds is not None and not isinstance(bounds, DesignBounds):
            raise ValueError(f"bounds must be None or a DesignBounds, got "
                             f"{type(bounds).__name__}")
        self.bounds = DesignBounds() if bounds is None else bounds
        if joints_apart:
            self.bounds = replace(self.bounds, joints_apart=True)
        if jaw is not None or jaw_per_finger is not None:
            self.bounds = self.bounds.with_jaw(jaw, jaw_per_finger)  # (validated there)
        self.weights = RewardWeights() if weights is None else weights
        if executor is not None and not callable(getattr(executor, "map", None)):
            raise ValueError("executor must be None or have a .map(fn, iterable) method")
        self.executor = executor
        self.chunk_size = None if chunk_size is None else check_integer(
            "chunk_size", chunk_size, 1, MAX_CHUNK_SIZE)
        self.progress = progress
        self.name = name
        self.time_limit_s: float | None = None
        # whether a driver may size its phases by the time limit (a user's time); the default
        # run's limit (DEFAULT_TIME_LIMIT_S) is a cap on a run sized by its budget
        self.plan_by_time = True
        self.start(None)

    @property
    def n_var(self) -> int:
        """Width of a normalized design: 6, plus the jaw columns of :attr:`bounds`."""
        return self.bounds.n_var

    @property
    def torsion_stiffness_nm_per_rad(self) -> float:
        """The joint spring ``k_f`` on this object [N·m/rad] (a relative one times the object's
        torque unit)."""
        if self.torsion_stiffness_rel is None:
            return self._torsion_absolute
        return self.torsion_stiffness_rel * self.disk.torque_unit_nm

    def joint_spring_kwargs(self) -> dict[str, float]:
        """The joint spring as keyword arguments of :func:`envs.evaluate_designs` and the envs
        (relative or absolute, as given)."""
        return joint_spring_kwargs(self.torsion_stiffness_rel, self._torsion_absolute)

    @classmethod
    def from_scene(cls, scene: str | Scene = "paper-r070",
                   strain_limit: float = DEFAULT_STRAIN_LIMIT,
                   friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
                   **kwargs: Any) -> DesignProblem:
        """The object and the joint spring of a scene preset (or a :class:`Scene`).

        The scene's gripper keeps its own spring, in N·m/rad, unless a spring is given.

        Raises
        ------
        ValueError
            For an unknown preset name (the message lists the allowed ones).
        """
        if isinstance(scene, str):
            if scene not in PRESETS:
                raise ValueError(f"unknown scene {scene!r}; allowed: {sorted(PRESETS)}")
            kwargs.setdefault("name", scene)
            scene = Scene.preset(scene)
        if not isinstance(scene, Scene):
            raise ValueError(f"scene must be a preset name or a Scene, got {scene!r}")
        if (kwargs.get("torsion_stiffness_rel") is None
                and kwargs.get("torsion_stiffness_nm_per_rad") is None):
            kwargs["torsion_stiffness_nm_per_rad"] = scene.gripper.torsion_stiffness_nm_per_rad
        return cls(scene.disk, strain_limit, friction_coefficient, **kwargs)

    # --- bookkeeping --------------------------------------------------------------------------

    def start(self, budget: int | None, time_limit_s: float | None = None) -> None:
        """Reset the count, best, history, archive and clock; set the budget (None: unlimited).

        ``time_limit_s``: wall seconds the run may take from now (default
        :attr:`time_limit_s`, set by whoever hands the problem to a driver; ``None``: no
        limit). Once it has passed, :attr:`remaining` is 0, so every driver stops after the
        batch under way (a batch is never cut short).
        """
        self.budget = None if budget is None else check_budget(budget)
        if time_limit_s is not None:
            self.time_limit_s = check_time_limit(time_limit_s)
        self.n_evaluations = 0
        self.best_reward = -math.inf
        self.best_x: np.ndarray | None = None
        self.best_metrics: dict[str, Any] = {}
        self.history_evaluations: list[int] = []
        self.history_best_reward: list[float] = []
        self.history_wall_time_s: list[float] = []
        self._archive: list[dict[str, np.ndarray]] = []
        self._t0 = time.perf_counter()

    @property
    def remaining(self) -> int:
        """Evaluations left in the budget (a large number when unlimited); 0 once the time
        limit (:attr:`time_limit_s`) has passed."""
        if self.out_of_time:
            return 0
        if self.budget is None:
            return 2**62
        return self.budget - self.n_evaluations

    @property
    def out_of_time(self) -> bool:
        """Whether the run's time limit has passed (never without one)."""
        return self.time_limit_s is not None and self.elapsed_s >= self.time_limit_s

    @property
    def elapsed_s(self) -> float:
        """Wall time since :meth:`start` [s]."""
        return time.perf_counter() - self._t0

    def _chunk_size_for(self, batch: int) -> int:
        if self.chunk_size is not None:
            return self.chunk_size
        workers = int(getattr(self.executor, "n_workers", 0) or 0)
        if workers <= 0:
            return DEFAULT_CHUNK_SIZE
        return max(MIN_CHUNK_SIZE, math.ceil(batch / workers))

    # --- evaluation ---------------------------------------------------------------------------

    def to_physical(self, x: Any) -> np.ndarray:
        """Normalized rows (..., :attr:`n_var`), clipped to [-1, 1], in physical units (SI:
        6, 10 or 14 columns,
        :attr:`~envs.design_space.DesignBounds.design_width`)."""
        return self.bounds.scale(np.clip(real_array("x", x), -1.0, 1.0), self.disk)

    def design_dict(self, x: Any) -> dict[str, float]:
        """One normalized row as ``{field: value}`` in physical units (the jaw fields of
        :data:`~envs.model.jaw.JAW_FIELDS` included with shaped jaws)."""
        row = self.to_physical(np.asarray(x, dtype=np.float64).reshape(self.n_var))
        return design_mapping(row)

    def evaluate_physical(self, designs: Any, member: dict[str, Any] | None = None
                          ) -> dict[str, np.ndarray]:
        """Evaluate physical designs (B, 6), (B, 10) or (B, 14) on this object without
        counting them.

        With scenarios, one row per design: the robust reward, the governing scenario's own
        row and the envelopes over the scenarios (:class:`envs.scenarios.ScenarioTable`
        ``summary``). ``member``: a
        model member's keyword arguments instead of the problem's own (the finish's finer
        member).
        """
        designs = np.asarray(designs, dtype=np.float64)
        if self.scenarios is not None:
            return self.evaluate_scenarios(designs, member).summary
        return evaluate_designs(
            designs, self.disk, strain_limits=self.strain_limit,
            friction_coefficients=self.friction_coefficient,
            payload_factors=self.payload_factor, **self.joint_spring_kwargs(),
            load_set=self.load_set, weights=self.weights, executor=self.executor,
            **(self.model.kwargs() if member is None else member),
            chunk_size=self._chunk_size_for(designs.shape[0]),
        )

    def evaluate_scenarios(self, designs: Any, member: dict[str, Any] | None = None, *,
                           full: bool = False) -> ScenarioTable:
        """Physical designs (B, 6/10/14) under every scenario of the problem (the one nominal
        scenario without scenarios), one batch, not counted; ``member`` as in
        :meth:`evaluate_physical`; ``full``: every corner of the box, not the covering set
        (:func:`envs.scenarios.evaluate_scenarios`)."""
        designs = np.asarray(designs, dtype=np.float64)
        scenarios = Scenarios() if self.scenarios is None else self.scenarios
        rows = designs.shape[0] * len(scenarios.scenarios(full))
        return evaluate_scenarios(
            designs, self.disk, scenarios,
            torsion_stiffness_nm_per_rad=self.torsion_stiffness_nm_per_rad,
            friction_coefficient=self.friction_coefficient, robust=self.robust,
            strain_limits=self.strain_limit, payload_factors=self.payload_factor,
            load_set=self.load_set, weights=self.weights, executor=self.executor, full=full,
            **(self.model.kwargs() if member is None else member),
            chunk_size=self._chunk_size_for(rows))

    def scenario_rows(self, design: dict[str, float],
                      member: dict[str, Any] | None = None,
                      full: bool = False) -> list[dict[str, Any]]:
        """One design (``{field: value}``, SI) under every scenario (``full``: every corner):
        a row per scenario with the scenario and its grasp's metrics (what a result JSON
        records)."""
        row = design_row(design)[None, :]
        table = self.evaluate_scenarios(row, member, full=full)
        return [{"scenario": sc.as_dict(),
                 **{k: to_jsonable(table.per_scenario[k][0, j]) for k in BEST_METRIC_KEYS}}
                for j, sc in enumerate(table.scenarios)]

    def evaluate(self, x: Any) -> dict[str, np.ndarray]:
        """Evaluate a population of normalized designs and record it (the search).

        Parameters
        ----------
        x
            Array (B, :attr:`n_var`) of normalized designs (clipped to [-1, 1]).

        Returns
        -------
        dict[str, numpy.ndarray]
            The metrics of :func:`envs.evaluate.evaluate_designs`, first axis B.

        Raises
        ------
        BudgetExhaustedError
            If B exceeds :attr:`remaining` (drivers truncate their last population).
        """
        x = np.clip(np.asarray(x, dtype=np.float64), -1.0, 1.0)
        if x.ndim != 2 or x.shape[1] != self.n_var:
            raise ValueError(f"x must have shape (B, {self.n_var}), got {x.shape}")
        if x.shape[0] > self.remaining:
            raise BudgetExhaustedError(
                f"{x.shape[0]} evaluations asked, {self.remaining} left in the budget")
        if x.shape[0] == 0:
            return {k: np.zeros((0, *shape), dtype=dt) for k, (dt, shape) in METRIC_KEYS.items()}
        out = self.evaluate_physical(self.bounds.scale(x, self.disk))
        self._record(x, out)
        return out

    @property
    def scenario_count(self) -> int:
        """Scenarios every evaluation solves (1 without scenarios)."""
        return 1 if self.scenarios is None else len(self.scenarios.scenarios())

    def screen_cost(self, rows: int) -> int:
        """Evaluations :meth:`screen` charges for ``rows`` designs: a ninth of one each with 9
        scenarios, rounded up over the batch."""
        return math.ceil(rows / self.scenario_count)

    def screen(self, x: Any) -> dict[str, np.ndarray]:
        """Evaluate normalized designs on the nominal scenario alone: a cheap first look,
        charged :meth:`screen_cost` evaluations, not recorded as the run's designs (its best,
        archive and top designs hold robust judgements only).

        Raises
        ------
        BudgetExhaustedError
            If the charge exceeds :attr:`remaining`.
        """
        x = np.clip(np.asarray(x, dtype=np.float64), -1.0, 1.0)
        if x.ndim != 2 or x.shape[1] != self.n_var:
            raise ValueError(f"x must have shape (B, {self.n_var}), got {x.shape}")
        cost = self.screen_cost(x.shape[0])
        if cost > self.remaining:
            raise BudgetExhaustedError(
                f"a screen of {x.shape[0]} designs costs {cost} evaluations, {self.remaining} "
                "left in the budget")
        designs = self.bounds.scale(x, self.disk)
        out = evaluate_designs(
            designs, self.disk, strain_limits=self.strain_limit,
            friction_coefficients=self.friction_coefficient,
            payload_factors=self.payload_factor, **self.joint_spring_kwargs(),
            load_set=self.load_set, weights=self.weights, executor=self.executor,
            **self.model.kwargs(),
            chunk_size=self._chunk_size_for(designs.shape[0]))
        self.n_evaluations += cost
        if math.isfinite(self.best_reward):  # (the history holds robust judgements only)
            self.history_evaluations.append(self.n_evaluations)
            self.history_best_reward.append(self.best_reward)
            self.history_wall_time_s.append(self.elapsed_s)
        if self.progress is not None:
            self.progress(cost, self.best_reward)
        return out

    def add_external_evaluations(self, count: int) -> None:
        """Count evaluations done elsewhere (RL training steps on other objects)."""
        count = int(count)
        if count < 0 or count > self.remaining:
            raise BudgetExhaustedError(
                f"{count} external evaluations, {self.remaining} left in the budget")
        self.n_evaluations += count
        if self.progress is not None and count:
            self.progress(count, self.best_reward)

    def _record(self, x: np.ndarray, out: dict[str, np.ndarray]) -> None:
        reward = out["reward"]
        i = int(np.argmax(reward))  # first maximum: ties keep the earliest design
        if reward[i] > self.best_reward:
            self.best_reward = float(reward[i])
            self.best_x = x[i].copy()
            self.best_metrics = metrics_row(out, i)
        first = self.n_evaluations + 1
        self.n_evaluations += x.shape[0]
        self.history_evaluations.append(self.n_evaluations)
        self.history_best_reward.append(self.best_reward)
        self.history_wall_time_s.append(self.elapsed_s)
        contact, compression = front_columns(out)
        self._archive.append({
            "evaluations": np.arange(first, self.n_evaluations + 1, dtype=np.int64),
            "x": x.copy(),
            "reward": reward.copy(),
            "contact_score": contact.copy(),
            "peak_compression": compression.copy(),
            "feasible": self.feasible(out),
        })
        if self.progress is not None:
            self.progress(x.shape[0], self.best_reward)

    def feasible(self, out: dict[str, np.ndarray]) -> np.ndarray:
        """Grasps that hold the object (converged, both fingers touching, the required friction
        within the coefficient) and keep their peak compression within the strain limit; with
        scenarios, in every scenario (``holds_all``)."""
        if "holds_all" in out:
            return out["holds_all"].copy()
        return out["holds"] & (out["peak_compression"] <= self.strain_limit)

    def archive(self) -> dict[str, np.ndarray]:
        """Every evaluated point: ``x`` (n, :attr:`n_var`), ``reward``, ``contact_score``,
        ``peak_compression``, ``feasible`` (n,), in evaluation order, and ``evaluations`` (n,):
        the run's evaluation count that each is (the budget :meth:`screen` charged counted, its
        designs not among the points)."""
        keys = ("evaluations", "x", "reward", "contact_score", "peak_compression", "feasible")
        if not self._archive:
            return {k: np.zeros((0, self.n_var) if k == "x" else (0,),
                                dtype=np.int64 if k == "evaluations" else np.float64)
                    for k in keys}
        return {k: np.concatenate([a[k] for a in self._archive]) for k in keys}

    def top_designs(self, k: int = TOP_DESIGNS_KEPT) -> list[dict[str, Any]]:
        """The ``k`` best distinct evaluated designs, best first: each ``{"design": {...},
        "reward": ...}``.

        Designs closer than :data:`DISTINCT_DESIGN` in every normalized coordinate (1 % of the
        box's width) to a better one are the same design for this purpose: a converged CMA-ES
        run evaluates hundreds of near copies of its best.
        """
        arc = self.archive()
        return [{"design": self.design_dict(arc["x"][i]), "reward": float(arc["reward"][i])}
                for i in top_distinct(arc["x"], arc["reward"], k)]

    def pareto_front(self) -> list[dict[str, Any]]:
        """Non-dominated feasible evaluated designs (contact score up, peak compression down),
        sorted by contact score; with scenarios, of their envelopes, under the envelopes'
        names ``min_contact_score`` and ``max_peak_compression``."""
        arc = self.archive()
        rows = np.flatnonzero(arc["feasible"])
        if rows.size == 0:
            return []
        obj = np.column_stack([-arc["contact_score"][rows], arc["peak_compression"][rows]])
        front = rows[pareto_mask(obj)]
        front = front[np.argsort(arc["contact_score"][front], kind="stable")]
        prefix = ("min_", "max_") if self.scenarios is not None else ("", "")
        return [{
            "design": self.design_dict(arc["x"][i]),
            f"{prefix[0]}contact_score": float(arc["contact_score"][i]),
            f"{prefix[1]}peak_compression": float(arc["peak_compression"][i]),
            "reward": float(arc["reward"][i]),
        } for i in front.tolist()]

    def object_info(self) -> dict[str, Any]:
        """The fixed object as plain data."""
        d = self.disk
        return {
            "name": self.name,
            "radius_m": d.radius_m,
            "youngs_modulus_pa": d.youngs_modulus_pa,
            "poisson_ratio": d.poisson_ratio,
            "thickness_m": d.thickness_m,
            "stiffness_scale": d.stiffness_scale,
            "contour_stiffness_ratio": d.contour_stiffness_ratio,
            "strain_limit": self.strain_limit,
            "friction_coefficient": self.friction_coefficient,
            "density_kg_m3": d.density_kg_m3,
            "payload_factor": self.payload_factor,
            "payload_n": self.payload_n,
            "load_set": self.load_set,
            "torsion_stiffness_rel": self.torsion_stiffness_rel,
            "torsion_stiffness_nm_per_rad": self.torsion_stiffness_nm_per_rad,
            **outline_info(d),
            **self.model.kwargs(),
            **({} if self.scenarios is None else {"scenarios": self.scenarios.as_dict(),
                                                  "robust": self.robust}),
        }

    def result(self, method: str, seed: int, *, options: dict[str, Any] | None = None,
               pareto: bool = False, extra: dict[str, Any] | None = None) -> OptimResult:
        """Freeze the bookkeeping of the current run into an :class:`OptimResult`.

        Its ``extra["grasp_found"]`` tells whether the best design is a grasp; when it is not,
        a :class:`~optim.result.NoGraspWarning` says why (a design for a small or soft object
        that never touches it must not pass for an answer).
        """
        best_design = ({} if self.best_x is None else self.design_dict(self.best_x))
        found = grasp_found(self.best_metrics)
        if not found:
            warnings.warn(
                f"{method} found no grasp of {self.name or 'the object'} in "
                f"{self.n_evaluations} evaluations: its best design "
                f"{no_grasp_reason(self.best_metrics)} (reward {self.best_reward:.4f})",
                NoGraspWarning, stacklevel=3)
        return OptimResult(
            method=method,
            seed=seed,
            budget=self.budget if self.budget is not None else self.n_evaluations,
            best_design=best_design,
            best_reward=self.best_reward,
            best_metrics=dict(self.best_metrics),
            history_evaluations=tuple(self.history_evaluations),
            history_best_reward=tuple(self.history_best_reward),
            history_wall_time_s=tuple(self.history_wall_time_s),
            n_evaluations=self.n_evaluations,
            wall_time_s=self.elapsed_s,
            object=self.object_info(),
            pareto_front=tuple(self.pareto_front()) if pareto else (),
            top_designs=tuple(self.top_designs()),
            options=to_jsonable(dict(options or {})),
            executor=_describe_executor(self.executor),
            extra=to_jsonable({**(extra or {}), "grasp_found": found,
                               "time_limit_s": self.time_limit_s,
                               "out_of_time": self.out_of_time,
                               "joints_apart": self.bounds.joints_apart,
                               "jaw": self.bounds.jaw,
                               "jaw_per_finger": self.bounds.jaw_per_finger,
                               **self.scenario_extra(best_design)}),
        )

    def scenario_extra(self, design: dict[str, float],
                       member: dict[str, Any] | None = None,
                       full: bool = False) -> dict[str, Any]:
        """``{"scenario_rows": [...], "scenario_set": ...}``: the design under every scenario
        (``full``: every corner) and which set that is (a result's extra); empty without
        scenarios or without a design."""
        if self.scenarios is None or not design:
            return {}
        covering = self.scenarios.uses_covering_set and not full
        return {"scenario_rows": self.scenario_rows(design, member, full),
                "scenario_set": "covering" if covering else "full"}

    def use_spring_nm(self, torsion_stiffness_nm_per_rad: float) -> None:
        """Build every design with this absolute joint spring [N·m/rad] from now on (the
        spring rounded to the manufacturing resolution, :mod:`optim.parts.resolution`)."""
        self.torsion_stiffness_rel = None
        self._torsion_absolute = check_range("torsion_stiffness_nm_per_rad",
                                             torsion_stiffness_nm_per_rad, 0.0, math.inf,
                                             low_open=True)
