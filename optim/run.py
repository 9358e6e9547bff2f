"""Run one optimization and write its files: what ``psm-grasp optimize``, ``verify`` and
``demo`` do (the command line itself is :mod:`cli`).

:func:`run_optimize` runs one method on one object and writes, to its output folder:

- ``{method}_seed{S}_result.json``: the :class:`~optim.result.OptimResult` (a method
  ``ng:NAME`` is written ``ng-NAME``: :func:`~optim.optimize.method_stem`);
- ``{method}_seed{S}_convergence.png``: best reward so far against evaluations;
- ``{method}_seed{S}_best_grasp.png``: the best design's grasp, re-solved and drawn;
- ``{method}_seed{S}_design.json``, ``..._design.csv`` and ``..._drawing.png``: the best design
  as a builder needs it, in millimetres with its spring and torque in SI units
  (:mod:`optim.build_sheet`);
- ``{method}_seed{S}_pareto.png`` (NSGA-II): the front with a few of its designs drawn.

The object is a scene preset's disk or a designer's own (:class:`envs.object_file.ObjectSpec`,
read from a TOML file); the run's optimum is reported by a finer member of the model family
(:mod:`optim.finish`) unless asked otherwise.
"""

from __future__ import annotations

import json
import math
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from envs.design_space import JAW_KINDS
from envs.object_file import ObjectSpec
from envs.scenarios import ROBUST_MEASURES, Scenarios
from envs.scene import PRESETS, Scene

from .optimize import check_options, get_optimizer, method_stem
from .problem import (
    DEFAULT_STRAIN_LIMIT,
    DEFAULT_TIME_LIMIT_S,
    MAX_BUDGET,
    DesignProblem,
    check_budget,
    check_friction,
    check_payload_factor,
    check_seed,
    check_strain_limit,
    check_time_limit,
    default_budget,
    paper_design,
    paper_design_for,
)
from .result import NoGraspWarning, OptimResult, grasp_found, no_grasp_reason
from .verdict import NO_GRASP_EXIT, UNDECIDED_EXIT, search_verdict

__all__ = ["run_optimize", "run_demo", "paper_reference", "write_outputs", "grasp_found",
           "no_grasp_reason", "fem_available", "verify_outputs", "problem_kwargs",
           "check_observable", "jaw_settings", "check_policy_jaw", "NO_GRASP_EXIT",
           "UNDECIDED_EXIT", "DEMO_SCENE", "object_problem"]

# the demo's placement tolerance, +- both ways [m] (3 % of the disk's radius)
DEMO_TOLERANCE_M = 0.002
# the demo's manufacturing tolerances: a workshop's +-0.1 mm and +-0.5 degree, a torsion
# spring's +-10 %, an actuator's torque +-5 % (envs.tolerances)
DEMO_TOLERANCES = {"length_mm": 0.1, "angle_deg": 0.5, "spring_percent": 10.0,
                   "torque_percent": 5.0}
DEMO_BUDGET = 2000
DEMO_VERIFY_TOP = 3
DEMO_SCENE = "paper-r070"
REFERENCE_TORQUES_NM = (0.05, 0.1, 0.2, 0.3, 0.5)


def paper_reference(problem: DesignProblem, scene: str | None = DEMO_SCENE,
                    torques_nm: tuple[float, ...] = REFERENCE_TORQUES_NM) -> tuple[float, float]:
    """Best reward of the paper's gripper over a few torques, and that torque [N·m].

    With a scene preset: the scene's own gripper; without (a designer's own object): the
    paper's gripper on its r = 0.07 m disk, scaled to the object like every relative design
    (lengths in radii, torque in ``s E t r^2``). The torques are those of the paper-r070 disk
    scaled by the disk's torque unit (the same squeeze for every object: unchanged on
    paper-r070, 0.4 to 4 mN·m on the forceps' 2 mm beads). Not counted in the problem's
    evaluations.
    """
    paper = Scene.preset(DEMO_SCENE).disk
    ratio = problem.disk.torque_unit_nm / paper.torque_unit_nm
    if scene is not None:
        designs = np.array([paper_design(scene, t * ratio) for t in torques_nm])
    else:
        designs = paper_design_for(problem.disk, torques_nm)
    reward = problem.evaluate_physical(designs)["reward"]
    i = int(np.argmax(reward))
    return float(reward[i]), float(torques_nm[i] * ratio)


