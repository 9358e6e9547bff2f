"""The nonlinear solve: damped Newton, strong-Wolfe line search, load ramp with bisection.

:func:`_newton` solves one load, :func:`_solve_load` adds the augmented-Lagrangian passes and
the acceptance check, :func:`_ramp` walks a load ramp with secant predictors and step
bisection.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .system import _System

_MAX_NEWTON = 40
_MAX_BISECTIONS = 12


@dataclass
class _NewtonReport:
    converged: bool
    iterations: int
    message: str


def _line_search(
    system: _System, x: np.ndarray, dx: np.ndarray, e0: float, slope: float, load: float
) -> tuple[np.ndarray, bool]:
    """Bracketing line search on ``phi(a) = Pi(x + a dx)`` (strong Wolfe conditions).

    The full Newton step is taken when it satisfies Armijo's condition and does not overshoot
    the minimum along the line (``phi'(1) <= eta |phi'(0)|``). Otherwise the minimum is bracketed
    and located by safeguarded regula falsi on ``phi'`` until ``|phi'(a)| <= eta |phi'(0)|``:
    an accurate line minimum matters when the Newton model does not yet see a contact that is
    about to close (otherwise the steps would only creep towards the contact). Trial points with
    an inverted element or with a penetration beyond the system's cap (which would let a node or
    a tip corner tunnel through) count as overshoots. ``phi'`` is evaluated from the gradient, so
    the search stays meaningful when energy differences are at round-off level.
    """
    free = system.free
    eta = 0.25
    pen_cap = system.penetration_cap(x)
    lo, d_lo = 0.0, slope
    hi, d_hi = math.inf, math.inf
    alpha = 1.0
    best: np.ndarray | None = None
    for _ in range(60):
        xt = x.copy()
        xt[free] += alpha * dx
        et, gt = (math.inf, None)
        if system.penetration(xt) <= pen_cap:
            et, gt = system.energy_gradient(xt, load)
        if gt is None or not math.isfinite(et):
            hi, d_hi = alpha, math.inf
        else:
            dphi = float(gt[free] @ dx)
            floor = 1e-12 * (abs(e0) + abs(et))
            armijo = et <= e0 + 1e-4 * alpha * slope + floor
            if armijo and abs(dphi) <= eta * abs(slope):
                return xt, True
            if armijo and dphi < 0:
                if alpha == 1.0:
                    return xt, True  # the Newton step is still descending: take it
                lo, d_lo = alpha, dphi
                best = xt
            else:
                hi, d_hi = alpha, dphi if dphi > 0 else math.inf
        width = hi - lo
        if math.isfinite(d_hi) and d_hi > 0 > d_lo:
            a_new = lo + width * (-d_lo) / (d_hi - d_lo)
        else:
            a_new = lo + 0.25 * width
        if not lo + 0.05 * width <= a_new <= hi - 0.05 * width:
            a_new = lo + 0.5 * width
        alpha = a_new
        if width < 1e-14:
            break
    if best is not None:
        return best, True
    return x, False


def _newton(system: _System, x: np.ndarray, load: float) -> tuple[np.ndarray, _NewtonReport]:
    """Damped Newton on the total potential (energy line search, inversion guard)."""
    free = system.free
    nq = system.nq
    nu = free.size - nq
    x = x.copy()
    for it in range(_MAX_NEWTON):
        out = system.evaluate(x, load)
        if out is None:
            return x, _NewtonReport(False, it, "inverted element (det F <= 0) at the start point")
        e0, g, k = out
        if not math.isfinite(e0) or not np.all(np.isfinite(g)):
            return x, _NewtonReport(False, it, "non-finite energy or residual")
        if system.converged(g):
            return x, _NewtonReport(True, it, "converged")
        gf = g[free]
        kff = k[free][:, free].tocsr()
        try:
            dx = system.solve(kff, -gf)
        except RuntimeError:
            dx = None
        slope = float(gf @ dx) if dx is not None and np.all(np.isfinite(dx)) else math.nan
        if not slope < 0:
            # not a descent direction (indefinite tangent): shift towards the diagonal
            diag = np.abs(kff.diagonal()) + 1e-30
            shift = 1e-3
            while shift < 1e6:
                try:
                    dx = system.solve(kff + sp.diags(shift * diag), -gf)
                    slope = float(gf @ dx)
                except RuntimeError:
                    slope = math.nan
                if slope < 0:
                    break
                shift *= 10
            else:
                return x, _NewtonReport(False, it, "no descent direction found")
        # round-off floor: a negligible Newton correction with a nearly converged residual
        step_u = float(np.max(np.abs(dx[:nu]), initial=0.0))
        step_q = float(np.max(np.abs(dx[nu:]) * system.q_scale, initial=0.0))
        if max(step_u, step_q) < 1e-10 * system.length_scale_m and system.residual_ratio(g) < 1e3:
            return x, _NewtonReport(True, it, "converged (round-off floor)")
        xt, ok = _line_search(system, x, dx, e0, slope, load)
        if not ok:
            return x, _NewtonReport(False, it, "line search failed")
        x = xt
    out = system.evaluate(x, load)
    if out is not None and system.converged(out[1]):
        return x, _NewtonReport(True, _MAX_NEWTON, "converged")
    return x, _NewtonReport(False, _MAX_NEWTON, f"no convergence in {_MAX_NEWTON} Newton steps")


def _solve_load(
    system: _System,
    x: np.ndarray,
    load: float,
    al_iterations: int,
    accept: Callable[[np.ndarray], str | None],
) -> tuple[np.ndarray, _NewtonReport]:
    """Newton solve at one load, with optional augmented-Lagrangian passes and a final check."""
    saved = [m.copy() for m in system.multipliers]
    saved_c = system.corner_multipliers.copy()
    total = 0
    xs, rep = _newton(system, x, load)
    total += rep.iterations
    for _ in range(al_iterations):
        if not rep.converged:
            break
        system.update_multipliers(xs, load)
        xs, rep = _newton(system, xs, load)
        total += rep.iterations
    if rep.converged:
        problem = accept(xs)
        if problem:
            rep = _NewtonReport(False, rep.iterations, problem)
    if not rep.converged:
        system.multipliers = saved
        system.corner_multipliers = saved_c
    return xs, _NewtonReport(rep.converged, total, rep.message)


def _ramp(
    system: _System,
    x: np.ndarray,
    load_from: float,
    load_to: float,
    al_iterations: int,
    accept: Callable[[np.ndarray], str | None],
    previous: tuple[np.ndarray, float] | None = None,
) -> tuple[np.ndarray, float, _NewtonReport, tuple[np.ndarray, float] | None]:
    """Go from ``load_from`` to ``load_to`` with step bisection on failure.

    ``previous`` is the converged state before ``x`` (state, load); when given, each step starts
    from the secant extrapolation of the two last converged states (falling back to ``x`` if
    that fails). Returns the last converged state, its load, a report and the state before it.
    """
    cur = load_from
    step = load_to - load_from
    iters = 0
    depth = 0
    while True:
        target = load_to if abs(load_to - cur) <= abs(step) * (1 + 1e-12) else cur + step
        starts = [x]
        if previous is not None and previous[1] != cur:
            ratio = (target - cur) / (cur - previous[1])
            if 0 < ratio <= 2:
                xp = x + ratio * (x - previous[0])
                if system.penetration(xp) <= system.penetration_cap(x) and math.isfinite(
                    system.energy(xp, target)
                ):
                    starts.insert(0, xp)
        for x0 in starts:
            xs, rep = _solve_load(system, x0, target, al_iterations, accept)
            iters += rep.iterations
            if rep.converged:
                break
        if rep.converged:
            previous = (x, cur)
            x, cur = xs, target
            if target == load_to:
                return x, cur, _NewtonReport(True, iters, "converged"), previous
            if depth > 0:
                step *= 2  # try to grow the step again
                depth -= 1
        else:
            depth += 1
            if depth > _MAX_BISECTIONS:
                msg = f"step bisection exhausted ({_MAX_BISECTIONS} halvings): {rep.message}"
                return x, cur, _NewtonReport(False, iters, msg), previous
            step *= 0.5
