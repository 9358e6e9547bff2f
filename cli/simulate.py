"""``psm-grasp simulate``: solve one grasp and print it (text or JSON), optionally draw it."""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

from .options import cli_option

__all__ = ["add_simulate_parser", "run_simulate"]


def add_simulate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``simulate`` command to the ``psm-grasp`` sub-parsers."""
    from envs.model.defaults import MAX_TRIANGLES, MAX_TRIANGLES_FAMILY, STIFFNESS_RULES
    from envs.model.family import ELEMENTS
    from envs.model.rings import MAX_RINGS
    from envs.scene import PRESETS
    from envs.solver import METHODS

    sim = subparsers.add_parser("simulate", help="solve one grasp")
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
    sim.set_defaults(func=run_simulate)
    return sim


def run_simulate(args: argparse.Namespace) -> int:
    """The ``simulate`` command: exit code 0 when the grasp converged, 1 otherwise."""
    from envs.model.defaults import DEFAULT_ELEMENT
    from envs.scene import Scene
    from envs.solver import simulate
    from envs.solver.simulate import check_model
    from envs.solver.warmup import announce_compile
    from envs.validation import check_output_file, check_range

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
        _print_text(args, spec, res, load_s)
    if plot is not None:
        from envs.render import grasp_figure

        grasp_figure(scene, res, path=plot)
        if not args.json:
            print(f"  plot           : {plot}")
    return 0 if res.converged else 1


def _print_text(args: argparse.Namespace, spec, res, load_s: float) -> None:
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
