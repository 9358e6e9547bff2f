"""What a design near a run's optimum costs, and what of it is the holding check's load set.

A search's time is not its evaluations times a random design's cost: the designs a search
refines near a shaped-jaw optimum (a cradle that conforms to the object: many contacts on a
curved face) cost many times a random design. This measures it for finished runs: for each
``--result`` (a ``*_result.json`` of ``psm-grasp optimize --object FILE``), its kept best
designs (``top_designs``) judged as the search judges them (the object file's scenarios,
friction, payload), on one thread, CPU milliseconds a design (the medians of ``--repeats``):

- with the run's own load set (as searched), and with each load set of
  :data:`envs.model.loads.LOAD_SETS`;
- without a payload (the grasp and its metrics alone: what the load set adds is the
  difference);
- ``--random`` random designs of the same design box, as searched, for scale.

Usage::

    python scripts/optimum_cost.py --object examples/objects/silicone_puck.toml \\
        --result out/portfolio_seed0_result.json [--result ...] [--random 64] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from envs.model.loads import LOAD_SETS
from envs.parallel import set_solver_threads
from envs.scene import design_row
from optim.problem import DesignProblem
from optim.run import object_problem


def cpu_ms(problem: DesignProblem, designs: np.ndarray, repeats: int) -> float:
    """Median CPU milliseconds a design of ``problem.evaluate_physical`` (one thread)."""
    problem.evaluate_physical(designs[:1])  # (kernels loaded outside the clock)
    times = []
    for _ in range(repeats):
        start = time.process_time()
        problem.evaluate_physical(designs)
        times.append(time.process_time() - start)
    return 1e3 * statistics.median(times) / len(designs)


def measure(problem: DesignProblem, designs: np.ndarray, repeats: int) -> dict[str, float]:
    """CPU ms a design: as searched, under each load set, and without a payload."""
    own_set, own_payload = problem.load_set, problem.payload_factor
    row = {"as searched": cpu_ms(problem, designs, repeats)}
    try:
        for name in LOAD_SETS:
            problem.load_set = name
            row[f"load set {name}"] = cpu_ms(problem, designs, repeats)
        problem.load_set, problem.payload_factor = own_set, 0.0
        row["no payload"] = cpu_ms(problem, designs, repeats)
    finally:
        problem.load_set, problem.payload_factor = own_set, own_payload
    return row


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--object", type=Path, required=True)
    parser.add_argument("--result", type=Path, action="append", required=True)
    parser.add_argument("--random", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--jaw", default="any")
    args = parser.parse_args(argv)
    set_solver_threads(1)
    problem = object_problem(args.object, args.jaw)
    rows: dict[str, dict[str, float]] = {}
    rng = np.random.default_rng(0)
    x = rng.uniform(-1.0, 1.0, (args.random, problem.n_var))
    rows[f"{args.random} random designs"] = measure(problem, problem.to_physical(x),
                                                    args.repeats)
    for path in args.result:
        result = json.loads(path.read_text())
        designs = np.array([design_row(p["design"]) for p in result["top_designs"]])
        rows[f"{path.parent.name}/{path.name}"] = measure(problem, designs, args.repeats)
    columns = list(next(iter(rows.values())))
    print(f"{problem.name}: {problem.scenario_count} scenario(s), load set {problem.load_set}; "
          "CPU ms a design, one thread")
    print("| designs | " + " | ".join(columns) + " |")
    print("|---" * (len(columns) + 1) + "|")
    for name, row in rows.items():
        print(f"| {name} | " + " | ".join(f"{row[c]:.2f}" for c in columns) + " |")


if __name__ == "__main__":
    main()
