"""The result of one grasp: :class:`GraspResult`.

Every field comes from the one batch pipeline (:mod:`envs.solver.pipeline`), so a grasp
simulated alone and the same grasp in a batch mean the same thing: ``converged`` is True only
when the solver claims an equilibrium, the independent check of :mod:`envs.check` confirms it
and no fan triangle is turned over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from envs.check import KKTReport
from envs.model.holding import LIMIT_NAMES
from envs.model.layout import N_CORNERS
from envs.model.loads import DEFAULT_LOAD_SET

__all__ = ["GraspResult"]


@dataclass(frozen=True)
class GraspResult:
    """Equilibrium grasp of the point-spring disk at one actuation torque.

    Attributes
    ----------
    converged : bool
        True when the solver converged *and* the independent KKT check passed.
    message : str
        ``"converged"`` or the reason for failure.
    jaw_angles_rad : tuple[float, float]
        Right and left finger angles from the +y axis [rad].
    points_m : numpy.ndarray
        Deformed contour points [m], shape (N, 2), counter-clockwise from the top.
    contact_mask : numpy.ndarray
        Whether each point touches each finger (gap ~ 0 and positive force), shape (2, N).
    contact_forces_n : numpy.ndarray
        Normal force of each finger on each point [N], shape (2, N) (thickness included).
    peak_strain : float
        Largest ``|L - L0| / L0`` over all springs [-].
    iterations : int
        Newton iterations (all rounds and the polish) or baseline iterations.
    solve_time_s : float
        Time spent in the solver [s] (all attempts; the independent check is not counted).
    torque_nm, n_triangles, method, stiffness_rule
        The problem solved.
    corner_forces_n : numpy.ndarray
        Total force of each rounded corner of each finger on the contour [N], (2, 6); corners
        in the order (``C_*`` of :mod:`envs.model.layout`): tip and root of the gripping face,
        tip and root of the back of the bar, a jaw groove's mouth edges on the tip and the
        root side (zero for a straight jaw).
    corner_edges : numpy.ndarray
        Edge ``k`` (from point k to k+1) carrying most of each corner's force, -1 for none,
        (2, 6).
    corner_edge_forces_n : numpy.ndarray
        Force of each corner on each contour edge ``k`` [N], (2, 6, N): a corner pressing on a
        vertex bears on both edges that meet there.
    stop_torques_nm : numpy.ndarray
        Reaction torque of the closed-jaw stop of each finger [N·m] (non-zero: jaws closed).
    energy_j : float
        Total potential energy (springs, actuation, torsion springs) [J].
    max_displacement_ratio : float
        Largest contour-point displacement divided by the radius [-].
    stable : bool
        The Newton matrix of the contact-constrained problem was positive definite (a strict
        local minimum, not a saddle), up to 1e-8 of the stiffness scale: a softer mode, like
        a fine one-ring fan's nearly free turn about the pin, counts as neutral
        (:data:`envs.solver.polish.NEUTRAL`).
    kkt : KKTReport
        The independent equilibrium check.
    rounds : int
        Outer rounds updating the contact candidate set.
    peak_log_strain : float
        Largest principal logarithmic (Hencky) strain ``max |ln lambda|`` over the fan
        triangles [-]: the FEM reference's measure (docs/model.md); infinite where a triangle
        has folded.
    peak_compression : float
        Largest shortening of a radius by the fingers, ``max (r - |p - C|) / r`` over the
        contour points ``p`` (``C`` the disk's centre) [-]: how deep the grasp presses into
        the object (the deformation the design reward penalises, see
        :func:`envs.evaluate_designs`; a turn about the centre does not count).
    n_rings : int
        Rings ``M`` of the point mesh (1: the paper's fan).
    element : str
        Element energy of the member solved (``"spring"``, ``"cst"`` or ``"nhquad"``).
    model_scale : float
        Factor the member's shipped calibration put on the disk's ``stiffness_scale`` (1:
        none).
    interior_points_m : numpy.ndarray
        Interior points of a ring mesh, ``((M - 1) N, 2)``, ring by ring from the hub out
        (empty for the fan) [m].
    pin_force_n : numpy.ndarray
        Force the fixed centre exerts on the object, x and y in the gripper frame [N], (2,):
        what the frictionless contacts leave unbalanced (a free object would be pushed by its
        opposite; inclined jaws push the object out, along +y).
    pin_moment_nm : float
        Moment of the fixed centre on the object about the centre [N·m]: a ring mesh's hub
        carries one; a pin carries none (the value is then the equilibrium's round-off).
    required_friction : float
        The smallest Coulomb coefficient with which friction at the contacts (tangential forces
        along the finger axes on the faces, across the normal at the corners, each at most the
        coefficient times its normal force) could carry the pin's force and moment instead [-]
        (:mod:`envs.model.holding`): 0 when nothing is carried, ``inf`` when no friction can
        (one finger touching). A symmetric grasp on the faces at finger angle ``theta`` needs
        ``tan(theta)``. The object is freed of its centre: the reaction, and the payload
        (:attr:`payload_n` > 0) in every direction of the :attr:`load_set`, are loads the
        contacts carry, their normal forces moved as the grasp's stiffness decides
        (:mod:`envs.model.loads`); this is the largest friction over those loads.
    payload_n : float
        The payload ``W = f rho pi r^2 t g`` the required friction includes [N] (0: none).
    grip_force_n : float
        The grip: the sum of the contacts' normal forces [N] (``mu`` times it is the most any
        friction can carry out of the plane).
    friction_limit : int
        What sets the required friction, a code of :mod:`envs.model.holding`
        (``LIMIT_NONE``, ``LIMIT_REACTION``, ``LIMIT_OUT_OF_PLANE``, ``LIMIT_IN_PLANE``).
    friction_limit_angle_rad : float
        For ``LIMIT_IN_PLANE``: the direction of the payload's pull on the object that needs
        most friction [rad from +x, gripper frame]; NaN otherwise.
    load_set : str
        The payload's directions checked (:data:`envs.model.loads.LOAD_SETS`): ``"top-down"``,
        ``"side"`` or ``"any"``.
    inverted_triangles : int
        Mesh triangles (the fan's: centre, point i, point i+1) turned over in the returned
        state. The
        springs allow such a fold at finite energy; a result with any is reported as not
        converged (the squeeze is beyond the model's valid range). A failed solve can also end
        on a folded iterate: :attr:`folded` tells the two apart.
    """

    converged: bool
    message: str
    jaw_angles_rad: tuple[float, float]
    points_m: np.ndarray
    contact_mask: np.ndarray
    contact_forces_n: np.ndarray
    peak_strain: float
    iterations: int
    solve_time_s: float
    torque_nm: float = 0.0
    n_triangles: int = 0
    method: str = "newton"
    stiffness_rule: str = "van_gelder"
    corner_forces_n: np.ndarray = field(default_factory=lambda: np.zeros((2, N_CORNERS)))
    corner_edges: np.ndarray = field(
        default_factory=lambda: -np.ones((2, N_CORNERS), dtype=int))
    corner_edge_forces_n: np.ndarray = field(
        default_factory=lambda: np.zeros((2, N_CORNERS, 0)))
    stop_torques_nm: np.ndarray = field(default_factory=lambda: np.zeros(2))
    energy_j: float = math.nan
    max_displacement_ratio: float = math.nan
    stable: bool = True
    kkt: KKTReport | None = None
    rounds: int = 1
    inverted_triangles: int = 0
    peak_log_strain: float = math.nan
    n_rings: int = 1
    element: str = "spring"
    model_scale: float = 1.0
    interior_points_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    peak_compression: float = math.nan
    pin_force_n: np.ndarray = field(default_factory=lambda: np.zeros(2))
    pin_moment_nm: float = 0.0
    required_friction: float = 0.0
    payload_n: float = 0.0
    grip_force_n: float = 0.0
    friction_limit: int = 0
    friction_limit_angle_rad: float = math.nan
    load_set: str = DEFAULT_LOAD_SET

    @property
    def touching(self) -> tuple[bool, bool]:
        """Whether each finger touches the disk (with its face or a corner)."""
        return tuple(bool(self.contact_mask[j].any() or self.corner_forces_n[j].sum() > 0.0)
                     for j in range(2))

    def holds(self, friction_coefficient: float) -> bool:
        """Whether this grasp would hold a free object with this Coulomb coefficient: a
        converged grasp touching with both fingers whose :attr:`required_friction` is at most
        it."""
        return bool(self.converged and all(self.touching)
                    and self.required_friction <= friction_coefficient)

    @property
    def folded(self) -> bool:
        """An equilibrium (the independent check passed) with inverted fan triangles.

        The model's own limit, not a solver failure: such a state is never passed off as a
        grasp (``converged`` is False), but unlike a failed solve it is a correct answer.
        """
        return self.inverted_triangles > 0 and self.kkt is not None and self.kkt.passed

    @property
    def n_contacts(self) -> tuple[int, int]:
        """Number of contour points touching the right and left finger faces."""
        return int(self.contact_mask[0].sum()), int(self.contact_mask[1].sum())

    @property
    def contact_fraction(self) -> float:
        """Fraction of contour points touching a finger [-]."""
        return float(self.contact_mask.any(axis=0).mean())

    @property
    def total_force_n(self) -> tuple[float, float]:
        """Total normal force of each finger on the disk (faces and corners) [N]."""
        tot = self.contact_forces_n.sum(axis=1) + self.corner_forces_n.sum(axis=1)
        return float(tot[0]), float(tot[1])

    @property
    def asymmetry_rad(self) -> float:
        """Difference between the right and left jaw angles [rad] (0 for a symmetric grasp)."""
        return float(self.jaw_angles_rad[0] - self.jaw_angles_rad[1])

    @property
    def jaw_gap_angle_rad(self) -> float:
        """Angle between the two fingers [rad] (the paper's Fig. 4 quantity)."""
        return float(self.jaw_angles_rad[0] + self.jaw_angles_rad[1])

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {
            "converged": self.converged,
            "message": self.message,
            "method": self.method,
            "torque_nm": self.torque_nm,
            "n_triangles": self.n_triangles,
            "n_rings": self.n_rings,
            "element": self.element,
            "model_scale": self.model_scale,
            "jaw_angles_rad": list(self.jaw_angles_rad),
            "peak_strain": self.peak_strain,
            "peak_log_strain": self.peak_log_strain,
            "peak_compression": self.peak_compression,
            "pin_force_n": self.pin_force_n.tolist(),
            "pin_moment_nm": self.pin_moment_nm,
            "required_friction": (self.required_friction if math.isfinite(self.required_friction)
                                  else "inf"),
            "payload_n": self.payload_n,
            "grip_force_n": self.grip_force_n,
            "friction_limit": LIMIT_NAMES[self.friction_limit],
            "friction_limit_angle_rad": (self.friction_limit_angle_rad
                                         if math.isfinite(self.friction_limit_angle_rad)
                                         else None),
            "load_set": self.load_set,
            "max_displacement_ratio": self.max_displacement_ratio,
            "n_contacts": list(self.n_contacts),
            "total_force_n": list(self.total_force_n),
            "corner_forces_n": self.corner_forces_n.tolist(),
            "stop_torques_nm": self.stop_torques_nm.tolist(),
            "energy_j": self.energy_j,
            "stable": self.stable,
            "iterations": self.iterations,
            "rounds": self.rounds,
            "inverted_triangles": self.inverted_triangles,
            "folded": self.folded,
            "solve_time_s": self.solve_time_s,
            "kkt": self.kkt._asdict() if self.kkt is not None else None,
            "points_m": self.points_m.tolist(),
        }
