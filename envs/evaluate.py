"""Batched evaluation of gripper designs: designs -> grasp metrics and named reward terms.

:func:`evaluate_designs` is the one physics entry point of the design environment and of the
optimizers. It takes a whole population of designs at once (like pymoo's ``_evaluate``), solves
every grasp with the compiled batch solver :func:`envs.kernels.solve_batch` (rows run in parallel
threads) and computes the metrics and the reward terms vectorized in numpy. Parallelism beyond one
process is injected through ``executor`` (anything with ``.map``), never hard-coded.

A design is six numbers in SI units, in the column order of :data:`DESIGN_FIELDS`:

====  ====================  ===============================================  =======
col   field                 meaning                                          unit
====  ====================  ===============================================  =======
0     ``finger_length_m``   finger length ``l`` (joint to tip)               m
1     ``rest_angle_rad``    rest angle ``theta_a0`` of both fingers from +y  rad
2     ``joint_offset_m``    joint distance ``d_3`` from the symmetry axis    m
3     ``finger_width_m``    finger width ``w``                               m
4     ``torque_nm``         actuation torque ``T_a`` on each finger          N·m
5     ``distance_m``        object placement ``d_1`` (joints' line to disk)  m
====  ====================  ===============================================  =======
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numba
import numpy as np

from . import kernels, psm
from .psm import (
    MAX_TRIANGLES,
    MIN_TRIANGLES,
    N_PARAMS,
    P_C0X,
    P_C0Y,
    P_C1X,
    P_C1Y,
    P_H,
    P_HW,
    P_KAPPA,
    P_KC,
    P_KR,
    P_LMAX,
    P_PHASE,
    P_TAU,
    P_TH0,
    P_THMIN,
    rest_points,
    scaled_problem,
    spring_stiffness,
)
from .scene import Gripper, Scene, SoftDisk, check_range

__all__ = [
    "DESIGN_FIELDS",
    "DEFAULT_STRAIN_LIMIT",
    "METRIC_KEYS",
    "Design",
    "DesignBounds",
    "RewardWeights",
    "evaluate_designs",
]

DESIGN_FIELDS = (
    "finger_length_m",
    "rest_angle_rad",
    "joint_offset_m",
    "finger_width_m",
    "torque_nm",
    "distance_m",
)
N_DESIGN = len(DESIGN_FIELDS)
DEFAULT_STRAIN_LIMIT = 0.1
DEFAULT_CHUNK_SIZE = 256
PHASE_RAD = math.pi / 2  # first contour point at the top: mirror-symmetric for even N

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
    "peak_strain": (np.float64, ()),
    "max_displacement_ratio": (np.float64, ()),
    "strain_limit": (np.float64, ()),
    "reward_contact": (np.float64, ()),
    "reward_deform": (np.float64, ()),
    "penalty_miss": (np.float64, ()),
    "penalty_invalid": (np.float64, ()),
    "penalty_fail": (np.float64, ()),
    "reward": (np.float64, ()),
}
NOT_SOLVED = -1  # status of rows that were not solved (invalid at rest)


@dataclass(frozen=True)
class Design:
    """One gripper design and object placement, in SI units.

    A design may be physically impossible (fingers overlapping the disk, width larger than the
    length, ...): :func:`evaluate_designs` reports it with ``valid_at_rest=False`` and the invalid
    penalty instead of raising, so that optimizers can explore freely.

    Parameters
    ----------
    finger_length_m
        Finger length ``l`` from joint to tip [m].
    rest_angle_rad
        Rest angle ``theta_a0`` of both fingers, from the +y axis [rad].
    joint_offset_m
        Joint distance ``d_3`` from the symmetry axis [m].
    finger_width_m
        Finger width ``w`` [m].
    torque_nm
        Actuation torque ``T_a`` on each finger [N·m].
    distance_m
        Distance ``d_1`` from the joints' line to the nearest point of the undeformed disk [m].
    """

    finger_length_m: float
    rest_angle_rad: float
    joint_offset_m: float
    finger_width_m: float
    torque_nm: float
    distance_m: float

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, float(getattr(self, f.name)))

    def to_array(self) -> np.ndarray:
        """The design as a float64 array of shape (6,) in :data:`DESIGN_FIELDS` order."""
        return np.array([getattr(self, name) for name in DESIGN_FIELDS], dtype=np.float64)

    @classmethod
    def from_array(cls, values) -> Design:
        """Build a design from 6 numbers in :data:`DESIGN_FIELDS` order."""
        arr = np.asarray(values, dtype=np.float64)
        if arr.shape != (N_DESIGN,):
            raise ValueError(f"a design needs shape ({N_DESIGN},), got {arr.shape}")
        return cls(*arr.tolist())


@dataclass(frozen=True)
class DesignBounds:
    """Box of the design space, used to map actions in [-1, 1] to physical designs.

    The defaults bracket the paper scenes (Tables 1 and 2: ``l = 0.2`` m, ``theta_a0 = 45`` deg,
    ``d_3 = 0.025`` m, ``w = 0.01`` m, ``d_1`` = 4 to 25 mm). Parts of the box are invalid at rest
    (fingers overlapping the disk); those designs get the invalid penalty.

    Parameters
    ----------
    low, high
        Lower and upper bound of each column of :data:`DESIGN_FIELDS` (SI units), ``low < high``.
    """

    low: tuple[float, ...] = (0.05, math.radians(15.0), 0.0, 0.002, 0.0, 0.0)
    high: tuple[float, ...] = (0.30, math.radians(75.0), 0.05, 0.03, 1.0, 0.06)

    def __post_init__(self) -> None:
        for name in ("low", "high"):
            vals = tuple(float(v) for v in getattr(self, name))
            if len(vals) != N_DESIGN:
                raise ValueError(f"DesignBounds.{name} needs {N_DESIGN} values, got {len(vals)}")
            for field_name, v in zip(DESIGN_FIELDS, vals, strict=True):
                check_range(f"DesignBounds.{name}[{field_name}]", v)
            object.__setattr__(self, name, vals)
        for field_name, lo, hi in zip(DESIGN_FIELDS, self.low, self.high, strict=True):
            if not lo < hi:
                raise ValueError(
                    f"DesignBounds for {field_name}: low = {lo!r} must be smaller than "
                    f"high = {hi!r}"
                )

    @property
    def low_array(self) -> np.ndarray:
        """Lower bounds as a float64 array (6,)."""
        return np.array(self.low, dtype=np.float64)

    @property
    def high_array(self) -> np.ndarray:
        """Upper bounds as a float64 array (6,)."""
        return np.array(self.high, dtype=np.float64)

    def scale(self, action) -> np.ndarray:
        """Map normalized actions in [-1, 1] (shape (..., 6)) to physical designs (SI)."""
        a = np.asarray(action, dtype=np.float64)
        lo, hi = self.low_array, self.high_array
        return lo + 0.5 * (a + 1.0) * (hi - lo)

    def unscale(self, design) -> np.ndarray:
        """Map physical designs (shape (..., 6), SI) to normalized actions (inverse of scale)."""
        d = np.asarray(design, dtype=np.float64)
        lo, hi = self.low_array, self.high_array
        return 2.0 * (d - lo) / (hi - lo) - 1.0

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Draw ``size`` designs uniformly in the box, shape (size, 6)."""
        return self.scale(rng.uniform(-1.0, 1.0, size=(int(size), N_DESIGN)))


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms of :func:`evaluate_designs`.

    ``reward = contact * min(contact_score, contact_cap)
    - deform * min(peak_strain / strain_limit, deform_cap)
    - miss * (fingers not touching) - invalid * (invalid at rest) - fail * (not converged)``.

    The defaults order the outcomes: any valid converged grasp (>= -2) scores above a solver
    failure (-2.5), which scores above an invalid design (-3).

    Parameters
    ----------
    contact
        Weight of the contact score (fraction of the contour in contact) [-].
    deform
        Weight of the peak strain relative to the object's strain limit [-].
    miss
        Penalty per finger that does not touch the disk [-].
    invalid
        Penalty for a design that is invalid at rest (fingers overlapping the disk, ...) [-].
    fail
        Penalty when the solver did not converge [-].
    contact_cap
        Cap of the contact score [-], > 0.
    deform_cap
        Cap of ``peak_strain / strain_limit`` [-], > 0 (keeps the reward bounded).
    """

    contact: float = 1.0
    deform: float = 0.25
    miss: float = 0.5
    invalid: float = 3.0
    fail: float = 2.5
    contact_cap: float = 0.5
    deform_cap: float = 4.0

    def __post_init__(self) -> None:
        for f in fields(self):
            low_open = f.name.endswith("_cap")
            v = check_range(f"RewardWeights.{f.name}", getattr(self, f.name), 0.0, math.inf,
                            low_open=low_open)
            object.__setattr__(self, f.name, v)


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


def _disk_table(disks, batch: int) -> np.ndarray:
    """Columns: radius, Young's modulus, Poisson ratio, thickness, stiffness scale, contour
    stiffness ratio."""
    if isinstance(disks, SoftDisk):
        disks = [disks] * batch
    elif not isinstance(disks, Sequence) or len(disks) != batch:
        raise ValueError(f"disks must be a SoftDisk or a sequence of {batch} SoftDisks")
    rows = []
    for i, d in enumerate(disks):
        if not isinstance(d, SoftDisk):
            raise ValueError(f"disks[{i}] must be a SoftDisk, got {type(d).__name__}")
        rows.append((d.radius_m, d.youngs_modulus_pa, d.poisson_ratio, d.thickness_m,
                     d.stiffness_scale, d.contour_stiffness_ratio))
    return np.array(rows, dtype=np.float64).reshape(batch, 6)


def _per_row(name: str, value, batch: int, low: float, high: float, *, low_open: bool,
             integer: bool = False) -> np.ndarray:
    arr = np.asarray(value)
    if arr.ndim == 0:
        arr = np.full(batch, arr.item())
    if arr.shape != (batch,):
        raise ValueError(f"{name} must be a scalar or have shape ({batch},), got {arr.shape}")
    out = np.empty(batch, dtype=np.int64 if integer else np.float64)
    for i, v in enumerate(arr.tolist()):
        if integer and (isinstance(v, bool) or int(v) != v):
            raise ValueError(f"{name}[{i}] must be an integer, got {v!r}")
        out[i] = check_range(f"{name}[{i}]", v, low, high, low_open=low_open)
    return out


# ---------------------------------------------------------------------------------------------
# packing: the vectorized equivalent of Scene(...) validation + scaled_problem(...).params


def _valid_at_rest(des: np.ndarray, radius: np.ndarray, cos0: np.ndarray, sin0: np.ndarray,
                   clearance: np.ndarray) -> np.ndarray:
    """The checks of Gripper, SoftDisk, Scene and scaled_problem, row by row (mirror-symmetric,
    so the right finger decides for both)."""
    ln, th0, d3, w, torque, d1 = des.T
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(des), axis=1)
        ok &= (ln > 0) & (th0 > 0) & (th0 < math.pi / 2) & (d3 >= 0)
        ok &= (w > 0) & (w < ln) & (torque >= 0) & (w < 2 * radius)
        # disk centre in front of the gripping face: n . (C - J) - w/2 > 0
        ok &= cos0 * d3 + sin0 * (d1 + radius) - w / 2 > 0
        ok &= clearance > 0
    return ok


def _rest_geometry(des: np.ndarray, radius: np.ndarray):
    """cos/sin of the rest angle, the rest clearance of the disk to a finger bar and the closed
    angle, with the scalar ``math`` functions of scene.py so that values match it exactly."""
    batch = des.shape[0]
    cos0, sin0 = np.zeros(batch), np.zeros(batch)
    clearance, th_min = np.full(batch, -1.0), np.zeros(batch)
    for i in range(batch):
        ln, th0, d3, w, _, d1 = des[i].tolist()
        r = float(radius[i])
        if not all(math.isfinite(v) for v in (ln, th0, d3, w, d1)) or ln <= 0 or w <= 0:
            continue
        s, c = math.sin(th0), math.cos(th0)
        cos0[i], sin0[i] = c, s
        yc = d1 + r
        # right finger: J = (d3, 0), e = (s, c), n = (-c, s); rel = C - J = (-d3, yc)
        along = s * (0.0 - d3) + c * yc
        across = -c * (0.0 - d3) + s * yc
        hw = w / 2
        ds = max(0.0, -along, along - ln)
        dm = max(0.0, across - hw, -hw - across)
        clearance[i] = math.hypot(ds, dm) - r
        th_min[i] = math.atan2(hw, ln) - math.asin(min(1.0, d3 / math.hypot(ln, hw)))
    return cos0, sin0, clearance, th_min


def _scene_params(des_row: np.ndarray, disk_row: np.ndarray, n: int, kf: float) -> np.ndarray:
    """``scaled_problem(...).params`` of one valid row, through the real Scene (slow path)."""
    ln, th0, d3, w, torque, d1 = des_row.tolist()
    r, young, nu, thick, scale, ratio = disk_row.tolist()
    scene = Scene(Gripper(ln, th0, d3, w, kf),
                  SoftDisk(r, d1, young, nu, thick, scale, contour_stiffness_ratio=ratio))
    return scaled_problem(scene, torque, int(n), "van_gelder", PHASE_RAD).params


_PACK_VERIFIED: set[int] = set()  # N values whose fast packing matched scaled_problem


def _pack(des: np.ndarray, disk: np.ndarray, n_tri: np.ndarray, kf: np.ndarray):
    """Validity mask and solver parameter rows (zeros for invalid rows).

    The vectorized packing is checked against :func:`envs.psm.scaled_problem` on the first
    valid row; if they differ (the parameter layout changed in ``psm``), every valid row is
    packed by ``scaled_problem`` itself, with a warning: correct, only slower.
    """
    valid, prm = _pack_fast(des, disk, n_tri, kf)
    rows = np.flatnonzero(valid)
    if rows.size == 0:
        return valid, prm
    first = rows[0]
    if int(n_tri[first]) in _PACK_VERIFIED:
        # checked once per process and N: the code cannot change under a running process,
        # and the slow path (a Scene with its reach check) would double a single step's cost
        return valid, prm
    ref = _scene_params(des[first], disk[first], n_tri[first], kf[first])
    if ref.shape == prm[first].shape and np.array_equal(ref, prm[first]):
        _PACK_VERIFIED.add(int(n_tri[first]))
        return valid, prm
    warnings.warn(
        "evaluate_designs: the vectorized parameter packing differs from "
        "envs.psm.scaled_problem (layout changed?); packing row by row instead (slower). "
        "Update envs.evaluate._pack_fast.", RuntimeWarning, stacklevel=3,
    )
    prm = np.zeros((des.shape[0], ref.size))
    for i in rows.tolist():
        prm[i] = _scene_params(des[i], disk[i], n_tri[i], kf[i])
    return valid, prm


def _pack_fast(des: np.ndarray, disk: np.ndarray, n_tri: np.ndarray, kf: np.ndarray):
    """Vectorized Scene validation + scaled_problem packing; params shape (B, N_PARAMS)."""
    radius, young, _, thick, scale, ratio = disk.T
    cos0, sin0, clearance, th_min = _rest_geometry(des, radius)
    valid = _valid_at_rest(des, radius, cos0, sin0, clearance)
    prm = np.zeros((des.shape[0], N_PARAMS))
    ln, th0, d3, w, torque, d1 = np.where(valid[:, None], des, 0.0).T
    k_unit = scale * young * thick
    kr2 = k_unit * radius**2
    for n in np.unique(n_tri).tolist():
        rows = n_tri == n
        k_int, k_ext = spring_stiffness(n, 1.0, "van_gelder")
        prm[rows, P_KR], prm[rows, P_KC] = k_int, k_ext * ratio[rows]
        prm[rows, P_H] = 2 * math.sin(math.pi / n)
    yc = (d1 + radius) / radius
    prm[:, P_C0X], prm[:, P_C0Y] = (0.0 - d3) / radius, yc
    prm[:, P_C1X], prm[:, P_C1Y] = (0.0 + d3) / radius, yc
    prm[:, P_HW] = w / (2 * radius)
    prm[:, P_LMAX] = ln / radius
    prm[:, P_TAU] = torque / kr2
    prm[:, P_KAPPA] = kf / kr2
    prm[:, P_TH0] = th0
    prm[:, P_THMIN] = th_min
    prm[:, P_PHASE] = PHASE_RAD
    corner_radius = getattr(psm, "corner_radius", None)
    if corner_radius is not None and hasattr(psm, "P_RHO"):
        # rounded finger corners (newer parameter layout); _pack checks the result anyway
        prm[:, psm.P_RHO] = [corner_radius(wi, ri) / ri
                             for wi, ri in zip(w.tolist(), radius.tolist(), strict=True)]
    prm[~valid] = 0.0
    return valid, prm


# ---------------------------------------------------------------------------------------------
# solve and metrics


def _solve_group(n: int, prm: np.ndarray) -> dict[str, np.ndarray]:
    """Solve rows with the same N; return the raw metrics (vectorized, no GraspResult)."""
    g = prm.shape[0]
    rest = rest_points(n, PHASE_RAD)
    xs = np.empty((g, 2 * n + 2))
    xs[:, : 2 * n] = rest.ravel()
    xs[:, 2 * n] = prm[:, P_TH0]
    xs[:, 2 * n + 1] = prm[:, P_TH0]
    lam_face = np.zeros((g, 2, n))
    lam_corner = np.zeros((g, 2, 4, n))
    lam_stop = np.zeros(2 * g).reshape(g, 2)
    corner_cand = np.zeros((g, 2, 4, n), dtype=np.bool_)
    cand = np.zeros((g, 2, n), dtype=np.bool_)
    infos = np.zeros((g, 8))
    opts = kernels.default_options()
    prm = np.ascontiguousarray(prm)
    if g == 1:
        # a single row needs no thread pool (and stays fork-safe in process-based vector envs)
        kernels.solve_one(n, prm[0], opts, xs[0], lam_face[0], lam_corner[0], lam_stop[0],
                          corner_cand[0], cand[0], infos[0])
    else:
        # dynamic scheduling, one row at a time: solve times vary by 100x between rows (a row
        # hitting the iteration limit), so static blocks would leave threads idle
        with numba.parallel_chunksize(1):
            kernels.solve_batch(n, prm, opts, xs, lam_face, lam_corner, lam_stop, corner_cand, cand,
                                infos)
    q = xs[:, : 2 * n].reshape(g, n, 2)
    radial = np.sqrt(q[..., 0] * q[..., 0] + q[..., 1] * q[..., 1]) - 1.0
    d = np.roll(q, -1, axis=1) - q
    contour = np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) / prm[:, P_H, None] - 1.0
    du = q - rest
    disp = np.sqrt(du[..., 0] * du[..., 0] + du[..., 1] * du[..., 1])
    return {
        "status": infos[:, 0].astype(np.int64),
        "iterations": infos[:, 1].astype(np.int64),
        "stable": infos[:, 3] != 0.0,
        "jaw_angles_rad": xs[:, 2 * n :].copy(),
        "n_contacts": np.count_nonzero(lam_face > 0.0, axis=2).astype(np.int64),
        "corner_force": lam_corner.sum(axis=(2, 3)),
        "face_force": lam_face.sum(axis=2),
        "peak_strain": np.maximum(np.abs(radial).max(axis=1), np.abs(contour).max(axis=1)),
        "max_displacement_ratio": disp.max(axis=1),
    }


def _empty_output(batch: int) -> dict[str, np.ndarray]:
    return {k: np.zeros((batch, *shape), dtype=dt) for k, (dt, shape) in METRIC_KEYS.items()}


def _evaluate_arrays(des: np.ndarray, disk: np.ndarray, n_tri: np.ndarray, limits: np.ndarray,
                     kf: np.ndarray, weights: RewardWeights) -> dict[str, np.ndarray]:
    """In-process evaluation of validated, normalized inputs (one row per design)."""
    batch = des.shape[0]
    out = _empty_output(batch)
    out["n_triangles"][:] = n_tri
    out["strain_limit"][:] = limits
    out["status"][:] = NOT_SOLVED
    valid, prm = _pack(des, disk, n_tri, kf)
    out["valid_at_rest"][:] = valid
    force_unit = disk[:, 4] * disk[:, 1] * disk[:, 3] * disk[:, 0]  # s E t r [N]
    for n in np.unique(n_tri[valid]).tolist():
        rows = np.flatnonzero(valid & (n_tri == n))
        raw = _solve_group(n, prm[rows])
        force = (raw["face_force"] + raw["corner_force"]) * force_unit[rows, None]
        metrics = {
            "jaw_angles_rad": raw["jaw_angles_rad"],
            "n_contacts": raw["n_contacts"],
            "touching": (raw["n_contacts"] > 0) | (raw["corner_force"] > 0.0),
            "total_force_n": force,
            "contact_score": raw["n_contacts"].sum(axis=1) / n,
            "peak_strain": raw["peak_strain"],
            "max_displacement_ratio": raw["max_displacement_ratio"],
        }
        finite = np.ones(rows.size, dtype=bool)
        for v in metrics.values():
            finite &= np.all(np.isfinite(v.reshape(rows.size, -1)), axis=1)
        ok = (raw["status"] == kernels.OK) & finite
        out["status"][rows] = raw["status"]
        out["iterations"][rows] = raw["iterations"]
        out["stable"][rows] = raw["stable"]
        out["converged"][rows] = ok
        for key, v in metrics.items():
            # failed rows keep the zeros: finite, and the fail penalty says what happened
            out[key][rows[ok]] = v[ok]
    _add_reward(out, valid, weights)
    return out


def _add_reward(out: dict[str, np.ndarray], valid: np.ndarray, w: RewardWeights) -> None:
    ok = out["converged"]
    score = np.minimum(out["contact_score"], w.contact_cap)
    strain_ratio = np.minimum(out["peak_strain"] / out["strain_limit"], w.deform_cap)
    out["reward_contact"][:] = np.where(ok, w.contact * score, 0.0)
    out["reward_deform"][:] = np.where(ok, 0.0 - w.deform * strain_ratio, 0.0)
    missing = np.count_nonzero(~out["touching"], axis=1)
    out["penalty_miss"][:] = np.where(ok, 0.0 - w.miss * missing, 0.0)
    out["penalty_invalid"][:] = np.where(valid, 0.0, 0.0 - w.invalid)
    out["penalty_fail"][:] = np.where(valid & ~ok, 0.0 - w.fail, 0.0)
    out["reward"][:] = (out["reward_contact"] + out["reward_deform"] + out["penalty_miss"]
                        + out["penalty_invalid"] + out["penalty_fail"])


def _evaluate_chunk(chunk: tuple[np.ndarray, ...], weights: RewardWeights
                    ) -> dict[str, np.ndarray]:
    return _evaluate_arrays(*chunk, weights=weights)


def _result_of(item):
    # dask-like executors return futures from map
    result = getattr(item, "result", None)
    return result() if callable(result) else item


def evaluate_designs(
    designs,
    disks,
    *,
    torsion_stiffness_nm_per_rad=0.073,
    n_triangles=20,
    weights: RewardWeights | None = None,
    strain_limits=None,
    executor=None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
) -> dict[str, np.ndarray]:
    """Solve the grasp of every design and return its metrics and reward terms.

    Parameters
    ----------
    designs
        Array of shape (B, 6) in SI units with the columns of :data:`DESIGN_FIELDS`, a sequence
        of :class:`Design`, or one :class:`Design`.
    disks
        One :class:`~envs.scene.SoftDisk` for all rows or a sequence of B disks. Their radius,
        material and thickness are used; their ``distance_m`` is replaced by the design's
        ``distance_m`` column.
    torsion_stiffness_nm_per_rad
        Joint torsion spring ``k_f`` [N·m/rad], > 0; scalar or shape (B,).
    n_triangles
        Number of fan triangles ``N``; scalar or shape (B,). Rows are grouped by N and each group
        is solved with one call of :func:`envs.kernels.solve_batch`.
    weights
        Reward weights (default :class:`RewardWeights`).
    strain_limits
        Admissible strain of the object [-], in (0, 1]; scalar or shape (B,). Default
        :data:`DEFAULT_STRAIN_LIMIT`.
    executor
        ``None``: evaluate in this process (the rows of each N group run in parallel threads).
        Otherwise any object with ``.map(fn, iterable)`` (``concurrent.futures`` executors, a
        dask client wrapper, ...): the rows are cut into chunks of ``chunk_size`` that are
        evaluated with the same function, and the results are concatenated in order. With a
        process pool, prefer the ``"spawn"`` or ``"forkserver"`` start method (the numba
        OpenMP thread pool is not fork-safe).
    chunk_size
        Rows per chunk when an executor is given, >= 1.

    Returns
    -------
    dict[str, numpy.ndarray]
        One array per key of :data:`METRIC_KEYS`, first axis B. Never NaN: rows invalid at rest
        are not solved and rows whose solve failed keep zero metrics; both get their penalty.

        - ``valid_at_rest``: the scene can be built (fingers clear of the disk at rest, ...).
        - ``converged``: solver status OK (``status == 0``) and finite outputs. Unlike
          :func:`envs.solver.simulate`, the independent KKT check is not run here.
        - ``stable``, ``status`` (-1: not solved), ``iterations``: solver diagnostics.
        - ``jaw_angles_rad`` (B, 2): right and left finger angles [rad].
        - ``n_contacts`` (B, 2): contour points pressed by each face (positive force).
        - ``touching`` (B, 2): each finger touches the disk (face or corner contact).
        - ``total_force_n`` (B, 2): normal force of each finger on the disk [N].
        - ``contact_score``: ``(n_contacts_right + n_contacts_left) / N``, the fraction of the
          contour in contact (each point stands for an arc ``2 pi r / N``), so it barely
          depends on N.
        - ``peak_strain``: max ``|L - L0| / L0`` over radial and contour springs [-].
        - ``max_displacement_ratio``: max contour-point displacement / r [-].
        - ``strain_limit``: the limit used [-].
        - ``reward_contact``, ``reward_deform``, ``penalty_miss``, ``penalty_invalid``,
          ``penalty_fail``: signed reward terms (see :class:`RewardWeights`); ``reward`` is
          their sum.

    Raises
    ------
    ValueError
        For malformed inputs (shapes, disks, N, strain limits, ``k_f``). Physically invalid
        designs do not raise.
    """
    weights = RewardWeights() if weights is None else weights
    if not isinstance(weights, RewardWeights):
        raise ValueError(f"weights must be a RewardWeights, got {type(weights).__name__}")
    des = _design_table(designs)
    batch = des.shape[0]
    disk = _disk_table(disks, batch)
    n_tri = _per_row("n_triangles", n_triangles, batch, MIN_TRIANGLES, MAX_TRIANGLES,
                     low_open=False, integer=True)
    limits = _per_row("strain_limits", DEFAULT_STRAIN_LIMIT if strain_limits is None
                      else strain_limits, batch, 0.0, 1.0, low_open=True)
    kf = _per_row("torsion_stiffness_nm_per_rad", torsion_stiffness_nm_per_rad, batch, 0.0,
                  math.inf, low_open=True)
    if executor is None:
        return _evaluate_arrays(des, disk, n_tri, limits, kf, weights)
    if isinstance(chunk_size, bool) or int(chunk_size) != chunk_size or chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    if not callable(getattr(executor, "map", None)):
        raise ValueError("executor must have a .map(fn, iterable) method")
    starts = range(0, batch, int(chunk_size))
    chunks = [tuple(a[s : s + int(chunk_size)] for a in (des, disk, n_tri, limits, kf))
              for s in starts]
    fn = functools.partial(_evaluate_chunk, weights=weights)
    parts = [_result_of(p) for p in executor.map(fn, chunks)]
    if not parts:
        return _empty_output(0)
    return {k: np.concatenate([p[k] for p in parts]) for k in METRIC_KEYS}
