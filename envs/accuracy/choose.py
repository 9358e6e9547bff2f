"""Choice of the number of triangles ``N`` for a tolerance (:func:`choose_n_triangles`).

Holds the module-level in-memory caches of the choices and of the solved ramps
(:func:`clear_n_cache` empties both).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .curves import PsmCurve, psm_curve


@dataclass(frozen=True)
class NChoiceRow:
    """One candidate ``N`` of :func:`choose_n_triangles`.

    Attributes
    ----------
    n_triangles
        Candidate ``N``.
    closing_rel_error
        Largest relative closing-angle difference to the reference over the torques [-]
        (NaN if a solve failed).
    strain_rel_error
        Largest relative peak-strain difference to the reference [-] (NaN if a solve failed).
    n_failed
        Torques where the candidate did not converge.
    n_retried
        Torques answered by a retry at a torque 0.1-0.3 % away (see :func:`psm_curve`).
    time_per_solve_s
        Ramp wall time divided by the number of torques [s] (failures and retries count).
    median_solve_s
        Median solver-reported time of the converged solves [s].
    within_tolerance
        All torques converged and both errors are within the tolerance.
    """

    n_triangles: int
    closing_rel_error: float
    strain_rel_error: float
    n_failed: int
    n_retried: int
    time_per_solve_s: float
    median_solve_s: float
    within_tolerance: bool

    def to_dict(self) -> dict:
        """JSON-friendly copy (NaN as ``None``)."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in ((k, getattr(self, k)) for k in self.__dataclass_fields__)}


@dataclass(frozen=True)
class NChoice:
    """Outcome of :func:`choose_n_triangles`.

    Attributes
    ----------
    n_triangles
        The smallest candidate within tolerance (the largest candidate when none is, with
        ``within_tolerance=False``).
    within_tolerance
        Whether the chosen ``N`` meets the tolerance.
    tolerance
        Relative tolerance on the closing angle and the peak strain [-].
    torques_nm
        Torques compared [N·m] (those where the reference converged).
    reference_n
        Requested ``N`` of the reference.
    reference_ns
        ``N`` of the reference actually used at each torque (a nearby ``N`` where the requested
        one did not converge).
    reference_closing_rad, reference_peak_strains
        Reference values at ``torques_nm``.
    dropped_torques_nm
        Sampled torques left out because no reference converged there.
    rows
        Candidates evaluated, in increasing ``N`` (the search stops at the first one within
        tolerance unless ``full_table=True``).
    reference_time_per_solve_s
        Reference ramp wall time divided by the number of torques [s] (failed solves and
        retries included: a fine mesh that struggles costs that time).
    time_per_solve_s
        Same for the chosen ``N`` [s].
    reference_median_solve_s, median_solve_s
        Median solver-reported time of the converged solves of the reference and of the chosen
        ``N`` [s] (the cost without failures).
    """

    n_triangles: int
    within_tolerance: bool
    tolerance: float
    torques_nm: tuple[float, ...]
    reference_n: int
    reference_ns: tuple[int, ...]
    reference_closing_rad: tuple[float, ...]
    reference_peak_strains: tuple[float, ...]
    dropped_torques_nm: tuple[float, ...]
    rows: tuple[NChoiceRow, ...]
    reference_time_per_solve_s: float
    time_per_solve_s: float
    reference_median_solve_s: float = math.nan
    median_solve_s: float = math.nan

    @property
    def speedup(self) -> float:
        """Reference time per solve divided by the chosen ``N``'s [-]."""
        return self.reference_time_per_solve_s / max(self.time_per_solve_s, 1e-12)

    @property
    def median_speedup(self) -> float:
        """Ratio of the median converged solve times, reference over chosen ``N`` [-]."""
        return self.reference_median_solve_s / max(self.median_solve_s, 1e-12)

    def row(self, n_triangles: int) -> NChoiceRow:
        """The table row of a candidate (``KeyError`` if it was not evaluated)."""
        for r in self.rows:
            if r.n_triangles == n_triangles:
                return r
        raise KeyError(n_triangles)

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {
            "n_triangles": self.n_triangles,
            "within_tolerance": self.within_tolerance,
            "tolerance": self.tolerance,
            "torques_nm": list(self.torques_nm),
            "reference_n": self.reference_n,
            "reference_ns": list(self.reference_ns),
            "reference_closing_rad": list(self.reference_closing_rad),
            "reference_peak_strains": list(self.reference_peak_strains),
            "dropped_torques_nm": list(self.dropped_torques_nm),
            "rows": [r.to_dict() for r in self.rows],
            "reference_time_per_solve_s": self.reference_time_per_solve_s,
            "time_per_solve_s": self.time_per_solve_s,
            "speedup": self.speedup,
            "reference_median_solve_s": self.reference_median_solve_s,
            "median_solve_s": self.median_solve_s,
            "median_speedup": self.median_speedup,
        }


