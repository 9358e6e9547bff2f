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

from ..model.defaults import DEFAULT_ELEMENT, DEFAULT_MODEL_N_TRIANGLES, DEFAULT_MODEL_RINGS
from ..model.family import calibrated_disk, calibration_scale, hybrid_disk
from ..scene import Scene
from ..solver.simulate import simulate_ramp
from ..validation import check_integer, check_range
from .paper import PAPER_TORQUES_NM
from .reference import ReferenceCurve, fem_reference

__all__ = ["Member", "MemberRow", "ModelChoice", "DEFAULT_MEMBERS", "DEFAULT_MODEL",
           "choose_model"]


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


#: The default model of ``simulate``, ``evaluate_designs`` and ``GripperDesign-v2``
#: (:mod:`envs.model.defaults`): the cheapest of :data:`DEFAULT_MEMBERS` within 2 % RMS and 4 %
#: max on the held-out disks (``choose_model(list(heldout_scenes().values()), 0.04,
#: rms_tolerance=0.02)``, tested).
DEFAULT_MODEL = Member(DEFAULT_MODEL_N_TRIANGLES, DEFAULT_MODEL_RINGS, "calibrated",
                       DEFAULT_ELEMENT)

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
        failed); over several scenes, the worst scene's RMS and the largest error.
    n_failed
        Torques where the candidate did not converge.
    compiled_s_per_torque, wall_s_per_torque
        Mean compiled solve time and wall time of the ramp per torque [s].
    within_tolerance
        Every torque converged, ``max_rel_error <= tolerance`` (and ``rms_rel_error <=
        rms_tolerance`` if one was given).
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


def _worst_row(rows: Sequence[MemberRow], tolerance: float,
               rms_tolerance: float | None) -> MemberRow:
    """One member's rows over several scenes as one: the worst errors, the mean times."""
    failed = sum(r.n_failed for r in rows)
    rms = max(r.rms_rel_error for r in rows) if failed == 0 else math.nan
    worst = max(r.max_rel_error for r in rows) if failed == 0 else math.nan
    ok = failed == 0 and worst <= tolerance and (rms_tolerance is None or rms <= rms_tolerance)
    return MemberRow(rows[0].member, rms, worst, failed,
                     float(np.mean([r.compiled_s_per_torque for r in rows])),
                     float(np.mean([r.wall_s_per_torque for r in rows])), bool(ok))


def choose_model(scene: Scene | Sequence[Scene], tolerance: float = 0.02,
                 torques_nm: Sequence[float] = PAPER_TORQUES_NM, *,
                 members: Sequence[Member] = DEFAULT_MEMBERS,
                 rms_tolerance: float | None = None) -> ModelChoice:
    """Cheapest member of the model family whose closing angle stays within ``tolerance`` of
    the FEM at every torque (of every scene).

    Parameters
    ----------
    scene
        Gripper and disk (hybrid members replace the disk's scales by those of its E and nu),
        or several: a member must then be within tolerance on each. The package's default
        model is this choice over :func:`envs.accuracy.heldout_scenes` (disks no scale was
        fitted to) at 4 % max and 2 % RMS: :data:`DEFAULT_MODEL`.
    tolerance
        Largest admissible relative closing-angle error [-], in (0, 1).
    rms_tolerance
        Largest admissible RMS of that error over the torques [-], in (0, 1); ``None``: no
        RMS condition.
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
    scenes = [scene] if isinstance(scene, Scene) else list(scene) \
        if isinstance(scene, Sequence) else []
    if not scenes or not all(isinstance(sc, Scene) for sc in scenes):
        raise ValueError(f"scene must be an envs.Scene or a non-empty sequence of them, got "
                         f"{type(scene).__name__}")
    tol = check_range("tolerance", tolerance, 0.0, 1.0, low_open=True, high_open=True)
    rms_tol = None if rms_tolerance is None else check_range(
        "rms_tolerance", rms_tolerance, 0.0, 1.0, low_open=True, high_open=True)
    torques = [check_range(f"torques_nm[{i}]", t, 0.0, math.inf, low_open=True)
               for i, t in enumerate(torques_nm)]
    if not torques:
        raise ValueError("torques_nm must contain at least one torque")
    cands = tuple(members)
    if not cands or not all(isinstance(m, Member) for m in cands):
        raise ValueError("members must be a non-empty sequence of Member")
    refs = [fem_reference(sc.with_changes(stiffness_scale=1.0), torques) for sc in scenes]
    rows = tuple(_worst_row([_row(sc, ref, m, tol) for sc, ref in zip(scenes, refs, strict=True)],
                            tol, rms_tol) for m in cands)
    ok = [r for r in rows if r.within_tolerance]
    if ok:
        best = min(ok, key=lambda r: r.compiled_s_per_torque)
    else:
        best = min(rows, key=lambda r: r.max_rel_error if math.isfinite(r.max_rel_error)
                   else math.inf)
    return ModelChoice(best.member, best.within_tolerance, tol,
                       tuple(float(t) for t in refs[0].torques_nm),
                       "; ".join(dict.fromkeys(ref.source for ref in refs)), rows)
