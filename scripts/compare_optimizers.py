"""Compare the optimizers on the benchmark suite: equal budgets (or equal time), several seeds,
the reward a user is told.

Every method (the package's, its default ``portfolio`` first, Nevergrad's and Optuna's) runs
``--seeds`` times on each instance of :mod:`optim.bench` (an object, its scenarios and payload, and
the jaws designed) with the same evaluation budget, or with the same wall time (``--time``). Each
run is read as its user reads it: the finish's reward, the finer member re-scoring the ten best
distinct designs (:func:`optim.finish.finish_result`), at a few log-spaced prefixes of the run
(:func:`optim.bench.finished_curve`), and its gap to the instance's best-known reward
(``optim/bench/targets.json``, from ``python scripts/bench_targets.py``; an instance without one,
or a stale file, falls back to the best finished reward of this comparison, and says so).

A method's *runtime profile* is the share of (run, target) pairs it has reached after a number
of evaluations, or of seconds, over all instances and seeds, as the COCO platform draws them;
the targets of an instance are the best known minus :data:`GAPS` (the last, 0.01, is "found the
optimum"). A run is read where it would have stopped, not at its best so far: the finish's
reward can drop as a search moves on to designs its own model overrates. The script prints a
table per instance (the finished reward per method: median, quartiles, extremes, runs within
0.01 of the best known, evaluations and seconds) and writes:

- ``out/compare.json``: the configuration, the targets used, the tables, the profiles and every
  run (its finished curve and :class:`optim.OptimResult`); ``--replot`` reads them again with the
  best-known rewards as they are now (after ``scripts/bench_targets.py``);
- ``out/compare.png``: the runtime profiles against evaluations and against seconds, and each
  instance's median finished reward per method with its quartiles and the best known;
- ``out/compare_ioh/``: every run in IOHprofiler's format (IOHanalyzer reads it).

Usage::

    python scripts/compare_optimizers.py [--budget 1000] [--seeds 3] [--time SECONDS]
        [--methods portfolio cmaes ga nsga2 random ng:TwoPointsDE ng:NGOpt optuna:tpe]
        [--instances puck-any strawberry-any ...] [--out out] [--dask ADDRESS|local]
        [--workers K] [--checkpoints 8]
    python scripts/compare_optimizers.py --replot out/compare.json --out out
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from optim.bench import (
    INSTANCES,
    REACHED_GAP,
    BenchScore,
    IOHLog,
    load_targets,
    make_problem,
    run_method,
    targets_meta,
    targets_stale,
)
from optim.bench.scoring import CHECKPOINTS
from optim.charts import METHOD_COLOURS
from optim.executors import make_executor
from optim.optimize import get_optimizer
from optim.result import to_jsonable

# the package's default search first, then its other methods and those of other libraries
METHODS = ("portfolio", "cmaes", "ga", "nsga2", "random", "ng:TwoPointsDE", "ng:NGOpt",
           "optuna:tpe")
# a mix: three objects judged once, three with scenarios (9, 9 and 25 grasps a design)
INSTANCES_RUN = ("puck-any", "cherry-tomato-any", "foam-any", "strawberry-any",
                 "tomatoes-mu05-any", "blueberries-any")
GAPS = (0.16, 0.08, 0.04, 0.02, REACHED_GAP)  # targets: the best known minus these
GRID_POINTS = 200


def reached(score: BenchScore, target: float) -> bool:
    """Whether a run ended within :data:`~optim.bench.REACHED_GAP` of the instance's target."""
    return score.reward >= target - REACHED_GAP


def table_rows(scores: dict[str, list[BenchScore]], target: float) -> list[dict[str, Any]]:
    """One row per method: the finished reward's statistics over seeds, and the cost."""
    rows = []
    for method, runs in scores.items():
        fin = np.array([s.reward for s in runs])
        rows.append({
            "method": method, "runs": len(runs),
            "median": float(np.median(fin)), "q25": float(np.percentile(fin, 25)),
            "q75": float(np.percentile(fin, 75)), "min": float(fin.min()),
            "max": float(fin.max()),
            "reached": int(sum(reached(s, target) for s in runs)),
            "median_search_reward": float(np.median([s.search_reward for s in runs])),
            "median_evaluations": float(np.median([s.evaluations for s in runs])),
            "median_seconds": float(np.median([s.seconds for s in runs])),
        })
    rows.sort(key=lambda row: -row["median"])
    return rows


