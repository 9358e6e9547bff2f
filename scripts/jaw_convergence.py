"""Share of random grooved-jaw grasps the point-spring solver converges on, against straight
jaws at the same torques.

Random cradles (radius 0.7 to 2 r) and V-grooves (opening 90 to 170 deg) alternately, 15 to
75 % of the finger's width deep, centred near where the closing finger meets the disk, on the
paper-r070 scene at torques drawn from 0.03 to 0.5 N·m; each member solves the grooved scenes
and the straight ones::

    python scripts/jaw_convergence.py [--count 400] [--seed 7]

It prints, per member, the share converged (cradles and vees apart), the mean iterations and
the wall time of the two batches.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from envs.model.jaw import JawProfile
from envs.model.problem import SceneColumns
from envs.scene import Scene
from envs.solver.pipeline import solve_columns

MEMBERS = ((20, 1, "spring"), (40, 2, "nhquad"))


def random_jaws(rng: np.random.Generator, count: int, scene: Scene) -> list[JawProfile]:
    """``count`` random grooves for ``scene``'s fingers: cradles at even indices, V-grooves at
    odd ones (see the module)."""
    g, d = scene.gripper, scene.disk
    hw, r = g.finger_width_m / 2, d.radius_m
    # where the straight face first meets the disk: the centre at m = w/2 + r from the face
    a0 = math.sqrt(g.joint_offset_m ** 2 + (d.distance_m + r) ** 2 - (hw + r) ** 2)
    jaws = []
    for k in range(count):
        depth = g.finger_width_m * rng.uniform(0.15, 0.75)
        if k % 2 == 0:
            shape = JawProfile.cradle(max(r * rng.uniform(0.7, 2.0), depth), depth, 0.0)
        else:
            shape = JawProfile.vee(math.radians(rng.uniform(90.0, 170.0)), depth, 0.0)
        half = shape.mouth_half_width_m
        lo, hi = half + 1e-3, g.finger_length_m - half - 1e-3
        a = min(max(a0 + rng.uniform(-0.5, 0.5) * half, lo), hi)
        jaws.append(JawProfile(shape.depth_m, shape.bottom_radius_m, shape.opening_angle_rad,
                               a))
    return jaws


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=400)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    base = Scene.preset("paper-r070")
    rng = np.random.default_rng(args.seed)
    jaws = random_jaws(rng, args.count, base)
    torques = rng.uniform(0.03, 0.5, size=args.count)
    grooved = SceneColumns.from_rows(np.vstack(
        [base.with_changes(jaw=jaw).rows(t) for jaw, t in zip(jaws, torques, strict=True)]))
    straight = SceneColumns.from_rows(np.vstack([base.rows(t) for t in torques]))
    vee = np.arange(args.count) % 2 == 1
    for n, m, element in MEMBERS:
        # loads (or compiles) the member's kernels before timing
        solve_columns(grooved.take([0]), n, phase_rad=math.pi / 2, n_rings=m, element=element)
        times, sols = [], []
        for cols in (grooved, straight):
            t0 = time.perf_counter()
            sols.append(solve_columns(cols, n, phase_rad=math.pi / 2, n_rings=m,
                                      element=element))
            times.append(time.perf_counter() - t0)
        sol, ref = sols
        print(f"N = {n}, M = {m}, {element}: grooved converged {sol.converged.mean():.3f} "
              f"(cradles {sol.converged[~vee].mean():.3f}, vees {sol.converged[vee].mean():.3f}),"
              f" straight {ref.converged.mean():.3f}; mean iterations {sol.iterations.mean():.1f}"
              f" vs {ref.iterations.mean():.1f}; wall {times[0]:.2f} s vs {times[1]:.2f} s")


if __name__ == "__main__":
    main()
