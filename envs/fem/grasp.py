"""The torque-controlled grasp: :func:`fem_grasp` (validation, cache) and its solve.

Builds the grasp mesh with its rigid hub, the two jaws (flat faces or grooved solids) and their
corners, the torsion-spring potential of the fingers with the closed-jaw stop, and walks the
torque ramp, one :class:`~envs.fem.result.FemResult` per torque.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import fields, replace

import numpy as np

from envs.model.geometry import closed_angle_rad
from envs.model.holding import hertz_half_width, holding_fields
from envs.model.jaw import jaw_row
from envs.model.loads import DEFAULT_LOAD_SET, load_set_code
from envs.scene import Scene
from envs.validation import check_range

from .body import _Body
from .cache import FEM_VERSION, _cache_dir, _cache_key, _load_cache, _store_cache
from .contact import _PENALTY_FACTOR, _Rim, jaw_corners, jaw_obstacle, rim_contact_shares
from .loaded import fem_holding
from .material import _check_plane, _log_strain_magnitude, _stretch_strain_magnitude
from .mesh import (
    OutlineMap,
    _arc_facets,
    _check_mesh_size,
    _grasp_mesh,
    _quadratic_mesh,
    default_mesh_size_m,
)
from .newton import _ramp
from .result import FemResult
from .system import _System

_STOP_STIFFNESS_FACTOR = 1e4  # joint-stop penalty stiffness, in units of k_f


def fem_grasp(
    scene: Scene,
    torques_nm: Sequence[float],
    mesh_size_m: float | None = None,
    plane: str = "strain",
    hub_radius_m: float | None = None,
    cache: bool = True,
    *,
    penalty_pa_per_m: float | None = None,
    al_iterations: int = 0,
    payload_n: float = 0.0,
    load_set: str = DEFAULT_LOAD_SET,
) -> list[FemResult]:
    """Finite-element grasp of the scene's disk at a sequence of actuation torques.

    The torques are the load ramp: they are solved in the given order, each one warm-started from
    the previous converged state (starting from the open gripper at zero torque). A step that
    fails (Newton or line-search failure, inverted element) is bisected; a torque that cannot be
    reached gives ``converged=False`` with the reason and NaN fields, and the ramp continues from
    the last converged state.

    Parameters
    ----------
    scene
        Gripper and disk. ``disk.stiffness_scale`` is ignored (the FEM uses the physical ``E``).
        A finger with a groove (``Gripper.jaws``, :class:`envs.model.jaw.JawProfile`) presses
        the rim with its grooved solid (:func:`envs.model.jaw.jaw_gap`) and the groove's rounded
        mouth edges (:mod:`envs.fem.contact`).
        The hub holds the disk where it was placed, at ``disk.center_m`` (off the axis when
        ``disk.offset_x_m`` is not 0).
    torques_nm
        Actuation torques ``T_a >= 0`` [N·m], finite.
    mesh_size_m
        Element size ``h`` in (0, r); the disk is meshed with ``n = ceil(r / h)`` rings, i.e.
        ``6 n^2`` quadratic triangles (mirror symmetric about the y axis): ``k_h`` rings fill the
        hub and ``n - k_h`` evenly spaced rings the annulus outside it. Default ``r / 12``
        (864 elements).
    plane
        ``"strain"`` (default) or ``"stress"``.
    hub_radius_m
        Radius of the rigid hub holding the centre, in ``(0, 0.5 r]``, default ``0.1 r``. The
        mesh has a ring of nodes exactly on the hub's edge (curved P2 edges on the circle), and
        all nodes on or inside it are fixed, so the hub is the same circle on every mesh. The
        peak strain is measured outside the hub (see :class:`FemResult`).
    cache
        Read/write results in :func:`~envs.fem.cache.fem_cache_dir` (``$PSM_GRASP_CACHE/fem``,
        default ``~/.cache/psm-grasp/fem``), keyed by a hash of all inputs.
    penalty_pa_per_m
        Contact penalty ``eps`` [Pa/m]; default ``100 E / h``.
    al_iterations
        Augmented-Lagrangian multiplier updates per torque (0 = pure penalty).
    payload_n
        The payload ``W`` [N], >= 0, that the required friction includes (carried in every
        direction of the load set, :mod:`envs.model.loads`); 0: the hub's reaction alone.
    load_set
        How the gripper picks: the payload's directions, ``"top-down"`` (along the gripper's
        axis, both ways), ``"side"`` (out of the plane, both ways) or ``"any"`` (every
        direction; default). The free object's grasp is solved with the FEM's own compliance
        (:mod:`envs.fem.loaded`).

    Returns
    -------
    list of FemResult
        One result per torque, in order.

    Raises
    ------
    ValueError
        For an invalid parameter (the message names it and gives the allowed range).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a Scene, got {type(scene).__name__}")
    disk, grip = scene.disk, scene.gripper
    r = disk.radius_m
    try:
        torques = [float(v) for v in np.asarray(torques_nm, dtype=float).ravel()]
    except (TypeError, ValueError):
        raise ValueError("torques_nm must be a sequence of finite numbers >= 0") from None
    if not torques:
        raise ValueError("torques_nm must contain at least one torque")
    for i, tq in enumerate(torques):
        check_range(f"torques_nm[{i}]", tq, 0.0, math.inf)
    _check_plane(plane)
    h = default_mesh_size_m(r) if mesh_size_m is None else _check_mesh_size(mesh_size_m, r)
    if hub_radius_m is not None:
        check_range("hub_radius_m", hub_radius_m, 0.0, 0.5 * r, low_open=True)
    if penalty_pa_per_m is not None:
        check_range("penalty_pa_per_m", penalty_pa_per_m, 0.0, math.inf, low_open=True)
    payload = check_range("payload_n", payload_n, 0.0, math.inf)
    load_set_code(load_set)
    if not isinstance(al_iterations, int | np.integer) or not 0 <= al_iterations <= 50:
        raise ValueError(f"al_iterations must be an integer in [0, 50], got {al_iterations!r}")
    rings = max(2, math.ceil(r / h - 1e-9))
    h_eff = r / rings
    hub = 0.1 * r if hub_radius_m is None else float(hub_radius_m)
    eps = (
        _PENALTY_FACTOR * disk.youngs_modulus_pa / h_eff
        if penalty_pa_per_m is None
        else float(penalty_pa_per_m)
    )

    inputs = {
        "version": FEM_VERSION,
        "gripper": {f.name: getattr(grip, f.name) for f in fields(grip)
                    if f.name not in ("jaw", "left_jaw")},
        "disk": {
            f.name: getattr(disk, f.name) for f in fields(disk)
            if f.name not in ("stiffness_scale", "contour_stiffness_ratio", "density_kg_m3",
                              "outline", "orientation_rad")
        },
        "torques_nm": torques,
        "rings": rings,
        "plane": plane,
        "hub_radius_m": hub,
        "penalty_pa_per_m": eps,
        "al_iterations": int(al_iterations),
    }
    if any(jaw.depth_m > 0.0 for jaw in grip.jaws):  # (straight jaws keep their keys)
        # (lists: the entry's inputs are compared after a JSON round trip)
        inputs["jaws"] = [list(jaw_row(jaw)) for jaw in grip.jaws]
    if payload > 0.0:  # (keys of results without a payload stay as they were)
        inputs["payload_n"] = payload
    if disk.outline is not None:  # (a disk's keys stay as they were)
        # the model's own curve: the same key for a shape and its SplineOutline
        inputs["outline"] = disk.outline.coefficients().tolist()
        inputs["orientation_rad"] = disk.orientation_rad
    if load_set != DEFAULT_LOAD_SET:  # (the default's keys stay as they were)
        inputs["load_set"] = load_set
    path = _cache_dir() / f"{_cache_key(inputs)}.json"
    if cache:
        hit = _load_cache(path, inputs)
        if hit is not None:
            return hit

    results = _solve_grasp(scene, torques, rings, plane, hub, eps, int(al_iterations), payload,
                           load_set)
    if cache:
        _store_cache(path, inputs, results)
    return results


