"""Accuracy of the point-spring model (PSM): stiffness calibration and choice of ``N``.

The paper (section 3) calibrates the spring stiffnesses of the PSM on one finite-element grasp
and then studies how the jaw angle depends on the number of triangles ``N``. This package
provides the two tools behind those studies:

* :func:`calibrate` fits the stiffness scale ``s`` of the disk (``SoftDisk.stiffness_scale``),
  and optionally (``fit="scale_and_ratio"``) also the contour-only factor
  ``SoftDisk.contour_stiffness_ratio``, so that the PSM jaw angle along a torque ramp matches a
  reference curve (usually the FEM of :func:`envs.fem.fem_grasp`, see :func:`fem_reference`),
  and reports the error of the jaw *closing* angle ``theta_a0 - theta`` on the fitted curve and
  on held-out cases (other torques, other objects; see :func:`paper_heldout_cases`);
  :meth:`CalibrationResult.errors_on` evaluates any further case;
* :func:`choose_n_triangles` picks the smallest ``N`` whose closing angle and peak strain stay
  within a relative tolerance of a fine PSM reference over a torque range (cached per scene).

Conventions (``docs/model.md``): the jaw angle of a reference curve is the finger angle
``theta`` from the +y axis [rad] (mean of the right and left fingers); the closing angle is
``theta_a0 - theta`` with ``theta_a0`` the gripper's rest angle; relative errors are
``closing_psm / closing_ref - 1``. Every PSM curve is solved as a loading ramp
(:func:`envs.solver.simulate_ramp`), as in the paper; a torque whose solve does not converge is
reported (``converged=False``, NaN values) and left out of the error statistics. The accuracy
functions first retry such a torque at a torque 0.1-0.3 % away (``retry=True``, see
:func:`psm_curve`; the number of retried torques is reported), because the Newton solver's
failures are isolated and not a property of the model; pass ``retry=False`` to measure the
solver as it is.

Layout
------
:mod:`.paper` (the paper's disks and torque ramps), :mod:`.reference` (:class:`ReferenceCurve`,
:func:`fem_reference`), :mod:`.curves` (:class:`PsmCurve`, :func:`psm_curve`), :mod:`.errors`
(:class:`ErrorReport`, :func:`closing_errors`), :mod:`.fitting` (the calibration objective and
its scale and scale-and-ratio fits), :mod:`.calibration` (:class:`CalibrationResult`,
:func:`calibrate`), :mod:`.heldout` (:func:`paper_heldout_cases`), :mod:`.choose`
(:func:`choose_n_triangles` and its in-memory caches), :mod:`.pareto` (:func:`pareto_front`)
and :mod:`.jsonable` (:func:`jsonable`).
"""

from __future__ import annotations

from .calibration import CALIBRATION_FITS, CalibrationResult, calibrate
from .choose import DEFAULT_CANDIDATES as DEFAULT_CANDIDATES
from .choose import NChoice, NChoiceRow, choose_n_triangles, clear_n_cache
from .curves import RETRY_FACTORS, PsmCurve, psm_curve
from .errors import ErrorReport, closing_errors
from .heldout import heldout_scenes, paper_heldout_cases
from .jsonable import jsonable
from .members import DEFAULT_MEMBERS, DEFAULT_MODEL, Member, MemberRow, ModelChoice, choose_model
from .paper import HELDOUT_TORQUES_NM, PAPER_SCENES, PAPER_TORQUES_NM
from .pareto import pareto_front
from .reference import ReferenceCurve, fem_reference

__all__ = [
    "PAPER_SCENES",
    "PAPER_TORQUES_NM",
    "HELDOUT_TORQUES_NM",
    "RETRY_FACTORS",
    "ReferenceCurve",
    "PsmCurve",
    "ErrorReport",
    "CalibrationResult",
    "CALIBRATION_FITS",
    "NChoiceRow",
    "NChoice",
    "fem_reference",
    "psm_curve",
    "closing_errors",
    "calibrate",
    "paper_heldout_cases",
    "heldout_scenes",
    "choose_n_triangles",
    "choose_model",
    "Member",
    "MemberRow",
    "ModelChoice",
    "DEFAULT_MEMBERS",
    "DEFAULT_MODEL",
    "clear_n_cache",
    "pareto_front",
    "jsonable",
]
