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

Shaped jaws (:mod:`envs.model.jaw`) add four columns per groove: a row 10 wide cuts the same
groove into both fingers, a row 14 wide gives the left finger its own (columns 10-13, the same
fields prefixed ``left_``). A depth of 0 is the straight bar.

| col | field | meaning | unit |
|---|---|---|---|
| 6 | ``jaw_depth_m`` | groove depth ``h`` below the gripping face (0: straight) | m |
| 7 | ``jaw_bottom_radius_m`` | radius ``R_b`` of the groove's rounded bottom (a cradle's) | m |
| 8 | ``jaw_opening_angle_rad`` | full angle between the flanks (0: a cradle) | rad |
| 9 | ``jaw_position_m`` | the groove's centre along the finger from the joint | m |
"""

from __future__ import annotations

import functools
import warnings

import numpy as np

from .batch_inputs import (  # noqa: F401 (re-exported: the layouts of the batch's tables)
    DISK_AREA,
    DISK_OFFSET_X,
    DISK_POISSON,
    DISK_RADIUS,
    DISK_RATIO,
    DISK_SCALE,
    DISK_THICKNESS,
    DISK_YOUNG,
    N_DISK,
    N_NEEDS,
    NEED_FRICTION,
    NEED_PAYLOAD,
    NEED_STRAIN,
    _design_table,
    _disk_table,
    _joint_springs,
    _payloads,
    _per_row,
    nonfinite_rows,
)
from .batch_metrics import (  # noqa: F401 (re-exported: the metrics' definitions)
    METRIC_KEYS,
    _columns,
    _empty_output,
    _fill_fem,
    _fill_group,
    _fill_holding,
    _soft_disk,
    finger_gaps_m,
    grip_share,
    grooves_m,
    outline_finger_gaps_m,
    rest_violation,
)
from .design_space import DesignBounds  # noqa: F401
from .model.defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_FRICTION_COEFFICIENT,
    DEFAULT_PAYLOAD_FACTOR,
    DEFAULT_PHASE_RAD,
    DEFAULT_STRAIN_LIMIT,
    FEM_DESIGN_RINGS,
    FEM_MAX_RINGS,
    MAX_FRICTION_COEFFICIENT,
    PLAUSIBLE_RANGES,
)
from .model.family import resolve_model, triangle_range
from .model.loads import DEFAULT_LOAD_SET, load_set_code
from .model.problem import REST_OK, rest_codes
from .reward import RewardWeights, add_reward  # noqa: F401
from .scene import (
    DESIGN_FIELDS,
    N_DESIGN,
    Design,
    design_fields,
)
from .solver.pipeline import solve_columns
from .solver.status import NOT_FINITE, NOT_SOLVED
from .validation import InputWarning, check_integer

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
MAX_CHUNK_SIZE = 10_000_000  # rows of a chunk at most (MAX_BUDGET's evaluations in one)
FIDELITIES = ("psm", "fem")


def _evaluate_arrays(des: np.ndarray, disk: np.ndarray, n_tri: np.ndarray, needs: np.ndarray,
                     kf: np.ndarray, weights: RewardWeights,
                     model: tuple[int, str, float] = (1, "spring", 1.0),
                     fidelity: str = "psm", fem_rings: int = FEM_DESIGN_RINGS,
                     leaders: np.ndarray | None = None,
                     load_set: str = DEFAULT_LOAD_SET) -> dict[str, np.ndarray]:
    """In-process evaluation of validated, normalized inputs (one row per design);
    ``needs``: each object's strain limit, friction coefficient and payload (columns
    ``NEED_*``);
    ``model``: rings, element and the factor of the member's calibration on the disks'
    stiffness scale (``fidelity="psm"``); ``fem_rings``: the FEM mesh (``"fem"``);
    ``leaders``: validated leader rows (see :func:`evaluate_designs`) or None; ``load_set``:
    the payload's directions (:data:`envs.model.loads.LOAD_SETS`)."""
    batch = des.shape[0]
    n_rings, element, model_scale = model
    out = _empty_output(batch)
    out["n_triangles"][:] = n_tri
    out["strain_limit"][:] = needs[:, NEED_STRAIN]
    out["friction_coefficient"][:] = needs[:, NEED_FRICTION]
    out["payload_n"][:] = needs[:, NEED_PAYLOAD]
    out["status"][:] = NOT_SOLVED
    out["status"][nonfinite_rows(des)] = NOT_FINITE
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
            _fill_fem(out, rows, des, disk, kf, cols.take(rows), fem_rings,
                      needs[rows, NEED_PAYLOAD], load_set)
    for n in (np.unique(n_tri[valid]).tolist() if fidelity == "psm" else ()):
        rows = np.flatnonzero(valid & (n_tri == n))
        group = cols.take(rows)
        sol = solve_columns(group, n, phase_rad=DEFAULT_PHASE_RAD, n_rings=n_rings,
                            element=element, payload_n=needs[rows, NEED_PAYLOAD],
                            leaders=_group_leaders(leaders, rows), load_set=load_set)
        _fill_group(out, rows, sol, n, group, material_scale[rows])
    missing = out["converged"][:, None] & ~out["touching"]
    rows = np.flatnonzero(missing.any(axis=1))
    if rows.size:
        part = cols.take(rows)
        gaps = outline_finger_gaps_m(part, out["jaw_angles_rad"][rows], finger_gaps_m(
            des[rows], disk[rows, DISK_RADIUS], out["jaw_angles_rad"][rows],
            disk[rows, DISK_OFFSET_X], grooves_m(part)))
        out["finger_gap_m"][rows] = np.where(missing[rows], gaps, 0.0)
    out["holds"][:] = (out["converged"] & out["touching"].all(axis=1)
                       & (out["required_friction"] <= out["friction_coefficient"]))
    add_reward(out, valid, disk[:, DISK_RADIUS], weights)
    return out


