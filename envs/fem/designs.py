"""The finite-element fidelity of the design evaluator: design rows -> FEM grasps -> metrics.

:func:`envs.evaluate.evaluate_designs` with ``fidelity="fem"`` solves each design valid at rest
here instead of with the point-spring model, and reports the same metric keys with the same
meaning (:func:`fem_metrics`): the fraction of the contour in contact (interpolated between rim
nodes), the grip share of the actuation torque, the largest principal logarithmic strain outside
the hub.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from envs.scene import Scene

from .grasp import fem_grasp
from .result import FemResult

__all__ = ["fem_design_grasps", "fem_metrics"]


def fem_design_grasps(scenes: Sequence[Scene], torques_nm: Sequence[float], rings: int,
                      cache: bool = True, payloads_n: Sequence[float] | None = None,
                      load_set: str = "any") -> list[FemResult]:
    """The FEM grasp of each scene at its torque, reached by ramping from the open gripper.

    One :func:`~envs.fem.fem_grasp` per scene on a mesh of ``rings`` rings (element size
    ``r / rings``), read from and written to its disk cache when ``cache``: a design is solved
    once. ``payloads_n``: each grasp's payload [N] (default none); ``load_set``: its
    directions (:data:`envs.model.loads.LOAD_SETS`).
    """
    payloads = [0.0] * len(scenes) if payloads_n is None else [float(w) for w in payloads_n]
    return [fem_grasp(scene, [float(t)], mesh_size_m=scene.disk.radius_m / rings,
                      cache=cache, payload_n=w, load_set=load_set)[0]
            for scene, t, w in zip(scenes, torques_nm, payloads, strict=True)]


def fem_metrics(results: Sequence[FemResult], radius_m: np.ndarray,
                centre_y_m: np.ndarray, centre_x_m=0.0) -> dict[str, np.ndarray]:
    """Arrays of the FEM grasps' metrics, in the evaluator's keys (see
    :func:`envs.evaluate.evaluate_designs`); rows that did not converge hold NaN and
    ``converged`` False.

    ``contact_fractions`` (B, 2) is the share of the rim in contact with each face (the
    contact's extent interpolated between rim nodes, :func:`envs.fem.contact.rim_contact_shares`;
    uncapped), ``contact_fraction`` (B,) their sum, ``contact_shares`` (B, 2) the same capped by
    Hertz's width (:attr:`FemResult.contact_shares`; NaN where a result cached before it was
    stored lacks it), ``n_contacts`` (B, 2) the rim nodes in contact, ``face_force_n`` (B, 2)
    the force each face carries (the total without the tip corner's; a grooved jaw's mouth
    edges included), ``peak_compression`` (B,) the largest shortening of a radius
    ``max (r - |p - C|) / r`` over the rim nodes ``p`` (``C = (centre_x_m, centre_y_m)``, the
    disk centre; ``centre_x_m`` 0 unless the disk was displaced across the axis), the
    point-spring model's same measure (an outline's: the grasp's own
    :attr:`~envs.fem.result.FemResult.peak_compression`, each node's shortening over its rest
    distance from the centroid).
    """
    b = len(results)
    radius_m = np.broadcast_to(np.asarray(radius_m, dtype=float), (b,))
    centre_y_m = np.broadcast_to(np.asarray(centre_y_m, dtype=float), (b,))
    centre_x_m = np.broadcast_to(np.asarray(centre_x_m, dtype=float), (b,))

    compression = np.full(b, math.nan)
    for i, r in enumerate(results):
        if r.converged and math.isfinite(r.peak_compression):
            # an outline's: each rim node's shortening over its own rest distance
            compression[i] = r.peak_compression
        elif r.converged:
            rim = np.asarray(r.contour_m, dtype=float)
            dist = np.hypot(rim[:, 0] - centre_x_m[i], rim[:, 1] - centre_y_m[i])
            compression[i] = max(0.0, float(np.max(radius_m[i] - dist))) / radius_m[i]
    ok = np.array([r.converged for r in results], dtype=bool)

    def column(get, width: int | None = None) -> np.ndarray:
        shape = (b,) if width is None else (b, width)
        out = np.full(shape, math.nan)
        for i, r in enumerate(results):
            if r.converged:
                out[i] = get(r)
        return out

    return {
        "converged": ok,
        "iterations": np.array([r.newton_iterations for r in results], dtype=np.int64),
        "n_elements": np.array([r.n_elements for r in results], dtype=np.int64),
        "jaw_angles_rad": column(lambda r: r.jaw_angles_rad, 2),
        "n_contacts": column(lambda r: r.contact_node_counts, 2),
        "tip_forces_n": column(lambda r: r.tip_forces_n, 2),
        "total_force_n": column(lambda r: r.contact_forces_n, 2),
        "contact_fraction": column(lambda r: sum(r.contact_fractions)),
        "contact_fractions": column(lambda r: r.contact_fractions, 2),
        "contact_shares": column(lambda r: r.contact_shares, 2),
        "face_force_n": column(lambda r: np.subtract(r.contact_forces_n, r.tip_forces_n), 2),
        "peak_compression": compression,
        "stop_torques_nm": column(lambda r: r.stop_torques_nm, 2),
        "peak_strain": column(lambda r: r.peak_stretch_strain),
        "peak_log_strain": column(lambda r: r.peak_strain),
        "max_displacement_ratio": column(lambda r: r.max_displacement_m) / radius_m,
        "pin_force_n": column(lambda r: r.pin_force_n, 2),
        "pin_moment_nm": column(lambda r: r.pin_moment_nm),
        "required_friction": column(lambda r: r.required_friction),
        "payload_n": column(lambda r: r.payload_n),
        "grip_force_n": column(lambda r: r.grip_force_n),
        "friction_limit": column(lambda r: r.friction_limit),
        "friction_limit_angle_rad": column(lambda r: r.friction_limit_angle_rad),
        "message": np.array([r.message for r in results], dtype=object),
    }