def format_table(label: str, rows: list[dict[str, Any]], target: float, source: str) -> str:
    """An instance's table as aligned text."""
    head = (f"{'method':>15s} {'runs':>4s} {'median':>8s} {'IQR':>17s} {'min':>8s} "
            f"{'max':>8s} {'<=0.01':>6s} {'search':>8s} {'evals':>6s} {'s':>6s}")
    lines = [f"{label}: finished reward (finer member); best known {target:.4f} ({source})",
             head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['method']:>15s} {r['runs']:>4d} {r['median']:8.4f} "
                     f"[{r['q25']:7.4f},{r['q75']:7.4f}] {r['min']:8.4f} {r['max']:8.4f} "
                     f"{r['reached']:>2d}/{r['runs']:<3d} {r['median_search_reward']:8.4f} "
                     f"{r['median_evaluations']:6.0f} {r['median_seconds']:6.1f}")
    return "\n".join(lines)


def current_targets() -> dict:
    """The best-known rewards of targets.json, none when they were computed with another
    version of the model (read once: a campaign may rewrite the file during a comparison)."""
    return {} if targets_stale() else load_targets()


def instance_target(name: str, scores: dict[str, list[BenchScore]], known: dict
                    ) -> tuple[float, str]:
    """The best-known reward of an instance and where it comes from; the best finished reward
    of this comparison where no current target is known (or a run beat it)."""
    here = max(s.reward for runs in scores.values() for s in runs)
    if name in known:
        target = known[name].reward
        if here > target:
            return here, f"this comparison, above targets.json's {target:.4f}"
        return target, "targets.json"
    return here, "this comparison (no current target)"


def share_reached(curves: list[tuple[np.ndarray, np.ndarray, np.ndarray]], grid: np.ndarray
                  ) -> np.ndarray:
    """The share of (run, target) pairs whose run, stopped at each grid value, reports a
    reward at or above the target: each curve is ``(xs, rewards, targets)``, its reward at a
    grid value the one of its last point within it (the finish's reward can drop as a run
    goes on: it is read where the run stopped, not at its best so far)."""
    reached = np.zeros(grid.size)
    pairs = 0
    for xs, rewards, targets in curves:
        idx = np.searchsorted(np.asarray(xs, dtype=float), grid, side="right") - 1
        value = np.where(idx >= 0, np.asarray(rewards, dtype=float)[np.maximum(idx, 0)],
                         -np.inf)
        reached += np.count_nonzero(value[:, None] >= np.asarray(targets)[None, :], axis=1)
        pairs += len(targets)
    return reached / max(pairs, 1)


def profiles(instances: dict[str, dict], grids: dict[str, np.ndarray]) -> dict[str, dict]:
    """The runtime profiles of every method over every instance, seed and target."""
    out: dict[str, dict] = {}
    methods = list(next(iter(instances.values()))["scores"])
    for axis in ("evaluations", "seconds"):
        out[axis] = {"grid": grids[axis]}
        for method in methods:
            curves = [(getattr(s.curve, axis), s.curve.reward, o["target"] - np.array(GAPS))
                      for o in instances.values() for s in o["scores"][method]]
            out[axis][method] = share_reached(curves, grids[axis])
    return out


