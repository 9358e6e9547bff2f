"""The metrics of a solved batch, written into one table of arrays (:data:`METRIC_KEYS`): the
point-spring rows and the FEM rows (the same definitions at both fidelities), the grip share,
the rest violation and the fingers' gaps.
"""

from __future__ import annotations

import math

import numpy as np

from .batch_inputs import (
    DISK_OFFSET_X,
    DISK_ORIENT,
    DISK_OUTLINE,
    DISK_POISSON,
    DISK_RADIUS,
    DISK_SHAPE,
    DISK_THICKNESS,
    DISK_YOUNG,
)
from .model.contact_width import (
    FLAT_FACE_CURVATURE_PER_M,
    contact_share,
    hertz_arc_coefficient,
    relative_radius_m,
)
from .model.geometry import bar_distance, corner_radius, jaw_finger_gap
from .model.holding import (
    H_LIMIT,
    H_LIMIT_ANGLE,
    H_PIN_MOMENT,
    H_PIN_X,
    H_PIN_Y,
    HOLDING_SCALARS,
    N_HOLD,
)
from .model.jaw import JAW_FIELDS, pack_groove
from .model.layout import G_DEPTH, N_GROOVE, S_OFFSET_X, SHAPE_DISK
from .model.outline import outline_contact_geometry
from .model.problem import SceneColumns, _clearance, outline_bar_distance_m
from .objects import SplineOutline, as_object
from .scene import DESIGN_FIELDS, N_DESIGN, Design, SoftDisk
from .scoring import grip_share_rows, psm_metrics_rows
from .solver.pipeline import BatchSolution
from .solver.status import FEM_FAILED, OK

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
    "payload_n": (np.float64, ()),
    "grip_force_n": (np.float64, ()),
    "friction_limit": (np.int64, ()),
    "friction_limit_angle_rad": (np.float64, ()),
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


# ---------------------------------------------------------------------------------------------
# scenes, solve and metrics


def _columns(des: np.ndarray, disk: np.ndarray, kf: np.ndarray) -> SceneColumns:
    """Scene columns of design rows (the one Design -> Scene mapping, see
    :meth:`Design.to_scene`): the design's ``distance_m`` replaces the disk's; the disk keeps
    its lateral offset (a placement of the object, not part of the design). Rows 10 or 14
    wide carry the jaws (:data:`~envs.model.jaw.JAW_FIELDS`, both fingers or the right one's,
    then the left one's) as the (B, 2) jaw columns; 6 wide, straight bars (``None``)."""
    ln, th0, d3, w, torque, d1 = (np.ascontiguousarray(c) for c in des[:, :N_DESIGN].T)
    radius, young, nu, thick, scale, ratio, area, offset = (np.ascontiguousarray(c)
                                                            for c in disk[:, :DISK_SHAPE].T)
    outline = ((None,) * 3 if not np.any(disk[:, DISK_SHAPE] != SHAPE_DISK) else
               (np.ascontiguousarray(disk[:, DISK_SHAPE]),
                np.ascontiguousarray(disk[:, DISK_ORIENT]),
                np.ascontiguousarray(disk[:, DISK_OUTLINE:])))
    return SceneColumns(ln, th0, d3, w, kf, radius, d1, young, nu, thick, scale, ratio, area,
                        torque, offset, *_jaw_columns(des), *outline)


def _jaw_columns(des: np.ndarray) -> tuple[np.ndarray | None, ...]:
    """The jaw columns of :class:`SceneColumns` (each (B, 2): right, left finger) of design
    rows, in the ``J_*`` order of :mod:`envs.model.layout`; ``None`` each for 6-wide rows."""
    n_jaw = len(JAW_FIELDS)
    if des.shape[1] == N_DESIGN:
        return (None,) * n_jaw
    right = des[:, N_DESIGN : N_DESIGN + n_jaw]
    left = des[:, N_DESIGN + n_jaw :] if des.shape[1] > N_DESIGN + n_jaw else right
    return tuple(np.ascontiguousarray(np.stack([right[:, k], left[:, k]], axis=1))
                 for k in range(n_jaw))


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
    grooves, rounding = grooves_m(cols)
    # C order: these are columns of the solution's metrics table, strided views (numba's layout
    # "A") but contiguous for a batch of one ("C"), and each layout would compile the kernel
    # once more (a single design's step after a batch)
    strains = [np.ascontiguousarray(a) for a in (sol.peak_strain, sol.peak_log_strain,
                                                 sol.max_displacement_ratio, sol.peak_compression)]
    psm_metrics_rows(
        rows, n, sol.status, sol.converged, sol.iterations, sol.stable, sol.jaw_angles_rad,
        sol.points_m, sol.face_forces_n, sol.corner_forces_n, sol.corner_totals_n,
        sol.stop_torques_nm, *strains,
        cols.finger_length_m, cols.joint_offset_m, cols.finger_width_m, cols.radius_m,
        cols.thickness_m, cols.youngs_modulus_pa, cols.poisson_ratio,
        material_scale, cols.torque_nm, cols.torsion_stiffness_nm_per_rad,
        cols.rest_angle_rad, grooves, rounding,
        *outline_contact_geometry(cols.shape, cols.orientation_rad, cols.outline, cols.radius_m,
                                  n),
        out["status"], out["converged"],
        out["iterations"], out["stable"],
        out["jaw_angles_rad"], out["n_contacts"], out["touching"], out["total_force_n"],
        out["contact_score"], out["grip_share"], out["peak_strain"], out["peak_log_strain"],
        out["max_displacement_ratio"], out["peak_compression"])
    ok = rows[out["converged"][rows]]
    done = out["converged"][rows]
    _fill_holding(out, ok, sol.holding[done])


