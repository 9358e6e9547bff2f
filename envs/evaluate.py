"""Batched evaluation of gripper designs: designs -> grasp metrics and named reward terms.

:func:`evaluate_designs` is the one physics entry point of the design environment and of the
optimizers. It takes a whole population of designs at once (like pymoo's ``_evaluate``), solves
every grasp through the one pipeline :func:`envs.solver.pipeline.solve_columns` (compiled, rows
in parallel threads, each answer checked independently) and computes the metrics and the
reward terms vectorized in numpy. Parallelism beyond one
process is injected through ``executor`` (anything with ``.map``), never hard-coded.

A design is six numbers in SI units, in the column order of :data:`DESIGN_FIELDS`:

| col | field | meaning | unit |
|---|---|---|---|
| 0 | ``finger_length_m`` | finger length ``l`` (joint to tip) | m |
| 1 | ``rest_angle_rad`` | rest angle ``theta_a0`` of both fingers from +y | rad |
| 2 | ``joint_offset_m`` | joint distance ``d_3`` from the symmetry axis | m |
| 3 | ``finger_width_m`` | finger width ``w`` | m |
| 4 | ``torque_nm`` | actuation torque ``T_a`` on each finger | N·m |
| 5 | ``distance_m`` | object placement ``d_1`` (joints' line to disk) | m |
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from .model.contact_width import contact_share, hertz_arc_coefficient
from .model.defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_FRICTION_COEFFICIENT,
    DEFAULT_PHASE_RAD,
    DEFAULT_STRAIN_LIMIT,
    FEM_DESIGN_RINGS,
    FEM_MAX_RINGS,
    MAX_FRICTION_COEFFICIENT,
    PAPER_TORSION_STIFFNESS_REL,
)
from .model.family import resolve_model, triangle_range
from .model.geometry import bar_distance
from .model.holding import H_MU, H_PIN_MOMENT, H_PIN_X, H_PIN_Y
from .model.problem import REST_OK, SceneColumns, _clearance, rest_codes
from .scene import (
    DESIGN_FIELDS,
    N_DESIGN,
    RELATIVE_FIELDS,
    SPRING_TWICE,
    Design,
    SoftDisk,
    design_from_relative,
    relative_from_design,
)
from .scoring import (
    N_WEIGHTS,
    W_CONTACT,
    W_CONTACT_CAP,
    W_DEFORM,
    W_DEFORM_CAP,
    W_FAIL,
    W_GAP,
    W_INVALID,
    W_MISS,
    W_SLIP,
    W_VIOLATION,
    grip_share_rows,
    psm_metrics_rows,
    reward_rows,
)
from .solver.pipeline import BatchSolution, solve_columns
from .solver.status import FEM_FAILED, NOT_SOLVED, OK
from .validation import check_integer, check_range

__all__ = [
    "DESIGN_FIELDS",
    "N_DESIGN",
    "Design",
    "DEFAULT_STRAIN_LIMIT",
    "METRIC_KEYS",
    "Design",
    "DesignBounds",
    "RewardWeights",
    "evaluate_designs",
    "finger_gaps_m",
    "rest_violation",
]

DEFAULT_CHUNK_SIZE = 256
FIDELITIES = ("psm", "fem")
TORQUE_COLUMN = DESIGN_FIELDS.index("torque_nm")
DISTANCE_COLUMN = DESIGN_FIELDS.index("distance_m")

# Keys of the dict returned by evaluate_designs, with their dtype and trailing shape.
METRIC_KEYS: dict[str, tuple[type, tuple[int, ...]]] = {
    "valid_at_rest": (np.bool_, ()),
    "converged": (np.bool_, ()),
    "stable": (np.bool_, ()),
    "status": (np.int64, ()),
    "iterations": (np.int64, ()),
    "n_triangles": (np.int64, ()),
    "jaw_angles_rad": (np.float64, (2,)),
    "n_contacts": (np.int64, (2,)),
    "touching": (np.bool_, (2,)),
    "total_force_n": (np.float64, (2,)),
    "contact_score": (np.float64, ()),
    "grip_share": (np.float64, ()),
    "peak_strain": (np.float64, ()),
    "peak_log_strain": (np.float64, ()),
    "max_displacement_ratio": (np.float64, ()),
    "peak_compression": (np.float64, ()),
    "strain_limit": (np.float64, ()),
    "pin_force_n": (np.float64, (2,)),
    "pin_moment_nm": (np.float64, ()),
    "required_friction": (np.float64, ()),
    "friction_coefficient": (np.float64, ()),
    "holds": (np.bool_, ()),
    "finger_gap_m": (np.float64, (2,)),
    "rest_violation": (np.float64, ()),
    "reward_contact": (np.float64, ()),
    "reward_deform": (np.float64, ()),
    "penalty_slip": (np.float64, ()),
    "penalty_miss": (np.float64, ()),
    "penalty_gap": (np.float64, ()),
    "penalty_invalid": (np.float64, ()),
    "penalty_fail": (np.float64, ()),
    "reward": (np.float64, ()),
}


def _scales(disks, batch: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Radius [m] and torque unit ``s E t r^2`` [N·m] of one disk (scalars) or of a sequence of
    ``batch`` disks (arrays (batch,))."""
    if isinstance(disks, SoftDisk):
        return np.float64(disks.radius_m), np.float64(disks.torque_unit_nm)
    if not isinstance(disks, Sequence) or (batch is not None and len(disks) != batch):
        raise ValueError(f"disks must be a SoftDisk or a sequence of {batch} SoftDisks, got "
                         f"{type(disks).__name__}")
    for i, d in enumerate(disks):
        if not isinstance(d, SoftDisk):
            raise ValueError(f"disks[{i}] must be a SoftDisk, got {type(d).__name__}")
    return (np.array([d.radius_m for d in disks], dtype=np.float64),
            np.array([d.torque_unit_nm for d in disks], dtype=np.float64))


