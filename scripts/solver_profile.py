"""Where a batched evaluation's time goes: the batch, one Newton iteration's parts, the cores.

1. ``batch``: one :func:`envs.evaluate.evaluate_designs` call on ``--batch`` random designs of
   the design box on paper-r070 (the default model, or ``--element spring`` for the paper's
   fan), split into the compiled solve, the finish (SI answers, metrics, the independent
   check, the pin reaction) and the Python around them; Newton iterations a design and the
   solve's time per iteration, on one thread.
2. ``parts``: the pieces of one interior-point iteration timed alone in compiled loops, at the
   answers of ``--states`` of those designs with the constraint set a solve starts with: the
   assembly of the Newton matrix and the gradients (:func:`envs.solver.assembly._newton_matrix`),
   the banded factor and solve (:func:`envs.solver.banded._factor_solve`), one merit
   evaluation of the line search (:func:`envs.solver.assembly._merit`) and the
   anti-tunnelling test (:func:`envs.solver.contact._tunnels`); and one whole grasp
   (:func:`envs.solver.driver.solve_one`) from the same start, for the sum to be compared with.
3. ``scaling``: designs per second on 1 and on every thread
   (:func:`envs.parallel.set_solver_threads`) and with worker processes of one thread each
   (:class:`optim.executors.ProcessExecutor`), with each one's efficiency against one thread.

Usage: ``python scripts/solver_profile.py [--batch 2048] [--element nhquad] [--out out/x.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np
from numba import njit

from envs.evaluate import DesignBounds, evaluate_designs
from envs.model.layout import N_CORNERS, N_INFO, P_RINGS, default_options
from envs.model.rings import kernel_copy, mesh_band_index
from envs.parallel import set_solver_threads, solver_threads
from envs.scene import PRESETS
from envs.solver import driver
from envs.solver import pipeline as pl
from envs.solver.assembly import CH_BLOCK, _merit, _newton_matrix
from envs.solver.banded import _factor_solve, band_shape
from envs.solver.candidates import CORNER_SWEEP, _initial_candidates
from envs.solver.contact import _all_gaps, _build_constraints, _tunnels

DISK = PRESETS["paper-r070"][1]
BARRIER_MU = 1e-6  # a barrier parameter of the middle of a solve (scaled)
REPEATS = 2000  # calls of a part per timing


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


@njit
def _time_newton(reps, x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd,
                 g, grad5, hess5, dofs, gb, res, cg, cd, ch):
    acc = 0.0
    for _ in range(reps):
        _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, g)
        _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd, g,
                       grad5, hess5, dofs, BARRIER_MU, n < 0, gb, res, cg, cd, ch)
        acc += ab[0, 0]
    return acc


@njit
def _time_factor(reps, ab, bb, dd, lb, ybuf, nbb, rb, rt, ob, ot):
    acc = 0.0
    for _ in range(reps):
        acc += _factor_solve(ab, bb, dd, lb, ybuf, nbb, 1e-3, rb, rt, ob, ot) + ob[0]
    return acc


@njit
def _time_merit(reps, x, n, prm, kinds, fj, fidx, mcount, g):
    acc = 0.0
    for _ in range(reps):
        acc += _merit(x, n, prm, kinds, fj, fidx, mcount, g)[0]
    return acc


@njit
def _time_tunnels(reps, x, xt, n, prm):
    acc = 0
    for _ in range(reps):
        acc += _tunnels(x, xt, n, prm)
    return acc


@njit
def _time_solve(reps, n, prm, opts, x0, lam0):
    acc = 0.0
    for _ in range(reps):
        x = x0.copy()
        lam_face = lam0.copy()
        info = np.zeros(N_INFO)
        driver.solve_one(n, prm, opts, x, lam_face, np.zeros((2, N_CORNERS, n)), np.zeros(2),
                         np.zeros((2, N_CORNERS, n), dtype=np.bool_),
                         np.zeros((2, n), dtype=np.bool_), info)
        acc += x[0]
    return acc


def _us(kernel, reps: int, *args) -> float:
    """Microseconds a call of a part: ``kernel(reps, *args)`` loops it in compiled code."""
    kernel(1, *args)  # compile
    t0 = time.perf_counter()
    kernel(reps, *args)
    return 1e6 * (time.perf_counter() - t0) / reps


def batch_breakdown(designs: np.ndarray, model: dict) -> tuple[dict, dict]:
    """One-thread evaluation of ``designs``, timed by stage; returns it and the solver's
    inputs and answers (for :func:`iteration_parts`)."""
    seen: dict = {}
    timer = {"solve": 0.0, "finish": 0.0}
    solve, finish = pl._solve, pl.checked_solution

    def timed_solve(n, prm, xs, lam):
        seen.update(n=n, prm=prm.copy(), x0=xs.copy(), lam0=lam.copy())
        t0 = time.perf_counter()
        out = solve(n, prm, xs, lam)
        timer["solve"] += time.perf_counter() - t0
        seen["x"] = xs.copy()
        return out

    def timed_finish(*args):
        t0 = time.perf_counter()
        out = finish(*args)
        timer["finish"] += time.perf_counter() - t0
        return out

    pl._solve, pl.checked_solution = timed_solve, timed_finish
    try:
        evaluate_designs(designs[:4], DISK, **model)
        timer.update(solve=0.0, finish=0.0)
        t0 = time.perf_counter()
        out = evaluate_designs(designs, DISK, **model)
        wall = time.perf_counter() - t0
    finally:
        pl._solve, pl.checked_solution = solve, finish
    iterations = out["iterations"][out["valid_at_rest"]]
    return {
        "designs": len(designs),
        "wall_s": wall,
        "designs_per_s": len(designs) / wall,
        "solve_s": timer["solve"],
        "finish_s": timer["finish"],
        "python_s": wall - timer["solve"] - timer["finish"],
        "mean_iterations": float(iterations.mean()),
        "median_iterations": float(np.median(iterations)),
        "solve_us_per_iteration": 1e6 * timer["solve"] / float(iterations.sum()),
        "converged_of_valid": float(out["converged"][out["valid_at_rest"]].mean()),
    }, seen


def iteration_parts(seen: dict, states: int) -> dict:
    """Median microseconds of each part of an iteration over ``states`` answers."""
    n, opts = seen["n"], default_options()
    parts: dict[str, list[float]] = {}
    for row in range(states):
        prm = kernel_copy(seen["prm"][row], n)
        x = seen["x"][row].copy()
        nbb, bw = band_shape(n, prm)
        bidx = mesh_band_index(n, int(prm[P_RINGS]))
        face = np.zeros((2, n), dtype=np.bool_)
        corner = np.zeros((2, N_CORNERS, n), dtype=np.bool_)
        _initial_candidates(seen["x0"][row], n, prm, face, corner, np.zeros((n, 4)),
                            np.zeros((CORNER_SWEEP, 2)))
        mmax = 10 * n + 2
        kinds, fj, fidx = (np.zeros(mmax, np.int64) for _ in range(3))
        mcount = _build_constraints(face, corner, n, kinds, fj, fidx)
        nx = x.shape[0]
        g = np.zeros(mcount)
        _all_gaps(x, n, prm, kinds[:mcount], fj, fidx, g)
        g = np.maximum(g, 1e-6)  # a strictly feasible barrier point near the answer
        lam = BARRIER_MU / g
        sig = lam / g
        grad, gb, res = np.zeros(nx), np.zeros(nx), np.zeros(nx)
        ab, bb, dd = np.zeros((nbb, bw + 1)), np.zeros((nbb, 2)), np.zeros((2, 2))
        grad5, hess5, dofs = np.zeros(5), np.zeros((5, 5)), np.zeros(5, np.int64)
        cg, cd = np.zeros((mcount, 5)), np.zeros((mcount, 5), np.int64)
        ch = np.zeros((mcount, CH_BLOCK + 1))
        # a positive definite matrix for the factor's timing: the convexified one
        _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, lam, sig, grad, ab, bb, dd,
                       g.copy(), grad5, hess5, dofs, BARRIER_MU, True, gb, res, cg, cd, ch)
        lb, ybuf = np.zeros_like(ab), np.zeros((nbb, 2))
        rb, ob, rt, ot = np.ones(nbb), np.zeros(nbb), np.ones(2), np.zeros(2)
        xt = x + 1e-4
        timings = {
            "assembly_us": _us(_time_newton, REPEATS, x, n, prm, bidx, kinds, fj, fidx, mcount,
                               lam, sig, grad, ab.copy(), bb.copy(), dd.copy(), g, grad5, hess5,
                               dofs, gb, res, cg, cd, ch),
            "factor_solve_us": _us(_time_factor, REPEATS, ab, bb, dd, lb, ybuf, nbb, rb, rt, ob,
                                   ot),
            "merit_us": _us(_time_merit, REPEATS, x, n, prm, kinds, fj, fidx, mcount, g),
            "tunnels_us": _us(_time_tunnels, REPEATS, x, xt, n, prm),
            "grasp_us": _us(_time_solve, 100, n, seen["prm"][row], opts, seen["x0"][row],
                            seen["lam0"][row]),
            "constraints": float(mcount),
            "unknowns": float(nx),
        }
        for key, v in timings.items():
            parts.setdefault(key, []).append(v)
    return {key: statistics.median(v) for key, v in parts.items()}


def scaling(designs: np.ndarray, model: dict, workers: int) -> dict:
    """Designs per second on one thread, on ``workers`` threads and ``workers`` processes."""
    from optim.executors import ProcessExecutor

    out: dict[str, float] = {}
    default = solver_threads()
    try:
        for threads in sorted({1, workers}):
            set_solver_threads(threads)
            evaluate_designs(designs[:4], DISK, **model)
            t0 = time.perf_counter()
            evaluate_designs(designs, DISK, **model)
            out[f"threads_{threads}_designs_per_s"] = len(designs) / (time.perf_counter() - t0)
    finally:
        set_solver_threads(None if default == solver_threads() else default)
    pool = ProcessExecutor(workers)
    try:
        chunk = max(64, len(designs) // (4 * workers))
        evaluate_designs(designs[: 2 * chunk], DISK, executor=pool, chunk_size=chunk, **model)
        t0 = time.perf_counter()
        evaluate_designs(designs, DISK, executor=pool, chunk_size=chunk, **model)
        out[f"processes_{workers}_designs_per_s"] = len(designs) / (time.perf_counter() - t0)
    finally:
        pool.close()
    one = out["threads_1_designs_per_s"]
    out[f"threads_{workers}_efficiency"] = out[f"threads_{workers}_designs_per_s"] / (workers * one)
    out[f"processes_{workers}_efficiency"] = (out[f"processes_{workers}_designs_per_s"]
                                              / (workers * one))
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=2048)
    parser.add_argument("--element", default="nhquad", choices=("nhquad", "spring"),
                        help="nhquad: the default model; spring: the paper's fan")
    parser.add_argument("--states", type=int, default=8)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--skip-scaling", action="store_true")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    model = {} if args.element == "nhquad" else {"element": "spring"}
    designs = DesignBounds().sample(np.random.default_rng(args.seed), args.batch, DISK)
    report: dict = {"cores": os.cpu_count(), "load_before": _load(), "element": args.element}
    default = solver_threads()
    set_solver_threads(1)
    try:
        report["batch"], seen = batch_breakdown(designs, model)
    finally:
        set_solver_threads(None if default == 1 else default)
    print("batch (one thread):", {k: round(v, 4) for k, v in report["batch"].items()},
          flush=True)
    report["parts"] = iteration_parts(seen, min(args.states, len(designs)))
    print("parts (median over states):", {k: round(v, 2) for k, v in report["parts"].items()},
          flush=True)
    if not args.skip_scaling:
        report["scaling"] = scaling(designs, model, args.workers)
        print("scaling:", {k: round(v, 3) for k, v in report["scaling"].items()}, flush=True)
    report["load_after"] = _load()
    print(f"load {report['load_before']} -> {report['load_after']}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