def grooves_m(cols: SceneColumns) -> tuple[np.ndarray, np.ndarray]:
    """Each scene's two jaw grooves packed in metres, (B, 2 N_GROOVE): the right finger's
    ``G_*`` slots, then the left's (:func:`envs.model.jaw.pack_groove` with unit 1; zeros for a
    straight jaw), and the corner radius ``rho`` [m] they were packed with, (B,), the
    solver's own (:func:`envs.model.geometry.corner_radius`)."""
    rounding = np.asarray(corner_radius(cols.finger_width_m, cols.radius_m), dtype=np.float64)
    out = np.zeros((cols.size, 2 * N_GROOVE))
    if cols.jaw_depth_m is None:
        return out, rounding
    for i in np.flatnonzero((np.asarray(cols.jaw_depth_m) > 0.0).any(axis=1)):
        for j in range(2):
            pack_groove(float(cols.jaw_depth_m[i, j]), float(cols.jaw_bottom_radius_m[i, j]),
                        float(cols.jaw_opening_angle_rad[i, j]), float(cols.jaw_position_m[i, j]),
                        float(rounding[i]), 1.0, out[i], N_GROOVE * j)
    return out, rounding


def _fill_holding(out: dict[str, np.ndarray], rows: np.ndarray, hold: np.ndarray) -> None:
    """Write the holding rows (layout ``H_*``) of ``rows``; the limit's angle 0 where no
    in-plane payload sets the friction (the outputs are never NaN)."""
    out["pin_force_n"][rows] = hold[:, H_PIN_X : H_PIN_Y + 1]
    for name, slot in HOLDING_SCALARS:
        out[name][rows] = hold[:, slot]
    out["friction_limit"][rows] = hold[:, H_LIMIT].astype(np.int64)
    out["friction_limit_angle_rad"][rows] = np.nan_to_num(hold[:, H_LIMIT_ANGLE])


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
                  offset_x_m=0.0, grooves: tuple[np.ndarray, np.ndarray] | None = None
                  ) -> np.ndarray:
    """Distance from each finger bar to the undeformed disk at given jaw angles [m], (B, 2).

    0 where a bar reaches into the disk. Used for the fingers that do not touch the disk in a
    grasp: how far they are from closing on it (the disk centre is fixed, so the undeformed
    circle is where the fingers would meet it). ``offset_x_m``: the centre's lateral offset
    ``x_c`` [m], scalar or (B,); the centre is at ``(x_c, d_1 + r)``. ``grooves``: the rows'
    jaw grooves and corner radii of :func:`grooves_m`; a grooved finger's distance is the jaw
    gap of the centre (:func:`envs.model.geometry.jaw_finger_gap`) less the radius (a groove
    the disk could sit in moves the finger's surface away from it).
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
    if grooves is not None:
        packed, rounding = grooves
        radius = np.broadcast_to(np.asarray(radius_m, dtype=np.float64), centre_y.shape)
        offset = np.broadcast_to(np.asarray(offset_x_m, dtype=np.float64), centre_y.shape)
        for i in np.flatnonzero((packed[:, N_GROOVE * np.arange(2) + G_DEPTH] > 0.0).any(axis=1)):
            for side in range(2):
                gap, _ = jaw_finger_gap(float(offset[i]), float(centre_y[i]), side,
                                        float(jaw_angles_rad[i, side]), float(d3[i]),
                                        float(ln[i]), float(w[i]), float(rounding[i]),
                                        packed[i], N_GROOVE * side)
                out[i, side] = max(0.0, gap - float(radius[i]))
    return out


def outline_finger_gaps_m(cols: SceneColumns, jaw_angles_rad: np.ndarray, gaps: np.ndarray
                          ) -> np.ndarray:
    """``gaps`` (:func:`finger_gaps_m`, (B, 2)) with the rows whose object is an outline
    replaced by the distance from each finger bar to the undeformed outline at the given jaw
    angles [m] (0 where a bar reaches into it; a groove is not taken off the bar)."""
    if not cols.has_outlines:
        return gaps
    out = np.array(gaps, dtype=np.float64, copy=True)
    table = cols.rows()
    for i in np.flatnonzero(cols.shape != SHAPE_DISK):
        for side, sign in ((0, 1.0), (1, -1.0)):
            out[i, side] = max(0.0, outline_bar_distance_m(
                table[i], sign, float(table[i, S_OFFSET_X]), float(jaw_angles_rad[i, side])))
    return out


def _soft_disk(row: np.ndarray) -> SoftDisk:
    """The disk of a row of :func:`_disk_table` (its distance ``d_1`` comes from the design;
    an outline as the model's spline, :class:`~envs.objects.SplineOutline`)."""
    radius, young, nu, thick, scale, ratio, area, offset = row[:DISK_SHAPE].tolist()
    if row[DISK_SHAPE] == SHAPE_DISK:
        return SoftDisk(radius, 0.0, young, nu, thick, scale, ratio, area, offset_x_m=offset)
    return as_object(SoftDisk(radius, 0.0, young, nu, thick, scale, ratio, area,
                              offset_x_m=offset),
                     SplineOutline(tuple(row[DISK_OUTLINE:].tolist())), float(row[DISK_ORIENT]))


def _fill_fem(out: dict[str, np.ndarray], rows: np.ndarray, des: np.ndarray, disk: np.ndarray,
              kf: np.ndarray, cols: SceneColumns, fem_rings: int, payload_n: np.ndarray,
              load_set: str = "any") -> None:
    """Solve the rows with the finite-element reference and write the same metrics as
    :func:`_fill_group` does for the point-spring model (same definitions, see
    :func:`evaluate_designs`)."""
    from .fem.designs import fem_design_grasps, fem_metrics

    # (a design row carries its jaws: Design.from_array reads them)
    scenes = [Design.from_array(des[i]).to_scene(_soft_disk(disk[i]), float(kf[i]))
              for i in rows.tolist()]
    fem = fem_metrics(fem_design_grasps(scenes, des[rows, TORQUE_COLUMN], fem_rings,
                                        payloads_n=payload_n, load_set=load_set),
                      disk[rows, DISK_RADIUS], des[rows, DISTANCE_COLUMN] + disk[rows, DISK_RADIUS],
                      disk[rows, DISK_OFFSET_X])
    n_contacts = np.nan_to_num(fem["n_contacts"]).astype(np.int64)
    # each face's share of the rim, at most the Hertz width of its force (as for the PSM,
    # with the physical E the FEM solves with): the FEM's own capped shares (per contact
    # segment on a grooved jaw), else, for a straight result cached before they were stored,
    # the flat face's cap of its force; NaN (not converged) stays NaN
    shares = np.empty(rows.size)
    for i, d in enumerate(disk[rows]):
        if np.all(np.isfinite(fem["contact_shares"][i])):
            shares[i] = float(np.sum(fem["contact_shares"][i]))
            continue
        k = hertz_arc_coefficient(d[DISK_RADIUS], d[DISK_THICKNESS], d[DISK_YOUNG],
                                  d[DISK_POISSON],
                                  relative_radius_m(d[DISK_RADIUS], FLAT_FACE_CURVATURE_PER_M))
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
        }
        hold = np.empty((rows.size, N_HOLD))
        hold[:, H_PIN_X : H_PIN_Y + 1] = fem["pin_force_n"]
        for key, slot in (*HOLDING_SCALARS, ("friction_limit", H_LIMIT)):
            hold[:, slot] = fem[key]
    # (an infinite required friction is an answer, one finger touching: not a failure)
    floats = np.column_stack([np.reshape(v, (rows.size, -1)) for v in metrics.values()
                              if v.dtype.kind == "f"] + [hold[:, H_PIN_X : H_PIN_MOMENT + 1]])
    ok = fem["converged"] & np.isfinite(floats).all(axis=1)
    out["status"][rows] = np.where(ok, OK, FEM_FAILED)
    out["iterations"][rows] = fem["iterations"]
    out["n_triangles"][rows] = fem["n_elements"]
    out["stable"][rows] = ok  # Newton on the total energy with a descent line search
    out["converged"][rows] = ok
    for key, v in metrics.items():
        out[key][rows[ok]] = v[ok]
    _fill_holding(out, rows[ok], hold[ok])
