"""Train the design policy shipped with the package (``optim/policies/default``).

SAC over the default object distribution (:class:`envs.design_env.ObjectDistribution`: radius
1 mm - 0.2 m, modulus 10 kPa - 10 MPa, Poisson 0.25-0.49, strain limit 0.03-0.17, friction
0.2-1.0, density 20-1200 kg/m^3, payload factor 0-2, placement tolerance 0-0.25 radii; the
reward the worst of the object's 9 placements), with the settings of
:class:`optim.rl.TrainingSettings` and a fixed seed, so that the file can be made again. Writes
``policy.json`` (metadata, with the learning curve) and ``policy.npz`` (the actor's layers, ~40
KB): what :func:`optim.rl.load_policy` reads. The learning curve is scored on held-out objects
(:func:`optim.rl.heldout_objects`, a seed no training env draws from).

Usage: ``python scripts/train_shipped_policy.py [--steps 80000] [--seed 0] [--jaw any]
[--out DIR]`` (``--jaw any``: the policy that designs shaped jaws too, GripperJawDesign-v0's
action, written to ``optim/policies/jaws``).
A step solves up to 9 placements, so the shipped training takes fewer steps than
``train-policy``'s default.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from optim.rl import SHIPPED_JAWS, heldout_objects, learning_curve_figure, train_policy

HELDOUT_SEED = 12345  # the benchmark's held-out objects (scripts/bench_policy.py)
SHIPPED_STEPS = 80_000  # each step solves up to 9 placements: 9x the cost of a step without
SHIPPED_SEED = 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=SHIPPED_STEPS)
    parser.add_argument("--seed", type=int, default=SHIPPED_SEED)
    parser.add_argument("--jaw", default="straight", choices=("straight", "any"),
                        help="straight (optim/policies/default) or any shaped jaws "
                        "(optim/policies/jaws)")
    parser.add_argument("--out", type=Path, default=None,
                        help="default: the shipped folder of --jaw")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    out = SHIPPED_JAWS[args.jaw] if args.out is None else args.out
    policy = train_policy("sac", steps=args.steps, seed=args.seed,
                          name="shipped" if args.jaw == "straight" else f"shipped, {args.jaw} jaws",
                          heldout=heldout_objects(20, HELDOUT_SEED), curve_points=20,
                          progress=not args.no_progress, jaw=args.jaw)
    policy.save(out)
    Path("out").mkdir(exist_ok=True)
    suffix = "" if args.jaw == "straight" else f"_{args.jaw}"
    learning_curve_figure({"shipped": policy.meta["training"]["curve"]},
                          Path("out") / f"shipped_policy_curve{suffix}.png",
                          title=f"the shipped policy: SAC, {args.steps} steps, seed {args.seed}")
    t = policy.meta["training"]
    print(f"{out}: trained in {t['wall_time_s']:.0f} s; held-out mean reward "
          f"{t['curve'][-1]['heldout_reward']:.4f}")


if __name__ == "__main__":
    main()
