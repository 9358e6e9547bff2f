"""The design policy on objects it never saw: one forward pass, and with K refining evaluations,
against a per-object CMA-ES optimum and cold CMA-ES at the same K.

For ``--objects`` held-out objects (:func:`optim.rl.heldout_objects`: the default distribution,
with its densities, payload factors and placement tolerances, a seed no training env draws
from) and ``--seeds`` training seeds: each policy is trained (``--steps``, SAC; or read from
``out/bench_policy/seed{S}`` when it is there) and scored by its gap to each object's CMA-ES
optimum (1000 evaluations): the optimum's reward less the design's, 0 at the optimum (not a
share: with payloads an optimum may be near or below zero). The policy alone, the policy + K
evaluations of CMA-ES started at its design, and cold CMA-ES with K evaluations, for K in 50,
100, 200 (``--ks``). Every reward is the env's: the worst over the object's placements within
its tolerance (:func:`envs.design_env.evaluate_objects`; the problems carry the payload and
the tolerance as :class:`envs.scenarios.Scenarios`). Also: the worst object, the seeds' spread,
grasps that do not hold or miss, the training time and the policy's time per design. Every
score is the default model's reward (the search model; ``psm-grasp optimize`` reports a finer
member's, the same for both sides).

``--ablation`` also trains seed 0 with the env's reward as it is (no bounded tail,
:func:`optim.rl.bounded_tail`) and draws both learning curves. ``--object-files N`` checks the
commands as a user runs them: N objects of the distribution written as TOML files (with their
strain limit, friction, density, payload factor and placement tolerance), ``psm-grasp design
--object F`` (the shipped policy) and ``--refine 100`` against ``psm-grasp optimize --object F
--budget 1000``, each as reported (the finer member's reward after the finish).

Writes ``out/bench_policy.json`` and ``out/bench_policy.png`` (``--jaw any``: the policies that
design shaped jaws, against CMA-ES in the same space; ``bench_policy_any.json`` and ``.png``).

Usage: ``python scripts/bench_policy.py [--objects 24] [--seeds 0 1 2] [--steps 80000]
[--ablation] [--object-files 12] [--shipped] [--ks 50 100 200]`` (a training of 80,000 steps
takes ~16 minutes on 2 cores; ``--shipped`` scores the shipped policy without training).
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

from envs.design_env import evaluate_objects, observe_rows
from envs.scenarios import Scenarios
from optim import DesignProblem, NoGraspWarning, optimize
from optim.rl import heldout_objects, learning_curve_figure, load_policy, train_policy

HELDOUT_SEED = 12345
REFERENCE_BUDGET = 1000
KS = (50, 100, 200)
NEAR = 0.01  # a design within this reward of the optimum counts as near it
REWARD_HOLDS = -1.0  # every reward of a grasp that holds (within the limit or crushing) is above


JAW = {"jaw": "straight"}  # the jaws designed (--jaw), set once by main


def problem_of(obj) -> DesignProblem:
    """The design problem of a held-out object (disk, strain limit, friction, payload factor,
    tolerance over the radius): the env's reward, the worst over its placements, in the
    design space of the jaws of ``--jaw``."""
    disk, limit, mu, factor, tolerance = obj
    return DesignProblem(disk, limit, mu, payload_factor=factor, jaw=JAW["jaw"],
                         scenarios=Scenarios.of(placement_tolerance_m=tolerance * disk.radius_m))


def reference_optima(objects, budget: int) -> np.ndarray:
    """Each object's CMA-ES optimum (seed 0), the 100 %."""
    return np.array([optimize("cmaes", problem_of(o), budget=budget, seed=0).best_reward
                     for o in objects])


def cached_optima(objects, budget: int, path: Path) -> np.ndarray:
    """:func:`reference_optima`, read from ``path`` when it holds those of the same objects
    and budget (they take the longest and do not depend on the policy), else computed and
    written there."""
    key = {"objects": len(objects), "heldout_seed": HELDOUT_SEED, "budget": budget,
           "first_radius_m": objects[0][0].radius_m, "jaw": JAW["jaw"]}
    if path.is_file():
        data = json.loads(path.read_text())
        if data.get("key") == key:
            return np.array(data["optima"])
    optima = reference_optima(objects, budget)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"key": key, "optima": optima.tolist()}) + "\n")
    return optima


