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
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from envs.model.defaults import MAX_TRIANGLES, MAX_TRIANGLES_FAMILY
from envs.model.family import ELEMENTS
from envs.scene import PRESETS, Scene
from envs.validation import check_integer

from .optimize import METHODS, get_optimizer
from .problem import (
    DEFAULT_STRAIN_LIMIT,
    DesignProblem,
    check_budget,
    check_seed,
    check_strain_limit,
    paper_design,
)
from .result import NoGraspWarning, OptimResult, no_grasp_reason
from .verify import DEFAULT_TOP, MAX_TOP

__all__ = ["add_optimize_parser", "add_verify_parser", "run_optimize", "run_demo",
           "paper_reference", "verify_outputs"]

DEMO_BUDGET = 2000
DEMO_VERIFY_TOP = 3
NO_GRASP_EXIT = 3  # exit code of `optimize` when the best design found is not a grasp
DEMO_SCENE = "paper-r070"
REFERENCE_TORQUES_NM = (0.05, 0.1, 0.2, 0.3, 0.5)


def paper_reference(problem: DesignProblem, scene: str = DEMO_SCENE,
                    torques_nm: tuple[float, ...] = REFERENCE_TORQUES_NM) -> tuple[float, float]:
    """Best reward of the scene's own (paper) gripper over a few torques, and that torque.

    The torques are those of the paper-r070 disk scaled by the disk's torque unit ``s E t r^2``
    (the same squeeze for every object: unchanged on paper-r070, 0.4 to 4 mN·m on the forceps'
    2 mm beads). Not counted in the problem's evaluations.
    """
    ratio = problem.disk.torque_unit_nm / Scene.preset(DEMO_SCENE).disk.torque_unit_nm
    designs = np.array([paper_design(scene, t * ratio) for t in torques_nm])
    reward = problem.evaluate_physical(designs)["reward"]
    i = int(np.argmax(reward))
    return float(reward[i]), float(torques_nm[i] * ratio)


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
        print(f"  the scene's own gripper (best of 5 torques): {reference[0]:.4f} at "
              f"T_a = {reference[1]:.3g} N·m")
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
    n_triangles: int | None = None,
    progress: bool = True,
    n_rings: int | None = None,
    element: str | None = None,
    prefix: str | None = None,
    verbose: bool = True,
    **options: Any,
) -> tuple[OptimResult, dict[str, Path]]:
    """Run one method on a scene's object and write its files (what ``optimize`` does).

    Every option is validated before any cluster is started or any evaluation is spent, the
    output folder included. ``result.extra["grasp_found"]`` tells whether the best design is a
    grasp (valid, converged, both fingers touching); when it is not, a warning goes to stderr
    (and ``psm-grasp optimize`` exits with :data:`NO_GRASP_EXIT`).

    Raises
    ------
    ValueError
        Unknown method or scene, budget <= 0, bad seed, strain limit outside (0, 1], a model
        member outside the family (:func:`envs.model.family.resolve_model`; default: the
        default model, ``element="spring"`` the paper's fan), bad worker count or Dask
        address, an output folder that cannot be written.
    """
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.model.family import resolve_model
    from envs.validation import check_output_dir

    from .executors import check_executor_options, make_executor

    # every option before any work (no cluster started, no evaluation spent)
    driver = get_optimizer(method)
    if scene not in PRESETS:
        raise ValueError(f"unknown scene {scene!r}; allowed: {sorted(PRESETS)}")
    budget, seed = check_budget(budget), check_seed(seed)
    strain_limit = check_strain_limit(strain_limit)
    model = resolve_model(n_triangles, n_rings, element or DEFAULT_ELEMENT)
    check_executor_options(dask, workers)
    out_dir = check_output_dir("out", out)
    prefix = prefix or f"{method}_seed{seed}"
    bar, hook = _progress_bar(budget, method, progress)
    with make_executor(dask, workers) as executor:
        problem = DesignProblem.from_scene(scene, strain_limit, executor=executor,
                                           progress=hook, **model.kwargs())
        try:
            with warnings.catch_warnings():
                # said once below, with the files written
                warnings.simplefilter("ignore", NoGraspWarning)
                result = driver(problem, budget=budget, seed=seed, **options)
        finally:
            bar.close()
        reference = paper_reference(problem, scene)
        paths = write_outputs(result, out_dir, prefix, problem,
                              None if reference is None else reference[0])
    if verbose:
        _print_summary(result, reference, paths)
    if not result.extra["grasp_found"]:
        print(f"psm-grasp: warning: {method} found no grasp in {result.n_evaluations} "
              f"evaluations: its best design {no_grasp_reason(result.best_metrics)} (reward "
              f"{result.best_reward:.4f}); the files in {str(out_dir)!r} describe that design",
              file=sys.stderr)
    return result, paths


def _optimize_command(args: argparse.Namespace) -> int:
    from envs.cli import cli_option
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.model.family import resolve_model
    from envs.validation import check_output_dir

    # the options a user typed, named as typed (run_optimize checks them all again)
    cli_option("--triangles/--rings/--element", resolve_model, args.triangles, args.rings,
               args.element or DEFAULT_ELEMENT)
    cli_option("--budget", check_budget, args.budget)
    cli_option("--seed", check_seed, args.seed)
    cli_option("--strain-limit", check_strain_limit, args.strain_limit)
    check_output_dir("--out", args.out)
    if args.verify_top is not None:
        check_integer("--verify-top", args.verify_top, 1, MAX_TOP)
        if not fem_available():
            raise ValueError("--verify-top needs scikit-fem: pip install -e '.[fem]'")
    from envs.solver.warmup import announce_compile

    announce_compile()
    result, _ = run_optimize(args.method, scene=args.scene, budget=args.budget, seed=args.seed,
                             out=args.out, dask=args.dask, workers=args.workers,
                             strain_limit=args.strain_limit, n_triangles=args.triangles,
                             n_rings=args.rings, element=args.element,
                             progress=not args.no_progress)
    if args.verify_top is not None:
        verify_outputs(args.out, f"{args.method}_seed{args.seed}_result.json", args.verify_top)
    # a run that found no grasp is not a success, whatever files it wrote
    return 0 if result.extra["grasp_found"] else NO_GRASP_EXIT


