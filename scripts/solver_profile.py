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
3. ``scaling``: designs per second on 1 thread and on each count of ``--workers`` threads
   (:func:`envs.parallel.set_solver_threads`) and worker processes of one thread each
   (:class:`optim.executors.ProcessExecutor`), each the median of ``--repeats`` evaluations of
   the batch, with each one's efficiency against one thread.
4. ``copies`` (``--copies``): as many independent single-thread processes as each count,
   every one solving the whole batch at once: the machine's own ceiling for the scaling.

Usage: ``python scripts/solver_profile.py [--batch 2048] [--element nhquad] [--workers 2 4]
[--skip-parts] [--out out/x.json]``
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
    inputs and answers (for :func:`iteration_parts`), with each design's Newton iterations,
    whether it was valid at rest and whether it converged."""
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
    seen.update(iterations=out["iterations"], valid=out["valid_at_rest"],
                converged=out["converged"])
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


def newton_state(seen: dict, row: int) -> dict:
    """The solver's arrays at the answer of design ``row`` of :func:`batch_breakdown`, with the
    constraint set a solve starts with at a strictly feasible barrier point near the answer,
    and the convexified (positive definite) Newton matrix assembled there in ``ab``, ``bb``,
    ``dd``: the inputs of :func:`_newton_matrix` and :func:`_factor_solve` by their names."""
    n = seen["n"]
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
    st = {
        "n": n, "prm": prm, "x": x, "nbb": nbb, "bidx": bidx, "kinds": kinds, "fj": fj,
        "fidx": fidx, "mcount": mcount, "lam": lam, "sig": lam / g, "g": g,
        "grad": np.zeros(nx), "gb": np.zeros(nx), "res": np.zeros(nx),
        "ab": np.zeros((nbb, bw + 1)), "bb": np.zeros((nbb, 2)), "dd": np.zeros((2, 2)),
        "grad5": np.zeros(5), "hess5": np.zeros((5, 5)), "dofs": np.zeros(5, np.int64),
        "cg": np.zeros((mcount, 5)), "cd": np.zeros((mcount, 5), np.int64),
        "ch": np.zeros((mcount, CH_BLOCK + 1)),
    }
    # a positive definite matrix for the factor's timing: the convexified one
    _newton_matrix(x, n, prm, bidx, kinds, fj, fidx, mcount, st["lam"], st["sig"], st["grad"],
                   st["ab"], st["bb"], st["dd"], g.copy(), st["grad5"], st["hess5"],
                   st["dofs"], BARRIER_MU, True, st["gb"], st["res"], st["cg"], st["cd"],
                   st["ch"])
    return st


def iteration_parts(seen: dict, states: int) -> dict:
    """Median microseconds of each part of an iteration over ``states`` answers."""
    n, opts = seen["n"], default_options()
    parts: dict[str, list[float]] = {}
    for row in range(states):
        st = newton_state(seen, row)
        x, prm, nbb, mcount = st["x"], st["prm"], st["nbb"], st["mcount"]
        newton_args = (x, n, prm, st["bidx"], st["kinds"], st["fj"], st["fidx"], mcount,
                       st["lam"], st["sig"], st["grad"], st["ab"].copy(), st["bb"].copy(),
                       st["dd"].copy(), st["g"], st["grad5"], st["hess5"], st["dofs"],
                       st["gb"], st["res"], st["cg"], st["cd"], st["ch"])
        ab, bb, dd = st["ab"], st["bb"], st["dd"]
        lb, ybuf = np.zeros_like(ab), np.zeros((nbb, 2))
        rb, ob, rt, ot = np.ones(nbb), np.zeros(nbb), np.ones(2), np.zeros(2)
        xt = x + 1e-4
        timings = {
            "assembly_us": _us(_time_newton, REPEATS, *newton_args),
            "factor_solve_us": _us(_time_factor, REPEATS, ab, bb, dd, lb, ybuf, nbb, rb, rt, ob,
                                   ot),
            "merit_us": _us(_time_merit, REPEATS, x, n, prm, st["kinds"], st["fj"], st["fidx"],
                            mcount, st["g"]),
            "tunnels_us": _us(_time_tunnels, REPEATS, x, xt, n, prm),
            "grasp_us": _us(_time_solve, 100, n, seen["prm"][row], opts, seen["x0"][row],
                            seen["lam0"][row]),
            "constraints": float(mcount),
            "unknowns": float(x.shape[0]),
        }
        for key, v in timings.items():
            parts.setdefault(key, []).append(v)
    return {key: statistics.median(v) for key, v in parts.items()}


def _designs_per_s(designs: np.ndarray, model: dict, repeats: int, **kwargs) -> float:
    """Median designs per second of ``repeats`` evaluations of the batch (after a warm-up)."""
    evaluate_designs(designs[:64], DISK, **model, **kwargs)
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        evaluate_designs(designs, DISK, **model, **kwargs)
        rates.append(len(designs) / (time.perf_counter() - t0))
    return statistics.median(rates)


def scaling(designs: np.ndarray, model: dict, counts: list[int], repeats: int = 3) -> dict:
    """Designs per second on 1 thread and on each of ``counts`` threads and worker processes
    (one solver thread each), with each one's efficiency against one thread."""
    from optim.executors import ProcessExecutor

    out: dict[str, float] = {}
    default = solver_threads()
    try:
        for threads in sorted({1, *counts}):
            set_solver_threads(threads)
            out[f"threads_{threads}_designs_per_s"] = _designs_per_s(designs, model, repeats)
    finally:
        set_solver_threads(None if default == solver_threads() else default)
    for workers in sorted(c for c in set(counts) if c > 1):
        pool = ProcessExecutor(workers)
        try:
            chunk = max(64, len(designs) // (4 * workers))
            out[f"processes_{workers}_designs_per_s"] = _designs_per_s(
                designs, model, repeats, executor=pool, chunk_size=chunk)
        finally:
            pool.close()
    one = out["threads_1_designs_per_s"]
    for key in [k for k in out if k != "threads_1_designs_per_s"]:
        count = int(key.split("_")[1])
        out[key.replace("designs_per_s", "efficiency")] = out[key] / (count * one)
    return out


def _independent_copy(barrier, queue, model: dict, batch: int, seed: int) -> None:
    """One worker of :func:`independent_copies`: the whole batch on one thread, timed after
    every copy has loaded its kernels and warmed up."""
    set_solver_threads(1)
    designs = DesignBounds().sample(np.random.default_rng(seed), batch, DISK)
    evaluate_designs(designs[:64], DISK, **model)
    barrier.wait()
    t0 = time.perf_counter()
    evaluate_designs(designs, DISK, **model)
    queue.put(time.perf_counter() - t0)


def independent_copies(model: dict, batch: int, seed: int, counts: list[int]) -> dict:
    """The machine's own ceiling: ``k`` processes each solving the same whole batch on one
    thread at once, sharing nothing; designs per second of all of them together, and their
    efficiency against one copy alone. What a batch split over ``k`` threads loses beyond this
    is the package's; what this loses is the cores' (shared caches, clocks, hyperthreads)."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    out: dict[str, float] = {}
    for k in sorted({1, *counts}):
        barrier, queue = ctx.Barrier(k), ctx.Queue()
        procs = [ctx.Process(target=_independent_copy, args=(barrier, queue, model, batch, seed))
                 for _ in range(k)]
        for proc in procs:
            proc.start()
        seconds = [queue.get() for _ in procs]
        for proc in procs:
            proc.join()
        out[f"copies_{k}_designs_per_s"] = k * batch / max(seconds)
    one = out["copies_1_designs_per_s"]
    for k in sorted({1, *counts}):
        out[f"copies_{k}_efficiency"] = out[f"copies_{k}_designs_per_s"] / (k * one)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=2048)
    parser.add_argument("--element", default="nhquad", choices=("nhquad", "spring"),
                        help="nhquad: the default model; spring: the paper's fan")
    parser.add_argument("--states", type=int, default=8)
    parser.add_argument("--workers", type=int, nargs="+", default=[os.cpu_count() or 1],
                        help="thread and process counts of the scaling (e.g. 2 4 8 16)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="evaluations of the batch per scaling figure (their median)")
    parser.add_argument("--copies", action="store_true",
                        help="also run --workers independent single-thread copies of the "
                             "batch at once: the machine's own scaling ceiling")
    parser.add_argument("--skip-parts", action="store_true",
                        help="skip the batch breakdown and the iteration's parts")
    parser.add_argument("--skip-scaling", action="store_true")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    model = {} if args.element == "nhquad" else {"element": "spring"}
    designs = DesignBounds().sample(np.random.default_rng(args.seed), args.batch, DISK)
    report: dict = {"cores": os.cpu_count(), "load_before": _load(), "element": args.element}
    if not args.skip_parts:
        default = solver_threads()
        set_solver_threads(1)
        try:
            report["batch"], seen = batch_breakdown(designs, model)
        finally:
            set_solver_threads(None if default == 1 else default)
        print("batch (one thread):", {k: round(v, 4) for k, v in report["batch"].items()},
              flush=True)
        report["parts"] = iteration_parts(seen, min(args.states, len(designs)))
        print("parts (median over states):",
              {k: round(v, 2) for k, v in report["parts"].items()}, flush=True)
    if not args.skip_scaling:
        report["scaling"] = scaling(designs, model, args.workers, args.repeats)
        print("scaling:", {k: round(v, 3) for k, v in report["scaling"].items()}, flush=True)
    if args.copies:
        report["copies"] = independent_copies(model, args.batch, args.seed, args.workers)
        print("independent copies:", {k: round(v, 3) for k, v in report["copies"].items()},
              flush=True)
    report["load_after"] = _load()
    print(f"load {report['load_before']} -> {report['load_after']}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
