"""PSM jaw-angle curves along a loading ramp (:class:`PsmCurve`, :func:`psm_curve`).

Includes the optional retry of an isolated solver failure at a torque 0.1-0.3 % away
(:data:`RETRY_FACTORS`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..scene import Scene
from ..solver import GraspResult, simulate, simulate_ramp

#: Torque factors of the retries of :func:`psm_curve` (``retry=True``).
RETRY_FACTORS = (1.001, 0.999, 1.003, 0.997)


@dataclass(frozen=True)
class PsmCurve:
    """PSM results along a torque ramp (in the order of the requested torques).

    Attributes
    ----------
    torques_nm
        Requested torques [N·m].
    jaw_angles_rad
        Mean finger angle [rad], NaN where the solve did not converge.
    peak_strains
        Peak spring strain [-], NaN where the solve did not converge.
    converged
        Convergence flag of each solve.
    messages
        Solver message of each solve.
    solve_times_s
        Solver-reported wall time of each solve [s].
    wall_time_s
        Wall time of the whole ramp [s] (retries included).
    retried
        Per torque, 1.0 when the ramp solve converged, otherwise the factor ``f`` of the
        perturbed torque ``f T`` whose independent solve answered in its place (``nan`` when
        no retry converged, or retries were off).
    results
        The raw :class:`envs.solver.GraspResult` objects (not compared, not serialised).
    """

    torques_nm: tuple[float, ...]
    jaw_angles_rad: tuple[float, ...]
    peak_strains: tuple[float, ...]
    converged: tuple[bool, ...]
    messages: tuple[str, ...]
    solve_times_s: tuple[float, ...]
    wall_time_s: float
    retried: tuple[float, ...] = ()
    results: tuple[GraspResult, ...] = field(default=(), compare=False, repr=False)

    @property
    def n_retried(self) -> int:
        """Number of torques answered by a retry at a slightly perturbed torque."""
        return int(sum(1 for f in self.retried if math.isfinite(f) and f != 1.0))

    @property
    def n_failed(self) -> int:
        """Number of torques whose solve did not converge."""
        return int(len(self.converged) - sum(self.converged))

    @property
    def time_per_solve_s(self) -> float:
        """Ramp wall time divided by the number of torques [s] (failures and retries count)."""
        return self.wall_time_s / max(1, len(self.torques_nm))

    @property
    def median_converged_solve_s(self) -> float:
        """Median solver-reported time of the converged solves [s] (NaN if none)."""
        t = [dt for dt, ok in zip(self.solve_times_s, self.converged, strict=True) if ok]
        return float(np.median(t)) if t else math.nan


def psm_curve(
    scene: Scene,
    torques_nm: Sequence[float],
    n_triangles: int = 20,
    method: str = "newton",
    *,
    stiffness_rule: str = "van_gelder",
    time_limit_s: float = 30.0,
    retry: bool = False,
) -> PsmCurve:
    """Solve the PSM along a loading ramp through ``torques_nm`` (any order, solved sorted).

    Non-converged solves give NaN angles and strains with ``converged=False``; nothing raises
    for a solver failure.

    The Newton solver occasionally fails at an isolated torque of a ramp while it converges at a
    torque 0.1 % away (its failures are not a property of the model). With ``retry=True`` a
    failed torque ``T`` is re-solved independently (from rest) at ``f T`` for ``f`` in
    :data:`RETRY_FACTORS`, and the first converged answer is used in its place, which changes
    the closing angle by less than 0.3 % of its value (unless the solve from rest reaches
    another equilibrium branch than the ramp); the factor is recorded in ``retried``. Use
    ``retry=False`` (default) to measure the solver itself.

    Parameters
    ----------
    scene
        Gripper and disk (its ``stiffness_scale`` is used as is).
    torques_nm
        Torques [N·m], >= 0.
    n_triangles, method, stiffness_rule, time_limit_s
        See :func:`envs.solver.simulate`.
    retry
        Retry failed torques as described above.

    Returns
    -------
    PsmCurve
        Results in the order of ``torques_nm``.
    """
    torques = np.asarray(torques_nm, dtype=float).ravel()
    order = np.argsort(torques, kind="stable")
    t0 = time.perf_counter()
    raw = simulate_ramp(scene, torques[order], n_triangles, method,
                        stiffness_rule=stiffness_rule, time_limit_s=time_limit_s, element="spring")
    res: list[GraspResult] = [None] * len(torques)  # type: ignore[list-item]
    for k, i in enumerate(order):
        res[i] = raw[k]
    retried = [1.0 if r.converged else math.nan for r in res]
    if retry:
        for i, r in enumerate(res):
            if r.converged or torques[i] <= 0:
                continue
            for f in RETRY_FACTORS:
                alt = simulate(scene, float(torques[i] * f), n_triangles, method,
                               stiffness_rule=stiffness_rule, time_limit_s=time_limit_s,
                                   element="spring")
                if alt.converged:
                    res[i], retried[i] = alt, f
                    break
    wall = time.perf_counter() - t0
    angles = tuple(float(np.mean(r.jaw_angles_rad)) if r.converged else math.nan for r in res)
    strains = tuple(float(r.peak_strain) if r.converged else math.nan for r in res)
    return PsmCurve(
        torques_nm=tuple(float(t) for t in torques),
        jaw_angles_rad=angles,
        peak_strains=strains,
        converged=tuple(bool(r.converged) for r in res),
        messages=tuple(str(r.message) for r in res),
        solve_times_s=tuple(float(r.solve_time_s) for r in res),
        wall_time_s=wall,
        retried=tuple(retried),
        results=tuple(res),
    )
