"""``psm-grasp optimize`` and the optimization part of ``psm-grasp demo``.

:mod:`envs.cli` imports :func:`add_optimize_parser` and :func:`run_demo` from here when they
exist. ``psm-grasp optimize`` runs one method on one object and writes, to ``--out``:

- ``{method}_seed{S}_result.json``: the :class:`~optim.result.OptimResult`;
- ``{method}_seed{S}_convergence.png``: best reward so far against evaluations;
- ``{method}_seed{S}_best_grasp.png``: the best design's grasp, re-solved and drawn;
- ``{method}_seed{S}_pareto.png`` (NSGA-II): the front with a few of its designs drawn.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from envs.scene import PRESETS

from .optimize import METHODS, get_optimizer
from .problem import (
    DEFAULT_STRAIN_LIMIT,
    DesignProblem,
    check_budget,
    check_seed,
    check_strain_limit,
    paper_design,
)
from .result import OptimResult

__all__ = ["add_optimize_parser", "run_optimize", "run_demo", "paper_reference"]

DEMO_BUDGET = 2000
DEMO_SCENE = "paper-r070"
REFERENCE_TORQUES_NM = (0.05, 0.1, 0.2, 0.3, 0.5)


def paper_reference(problem: DesignProblem, scene: str = DEMO_SCENE,
                    torques_nm: tuple[float, ...] = REFERENCE_TORQUES_NM) -> tuple[float, float]:
    """Best reward of the scene's own (paper) gripper over a few torques, and that torque.

    Not counted in the problem's evaluations.
    """
    designs = np.array([paper_design(scene, t) for t in torques_nm])
    reward = problem.evaluate_physical(designs)["reward"]
    i = int(np.argmax(reward))
    return float(reward[i]), float(torques_nm[i])


def _progress_bar(total: int, desc: str, enabled: bool):
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit="eval", disable=not enabled, leave=False)

    def hook(n_new: int, best: float) -> None:
        bar.update(n_new)
        if math.isfinite(best):
            bar.set_postfix(best=f"{best:.4f}", refresh=False)

    return bar, hook


def write_outputs(result: OptimResult, out_dir: Path, prefix: str,
                  problem: DesignProblem | None = None,
                  reference: float | None = None) -> dict[str, Path]:
    """Write the result JSON, the convergence chart, the best grasp (and the Pareto chart)."""
    from .charts import best_grasp_figure, convergence_figure, pareto_figure

    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {"result": result.to_json(out_dir / f"{prefix}_result.json")}
    paths["convergence"] = out_dir / f"{prefix}_convergence.png"
    convergence_figure([result], paths["convergence"], reference=reference,
                       title=f"{result.method} on {result.object.get('name') or 'object'}, "
                             f"strain limit {result.object['strain_limit']:g}")
    if result.best_design:
        paths["best_grasp"] = out_dir / f"{prefix}_best_grasp.png"
        best_grasp_figure(result, paths["best_grasp"])
    if result.method == "nsga2":
        paths["pareto"] = out_dir / f"{prefix}_pareto.png"
        pareto_figure(result, paths["pareto"],
                      archive=None if problem is None else problem.archive())
    return paths


def _print_summary(result: OptimResult, reference: tuple[float, float] | None,
                   paths: dict[str, Path]) -> None:
    print(result.summary())
    d = result.best_design
    if d:
        print(f"  best design: l = {d['finger_length_m']:.4f} m, "
              f"theta_a0 = {math.degrees(d['rest_angle_rad']):.2f} deg, "
              f"d3 = {d['joint_offset_m']:.4f} m, w = {d['finger_width_m']:.4f} m, "
              f"T_a = {d['torque_nm']:.4f} N·m, d1 = {d['distance_m']:.4f} m")
    if reference is not None:
        print(f"  paper gripper (best of T_a in {list(REFERENCE_TORQUES_NM)} N·m): "
              f"{reference[0]:.4f} at T_a = {reference[1]:g} N·m")
    if result.pareto_front:
        print(f"  Pareto front: {len(result.pareto_front)} designs")
    print(f"  executor: {result.executor}, {result.evaluations_per_s:.0f} evaluations/s")
    for name, path in paths.items():
        print(f"  {name:12s}: {path}")


def run_optimize(
    method: str,
    *,
    scene: str = DEMO_SCENE,
    budget: int = 2000,
    seed: int = 0,
    out: str | Path = "out",
    dask: str | None = None,
    workers: int | None = None,
    strain_limit: float = DEFAULT_STRAIN_LIMIT,
    n_triangles: int = 20,
    progress: bool = True,
    prefix: str | None = None,
    verbose: bool = True,
    **options: Any,
) -> tuple[OptimResult, dict[str, Path]]:
    """Run one method on a scene's object and write its files (what ``optimize`` does).

    Every option is validated before any cluster is started.

    Raises
    ------
    ValueError
        Unknown method or scene, budget <= 0, bad seed, strain limit outside (0, 1], bad
        worker count.
    """
    from .executors import make_executor

    driver = get_optimizer(method)
    if scene not in PRESETS:
        raise ValueError(f"unknown scene {scene!r}; allowed: {sorted(PRESETS)}")
    budget, seed = check_budget(budget), check_seed(seed)
    strain_limit = check_strain_limit(strain_limit)
    out_dir = Path(out)
    prefix = prefix or f"{method}_seed{seed}"
    bar, hook = _progress_bar(budget, method, progress)
    with make_executor(dask, workers) as executor:
        problem = DesignProblem.from_scene(scene, strain_limit, n_triangles=n_triangles,
                                           executor=executor, progress=hook)
        try:
            result = driver(problem, budget=budget, seed=seed, **options)
        finally:
            bar.close()
        reference = paper_reference(problem, scene) if scene.startswith("paper") else None
        paths = write_outputs(result, out_dir, prefix, problem,
                              None if reference is None else reference[0])
    if verbose:
        _print_summary(result, reference, paths)
    return result, paths


def _optimize_command(args: argparse.Namespace) -> int:
    run_optimize(args.method, scene=args.scene, budget=args.budget, seed=args.seed,
                 out=args.out, dask=args.dask, workers=args.workers,
                 strain_limit=args.strain_limit, n_triangles=args.triangles,
                 progress=not args.no_progress)
    return 0


def add_optimize_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``optimize`` command to the ``psm-grasp`` sub-parsers."""
    p = subparsers.add_parser(
        "optimize", help="optimize a gripper design for one object",
        description="Optimize a gripper design for the object of a scene preset and write the "
                    "result JSON, a convergence chart and the best grasp (NSGA-II: the Pareto "
                    "front) to --out.")
    p.add_argument("--method", default="cmaes", choices=METHODS)
    p.add_argument("--scene", default=DEMO_SCENE, choices=sorted(PRESETS),
                   help="object: the disk of this preset (default %(default)s)")
    p.add_argument("--budget", type=int, default=2000, help="evaluations (default %(default)s)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="out", help="output folder (default %(default)s)")
    p.add_argument("--dask", metavar="ADDRESS|local",
                   help="evaluate on a Dask cluster: a scheduler address, or 'local' to start "
                        "a LocalCluster of --workers workers")
    p.add_argument("--workers", type=int,
                   help="parallel workers: local processes without --dask, LocalCluster "
                        "workers with --dask local (default: in-process, batched)")
    p.add_argument("--strain-limit", type=float, default=DEFAULT_STRAIN_LIMIT,
                   help="admissible strain of the object, in (0, 1] (default %(default)s)")
    p.add_argument("--triangles", type=int, default=20, help="fan triangles N (default 20)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_optimize_command)
    return p


def run_demo(out_dir: Path) -> int:
    """CMA-ES design of the gripper for the paper's r = 0.07 m disk (budget 2000, seed 0).

    Writes ``demo_result.json``, ``demo_convergence.png`` and ``demo_best_grasp.png`` to
    ``out_dir`` and prints a short summary. Takes well under 2 minutes on 2 cores.
    """
    t0 = time.perf_counter()
    print(f"CMA-ES gripper design for the {DEMO_SCENE} disk: budget {DEMO_BUDGET} "
          f"evaluations, strain limit {DEFAULT_STRAIN_LIMIT}")
    run_optimize("cmaes", scene=DEMO_SCENE, budget=DEMO_BUDGET, seed=0, out=out_dir,
                 prefix="demo")
    print(f"demo done in {time.perf_counter() - t0:.1f} s")
    return 0