def _warn_nonfinite(des: np.ndarray) -> None:
    """One :class:`~envs.validation.InputWarning` naming the rows whose design holds a value
    that is not a finite number (the first one's column and value): they are flagged
    (``status`` :data:`~envs.solver.status.NOT_FINITE`, invalid at rest), the others answered."""
    rows = nonfinite_rows(des)
    if not rows.size:
        return
    first = int(rows[0])
    col = int(np.flatnonzero(~np.isfinite(des[first]))[0])
    names = design_fields(des.shape[1])
    shown = ", ".join(map(str, rows[:5].tolist())) + (", ..." if rows.size > 5 else "")
    value = float(des[first, col])
    warnings.warn(
        f"evaluate_designs: {rows.size} of {des.shape[0]} design rows hold a value that is not a "
        f"finite number (row {first}: {names[col]} = {value!r}; rows {shown}): they "
        f"are not solved (status {NOT_FINITE}, valid_at_rest False, the invalid penalty), the "
        "other rows are answered", InputWarning, stacklevel=3)


def _group_leaders(leaders: np.ndarray | None, rows: np.ndarray) -> np.ndarray | None:
    """The leaders of a group of ``rows`` (one N, valid at rest) in the group's own indices;
    a row whose leader is outside the group has none."""
    if leaders is None:
        return None
    position = np.full(leaders.shape[0], -1, dtype=np.int64)
    position[rows] = np.arange(rows.size)
    lead = leaders[rows]
    return np.where(lead >= 0, position[np.maximum(lead, 0)], -1)


def _check_leaders(leaders, batch: int) -> np.ndarray | None:
    """``leaders`` of :func:`evaluate_designs` as (B,) int64, or a ValueError."""
    if leaders is None:
        return None
    arr = np.asarray(leaders)
    if arr.shape != (batch,) or not (arr.size == 0 or np.issubdtype(arr.dtype, np.integer)):
        raise ValueError(f"leaders must be integers of shape ({batch},), got {arr.dtype} "
                         f"{arr.shape}")
    arr = arr.astype(np.int64)
    bad = (arr < -1) | (arr >= batch)
    if not bad.any():
        bad = (arr >= 0) & (arr[np.maximum(arr, 0)] >= 0)
    if bad.any():
        raise ValueError(f"leaders must be -1 or the index in [0, {batch - 1}] of a row without "
                         f"a leader; row {int(np.flatnonzero(bad)[0])} is not")
    return arr


def _chunk_leaders(leaders: np.ndarray | None, start: int, size: int) -> np.ndarray | None:
    """The leaders of rows ``start .. start + size - 1`` in the chunk's own indices."""
    if leaders is None:
        return None
    lead = leaders[start : start + size] - start
    return np.where((lead >= 0) & (lead < size), lead, -1)


