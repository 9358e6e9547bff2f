"""Best-known rewards of the benchmark suite (optim/bench/targets.json), from long runs.

For each instance of :data:`optim.bench.INSTANCES`, every method runs with every seed at a
large budget; each run's ten best distinct designs are re-scored by the finer member, as the
finish does (:func:`optim.finish.finish_result`), and the instance's target is the best of
them, kept with its design, the run that found it and the campaign's settings. The rewards
depend on the model: when its source (``envs/``) changes, run this again (the file records the
source's digest; :func:`optim.bench.targets_stale` says when it differs).

Every run is appended to ``--runs`` (JSON lines) as it ends, and ``--resume`` skips the runs
already there (same instance, method, seed, budget and model): a campaign cut off goes on where
it stopped. ``--add-runs out/compare.json`` adds the runs of ``scripts/compare_optimizers.py``
(their finished designs, same model) to the evidence. The targets are written after every
instance.

Usage::

    python scripts/bench_targets.py [--instances strawberry-any ...] [--seeds 3]
        [--methods portfolio cmaes ga nsga2 ng:TwoPointsDE ng:NGOpt cma:bipop]
        [--budget 6000] [--scenario-budget 3000] [--resume] [--add-runs out/compare.json]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from optim.bench import DEFAULT_INSTANCES, INSTANCES, make_problem, run_method
from optim.bench.targets import TARGETS_FILE, model_digest
from optim.finish import FINISH_TOP, RANKING_MEMBER
from optim.result import to_jsonable

METHODS = ("portfolio", "cmaes", "ga", "nsga2", "ng:TwoPointsDE", "ng:NGOpt", "cma:bipop")
BUDGET = 6000  # an instance judged on the one exact object
SCENARIO_BUDGET = 3000  # an instance with scenarios: each evaluation solves 9 or 25 grasps


def _commit() -> str | None:
    try:
        return subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                              check=True, cwd=Path(__file__).parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def _read_runs(path: Path, digest: str) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return [r for r in rows if r.get("model_digest") == digest]


def run_instance(name: str, args, budget: int, done: set, runs_path: Path,
                 digest: str, commit: str | None) -> list[dict[str, Any]]:
    """Every method and seed on one instance (those not done yet); the new rows."""
    problem = make_problem(name)
    rows = []
    for method in args.methods:
        for seed in range(args.seeds):
            if (name, method, seed, budget) in done:
                continue
            score = run_method(name, method, budget=budget, seed=seed, problem=problem,
                               targets={}, n_checkpoints=1)
            row = {"instance": name, "method": method, "seed": seed, "budget": budget,
                   "seconds": score.seconds, "search_reward": score.search_reward,
                   "reward": score.reward, "design": score.curve.best_design,
                   "design_search_reward": _search_reward_of(score),
                   "model_digest": digest, "commit": commit}
            rows.append(row)
            with runs_path.open("a") as f:
                f.write(json.dumps(to_jsonable(row)) + "\n")
            print(f"{name}: {method} seed {seed}: finished {score.reward:.4f} (search "
                  f"{score.search_reward:.4f}) in {score.seconds:.0f} s", flush=True)
    return rows


def _search_reward_of(score) -> float:
    """The search model's reward of the finished design (the best of the run's top ten and,
    for a portfolio, its starts' bests, by the finer member)."""
    design = score.curve.best_design
    for top in (*score.result.top_designs, *score.result.extra.get("start_designs", ())):
        if top["design"] == design:
            return float(top["reward"])
    return float("nan")


def compare_rows(path: Path, digest: str) -> list[dict[str, Any]]:
    """The runs of a ``scripts/compare_optimizers.py`` output as rows of this campaign (its
    finished design and reward, the evaluations it made as its budget)."""
    data = json.loads(Path(path).read_text())
    if data.get("targets_meta", {}).get("model_digest", digest) != digest:
        raise SystemExit(f"{path}: its runs were scored by another version of the model")
    rows = []
    for name, methods in data["runs"].items():
        for method, runs in methods.items():
            for run in runs:
                design = run["curve"]["best_design"]
                top = [t for t in run["result"]["top_designs"] if t["design"] == design]
                rows.append({"instance": name, "method": method, "seed": run["seed"],
                             "budget": run["evaluations"], "seconds": run["seconds"],
                             "search_reward": run["search_reward"], "reward": run["reward"],
                             "design": design,
                             "design_search_reward": top[0]["reward"] if top else float("nan"),
                             "model_digest": digest, "source": str(path)})
    return rows


