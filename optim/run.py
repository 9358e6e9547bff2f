"""Run one optimization and write its files: what ``psm-grasp optimize``, ``verify`` and
``demo`` do (the command line itself is :mod:`cli`).

:func:`run_optimize` runs one method on one object and writes, to its output folder:

- ``{method}_seed{S}_result.json``: the :class:`~optim.result.OptimResult`;
- ``{method}_seed{S}_convergence.png``: best reward so far against evaluations;
- ``{method}_seed{S}_best_grasp.png``: the best design's grasp, re-solved and drawn;
- ``{method}_seed{S}_pareto.png`` (NSGA-II): the front with a few of its designs drawn.
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from envs.scene import PRESETS, Scene

from .optimize import check_options, get_optimizer
from .problem import (
    DEFAULT_STRAIN_LIMIT,
    DesignProblem,
    check_budget,
    check_seed,
    check_strain_limit,
    paper_design,
)
from .result import NoGraspWarning, OptimResult, grasp_found, no_grasp_reason

__all__ = ["run_optimize", "run_demo", "paper_reference", "write_outputs", "grasp_found",
           "no_grasp_reason", "fem_available", "verify_outputs", "NO_GRASP_EXIT", "DEMO_SCENE"]

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
        Unknown method, scene or method option, budget <= 0, bad seed, strain limit outside
        (0, 1], a model member outside the family (:func:`envs.model.family.resolve_model`;
        default: the default model, ``element="spring"`` the paper's fan), bad worker count,
        a Dask address that is not a scheduler answering within seconds, an output folder
        that cannot be written.
    """
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.model.family import resolve_model
    from envs.validation import check_output_dir

    from .executors import check_executor_options, make_executor

    # every option before any work (no cluster started, no evaluation spent)
    driver = get_optimizer(method)
    check_options(method, options)
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