def _solve_grasp(
    scene: Scene,
    torques: list[float],
    rings: int,
    plane: str,
    hub: float,
    eps: float,
    al_iterations: int,
    payload: float = 0.0,
    load_set: str = DEFAULT_LOAD_SET,
) -> list[FemResult]:
    disk, grip = scene.disk, scene.gripper
    r, t = disk.radius_m, disk.thickness_m
    centre = disk.center_m
    base, _ = _grasp_mesh(r, rings, hub)
    arcs = _arc_facets(base, r)
    hub_edge = _arc_facets(base, hub, boundary=False)
    outline = None
    if disk.outline is None:
        base = replace(base, doflocs=base.p + centre[:, None])
        mesh = _quadratic_mesh(base, r, arcs, centre, extra_circles=[(hub, hub_edge)])
    else:
        # the disk mesh (its rings and rim on circles) mapped radially onto the outline
        outline = OutlineMap(disk.outline.coefficients(), disk.orientation_rad, r)
        disk_mesh = _quadratic_mesh(base, r, arcs, None, extra_circles=[(hub, hub_edge)])
        mesh = replace(disk_mesh, doflocs=outline.apply(disk_mesh.doflocs, r)
                       + centre[:, None])
    body = _Body(mesh, disk.youngs_modulus_pa, disk.poisson_ratio, t, plane)
    rim = _Rim.build(body, arcs, centre, t, curved=outline is not None)

    # the rigid hub: every node on or inside the (curved) hub ring (an outline's: the hub
    # ring is the outline scaled by hub / r)
    if outline is None:
        dist = np.linalg.norm(body.basis.doflocs - centre[:, None], axis=0)
    else:
        dist = r * outline.fraction(body.basis.doflocs, centre)
    fixed = np.nonzero(dist <= hub * (1 + 1e-9))[0]
    kf, th0 = grip.torsion_stiffness_nm_per_rad, grip.rest_angle_rad
    th_stop = closed_angle_rad(grip)
    k_stop = _STOP_STIFFNESS_FACTOR * kf

    def q_potential(q: np.ndarray, torque: float):
        e = float(np.sum(torque * q + 0.5 * kf * (q - th0) ** 2))
        g = torque + kf * (q - th0)
        hdiag = np.full(2, kf)
        below = q < th_stop
        e += float(np.sum(np.where(below, 0.5 * k_stop * (q - th_stop) ** 2, 0.0)))
        g = g + np.where(below, k_stop * (q - th_stop), 0.0)
        hdiag = hdiag + np.where(below, k_stop, 0.0)
        return e, g, np.diag(hdiag)

    force_tol = 1e-10 * disk.youngs_modulus_pa * t * r
    # rim nodes counter-clockwise from the top (contour output and tip-corner polygon)
    angle = np.arctan2(rim.ref_m[:, 1] - centre[1], rim.ref_m[:, 0] - centre[0])
    order = np.argsort(np.mod(angle - math.pi / 2, 2 * math.pi), kind="stable")
    system = _System(
        body,
        rim,
        fixed,
        [jaw_obstacle(scene, 0, 0), jaw_obstacle(scene, 1, 1)],
        2,
        q_potential,
        eps,
        q_scale=np.array([r, r]),
        force_tol_n=force_tol,
        length_scale_m=r,
        corners=jaw_corners(scene),
        rim_order=order,
    )
    n = body.n
    # strain regions (see FemResult.peak_strain; an outline's: of the mapped radius)
    rho = (np.linalg.norm(body.qp_xy - centre[:, None, None], axis=0) if outline is None
           else r * outline.fraction(body.qp_xy, centre))
    outside_hub = rho > 2 * hub
    hub_layer = (rho > hub) & ~outside_hub

    def accept(x: np.ndarray) -> str | None:
        if body.min_jacobian(x[:n]) <= 0:
            return "inverted element (det F <= 0 at a node or quadrature point)"
        return None

    x = np.zeros(n + 2)
    x[n:] = grip.rest_angle_rad
    load = 0.0
    previous: tuple[np.ndarray, float] | None = None
    n_free = system.free.size
    results = []
    for torque in torques:
        t0 = time.perf_counter()
        x_new, load_new, rep, previous = _ramp(
            system, x, load, torque, al_iterations, accept, previous
        )
        elapsed = time.perf_counter() - t0
        x, load = x_new, load_new
        common = dict(
            torque_nm=torque,
            n_elements=int(mesh.t.shape[1]),
            n_dofs=int(n_free),
            mesh_size_m=r / rings,
            solve_time_s=elapsed,
            newton_iterations=int(rep.iterations),
            plane=plane,
            hub_radius_m=hub,
        )
        if not rep.converged:
            results.append(
                FemResult(
                    jaw_angles_rad=(math.nan, math.nan),
                    converged=False,
                    message=f"failed at T_a = {torque:g} N·m (last converged "
                    f"{load:g} N·m): {rep.message}",
                    contour_m=np.full((rim.ref_m.shape[0], 2), math.nan),
                    contact_forces_n=(math.nan, math.nan),
                    tip_forces_n=(math.nan, math.nan),
                    peak_strain=math.nan,
                    **common,
                )
            )
            continue
        forces, corner_forces = system.contact_forces(x, load)
        # each finger's corners: its tip (corners 0 and 1) and its groove's mouth edges
        tip = corner_forces[:2]
        finger_corner_n = [float(sum(f for c, f in zip(system.corners, corner_forces,
                                                       strict=True) if c.side == side))
                           for side in (0, 1)]
        hold = fem_holding(system, body, rim, x, load, centre, r, grip.joint_offset_m, kf,
                           (bool(x[n] < th_stop), bool(x[n + 1] < th_stop)), payload,
                           load_set,
                           hertz_half_width(r, t, disk.youngs_modulus_pa, disk.poisson_ratio),
                           disk.youngs_modulus_pa * t * r)
        gaps = system.gaps(x)
        pen = 0.0
        for (g, valid), f in zip(gaps, forces, strict=True):
            act = valid & (f > 0)
            if np.any(act):
                pen = max(pen, float(np.max(-g[act])))
        # a tip's penetration from its force; a rounded mouth edge's (pure penalty, maybe on
        # two rim segments) from its geometry
        tip_pen = (tip - system.corner_multipliers[:2]) / system.k_corner
        pen = max(pen, float(np.max(np.where(tip > 0, tip_pen, 0.0))),
                  system.rounded_corner_penetration(x))
        extents, shares = rim_contact_shares(scene, rim, order, system.rim_positions(x),
                                             forces[:2], x[n:], outline)
        compression = math.nan
        if outline is not None:
            # each rim node's shortening over its own rest distance from the centroid
            rest = np.linalg.norm(rim.ref_m - centre, axis=1)
            now = np.linalg.norm(system.rim_positions(x) - centre, axis=1)
            compression = max(0.0, float(np.max((rest - now) / rest)))
        fmat = body.deformation_gradient(x[:n])
        strain = _log_strain_magnitude(fmat)
        stretch = _stretch_strain_magnitude(fmat)
        disp = np.linalg.norm(x[rim.dofs], axis=1)
        at_stop = bool(np.any(x[n:] < th_stop))
        stop = k_stop * np.maximum(0.0, th_stop - x[n:])
        results.append(
            FemResult(
                jaw_angles_rad=(float(x[n]), float(x[n + 1])),
                converged=True,
                message="converged (jaws on the closed stop)" if at_stop else "converged",
                contour_m=system.rim_positions(x)[order],
                contact_forces_n=(
                    float(np.sum(forces[0]) + finger_corner_n[0]),
                    float(np.sum(forces[1]) + finger_corner_n[1]),
                ),
                tip_forces_n=(float(tip[0]), float(tip[1])),
                peak_strain=float(np.max(strain[outside_hub])),
                hub_edge_peak_strain=float(np.max(strain[hub_layer], initial=0.0)),
                max_penetration_m=max(pen, 0.0),
                max_displacement_m=float(np.max(disp)),
                contact_node_counts=(
                    int(np.count_nonzero(forces[0] > 0)),
                    int(np.count_nonzero(forces[1] > 0)),
                ),
                contact_fractions=extents,
                contact_shares=shares,
                stop_torques_nm=(float(stop[0]), float(stop[1])),
                peak_stretch_strain=float(np.max(stretch[outside_hub])),
                peak_compression=compression,
                **holding_fields(hold),
                load_set=load_set,
                **common,
            )
        )
    return results
