"""The default run as a user runs it: ``psm-grasp optimize --object FILE --jaw JAW --seed S``
with no method and no budget, on several objects and seeds, and how far each run ends from the
best design known.

Each run is the command itself in a fresh process (import, kernels loaded from the cache, the
search, the finish, the charts and the files), timed as the user waits for it (wall) and by
the CPU it used (both cores count). Its answer is the result JSON's: the reward of the reported
design by the finer member, whether it holds in every scenario, the verdict and the exit code.

The best known reward of an object is the best of: ``--suite-targets`` (the benchmark suite's
best-known rewards, ``optim/bench/targets.json``, for the suite's objects of the same name),
``--targets`` (a JSON object mapping an object file's stem, and optionally ``STEM-JAW``, to a
reward), and every run of this measurement with either jaw (the straight bar lies inside the
shaped-jaw space). A run is *within reach* when it ends within ``--gap`` (default 0.01) of it.

Prints a table per object and jaw (median, extremes, runs within reach, runs that hold, wall
and CPU seconds) and whether ``--jaw any`` ends at least as high as ``--jaw straight`` on every
seed, and writes every run to ``OUT/default_search.json``.

Usage::

    python scripts/default_search.py examples/objects/strawberry.toml ... [--seeds 5]
        [--jaws any straight] [--suite-targets] [--targets FILE] [--gap 0.01]
        [--out out/default_search]
        [-- EXTRA OPTIONS FOR optimize]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
GAP = 0.01  # "found the optimum": within this reward of the best known (finer member)


def run_once(path: Path, jaw: str, seed: int, out: Path, extra: list[str]) -> dict[str, Any]:
    """One ``psm-grasp optimize`` in a fresh process: its result's answer, wall and CPU time."""
    folder = out / "runs" / f"{path.stem}-{jaw}-seed{seed}"
    folder.parent.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "cli", "optimize", "--object", str(path), "--jaw", jaw,
           "--seed", str(seed), "--out", str(folder), "--no-progress", *extra]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    row: dict[str, Any] = {"object": path.stem, "jaw": jaw, "seed": seed, "exit": done.returncode,
                           "wall_s": wall, "cpu_s": (after.ru_utime - before.ru_utime)
                           + (after.ru_stime - before.ru_stime)}
    results = sorted(folder.glob("*_result.json"))
    if not results:
        row["error"] = done.stderr.strip().splitlines()[-1:] or ["no result written"]
        return row
    data = json.loads(results[0].read_text())
    metrics = data.get("best_metrics") or {}
    verdict = data.get("extra", {}).get("verdict") or {}
    row.update(method=data["method"], budget=data["budget"], evaluations=data["n_evaluations"],
               search_s=data["wall_time_s"], reward=data["best_reward"],
               holds=bool(metrics.get("holds_all", metrics.get("holds", False))),
               verdict=verdict.get("verdict"))
    return row


def suite_targets(paths: list[Path]) -> dict[str, float]:
    """The benchmark suite's best-known rewards of the objects of ``paths`` (by the object's
    name: the suite's objects and the example files share theirs), keyed by file stem; a
    target computed with another version of the model is refused."""
    from envs.object_file import load_object
    from optim.bench import INSTANCES, load_targets, targets_stale
    from optim.bench.problems import OBJECTS

    if targets_stale():
        raise SystemExit("the suite's targets were computed with another version of the model: "
                         "python scripts/bench_targets.py first")
    by_name: dict[str, float] = {}
    for name, target in load_targets().items():
        key = OBJECTS[INSTANCES[name].object_key]["name"]
        by_name[key] = max(by_name.get(key, -float("inf")), target.reward)
    names = {path.stem: load_object(path).name for path in paths}
    return {stem: by_name[name] for stem, name in names.items() if name in by_name}


def best_known(rows: list[dict[str, Any]], targets: dict[str, float]) -> dict[str, float]:
    """Each object's best known reward: its target (any key ``STEM`` or ``STEM-JAW``) and the
    best reward of any of its runs, whichever is higher."""
    best: dict[str, float] = {}
    for row in rows:
        if "reward" in row:
            best[row["object"]] = max(best.get(row["object"], -float("inf")), row["reward"])
    for key, value in targets.items():
        stem = key.rsplit("-", 1)[0] if key.rsplit("-", 1)[-1] in ("any", "straight") else key
        if stem in best:
            best[stem] = max(best[stem], float(value))
    return best


