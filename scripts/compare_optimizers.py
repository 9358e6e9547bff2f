"""Compare the optimizers side by side: equal evaluation budgets, several seeds, several objects.

For each object (scene presets and object files, each with its own scenarios and payload) and
each method, the gripper is designed ``--seeds`` times with the same evaluation budget: CMA-ES,
GA, random search, NSGA-II and the design policy (``policy``: the shipped policy's design, one
forward pass, then CMA-ES refining it for the rest of the budget; straight jaws only). RL counts
as what it is: the policy was trained once, on other objects; its training is not a per-object
budget (``scripts/bench_policy.py`` measures it on held-out objects).

The comparison is drawn as COCO draws it (:mod:`optim.profiles`): each object gets a ladder of
target rewards between the median random design and the best reward any run found on it; a
method's *runtime profile* is the share of (run, target) pairs it has reached after a number
of evaluations (or seconds), over all objects and seeds. The script prints a table per object
(best reward per method: median, spread, evaluations needed to beat the median random design,
wall time) and writes:

- ``out/compare.json``: the configuration, the tables, the profiles and every run's
  :class:`optim.OptimResult`;
- ``out/compare.png``: the runtime profiles against evaluations and against wall time, and
  each object's median best reward per method.

Usage::

    python scripts/compare_optimizers.py [--budget 1000] [--seeds 5] [--jaw any]
        [--objects paper-r070 examples/objects/foam_disk.toml ...] [--out out]
        [--strain-limit LIMIT] [--dask ADDRESS|local] [--workers K]
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

from envs.object_file import load_object
from envs.scene import PRESETS
from optim import DesignProblem, NoGraspWarning, OptimResult, get_optimizer
from optim.charts import METHOD_COLOURS
from optim.executors import make_executor
from optim.profiles import first_hits, runtime_profile, target_ladder
from optim.result import to_jsonable
from optim.run import problem_kwargs

BASE_METHODS = ("cmaes", "ga", "random", "nsga2")
DEFAULT_OBJECTS = ("paper-r070", "examples/objects/foam_disk.toml",
                   "examples/objects/silicone_puck.toml", "examples/objects/cherry_tomato.toml",
                   "examples/objects/strawberry.toml")
GRID_POINTS = 200
N_TARGETS = 11  # targets per object (optim.profiles.target_ladder)
BASELINE_DESIGNS = 256  # random designs whose median reward is the easy end of the ladder


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
            "runs_beating_baseline": int(np.count_nonzero(best > reference)),
            "median_evals_to_beat_baseline": float(np.median(beat)),
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
            f"{'beat rand.':>10s} {'evals to beat':>13s} {'contact':>7s} {'compr.':>7s} "
            f"{'time s':>7s} {'eval/s':>7s}")
    lines = [f"best reward after {budget} evaluations (the median random design: "
             f"{reference:.4f})", head,
             "-" * len(head)]
    for r in rows:
        beat = r["median_evals_to_beat_baseline"]
        lines.append(
            f"{r['method']:>7s} {r['runs']:>4d} {r['median_best']:8.4f} "
            f"[{r['q25_best']:7.4f},{r['q75_best']:7.4f}] {r['min_best']:8.4f} "
            f"{r['max_best']:8.4f} {r['runs_beating_baseline']:>5d}/{r['runs']:<4d} "
            f"{'never' if math.isinf(beat) else f'{beat:.0f}':>13s} "
            f"{r['median_contact_score']:7.3f} {r['median_peak_compression']:7.4f} "
            f"{r['median_wall_time_s']:7.1f} {r['median_evaluations_per_s']:7.0f}")
    return "\n".join(lines)


def profile_hits(runs: dict[str, list[OptimResult]], targets: np.ndarray, axis: str
                 ) -> dict[str, np.ndarray]:
    """First hits (runs x targets) of every method's runs on one object."""
    return {m: np.array([first_hits(r, targets, axis) for r in rs]) for m, rs in runs.items()}


def draw(objects: dict[str, dict], budget: int, path: Path, title: str) -> dict[str, dict]:
    """The comparison chart: runtime profiles against evaluations and wall time over all
    objects, seeds and targets, and each object's median best reward per method. Returns the
    profiles drawn."""
    fig = Figure(figsize=(16, 4.8), dpi=100)
    axes = fig.subplots(1, 3)
    methods = list(next(iter(objects.values()))["runs"])
    t_max = max(r.wall_time_s for o in objects.values() for rs in o["runs"].values() for r in rs)
    grids = {"evaluations": np.unique(np.geomspace(1, budget, GRID_POINTS).round()),
             "wall_time": np.geomspace(1e-3, max(t_max, 2e-3), GRID_POINTS)}
    profiles: dict[str, dict] = {}
    for ax, axis, label in ((axes[0], "evaluations", "evaluations"),
                            (axes[1], "wall_time", "wall time [s]")):
        profiles[axis] = {"grid": grids[axis]}
        for method in methods:
            hits = np.concatenate([o["hits"][axis][method].ravel() for o in objects.values()])
            share = runtime_profile(hits, grids[axis])
            profiles[axis][method] = share
            ax.step(grids[axis], share, where="post", color=METHOD_COLOURS.get(method),
                    label=method)
        ax.set_xscale("log")
        ax.set_ylim(0.0, 1.02)
        ax.set_xlabel(label)
        ax.set_ylabel("share of (run, target) pairs reached")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[0].set_title(f"runtime profiles: {len(objects)} objects x seeds x "
                      f"{N_TARGETS} targets", fontsize=10)
    axes[1].set_title("runtime profiles against wall time", fontsize=10)
    ax = axes[2]
    width = 0.8 / len(methods)
    names = list(objects)
    for k, method in enumerate(methods):
        med = [np.median([r.best_reward for r in objects[n]["runs"][method]]) for n in names]
        ax.bar(np.arange(len(names)) + (k - (len(methods) - 1) / 2) * width, med, width,
               color=METHOD_COLOURS.get(method), label=method)
    ax.set_xticks(np.arange(len(names)), names, rotation=20, fontsize=8)
    ax.axhline(0.0, color="k", linewidth=0.8)
    ax.set_ylabel("median best reward")
    ax.grid(alpha=0.3, axis="y")
    ax.set_title("median best reward per object", fontsize=10)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png")
    return profiles


