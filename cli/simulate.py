"""``psm-grasp simulate``: solve one grasp and print it (text or JSON), optionally draw it."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any

from .options import add_load_set_option, cli_option, object_option

__all__ = ["add_simulate_parser", "run_simulate"]


def add_simulate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``simulate`` command to the ``psm-grasp`` sub-parsers."""
    from envs.model.defaults import MAX_TRIANGLES, MAX_TRIANGLES_FAMILY, STIFFNESS_RULES
    from envs.model.family import ELEMENTS
    from envs.model.rings import MAX_RINGS
    from envs.scene import PRESETS
    from envs.solver import METHODS

    sim = subparsers.add_parser(
        "simulate", help="solve one grasp",
        description="Solve one grasp of a scene preset or of your own object (--object FILE: "
                    "its [gripper] table, else the paper's gripper scaled to it) and print it: "
                    "jaw angles, contacts, forces, deformation, what the fixed centre carries "
                    "and the friction a free object would need.")
    sim.add_argument("--scene", default=None, choices=sorted(PRESETS),
                     help="a preset scene (default without --object: paper-r070)")
    sim.add_argument("--object", metavar="FILE.toml", default=None,
                     help="your object: a TOML file with an [object] table and an optional "
                     "[gripper] table (see examples/objects)")
    sim.add_argument("--friction", type=float, default=None,
                     help="friction coefficient of the fingers on the object, to say whether the "
                     "grasp holds (default: the object file's, else 0.5)")
    sim.add_argument("--payload-factor", type=float, default=None, metavar="F",
                     help="the friction needed includes lifting F m g (m: the object's mass), "
                     "in [0, 100] (default: the object file's, else 2: the weight plus a lift "
                     "at 1 g; 0: the fixed centre's reaction alone)")
    add_load_set_option(sim, "the object file's load_set, else any")
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
    sim.add_argument("--torque", type=float, default=None,
                     help="actuation torque T_a [N·m] (default 0.2 on a preset; with --object "
                     "the [gripper] table's torque_nm, else the squeeze of 0.2 N·m on "
                     "paper-r070: 0.041 of the object's torque unit s E t r^2)")
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
    if args.torque is not None:
        check_range("--torque", args.torque, 0.0, math.inf)  # its ceiling: with the scene
    plot = None if args.plot is None else check_output_file("--plot", args.plot, (".png",))
    scene, torque, name, friction, factor, load_set = _scene_of(args)
    if args.torque is not None:  # (a file's torque_nm is checked with the file)
        cli_option("--torque", scene.check_torque, args.torque)
    args.torque = torque
    for words in scene.warnings:  # a gripper that cannot reach the object, ...
        print(f"psm-grasp: warning: {words}", file=sys.stderr)
    model = {"stiffness_rule": args.rule, "payload_factor": factor, "load_set": load_set,
             **spec.kwargs()}
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
        data["scene"] = name
        data["friction_coefficient"] = friction
        data["holds"] = res.holds(friction)
        data["kernel_load_s"] = load_s
        print(json.dumps(data, indent=2))
    else:
        _print_text(args, spec, res, load_s, name, friction)
    if plot is not None:
        from envs.render import grasp_figure

        grasp_figure(scene, res, path=plot)
        if not args.json:
            print(f"  plot           : {plot}")
    if not res.converged:
        print(f"psm-grasp: warning: the grasp did not converge ({res.message}): exit code 1",
              file=sys.stderr)
    return 0 if res.converged else 1


