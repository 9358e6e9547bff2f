"""The cheapest member of the model family for a tolerance (:func:`choose_model`).

A member is named by its contour points ``N``, rings ``M``, element energy and material scales:
the paper's fan (``M = 1``, the disk's own ``stiffness_scale``, springs only unless the disk
says otherwise), a spring ring mesh with the physics-derived hybrid scales
(:func:`envs.model.family.hybrid_scales`) or a constant-strain ring mesh with its shipped
calibration (:data:`envs.model.family.CST_SCALES`).
:func:`choose_model` ramps each candidate through the torques, compares its closing angle with
the FEM reference of the same scene (:func:`envs.accuracy.fem_reference`, disk-cached) and
returns the cheapest one (measured compiled time per torque) within the tolerance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..model.family import calibrated_disk, calibration_scale, hybrid_disk
from ..scene import Scene
from ..solver.simulate import simulate_ramp
from ..validation import check_integer, check_range
from .paper import PAPER_TORQUES_NM
from .reference import ReferenceCurve, fem_reference

__all__ = ["Member", "MemberRow", "ModelChoice", "DEFAULT_MEMBERS", "choose_model"]


@dataclass(frozen=True)
class Member:
    """One member of the model family.

    Attributes
    ----------
    n_triangles
        Contour points ``N`` (4 to 20000).
    n_rings
        Rings ``M`` (1: the paper's fan).
    scales
        ``"disk"``: the disk's own ``stiffness_scale`` and ``area_stiffness_scale`` (the
        paper's model for a preset); ``"hybrid"``: the spring member's scales derived from E
        and nu (:func:`envs.model.family.hybrid_scales`); ``"calibrated"``: the member's
        shipped scale (:func:`envs.model.family.calibration_scale`) times the disk's own.
    element
        ``"spring"`` (springs and the area energy), ``"cst"`` (constant-strain neo-Hookean
        triangles) or ``"nhquad"`` (their deviatoric part, a volumetric term per quad).
    """

    n_triangles: int
    n_rings: int = 1
    scales: str = "disk"
    element: str = "spring"

    def __post_init__(self) -> None:
        check_integer("n_triangles", self.n_triangles, 4, 20000)
        check_integer("n_rings", self.n_rings, 1, 16)
        if self.scales not in ("disk", "hybrid", "calibrated"):
            raise ValueError(f"scales must be 'disk', 'hybrid' or 'calibrated', got "
                             f"{self.scales!r}")
        if self.element not in ("spring", "cst", "nhquad"):
            raise ValueError(f"element must be 'spring', 'cst' or 'nhquad', got "
                             f"{self.element!r}")
        if self.element == "nhquad" and self.n_rings < 2:
            raise ValueError(f"n_rings must be 2 to 16 for element 'nhquad', got "
                             f"{self.n_rings}")
        if self.scales == "calibrated":
            calibration_scale(self.n_triangles, self.n_rings, self.element)

    def scene(self, scene: Scene) -> Scene:
        """The scene as this member models it (its disk's scales set): solve it with
        ``calibrated=False``, the member's scale is already on the disk."""
        if self.scales == "hybrid":
            return replace(scene, disk=hybrid_disk(scene.disk))
        if self.scales == "calibrated":
            return replace(scene, disk=calibrated_disk(scene.disk, self.n_triangles,
                                                       self.n_rings, self.element))
        return scene

    @property
    def label(self) -> str:
        return f"N={self.n_triangles} M={self.n_rings} {self.element} {self.scales}"


#: Candidates of :func:`choose_model`, roughly by cost.
DEFAULT_MEMBERS = (
    Member(20, 1), Member(20, 2, "hybrid"), Member(20, 3, "hybrid"), Member(24, 4, "hybrid"),
    Member(20, 3, "calibrated", "cst"), Member(32, 2, "calibrated", "nhquad"),
    Member(40, 2, "calibrated", "nhquad"), Member(24, 4, "calibrated", "cst"),
    Member(48, 3, "calibrated", "nhquad"), Member(56, 4, "calibrated", "nhquad"),
    Member(32, 6, "calibrated", "cst"), Member(80, 6, "calibrated", "nhquad"),
    Member(48, 8, "calibrated", "cst"),
)


@dataclass(frozen=True)
class MemberRow:
    """A candidate's errors against the reference and its cost.

    Attributes
    ----------
    member
        The candidate.
    rms_rel_error, max_rel_error
        RMS and largest relative closing-angle error over the torques [-] (NaN if a solve
        failed).
    n_failed
        Torques where the candidate did not converge.
    compiled_s_per_torque, wall_s_per_torque
        Mean compiled solve time and wall time of the ramp per torque [s].
    within_tolerance
        Every torque converged and ``max_rel_error <= tolerance``.
    """

    member: Member
    rms_rel_error: float
    max_rel_error: float
    n_failed: int
    compiled_s_per_torque: float
    wall_s_per_torque: float
    within_tolerance: bool


@dataclass(frozen=True)
class ModelChoice:
    """Outcome of :func:`choose_model`: the chosen member (the most accurate candidate when
    none is within tolerance, with ``within_tolerance = False``) and the whole table."""

    member: Member
    within_tolerance: bool
    tolerance: float
    torques_nm: tuple[float, ...]
    reference: str
    rows: tuple[MemberRow, ...]


def _row(scene: Scene, ref: ReferenceCurve, member: Member, tolerance: float) -> MemberRow:
    import time

    t0 = time.perf_counter()
    out = simulate_ramp(member.scene(scene), list(ref.torques_nm), member.n_triangles,
                        n_rings=member.n_rings, element=member.element,
                        calibrated=False)
    wall = (time.perf_counter() - t0) / len(out)
    failed = sum(not r.converged for r in out)
    th0 = scene.gripper.rest_angle_rad
    err = (th0 - np.array([np.mean(r.jaw_angles_rad) for r in out])) / ref.closing_rad(scene) - 1
    rms = float(np.sqrt(np.mean(err**2))) if failed == 0 else math.nan
    worst = float(np.max(np.abs(err))) if failed == 0 else math.nan
    compiled = float(np.mean([r.solve_time_s for r in out]))
    return MemberRow(member, rms, worst, failed, compiled, wall,
                     bool(failed == 0 and worst <= tolerance))


def choose_model(scene: Scene, tolerance: float = 0.02,
                 torques_nm: Sequence[float] = PAPER_TORQUES_NM, *,
                 members: Sequence[Member] = DEFAULT_MEMBERS) -> ModelChoice:
    """Cheapest member of the model family whose closing angle stays within ``tolerance`` of
    the FEM at every torque.

    Parameters
    ----------
    scene
        Gripper and disk (hybrid members replace the disk's scales by those of its E and nu).
    tolerance
        Largest admissible relative closing-angle error [-], in (0, 1).
    torques_nm
        The torque ramp compared (non-decreasing, > 0) [N·m]; the FEM reference is computed
        once for it (tens of seconds, then cached on disk).
    members
        Candidates; every one is solved (the table is complete) and the cheapest by measured
        compiled time per torque within tolerance wins.

    Returns
    -------
    ModelChoice
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be an envs.Scene, got {type(scene).__name__}")
    tol = check_range("tolerance", tolerance, 0.0, 1.0, low_open=True, high_open=True)
    torques = [check_range(f"torques_nm[{i}]", t, 0.0, math.inf, low_open=True)
               for i, t in enumerate(torques_nm)]
    if not torques:
        raise ValueError("torques_nm must contain at least one torque")
    cands = tuple(members)
    if not cands or not all(isinstance(m, Member) for m in cands):
        raise ValueError("members must be a non-empty sequence of Member")
    ref = fem_reference(scene.with_changes(stiffness_scale=1.0), torques)
    rows = tuple(_row(scene, ref, m, tol) for m in cands)
    ok = [r for r in rows if r.within_tolerance]
    if ok:
        best = min(ok, key=lambda r: r.compiled_s_per_torque)
    else:
        best = min(rows, key=lambda r: r.max_rel_error if math.isfinite(r.max_rel_error)
                   else math.inf)
    return ModelChoice(best.member, best.within_tolerance, tol,
                       tuple(float(t) for t in ref.torques_nm), ref.source, rows)