def gaps(rewards: np.ndarray, optima: np.ndarray) -> dict:
    """The gaps to the optima (optimum - reward, reward units): mean, worst, the worst
    object, and how many objects come within :data:`NEAR` of their optimum."""
    gap = optima - rewards
    return {"mean": float(gap.mean()), "max": float(gap.max()),
            "worst_object": int(np.argmax(gap)), "near": int((gap <= NEAR).sum())}


def policy_alone(policy, objects) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reward, holding and touching (both fingers, every placement) of the policy's designs
    (one batched evaluation)."""
    disks = [o[0] for o in objects]
    needs = np.array([o[1:] for o in objects], dtype=float)
    designs = policy.bounds.scale(policy.actions(observe_rows(disks, needs)), disks)
    out = evaluate_objects(designs, disks, needs)
    return out["reward"], out["holds"], out["touching"].all(axis=1)


def with_budget(objects, k: int, policy=None) -> np.ndarray:
    """Best reward after k evaluations: cold CMA-ES, or the policy's design and k - 1
    refining evaluations."""
    rewards = []
    for obj in objects:
        problem = problem_of(obj)
        if policy is None:
            rewards.append(optimize("cmaes", problem, budget=k, seed=0).best_reward)
        else:
            rewards.append(policy.run(problem, budget=k, seed=0).best_reward)
    return np.array(rewards)


def policy_time_ms(policy, objects, repeat: int = 200) -> float:
    """Policy time of one design [ms]: the observation and the forward pass."""
    t0 = time.perf_counter()
    for _ in range(repeat):
        policy.normalized(*objects[0])
    return (time.perf_counter() - t0) / repeat * 1e3


def get_policy(seed: int, steps: int, folder: Path, objects, tail_scale: float = 1.0):
    """A trained policy: read from ``folder`` when it was trained before, else trained and
    saved there."""
    jaw = JAW["jaw"]
    path = folder / ((f"seed{seed}" if tail_scale else f"seed{seed}_no_tail")
                     + ("" if jaw == "straight" else f"_{jaw}"))
    if (path / "policy.json").is_file():
        return load_policy(path)
    policy = train_policy("sac", steps=steps, seed=seed, heldout=objects, curve_points=20,
                          name=path.name, tail_scale=tail_scale, progress=False, jaw=jaw)
    policy.save(path)
    return policy


def object_file_check(n: int, folder: Path) -> dict:
    """``design`` (alone and ``--refine 100``) against ``optimize --budget 1000`` on n object
    files, through the command line's own entry point."""
    from cli.main import main as cli

    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for k, (disk, limit, mu, factor, tol) in enumerate(heldout_objects(n, HELDOUT_SEED + 1)):
        path = folder / f"object_{k}.toml"
        path.write_text(
            "[object]\n"
            f"name = \"object {k}\"\nradius_m = {disk.radius_m!r}\n"
            f"youngs_modulus_pa = {disk.youngs_modulus_pa!r}\n"
            f"poisson_ratio = {disk.poisson_ratio!r}\nthickness_m = {disk.thickness_m!r}\n"
            f"density_kg_m3 = {disk.density_kg_m3!r}\npayload_factor = {factor!r}\n"
            f"strain_limit = {limit!r}\nfriction_coefficient = {mu!r}\n"
            f"placement_tolerance_m = {tol * disk.radius_m!r}\n")
        row = {"file": str(path)}
        for key, argv in (("optimize", ["optimize", "--budget", "1000"]),
                          ("design", ["design"]), ("design_refine_100", ["design", "--refine",
                                                                          "100"])):
            out = folder / f"{key}_{k}"
            code = cli([*argv, "--object", str(path), "--out", str(out), "--no-progress"])
            name = "cmaes_seed0_result.json" if key == "optimize" else "design_result.json"
            data = json.loads((out / name).read_text())
            # the search model's optimum: the best of the designs it kept (the finish reports
            # the one the finer member scores best, not always the search model's best)
            search = max(t.get("search_reward", t["reward"]) for t in data["top_designs"])
            row[key] = {"exit": code, "reward": data["best_reward"], "search_reward": search,
                        "grasp_found": data["extra"]["grasp_found"]}
        rows.append(row)
    out: dict = {"objects": n, "rows": rows,
                 "missed": sum(not r["design"]["grasp_found"] for r in rows)}
    for key in ("design", "design_refine_100"):
        gap = np.array([r["optimize"]["search_reward"] - r[key]["search_reward"]
                        for r in rows])
        reported = np.array([r["optimize"]["reward"] - r[key]["reward"] for r in rows])
        # the gaps to optimize's optimum (a share is meaningless where an optimum is near or
        # below zero): in the search model, and as reported (the finer member's rewards)
        out[f"{key}_gap"] = {"mean": float(gap.mean()), "max": float(gap.max())}
        out[f"{key}_reported_gap"] = {"mean": float(reported.mean()),
                                      "max": float(reported.max())}
    return out