def summary(rows: list[dict[str, Any]], best: dict[str, float], gap: float) -> list[str]:
    """The table's lines: one per object and jaw, then the jaw comparison per seed."""
    lines = ["| object | jaw | best known | median (min - max) | within reach | holds | "
             "wall s median (max) | CPU s median |", "|---|---|---|---|---|---|---|---|"]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["object"], row["jaw"]), []).append(row)
    for (name, jaw), runs in groups.items():
        done = [r for r in runs if "reward" in r]
        rewards = [r["reward"] for r in done]
        reach = sum(r["reward"] >= best[name] - gap for r in done)
        walls = [r["wall_s"] for r in runs]
        lines.append(
            f"| {name} | {jaw} | {best.get(name, float('nan')):.4f} | "
            + (f"{statistics.median(rewards):.4f} ({min(rewards):.4f} - {max(rewards):.4f})"
               if rewards else "no result")
            + f" | {reach} of {len(runs)} | {sum(r.get('holds', False) for r in done)} of "
            f"{len(runs)} | {statistics.median(walls):.1f} ({max(walls):.1f}) | "
            f"{statistics.median(r['cpu_s'] for r in runs):.1f} |")
    pairs = {}
    for row in rows:
        if "reward" in row:
            pairs.setdefault((row["object"], row["seed"]), {})[row["jaw"]] = row["reward"]
    both = [p for p in pairs.values() if {"any", "straight"} <= set(p)]
    if both:
        below = [(k, p) for k, p in pairs.items() if {"any", "straight"} <= set(p)
                 and p["any"] < p["straight"] - 1e-9]
        lines.append(f"\n--jaw any >= --jaw straight on {len(both) - len(below)} of {len(both)} "
                     "(object, seed) pairs" + ("" if not below else ": below on " + ", ".join(
                         f"{k[0]} seed {k[1]} ({p['any']:.4f} < {p['straight']:.4f})"
                         for k, p in below)))
    everything = [r for r in rows if "reward" in r and r["jaw"] == "any"]
    if everything:
        reach = sum(r["reward"] >= best[r["object"]] - gap for r in everything)
        lines.append(f"--jaw any within {gap} of the best known: {reach} of {len(everything)} "
                     f"runs ({100 * reach / len(everything):.0f} %); wall at most "
                     f"{max(r['wall_s'] for r in everything):.1f} s")
    return lines


def main(argv: list[str] | None = None) -> None:
    argv = list(sys.argv[1:] if argv is None else argv)
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[: argv.index("--")] if "--" in argv else argv
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("objects", type=Path, nargs="+", help="object files (TOML)")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--jaws", nargs="+", default=["any", "straight"],
                        choices=("straight", "cradle", "vee", "any"))
    parser.add_argument("--targets", type=Path, help="JSON: object stem (or STEM-JAW) -> reward")
    parser.add_argument("--suite-targets", action="store_true",
                        help="also the benchmark suite's best-known rewards (optim/bench)")
    parser.add_argument("--gap", type=float, default=GAP)
    parser.add_argument("--out", type=Path, default=Path("out/default_search"))
    parser.add_argument("--resume", action="store_true",
                        help="keep the runs already in OUT/default_search.json")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")
    args.out.mkdir(parents=True, exist_ok=True)
    record = args.out / "default_search.json"
    rows: list[dict[str, Any]] = (json.loads(record.read_text())["runs"]
                                  if args.resume and record.is_file() else [])
    seen = {(r["object"], r["jaw"], r["seed"]) for r in rows}
    targets = json.loads(args.targets.read_text()) if args.targets else {}
    if args.suite_targets:
        targets.update(suite_targets(args.objects))
    print(f"cores {os.cpu_count()}, load {os.getloadavg()[0]:.2f}; extra options {extra}",
          flush=True)
    for seed in range(args.seeds):  # seeds outermost: every object has a few runs early
        for path in args.objects:
            for jaw in args.jaws:
                if (path.stem, jaw, seed) in seen:
                    continue
                row = run_once(path.resolve(), jaw, seed, args.out.resolve(), extra)
                row["load"] = os.getloadavg()[0]
                rows.append(row)
                print(json.dumps(row), flush=True)
                record.write_text(json.dumps({"extra": extra, "runs": rows}, indent=1) + "\n")
    best = best_known(rows, targets)
    text = "\n".join(summary(rows, best, args.gap))
    print(text)
    (args.out / "default_search.md").write_text(text + "\n")


if __name__ == "__main__":
    main()