def _progress_bar(total: int | None, desc: str, enabled: bool):
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit="eval", disable=not enabled, leave=False)

    def hook(n_new: int, best: float) -> None:
        bar.update(n_new)
        if math.isfinite(best):
            bar.set_postfix(best=f"{best:.4f}", refresh=False)

    return bar, hook


def write_outputs(result: OptimResult, out_dir: Path, prefix: str,
                  problem: DesignProblem | None = None,
                  reference: float | None = None, parts=None) -> dict[str, Path]:
    """Write the result JSON, the convergence chart, the best grasp, the build sheet with its
    parts (``parts``: :class:`optim.parts.options.PartOptions`, default the defaults; and the
    Pareto chart)."""
    from .build_sheet import write_build_sheet
    from .charts import best_grasp_figure, convergence_figure, pareto_figure, scenario_figure

    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {"result": result.to_json(out_dir / f"{prefix}_result.json")}
    paths["convergence"] = out_dir / f"{prefix}_convergence.png"
    convergence_figure([result], paths["convergence"], reference=reference,
                       title=f"{result.method} on {result.object.get('name') or 'object'}, "
                             f"strain limit {result.object['strain_limit']:g}, friction "
                             f"{result.object.get('friction_coefficient', float('nan')):g}")
    if result.best_design:
        paths["best_grasp"] = out_dir / f"{prefix}_best_grasp.png"
        best_grasp_figure(result, paths["best_grasp"])
        paths.update(write_build_sheet(result.best_design, result.object, out_dir, prefix,
                                       result.best_metrics, result.extra.get("scenario_rows"),
                                       parts=parts, extra=result.extra))
    if result.extra.get("scenario_rows"):
        paths["scenarios"] = out_dir / f"{prefix}_scenarios.png"
        scenario_figure(result, paths["scenarios"])
    if result.method == "nsga2":
        paths["pareto"] = out_dir / f"{prefix}_pareto.png"
        pareto_figure(result, paths["pareto"],
                      archive=None if problem is None else problem.archive())
    return paths


def _print_summary(result: OptimResult, reference: tuple[float, float] | None,
                   paths: dict[str, Path]) -> None:
    print(result.summary())
    d, m, extra = result.best_design, result.best_metrics, result.extra
    if "search_reward" in extra:
        rm = extra["reward_model"]
        print(f"  reported by the finer member {rm['element']} N = {rm['n_triangles']}, M = "
              f"{rm['n_rings']} (the search model said {extra['search_reward']:.4f}; the "
              f"finish took {extra['finish']['evaluations']} evaluations, "
              f"{extra['finish']['seconds']:.2f} s)")
    if d:
        print(f"  best design: l = {d['finger_length_m'] * 1e3:.4g} mm, "
              f"theta_a0 = {math.degrees(d['rest_angle_rad']):.2f} deg, "
              f"d3 = {d['joint_offset_m'] * 1e3:.4g} mm, w = {d['finger_width_m'] * 1e3:.4g} mm, "
              f"T_a = {d['torque_nm']:.4g} N·m, d1 = {d['distance_m'] * 1e3:.4g} mm, "
              f"k_f = {result.object['torsion_stiffness_nm_per_rad']:.4g} N·m/rad")
        from .charts import jaw_label

        for line in jaw_label(d).split("\n")[1:]:
            print(f"  {line}")
    if m.get("required_friction") is not None:
        payload = m.get("payload_n", 0.0)
        where = " (the governing scenario)" if m.get("governing_scenario") else ""
        print(f"  holding{where}: needs friction {float(m['required_friction']):.3g} (the "
              f"object's "
              f"{m.get('friction_coefficient', float('nan')):.3g}) with a payload of "
              f"{payload:.3g} N and a grip of {m.get('grip_force_n', float('nan')):.3g} N: "
              + ("holds and lifts it" if m.get("holds") else "would drop it without the pin")
              + f"; the pin carries {math.hypot(*m['pin_force_n']):.4g} N")
    rows = extra.get("scenario_rows")
    if rows:
        _print_scenarios(result, rows)
    if reference is not None:
        print(f"  the paper's gripper (best of 5 torques): {reference[0]:.4f} at "
              f"T_a = {reference[1]:.3g} N·m")
    if result.pareto_front:
        print(f"  Pareto front: {len(result.pareto_front)} designs")
    print(f"  executor: {result.executor}, {result.evaluations_per_s:.0f} evaluations/s")
    for name, path in paths.items():
        print(f"  {name:12s}: {path}")


