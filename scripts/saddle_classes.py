"""Where the Newton iterations of random designs go: the grasps sorted by their symmetry.

Every random design of the evaluator is mirror-symmetric about the gripper's axis, and the
solve starts from a mirror-symmetric rest state (even N, first contour point on the axis). The
equilibrium it ends on is one of three kinds:

* ``point-centred``: mirror-symmetric with a contour point on the axis (the start's symmetry);
* ``edge-centred``: mirror-symmetric with an edge centred on the axis, i.e. the contour turned
  about the pin by half a point spacing from the start;
* ``asymmetric``: the contour turned part of the way (the mirror images of one equilibrium).

The last two are reached only by turning off a symmetric saddle. This script counts each kind,
the iterations each needs from the default start, and what they need from a start turned by
half a spacing (where the edge-centred answers lie): the iterations an ideal choice of start
would leave (the smaller of the two, an oracle). It is the measurement behind the statement
that a better start alone cannot take batched evaluation to 20,000 designs/s (README,
"Performance").

Usage: ``python scripts/saddle_classes.py [--designs 2000] [--disk paper-r070]``;
writes ``out/saddle_classes.json``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from envs.evaluate import Design, DesignBounds
from envs.model.defaults import DEFAULT_PHASE_RAD
from envs.scene import Scene
from envs.solver import simulate

KINDS = ("point-centred", "edge-centred", "asymmetric")
SYMMETRY_TOL = 1e-6  # a state is mirror-symmetric to this share of the radius


def mirror_kind(points_m: np.ndarray, radius_m: float) -> str:
    """Which of :data:`KINDS` a contour (N, 2), first point at the top at rest, belongs to.

    The mirror image about the axis x = 0 of a point-centred contour maps point i to point -i;
    of an edge-centred one, point i to point -1 - i.
    """
    n = points_m.shape[0]
    mirrored = points_m * np.array([-1.0, 1.0])
    for kind, shift in (("point-centred", 0), ("edge-centred", -1)):
        partner = (shift - np.arange(n)) % n
        if np.max(np.abs(mirrored[partner] - points_m)) <= SYMMETRY_TOL * radius_m:
            return kind
    return "asymmetric"


def _designs(count: int, disk, seed: int) -> list[Design]:
    rows = DesignBounds().sample(np.random.default_rng(seed), count, disk)
    designs = []
    for row in rows:
        design = Design(*row)
        try:
            design.to_scene(disk)
        except ValueError:
            continue  # invalid at rest: not solved by the evaluator either
        designs.append(design)
    return designs


def measure(count: int, disk_name: str, n: int, seed: int) -> dict:
    """Solve each valid design from both starts; per kind: counts and mean iterations."""
    disk = Scene.preset(disk_name).disk
    half = math.pi / n
    rows = []
    for design in _designs(count, disk, seed):
        scene = design.to_scene(disk)
        base = simulate(scene, design.torque_nm, n, element="spring")
        turned = simulate(scene, design.torque_nm, n, element="spring",
                          phase_rad=DEFAULT_PHASE_RAD + half)
        if not (base.converged and turned.converged):
            continue
        rows.append((mirror_kind(base.points_m, disk.radius_m), base.iterations,
                     turned.iterations))
    if not rows:
        raise ValueError(f"none of the {count} random designs on {disk_name} is valid at rest "
                         "and converged from both starts: draw more (--designs)")
    report = {"disk": disk_name, "n_triangles": n, "element": "spring", "designs": len(rows),
              "kinds": {}}
    its = np.array([r[1:] for r in rows], dtype=float).reshape(-1, 2)
    for kind in KINDS:
        sel = np.array([r[0] == kind for r in rows], dtype=bool)
        report["kinds"][kind] = {
            "share": float(sel.mean()),
            "mean_iterations_default_start": float(its[sel, 0].mean()) if sel.any() else None,
            "mean_iterations_turned_start": float(its[sel, 1].mean()) if sel.any() else None,
        }
    report["mean_iterations_default_start"] = float(its[:, 0].mean())
    report["mean_iterations_best_of_two_starts"] = float(its.min(axis=1).mean())
    point = its[[r[0] == "point-centred" for r in rows], 0]
    report["mean_iterations_if_all_cost_as_point_centred"] = (float(point.mean()) if point.size
                                                              else None)
    return report


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=2000, help="random designs drawn")
    parser.add_argument("--disk", default="paper-r070", help="preset scene of the disk")
    parser.add_argument("--n-triangles", type=int, default=20, help="contour points N (even)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args(argv)
    if args.n_triangles % 2:
        parser.error("--n-triangles must be even (a mirror-symmetric start)")
    report = measure(args.designs, args.disk, args.n_triangles, args.seed)
    print(f"{report['designs']} converged random designs, {args.disk}, fan N = "
          f"{args.n_triangles}: Newton iterations (all attempts) by the kind of equilibrium")
    print(f"{'kind':>14}  {'share':>6}  {'default start':>13}  {'turned start':>12}")
    for kind, row in report["kinds"].items():
        if row["mean_iterations_default_start"] is None:
            continue
        print(f"{kind:>14}  {row['share']:6.2f}  {row['mean_iterations_default_start']:13.1f}  "
              f"{row['mean_iterations_turned_start']:12.1f}")
    ideal = report["mean_iterations_if_all_cost_as_point_centred"]
    print(f"mean: default start {report['mean_iterations_default_start']:.1f}, best of the two "
          f"starts (oracle) {report['mean_iterations_best_of_two_starts']:.1f}, every design as "
          f"cheap as a point-centred one {'-' if ideal is None else f'{ideal:.1f}'}")
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "saddle_classes.json"
    path.write_text(json.dumps(report, indent=2))
    print(f"wrote {path}")
    return report


if __name__ == "__main__":
    main()