@dataclass(frozen=True)
class DesignBounds:
    """Box of the design space relative to the object; maps actions in [-1, 1] to designs.

    The box is in the units of :data:`envs.scene.RELATIVE_FIELDS`: finger length, joint offset
    and finger width in disk radii, the rest angle in radians, the torque in the disk's torque
    unit ``s E t r^2`` (:attr:`~envs.scene.SoftDisk.torque_unit_nm`) and, for the placement, the
    rest clearance between the disk and the gripping faces in radii
    (:func:`~envs.scene.design_from_relative`). The model is invariant under this scaling, so
    a box means the same for every object: the paper's foam disks and the forceps' 2 mm TPU
    beads alike. Every design of the default box is valid at rest (its clearance is positive),
    and most of its random designs grasp with both fingers, on every preset.

    | # | field | meaning | low | high |
    |---|---|---|---|---|
    | 0 | ``finger_length_r`` | finger length ``l / r`` | 1.5 | 8 |
    | 1 | ``rest_angle_rad`` | rest angle ``theta_a0`` | 10 deg | 60 deg |
    | 2 | ``joint_offset_r`` | joint offset ``d_3 / r`` | 0 | 0.6 |
    | 3 | ``finger_width_r`` | finger width ``w / r`` | 0.05 | 0.4 |
    | 4 | ``torque_rel`` | ``T_a / (s E t r^2)`` | 0 | 0.3 |
    | 5 | ``rest_clearance_r`` | rest clearance / ``r`` | 0.005 | 1.2 |

    The box holds the paper's grippers (``l / r`` = 2 to 4, 45 deg, clearance 0.01 to 0.02, the
    paper's torques 0.05 to 0.5 N·m at 0.005 to 0.2 units) and the forceps (``l / r`` = 5.3 to 8,
    15 deg, clearance 0.6 to 1.2).

    Parameters
    ----------
    low, high
        Lower and upper bound of each relative column, ``low < high``.
    """

    low: tuple[float, ...] = (1.5, math.radians(10.0), 0.0, 0.05, 0.0, 0.005)
    high: tuple[float, ...] = (8.0, math.radians(60.0), 0.6, 0.4, 0.3, 1.2)

    def __post_init__(self) -> None:
        for name in ("low", "high"):
            given = tuple(getattr(self, name))
            if len(given) != N_DESIGN:
                raise ValueError(f"DesignBounds.{name} needs {N_DESIGN} values, got {len(given)}")
            # checked as given, not after float(): "0.2" and True are not bounds
            vals = tuple(check_range(f"DesignBounds.{name}[{field_name}]", v)
                         for field_name, v in zip(RELATIVE_FIELDS, given, strict=True))
            object.__setattr__(self, name, vals)
        for field_name, lo, hi in zip(RELATIVE_FIELDS, self.low, self.high, strict=True):
            if not lo < hi:
                raise ValueError(
                    f"DesignBounds for {field_name}: low = {lo!r} must be smaller than "
                    f"high = {hi!r}"
                )

    @property
    def low_array(self) -> np.ndarray:
        """Lower bounds (relative units) as a float64 array (6,)."""
        return np.array(self.low, dtype=np.float64)

    @property
    def high_array(self) -> np.ndarray:
        """Upper bounds (relative units) as a float64 array (6,)."""
        return np.array(self.high, dtype=np.float64)

    def relative(self, action) -> np.ndarray:
        """Map normalized actions in [-1, 1] (shape (..., 6)) to relative designs."""
        a = np.asarray(action, dtype=np.float64)
        lo, hi = self.low_array, self.high_array
        return lo + 0.5 * (a + 1.0) * (hi - lo)

    def scale(self, action, disks) -> np.ndarray:
        """Map normalized actions (shape (B, 6) or (6,)) to SI designs for their objects.

        Parameters
        ----------
        action
            Normalized actions in [-1, 1].
        disks
            One :class:`~envs.scene.SoftDisk` for every row or a sequence of one per row (its
            radius and torque unit set the scale; its ``distance_m`` is not used).
        """
        a = np.asarray(action, dtype=np.float64)
        radius, unit = _scales(disks, a.shape[0] if a.ndim == 2 else None)
        return design_from_relative(self.relative(a), radius, unit)

    def unscale(self, designs, disks) -> np.ndarray:
        """Map SI designs (shape (B, 6) or (6,)) to normalized actions (inverse of
        :meth:`scale` where the placement was not raised to 0)."""
        d = np.asarray(designs, dtype=np.float64)
        radius, unit = _scales(disks, d.shape[0] if d.ndim == 2 else None)
        rel = relative_from_design(d, radius, unit)
        lo, hi = self.low_array, self.high_array
        return 2.0 * (rel - lo) / (hi - lo) - 1.0

    def sample(self, rng: np.random.Generator, size: int, disks) -> np.ndarray:
        """Draw ``size`` SI designs uniformly in the box for the object(s), shape (size, 6)."""
        return self.scale(rng.uniform(-1.0, 1.0, size=(int(size), N_DESIGN)), disks)


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms of :func:`evaluate_designs`.

    The reward ranks outcomes in tiers, each graded so that an optimizer is pointed towards
    the tier above, and every outcome of a tier below every outcome of the tiers above:

    1. a grasp that **holds** (converged, both fingers touching, ``required_friction`` within
       the object's friction coefficient ``mu``):
       ``contact * min(contact_score, contact_cap) - deform * min(peak_compression /
       strain_limit, deform_cap)``, in ``[-F, contact * contact_cap]`` with ``F = deform *
       deform_cap`` (-1 with the defaults);
    2. a grasp that would **slip** (it needs more friction than ``mu``):
       ``-F - slip * x / (1 + x)``, ``x = required_friction / mu - 1`` (``x / (1 + x)`` = 1
       for an infinite need), in ``[-F - slip, -F)``: the less friction it needs, the
       higher;
    3. a **miss** (converged, a finger not touching the object):
       ``-F - slip - miss * m - gap * g / (1 + g)`` with ``m`` the fingers not touching and
       ``g`` the largest gap of such a finger to the disk, in radii: closer fingers score
       higher, in ``(-F - slip - 2 miss - gap, -F - slip - miss]``;
    4. a solver **failure** on a valid design: ``-fail``, at most the worst miss;
    5. a design **invalid** at rest: ``-invalid - violation * v / (1 + v)``, with ``v`` how far
       it is from valid (overlap depth and the other violated limits, in radii or radians;
       :func:`rest_violation`); ``invalid`` at least ``fail``.

    With the defaults: holds ``[-1, 0.5]``, slips ``[-1.5, -1)``, misses ``(-3, -2]``, a failure
    -3, invalid designs ``[-4.5, -3.5]``. Weights that would break the order are rejected.

    Parameters
    ----------
    contact
        Weight of the contact score (fraction of the contour in contact) [-].
    deform
        Weight of the peak compression (the largest shortening of a radius by the fingers,
        over r: how deep the grasp presses in) relative to the object's strain limit [-].
    miss
        Penalty per finger that does not touch the disk [-], > 0.
    gap
        Weight of the normalised gap ``g / (1 + g)`` of the farthest finger that does not
        touch the disk (``g`` its distance to the undeformed disk in the grasp, in radii) [-].
    invalid
        Penalty for a design that is invalid at rest (fingers overlapping the disk, ...) [-],
        at least ``fail``.
    violation
        Weight of the normalised violation ``v / (1 + v)`` of an invalid design, added to
        ``invalid`` [-].
    fail
        Penalty when the solver did not converge [-], at least ``deform * deform_cap + slip
        + 2 miss + gap``.
    contact_cap
        Cap of the contact score [-], > 0.
    deform_cap
        Cap of ``peak_compression / strain_limit`` [-], > 0 (keeps the reward bounded).
    slip
        Width of the tier of grasps that would slip [-], > 0: how much a grasp needing
        unlimited friction scores below one needing just the object's coefficient.
    """

    contact: float = 1.0
    deform: float = 0.25
    miss: float = 0.5
    gap: float = 0.5
    invalid: float = 3.5
    violation: float = 1.0
    fail: float = 3.0
    contact_cap: float = 0.5
    deform_cap: float = 4.0
    slip: float = 0.5

    def __post_init__(self) -> None:
        for f in fields(self):
            low_open = f.name.endswith("_cap") or f.name in ("slip", "miss")
            v = check_range(f"RewardWeights.{f.name}", getattr(self, f.name), 0.0, math.inf,
                            low_open=low_open)
            object.__setattr__(self, f.name, v)
        worst_valid = self.deform * self.deform_cap + self.slip + 2 * self.miss + self.gap
        if self.fail < worst_valid:
            raise ValueError(
                f"RewardWeights.fail = {self.fail!r} must be at least deform * deform_cap + "
                f"slip + 2 miss + gap = {worst_valid!r}, so that every solver failure scores "
                "below every converged design")
        if self.invalid < self.fail:
            raise ValueError(
                f"RewardWeights.invalid = {self.invalid!r} must be at least fail = "
                f"{self.fail!r}, so that every invalid design scores below every valid one")
        weights = np.empty(N_WEIGHTS)
        for name, k in (("contact", W_CONTACT), ("contact_cap", W_CONTACT_CAP),
                        ("deform", W_DEFORM), ("deform_cap", W_DEFORM_CAP), ("miss", W_MISS),
                        ("gap", W_GAP), ("invalid", W_INVALID), ("violation", W_VIOLATION),
                        ("fail", W_FAIL), ("slip", W_SLIP)):
            weights[k] = getattr(self, name)
        weights.flags.writeable = False
        object.__setattr__(self, "_vector", weights)

    def vector(self) -> np.ndarray:
        """The weights in the layout of :func:`envs.scoring.reward_rows` (read-only)."""
        return self._vector


# ---------------------------------------------------------------------------------------------
# input normalization


def _design_table(designs) -> np.ndarray:
    if isinstance(designs, Design):
        return designs.to_array()[None, :]
    if isinstance(designs, Sequence) and len(designs) > 0 and isinstance(designs[0], Design):
        if not all(isinstance(d, Design) for d in designs):
            raise ValueError("designs mixes Design objects and other values")
        return np.stack([d.to_array() for d in designs])
    try:
        arr = np.array(designs, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"designs must be a (B, {N_DESIGN}) array of numbers: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != N_DESIGN:
        raise ValueError(
            f"designs must have shape (B, {N_DESIGN}) with columns {DESIGN_FIELDS}, "
            f"got {arr.shape} (use designs[None] for a single row)"
        )
    return arr


# columns of :func:`_disk_table`
(DISK_RADIUS, DISK_YOUNG, DISK_POISSON, DISK_THICKNESS, DISK_SCALE, DISK_RATIO, DISK_AREA,
 DISK_OFFSET_X) = range(8)
N_DISK = 8
# columns of the objects' requirements: strain limit and friction coefficient
NEED_STRAIN, NEED_FRICTION = range(2)


def _disk_table(disks, batch: int) -> np.ndarray:
    """Columns (``DISK_*``): radius, Young's modulus, Poisson ratio, thickness, stiffness scale,
    contour stiffness ratio, area stiffness scale, the centre's lateral offset."""
    if isinstance(disks, SoftDisk):
        disks = [disks] * batch
    elif not isinstance(disks, Sequence) or len(disks) != batch:
        raise ValueError(f"disks must be a SoftDisk or a sequence of {batch} SoftDisks")
    rows = []
    for i, d in enumerate(disks):
        if not isinstance(d, SoftDisk):
            raise ValueError(f"disks[{i}] must be a SoftDisk, got {type(d).__name__}")
        rows.append((d.radius_m, d.youngs_modulus_pa, d.poisson_ratio, d.thickness_m,
                     d.stiffness_scale, d.contour_stiffness_ratio, d.area_stiffness_scale,
                     d.offset_x_m))
    return np.array(rows, dtype=np.float64).reshape(batch, N_DISK)


def _per_row(name: str, value, batch: int, low: float, high: float, *, low_open: bool,
             integer: bool = False) -> np.ndarray:
    """A scalar or one value per row, each validated (the message names the row)."""
    arr = np.asarray(value, dtype=object if integer else None)
    if arr.ndim == 0:
        one = (check_integer(name, arr.item(), int(low), int(high)) if integer
               else check_range(name, arr.item(), low, high, low_open=low_open))
        return np.full(batch, one, dtype=np.int64 if integer else np.float64)
    if arr.shape != (batch,):
        raise ValueError(f"{name} must be a scalar or have shape ({batch},), got {arr.shape}")
    if not integer and arr.dtype.kind in "fiu":
        # a numeric column (a vector env's strain limits each step): checked as one array; the
        # row loop below only runs to name the first bad row
        vals = arr.astype(np.float64)
        with np.errstate(invalid="ignore"):
            inside = (vals > low if low_open else vals >= low) & (vals <= high)
        if np.all(inside & np.isfinite(vals)):
            return vals
    out = np.empty(batch, dtype=np.int64 if integer else np.float64)
    for i, v in enumerate(arr.tolist()):
        out[i] = (check_integer(f"{name}[{i}]", v, int(low), int(high)) if integer
                  else check_range(f"{name}[{i}]", v, low, high, low_open=low_open))
    return out


def _joint_springs(rel, absolute, disk: np.ndarray, batch: int) -> np.ndarray:
    """The joint spring ``k_f`` [N·m/rad] of every row: an absolute one as given, a relative
    one (default :data:`PAPER_TORSION_STIFFNESS_REL`) times the row's torque unit ``s E t r^2``
    with the disk's own scale (see :func:`envs.scene.joint_spring`)."""
    if absolute is not None:
        if rel is not None:
            raise ValueError(SPRING_TWICE)
        return _per_row("torsion_stiffness_nm_per_rad", absolute, batch, 0.0, math.inf,
                        low_open=True)
    rel = _per_row("torsion_stiffness_rel", PAPER_TORSION_STIFFNESS_REL if rel is None else rel,
                   batch, 0.0, math.inf, low_open=True)
    unit = (disk[:, DISK_SCALE] * disk[:, DISK_YOUNG] * disk[:, DISK_THICKNESS]
            * disk[:, DISK_RADIUS] ** 2)
    return rel * unit


# ---------------------------------------------------------------------------------------------
# scenes, solve and metrics


def _columns(des: np.ndarray, disk: np.ndarray, kf: np.ndarray) -> SceneColumns:
    """Scene columns of design rows (the one Design -> Scene mapping, see
    :meth:`Design.to_scene`): the design's ``distance_m`` replaces the disk's; the disk keeps
    its lateral offset (a placement of the object, not part of the design)."""
    ln, th0, d3, w, torque, d1 = (np.ascontiguousarray(c) for c in des.T)
    radius, young, nu, thick, scale, ratio, area, offset = (np.ascontiguousarray(c)
                                                            for c in disk.T)
    return SceneColumns(ln, th0, d3, w, kf, radius, d1, young, nu, thick, scale, ratio, area,
                        torque, offset)


def _empty_output(batch: int) -> dict[str, np.ndarray]:
    return {k: np.zeros((batch, *shape), dtype=dt) for k, (dt, shape) in METRIC_KEYS.items()}


def grip_share(cols: SceneColumns, jaw_angles_rad: np.ndarray, stop_torques_nm: np.ndarray
               ) -> np.ndarray:
    """Share of the actuation torque that grips the object, the smaller of the two fingers',
    in [0, 1], shape (B,).

    By a finger's moment balance the object receives ``T_a - k_f (theta_a0 - theta) - M_stop``:
    what the torsion spring and the joint stop take does not grip. A design that tunes the
    torque so that the spring stops the fingers just at the object (contact forces of 1e-7 N)
    or that closes the jaws on their stops has a share near 0 (CMA-ES found such designs when
    contact was counted by force > 0 alone); a squeeze with little travel keeps nearly all.
    """
    angles = np.ascontiguousarray(jaw_angles_rad, dtype=np.float64)
    stops = np.ascontiguousarray(stop_torques_nm, dtype=np.float64)
    for name, arr in (("jaw_angles_rad", angles), ("stop_torques_nm", stops)):
        # the compiled loop does not check bounds: a short array would be read past its end
        if arr.shape != (cols.size, 2):
            raise ValueError(f"{name} must have shape ({cols.size}, 2) (one row a scene, one "
                             f"column a finger), got {arr.shape}")
    out = np.empty(cols.size)
    grip_share_rows(cols.torque_nm, cols.torsion_stiffness_nm_per_rad, cols.rest_angle_rad,
                    angles, stops, out)
    return out


def _fill_group(out: dict[str, np.ndarray], rows: np.ndarray, sol: BatchSolution, n: int,
                cols: SceneColumns, material_scale: np.ndarray) -> None:
    """Write the metrics of solved rows (failed rows keep zeros: finite, the fail penalty says
    what happened; :func:`envs.scoring.psm_metrics_rows`); ``material_scale``: the rows' own
    disk scale, without the member's calibration factor that ``cols.stiffness_scale`` carries
    (the contact width takes the material's modulus)."""
    psm_metrics_rows(
        rows, n, sol.status, sol.converged, sol.iterations, sol.stable, sol.jaw_angles_rad,
        sol.face_forces_n, sol.corner_totals_n, sol.stop_torques_nm, sol.peak_strain,
        sol.peak_log_strain, sol.max_displacement_ratio, sol.peak_compression, cols.radius_m,
        cols.thickness_m, cols.youngs_modulus_pa, cols.poisson_ratio,
        material_scale, cols.torque_nm, cols.torsion_stiffness_nm_per_rad,
        cols.rest_angle_rad, out["status"], out["converged"], out["iterations"], out["stable"],
        out["jaw_angles_rad"], out["n_contacts"], out["touching"], out["total_force_n"],
        out["contact_score"], out["grip_share"], out["peak_strain"], out["peak_log_strain"],
        out["max_displacement_ratio"], out["peak_compression"])
    ok = rows[out["converged"][rows]]
    done = out["converged"][rows]
    out["pin_force_n"][ok] = sol.holding[done, H_PIN_X : H_PIN_Y + 1]
    out["pin_moment_nm"][ok] = sol.holding[done, H_PIN_MOMENT]
    out["required_friction"][ok] = sol.holding[done, H_MU]


def rest_violation(cols: SceneColumns) -> np.ndarray:
    """How far each scene is from being valid at rest, >= 0 (0 where it is valid), shape (B,).

    The sum of every violated limit of :func:`envs.model.problem.rest_codes`, lengths in disk
    radii, angles in radians, the torque in the disk's torque unit ``s E t r^2``: the depth of
    the fingers' overlap with the disk, how far the disk centre lies behind a gripping face, how
    much wider than the disk the fingers are, how far a gripper field is out of its range. A
    scene exactly on a limit is invalid with violation 0; a non-finite value gives ``inf``.
    """
    r = cols.radius_m
    unit = cols.stiffness_scale * cols.youngs_modulus_pa * cols.thickness_m * r * r
    ln, th0, d3, w = (cols.finger_length_m, cols.rest_angle_rad, cols.joint_offset_m,
                      cols.finger_width_m)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        front, clearance = _clearance(cols)
        parts = (
            np.maximum(0.0, -clearance) / r,  # overlap depth
            np.maximum(0.0, -front) / r,  # centre behind a gripping face
            np.maximum(0.0, w - 2 * r) / r,  # fingers wider than the disk
            np.maximum(0.0, -ln) / r,
            np.maximum(0.0, -th0) + np.maximum(0.0, th0 - math.pi / 2),
            np.maximum(0.0, -d3) / r,
            np.maximum(0.0, -w) / r + np.maximum(0.0, w - ln) / r,
            np.maximum(0.0, -cols.torque_nm) / unit,
        )
        total = np.sum(parts, axis=0)
    return np.where(np.isfinite(total), total, math.inf)


def finger_gaps_m(des: np.ndarray, radius_m: np.ndarray, jaw_angles_rad: np.ndarray,
                  offset_x_m=0.0) -> np.ndarray:
    """Distance from each finger bar to the undeformed disk at given jaw angles [m], (B, 2).

    0 where a bar reaches into the disk. Used for the fingers that do not touch the disk in a
    grasp: how far they are from closing on it (the disk centre is fixed, so the undeformed
    circle is where the fingers would meet it). ``offset_x_m``: the centre's lateral offset
    ``x_c`` [m], scalar or (B,); the centre is at ``(x_c, d_1 + r)``.
    """
    ln, _, d3, w, _, d1 = (des[:, k] for k in range(N_DESIGN))
    centre_y = d1 + radius_m
    out = np.empty((des.shape[0], 2))
    for side, centre_x in enumerate((offset_x_m, -np.asarray(offset_x_m))):
        # frame of the right finger; the left one is its mirror image about the axis, which
        # sees the centre mirrored too
        s, c = np.sin(jaw_angles_rad[:, side]), np.cos(jaw_angles_rad[:, side])
        along = s * (centre_x - d3) + c * centre_y
        across = -c * (centre_x - d3) + s * centre_y
        out[:, side] = np.maximum(0.0, bar_distance(along, across, ln, w) - radius_m)
    return out


def _soft_disk(row: np.ndarray) -> SoftDisk:
    """The disk of a row of :func:`_disk_table` (its distance ``d_1`` comes from the design)."""
    radius, young, nu, thick, scale, ratio, area, offset = row.tolist()
    return SoftDisk(radius, 0.0, young, nu, thick, scale, ratio, area, offset_x_m=offset)


def _fill_fem(out: dict[str, np.ndarray], rows: np.ndarray, des: np.ndarray, disk: np.ndarray,
              kf: np.ndarray, cols: SceneColumns, fem_rings: int) -> None:
    """Solve the rows with the finite-element reference and write the same metrics as
    :func:`_fill_group` does for the point-spring model (same definitions, see
    :func:`evaluate_designs`)."""
    from .fem.designs import fem_design_grasps, fem_metrics

    scenes = [Design.from_array(des[i]).to_scene(_soft_disk(disk[i]), float(kf[i]))
              for i in rows.tolist()]
    fem = fem_metrics(fem_design_grasps(scenes, des[rows, TORQUE_COLUMN], fem_rings),
                      disk[rows, DISK_RADIUS], des[rows, DISTANCE_COLUMN] + disk[rows, DISK_RADIUS],
                      disk[rows, DISK_OFFSET_X])
    n_contacts = np.nan_to_num(fem["n_contacts"]).astype(np.int64)
    # each face's share of the rim, at most the Hertz width of its force (as for the PSM,
    # with the physical E the FEM solves with); NaN (not converged) stays NaN
    shares = np.empty(rows.size)
    for i, d in enumerate(disk[rows]):
        k = hertz_arc_coefficient(d[DISK_RADIUS], d[DISK_THICKNESS], d[DISK_YOUNG],
                                  d[DISK_POISSON])
        shares[i] = sum(contact_share(float(f), float(force), k) for f, force in
                        zip(fem["contact_fractions"][i], fem["face_force_n"][i], strict=True))
    with np.errstate(invalid="ignore"):
        grip = grip_share(cols, fem["jaw_angles_rad"], fem["stop_torques_nm"])
        metrics = {
            "jaw_angles_rad": fem["jaw_angles_rad"],
            "n_contacts": n_contacts,
            "touching": (n_contacts > 0) | (fem["tip_forces_n"] > 0.0),
            "total_force_n": fem["total_force_n"],
            "contact_score": grip * shares,
            "grip_share": grip,
            "peak_strain": fem["peak_strain"],
            "peak_log_strain": fem["peak_log_strain"],
            "max_displacement_ratio": fem["max_displacement_ratio"],
            "peak_compression": fem["peak_compression"],
            "pin_force_n": fem["pin_force_n"],
            "pin_moment_nm": fem["pin_moment_nm"],
            "required_friction": fem["required_friction"],
        }
    # (an infinite required friction is an answer, one finger touching: not a failure)
    floats = np.column_stack([np.reshape(v, (rows.size, -1)) for k, v in metrics.items()
                              if v.dtype.kind == "f" and k != "required_friction"])
    ok = fem["converged"] & np.isfinite(floats).all(axis=1)
    out["status"][rows] = np.where(ok, OK, FEM_FAILED)
    out["iterations"][rows] = fem["iterations"]
    out["n_triangles"][rows] = fem["n_elements"]
    out["stable"][rows] = ok  # Newton on the total energy with a descent line search
    out["converged"][rows] = ok
    for key, v in metrics.items():
        out[key][rows[ok]] = v[ok]


def _evaluate_arrays(des: np.ndarray, disk: np.ndarray, n_tri: np.ndarray, needs: np.ndarray,
                     kf: np.ndarray, weights: RewardWeights,
                     model: tuple[int, str, float] = (1, "spring", 1.0),
                     fidelity: str = "psm", fem_rings: int = FEM_DESIGN_RINGS
                     ) -> dict[str, np.ndarray]:
    """In-process evaluation of validated, normalized inputs (one row per design);
    ``needs``: each object's strain limit and friction coefficient (columns ``NEED_*``);
    ``model``: rings, element and the factor of the member's calibration on the disks'
    stiffness scale (``fidelity="psm"``); ``fem_rings``: the FEM mesh (``"fem"``)."""
    batch = des.shape[0]
    n_rings, element, model_scale = model
    out = _empty_output(batch)
    out["n_triangles"][:] = n_tri
    out["strain_limit"][:] = needs[:, NEED_STRAIN]
    out["friction_coefficient"][:] = needs[:, NEED_FRICTION]
    out["status"][:] = NOT_SOLVED
    material_scale = disk[:, DISK_SCALE]  # the disks' own (the contact width's modulus)
    if model_scale != 1.0:
        disk = disk.copy()
        disk[:, DISK_SCALE] *= model_scale
    cols = _columns(des, disk, kf)
    valid = rest_codes(cols) == REST_OK
    out["valid_at_rest"][:] = valid
    if not valid.all():
        # (skipped when every row is valid: a single env step pays ~0.1 ms for empty arrays)
        v = rest_violation(cols.take(~valid))
        # normalised to [0, 1] so that outputs stay finite (1: a non-finite design value)
        finite = np.isfinite(v)
        out["rest_violation"][~valid] = np.divide(v, 1.0 + v, out=np.ones_like(v),
                                                  where=finite)
    if fidelity == "fem":
        rows = np.flatnonzero(valid)
        out["n_triangles"][:] = 0
        if rows.size:
            _fill_fem(out, rows, des, disk, kf, cols.take(rows), fem_rings)
    for n in (np.unique(n_tri[valid]).tolist() if fidelity == "psm" else ()):
        rows = np.flatnonzero(valid & (n_tri == n))
        group = cols.take(rows)
        sol = solve_columns(group, n, phase_rad=DEFAULT_PHASE_RAD, n_rings=n_rings,
                            element=element)
        _fill_group(out, rows, sol, n, group, material_scale[rows])
    missing = out["converged"][:, None] & ~out["touching"]
    rows = np.flatnonzero(missing.any(axis=1))
    if rows.size:
        gaps = finger_gaps_m(des[rows], disk[rows, DISK_RADIUS], out["jaw_angles_rad"][rows],
                             disk[rows, DISK_OFFSET_X])
        out["finger_gap_m"][rows] = np.where(missing[rows], gaps, 0.0)
    out["holds"][:] = (out["converged"] & out["touching"].all(axis=1)
                       & (out["required_friction"] <= out["friction_coefficient"]))
    _add_reward(out, valid, disk[:, DISK_RADIUS], weights)
    return out


def _add_reward(out: dict[str, np.ndarray], valid: np.ndarray, radius_m: np.ndarray,
                w: RewardWeights) -> None:
    reward_rows(w.vector(), valid, out["converged"], out["contact_score"],
                out["peak_compression"], out["strain_limit"], out["touching"],
                out["finger_gap_m"], np.ascontiguousarray(radius_m, dtype=np.float64),
                out["rest_violation"], out["required_friction"], out["friction_coefficient"],
                out["reward_contact"], out["reward_deform"], out["penalty_slip"],
                out["penalty_miss"], out["penalty_gap"], out["penalty_invalid"],
                out["penalty_fail"], out["reward"])


def _evaluate_chunk(chunk: tuple[np.ndarray, ...], weights: RewardWeights,
                    model: tuple[int, str, float] = (1, "spring", 1.0), fidelity: str = "psm",
                    fem_rings: int = FEM_DESIGN_RINGS) -> dict[str, np.ndarray]:
    return _evaluate_arrays(*chunk, weights=weights, model=model, fidelity=fidelity,
                            fem_rings=fem_rings)


def _result_of(item):
    # dask-like executors return futures from map
    result = getattr(item, "result", None)
    return result() if callable(result) else item


def evaluate_designs(
    designs,
    disks,
    *,
    torsion_stiffness_rel=None,
    torsion_stiffness_nm_per_rad=None,
    n_triangles=None,
    weights: RewardWeights | None = None,
    strain_limits=None,
    friction_coefficients=None,
    offsets_x_m=None,
    executor=None,
    chunk_size: int | None = None,
    n_rings: int | None = None,
    element: str | None = None,
    calibrated: bool | None = None,
    fidelity: str = "psm",
    fem_rings: int = FEM_DESIGN_RINGS,
) -> dict[str, np.ndarray]:
    """Solve the grasp of every design and return its metrics and reward terms.

    Parameters
    ----------
    designs
        Array of shape (B, 6) in SI units with the columns of :data:`DESIGN_FIELDS`, a sequence
        of :class:`Design`, or one :class:`Design`.
    disks
        One :class:`~envs.scene.SoftDisk` for all rows or a sequence of B disks. Their radius,
        material, thickness and lateral offset ``offset_x_m`` are used; their ``distance_m`` is
        replaced by the design's ``distance_m`` column.
    torsion_stiffness_rel
        Joint torsion spring ``k_f`` relative to each row's object: in its torque unit
        ``s E t r^2`` per radian [1/rad] (:attr:`~envs.scene.SoftDisk.torque_unit_nm`, with the
        disk's own ``s``), > 0; scalar or shape (B,). The default (with
        ``torsion_stiffness_nm_per_rad`` also ``None``) is the paper gripper's 0.073 N·m/rad on
        its r = 0.07 m disk, 0.0149 per radian
        (:data:`~envs.model.defaults.PAPER_TORSION_STIFFNESS_REL`): the spring scales like the
        torque, so a relative design scores the same on every object whatever its size and
        stiffness (the model is scale invariant).
    torsion_stiffness_nm_per_rad
        An absolute joint spring ``k_f`` [N·m/rad] instead, > 0; scalar or shape (B,). Not
        with ``torsion_stiffness_rel``.
    n_triangles
        Contour points ``N``; scalar or shape (B,); ``None``: the member's default. Rows are
        grouped by N and each group is solved with one call of
        :func:`envs.solver.pipeline.solve_columns`.
    n_rings, element, calibrated
        The member of the model family every row is solved with, as in :func:`envs.simulate`
        (:func:`envs.model.family.resolve_model`): by default the default model (nh-quad,
        N = 40, M = 2, its shipped calibration); ``element="spring"`` is the paper's fan
        (N = 20).
    weights
        Reward weights (default :class:`RewardWeights`).
    strain_limits
        Admissible compressive strain of the object [-], in (0, 1], a limit on
        ``peak_compression``; scalar or shape (B,). Default :data:`DEFAULT_STRAIN_LIMIT`.
    friction_coefficients
        Coulomb friction coefficient between the fingers and the object [-], in (0, 10];
        scalar or shape (B,). A grasp that needs more (``required_friction``) does not hold
        the object once the centre is free: it scores below every grasp that holds
        (:class:`RewardWeights`). Default
        :data:`~envs.model.defaults.DEFAULT_FRICTION_COEFFICIENT` (0.5, a rubber or silicone
        pad on skin, fruit or tissue).
    offsets_x_m
        Placement of each object's centre across the gripper's axis, ``x_c`` [m] (the centre
        at ``(x_c, d_1 + r)``), any finite number; scalar or shape (B,). Replaces the disks'
        ``offset_x_m`` (default ``None``: theirs, 0 unless set). The displaced object is held
        where it was placed (its centre stays fixed while the jaws close): conservative across
        the axis, where a free object on a slippery surface would be pushed towards the
        middle. A displacement that brings the disk onto a finger at rest makes the row
        invalid at rest (:data:`~envs.model.problem.REST_OFFSET`); a displacement along the
        axis is a change of the design's ``distance_m``.
    executor
        ``None``: evaluate in this process (the rows of each N group run in parallel threads).
        Otherwise any object with ``.map(fn, iterable)`` (``concurrent.futures`` executors, a
        dask client wrapper, ...): the rows are cut into chunks of ``chunk_size`` that are
        evaluated with the same function, and the results are concatenated in order. Any
        start method works, ``"fork"`` included (the rows run on Python threads in compiled
        code that releases the GIL, :mod:`envs.parallel`, not on numba's OpenMP pool, which a
        forked child could not use). On one machine no executor beats the default: the
        in-process evaluation already runs the rows on every core.
    chunk_size
        Rows per chunk when an executor is given, >= 1 (default 256 at ``fidelity="psm"``, 1
        at ``"fem"``: one FEM grasp is worth shipping to a worker).
    fidelity
        ``"psm"`` (default): the point-spring model above. ``"fem"``: every design valid at
        rest is solved with the package's finite-element reference instead
        (:func:`envs.fem.fem_grasp`: quadratic triangles, neo-Hookean with the disk's physical
        ``E`` and ``nu``, the disk's calibration scales ignored) on a structured mesh of
        ``fem_rings`` rings (element size ``r / fem_rings``; the default 12 gives 864
        quadratic triangles, ~3,500 unknowns, within ~0.5 % of the mesh-converged closing
        angle), ramped from the open gripper to the design's torque. It costs about 10^4
        times the point-spring model (docs/performance.md) and is cached on disk per
        design (:func:`envs.fem.fem_cache_dir`: ``$PSM_GRASP_CACHE/fem``, default
        ``~/.cache/psm-grasp/fem``), so a design is solved
        once; with an executor the designs run in parallel (one per task by default). The
        keys, their meaning and the reward are the same at both fidelities (see below);
        ``n_triangles``, ``n_rings``, ``element`` and ``calibrated`` must be left ``None``.
    fem_rings
        Rings of the FEM mesh at ``fidelity="fem"``, in [2, 40].

    Returns
    -------
    dict[str, numpy.ndarray]
        One array per key of :data:`METRIC_KEYS`, first axis B. Never NaN: rows invalid at rest
        are not solved and rows whose solve failed keep zero metrics; both get their penalty.

        - ``valid_at_rest``: the scene can be built (fingers clear of the disk at rest, ...).
        - ``converged``: as in :func:`envs.simulate`: the solver claimed an equilibrium, the
          independent check of :mod:`envs.check` confirmed it, no fan triangle is turned over
          and every output is finite (FEM: Newton converged, no element inverted).
        - ``stable``, ``status``, ``iterations``: solver diagnostics; ``status`` is a public
          code of :mod:`envs.solver.status` (-1: not solved, 0: converged, 8: folded, 11: the
          independent check failed, 12: the FEM did not converge, ...; message in
          ``STATUS_MESSAGES``); FEM: Newton iterations.
        - ``n_triangles``: the model's contour points ``N`` (FEM: its quadratic triangles).
        - ``jaw_angles_rad`` (B, 2): right and left finger angles [rad].
        - ``n_contacts`` (B, 2): contour points pressed by each face (positive force; FEM:
          rim nodes).
        - ``touching`` (B, 2): each finger touches the disk (face or corner contact).
        - ``total_force_n`` (B, 2): normal force of each finger on the disk [N].
        - ``contact_score``: ``grip_share`` times the fraction of the contour in contact,
          summed over the two faces, each face's share the smaller of its pressed points
          ``n_contacts / N`` (each point stands for an arc ``2 pi r / N``) and the Hertz width
          of its face force (:mod:`envs.model.contact_width`: a contact narrower than a point
          spacing, a light touch, counts with its physical width, not a whole facet), as far
          as the actuation grips the object. FEM: the share of the rim's length whose nodes
          press on each face (each node with its share of the rim), capped alike: the same
          measure (the node count alone would let an optimizer exploit facets with forces
          near zero).
        - ``grip_share``: the share of the actuation torque that grips the object (not taken
          by the torsion springs or the joint stops), the smaller finger's (:func:`grip_share`):
          near 1 for a squeeze with little travel, 0 for fingers that merely touch the object
          (a torque tuned so that the springs stop the fingers at the object, with contact
          forces of 1e-7 N, earns no contact).
        - ``peak_strain``: max ``|L - L0| / L0`` over the springs (mesh edges) [-]; FEM:
          the largest principal engineering strain ``max |lambda - 1|``, the largest length
          change of any fibre (an edge's strain never exceeds it).
        - ``peak_log_strain``: largest principal logarithmic strain ``max |ln lambda|`` over
          the triangles outside twice the hub radius [-]; FEM: the same over its quadrature
          points outside twice the hub radius.
        - ``max_displacement_ratio``: max contour-point displacement / r [-] (FEM: rim
          nodes).
        - ``peak_compression``: the largest shortening of a radius by the fingers,
          ``max (r - |p - C|) / r`` over the contour points ``p`` [-] (FEM: rim nodes), i.e.
          the engineering strain of the most compressed radius, how deep the grasp presses
          into the object; the deformation the reward penalises. Unlike the peak strain, whose
          value under a finger's tip corner (a point load) depends on the mesh in either model,
          it converges with the mesh, and the default model and the FEM rank designs by it
          alike (docs/accuracy.md).
        - ``strain_limit``: the limit used [-].
        - ``pin_force_n`` (B, 2): the force the fixed centre exerts on the object, x and y in
          the gripper frame [N]: what the frictionless contacts leave unbalanced (inclined jaws
          push the object out of the grip, along +y); ``pin_moment_nm``: its moment about the
          centre [N·m] (a hub's; ~0 for the fan's pin). FEM: the hub's reaction.
        - ``required_friction``: the smallest Coulomb coefficient with which friction at the
          contacts could carry that force and moment instead of the centre [-]
          (:mod:`envs.model.holding`): 0 when nothing is carried, ``inf`` when no friction
          can (one finger touching); ``tan(theta)`` for a symmetric grasp on the faces at
          finger angle ``theta``.
        - ``friction_coefficient``: the coefficient used [-]; ``holds``: a converged grasp
          touching with both fingers whose required friction is within it (it would hold
          the object without the pin).
        - ``finger_gap_m`` (B, 2): for a converged grasp, the distance from each finger that
          does not touch the disk to the undeformed disk [m] (0 for a touching finger).
        - ``rest_violation``: for a design invalid at rest, how far it is from valid,
          ``v / (1 + v)`` in [0, 1] with ``v`` of :func:`rest_violation` (1 for a non-finite
          value); 0 for valid designs.
        - ``reward_contact``, ``reward_deform``, ``penalty_slip``, ``penalty_miss``,
          ``penalty_gap``,
          ``penalty_invalid``, ``penalty_fail``: signed reward terms (see
          :class:`RewardWeights`); ``reward`` is their sum.

    Raises
    ------
    ValueError
        For malformed inputs (shapes, disks, N, strain limits, ``k_f``, offsets). Physically
        invalid designs do not raise.
    """
    weights = RewardWeights() if weights is None else weights
    if not isinstance(weights, RewardWeights):
        raise ValueError(f"weights must be a RewardWeights, got {type(weights).__name__}")
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    if fidelity == "fem":
        given = [name for name, v in (("n_triangles", n_triangles), ("n_rings", n_rings),
                                      ("element", element), ("calibrated", calibrated))
                 if v is not None]
        if given:
            raise ValueError(f"{', '.join(given)} choose a point-spring member: leave them None "
                             "with fidelity='fem' (its mesh is set by fem_rings)")
        fem_rings = check_integer("fem_rings", fem_rings, 2, FEM_MAX_RINGS)
    des = _design_table(designs)
    batch = des.shape[0]
    disk = _disk_table(disks, batch)
    n_each = np.asarray(n_triangles, dtype=object)
    spec = resolve_model(None if n_each.ndim else n_triangles, n_rings,
                         DEFAULT_ELEMENT if element is None else element, calibrated)
    n_min, n_max = triangle_range(spec.n_rings, spec.element)
    n_tri = _per_row("n_triangles", spec.n_triangles if n_each.ndim == 0 else n_triangles,
                     batch, n_min, n_max, low_open=False, integer=True)
    if n_each.ndim and spec.element == "cst" and spec.scale != 1.0:
        raise ValueError("a calibrated constant-strain member has one N (its scale depends on "
                         "N): pass a scalar n_triangles")
    model = (spec.n_rings, spec.element, spec.scale)
    needs = np.empty((batch, 2))
    needs[:, NEED_STRAIN] = _per_row(
        "strain_limits", DEFAULT_STRAIN_LIMIT if strain_limits is None else strain_limits,
        batch, 0.0, 1.0, low_open=True)
    needs[:, NEED_FRICTION] = _per_row(
        "friction_coefficients", DEFAULT_FRICTION_COEFFICIENT if friction_coefficients is None
        else friction_coefficients, batch, 0.0, MAX_FRICTION_COEFFICIENT, low_open=True)
    kf = _joint_springs(torsion_stiffness_rel, torsion_stiffness_nm_per_rad, disk, batch)
    if offsets_x_m is not None:
        disk[:, DISK_OFFSET_X] = _per_row("offsets_x_m", offsets_x_m, batch, -math.inf,
                                          math.inf, low_open=False)
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE if fidelity == "psm" else 1
    if isinstance(chunk_size, bool) or int(chunk_size) != chunk_size or chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    if executor is None:
        return _evaluate_arrays(des, disk, n_tri, needs, kf, weights, model, fidelity,
                                fem_rings)
    if not callable(getattr(executor, "map", None)):
        raise ValueError("executor must have a .map(fn, iterable) method")
    starts = range(0, batch, int(chunk_size))
    chunks = [tuple(a[s : s + int(chunk_size)] for a in (des, disk, n_tri, needs, kf))
              for s in starts]
    fn = functools.partial(_evaluate_chunk, weights=weights, model=model, fidelity=fidelity,
                           fem_rings=fem_rings)
    parts = [_result_of(p) for p in executor.map(fn, chunks)]
    if not parts:
        return _empty_output(0)
    return {k: np.concatenate([p[k] for p in parts]) for k in METRIC_KEYS}