def draw(instances: dict[str, dict], prof: dict[str, dict], path: Path, title: str) -> None:
    """Runtime profiles against evaluations and seconds; each instance's finished rewards."""
    fig = Figure(figsize=(17, 5.2), dpi=100)
    axes = fig.subplots(1, 3)
    methods = [m for m in prof["evaluations"] if m != "grid"]
    for ax, axis, label in ((axes[0], "evaluations", "evaluations"),
                            (axes[1], "seconds", "search wall time [s]")):
        for method in methods:
            ax.step(prof[axis]["grid"], prof[axis][method], where="post",
                    color=METHOD_COLOURS.get(method), label=method)
        ax.set_xscale("log")
        ax.set_ylim(0.0, 1.02)
        ax.set_xlabel(label)
        ax.set_ylabel("share of (run, target) pairs reached")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    gaps = ", ".join(f"{g:g}" for g in GAPS)
    axes[0].set_title(f"runtime profiles: {len(instances)} instances x seeds x targets "
                      f"(best known - {gaps})", fontsize=9)
    axes[1].set_title("runtime profiles against the search's wall time", fontsize=9)
    ax = axes[2]
    names = list(instances)
    width = 0.8 / len(methods)
    for k, method in enumerate(methods):
        fin = [np.array([s.reward for s in instances[n]["scores"][method]]) for n in names]
        med = np.array([np.median(f) for f in fin])
        err = np.array([[m - np.percentile(f, 25) for f, m in zip(fin, med, strict=True)],
                        [np.percentile(f, 75) - m for f, m in zip(fin, med, strict=True)]])
        ax.bar(np.arange(len(names)) + (k - (len(methods) - 1) / 2) * width, med, width,
               yerr=err, color=METHOD_COLOURS.get(method), label=method,
               error_kw={"elinewidth": 0.8, "capsize": 1.5})
    ax.scatter(np.arange(len(names)), [instances[n]["target"] for n in names], marker="_",
               s=400, color="k", zorder=3, label="best known")
    ax.set_xticks(np.arange(len(names)), names, rotation=25, fontsize=8, ha="right")
    ax.axhline(0.0, color="k", linewidth=0.6)
    ax.set_ylabel("finished reward (finer member): median, quartiles")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("each instance's finished reward per method", fontsize=9)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png")


def run_instance(name: str, args, methods: list[str], executor, logs: dict[str, IOHLog],
                 known: dict) -> dict:
    """Every method and seed on one instance, scored."""
    problem = make_problem(name, executor=executor)
    scores: dict[str, list[BenchScore]] = {m: [] for m in methods}
    for method in methods:
        for seed in range(args.seeds):
            score = run_method(name, method, budget=args.budget, seed=seed,
                               time_limit_s=args.time, problem=problem, targets=known,
                               log=logs[method], n_checkpoints=args.checkpoints)
            scores[method].append(score)
            print(f"{name}: {method} seed {seed}: finished {score.reward:.4f} (search "
                  f"{score.search_reward:.4f}), {score.evaluations} evaluations, "
                  f"{score.seconds:.1f} s", flush=True)
    target, source = instance_target(name, scores, known)
    return {"scores": scores, "target": target, "target_source": source}


def report(instances: dict[str, dict], config: dict[str, Any], out: Path,
           total_s: float) -> None:
    """Print the tables and the profiles' ends; write the figure and the JSON."""
    tables = {}
    for name, o in instances.items():
        tables[name] = table_rows(o["scores"], o["target"])
        print()
        print(format_table(name, tables[name], o["target"], o["target_source"]))
    methods = config["methods"]
    all_scores = [s for o in instances.values() for rs in o["scores"].values() for s in rs]
    grids = {"evaluations": np.unique(np.geomspace(
                 1, max(s.evaluations for s in all_scores), GRID_POINTS).round()),
             "seconds": np.geomspace(1e-2, max(max(s.seconds for s in all_scores), 0.02),
                                     GRID_POINTS)}
    prof = profiles(instances, grids)
    budget = (f"{config['time_s']:g} s" if config["time_s"] is not None
              else f"{config['budget']} evaluations")
    draw(instances, prof, out / "compare.png",
         f"{len(instances)} instances of the suite: {config['seeds']} seeds x {budget} per "
         "method; finished rewards (the finer member re-scoring the ten best distinct designs)")
    print("\nshare of (run, target) pairs reached at the end: "
          + ", ".join(f"{m} {prof['evaluations'][m][-1]:.2f}" for m in methods))
    counts = {m: (sum(reached(s, o["target"]) for o in instances.values()
                      for s in o["scores"][m]),
                  sum(len(o["scores"][m]) for o in instances.values())) for m in methods}
    print(f"runs within {REACHED_GAP} of the best known: "
          + ", ".join(f"{m} {k}/{n}" for m, (k, n) in counts.items()))
    payload = {
        "config": config,
        "machine": {"platform": platform.platform(), "python": platform.python_version(),
                    "cpus": os.cpu_count()},
        "targets": {n: {"reward": o["target"], "source": o["target_source"]}
                    for n, o in instances.items()},
        "targets_meta": targets_meta(),
        "tables": tables,
        "reached": {m: {"runs": k, "of": n} for m, (k, n) in counts.items()},
        "profiles": prof,
        "runs": {n: {m: [s.to_dict() for s in rs] for m, rs in o["scores"].items()}
                 for n, o in instances.items()},
        "total_time_s": total_s,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "compare.json").write_text(json.dumps(to_jsonable(payload), indent=1) + "\n")
    print(f"\nwrote {out / 'compare.json'} and {out / 'compare.png'}")