def fem_available() -> bool:
    """Whether the FEM reference can run (the optional extra ``fem``: scikit-fem)."""
    import importlib.util

    return importlib.util.find_spec("skfem") is not None


def verify_outputs(out: str | Path, result_name: str | None, top: int) -> dict:
    """Run the FEM verification of a written run and print its table."""
    from .verify import print_report, verify_run

    if not fem_available():
        raise ValueError("the FEM verification needs scikit-fem: pip install -e '.[fem]'")

    report, paths = verify_run(out, top, result=result_name)
    print_report(report, paths)
    return report


def _verify_command(args: argparse.Namespace) -> int:
    from .verify import find_result

    find_result(args.out_dir, args.result)  # a bad folder or file before any work
    report = verify_outputs(args.out_dir, args.result, args.top)
    return 0 if report["summary"]["all_fem_converged"] else 1


def add_verify_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``verify`` command to the ``psm-grasp`` sub-parsers."""
    p = subparsers.add_parser(
        "verify", help="re-score a run's best designs with the FEM",
        description="Re-score the K best distinct designs of an optimization run (its "
                    "*_result.json in OUT_DIR) with the model the run used and with the "
                    "finite-element reference (same metrics and reward), and write verify.json "
                    "and verify.png (both rewards and rankings) to OUT_DIR. Each FEM grasp "
                    "takes 0.3-2 s and is cached (out/cache/fem).")
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder of the run (psm-grasp optimize "
                   "--out, or the demo's out)")
    p.add_argument("--top", type=int, default=DEFAULT_TOP,
                   help=f"designs to verify, in [1, {MAX_TOP}] (default %(default)s)")
    p.add_argument("--result", default=None,
                   help="the result file in OUT_DIR when it holds several")
    p.set_defaults(func=_verify_command)
    return p


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
    p.add_argument("--out", default="out",
                   help="output folder, created if its parent exists (default %(default)s)")
    p.add_argument("--dask", metavar="ADDRESS|local",
                   help="evaluate on a Dask cluster: a scheduler address, or 'local' to start "
                        "a LocalCluster of --workers workers. Pays only with more cores than "
                        "this machine has (a remote cluster) and populations of hundreds of "
                        "designs (GA, random search): each task carries at least 64 designs")
    p.add_argument("--workers", type=int,
                   help="parallel workers: local processes without --dask, LocalCluster "
                        "workers with --dask local (default: in-process, batched, already on "
                        "every core; on one machine workers do not pay: 2 processes measured "
                        "4200-4700 designs/s against 4400-4900 in process on 2 cores, and "
                        "far less for CMA-ES's 9-design populations)")
    p.add_argument("--strain-limit", type=float, default=DEFAULT_STRAIN_LIMIT,
                   help="admissible strain of the object, in (0, 1] (default %(default)s)")
    p.add_argument("--element", default=None, choices=ELEMENTS,
                   help="element of the disk model (default nhquad: the default model, within "
                   "2 %% RMS of the FEM; spring: the paper's fan, ~5x cheaper, 30-40 %% off)")
    p.add_argument("--triangles", type=int, default=None,
                   help=f"contour points N (default 40 for nhquad, 20 for the fan), in [4, "
                   f"{MAX_TRIANGLES}] for the fan, [4, {MAX_TRIANGLES_FAMILY}] otherwise")
    p.add_argument("--rings", type=int, default=None,
                   help="rings M of the disk mesh (default 2 for nhquad, 1 otherwise)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--verify-top", type=int, default=None, metavar="K",
                   help=f"then re-score the K best distinct designs with the FEM (as psm-grasp "
                   f"verify; K in [1, {MAX_TOP}])")
    p.set_defaults(func=_optimize_command)
    return p


def run_demo(out_dir: Path) -> int:
    """CMA-ES design of the gripper for the paper's r = 0.07 m disk (budget 2000, seed 0).

    Writes ``demo_result.json``, ``demo_convergence.png`` and ``demo_best_grasp.png`` to
    ``out_dir``, verifies its 3 best distinct designs with the FEM (``verify.json``,
    ``verify.png``) and prints a short summary. Takes well under 2 minutes on 2 cores once the
    kernels are compiled.
    """
    t0 = time.perf_counter()
    print(f"CMA-ES gripper design for the {DEMO_SCENE} disk: budget {DEMO_BUDGET} "
          f"evaluations, strain limit {DEFAULT_STRAIN_LIMIT}")
    run_optimize("cmaes", scene=DEMO_SCENE, budget=DEMO_BUDGET, seed=0, out=out_dir,
                 prefix="demo")
    if fem_available():
        verify_outputs(out_dir, "demo_result.json", DEMO_VERIFY_TOP)
    else:
        print("  (FEM verification skipped: install the 'fem' extra for it)")
    print(f"demo done in {time.perf_counter() - t0:.1f} s")
    return 0
