"""The reward's weights and tiers (:class:`RewardWeights`) and their application to a batch's
metrics (:func:`add_reward`, the compiled :func:`envs.scoring.reward_rows`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .scoring import (
    N_WEIGHTS,
    W_CONTACT,
    W_CONTACT_CAP,
    W_DEFORM,
    W_DEFORM_CAP,
    W_FAIL,
    W_GAP,
    W_INVALID,
    W_MISS,
    W_SLIP,
    W_VIOLATION,
    reward_rows,
)
from .validation import check_range

MAX_WEIGHT = 1e3  # a reward weight at most: 1000 times another is no longer a weighting


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms of :func:`evaluate_designs`.

    The reward ranks outcomes in tiers, each graded so that an optimizer is pointed towards
    the tier above, and every outcome of a tier below every outcome of the tiers above:

    1. a grasp that **holds** (converged, both fingers touching, ``required_friction`` within
       the object's friction coefficient ``mu``) within the strain limit (``q =
       peak_compression / strain_limit <= 1``):
       ``contact * min(contact_score, contact_cap) - deform * q``, in ``[-deform, contact *
       contact_cap]``; one that holds but **crushes** (``q > 1``, beyond the strain limit):
       ``-deform - (F - deform) x / (1 + x)``, ``x = q - 1``, in ``(-F, -deform)``, below
       every hold within the limit (a design must not crush its object in any scenario), with
       ``F = deform * deform_cap`` (-1 with the defaults);
    2. a grasp that would **slip** (it needs more friction than ``mu``):
       ``-F - slip * x / (1 + x)``, ``x = required_friction / mu - 1`` (``x / (1 + x)`` = 1
       for an infinite need), in ``[-F - slip, -F)``: the less friction it needs, the
       higher;
    3. a **miss** (converged, a finger not touching the object):
       ``-F - slip - miss * m - gap * g / (1 + g)`` with ``m`` the fingers not touching and
       ``g`` the largest gap of such a finger to the disk, in radii: closer fingers score
       higher, in ``(-F - slip - 2 miss - gap, -F - slip - miss]``;
    4. a solver **failure** on a valid design: ``-fail``, at most the worst miss;
    5. a design **invalid** at rest: ``-invalid - violation * v / (1 + v)``, with ``v`` how far
       it is from valid (overlap depth and the other violated limits, in radii or radians;
       :func:`rest_violation`); ``invalid`` at least ``fail``.

    With the defaults: holds within the strain limit ``[-0.25, 0.5]``, crushes ``(-1, -0.25)``,
    slips ``[-1.5, -1)``, misses ``(-3, -2]``, a failure -3, invalid designs ``[-4.5, -3.5]``.
    Weights that would break the order are rejected.

    Parameters
    ----------
    contact
        Weight of the contact score (fraction of the contour in contact) [-].
    deform
        Weight of the peak compression (the largest shortening of a radius by the fingers,
        over r: how deep the grasp presses in) relative to the object's strain limit [-].
    miss
        Penalty per finger that does not touch the disk [-], > 0.
    gap
        Weight of the normalised gap ``g / (1 + g)`` of the farthest finger that does not
        touch the disk (``g`` its distance to the undeformed disk in the grasp, in radii) [-].
    invalid
        Penalty for a design that is invalid at rest (fingers overlapping the disk, ...) [-],
        at least ``fail``.
    violation
        Weight of the normalised violation ``v / (1 + v)`` of an invalid design, added to
        ``invalid`` [-].
    fail
        Penalty when the solver did not converge [-], at least ``deform * deform_cap + slip
        + 2 miss + gap``.
    contact_cap
        Cap of the contact score [-], > 0.
    deform_cap
        ``F / deform`` [-], > 1: the floor ``-F`` of the crushing grasps (keeps the reward
        bounded).
    slip
        Width of the tier of grasps that would slip [-], > 0: how much a grasp needing
        unlimited friction scores below one needing just the object's coefficient.
    """

    contact: float = 1.0
    deform: float = 0.25
    miss: float = 0.5
    gap: float = 0.5
    invalid: float = 3.5
    violation: float = 1.0
    fail: float = 3.0
    contact_cap: float = 0.5
    deform_cap: float = 4.0
    slip: float = 0.5

    def __post_init__(self) -> None:
        for f in fields(self):
            low_open = f.name.endswith("_cap") or f.name in ("slip", "miss")
            low = 1.0 if f.name == "deform_cap" else 0.0
            v = check_range(f"RewardWeights.{f.name}", getattr(self, f.name), low,
                            MAX_WEIGHT, low_open=low_open)
            object.__setattr__(self, f.name, v)
        worst_valid = self.deform * self.deform_cap + self.slip + 2 * self.miss + self.gap
        if self.fail < worst_valid:
            raise ValueError(
                f"RewardWeights.fail = {self.fail!r} must be at least deform * deform_cap + "
                f"slip + 2 miss + gap = {worst_valid!r}, so that every solver failure scores "
                "below every converged design")
        if self.invalid < self.fail:
            raise ValueError(
                f"RewardWeights.invalid = {self.invalid!r} must be at least fail = "
                f"{self.fail!r}, so that every invalid design scores below every valid one")
        weights = np.empty(N_WEIGHTS)
        for name, k in (("contact", W_CONTACT), ("contact_cap", W_CONTACT_CAP),
                        ("deform", W_DEFORM), ("deform_cap", W_DEFORM_CAP), ("miss", W_MISS),
                        ("gap", W_GAP), ("invalid", W_INVALID), ("violation", W_VIOLATION),
                        ("fail", W_FAIL), ("slip", W_SLIP)):
            weights[k] = getattr(self, name)
        weights.flags.writeable = False
        object.__setattr__(self, "_vector", weights)

    def vector(self) -> np.ndarray:
        """The weights in the layout of :func:`envs.scoring.reward_rows` (read-only)."""
        return self._vector


def add_reward(out: dict[str, np.ndarray], valid: np.ndarray, radius_m: np.ndarray,
                w: RewardWeights) -> None:
    reward_rows(w.vector(), valid, out["converged"], out["contact_score"],
                out["peak_compression"], out["strain_limit"], out["touching"],
                out["finger_gap_m"], np.ascontiguousarray(radius_m, dtype=np.float64),
                out["rest_violation"], out["required_friction"], out["friction_coefficient"],
                out["reward_contact"], out["reward_deform"], out["penalty_slip"],
                out["penalty_miss"], out["penalty_gap"], out["penalty_invalid"],
                out["penalty_fail"], out["reward"])