def chart(report: dict, path: Path) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4.2), dpi=110)
    ax, ax2 = fig.subplots(1, 2)
    ks = list(report["ks"])
    cold = [report["cold_cmaes"][str(k)]["mean"] for k in ks]
    ax.plot(ks, cold, "o-", color="tab:gray", label="cold CMA-ES, K evaluations")
    for n, row in enumerate(report["seeds"].values()):
        ax.plot(ks, [row["refined"][str(k)]["mean"] for k in ks], "o-", color="tab:blue",
                alpha=0.7, label="policy + K (each policy)" if n == 0 else None)
        ax.axhline(row["alone"]["mean"], color="tab:blue", ls="--", lw=0.8,
                   label="policy alone, one forward pass (each policy)" if n == 0 else None)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("evaluations K on the new object")
    ax.set_ylabel("mean gap to the per-object CMA-ES optimum (reward)")
    ax.set_title(f"{report['objects']} objects never trained on", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    curves = {f"seed {s}": row["curve"] for s, row in report["seeds"].items() if row["curve"]}
    if "ablation_no_tail" in report:
        curves["seed 0, no bounded tail"] = report["ablation_no_tail"]["curve"]
    if curves:
        tmp = path.with_name(path.stem + "_curves.png")
        learning_curve_figure(curves, tmp, title="learning curves")
        for k, (label, curve) in enumerate(curves.items()):
            ax2.plot([p["steps"] for p in curve], [p["heldout_reward"] for p in curve],
                     color=f"C{k}", label=label)
        ax2.axhline(report["optimum_mean_reward"], color="k", ls="--", lw=0.8,
                    label="per-object CMA-ES optima (mean)")
        ax2.set_xlabel("designs evaluated in training")
        ax2.set_ylabel("mean reward on the held-out objects")
        ax2.legend(fontsize=7)
        ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=24)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--steps", type=int, default=80_000)
    parser.add_argument("--shipped", action="store_true",
                        help="score the shipped policy instead of training seeds")
    parser.add_argument("--ablation", action="store_true",
                        help="also train seed 0 without the bounded tail (learning curves)")
    parser.add_argument("--object-files", type=int, default=0, metavar="N",
                        help="check design against optimize on N object files")
    parser.add_argument("--ks", type=int, nargs="+", default=list(KS),
                        help="refining budgets K (default %(default)s)")
    parser.add_argument("--reference-only", action="store_true",
                        help="only compute the per-object optima (cached in --out)")
    parser.add_argument("--jaw", default="straight", choices=("straight", "any"),
                        help="the jaws designed: straight, or any shaped jaws (the policies "
                        "trained in GripperJawDesign-v0's space; --shipped: the shipped one)")
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    JAW["jaw"] = args.jaw
    warnings.simplefilter("ignore", NoGraspWarning)
    objects = heldout_objects(args.objects, HELDOUT_SEED)
    suffix = "" if args.jaw == "straight" else f"_{args.jaw}"
    optima = cached_optima(objects, REFERENCE_BUDGET,
                           args.out / f"bench_policy_optima{suffix}.json")
    if args.reference_only:
        print(f"optima of {len(objects)} objects: mean {optima.mean():.4f}")
        return
    ks = tuple(args.ks)
    report: dict = {"objects": len(objects), "reference_budget": REFERENCE_BUDGET, "ks": ks,
                    "optimum_mean_reward": float(optima.mean()),
                    "optima": optima.tolist(), "steps": args.steps, "seeds": {},
                    "cold_cmaes": {}}
    for k in ks:
        cold = with_budget(objects, k)
        report["cold_cmaes"][str(k)] = {**gaps(cold, optima),
                                        "not_holding": int((cold <= REWARD_HOLDS).sum())}
    policies = ({"shipped": load_policy(jaw=args.jaw)} if args.shipped else
                {str(s): get_policy(s, args.steps, args.out / "bench_policy", objects)
                 for s in args.seeds})
    for name, policy in policies.items():
        reward, holds, touching = policy_alone(policy, objects)
        row = {"alone": {**gaps(reward, optima),
                         "not_holding": int((~holds).sum()),
                         "missed": int((~touching).sum()),
                         "mean_reward": float(reward.mean())},
               "refined": {},
               "training_s": policy.meta.get("training", {}).get("wall_time_s"),
               "policy_ms": policy_time_ms(policy, objects),
               "curve": policy.meta.get("training", {}).get("curve", [])}
        for k in ks:
            refined = with_budget(objects, k, policy)
            row["refined"][str(k)] = {**gaps(refined, optima),
                                      "not_holding": int((refined <= REWARD_HOLDS).sum())}
        report["seeds"][name] = row
        kp = "100" if 100 in ks else str(ks[-1])
        a, r = row["alone"], row["refined"][kp]
        print(f"policy {name}, gap to the optimum: alone {a['mean']:.4f} (worst {a['max']:.4f}, "
              f"{a['near']} near, {a['not_holding']} not holding, {a['missed']} missed), "
              f"+ {kp}: {r['mean']:.4f} (worst {r['max']:.4f}, {r['near']} near, "
              f"{r['not_holding']} not holding); "
              f"trained in {row['training_s'] or 0:.0f} s; {row['policy_ms']:.3f} ms a design",
              flush=True)
    if args.ablation:
        plain = get_policy(0, args.steps, args.out / "bench_policy", objects, tail_scale=0.0)
        reward, holds, _ = policy_alone(plain, objects)
        report["ablation_no_tail"] = {
            "alone": {**gaps(reward, optima), "not_holding": int((~holds).sum())},
            "curve": plain.meta["training"]["curve"]}
        print(f"without the bounded tail (seed 0): alone, gap "
              f"{report['ablation_no_tail']['alone']['mean']:.4f}", flush=True)
    if args.object_files:
        report["object_files"] = object_file_check(args.object_files,
                                                   args.out / "bench_policy_objects")
        of = report["object_files"]
        print(f"object files ({args.object_files}), gap to optimize --budget 1000 in the "
              f"search model: design {of['design_gap']['mean']:.4f} (worst "
              f"{of['design_gap']['max']:.4f}), --refine 100 "
              f"{of['design_refine_100_gap']['mean']:.4f} (worst "
              f"{of['design_refine_100_gap']['max']:.4f}); as reported: "
              f"{of['design_reported_gap']['mean']:.4f} and "
              f"{of['design_refine_100_reported_gap']['mean']:.4f}; missed {of['missed']}",
              flush=True)
    alone = [r["alone"]["mean"] for r in report["seeds"].values()]
    report["alone_spread"] = [min(alone), max(alone)]
    print("cold CMA-ES, gap to the optimum: " + ", ".join(
        f"K = {k}: {c['mean']:.4f} (worst {c['max']:.4f}, {c['near']} near, "
        f"{c['not_holding']} not holding)" for k, c in
        ((k, report["cold_cmaes"][str(k)]) for k in ks)))
    args.out.mkdir(parents=True, exist_ok=True)
    report["jaw"] = args.jaw
    (args.out / f"bench_policy{suffix}.json").write_text(json.dumps(report, indent=1) + "\n")
    chart(report, args.out / f"bench_policy{suffix}.png")
    print(f"wrote {args.out / f'bench_policy{suffix}.json'} and "
          f"{args.out / f'bench_policy{suffix}.png'}")


if __name__ == "__main__":
    main()