def _print_scenarios(result: OptimResult, rows: list[dict[str, Any]]) -> None:
    """The scenario lines of the run's summary: the set, the nominal and governing rewards,
    the envelopes under their own names, and the verdict."""
    from .design_verdict import verdict_of

    m = result.best_metrics
    worst = min(rows, key=lambda r: r["reward"])
    verdict = verdict_of(m, rows)
    checked = ("every corner of the box" if result.extra.get("scenario_set") == "full"
               and len(rows) > 1 else "the scenario set")
    print(f"  scenarios: {len(rows)}, {checked} ({result.object.get('robust', 'worst')} "
          f"reward reported); nominal {rows[0]['reward']:.4f}, governing "
          f"{worst['reward']:.4f} at {worst['scenario']['label']}; holds within the strain "
          f"limit in {verdict.total - verdict.failing} of {verdict.total} (a displaced "
          "object is held where it was placed)")
    if "max_payload_n" in m:
        print(f"  over the scenarios: largest payload {m['max_payload_n']:.4g} N, largest "
              f"friction needed {_as_text(m['max_required_friction'])}, largest compression "
              f"{m['max_peak_compression']:.4g}, smallest contact "
              f"{m['min_contact_score']:.4g}, smallest strain margin "
              f"{m['min_strain_margin']:.4g}")
    if verdict.banner:
        print(f"  {verdict.banner}")


def _as_text(value: Any) -> str:
    """A metric of a result JSON (infinity written as text) as text."""
    return value if isinstance(value, str) else f"{float(value):.3g}"


def object_problem(path: str | Path, jaw: str | None = None) -> DesignProblem:
    """The :class:`~optim.problem.DesignProblem` of an object file as ``psm-grasp optimize
    --object PATH --jaw JAW`` judges designs (its scenarios, friction, payload and load set,
    the default model), without an executor: for scripts that score designs of a run."""
    from envs.object_file import load_object

    obj = load_object(path)
    target, settings = problem_kwargs(None, obj, None, None, None, None, jaw=jaw)
    return DesignProblem(target, name=obj.name, **settings)


