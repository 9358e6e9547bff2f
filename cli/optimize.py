"""``psm-grasp optimize``, ``verify`` and ``demo``: the optimization commands.

The work itself is the library's (:mod:`optim.run`: :func:`~optim.run.run_optimize`,
:func:`~optim.run.verify_outputs`, :func:`~optim.run.run_demo`); here the options are parsed
and checked, by the names the user typed, before any of it starts.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from optim import run

from .options import add_load_set_option, cli_option, object_option

__all__ = ["add_optimize_parser", "add_verify_parser", "add_demo_parser"]


def _optimize_command(args: argparse.Namespace) -> int:
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.model.family import resolve_model
    from envs.scene import joint_spring
    from envs.solver.warmup import announce_compile
    from envs.validation import check_integer, check_output_dir
    from optim.executors import check_executor_options
    from optim.problem import (
        check_budget,
        check_friction,
        check_payload_factor,
        check_seed,
        check_strain_limit,
        check_time_limit,
    )
    from optim.verdict import search_verdict, verdict_exit_code
    from optim.verify import MAX_TOP, verify_exit_code

    # the options a user typed, named as typed (run_optimize checks them all again)
    if args.object is not None and args.scene is not None:
        raise ValueError("--object and --scene exclude each other: the object is a preset's "
                         "disk or your own")
    obj = None if args.object is None else object_option(args.object)
    cli_option("--method", method_name, args.method)
    cli_option("--triangles/--rings/--element", resolve_model, args.triangles, args.rings,
               args.element or DEFAULT_ELEMENT)
    if args.budget is not None:
        cli_option("--budget", check_budget, args.budget)
    cli_option("--seed", check_seed, args.seed)
    if args.time is not None:
        cli_option("--time", check_time_limit, args.time)
    if args.strain_limit is not None:
        cli_option("--strain-limit", check_strain_limit, args.strain_limit)
    if args.friction is not None:
        cli_option("--friction", check_friction, args.friction)
    if args.payload_factor is not None:
        cli_option("--payload-factor", check_payload_factor, args.payload_factor)
    cli_option("--joint-spring/--joint-spring-nm-per-rad", joint_spring, args.joint_spring,
               args.joint_spring_nm_per_rad)
    tolerances = (None if args.tolerances is None
                  else cli_option("--tolerances", tolerances_option, args.tolerances))
    parts = cli_option("--resolution/--pin-diameter", parts_option, args.resolution,
                       args.pin_diameter)
    cli_option("--workers", check_executor_options, None, args.workers)
    cli_option("--dask", check_executor_options, args.dask, None)
    check_output_dir("--out", args.out)
    if args.joints_apart and args.method == "policy":
        raise ValueError("--joints-apart: the design policy designs in the default design "
                         "space and cannot keep the joints apart; use another --method")
    jaws = cli_option("--jaw/--jaw-per-finger", run.jaw_settings, obj, args.jaw,
                      args.jaw_per_finger)
    cli_option("--jaw", run.check_policy_jaw, args.method, jaws)
    cli_option("--load-set", run.load_set_of, obj, args.load_set)
    if args.method == "policy":  # an object the policy cannot observe, before any work
        target, kwargs = run.problem_kwargs(args.scene or (None if obj else run.DEMO_SCENE),
                                            obj, args.strain_limit, args.friction,
                                            args.joint_spring, args.joint_spring_nm_per_rad,
                                            args.placement_tolerance, args.robust)
        run.check_observable(target, kwargs)
    if args.verify_top is not None:
        check_integer("--verify-top", args.verify_top, 1, MAX_TOP)
        if not run.fem_available():
            raise ValueError("--verify-top needs scikit-fem: pip install -e '.[fem]'")
    announce_compile()
    result, _ = run.run_optimize(args.method, scene=args.scene, obj=obj, budget=args.budget,
                                 seed=args.seed, out=args.out, dask=args.dask,
                                 workers=args.workers, strain_limit=args.strain_limit,
                                 friction_coefficient=args.friction,
                                 payload_factor=args.payload_factor,
                                 torsion_stiffness_rel=args.joint_spring,
                                 torsion_stiffness_nm_per_rad=args.joint_spring_nm_per_rad,
                                 n_triangles=args.triangles, n_rings=args.rings,
                                 element=args.element, progress=not args.no_progress,
                                 finish=not args.no_finish,
                                 placement_tolerance_m=args.placement_tolerance,
                                 robust=args.robust, joints_apart=args.joints_apart,
                                 jaw=args.jaw, jaw_per_finger=args.jaw_per_finger,
                                 load_set=args.load_set,
                                 tolerances=tolerances, parts=parts, time_s=args.time)
    report = None
    if args.verify_top is not None:
        from optim.optimize import method_stem

        report = run.verify_outputs(args.out,
                                    f"{method_stem(args.method)}_seed{args.seed}_result.json",
                                    args.verify_top)
    # a run that found no grasp is not a success, whatever files it wrote; nor one whose
    # optimum the FEM does not confirm
    if not result.extra["grasp_found"]:
        return verdict_exit_code(result.extra.get("verdict") or search_verdict(result))
    return 0 if report is None else verify_exit_code(report)


def method_name(text: str) -> str:
    """``--method``: a method of :data:`optim.optimize.METHODS`, or ``PREFIX:NAME`` of another
    library's family; a missing optional dependency is refused as bad input (with its install
    hint), not as a crash."""
    from optim.optimize import get_optimizer

    try:
        get_optimizer(text)
    except ImportError as exc:
        raise ValueError(str(exc)) from None
    return text


# --tolerances' short keys and the object file's keys they stand for (envs.tolerances)
TOLERANCE_OPTION_KEYS = {"length": "length_mm", "angle": "angle_deg", "spring": "spring_percent",
                         "torque": "torque_percent"}


def tolerances_option(text: str):
    """``--tolerances length=MM,angle=DEG,spring=PCT,torque=PCT`` (any of them; the object
    file's key names are accepted too): :class:`envs.tolerances.Tolerances`."""
    from envs.tolerances import parse_tolerances

    values = {}
    for item in str(text).split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep:
            raise ValueError(f"must be KEY=VALUE pairs (length=MM, angle=DEG, spring=PCT, "
                             f"torque=PCT), got {item!r}")
        try:
            values[TOLERANCE_OPTION_KEYS.get(key, key)] = float(value)
        except ValueError:
            raise ValueError(f"{key} must be a number, got {value!r}") from None
    return parse_tolerances(values, "tolerances")


def parts_option(resolution: str | None, pin_diameter_mm: float | None):
    """``--resolution MM[,DEG[,DIGITS]]`` (or ``none``: the design as found, unrounded) and
    ``--pin-diameter MM``: :class:`optim.parts.options.PartOptions`."""
    from optim.parts.options import PartOptions
    from optim.parts.resolution import DEFAULT_RESOLUTION, parse_resolution

    res = (DEFAULT_RESOLUTION if resolution is None else None if resolution.strip() == "none"
           else parse_resolution(resolution))
    pin = None if pin_diameter_mm is None else pin_diameter_mm * 1e-3
    return PartOptions(res, pin)


def placement_tolerance(text: str) -> float | tuple[float, float]:
    """``--placement-tolerance``: ``M`` or ``ALONG,ACROSS`` [m], each >= 0 and finite."""
    from envs.validation import check_range

    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be a number or two numbers ALONG,ACROSS [m], got {text!r}") from None
    if len(values) not in (1, 2):
        raise argparse.ArgumentTypeError(f"must be one or two numbers [m], got {text!r}")
    try:
        for v in values:
            check_range("--placement-tolerance", v, 0.0, 1.0)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return values[0] if len(values) == 1 else (values[0], values[1])


def _verify_command(args: argparse.Namespace) -> int:
    from envs.validation import check_integer, check_output_dir
    from optim.result import OptimResult
    from optim.verify import MAX_TOP, find_result, verify_exit_code

    # a bad folder or file, or a folder verify.json cannot be written to, before any work
    check_integer("--top", args.top, 1, MAX_TOP)
    path = find_result(args.out_dir, args.result)
    check_output_dir("OUT_DIR", args.out_dir)
    recorded = OptimResult.from_json(path)
    if args.object is not None:
        _check_same_object(args.object, recorded.object, path)
    if args.jaw is not None or args.jaw_per_finger is not None:
        _check_same_jaws(args.jaw, args.jaw_per_finger, recorded.extra, path)
    if args.load_set is not None:
        # (a run recorded before the load sets checked every direction)
        ran = recorded.object.get("load_set", "any")
        if ran != args.load_set:
            raise ValueError(f"--load-set: the run in {str(path)!r} checked the load set "
                             f"{ran!r}, not {args.load_set!r}")
    report = run.verify_outputs(args.out_dir, args.result, args.top)
    return verify_exit_code(report)


def _check_same_object(object_file: str, recorded: dict, result_path) -> None:
    """``verify --object FILE``: the run in OUT_DIR must be a run for that object."""

    spec = object_option(object_file)
    fields = ("radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
              "stiffness_scale")
    differ = [k for k in fields
              if not math.isclose(spec.info()[k], recorded.get(k, math.nan), rel_tol=1e-12)]
    if differ:
        raise ValueError(f"--object {object_file!r}: the run in {str(result_path)!r} was for "
                         f"another object ({differ[0]} {recorded.get(differ[0])!r}, the file's "
                         f"{spec.info()[differ[0]]!r})")
    for key in ("shape", "orientation_rad", "outline_coefficients"):  # an outline's
        if spec.info().get(key) != recorded.get(key):
            raise ValueError(f"--object {object_file!r}: the run in {str(result_path)!r} was "
                             f"for another object (its {key} differs from the file's)")


def _check_same_jaws(jaw: str | None, per_finger: bool | None, extra: dict,
                     result_path) -> None:
    """``verify --jaw KIND [--jaw-per-finger]``: the run in OUT_DIR must have designed those
    jaws (a run recorded before shaped jaws designed straight bars)."""
    ran = (extra.get("jaw", "straight"), bool(extra.get("jaw_per_finger", False)))
    asked = (ran[0] if jaw is None else jaw, ran[1] if per_finger is None else per_finger)
    if asked != ran:
        def words(kind, each):
            return f"jaw {kind!r}" + (" per finger" if each else "")

        raise ValueError(f"--jaw: the run in {str(result_path)!r} designed {words(*ran)}, not "
                         f"{words(*asked)}")


def add_jaw_options(p: argparse.ArgumentParser, verb: str, default: str) -> None:
    """``--jaw KIND`` and ``--jaw-per-finger`` of a command (``verb``: what they do there)."""
    from envs.design_space import JAW_KINDS

    p.add_argument("--jaw", default=None, choices=JAW_KINDS,
                   help=f"{verb} jaws: straight bars, a circular cradle, a V-groove, or any "
                   f"rounded V between them cut into the gripping faces (default: {default})")
    p.add_argument("--jaw-per-finger", action="store_const", const=True, default=None,
                   help=f"{verb} each finger's own groove (with --jaw cradle, vee or any)")


def _demo_command(args: argparse.Namespace) -> int:
    from envs.solver.warmup import announce_compile
    from envs.validation import check_output_dir

    out = check_output_dir("--out", args.out)
    out.mkdir(parents=True, exist_ok=True)
    announce_compile()
    return run.run_demo(out)


def add_demo_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``demo`` command to the ``psm-grasp`` sub-parsers."""
    demo = subparsers.add_parser("demo", help="run the main job and write charts to --out")
    demo.add_argument("--out", default="out")
    demo.set_defaults(func=_demo_command)
    return demo


def add_verify_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``verify`` command to the ``psm-grasp`` sub-parsers."""
    from optim.verify import DEFAULT_TOP, MAX_TOP

    p = subparsers.add_parser(
        "verify", help="re-score a run's best designs with the FEM",
        description="Re-score the K best distinct designs of an optimization run (its "
                    "*_result.json in OUT_DIR) with the model the run used and with the "
                    "finite-element reference (same metrics and reward), and write verify.json "
                    "and verify.png (both rewards and rankings) to OUT_DIR. Each FEM grasp "
                    "is cached in the user cache folder (~/.cache/psm-grasp/fem, or "
                    "$PSM_GRASP_CACHE/fem).")
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder of the run (psm-grasp optimize "
                   "--out, or the demo's out)")
    p.add_argument("--top", type=int, default=DEFAULT_TOP,
                   help=f"designs to verify, in [1, {MAX_TOP}] (default %(default)s)")
    p.add_argument("--result", default=None,
                   help="the result file in OUT_DIR when it holds several")
    p.add_argument("--object", metavar="FILE.toml", default=None,
                   help="check that the run was for this object file's object")
    add_jaw_options(p, "check that the run designed these", "no check; the FEM always "
                    "solves each design with its own jaws")
    add_load_set_option(p, "no check; the FEM always checks the run's own load set")
    p.set_defaults(func=_verify_command)
    return p


def add_optimize_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``optimize`` command to the ``psm-grasp`` sub-parsers."""
    from envs.model.defaults import (
        DEFAULT_FRICTION_COEFFICIENT,
        MAX_TRIANGLES,
        MAX_TRIANGLES_FAMILY,
    )
    from envs.model.family import ELEMENTS
    from envs.scenarios import ROBUST_MEASURES
    from envs.scene import PRESETS
    from optim.executors import MAX_WORKERS_PER_CPU
    from optim.optimize import METHODS
    from optim.problem import (
        DEFAULT_BUDGET_RANGE,
        DEFAULT_GRASP_BUDGET,
        DEFAULT_STRAIN_LIMIT,
        DEFAULT_TIME_LIMIT_S,
        MAX_BUDGET,
    )
    from optim.verify import MAX_TOP

    p = subparsers.add_parser(
        "optimize", help="optimize a gripper design for one object",
        description="Optimize a gripper design for an object (your own from --object FILE, or "
                    "a scene preset's disk) and write the result JSON, a convergence chart, the "
                    "best grasp, the design in millimetres (JSON, CSV and a dimensioned "
                    "drawing) and, for NSGA-II, the Pareto front to --out. The optimum is "
                    "reported by a finer member of the model family (within a few percent of "
                    "the FEM) unless --no-finish.")
    p.add_argument("--method", default="portfolio", metavar="METHOD",
                   help="the search (default portfolio: CMA-ES starts from a screened sample, "
                   "raced; see the optimizers page); one of " + ", ".join(METHODS)
                   + ", or ng:NAME for any optimizer of Nevergrad's registry (the ng: and "
                   "optuna: methods need the extras ng and optuna)")
    p.add_argument("--object", metavar="FILE.toml", default=None,
                   help="your object: a TOML file with an [object] table (radius_m, "
                   "youngs_modulus_pa, poisson_ratio, thickness_m; optional name, "
                   "stiffness_scale, strain_limit, friction_coefficient, density_kg_m3, "
                   "payload_factor, load_set, jaw, jaw_per_finger); see examples/objects")
    p.add_argument("--scene", default=None, choices=sorted(PRESETS),
                   help=f"or the disk of this preset, with its gripper's own joint spring "
                   f"(default without --object: {run.DEMO_SCENE})")
    p.add_argument("--budget", type=int, default=None,
                   help=f"evaluations (designs, each judged in every scenario), in [1, "
                   f"{MAX_BUDGET:,}] (default: with --time, as many as it allows; else "
                   f"{DEFAULT_GRASP_BUDGET:,} grasps over the scenario count, within "
                   f"{DEFAULT_BUDGET_RANGE[0]:,}-{DEFAULT_BUDGET_RANGE[1]:,}: 3,600 with 9 "
                   f"scenarios, searched for at most {DEFAULT_TIME_LIMIT_S:.0f} s)")
    p.add_argument("--time", type=float, default=None, metavar="SECONDS",
                   help="wall seconds the search may take, beside --budget: it stops at "
                   "whichever ends first (the finish and the files come after it)")
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
                        f"workers with --dask local, at most {MAX_WORKERS_PER_CPU} per core "
                        "(default: in-process, batched, already on "
                        "every core; on one machine workers do not pay, least of all for "
                        "CMA-ES's 9-design populations)")
    p.add_argument("--strain-limit", type=float, default=None,
                   help=f"admissible peak compression of the object, in (0, 1] (default: the "
                   f"object file's, else {DEFAULT_STRAIN_LIMIT})")
    p.add_argument("--friction", type=float, default=None,
                   help=f"Coulomb friction coefficient of the fingers on the object, in "
                   f"(0, 10]: a grasp needing more does not hold (default: the object file's, "
                   f"else {DEFAULT_FRICTION_COEFFICIENT}, a rubber or silicone pad)")
    p.add_argument("--payload-factor", type=float, default=None, metavar="F",
                   help="the grasp must lift the payload F m g (m: the object's mass) by "
                   "friction in every direction of --load-set; in [0, 100] "
                   "(default: the object file's, else 2: the weight plus a lift at 1 g; 0: no "
                   "payload)")
    p.add_argument("--joint-spring", type=float, default=None, metavar="REL",
                   help="joint torsion spring in the object's torque unit s E t r^2 per "
                   "radian (default 0.0149: the paper gripper's on its r = 0.07 m disk, scaled "
                   "with the object; a preset keeps its gripper's own)")
    p.add_argument("--joint-spring-nm-per-rad", type=float, default=None, metavar="K_F",
                   help="an absolute joint torsion spring [N·m/rad] instead")
    p.add_argument("--element", default=None, choices=ELEMENTS,
                   help="element of the disk model (default nhquad: the default model, within "
                   "2 %% RMS of the FEM; spring: the paper's fan, cheaper, far off the FEM)")
    p.add_argument("--triangles", type=int, default=None,
                   help=f"contour points N (default 40 for nhquad, 20 for the fan), in [4, "
                   f"{MAX_TRIANGLES}] for the fan, [4, {MAX_TRIANGLES_FAMILY}] otherwise")
    p.add_argument("--rings", type=int, default=None,
                   help="rings M of the disk mesh (default 2 for nhquad, 1 otherwise)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-finish", action="store_true",
                   help="report the optimum by the search model itself, not re-scored by the "
                   "finer member")
    p.add_argument("--placement-tolerance", default=None, metavar="M[,M]",
                   type=placement_tolerance,
                   help="placement error the design must survive, +- metres: one number for "
                   "both ways, or ALONG,ACROSS the gripper's axis (default: the object file's "
                   "placement_tolerance_m, else none)")
    p.add_argument("--tolerances", default=None, metavar="length=MM,angle=DEG,...",
                   help="manufacturing tolerances the design must survive, +-: length=MM "
                   "(finger length, width, joint offset), angle=DEG (rest angle), spring=PCT "
                   "and torque=PCT, each a scenario dimension beside the object's (default: "
                   "the object file's [gripper.tolerances], else none)")
    p.add_argument("--resolution", default=None, metavar="MM[,DEG[,DIGITS]]",
                   help="manufacturing resolution the reported design is rounded to before "
                   "it is scored: lengths, angles, significant figures of torque and spring "
                   "(default 0.1,0.1,3; 'none': unrounded)")
    p.add_argument("--pin-diameter", type=float, default=None, metavar="MM",
                   help="the joint pin's diameter (default: half the finger width, rounded "
                   "down to the resolution)")
    p.add_argument("--robust", default=None, choices=ROBUST_MEASURES,
                   help="with scenarios (ranges in the object file, a placement tolerance): "
                   "the reward over them, the worst scenario's (default), the mean or the "
                   "CVaR (the mean of the worst quarter)")
    p.add_argument("--joints-apart", action="store_true",
                   help="keep the joints at least half a finger width from the axis (d3 >= "
                   "w/2), for a gripper whose fingers cannot be stacked at the joints like "
                   "forceps jaws (default: any d3 in the box; the build sheet says when the "
                   "fingers must be stacked)")
    add_jaw_options(p, "design", "the object file's jaw, else straight")
    add_load_set_option(p, "the object file's load_set, else any")
    p.add_argument("--verify-top", type=int, default=None, metavar="K",
                   help=f"then re-score the K best distinct designs with the FEM (as psm-grasp "
                   f"verify; K in [1, {MAX_TOP}])")
    p.set_defaults(func=_optimize_command)
    return p
