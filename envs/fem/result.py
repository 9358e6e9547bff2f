"""The finite-element grasp state at one torque (:class:`FemResult`) and its JSON round trip."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np


@dataclass(frozen=True, eq=False)
class FemResult:
    """Finite-element grasp state at one actuation torque.

    Attributes
    ----------
    torque_nm
        Actuation torque ``T_a`` of each finger [N·m].
    jaw_angles_rad
        ``(theta_R, theta_L)`` [rad] (NaN when not converged).
    converged
        Whether Newton converged and all post-checks passed.
    message
        ``"converged"`` (``"converged (jaws on the closed stop)"`` when the disk is out of reach
        and the jaws rest on the ``closed_angle_rad`` stop) or the reason of the failure.
    contour_m
        Deformed positions of all rim nodes of the P2 mesh (vertices and midside nodes), ordered
        counter-clockwise by their reference polar angle about the disk centre starting at the
        top (angle pi/2), shape ``(M, 2)`` [m].
    contact_forces_n
        Total normal contact force on the right and left jaw [N] (whole thickness).
    peak_strain
        Largest magnitude of the in-plane principal logarithmic (Hencky) strain
        ``max |ln lambda_i|`` over the quadrature points outside the hub [-], excluding the layer
        ``hub_radius_m < rho <= 2 hub_radius_m`` around it: the clamped rigid hub carries the
        net jaw force and causes a local strain concentration at its edge (an artefact of the
        hub model, reported separately as ``hub_edge_peak_strain``).
    n_elements
        Number of quadratic triangles.
    n_dofs
        Number of unknowns: free displacement dofs (hub dofs excluded) plus the two angles.
    mesh_size_m
        Element size ``r / rings`` of the structured disk mesh [m].
    solve_time_s
        Wall time of the solve [s] (of the original solve when read from the cache; ignored by
        ``==``, which compares the physical results).
    newton_iterations
        Newton iterations spent on this torque (including bisected sub-steps).
    max_penetration_m
        Largest penetration of a rim node into a jaw or of a jaw corner into the rim [m]
        (penalty artefact; reduce it with ``al_iterations``).
    max_displacement_m
        Largest rim-node displacement [m].
    contact_node_counts
        Number of rim nodes in contact with the right and left jaw's face.
    tip_forces_n
        Part of ``contact_forces_n`` carried by each finger's tip corner [N] (0 when the corner
        does not touch the disk); a grooved jaw's mouth edges are corners too, their forces in
        ``contact_forces_n`` but not here.
    plane
        ``"strain"`` or ``"stress"``.
    hub_radius_m
        Radius of the rigid hub [m].
    hub_edge_peak_strain
        Same strain measure over the layer ``hub_radius_m < rho <= 2 hub_radius_m`` [-].
    contact_fractions
        Share of the rim in contact with the right and left jaw's face [-], the contact's
        extent interpolated between rim nodes from their pressures and gaps
        (:func:`envs.fem.contact.rim_contact_shares`): the point-spring model's measure of the
        fraction of the contour in contact (:mod:`envs.model.contact_width`), continuous in
        the design. On a grooved jaw a free node's gap is to the grooved solid.
    contact_shares
        The same share at most the physical width (Hertz line contact) [-]: a straight face's
        extent at most the width of its force on a flat face, a grooved jaw's contact segments
        each at most the width of its own force on the jaw's curvature under it (a cradle that
        fits the disk is not capped; each flank of a V is a flat contact of its own). NaN in
        results cached before it was stored (straight faces: the flat cap of the face's force,
        :func:`envs.model.contact_width.contact_share`, gives it).
    stop_torques_nm
        Torque the closed-jaw stop takes from each finger [N·m] (0 unless the jaws are on it).
    peak_stretch_strain
        Largest principal engineering strain ``max |lambda_i - 1|`` over the same quadrature
        points as ``peak_strain`` [-]: the largest relative length change of any material fibre
        (the FEM's counterpart of the point-spring model's largest spring strain).
    pin_force_n
        Force the rigid hub exerts on the disk, x and y [N] (NaN when not converged): what
        the frictionless contacts leave unbalanced (:mod:`envs.model.holding`).
    pin_moment_nm
        The hub's moment on the disk about its centre [N·m].
    required_friction
        The smallest Coulomb coefficient with which friction at the contacts (rim nodes on the
        faces, the tip corners) could carry the hub's force and moment instead [-]
        (:mod:`envs.model.holding`, the point-spring model's definition): the freed disk's
        grasp under the hub's reaction and, where one is given, the payload in every direction
        of :attr:`load_set`, its normal forces moved by the FEM's own compliance
        (:mod:`envs.fem.loaded`).
    payload_n, grip_force_n, friction_limit, friction_limit_angle_rad
        The payload the required friction includes [N], the sum of the contacts' normal forces
        [N], what sets the required friction (a ``LIMIT_*`` code of :mod:`envs.model.holding`)
        and, for an in-plane payload, the direction of its worst pull [rad] (as in
        :class:`envs.solver.result.GraspResult`).
    peak_compression
        An outline's largest shortening of a rim node's distance from the centroid over its
        rest distance, ``max (r_i - |p_i - C|) / r_i`` [-] (the point-spring model's measure);
        NaN for a disk (:func:`envs.fem.designs.fem_metrics` measures it from ``contour_m``).
    load_set
        The payload's directions checked (:data:`envs.model.loads.LOAD_SETS`).
    from_cache
        Whether the result was read from the disk cache (ignored by ``==``).
    """

    torque_nm: float
    jaw_angles_rad: tuple[float, float]
    converged: bool
    message: str
    contour_m: np.ndarray
    contact_forces_n: tuple[float, float]
    peak_strain: float
    n_elements: int
    n_dofs: int
    mesh_size_m: float
    solve_time_s: float = field(compare=False)
    newton_iterations: int
    max_penetration_m: float = math.nan
    max_displacement_m: float = math.nan
    contact_node_counts: tuple[int, int] = (0, 0)
    tip_forces_n: tuple[float, float] = (0.0, 0.0)
    plane: str = "strain"
    hub_radius_m: float = math.nan
    hub_edge_peak_strain: float = math.nan
    contact_fractions: tuple[float, float] = (math.nan, math.nan)
    contact_shares: tuple[float, float] = (math.nan, math.nan)
    stop_torques_nm: tuple[float, float] = (0.0, 0.0)
    peak_stretch_strain: float = math.nan
    pin_force_n: tuple[float, float] = (math.nan, math.nan)
    pin_moment_nm: float = math.nan
    required_friction: float = math.nan
    payload_n: float = 0.0
    grip_force_n: float = math.nan
    friction_limit: int = 0
    friction_limit_angle_rad: float = math.nan
    peak_compression: float = math.nan
    load_set: str = "any"
    from_cache: bool = field(default=False, compare=False)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, FemResult):
            return NotImplemented
        for f in fields(self):
            if not f.compare:
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, str) or isinstance(b, str):
                if a != b:
                    return False
            elif not np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True):
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def to_json(self) -> dict:
        """JSON-serialisable dict (floats round-trip exactly)."""
        out = {}
        for f in fields(self):
            if f.name == "from_cache":
                continue
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple):
                v = list(v)
            out[f.name] = v
        return out

    @classmethod
    def from_json(cls, data: dict, from_cache: bool = True) -> FemResult:
        """Inverse of :meth:`to_json`."""
        kw = dict(data)
        kw["contour_m"] = np.asarray(kw["contour_m"], dtype=float).reshape(-1, 2)
        kw["jaw_angles_rad"] = tuple(float(v) for v in kw["jaw_angles_rad"])
        kw["contact_forces_n"] = tuple(float(v) for v in kw["contact_forces_n"])
        kw["contact_node_counts"] = tuple(int(v) for v in kw["contact_node_counts"])
        for name in ("tip_forces_n", "contact_fractions", "stop_torques_nm", "pin_force_n"):
            kw[name] = tuple(float(v) for v in kw[name])
        if "contact_shares" in kw:  # (absent from results cached before it was stored)
            kw["contact_shares"] = tuple(float(v) for v in kw["contact_shares"])
        return cls(**kw, from_cache=from_cache)