def problem_kwargs(scene: str | None, obj: ObjectSpec | None, strain_limit, friction,
                    spring_rel, spring_nm, placement_tolerance_m=None,
                    robust: str | None = None, payload_factor=None, jaw: str | None = None,
                    jaw_per_finger: bool | None = None,
                    load_set: str | None = None, tolerances=None) -> tuple[Any, dict[str, Any]]:
    """The object (a disk, or a preset's scene) and the DesignProblem keyword arguments of a
    run, validated: explicit values first, then the object file's, then the defaults.

    The scenarios: the object file's ranges, with the placement tolerance given here (one
    number for both ways, or ``(along, across)`` [m]) or else the file's, and the
    manufacturing tolerances given here (:class:`envs.tolerances.Tolerances`) or else the
    file's ``[gripper.tolerances]``. The jaws (``jaw``,
    ``jaw_per_finger``, always in the keyword arguments): as given, else the object file's,
    else straight bars. The load set (how the object is picked, always in the keyword
    arguments): as given, else the object file's, else
    :data:`envs.model.loads.DEFAULT_LOAD_SET`."""
    from envs.model.defaults import DEFAULT_FRICTION_COEFFICIENT, DEFAULT_PAYLOAD_FACTOR
    from envs.scene import joint_spring_kwargs

    if obj is not None and scene is not None:
        raise ValueError("give the object once: a scene preset or an object (file), not both")
    if obj is not None and not isinstance(obj, ObjectSpec):
        raise ValueError(f"obj must be an ObjectSpec (envs.object_file.load_object), got "
                         f"{type(obj).__name__}")
    if obj is None and scene not in PRESETS:
        raise ValueError(f"unknown scene {scene!r}; allowed: {sorted(PRESETS)}")
    own = obj if obj is not None else None
    limit = strain_limit if strain_limit is not None else (
        own.strain_limit if own is not None and own.strain_limit is not None
        else DEFAULT_STRAIN_LIMIT)
    mu = friction if friction is not None else (
        own.friction_coefficient if own is not None and own.friction_coefficient is not None
        else DEFAULT_FRICTION_COEFFICIENT)
    factor = payload_factor if payload_factor is not None else (
        own.payload_factor if own is not None and own.payload_factor is not None
        else DEFAULT_PAYLOAD_FACTOR)
    kwargs: dict[str, Any] = {"strain_limit": check_strain_limit(limit),
                              "friction_coefficient": check_friction(mu),
                              "payload_factor": check_payload_factor(factor),
                              "load_set": load_set_of(own, load_set)}
    if spring_rel is not None or spring_nm is not None:
        kwargs.update(joint_spring_kwargs(spring_rel, spring_nm))
    kwargs.update(jaw_settings(own, jaw, jaw_per_finger))
    scenarios = scenarios_of(own, placement_tolerance_m, tolerances)
    if scenarios is not None:
        kwargs["scenarios"] = scenarios
    if robust is not None:
        if robust not in ROBUST_MEASURES:
            raise ValueError(f"robust must be one of {ROBUST_MEASURES}, got {robust!r}")
        kwargs["robust"] = robust
    return (obj.disk if obj is not None else scene), kwargs


def load_set_of(obj: ObjectSpec | None, load_set: str | None = None) -> str:
    """The load set a run checks (the payload's directions, :mod:`envs.model.loads`),
    validated: as given, else the object file's, else the default (``"any"``)."""
    from envs.model.loads import DEFAULT_LOAD_SET, load_set_code

    if load_set is None:
        load_set = (obj.load_set if obj is not None and obj.load_set is not None
                    else DEFAULT_LOAD_SET)
    load_set_code(load_set)
    return load_set


def jaw_settings(obj: ObjectSpec | None, jaw: str | None = None,
                 jaw_per_finger: bool | None = None) -> dict[str, Any]:
    """The jaws a run designs, ``{"jaw": ..., "jaw_per_finger": ...}``, validated: as given,
    else the object file's, else ``"straight"`` and ``False``
    (:class:`~envs.evaluate.DesignBounds`)."""
    from envs.design_space import DesignBounds

    if jaw is None:
        jaw = obj.jaw if obj is not None and obj.jaw is not None else "straight"
    if jaw_per_finger is None:
        # (a file's per-finger flag goes with its groove, not with straight bars asked for)
        jaw_per_finger = (obj.jaw_per_finger if obj is not None and jaw != "straight"
                          and obj.jaw_per_finger is not None else False)
    if not isinstance(jaw, str) or jaw not in JAW_KINDS:
        raise ValueError(f"jaw must be one of {JAW_KINDS}, got {jaw!r}")
    if not isinstance(jaw_per_finger, bool):
        raise ValueError(f"jaw_per_finger must be True or False, got {jaw_per_finger!r}")
    # its rules (a jaw per finger needs a groove)
    bounds = DesignBounds(jaw=jaw, jaw_per_finger=jaw_per_finger)
    return {"jaw": bounds.jaw, "jaw_per_finger": bounds.jaw_per_finger}


def check_policy_jaw(method: str, settings: dict[str, Any]) -> None:
    """The shipped design policies design straight jaws (six actions) or any shaped jaws, both
    fingers alike (:data:`optim.rl.SHIPPED_JAWS`): refuse the policy for other jaws, before
    any work."""
    from .rl import SHIPPED_JAWS

    jaw = settings.get("jaw", "straight")
    if method == "policy" and (jaw not in SHIPPED_JAWS or settings.get("jaw_per_finger")):
        raise ValueError(
            f"the design policies design jaws {' or '.join(sorted(SHIPPED_JAWS))} alike on "
            f"both fingers, not jaw {jaw!r}"
            + (" per finger" if settings.get("jaw_per_finger") else "")
            + ": use another method for them (psm-grasp optimize --jaw ...)")