_N_CACHE: dict[tuple, NChoice] = {}
_CURVE_CACHE: dict[tuple, PsmCurve] = {}  # ramps of choose_n_triangles, shared by its calls
DEFAULT_CANDIDATES = (4, 6, 8, 10, 12, 16, 20, 24, 32, 40, 60, 80)


def clear_n_cache() -> None:
    """Forget the results (and the solved ramps) of :func:`choose_n_triangles`."""
    _N_CACHE.clear()
    _CURVE_CACHE.clear()


def _cached_curve(scene: Scene, torques: np.ndarray, n: int, method: str, stiffness_rule: str,
                  retry: bool) -> PsmCurve:
    key = (scene, tuple(float(t) for t in torques), int(n), method, stiffness_rule, bool(retry))
    if key not in _CURVE_CACHE:
        _CURVE_CACHE[key] = psm_curve(scene, torques, n, method, stiffness_rule=stiffness_rule,
                                      retry=retry)
    return _CURVE_CACHE[key]


def _reference_values(
    scene: Scene, torques: np.ndarray, reference_n: int, method: str, stiffness_rule: str,
    retry: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Fine reference at each torque; a failed torque is retried on nearby meshes."""
    curve = _cached_curve(scene, torques, reference_n, method, stiffness_rule, retry)
    angles = np.asarray(curve.jaw_angles_rad, dtype=float)
    strains = np.asarray(curve.peak_strains, dtype=float)
    used_n = np.full(len(torques), reference_n)
    for dn in (4, -4, 8, -8):
        bad = ~np.isfinite(angles)
        if not bad.any():
            break
        alt = _cached_curve(scene, torques[bad], reference_n + dn, method, stiffness_rule,
                            retry)
        angles[bad] = alt.jaw_angles_rad
        strains[bad] = alt.peak_strains
        used_n[bad] = reference_n + dn
    return angles, strains, used_n, curve.time_per_solve_s, curve.median_converged_solve_s


def choose_n_triangles(
    scene: Scene,
    torque_range: tuple[float, float],
    tolerance: float = 0.01,
    *,
    candidates: Sequence[int] = DEFAULT_CANDIDATES,
    reference_n: int = 160,
    n_torques: int = 5,
    method: str = "newton",
    stiffness_rule: str = "van_gelder",
    full_table: bool = False,
    retry: bool = True,
) -> NChoice:
    """Smallest ``N`` whose closing angle and peak strain match a fine PSM within a tolerance.

    ``n_torques`` torques evenly spaced over ``torque_range`` are solved as a ramp with the
    reference ``N`` and with each candidate in increasing order; a candidate is accepted when it
    converges at every torque and its closing angle ``theta_a0 - theta`` and peak strain are
    within ``tolerance`` (relative) of the reference at every torque. The first accepted
    candidate is returned, so the one before it (if any) violates the tolerance.

    A reference torque that does not converge is retried with ``reference_n`` +- 4 and +- 8
    triangles (recorded in ``reference_n``) and dropped if none converges.

    Results are cached per (scene, arguments) in memory, and so are the solved ramps (calls
    that differ only by the tolerance reuse them, so their times per solve are the same
    measurements); see :func:`clear_n_cache`.

    Parameters
    ----------
    scene
        Gripper and disk (its ``stiffness_scale`` is used as is).
    torque_range
        ``(T_min, T_max)`` [N·m], ``0 < T_min <= T_max``.
    tolerance
        Relative tolerance on the closing angle and the peak strain [-], > 0.
    candidates
        Candidate ``N`` values (sorted here; each >= 4).
    reference_n
        ``N`` of the fine reference (larger than every candidate).
    n_torques
        Number of torques sampled in ``torque_range``.
    method, stiffness_rule
        PSM settings.
    full_table
        Evaluate every candidate (the choice is the same; the table is complete).
    retry
        Retry isolated solver failures at a torque 0.1-0.3 % away (see :func:`psm_curve`);
        a candidate must still answer at every torque.

    Returns
    -------
    NChoice
        The chosen ``N`` with the errors table and the time per solve.

    Raises
    ------
    ValueError
        For an invalid range, tolerance or candidate list.
    """
    try:
        t_lo, t_hi = (float(v) for v in torque_range)
    except (TypeError, ValueError):
        raise ValueError("torque_range must be a pair (T_min, T_max) of numbers") from None
    if not (math.isfinite(t_lo) and math.isfinite(t_hi) and 0 < t_lo <= t_hi):
        raise ValueError(f"torque_range must satisfy 0 < T_min <= T_max, got {torque_range!r}")
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be > 0, got {tolerance!r}")
    cands = tuple(sorted({int(c) for c in candidates}))
    if not cands or cands[0] < 4:
        raise ValueError("candidates must be a non-empty list of integers >= 4")
    if int(reference_n) <= cands[-1]:
        raise ValueError(
            f"reference_n = {reference_n} must be larger than every candidate (max {cands[-1]})"
        )
    if int(n_torques) < 1:
        raise ValueError("n_torques must be >= 1")
    key = (scene, t_lo, t_hi, float(tolerance), cands, int(reference_n), int(n_torques), method,
           stiffness_rule, bool(full_table), bool(retry))
    if key in _N_CACHE:
        return _N_CACHE[key]

    torques = np.linspace(t_lo, t_hi, int(n_torques))
    th0 = scene.gripper.rest_angle_rad
    angles, strains, used_n, ref_time, ref_median = _reference_values(
        scene, torques, int(reference_n), method, stiffness_rule, bool(retry)
    )
    keep = np.isfinite(angles)
    dropped = tuple(float(t) for t in torques[~keep])
    torques, angles, strains, used_n = torques[keep], angles[keep], strains[keep], used_n[keep]
    c_ref = th0 - angles
    rows: list[NChoiceRow] = []
    chosen: NChoiceRow | None = None
    if torques.size:
        for n in cands:
            curve = _cached_curve(scene, torques, n, method, stiffness_rule, retry)
            c = th0 - np.asarray(curve.jaw_angles_rad)
            s = np.asarray(curve.peak_strains)
            e_c = float(np.max(np.abs(c / c_ref - 1))) if curve.n_failed == 0 else math.nan
            e_s = float(np.max(np.abs(s / strains - 1))) if curve.n_failed == 0 else math.nan
            ok = curve.n_failed == 0 and e_c <= tolerance and e_s <= tolerance
            row = NChoiceRow(n, e_c, e_s, curve.n_failed, curve.n_retried,
                             curve.time_per_solve_s, curve.median_converged_solve_s, bool(ok))
            rows.append(row)
            if ok and chosen is None:
                chosen = row
                if not full_table:
                    break
    if chosen is None:
        chosen = rows[-1] if rows else NChoiceRow(cands[-1], math.nan, math.nan, 0, 0,
                                                  math.nan, math.nan, False)
    out = NChoice(
        n_triangles=chosen.n_triangles,
        within_tolerance=chosen.within_tolerance,
        tolerance=float(tolerance),
        torques_nm=tuple(float(t) for t in torques),
        reference_n=int(reference_n),
        reference_ns=tuple(int(v) for v in used_n),
        reference_closing_rad=tuple(float(v) for v in c_ref),
        reference_peak_strains=tuple(float(v) for v in strains),
        dropped_torques_nm=dropped,
        rows=tuple(rows),
        reference_time_per_solve_s=float(ref_time),
        time_per_solve_s=float(chosen.time_per_solve_s),
        reference_median_solve_s=float(ref_median),
        median_solve_s=float(chosen.median_solve_s),
    )
    _N_CACHE[key] = out
    return out
