"""``psm-grasp train-policy`` and ``psm-grasp design``: the design policy's commands.

The work is the library's (:mod:`optim.rl`: :func:`~optim.rl.train_policy`,
:func:`~optim.rl.load_policy`; :func:`optim.run.run_optimize` with the ``"policy"`` method);
here the options are parsed and checked, by the names the user typed, before any of it starts.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .optimize import add_jaw_options
from .options import cli_option, object_option

__all__ = ["add_policy_parsers"]

DEFAULT_TRAIN_STEPS = 200_000


def _train_command(args: argparse.Namespace) -> int:
    from envs.validation import check_output_dir
    from optim.problem import check_budget, check_seed
    from optim.rl import RL_METHODS, TrainingSettings

    if args.method not in RL_METHODS:  # (argparse's choices say so first)
        raise ValueError(f"--method must be one of {RL_METHODS}")
    cli_option("--steps", check_budget, args.steps)
    cli_option("--seed", check_seed, args.seed)
    cli_option("--steps", TrainingSettings, args.method, args.steps, args.seed)
    out = check_output_dir("--out", args.out)
    from optim.rl import train_policy, write_training_outputs

    jaw = args.jaw or "straight"
    if jaw == "straight" and args.jaw_per_finger:
        raise ValueError("--jaw-per-finger: needs shaped jaws (--jaw cradle, vee or any)")
    policy = train_policy(args.method, steps=args.steps, seed=args.seed,
                          progress=not args.no_progress, jaw=jaw,
                          jaw_per_finger=bool(args.jaw_per_finger))
    paths = write_training_outputs(policy, out)
    t = policy.meta["training"]
    print(f"trained {args.method} for {args.steps} steps (seed {args.seed}) in "
          f"{t['wall_time_s']:.0f} s")
    for name, path in paths.items():
        print(f"  {name:12s}: {path}")
    print(f"use it: psm-grasp design --object FILE --policy {out}")
    return 0


def _design_command(args: argparse.Namespace) -> int:
    from envs.solver.warmup import announce_compile
    from envs.validation import check_integer, check_output_dir
    from optim import run
    from optim.problem import check_seed
    from optim.rl import load_policy
    from optim.verdict import verdict_exit_code

    obj = object_option(args.object)
    # the shipped policies design straight or any jaws: others (asked for here or by the
    # object file) are refused before any work, with the command that designs them
    jaws = cli_option("--jaw/--jaw-per-finger", run.jaw_settings, obj, args.jaw,
                      args.jaw_per_finger)
    try:
        run.check_policy_jaw("policy", jaws)
    except ValueError:
        raise ValueError(
            f"--jaw: the design policies design straight or any jaws alike on both fingers, "
            f"not jaw {jaws['jaw']!r}" + (" per finger" if jaws["jaw_per_finger"] else "")
            + (" (the object file's)" if args.jaw is None else "") + f": run psm-grasp "
            f"optimize --object {args.object} --jaw {jaws['jaw']}"
            + (" --jaw-per-finger" if jaws["jaw_per_finger"] else "") + " for them") from None
    # a bad or mismatched policy before any work, named as typed
    policy = load_policy(jaw=jaws["jaw"]) if args.policy is None else cli_option(
        "--policy", load_policy, args.policy)
    if policy.bounds.jaw != jaws["jaw"]:
        raise ValueError(f"--policy: the policy designs {policy.bounds.jaw} jaws, not "
                         f"{jaws['jaw']} (--jaw)")
    refine = check_integer("--refine", args.refine, 0, 100_000)
    cli_option("--seed", check_seed, args.seed)
    check_output_dir("--out", args.out)
    if args.policy is None and jaws["jaw"] != "straight":
        # measured (docs/environment.md, the policy for shaped jaws): its designs start a
        # search worse than a cold CMA-ES at every budget; the search does not depend on it
        print("psm-grasp: note: the shipped policy for shaped jaws is a quick first look, a "
              "weaker start than a search (scripts/bench_policy.py --jaw any): for the design "
              f"to build, run psm-grasp optimize --object {args.object} --jaw {jaws['jaw']}",
              file=sys.stderr)
    announce_compile()
    result, _ = run.run_optimize("policy", obj=obj, budget=1 + refine, seed=args.seed,
                                 out=args.out, prefix="design", policy=policy,
                                 progress=not args.no_progress, **jaws)
    # one start (the policy's design, refined) cannot say that nothing holds: exit 5, not 3
    return 0 if result.extra["grasp_found"] else verdict_exit_code(result.extra["verdict"])


def add_policy_parsers(subparsers: Any) -> None:
    """Add the ``train-policy`` and ``design`` commands to the ``psm-grasp`` sub-parsers."""
    from optim.rl import RL_METHODS

    train = subparsers.add_parser(
        "train-policy", help="train a design policy over objects of real use",
        description="Train a design policy (stable-baselines3) over objects of radius 1 mm - "
                    "0.2 m, modulus 10 kPa - 10 MPa, Poisson ratio 0.25-0.49, strain limit "
                    "0.03-0.17, friction 0.2-1.0, density 20-1200 kg/m^3, payload factor "
                    "0-2 and placement tolerance 0-0.25 radii (the reward: the worst of the "
                    "placements), and write it to --out (policy.json, "
                    "policy.npz: what psm-grasp design --policy reads; sb3_model.zip; the "
                    "learning curve). The shipped policy was trained this way.")
    train.add_argument("--method", default="sac", choices=RL_METHODS)
    train.add_argument("--steps", type=int, default=DEFAULT_TRAIN_STEPS,
                       help="designs evaluated in training (default %(default)s, minutes on 2 "
                       "cores)")
    train.add_argument("--seed", type=int, default=0)
    add_jaw_options(train, "design", "straight: GripperDesign-v2's six actions; shaped jaws "
                    "train in GripperJawDesign-v0's action space")
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.add_argument("--out", required=True, help="output folder, created if its parent "
                       "exists")
    train.set_defaults(func=_train_command)

    design = subparsers.add_parser(
        "design", help="a gripper for your object in one forward pass of a design policy",
        description="Design a gripper for an object file with a trained policy (one forward "
                    "pass; --refine K: then K evaluations of CMA-ES started at its design) and "
                    "write the result JSON (like optimize), the best grasp and the design in "
                    "millimetres (JSON, CSV, a dimensioned drawing) to --out.")
    design.add_argument("--object", metavar="FILE.toml", required=True,
                        help="your object (see examples/objects)")
    design.add_argument("--policy", metavar="DIR", default=None,
                        help="a policy folder written by train-policy (default: the one "
                        "shipped with the package)")
    design.add_argument("--refine", type=int, default=0, metavar="K",
                        help="CMA-ES evaluations around the policy's design (default 0)")
    design.add_argument("--seed", type=int, default=0)
    add_jaw_options(design, "design", "the object file's jaw, else straight; the shipped "
                    "policies design straight or any jaws alike on both fingers")
    design.add_argument("--no-progress", action="store_true", help="no progress bar")
    design.add_argument("--out", default="out",
                        help="output folder, created if its parent exists (default %(default)s)")
    design.set_defaults(func=_design_command)
