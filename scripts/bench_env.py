"""Benchmark GripperDesign-v2: the plain step loop against batched ``evaluate_designs``.

Prints a summary and writes ``out/bench_env.json``. All paths draw designs uniformly from the
default :class:`envs.DesignBounds` (relative to the object: every design is valid at rest, a few
of the solves fail, in all paths alike) on the paper-r070 disk, at N = 20. numba is warmed up
before any timing. The third path is what RL training sees: random actions stepped through the
stable-baselines3 ``VecEnv`` of :func:`envs.sb3_env.sb3_vec_env` (one batched evaluation per
step, every sub-env resetting itself with a new object drawn from a distribution holding only
that disk); it is skipped if stable-baselines3 is not installed.

Targets: batched >= 20,000 designs/s and >= 10x the step loop.

Usage::

    python scripts/bench_env.py [--steps 300] [--batch-sizes 1000 10000] [--sb3-envs 256]
                                [--sb3-steps 40] [--out out]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from envs import DesignBounds, GripperDesignEnv, ObjectDistribution, SoftDisk, evaluate_designs
from envs.parallel import solver_threads
from envs.scene import PRESETS

TARGET_DESIGNS_PER_S = 20_000
TARGET_RATIO = 10.0


def paper_disk() -> SoftDisk:
    """The object of the paper-r070 scene."""
    return PRESETS["paper-r070"][1]


def warm_up(model: dict) -> None:
    """Compile (or load from the cache) every kernel the timed code uses."""
    g, disk = PRESETS["paper-r070"]
    row = [g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m, 0.2,
           disk.distance_m]
    evaluate_designs(np.array([row]), disk, **model)  # solve_one
    evaluate_designs(np.array([row, row]), disk, **model)  # solve_batch
    env = GripperDesignEnv(**model)
    env.reset(seed=0)
    env.step(np.zeros(6))


def bench_step_loop(n_steps: int, model: dict, seed: int) -> dict:
    """``reset`` + ``step`` with a random action, ``n_steps`` times."""
    env = GripperDesignEnv(**model)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(n_steps)]
    valid = converged = 0
    t0 = time.perf_counter()
    for k, action in enumerate(actions):
        env.reset(seed=seed + k, options={"disk": paper_disk()})
        *_, info = env.step(action)
        valid += info["valid_at_rest"]
        converged += info["converged"]
    elapsed = time.perf_counter() - t0
    return {
        "steps": n_steps,
        "seconds": elapsed,
        "steps_per_s": n_steps / elapsed,
        "valid_fraction": valid / n_steps,
        "converged_fraction_of_valid": converged / max(valid, 1),
    }


def bench_batch(batch: int, model: dict, seed: int) -> dict:
    """One ``evaluate_designs`` call on ``batch`` random designs."""
    designs = DesignBounds().sample(np.random.default_rng(seed), batch, paper_disk())
    t0 = time.perf_counter()
    out = evaluate_designs(designs, paper_disk(), **model)
    elapsed = time.perf_counter() - t0
    valid = out["valid_at_rest"]
    solved = int(valid.sum())
    status = out["status"][valid]
    return {
        "batch": batch,
        "seconds": elapsed,
        "designs_per_s": batch / elapsed,
        "solved_designs_per_s": solved / elapsed,
        "valid_fraction": float(valid.mean()),
        "converged_fraction_of_valid": float(out["converged"][valid].mean()) if solved else 0.0,
        "status_counts_of_valid": {str(s): int(c) for s, c in zip(*np.unique(status,
                                                                            return_counts=True),
                                                                  strict=True)},
        "mean_iterations_of_valid": float(out["iterations"][valid].mean()) if solved else 0.0,
        "median_iterations_of_valid": (float(np.median(out["iterations"][valid])) if solved
                                       else 0.0),
        "finite": bool(all(np.all(np.isfinite(np.asarray(v, dtype=float)))
                           for v in out.values())),
    }


def bench_sb3(num_envs: int, n_steps: int, model: dict, seed: int) -> dict | None:
    """``n_steps`` steps of random actions through ``sb3_vec_env(num_envs)``, after a warm step.

    Returns None if stable-baselines3 is not installed.
    """
    try:
        from envs.sb3_env import sb3_vec_env

        env = sb3_vec_env(num_envs, seed=seed, distribution=paper_distribution(),
                          **model)
    except ImportError:
        return None
    actions = np.random.default_rng(seed).uniform(
        -1.0, 1.0, size=(n_steps, num_envs, 6)).astype(np.float32)
    env.reset()
    env.step(actions[0])  # warm: first-call costs of the adapter, not timed
    infos = []
    t0 = time.perf_counter()
    for a in actions:
        infos.extend(env.step(a)[3])
    elapsed = time.perf_counter() - t0
    env.close()
    valid = sum(info["valid_at_rest"] for info in infos)
    converged = sum(info["converged"] for info in infos)
    return {
        "num_envs": num_envs,
        "steps": n_steps,
        "seconds": elapsed,
        "designs_per_s": len(infos) / elapsed,
        "valid_fraction": valid / len(infos),
        "converged_fraction_of_valid": converged / max(valid, 1),
    }


def bench_make_vec(num_envs: int, n_steps: int, model: dict, seed: int) -> dict:
    """``n_steps`` steps of ``gymnasium.make_vec(ENV_ID, num_envs, "vector_entry_point",
    autoreset_mode=SAME_STEP)``: every step evaluates every sub-env's design."""
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    import envs

    vec = gym.make_vec(envs.ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point",
                       autoreset_mode=AutoresetMode.SAME_STEP, **model,
                       distribution=paper_distribution())
    actions = np.random.default_rng(seed).uniform(
        -1.0, 1.0, size=(n_steps, num_envs, 6)).astype(np.float32)
    vec.reset(seed=seed)
    vec.step(actions[0])  # warm
    evaluated = 0
    t0 = time.perf_counter()
    for a in actions:
        _, _, terminated, _, _ = vec.step(a)
        evaluated += int(np.count_nonzero(terminated))
    elapsed = time.perf_counter() - t0
    vec.close()
    return {"num_envs": num_envs, "steps": n_steps, "seconds": elapsed,
            "designs_per_s": evaluated / elapsed}