def scenarios_of(obj: ObjectSpec | None, placement_tolerance_m=None,
                 tolerances=None) -> Scenarios | None:
    """The scenarios of a run: the object file's ranges, placement tolerance and
    manufacturing tolerances, the placement tolerance replaced by ``placement_tolerance_m``
    and the manufacturing ones by ``tolerances`` when given; ``None`` when nothing varies."""
    base = None if obj is None else obj.scenarios
    if placement_tolerance_m is not None:
        base = Scenarios.of({} if base is None else base.ranges, placement_tolerance_m,
                            None if base is None else base.tolerances)
    if tolerances is not None:
        base = (Scenarios() if base is None else base).with_tolerances(tolerances)
    return None if base is None or base.is_trivial else base


def check_joints_apart(method: str, joints_apart: Any) -> None:
    """``joints_apart`` is True or False, and the design policy, trained in the default design
    space, cannot keep the joints apart."""
    if not isinstance(joints_apart, bool):
        raise ValueError(f"joints_apart must be True or False, got {joints_apart!r}")
    if joints_apart and method == "policy":
        raise ValueError("the design policy designs in the default design space and cannot keep "
                         "the joints apart: use another method with joints_apart (--joints-apart)")


def check_observable(target: Any, settings: dict[str, Any]) -> None:
    """The design policy answers objects it can observe only: say so before any work."""
    from envs.design_env import observe

    disk = Scene.preset(target).disk if isinstance(target, str) else target
    try:
        observe(disk, settings["strain_limit"], settings["friction_coefficient"])
    except ValueError as exc:
        raise ValueError(f"the design policy cannot design for this object: {exc} (the "
                         "object, --strain-limit or --friction; use another method)") from None