def replot(path: Path, out: Path) -> None:
    """Read the runs of a comparison's JSON again, with the targets as they are now."""
    data = json.loads(Path(path).read_text())
    known = current_targets()
    instances = {}
    for name, methods in data["runs"].items():
        scores = {m: [BenchScore.from_dict(r) for r in runs] for m, runs in methods.items()}
        target, source = instance_target(name, scores, known)
        instances[name] = {"scores": scores, "target": target, "target_source": source}
    report(instances, data["config"], out, data.get("total_time_s", 0.0))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=int, default=1000,
                        help="evaluations per run (with --time: the most a run may take)")
    parser.add_argument("--time", type=float, default=None, metavar="SECONDS",
                        help="each run's wall time instead: equal time for every method")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per method and instance")
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--instances", nargs="+", default=list(INSTANCES_RUN),
                        choices=list(INSTANCES))
    parser.add_argument("--checkpoints", type=int, default=CHECKPOINTS,
                        help="evaluation counts of each run the finish scores, log-spaced, "
                        "besides the quarters (default %(default)s; each costs up to ten "
                        "finer evaluations)")
    parser.add_argument("--dask", metavar="ADDRESS|local")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--out", default="out")
    parser.add_argument("--replot", type=Path, metavar="COMPARE_JSON",
                        help="run nothing: read the runs of a comparison's compare.json again "
                        "with the best-known rewards as they are now, and write to --out")
    args = parser.parse_args(argv)
    out = Path(args.out)
    if args.replot is not None:
        replot(args.replot, out)
        return 0
    methods = list(dict.fromkeys(args.methods))
    if (args.seeds < 1 or args.budget < 1 or args.checkpoints < 1
            or (args.time is not None and args.time <= 0)):
        parser.error("--seeds, --budget, --checkpoints and --time must be positive")
    for method in methods:
        try:
            get_optimizer(method)
        except (ValueError, ImportError) as exc:
            parser.error(str(exc))
    known = current_targets()
    t0 = time.perf_counter()
    instances: dict[str, dict] = {}
    logs = {m: IOHLog(out / "compare_ioh", m) for m in methods}
    try:
        with make_executor(args.dask, args.workers) as executor:
            for name in args.instances:
                instances[name] = run_instance(name, args, methods, executor, logs, known)
    finally:
        for log in logs.values():
            log.close()
    executor_name = next(iter(next(iter(instances.values()))["scores"].values()))[0]
    config = {"budget": args.budget, "time_s": args.time, "seeds": args.seeds,
              "checkpoints": args.checkpoints, "methods": methods,
              "instances": list(instances), "gaps": list(GAPS),
              "executor": executor_name.result.executor}
    report(instances, config, out, time.perf_counter() - t0)
    print(f"IOHprofiler logs in {out / 'compare_ioh'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