def paper_distribution() -> ObjectDistribution:
    """Objects identical to the paper-r070 disk (the strain limit does not change the solve)."""
    d = paper_disk()
    return ObjectDistribution(
        radius_range_m=(d.radius_m,) * 2, youngs_modulus_range_pa=(d.youngs_modulus_pa,) * 2,
        poisson_ratio_range=(d.poisson_ratio,) * 2, thickness_range_m=(d.thickness_m,) * 2,
        stiffness_scale=d.stiffness_scale)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300, help="step-loop iterations")
    parser.add_argument("--batch-sizes", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--sb3-envs", type=int, default=256,
                        help="sub-envs of the stable-baselines3 VecEnv")
    parser.add_argument("--sb3-steps", type=int, default=40, help="its timed steps")
    parser.add_argument("--n-triangles", type=int, default=None,
                        help="contour points N (default: 20 for the fan, 40 for nhquad)")
    parser.add_argument("--element", default="spring", choices=("spring", "nhquad", "cst"),
                        help="spring: the paper's fan (default, the issue's N = 20 target); "
                        "nhquad: the default model")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args(argv)
    from envs.model.family import resolve_model

    spec = resolve_model(args.n_triangles, None, args.element)
    model = spec.kwargs()

    t0 = time.perf_counter()
    warm_up(model)
    warm_s = time.perf_counter() - t0
    loop = bench_step_loop(args.steps, model, args.seed)
    batches = [bench_batch(b, model, args.seed) for b in args.batch_sizes]
    sb3 = bench_sb3(args.sb3_envs, args.sb3_steps, model, args.seed)
    mvec = bench_make_vec(args.sb3_envs, args.sb3_steps, model, args.seed)
    best = max(batches, key=lambda r: r["designs_per_s"])
    ratio = best["designs_per_s"] / loop["steps_per_s"]
    report = {
        **model,
        "disk": "paper-r070",
        "solver_threads": solver_threads(),
        "cpu": platform.processor() or platform.machine(),
        "warm_up_s": warm_s,
        "step_loop": loop,
        "batched": batches,
        "batched_over_step_loop": ratio,
        "sb3_vec_env": sb3,
        "make_vec_same_step": mvec,
        "targets": {
            "designs_per_s": TARGET_DESIGNS_PER_S,
            "ratio": TARGET_RATIO,
            "designs_per_s_met": best["designs_per_s"] >= TARGET_DESIGNS_PER_S,
            "ratio_met": ratio >= TARGET_RATIO,
        },
    }
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / ("bench_env.json" if spec.element == "spring"
                       else f"bench_env_{spec.element}.json")
    path.write_text(json.dumps(report, indent=2))

    print(f"solver threads: {report['solver_threads']} (Python threads, nogil kernels), "
          f"{spec.element} N = {spec.n_triangles}, M = {spec.n_rings}, warm-up {warm_s:.1f} s")
    print(f"step loop (reset + step): {loop['steps_per_s']:9.1f} steps/s   "
          f"valid {loop['valid_fraction']:.2f}, converged "
          f"{loop['converged_fraction_of_valid']:.3f} of valid")
    for r in batches:
        print(f"batched B={r['batch']:>6}:      {r['designs_per_s']:9.1f} designs/s "
              f"({r['solved_designs_per_s']:.1f} solved/s)   valid {r['valid_fraction']:.2f}, "
              f"converged {r['converged_fraction_of_valid']:.3f} of valid, "
              f"iterations median {r['median_iterations_of_valid']:.0f} / mean "
              f"{r['mean_iterations_of_valid']:.1f}, status {r['status_counts_of_valid']}")
    print(f"make_vec SAME_STEP n={mvec['num_envs']:>4}: {mvec['designs_per_s']:9.1f} designs/s")
    if sb3 is None:
        print("sb3_vec_env: skipped (stable-baselines3 is not installed)")
    else:
        print(f"sb3_vec_env n={sb3['num_envs']:>4}:  {sb3['designs_per_s']:9.1f} designs/s "
              f"({sb3['designs_per_s'] / loop['steps_per_s']:.1f}x the step loop; "
              f"random actions, {sb3['steps']} steps)   valid {sb3['valid_fraction']:.2f}, "
              f"converged {sb3['converged_fraction_of_valid']:.3f} of valid")
    print(f"batched / step loop: {ratio:.2f}x "
          f"(target {TARGET_RATIO:g}x: {'met' if report['targets']['ratio_met'] else 'NOT met'}); "
          f"{best['designs_per_s']:.0f} designs/s (target {TARGET_DESIGNS_PER_S}: "
          f"{'met' if report['targets']['designs_per_s_met'] else 'NOT met'})")
    print(f"wrote {path}")
    return report


if __name__ == "__main__":
    main()