def _scene_of(args: argparse.Namespace):
    """The scene, torque [N·m], name, friction coefficient, payload factor and load set of
    the command's options."""
    from envs.model.defaults import DEFAULT_FRICTION_COEFFICIENT, DEFAULT_PAYLOAD_FACTOR
    from envs.scene import Design, Scene
    from optim.problem import check_friction, check_payload_factor, paper_design_for
    from optim.run import load_set_of

    if args.object is not None and args.scene is not None:
        raise ValueError("--object and --scene exclude each other")
    if args.friction is not None:
        cli_option("--friction", check_friction, args.friction)
    if args.payload_factor is not None:
        cli_option("--payload-factor", check_payload_factor, args.payload_factor)
    if args.object is None:
        name = args.scene or "paper-r070"
        torque = 0.2 if args.torque is None else args.torque
        friction = DEFAULT_FRICTION_COEFFICIENT if args.friction is None else args.friction
        factor = DEFAULT_PAYLOAD_FACTOR if args.payload_factor is None else args.payload_factor
        load_set = load_set_of(None, args.load_set)
        return Scene.preset(name), torque, name, friction, factor, load_set
    spec = object_option(args.object)
    load_set = load_set_of(spec, args.load_set)
    factor = (args.payload_factor if args.payload_factor is not None else spec.payload_factor
              if spec.payload_factor is not None else DEFAULT_PAYLOAD_FACTOR)
    friction = (args.friction if args.friction is not None else spec.friction_coefficient
                if spec.friction_coefficient is not None else DEFAULT_FRICTION_COEFFICIENT)
    # the default squeeze: 0.2 N·m on paper-r070, in the object's torque unit s E t r^2
    paper = Scene.preset("paper-r070").disk
    unit = spec.disk.torque_unit_nm
    squeeze = 0.2 / paper.torque_unit_nm * unit
    if spec.gripper is not None:
        scene = spec.scene()
        torque = (args.torque if args.torque is not None else spec.gripper.torque_nm
                  if spec.gripper.torque_nm is not None else squeeze)
        return scene, torque, spec.name, friction, factor, load_set
    # no [gripper] table: the paper's gripper, scaled to the object like a relative design
    design = Design.from_array(paper_design_for(spec.disk, 0.2)[0])
    torque = design.torque_nm if args.torque is None else args.torque
    return (design.to_scene(spec.disk), torque, f"{spec.name} (the paper's gripper)", friction,
            factor, load_set)


def _limit_words(res) -> str:
    """What sets the required friction, in words."""
    from envs.model.holding import LIMIT_IN_PLANE, LIMIT_NAMES

    words = f"set by: {LIMIT_NAMES[res.friction_limit]}"
    if res.friction_limit == LIMIT_IN_PLANE and math.isfinite(res.friction_limit_angle_rad):
        words += f", a pull at {math.degrees(res.friction_limit_angle_rad):.0f} deg from +x"
    return words


def _print_text(args: argparse.Namespace, spec, res, load_s: float, name: str,
                friction: float) -> None:
    r, left = (math.degrees(a) for a in res.jaw_angles_rad)
    print(f"scene {name}, N = {spec.n_triangles}, M = {spec.n_rings} ({spec.element}"
          f"{f', shipped scale x{spec.scale:.4f}' if spec.scale != 1.0 else ''}), "
          f"T_a = {args.torque:g} N·m, method {args.method}")
    print(f"  converged      : {res.converged} ({res.message})")
    print(f"  jaw angles     : right {r:.4f} deg, left {left:.4f} deg")
    print(f"  contacts       : right {res.n_contacts[0]}, left {res.n_contacts[1]}")
    print(f"  total force    : {res.total_force_n[0]:.4g} N, {res.total_force_n[1]:.4g} N")
    print(f"  peak strain    : {res.peak_strain:.4%}")
    print(f"  max disp / r   : {res.max_displacement_ratio:.4%}")
    print(f"  peak compr.    : {res.peak_compression:.4%}")
    print(f"  pin force      : ({res.pin_force_n[0]:.4g}, {res.pin_force_n[1]:.4g}) N, moment "
          f"{res.pin_moment_nm:.3g} N·m (what the fixed centre carries)")
    verdict = ("holds" if res.holds(friction) else "would slip"
               if all(res.touching) and res.converged
               else "no grasp: a finger does not touch the object")
    print(f"  payload        : {res.payload_n:.4g} N to lift, load set {res.load_set} (grip "
          f"{res.grip_force_n:.4g} N; at most {friction * res.grip_force_n:.4g} N by friction "
          f"{friction:g})")
    task = "hold and lift it" if res.payload_n > 0.0 else "hold it"
    print(f"  friction needed: {res.required_friction:.4g} to {task} without the pin "
          f"({_limit_words(res)}); with {friction:g}: {verdict}")
    print(f"  stable         : {res.stable}")
    print(f"  KKT residual   : force {res.kkt.force_residual_rel:.1e}, "
          f"moment {res.kkt.moment_residual_rel:.1e}")
    print(f"  solve time     : {res.solve_time_s * 1e3:.2f} ms, {res.iterations} iterations")
    print(f"  kernel load    : {load_s * 1e3:.0f} ms (first call in this process: numba "
          "loads its cached kernels, or compiles them on a fresh install)")