def run_method(method: str, problem: DesignProblem, budget: int, seed: int) -> OptimResult:
    """One run of a method on the problem."""
    return get_optimizer(method)(problem, budget=budget, seed=seed)


def object_problem(name: str, strain_limit: float | None, jaw: str, executor):
    """The design problem of a scene preset or an object file (its scenarios and payload)."""
    if name in PRESETS:
        target, settings = problem_kwargs(name, None, strain_limit, None, None, None, jaw=jaw)
        return DesignProblem.from_scene(target, executor=executor, **settings), name
    obj = load_object(Path(name))
    target, settings = problem_kwargs(None, obj, strain_limit, None, None, None, jaw=jaw)
    return DesignProblem(target, name=obj.name, executor=executor, **settings), obj.name


def baseline_reward(problem: DesignProblem, seed: int = 0) -> float:
    """Median reward of random designs of the box: the easy end of the target ladder."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, size=(BASELINE_DESIGNS, problem.n_var))
    return float(np.median(problem.evaluate_physical(problem.to_physical(x))["reward"]))


def run_object(name: str, args, methods: list[str], executor) -> dict:
    """Every method and seed on one object, with its target ladder and first hits."""
    problem, label = object_problem(name, args.strain_limit, args.jaw, executor)
    base = baseline_reward(problem)
    runs: dict[str, list[OptimResult]] = {m: [] for m in methods}
    for method in methods:
        for seed in range(args.seeds):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", NoGraspWarning)  # in the table
                result = run_method(method, problem, args.budget, seed)
            runs[method].append(result)
            print(f"{label}: {result.summary()}", flush=True)
    best = max(r.best_reward for rs in runs.values() for r in rs)
    targets = target_ladder(best, min(base, best), N_TARGETS)
    return {"label": label, "runs": runs, "baseline": base, "best": best,
            "targets": targets,
            "hits": {axis: profile_hits(runs, targets, axis)
                     for axis in ("evaluations", "wall_time")}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=int, default=1000, help="evaluations per run")
    parser.add_argument("--seeds", type=int, default=5, help="seeds per method and object")
    parser.add_argument("--methods", nargs="+", default=list(BASE_METHODS),
                        choices=[*BASE_METHODS, "policy"])
    parser.add_argument("--objects", nargs="+", default=list(DEFAULT_OBJECTS),
                        help="scene presets or object files")
    parser.add_argument("--jaw", default="any", choices=("straight", "cradle", "vee", "any"),
                        help="the design space's jaw profiles")
    parser.add_argument("--strain-limit", type=float, default=None,
                        help="the strain limit (default: the object file's, else 0.15)")
    parser.add_argument("--dask", metavar="ADDRESS|local")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--out", default="out")
    args = parser.parse_args(argv)
    methods = list(dict.fromkeys(args.methods))
    if args.seeds < 1 or args.budget < 1:
        parser.error("--seeds and --budget must be >= 1")
    out = Path(args.out)
    t0 = time.perf_counter()
    objects: dict[str, dict] = {}
    with make_executor(args.dask, args.workers) as executor:
        for name in args.objects:
            got = run_object(name, args, methods, executor)
            objects[got["label"]] = got
    total_s = time.perf_counter() - t0
    tables = {}
    for label, o in objects.items():
        rows = table_rows(o["runs"], o["baseline"])
        tables[label] = rows
        print()
        print(f"{label} (the median random design: {o['baseline']:.4f})")
        print(format_table(rows, o["baseline"], args.budget))
    executor_name = next(iter(next(iter(objects.values()))["runs"].values()))[0].executor
    title = (f"{len(objects)} objects, {args.jaw} jaws: {args.seeds} seeds x {args.budget} "
             f"evaluations per method ({executor_name})")
    profiles = draw(objects, args.budget, out / "compare.png", title)
    for axis in ("evaluations",):
        print(f"\nshare of (run, target) pairs reached within the budget ({axis}): "
              + ", ".join(f"{m} {profiles[axis][m][-1]:.2f}" for m in methods))
    payload = {
        "config": {"budget": args.budget, "seeds": args.seeds, "methods": methods,
                   "objects": list(objects), "jaw": args.jaw, "strain_limit": args.strain_limit,
                   "executor": executor_name, "targets": N_TARGETS},
        "machine": {"platform": platform.platform(), "python": platform.python_version(),
                    "cpus": os.cpu_count()},
        "tables": tables,
        "profiles": to_jsonable(profiles),
        "objects": {label: {"baseline": o["baseline"], "best": o["best"],
                            "targets": o["targets"].tolist(),
                            "runs": {m: [r.to_dict() for r in rs]
                                     for m, rs in o["runs"].items()}}
                    for label, o in objects.items()},
        "total_time_s": total_s,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps(to_jsonable(payload), indent=1) + "\n")
    print(f"\nwrote {out / 'compare.json'} and {out / 'compare.png'} ({total_s:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
