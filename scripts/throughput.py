"""Throughput of this checkout against a baseline checkout, side by side in one run.

Each repeat starts one measuring process per checkout, interleaved (baseline, this, baseline,
this, ...), each importing its own ``envs`` (``PYTHONPATH``) with this interpreter; it loads
(or compiles, the first time) its kernels, warms up, and times:

- ``batch``: one :func:`envs.evaluate.evaluate_designs` call on ``--batch`` random designs of
  the design box on paper-r070 (``--jaw``: with grooved jaws), the default model (designs per
  second; ``--fan``: the paper's fan too);
- ``scenarios``: :func:`envs.scenarios.evaluate_scenarios` of ``--scenario-designs`` designs
  under a 3 x 3 placement grid (``--placement-mm``, both ways, 9 scenarios a design), from
  rest (``warm_start=False``, as every scenario was solved before) and, where the checkout
  has it, with the warm start from each design's nominal scenario (seconds); ``--scenario-jaws
  straight any``: the same batch of designs of each jaw (keys ``scenarios_<jaw>_*`` for a jaw
  other than straight);
- ``objects`` (``--objects FILE ...``): each object file's own scenario batch (its ranges and
  placement tolerance, strain limit, friction and payload, as ``psm-grasp optimize --object``
  judges a design) of ``--scenario-designs`` random designs of each jaw of ``--object-jaws``
  (straight bars and ``any`` shaped jaws by default), as the search runs it (designs per
  second, and the batch's seconds; keys ``object_<file>_<jaw>_*``).

Each is timed twice: wall seconds, and the CPU seconds of the measuring process (its threads'
work, which the other jobs of a shared machine disturb far less; keys ``*_cpu_s``). It prints
each measurement, the machine's load, and the ratios of the medians (this checkout over the
baseline; for the scenarios also warm over independent, both of this checkout)::

    git archive <commit> | (mkdir -p /tmp/base && tar -x -C /tmp/base)
    python scripts/throughput.py --baseline /tmp/base [--repeats 3]

The baseline's kernels compile on its first run (minutes); later runs load them.
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


def _seconds(fn) -> tuple[float, float]:
    """Wall seconds of ``fn()`` and the CPU seconds of this process's threads meanwhile (the
    work, which other jobs on a shared machine disturb far less than the wall time)."""
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def measure(args: argparse.Namespace) -> dict:
    """One process's measurements (``--worker``): the ``envs`` on ``sys.path`` first."""
    import numpy as np

    from envs.evaluate import DesignBounds, evaluate_designs
    from envs.model.defaults import PAPER_TORSION_STIFFNESS_NM_PER_RAD
    from envs.scenarios import Scenarios, evaluate_scenarios
    from envs.scene import PRESETS

    disk = PRESETS["paper-r070"][1]
    rng = np.random.default_rng(args.seed)
    designs = DesignBounds(jaw=getattr(args, "jaw", "straight")).sample(rng, args.batch, disk)
    members = {"default": {}}
    if args.fan:
        members["fan"] = {"element": "spring"}
    out: dict = {"envs": str(Path(sys.modules["envs"].__file__).parent), "load_before": _load()}
    for name, model in members.items():
        evaluate_designs(designs[:4], disk, **model)  # load or compile, and warm up
        wall, cpu = _seconds(lambda model=model: evaluate_designs(designs, disk, **model))
        out[f"batch_{name}_designs_per_s"] = args.batch / wall
        out[f"batch_{name}_cpu_s"] = cpu
    grid = Scenarios.of(placement_tolerance_m=args.placement_mm * 1e-3)
    common = {"torsion_stiffness_nm_per_rad": PAPER_TORSION_STIFFNESS_NM_PER_RAD,
              "friction_coefficient": 0.5}
    modes = {"independent": {}}
    if "warm_start" in inspect.signature(evaluate_scenarios).parameters:
        modes = {"independent": {"warm_start": False}, "warm": {"warm_start": True}}
    for jaw in (args.scenario_jaws if args.scenario_designs > 0 else ()):
        picked = (designs[: args.scenario_designs] if jaw == "straight" else
                  DesignBounds(jaw=jaw).sample(np.random.default_rng(args.seed),
                                               args.scenario_designs, disk))
        prefix = "scenarios" if jaw == "straight" else f"scenarios_{jaw}"
        for mode, extra in modes.items():
            evaluate_scenarios(picked[:2], disk, grid, **common, **extra)
            out[f"{prefix}_{mode}_s"], out[f"{prefix}_{mode}_cpu_s"] = _seconds(
                lambda extra=extra, picked=picked: evaluate_scenarios(picked, disk, grid,
                                                                      **common, **extra))
    for path in (args.objects if args.scenario_designs > 0 else ()):
        for jaw in args.object_jaws:
            problem = _object_problem(path, jaw)
            rng = np.random.default_rng(args.seed)
            picked = problem.to_physical(rng.uniform(-1.0, 1.0, (args.scenario_designs,
                                                                  problem.n_var)))
            problem.evaluate_physical(picked[:2])  # warm up
            key = f"object_{Path(path).stem}_{jaw}"
            wall, out[f"{key}_cpu_s"] = _seconds(
                lambda problem=problem, picked=picked: problem.evaluate_physical(picked))
            out[f"{key}_s"] = wall
            out[f"{key}_designs_per_s"] = args.scenario_designs / wall
    out["load_after"] = _load()
    return out