def run_optimize(
    method: str,
    *,
    scene: str | None = None,
    obj: ObjectSpec | None = None,
    budget: int | None = None,
    seed: int = 0,
    out: str | Path = "out",
    dask: str | None = None,
    workers: int | None = None,
    strain_limit: float | None = None,
    friction_coefficient: float | None = None,
    torsion_stiffness_rel: float | None = None,
    torsion_stiffness_nm_per_rad: float | None = None,
    n_triangles: int | None = None,
    progress: bool = True,
    payload_factor: float | None = None,
    n_rings: int | None = None,
    element: str | None = None,
    prefix: str | None = None,
    verbose: bool = True,
    finish: bool = True,
    placement_tolerance_m: float | tuple[float, float] | None = None,
    robust: str | None = None,
    joints_apart: bool = False,
    jaw: str | None = None,
    jaw_per_finger: bool | None = None,
    load_set: str | None = None,
    tolerances=None,
    parts=None,
    time_s: float | None = None,
    **options: Any,
) -> tuple[OptimResult, dict[str, Path]]:
    """Run one method on an object and write its files (what ``optimize`` does).

    The object is a scene preset's disk (``scene``; its gripper keeps its own joint spring)
    or a designer's own (``obj``, e.g. :func:`envs.object_file.load_object`; the spring is
    relative to it unless given); neither: :data:`DEMO_SCENE`. The strain limit, the
    friction coefficient and the payload factor are the arguments', else the object file's,
    else the defaults. With
    ``finish`` (default) the run's best distinct designs are re-scored by a finer member
    (:func:`optim.finish.finish_result`): the reported optimum is the FEM's within a few
    percent; the result JSON says which model reported it (``extra["reward_model"]``).

    Scenarios (:mod:`envs.scenarios`): the object file's ranges and placement tolerance, or
    ``placement_tolerance_m`` (one number for both ways, or ``(along, across)`` [m]); the
    reward is then the ``robust`` measure over them (default the worst scenario's), and the
    result JSON has a row per scenario for the reported design (``extra["scenario_rows"]``).

    ``joints_apart``: every design keeps its joints at least half a finger width from the axis
    (``d_3 >= w / 2``), for fingers that cannot be stacked at the joints
    (:class:`~envs.evaluate.DesignBounds`); the result JSON records it (``extra["joints_apart"]``).

    ``jaw`` (``"straight"``, ``"cradle"``, ``"vee"`` or ``"any"``) and ``jaw_per_finger``: the
    jaws designed (:class:`~envs.evaluate.DesignBounds`); ``None``: the object file's, else
    straight bars. The result's designs then carry the jaw fields by name
    (:data:`envs.model.jaw.JAW_FIELDS`, ``left_...`` per finger) and its extra records both.
    The design policy designs straight jaws, or any shaped jaws alike on both fingers.

    ``load_set``: how the object is picked, the payload's directions the grasp must hold it in
    (``"top-down"``, ``"side"`` or ``"any"``, :mod:`envs.model.loads`); ``None``: the object
    file's, else ``"any"``. The result JSON records it (``object["load_set"]``).

    ``tolerances`` (:class:`envs.tolerances.Tolerances`): the manufacturing tolerances the
    design must survive, scenario dimensions beside the object's (default: the object file's
    ``[gripper.tolerances]``, else none). ``parts`` (:class:`optim.parts.options.PartOptions`):
    the manufacturing resolution the reported design is rounded to (the joint spring before
    the search, the designs before the finish scores them: the sheet states the rounded design,
    the one scored) and the parts' options (pin diameter); default the defaults.

    ``budget``: evaluations (designs judged under every scenario); ``None`` (default): with
    ``time_s`` as many as the time allows, else :func:`optim.problem.default_budget` of the
    problem's scenario count (3,600 designs with 9 scenarios), searched for at most
    :data:`optim.problem.DEFAULT_TIME_LIMIT_S` seconds. ``time_s``: the search's wall-time
    limit [s] beside the budget (whichever ends first; the finish, the charts and the files
    come after it).

    Every option is validated before any cluster is started or any evaluation is spent, the
    output folder included. ``result.extra["grasp_found"]`` tells whether the best design is a
    grasp that holds the object (valid, converged, both fingers touching, the friction it
    needs within the object's); when it is not, a warning goes to stderr (and ``psm-grasp
    optimize`` exits with :data:`NO_GRASP_EXIT` when the run's independent starts agree that
    nothing holds, :data:`UNDECIDED_EXIT` when they cannot say: ``extra["verdict"]``,
    :func:`optim.verdict.search_verdict`).

    Raises
    ------
    ValueError
        Unknown method, scene or method option, both a scene and an object, budget <= 0, bad
        seed, strain limit outside (0, 1], friction outside (0, 10], a bad joint spring, a
        model member outside the family (:func:`envs.model.family.resolve_model`; default: the
        default model, ``element="spring"`` the paper's fan), bad worker count, a Dask address
        that is not a scheduler answering within seconds, an output folder that cannot be
        written.
    """
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.model.family import resolve_model
    from envs.validation import check_output_dir

    from .executors import check_executor_options, make_executor

    # every option before any work (no cluster started, no evaluation spent)
    driver = get_optimizer(method)
    check_options(method, options)
    if obj is None and scene is None:
        scene = DEMO_SCENE
    target, settings = problem_kwargs(scene, obj, strain_limit, friction_coefficient,
                                      torsion_stiffness_rel, torsion_stiffness_nm_per_rad,
                                      placement_tolerance_m, robust,
                                      payload_factor=payload_factor, jaw=jaw,
                                      jaw_per_finger=jaw_per_finger, load_set=load_set,
                                      tolerances=tolerances)
    parts = check_parts(parts)
    budget = None if budget is None else check_budget(budget)
    seed = check_seed(seed)
    time_s = None if time_s is None else check_time_limit(time_s, "time_s")
    check_joints_apart(method, joints_apart)
    check_policy_jaw(method, settings)
    if method == "policy":
        check_observable(target, settings)
    model = resolve_model(n_triangles, n_rings, element or DEFAULT_ELEMENT)
    check_executor_options(dask, workers)
    out_dir = check_output_dir("out", out)
    prefix = prefix or f"{method_stem(method)}_seed{seed}"
    with make_executor(dask, workers) as executor:
        common = {"executor": executor, "joints_apart": joints_apart, **settings,
                  **model.kwargs()}
        if obj is None:
            problem = DesignProblem.from_scene(target, **common)
        else:
            problem = DesignProblem(target, name=obj.name, **common)
        _apply_resolution(problem, parts)
        problem.time_limit_s = time_s
        if budget is None and time_s is not None:  # a time alone runs until it is up
            budget = MAX_BUDGET
        elif budget is None:  # the default: its budget, within the default time
            budget = default_budget(problem.scenario_count)
            problem.time_limit_s, problem.plan_by_time = DEFAULT_TIME_LIMIT_S, False
        bar, hook = _progress_bar(None if budget == MAX_BUDGET else budget, method, progress)
        problem.progress = hook
        try:
            with warnings.catch_warnings():
                # said once below, with the files written
                warnings.simplefilter("ignore", NoGraspWarning)
                result = driver(problem, budget=budget, seed=seed, **options)
        finally:
            bar.close()
        if obj is not None:
            result = replace(result, object={**result.object, "file": obj.info()["file"]})
        search_s = result.wall_time_s
        result = _finish(problem, result, finish, parts)
        result = replace(result, extra={**result.extra,
                                        "verdict": search_verdict(result, search_s)})
        reference = paper_reference(problem, scene)
        paths = write_outputs(result, out_dir, prefix, problem,
                              None if reference is None else reference[0], parts)
    if verbose:
        _print_summary(result, reference, paths)
    if not result.extra["grasp_found"]:
        print(f"psm-grasp: warning: {method}: {result.extra['verdict']['message']} (reward "
              f"{result.best_reward:.4f}); the files in {str(out_dir)!r} describe that design",
              file=sys.stderr)
    return result, paths


