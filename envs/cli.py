"""Command line: ``psm-grasp simulate | demo | optimize | verify``."""

from __future__ import annotations

import argparse
import json
import math
import sys

__all__ = ["main"]


def cli_option(option: str, check, *args):
    """``check(*args)``, its ``ValueError`` prefixed with the command-line option's name."""
    try:
        return check(*args)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def _simulate(args: argparse.Namespace) -> int:
    import time

    from .model.defaults import DEFAULT_ELEMENT
    from .scene import Scene
    from .solver import simulate
    from .solver.simulate import check_model
    from .solver.warmup import announce_compile
    from .validation import check_output_file, check_range

    # every option before any work: a bad --plot must not cost a solve
    if args.calibrated and args.uncalibrated:
        raise ValueError("--calibrated and --uncalibrated exclude each other")
    calibrated = True if args.calibrated else (False if args.uncalibrated else None)
    element = args.element or (DEFAULT_ELEMENT if args.method == "newton" else "spring")
    spec = cli_option("--triangles/--rings/--element/--calibrated", check_model,
                      args.triangles, args.rings, element, calibrated)
    check_range("--torque", args.torque, 0.0, math.inf)
    plot = None if args.plot is None else check_output_file("--plot", args.plot, (".png",))
    scene = Scene.preset(args.scene)
    model = {"stiffness_rule": args.rule, **spec.kwargs()}
    n_tri = model.pop("n_triangles")
    # the first solve in a process loads (or compiles) the numba kernels: time it apart, then
    # report the solve of the answer shown, as a user's next call would see it
    t0 = time.perf_counter()
    announce_compile()
    first = simulate(scene, args.torque, n_tri, args.method, **model)
    first_wall_s = time.perf_counter() - t0
    res = simulate(scene, args.torque, n_tri, args.method, **model)
    load_s = max(0.0, first_wall_s - first.solve_time_s)
    if args.json:
        data = res.to_dict()
        data["scene"] = args.scene
        data["kernel_load_s"] = load_s
        print(json.dumps(data, indent=2))
    else:
        r, left = (math.degrees(a) for a in res.jaw_angles_rad)
        print(f"scene {args.scene}, N = {spec.n_triangles}, M = {spec.n_rings} ({spec.element}"
              f"{f', shipped scale x{spec.scale:.4f}' if spec.scale != 1.0 else ''}), "
              f"T_a = {args.torque:g} N·m, method {args.method}")
        print(f"  converged      : {res.converged} ({res.message})")
        print(f"  jaw angles     : right {r:.4f} deg, left {left:.4f} deg")
        print(f"  contacts       : right {res.n_contacts[0]}, left {res.n_contacts[1]}")
        print(f"  total force    : {res.total_force_n[0]:.4g} N, {res.total_force_n[1]:.4g} N")
        print(f"  peak strain    : {res.peak_strain:.4%}")
        print(f"  max disp / r   : {res.max_displacement_ratio:.4%}")
        print(f"  stable         : {res.stable}")
        print(f"  KKT residual   : force {res.kkt.force_residual_rel:.1e}, "
              f"moment {res.kkt.moment_residual_rel:.1e}")
        print(f"  solve time     : {res.solve_time_s * 1e3:.2f} ms, {res.iterations} iterations")
        print(f"  kernel load    : {load_s * 1e3:.0f} ms (first call in this process: numba "
              "loads its cached kernels, or compiles them on a fresh install)")
    if plot is not None:
        from .render import grasp_figure

        grasp_figure(scene, res, path=plot)
        if not args.json:
            print(f"  plot           : {plot}")
    return 0 if res.converged else 1


def _demo(args: argparse.Namespace) -> int:
    from .solver.warmup import announce_compile
    from .validation import check_output_dir

    out = check_output_dir("--out", args.out)
    out.mkdir(parents=True, exist_ok=True)
    announce_compile()
    try:
        from optim.cli import run_demo
    except ImportError:
        run_demo = None
    if run_demo is not None:
        return run_demo(out)
    from .render import grasp_figure
    from .scene import Scene
    from .solver import simulate

    scene = Scene.preset("paper-r070")
    res = simulate(scene, 0.2, 20, element="spring")
    grasp_figure(scene, res, path=out / "grasp.png")
    print(f"wrote {out / 'grasp.png'} (converged: {res.converged})")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from .model.defaults import MAX_TRIANGLES, MAX_TRIANGLES_FAMILY, STIFFNESS_RULES
    from .model.family import ELEMENTS
    from .model.rings import MAX_RINGS
    from .scene import PRESETS
    from .solver import METHODS

    parser = argparse.ArgumentParser(prog="psm-grasp", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="solve one grasp")
    sim.add_argument("--scene", default="paper-r070", choices=sorted(PRESETS))
    sim.add_argument("--element", default=None, choices=ELEMENTS,
                     help="nhquad (default: the default model, 40 points, 2 rings, within 2 %% "
                     "RMS of the FEM); spring: springs and the area energy (the paper's fan: "
                     "20 points, 1 ring); cst: constant-strain neo-Hookean triangles")
    sim.add_argument("--triangles", type=int, default=None,
                     help=f"contour points N, in [4, {MAX_TRIANGLES}] for the springs-only fan, "
                     "cells 0.4-2.5 times as deep as wide for spring rings (M = 2: N <= 22, "
                     f"M = 8: 11-62), [4, {MAX_TRIANGLES_FAMILY}] otherwise (default 40 for "
                     "nhquad, 20 else)")
    sim.add_argument("--rings", type=int, default=None,
                     help=f"rings M of the point mesh, in [1, {MAX_RINGS}] (default 2 for "
                     "nhquad, 1 otherwise: the paper's fan)")
    sim.add_argument("--calibrated", action="store_true",
                     help="require the member's shipped scale (fitted on the paper disks; by "
                     "default it is applied where the member has one)")
    sim.add_argument("--uncalibrated", action="store_true",
                     help="the member without its shipped scale (the disk's own scale only)")
    sim.add_argument("--torque", type=float, default=0.2, help="actuation torque T_a [N·m]")
    sim.add_argument("--method", default="newton", choices=METHODS)
    sim.add_argument("--rule", default="van_gelder", choices=STIFFNESS_RULES)
    sim.add_argument("--json", action="store_true", help="print the result as JSON")
    sim.add_argument("--plot", metavar="PNG", help="write a drawing of the grasp (a .png file "
                     "in an existing folder)")
    sim.set_defaults(func=_simulate)
    demo = sub.add_parser("demo", help="run the main job and write charts to --out")
    demo.add_argument("--out", default="out")
    demo.set_defaults(func=_demo)
    try:
        from optim.cli import add_optimize_parser
    except ImportError:
        add_optimize_parser = None
    if add_optimize_parser is not None:
        from optim.cli import add_verify_parser

        add_optimize_parser(sub)
        add_verify_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``psm-grasp`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ValueError as exc:
        print(f"psm-grasp: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
