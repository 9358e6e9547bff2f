"""How far a run's reported reward moves among the designs a workshop cannot tell from it.

A workshop builds to a resolution (0.1 mm, 0.1 degree, three significant figures of torque:
:data:`optim.parts.resolution.DEFAULT_RESOLUTION`); the reported optimum is the rounded design.
This draws ``--count`` designs within half that resolution of each ``--result``'s reported
design (every length within +-half the length step, every angle within +-half the angle step,
the torque within +-half a unit of its third significant figure, the relative step 0.5 %),
scores them as the finish scores the reported one (the finer member,
:data:`optim.finish.RANKING_MEMBER`, under the object file's scenarios) and prints, per
result: the reported reward, how many neighbours are valid at rest (a design at the edge of
the design box, a groove at the finger's limit, has invalid neighbours), and the valid ones'
least, median and largest reward and their spread.

Usage::

    python scripts/optimum_neighbours.py --object examples/objects/tomatoes_10_15mm.toml \\
        --result out/portfolio_seed0_result.json [--result ...] [--count 24] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from envs.scene import design_row
from optim.finish import RANKING_MEMBER
from optim.parts.resolution import DEFAULT_RESOLUTION
from optim.problem import DesignProblem
from optim.run import object_problem

# the reward of a design invalid at rest (the lowest tier)
INVALID_BELOW = -3.5 + 1e-9
TORQUE_RELATIVE_STEP = 0.005  # half a unit of the third significant figure, at most


def neighbours(design: dict[str, float], count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` design rows within half the manufacturing resolution of ``design`` (lengths
    ``*_m``, angles ``*_rad``, torques ``*_nm``; zero lengths, e.g. a straight bar's groove,
    kept at zero)."""
    half_length = 0.5 * DEFAULT_RESOLUTION.length_m
    half_angle = 0.5 * DEFAULT_RESOLUTION.angle_rad
    rows = []
    for _ in range(count):
        moved = {}
        for name, value in design.items():
            if name.endswith("_m") and value != 0.0:
                value += rng.uniform(-half_length, half_length)
            elif name.endswith("_rad"):
                value += rng.uniform(-half_angle, half_angle)
            elif name.endswith("_nm"):
                value *= 1.0 + rng.uniform(-TORQUE_RELATIVE_STEP, TORQUE_RELATIVE_STEP)
            moved[name] = value
        rows.append(design_row(moved))
    return np.array(rows)


def summary(problem: DesignProblem, result: dict, count: int, seed: int) -> dict[str, float]:
    """The reported reward and its neighbours' rewards by the finer member."""
    rows = neighbours(result["best_design"], count, np.random.default_rng(seed))
    reward = problem.evaluate_physical(rows, RANKING_MEMBER)["reward"]
    valid = reward[reward > INVALID_BELOW]
    out = {"reported": float(result["best_reward"]), "valid": int(valid.size),
           "count": int(count)}
    if valid.size:
        out.update(least=float(valid.min()), median=float(np.median(valid)),
                   largest=float(valid.max()), spread=float(valid.max() - valid.min()))
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--object", type=Path, required=True)
    parser.add_argument("--result", type=Path, action="append", required=True)
    parser.add_argument("--count", type=int, default=24)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jaw", default="any")
    args = parser.parse_args(argv)
    problem = object_problem(args.object, args.jaw)
    print("| result | reported | valid at rest | least | median | largest | spread |")
    print("|---|---|---|---|---|---|---|")
    for path in args.result:
        row = summary(problem, json.loads(path.read_text()), args.count, args.seed)
        cells = [f"{row[k]:.4f}" if k in row else "" for k in
                 ("least", "median", "largest", "spread")]
        print(f"| {path.parent.name}/{path.name} | {row['reported']:.4f} | "
              f"{row['valid']} of {row['count']} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