def _evaluate_chunk(chunk: tuple[np.ndarray, ...], weights: RewardWeights,
                    model: tuple[int, str, float] = (1, "spring", 1.0), fidelity: str = "psm",
                    fem_rings: int = FEM_DESIGN_RINGS,
                    load_set: str = DEFAULT_LOAD_SET) -> dict[str, np.ndarray]:
    *arrays, leaders = chunk
    return _evaluate_arrays(*arrays, weights=weights, model=model, fidelity=fidelity,
                            fem_rings=fem_rings, leaders=leaders, load_set=load_set)


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
    payload_factors=None,
    load_set: str = DEFAULT_LOAD_SET,
    executor=None,
    chunk_size: int | None = None,
    n_rings: int | None = None,
    element: str | None = None,
    calibrated: bool | None = None,
    fidelity: str = "psm",
    fem_rings: int = FEM_DESIGN_RINGS,
    leaders=None,
) -> dict[str, np.ndarray]:
    """Solve the grasp of every design and return its metrics and reward terms.

    Parameters
    ----------
    designs
        Array of shape (B, 6) in SI units with the columns of :data:`DESIGN_FIELDS`, a sequence
        of :class:`Design`, or one :class:`Design`. Shaped jaws: (B, 10) with the four
        :data:`~envs.model.jaw.JAW_FIELDS` after the six (both fingers alike), or (B, 14) with
        the left finger's four :data:`~envs.model.jaw.LEFT_JAW_FIELDS` after those (the
        module's table). A groove that does not fit its finger makes its row invalid at rest
        (:data:`~envs.model.problem.REST_JAW`), the other rows are answered.
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
    payload_factors
        Payload factor ``f`` [-], in [0, 100]; scalar or shape (B,). The grasp must carry the
        payload ``W = f m g`` (``m = rho pi r^2 t`` of each row's disk, its
        ``density_kg_m3``; g = 9.81 m/s^2) in every direction of the ``load_set``, besides
        the centre's reaction, the freed object's normal forces moved by each load as the
        grasp's stiffness decides (:mod:`envs.model.loads`). Default
        :data:`~envs.model.defaults.DEFAULT_PAYLOAD_FACTOR` (2: the weight plus a lift at 1 g);
        0 turns the payload off (the reaction alone).
    load_set
        How the gripper picks, the payload's directions (one for the whole batch):
        ``"top-down"`` (along the gripper's axis, towards the tips and back), ``"side"`` (out
        of the plane, both ways) or ``"any"`` (every in-plane direction and out of the plane;
        default, :data:`envs.model.loads.DEFAULT_LOAD_SET`).
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
    leaders
        Optional (B,) integers: for each row, a row of the same batch whose answer starts its
        solve (its *leader*: the same design in a scenario a few percent away), or -1 for
        none; a leader has none itself. Such a row is solved from its leader's answer on the
        leader's contact set first (a few Newton steps) and keeps that answer only where the
        independent check confirms it as a stable equilibrium; otherwise it is solved from
        rest like any row (:func:`envs.solver.pipeline.solve_columns`). The answers agree
        with independent solves within the solver's tolerance, except where a scene has
        several stable grasps and the two starts find different ones. A row whose leader is
        invalid at rest, has another ``N`` or lies in another chunk of an ``executor`` is
        solved from rest. :func:`envs.scenarios.evaluate_scenarios` sets it.

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
          independent check failed, 12: the FEM did not converge, 13: a design value is not a
          finite number, NaN or inf: not solved, and an
          :class:`~envs.validation.InputWarning` names the rows; ...; message in
          ``STATUS_MESSAGES``); FEM: Newton iterations.
        - ``n_triangles``: the model's contour points ``N`` (FEM: its quadratic triangles).
        - ``jaw_angles_rad`` (B, 2): right and left finger angles [rad].
        - ``n_contacts`` (B, 2): contour points pressed by each face (positive force; FEM:
          rim nodes).
        - ``touching`` (B, 2): each finger touches the disk (face or corner contact).
        - ``total_force_n`` (B, 2): normal force of each finger on the disk [N].
        - ``contact_score``: ``grip_share`` times the fraction of the contour in contact,
          summed over the two faces (:mod:`envs.model.contact_width`), as far as the actuation
          grips the object. Each face's share is the contact's extent, its edges interpolated
          between a pressed point and its free neighbour from the pressed point's pressure and
          the free one's gap to the finger (not a count of points: continuous in the design,
          from 0 at first touch), at most the Hertz width of the face force on a flat face (a
          contact resolved by a point spacing counts with its physical width). FEM: the same
          measure on the rim nodes (penalty forces, gaps), capped alike.
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
          contacts holds the object freed of its centre [-] (:mod:`envs.model.loads`): the
          centre's reaction and ``payload_n`` in every direction of the ``load_set`` are loads
          on the free object, whose normal forces move under each as the grasp's stiffness
          decides; friction carries what they leave (3-D Coulomb cones out of the plane). 0
          when nothing is carried, ``inf`` when no friction can (one finger touching);
          ``tan(theta)`` for a symmetric grasp on the faces at finger angle ``theta`` without
          a payload.
        - ``payload_n``: the payload ``W = f rho pi r^2 t g`` the required friction includes
          [N] (0 with ``payload_factors=0``); ``grip_force_n``: the sum of the contacts'
          normal forces [N] (``mu * grip_force_n >= payload_n`` is necessary to lift the
          object); ``friction_limit``: what sets the required friction, a code of
          :mod:`envs.model.holding` (0 nothing, 1 the reaction alone, 2 the payload out of the
          plane, 3 the payload in the plane); ``friction_limit_angle_rad``: for 3, the
          direction of the payload's pull on the object that needs most friction [rad from
          +x, gripper frame], 0 otherwise.
        - ``friction_coefficient``: the coefficient used [-]; ``holds``: a converged grasp
          touching with both fingers whose required friction is within it (it would hold
          and lift the object without the pin).
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
        For malformed inputs (shapes, disks, N, strain limits, ``k_f``, offsets; designs of
        strings or booleans, which numpy would turn into numbers). Physically invalid designs
        do not raise, nor do rows holding NaN or inf (status 13, see above).
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
    _warn_nonfinite(des)
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
    needs = np.empty((batch, N_NEEDS))
    needs[:, NEED_STRAIN] = _per_row(
        "strain_limits", DEFAULT_STRAIN_LIMIT if strain_limits is None else strain_limits,
        batch, 0.0, 1.0, low_open=True)
    needs[:, NEED_FRICTION] = _per_row(
        "friction_coefficients", DEFAULT_FRICTION_COEFFICIENT if friction_coefficients is None
        else friction_coefficients, batch, 0.0, MAX_FRICTION_COEFFICIENT, low_open=True)
    needs[:, NEED_PAYLOAD] = _payloads(disks, batch, DEFAULT_PAYLOAD_FACTOR
                                       if payload_factors is None else payload_factors)
    load_set_code(load_set)  # (validated before any work)
    kf = _joint_springs(torsion_stiffness_rel, torsion_stiffness_nm_per_rad, disk, batch)
    if offsets_x_m is not None:
        disk[:, DISK_OFFSET_X] = _per_row("offsets_x_m", offsets_x_m, batch,
                                          *PLAUSIBLE_RANGES["offset_x_m"], low_open=False)
    leaders = _check_leaders(leaders, batch) if fidelity == "psm" else None
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE if fidelity == "psm" else 1
    chunk_size = check_integer("chunk_size", chunk_size, 1, MAX_CHUNK_SIZE)
    if executor is None:
        return _evaluate_arrays(des, disk, n_tri, needs, kf, weights, model, fidelity,
                                fem_rings, leaders, load_set)
    if not callable(getattr(executor, "map", None)):
        raise ValueError("executor must have a .map(fn, iterable) method")
    starts = range(0, batch, int(chunk_size))
    # each chunk's leaders in its own rows (a leader in another chunk: none)
    chunks = [(*(a[s : s + int(chunk_size)] for a in (des, disk, n_tri, needs, kf)),
               _chunk_leaders(leaders, s, int(chunk_size))) for s in starts]
    fn = functools.partial(_evaluate_chunk, weights=weights, model=model, fidelity=fidelity,
                           fem_rings=fem_rings, load_set=load_set)
    parts = [_result_of(p) for p in executor.map(fn, chunks)]
    if not parts:
        return _empty_output(0)
    return {k: np.concatenate([p[k] for p in parts]) for k in METRIC_KEYS}