def _object_problem(path: Path, jaw: str):
    """The problem ``psm-grasp optimize --object path --jaw jaw`` evaluates designs of."""
    from envs.object_file import load_object
    from optim.problem import DesignProblem
    from optim.run import problem_kwargs

    obj = load_object(path)
    target, settings = problem_kwargs(None, obj, None, None, None, None, jaw=jaw)
    return DesignProblem(target, name=obj.name, **settings)


def _run_worker(tree: Path, args: argparse.Namespace) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", "--batch",
           str(args.batch), "--scenario-designs", str(args.scenario_designs), "--placement-mm",
           str(args.placement_mm), "--seed", str(args.seed), "--jaw",
           getattr(args, "jaw", "straight"), "--scenario-jaws",
           *args.scenario_jaws, "--object-jaws", *args.object_jaws]
    cmd += (["--fan"] if args.fan else []) + (["--objects", *map(str, args.objects)]
                                              if args.objects else [])
    done = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"measurement in {tree} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _median(rows: list[dict], key: str) -> float | None:
    values = [r[key] for r in rows if key in r]
    return statistics.median(values) if values else None


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", type=Path, help="a checkout to compare against")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--batch", type=int, default=2048)
    parser.add_argument("--scenario-designs", type=int, default=128)
    parser.add_argument("--placement-mm", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fan", action="store_true", help="also the paper's fan's batch")
    parser.add_argument("--jaw", default="straight",
                        help="the designs' jaws (envs.DesignBounds jaw: straight, cradle, vee, "
                        "any)")
    parser.add_argument("--scenario-jaws", nargs="+", default=["straight"],
                        choices=("straight", "cradle", "vee", "any"),
                        help="the jaws of the placement batch's designs")
    parser.add_argument("--objects", type=Path, nargs="*", default=[],
                        help="object files whose own scenario batches to time")
    parser.add_argument("--object-jaws", nargs="+", default=["straight", "any"],
                        choices=("straight", "cradle", "vee", "any"))
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, default=None, help="write the results as JSON")
    args = parser.parse_args(argv)
    args.objects = [path.resolve() for path in args.objects]
    if args.worker:
        print(json.dumps(measure(args)))
        return
    if args.baseline is None or not (args.baseline / "envs" / "__init__.py").is_file():
        parser.error("--baseline must be a checkout of the package (with envs/)")
    trees = {"baseline": args.baseline.resolve(), "this": HERE}
    results: dict[str, list[dict]] = {name: [] for name in trees}
    print(f"cores {os.cpu_count()}, load {_load()}; batch {args.batch}, scenarios "
          f"{args.scenario_designs} designs x 9 placements (+-{args.placement_mm} mm)",
          flush=True)
    for rep in range(args.repeats):
        for name, tree in trees.items():
            row = _run_worker(tree, args)
            results[name].append(row)
            shown = {k: round(v, 3) for k, v in row.items() if isinstance(v, float)}
            print(f"repeat {rep} {name}: {shown} load {row['load_before']} -> "
                  f"{row['load_after']}", flush=True)
    summary: dict[str, float] = {}
    for key in sorted({k for rows in results.values() for r in rows for k in r
                       if k.endswith(("_per_s", "_s"))}):
        base, this = _median(results["baseline"], key), _median(results["this"], key)
        if base is None or this is None:
            continue
        # designs per second: this over the baseline; seconds: the baseline over this
        ratio = this / base if key.endswith("_per_s") else base / this
        summary[f"{key}_ratio"] = ratio
        print(f"{key}: baseline {base:.3f}, this {this:.3f}: {ratio:.2f}x")
    for clock in ("", "_cpu"):
        indep, warm = (_median(results["this"], f"scenarios_independent{clock}_s"),
                       _median(results["this"], f"scenarios_warm{clock}_s"))
        if indep and warm:
            summary[f"scenarios{clock}_warm_over_independent"] = indep / warm
            print(f"scenarios{clock}, this checkout: independent {indep:.3f} s, warm "
                  f"{warm:.3f} s: {indep / warm:.2f}x")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({"results": results, "summary": summary}, indent=1))


if __name__ == "__main__":
    main()