def targets_of(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """The best finished reward of each instance, its design and run, and every run's."""
    out: dict[str, dict[str, Any]] = {}
    for name in dict.fromkeys(r["instance"] for r in rows):
        mine = [r for r in rows if r["instance"] == name]
        best = max(mine, key=lambda r: r["reward"])
        by_method: dict[str, list[float]] = {}
        for r in mine:
            key = r["method"] if "source" not in r else f"{r['method']} ({r['budget']} evals)"
            by_method.setdefault(key, []).append(round(r["reward"], 6))
        out[name] = {"reward": best["reward"], "search_reward": best["design_search_reward"],
                     "design": best["design"], "method": best["method"], "seed": best["seed"],
                     "budget": best["budget"], "runs": len(mine),
                     **({"source": best["source"]} if "source" in best else {}),
                     "finished_by_method": by_method}
    return out


def write_targets(path: Path, rows: list[dict[str, Any]], args, digest: str,
                  commit: str | None) -> None:
    """The targets file: the targets and how they were obtained."""
    targets = targets_of(rows)
    command = "python " + " ".join(shlex.quote(a) for a in sys.argv)
    commands = [command]
    if args.resume and path.exists():  # the commands whose runs are kept (same model)
        old = json.loads(path.read_text()).get("meta", {})
        if old.get("model_digest") == digest:
            commands = [c for c in old.get("commands", []) if c != command] + commands
    meta = {
        "how": "the best reward the finer member gave any design of the runs: each run's ten "
               "best distinct designs (by the search model) re-scored, as the finish does; "
               "each target lists its runs' finished rewards by method (seeds 0, 1, ...) and "
               "their budget",
        "commands": commands,
        "date": datetime.date.today().isoformat(),
        "commit": commit,
        # the code each kept run ran (a campaign resumed after commits spans several)
        "run_commits": sorted({r["commit"] for r in rows if r.get("commit")}),
        "model_digest": digest,
        "finer_member": RANKING_MEMBER,
        "finish_top": FINISH_TOP,
        "runs": len(rows),
        "methods": sorted({r["method"] for r in rows}),
        "instances_without_target": [n for n in INSTANCES if n not in targets],
        # the searches' wall time, summed over the runs (the finishes' re-scoring left out)
        "run_seconds": round(sum(r["seconds"] for r in rows), 1),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
    }
    path.write_text(json.dumps(to_jsonable({"meta": meta, "targets": targets}), indent=1)
                    + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--instances", nargs="*", default=list(DEFAULT_INSTANCES),
                        choices=list(INSTANCES),
                        help="the instances to run (none: only write the targets of the runs "
                        "kept with --resume and --add-runs)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--budget", type=int, default=BUDGET,
                        help="evaluations per run on an instance without scenarios")
    parser.add_argument("--scenario-budget", type=int, default=SCENARIO_BUDGET,
                        help="evaluations per run on an instance with scenarios")
    parser.add_argument("--out", type=Path, default=TARGETS_FILE, help="the targets file")
    parser.add_argument("--runs", type=Path, default=Path("out/bench_targets_runs.jsonl"),
                        help="every run, one JSON line each")
    parser.add_argument("--add-runs", type=Path, nargs="*", default=[], metavar="COMPARE_JSON",
                        help="add the runs of scripts/compare_optimizers.py outputs")
    parser.add_argument("--resume", action="store_true",
                        help="skip the runs already in --runs (same model) and keep them (the "
                        "targets are those of every run in it)")
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.budget < 1 or args.scenario_budget < 1:
        parser.error("--seeds and the budgets must be >= 1")
    digest, commit = model_digest(), _commit()
    args.runs.parent.mkdir(parents=True, exist_ok=True)
    if not args.resume and args.runs.exists():
        args.runs.unlink()
    rows = _read_runs(args.runs, digest)
    done = {(r["instance"], r["method"], r["seed"], r["budget"]) for r in rows}
    for path in args.add_runs:
        rows += compare_rows(path, digest)
    t0 = time.perf_counter()
    for name in args.instances:
        budget = args.budget if INSTANCES[name].n_scenarios() == 1 else args.scenario_budget
        rows += run_instance(name, args, budget, done, args.runs, digest, commit)
        write_targets(args.out, rows, args, digest, commit)
    if not args.instances:
        write_targets(args.out, rows, args, digest, commit)
    for name, t in targets_of(rows).items():
        print(f"{name:24s} {t['reward']:8.4f}  ({t['method']}, seed {t['seed']}, "
              f"{t['budget']} evaluations; {t['runs']} runs)")
    print(f"wrote {args.out} ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
