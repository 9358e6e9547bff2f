"""Compare the optimizers side by side: equal evaluation budgets, several seeds, one object.

For each method and each seed the design of the gripper for the object of ``--scene`` is
optimized with the same evaluation budget: CMA-ES, GA, random search, NSGA-II and the design
policy (``policy``: the shipped policy's design, one forward pass, then CMA-ES refining it for
the rest of the budget). RL counts as what it is: the policy was trained once, on other
objects (``scripts/train_shipped_policy.py``); its training is not a per-object budget
(``scripts/bench_policy.py`` measures it on held-out objects). The script prints a table (best
reward per method: median, spread, evaluations needed to beat the paper's gripper, wall time)
and writes:

- ``out/compare.json``: the configuration, the table, the median / quartile curves and every
  run's :class:`optim.OptimResult`;
- ``out/compare.png``: best reward so far against evaluations and against wall time (median and
  interquartile band across seeds), and the NSGA-II Pareto front (contact score up, peak strain
  down) against the best designs of the single-objective methods.

Usage::

    python scripts/compare_optimizers.py [--budget 1500] [--seeds 5] [--out out]
        [--scene paper-r070] [--strain-limit 0.15] [--dask ADDRESS|local] [--workers K]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from envs.model.defaults import DEFAULT_STRAIN_LIMIT
from optim import DesignProblem, NoGraspWarning, OptimResult, get_optimizer
from optim.charts import METHOD_COLOURS
from optim.executors import make_executor
from optim.problem import pareto_mask
from optim.result import to_jsonable
from optim.run import paper_reference

BASE_METHODS = ("cmaes", "ga", "random", "nsga2", "policy")
GRID_POINTS = 200


def best_at(result: OptimResult, grid: np.ndarray, axis: str) -> np.ndarray:
    """Best reward so far of a run at each grid value (NaN before its first batch).

    ``axis`` is ``"evaluations"`` or ``"wall_time"``.
    """
    xs = np.asarray(result.history_evaluations if axis == "evaluations"
                    else result.history_wall_time_s, dtype=float)
    ys = np.asarray(result.history_best_reward, dtype=float)
    idx = np.searchsorted(xs, grid, side="right") - 1
    out = np.full(grid.shape, np.nan)
    ok = idx >= 0
    out[ok] = ys[idx[ok]]
    return out


def band(results: list[OptimResult], grid: np.ndarray, axis: str) -> dict[str, np.ndarray]:
    """Median and quartiles across runs at each grid value where every run has a best so far.

    Quantiles of non-decreasing curves are non-decreasing, but only over the same runs: a median
    over the runs that have started (RL runs start late, at their first probe) would drop when
    a weaker run joins. Before the last run's first batch the band is NaN (not drawn).
    """
    curves = np.array([best_at(r, grid, axis) for r in results])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns before a first batch
        q = np.nanpercentile(curves, [25, 50, 75], axis=0)
    q[:, np.any(np.isnan(curves), axis=0)] = np.nan
    return {"grid": grid, "q25": q[0], "median": q[1], "q75": q[2]}


def evaluations_to_beat(result: OptimResult, reference: float) -> float:
    """Evaluations after which the best reward first exceeds ``reference`` (inf: never)."""
    for n, best in zip(result.history_evaluations, result.history_best_reward, strict=True):
        if best > reference:
            return float(n)
    return math.inf


def table_rows(runs: dict[str, list[OptimResult]], reference: float) -> list[dict[str, Any]]:
    """One row per method: statistics of the best reward and of the cost across seeds."""
    rows = []
    for method, results in runs.items():
        best = np.array([r.best_reward for r in results])
        beat = np.array([evaluations_to_beat(r, reference) for r in results])
        rows.append({
            "method": method,
            "runs": len(results),
            "median_best": float(np.median(best)),
            "q25_best": float(np.percentile(best, 25)),
            "q75_best": float(np.percentile(best, 75)),
            "min_best": float(best.min()),
            "max_best": float(best.max()),
            "mean_best": float(best.mean()),
            "std_best": float(best.std(ddof=1)) if len(best) > 1 else 0.0,
            "runs_beating_paper": int(np.count_nonzero(best > reference)),
            "median_evals_to_beat_paper": float(np.median(beat)),
            "median_contact_score": float(np.median(
                [r.best_metrics.get("contact_score", np.nan) for r in results])),
            "median_peak_compression": float(np.median(
                [r.best_metrics.get("peak_compression", np.nan) for r in results])),
            "median_wall_time_s": float(np.median([r.wall_time_s for r in results])),
            "median_evaluations_per_s": float(np.median([r.evaluations_per_s for r in results])),
        })
    rows.sort(key=lambda row: -row["median_best"])
    return rows


def format_table(rows: list[dict[str, Any]], reference: float, budget: int) -> str:
    """The table as aligned text."""
    head = (f"{'method':>7s} {'runs':>4s} {'median':>8s} {'IQR':>17s} {'min':>8s} {'max':>8s} "
            f"{'beat paper':>10s} {'evals to beat':>13s} {'contact':>7s} {'compr.':>7s} "
            f"{'time s':>7s} {'eval/s':>7s}")
    lines = [f"best reward after {budget} evaluations (the scene's own gripper: "
             f"{reference:.4f})", head,
             "-" * len(head)]
    for r in rows:
        beat = r["median_evals_to_beat_paper"]
        lines.append(
            f"{r['method']:>7s} {r['runs']:>4d} {r['median_best']:8.4f} "
            f"[{r['q25_best']:7.4f},{r['q75_best']:7.4f}] {r['min_best']:8.4f} "
            f"{r['max_best']:8.4f} {r['runs_beating_paper']:>5d}/{r['runs']:<4d} "
            f"{'never' if math.isinf(beat) else f'{beat:.0f}':>13s} "
            f"{r['median_contact_score']:7.3f} {r['median_peak_compression']:7.4f} "
            f"{r['median_wall_time_s']:7.1f} {r['median_evaluations_per_s']:7.0f}")
    return "\n".join(lines)


def union_front(results: list[OptimResult]) -> list[dict[str, Any]]:
    """Non-dominated points of the union of several NSGA-II fronts."""
    points = [p for r in results for p in r.pareto_front]
    if not points:
        return []
    obj = np.array([[-p["contact_score"], p["peak_compression"]] for p in points])
    keep = np.flatnonzero(pareto_mask(obj))
    return sorted((points[i] for i in keep), key=lambda p: p["contact_score"])


def draw(runs: dict[str, list[OptimResult]], curves: dict[str, dict[str, dict]],
         front: list[dict[str, Any]], reference: float, path: Path, title: str) -> None:
    """The three-panel comparison chart."""
    fig = Figure(figsize=(16, 4.8), dpi=100)
    axes = fig.subplots(1, 3)
    for ax, axis, label in ((axes[0], "evaluations", "evaluations"),
                            (axes[1], "wall_time", "wall time [s]")):
        for method, c in curves.items():
            b = c[axis]
            colour = METHOD_COLOURS.get(method)
            ax.plot(b["grid"], b["median"], color=colour, label=f"{method} (median)")
            ax.fill_between(b["grid"], b["q25"], b["q75"], color=colour, alpha=0.2, linewidth=0)
        ax.axhline(reference, color="k", linestyle="--", linewidth=1, label="scene's own gripper")
        ax.set_xlabel(label)
        ax.set_ylabel("best reward so far")
        ax.grid(alpha=0.3)
        lows = [np.nanmin(c[axis]["q25"]) for c in curves.values()
                if np.any(np.isfinite(c[axis]["q25"]))]
        if lows:
            ax.set_ylim(max(min(lows), reference - 0.1), None)
        ax.legend(fontsize=8, loc="lower right")
    axes[0].set_title("best so far vs evaluations (band: quartiles over seeds)", fontsize=10)
    axes[1].set_title("best so far vs wall time", fontsize=10)
    ax = axes[2]
    for r in runs.get("nsga2", []):
        ax.plot([p["peak_compression"] for p in r.pareto_front],
                [p["contact_score"] for p in r.pareto_front], ".", color="tab:olive",
                alpha=0.35, markersize=4)
    if front:
        s = [p["peak_compression"] for p in front]
        c = [p["contact_score"] for p in front]
        ax.step(s, c, where="post", color="tab:red")
        ax.plot(s, c, "o", color="tab:red", markersize=4, label="NSGA-II front (all seeds)")
    for method, results in runs.items():
        if method == "nsga2":
            continue
        ax.plot([r.best_metrics.get("peak_compression", np.nan) for r in results],
                [r.best_metrics.get("contact_score", np.nan) for r in results], "*",
                markersize=10, color=METHOD_COLOURS.get(method), label=f"best {method} designs")
    limit = next(iter(runs.values()))[0].object.get("strain_limit")
    if limit:
        ax.axvline(limit, color="k", linestyle=":", linewidth=1, label="strain limit")
    ax.set_xlabel("peak compression [-] (down)")
    ax.set_ylabel("contact score [-] (up)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Pareto front vs best single-objective designs", fontsize=10)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png")


def run_method(method: str, problem: DesignProblem, budget: int, seed: int) -> OptimResult:
    """One run of a method on the problem."""
    return get_optimizer(method)(problem, budget=budget, seed=seed)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=int, default=1500, help="evaluations per run")
    parser.add_argument("--seeds", type=int, default=5, help="seeds per method (>= 5)")
    parser.add_argument("--methods", nargs="+", default=list(BASE_METHODS),
                        choices=list(BASE_METHODS))
    parser.add_argument("--scene", default="paper-r070")
    parser.add_argument("--strain-limit", type=float, default=DEFAULT_STRAIN_LIMIT)
    parser.add_argument("--dask", metavar="ADDRESS|local")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--out", default="out")
    args = parser.parse_args(argv)
    methods = list(dict.fromkeys(args.methods))
    if args.seeds < 1 or args.budget < 1:
        parser.error("--seeds and --budget must be >= 1")
    out = Path(args.out)
    runs: dict[str, list[OptimResult]] = {m: [] for m in methods}
    t0 = time.perf_counter()
    with make_executor(args.dask, args.workers) as executor:
        problem = DesignProblem.from_scene(args.scene, args.strain_limit, executor=executor)
        reference, ref_torque = paper_reference(problem, args.scene)
        problem.evaluate_physical(problem.to_physical(np.zeros((2, 6))))  # compile / load
        for method in methods:
            for seed in range(args.seeds):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", NoGraspWarning)  # in the table
                    result = run_method(method, problem, args.budget, seed)
                runs[method].append(result)
                print(result.summary(), flush=True)
    total_s = time.perf_counter() - t0
    grid_e = np.linspace(1, args.budget, GRID_POINTS)
    t_max = max(r.wall_time_s for rs in runs.values() for r in rs)
    grid_t = np.linspace(0.0, t_max, GRID_POINTS)
    curves = {m: {"evaluations": band(rs, grid_e, "evaluations"),
                  "wall_time": band(rs, grid_t, "wall_time")} for m, rs in runs.items()}
    rows = table_rows(runs, reference)
    front = union_front(runs.get("nsga2", []))
    text = format_table(rows, reference, args.budget)
    print()
    print(text)
    if front:
        print(f"\nNSGA-II front (union of {len(runs['nsga2'])} seeds), contact score vs peak "
              "compression:")
        for p in front:
            print(f"  contact {p['contact_score']:.2f}  compression {p['peak_compression']:.4f}  "
                  f"reward {p['reward']:.4f}")
    title = (f"{args.scene}, strain limit {args.strain_limit:g}: {args.seeds} seeds x "
             f"{args.budget} evaluations per method ({runs[methods[0]][0].executor})")
    draw(runs, curves, front, reference, out / "compare.png", title)
    payload = {
        "config": {"budget": args.budget, "seeds": args.seeds, "methods": methods,
                   "scene": args.scene, "strain_limit": args.strain_limit,
                   "executor": runs[methods[0]][0].executor},
        "machine": {"platform": platform.platform(), "python": platform.python_version(),
                    "cpus": os.cpu_count()},
        "paper_reference": {"reward": reference, "torque_nm": ref_torque},
        "table": rows,
        "table_text": text,
        "pareto_front_union": front,
        "curves": to_jsonable(curves),
        "runs": {m: [r.to_dict() for r in rs] for m, rs in runs.items()},
        "total_time_s": total_s,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps(to_jsonable(payload), indent=1) + "\n")
    print(f"\nwrote {out / 'compare.json'} and {out / 'compare.png'} ({total_s:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