def check_parts(parts):
    """The parts' options of a run (:class:`optim.parts.options.PartOptions`; ``None``: the
    defaults)."""
    from .parts.options import PartOptions

    if parts is None:
        return PartOptions()
    if not isinstance(parts, PartOptions):
        raise ValueError(f"parts must be None or an optim.parts.options.PartOptions, got "
                         f"{type(parts).__name__}")
    return parts


def _apply_resolution(problem: DesignProblem, parts) -> None:
    """The joint spring rounded to the resolution before the search (the spring the sheet
    states is the one every design is scored with)."""
    from .parts.resolution import apply_resolution

    if parts.resolution is not None:
        apply_resolution(problem, parts.resolution)


def _finish(problem: DesignProblem, result: OptimResult, finish: bool, parts) -> OptimResult:
    """The reported design: the run's best distinct designs rounded to the resolution and
    re-scored, by the finer member with ``finish``, else by the search model
    (:func:`optim.finish.finish_result`)."""
    from .finish import finish_result

    if not finish and parts.resolution is None:
        return result
    return finish_result(problem, result, None if finish else problem.model.kwargs(),
                         resolution=parts.resolution)


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


def front_picks(front: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The ends and the knee of a Pareto front (contact score up, peak compression down),
    labelled: the most contact, the least compression and the knee, the point farthest from
    the line through the ends in coordinates normalised by the front's ranges."""
    if not front:
        return []
    from .result import front_point

    c, q = (np.array(v) for v in zip(*map(front_point, front), strict=True))
    ends = {"front: most contact": int(np.argmax(c)), "front: least compression": int(np.argmin(q))}
    span_c, span_q = max(np.ptp(c), 1e-12), max(np.ptp(q), 1e-12)
    a, b = ends["front: most contact"], ends["front: least compression"]
    pa = np.array([c[a] / span_c, q[a] / span_q])
    pb = np.array([c[b] / span_c, q[b] / span_q])
    pts = np.column_stack([c / span_c, q / span_q])
    line = pb - pa
    norm = float(np.hypot(*line)) or 1.0
    dist = np.abs(line[0] * (pts[:, 1] - pa[1]) - line[1] * (pts[:, 0] - pa[0])) / norm
    picks = {**ends, "front: knee": int(np.argmax(dist))}
    out, seen = [], set()
    for label, i in picks.items():
        if i not in seen:
            seen.add(i)
            out.append({"design": front[i]["design"], "reward": front[i]["reward"],
                        "label": label})
    return out


def run_demo(out_dir: Path) -> int:
    """The main job: gripper designs for the paper's r = 0.07 m disk, checked by the FEM.

    CMA-ES (budget 2000, seed 0; its optimum reported by the finer member) writes
    ``demo_result.json``, ``demo_convergence.png``, ``demo_best_grasp.png`` and the build
    sheet (``demo_design.json``, ``.csv``, ``demo_drawing.png``); NSGA-II (budget 2000) writes
    ``demo_front_result.json`` and its front ``demo_front_pareto.png``. Then four distinct
    designs, CMA-ES's optimum and the ends and knee of the front, are re-scored by the FEM
    (``verify.json``, ``verify.png``): designs that differ, so that the FEM's ranking can
    disagree with the model's. Every design is judged over the placements within
    :data:`DEMO_TOLERANCE_M` and the manufacturing tolerances :data:`DEMO_TOLERANCES`. Takes
    seconds on 2 cores once the kernels are compiled. Returns 0, else the exit code of CMA-ES's
    verdict when its optimum does not hold in every scenario
    (:func:`optim.verdict.verdict_exit_code`: :data:`UNDECIDED_EXIT` for its one start), else
    :func:`optim.verify.verify_exit_code`'s (:data:`optim.verify.NOT_CONFIRMED_EXIT` when the FEM
    does not confirm it).
    """
    from envs.tolerances import parse_tolerances

    from .verify import print_report, verify_exit_code, verify_figure, verify_result

    t0 = time.perf_counter()
    code = 0
    tolerances = parse_tolerances(DEMO_TOLERANCES, "DEMO_TOLERANCES")
    scenarios = Scenarios.of(placement_tolerance_m=DEMO_TOLERANCE_M, tolerances=tolerances)
    print(f"Gripper design for the {DEMO_SCENE} disk: CMA-ES and NSGA-II, {DEMO_BUDGET} "
          f"evaluations each, strain limit {DEFAULT_STRAIN_LIMIT}, friction 0.5, placed within "
          f"+-{DEMO_TOLERANCE_M * 1e3:g} mm both ways, built within +-"
          f"{DEMO_TOLERANCES['length_mm']:g} mm, +-{DEMO_TOLERANCES['angle_deg']:g} deg, "
          f"spring +-{DEMO_TOLERANCES['spring_percent']:g} %, torque "
          f"+-{DEMO_TOLERANCES['torque_percent']:g} % (each design judged by its worst of "
          f"{len(scenarios.scenarios())} scenarios, the reported one on all "
          f"{len(scenarios.scenarios(full=True))})")
    best, _ = run_optimize("cmaes", scene=DEMO_SCENE, budget=DEMO_BUDGET, seed=0, out=out_dir,
                           prefix="demo", placement_tolerance_m=DEMO_TOLERANCE_M,
                           tolerances=tolerances)
    front, _ = run_optimize("nsga2", scene=DEMO_SCENE, budget=DEMO_BUDGET, seed=0,
                            out=out_dir, prefix="demo_front", verbose=False,
                            placement_tolerance_m=DEMO_TOLERANCE_M, tolerances=tolerances)
    print(f"  NSGA-II front: {len(front.pareto_front)} designs holding the disk within its "
          f"strain limit; its ends and knee are verified with CMA-ES's optimum")
    if not fem_available():
        print("  (FEM verification skipped: install the 'fem' extra for it)")
    else:
        picks = [{"design": best.best_design, "reward": best.best_reward,
                  "label": "CMA-ES optimum"}, *front_picks(list(front.pareto_front))]
        report = verify_result(replace(best, top_designs=tuple(picks)), top=len(picks))
        report["run"]["result_file"] = "demo_result.json, demo_front_result.json"
        paths = {"verify": out_dir / "verify.json", "chart": out_dir / "verify.png"}
        paths["verify"].write_text(json.dumps(report, indent=1) + "\n")
        verify_figure(report, paths["chart"])
        print_report(report, paths)
        code = verify_exit_code(report)
    if not best.extra["grasp_found"]:
        from .verdict import verdict_exit_code

        code = verdict_exit_code(best.extra["verdict"])
    print(f"demo done in {time.perf_counter() - t0:.1f} s")
    return code
