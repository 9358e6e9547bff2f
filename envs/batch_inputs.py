"""The inputs of a batch of designs, validated and laid out as columns: the design table, the
disks' table (``DISK_*``), the objects' needs (``NEED_*``: strain limit, friction, payload)
and the joint springs. One bad row is named by its index.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .model.defaults import (
    MAX_PAYLOAD_FACTOR,
    MAX_SPRING_REL,
    PAPER_TORSION_STIFFNESS_REL,
    PLAUSIBLE_RANGES,
)
from .model.jaw import DESIGN_WIDTHS, JAW_FIELDS, LEFT_JAW_FIELDS
from .model.layout import N_OUTLINE
from .scene import (
    DESIGN_FIELDS,
    N_DESIGN,
    SPRING_TWICE,
    Design,
    SoftDisk,
)
from .validation import check_integer, check_range, real_array

# ---------------------------------------------------------------------------------------------
# input normalization


def _design_table(designs) -> np.ndarray:
    """The design rows as a float64 table (B, 6), (B, 10) or (B, 14) (columns
    :data:`~envs.scene.ALL_DESIGN_FIELDS`); a sequence of :class:`Design` objects as wide as
    its widest one."""
    if isinstance(designs, Design):
        return designs.to_array()[None, :]
    if isinstance(designs, Sequence) and len(designs) > 0 and isinstance(designs[0], Design):
        if not all(isinstance(d, Design) for d in designs):
            raise ValueError("designs mixes Design objects and other values")
        width = max(d.width for d in designs)
        return np.stack([d.to_array(width) for d in designs])
    arr = real_array("designs", designs, f"numbers of shape (B, {N_DESIGN})")
    if arr.ndim != 2 or arr.shape[1] not in DESIGN_WIDTHS:
        raise ValueError(
            f"designs must have shape (B, {N_DESIGN}) with columns {DESIGN_FIELDS}, or (B, 10) "
            f"or (B, 14) with the jaw columns {JAW_FIELDS} (both fingers) and "
            f"{LEFT_JAW_FIELDS} (the left finger's) after them, got {arr.shape} (use "
            "designs[None] for a single row)"
        )
    return arr


def nonfinite_rows(des: np.ndarray) -> np.ndarray:
    """Indices of the design rows holding a value that is not a finite number (NaN, inf)."""
    return np.flatnonzero(~np.isfinite(des).all(axis=1))


# columns of :func:`_disk_table`; then the object's shape (SHAPE_* of envs.model.layout),
# an outline's orientation [rad] and its N_OUTLINE B-spline coefficients (a disk: zeros)
(DISK_RADIUS, DISK_YOUNG, DISK_POISSON, DISK_THICKNESS, DISK_SCALE, DISK_RATIO, DISK_AREA,
 DISK_OFFSET_X) = range(8)
DISK_SHAPE, DISK_ORIENT, DISK_OUTLINE = 8, 9, 10
N_DISK = DISK_OUTLINE + N_OUTLINE
# columns of the objects' requirements: strain limit, friction coefficient, payload [N]
NEED_STRAIN, NEED_FRICTION, NEED_PAYLOAD = range(3)
N_NEEDS = 3


def _disk_table(disks, batch: int) -> np.ndarray:
    """Columns (``DISK_*``): radius, Young's modulus, Poisson ratio, thickness, stiffness scale,
    contour stiffness ratio, area stiffness scale, the centre's lateral offset, then the
    object's shape, orientation and outline coefficients (zeros for a disk)."""
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
    table = np.zeros((batch, N_DISK))
    table[:, :DISK_SHAPE] = np.array(rows, dtype=np.float64).reshape(batch, DISK_SHAPE)
    for i, d in enumerate(disks):
        if d.outline is not None:
            shape, orientation, outline = d.outline_columns()
            table[i, DISK_SHAPE], table[i, DISK_ORIENT] = shape, orientation
            table[i, DISK_OUTLINE:] = outline
    return table


def _payloads(disks, batch: int, factors) -> np.ndarray:
    """The payload ``W = f rho pi r^2 t g`` [N] of every row (:meth:`SoftDisk.payload_n`)."""
    f = _per_row("payload_factors", factors, batch, 0.0, MAX_PAYLOAD_FACTOR, low_open=False)
    disks = [disks] * batch if isinstance(disks, SoftDisk) else disks
    return np.array([d.payload_n(1.0) for d in disks], dtype=np.float64) * f


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
        return _per_row("torsion_stiffness_nm_per_rad", absolute, batch, 0.0,
                        PLAUSIBLE_RANGES["torsion_stiffness_nm_per_rad"][1], low_open=True)
    rel = _per_row("torsion_stiffness_rel", PAPER_TORSION_STIFFNESS_REL if rel is None else rel,
                   batch, 0.0, MAX_SPRING_REL, low_open=True)
    unit = (disk[:, DISK_SCALE] * disk[:, DISK_YOUNG] * disk[:, DISK_THICKNESS]
            * disk[:, DISK_RADIUS] ** 2)
    return rel * unit
